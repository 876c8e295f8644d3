//! End-to-end tests through the library: simulate → train → eval, determinism, diagnosis.
mod common;
mod determinism;
mod hidden_effect;
mod recover;
