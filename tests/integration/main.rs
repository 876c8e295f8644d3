//! End-to-end tests through the library: simulate → train → eval, determinism, diagnosis.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers panic on failure by design
mod choices;
mod common;
mod determinism;
mod few_runs;
mod hidden_effect;
mod identifiability;
mod motion_coverage;
mod readme;
mod recover;
