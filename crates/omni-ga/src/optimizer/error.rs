//! Errors of the optimizers.
use thiserror::Error;

/// An optimizer refused its inputs.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum OptimizeError {
    /// Start point and bounds disagree in size.
    #[error("start point has {start} parameters but bounds have {bounds}")]
    DimensionMismatch {
        /// Entries of the start point.
        start: usize,
        /// Entries of the bounds.
        bounds: usize,
    },
    /// A start entry is NaN or infinite.
    #[error("start point entry {index} is {value}, not finite")]
    StartNotFinite {
        /// Index.
        index: usize,
        /// Value.
        value: f64,
    },
    /// A bound pair is invalid.
    #[error("bounds of parameter {index}: lower {lower} > upper {upper} or not a number")]
    BadBounds {
        /// Index.
        index: usize,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// A configuration value is invalid.
    #[error("{what}: {why}")]
    BadConfig {
        /// The setting.
        what: &'static str,
        /// Why.
        why: String,
    },
}
