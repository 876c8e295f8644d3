//! The crate's error, [`Error`]: what calibration, diagnosis and planning return. The optimizer layer
//! reports with its own [`OptimizeError`], which converts into it.

pub use crate::optimizer::error::OptimizeError;
use omni_kin::KinError;
use thiserror::Error as ThisError;

/// A calibration, diagnosis or plan failed.
#[derive(Debug, ThisError)]
pub enum Error {
    /// The model or runs are not usable.
    #[error(transparent)]
    Kin(#[from] KinError),
    /// The optimizer refused its inputs.
    #[error(transparent)]
    Optimize(#[from] OptimizeError),
    /// Nothing to fit.
    #[error("no training runs")]
    NoRuns,
    /// A run-planning request is out of range ([`crate::science::excitation::PlanRequest`]).
    #[error("plan {what}: {why}")]
    BadPlanRequest {
        /// The settings concerned.
        what: &'static str,
        /// What they must satisfy.
        why: &'static str,
    },
}
