//! # omnical
//!
//! Calibrate the kinematics of omnidirectional wheeled robots from their own logs, and find out why the
//! model still misses. This facade re-exports the workspace crates.
pub use omni_cli as cli;
pub use omni_ga as ga;
pub use omni_kin as kin;
