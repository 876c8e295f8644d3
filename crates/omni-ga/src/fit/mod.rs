//! The fit layer: the calibration problem and the pipeline that fits it.

mod problem;

pub use problem::*;
