//! The optimizer interface and its result.

pub mod error;
pub mod ga;
pub mod lm;
pub mod observe;
pub mod problem;

use crate::error::OptimizeError;
use crate::observe::Observer;
use serde::{Deserialize, Serialize};

/// Why an optimizer stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The stall rule was met.
    Converged,
    /// Generation cap.
    MaxGenerations,
    /// Evaluation cap.
    MaxEvaluations,
    /// Time cap.
    MaxTime,
    /// The observer asked to stop.
    Stopped,
    /// Levenberg–Marquardt converged.
    LocalMinimum,
    /// Levenberg–Marquardt could not improve on its start, which is returned.
    NoImprovement,
}

/// The result of a minimisation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Solution {
    /// Best parameters found.
    pub params: Vec<f64>,
    /// Their cost.
    pub cost: f64,
    /// Iterations (GA generations, LM: 1).
    pub iterations: usize,
    /// Cost (or residual) evaluations.
    pub evaluations: usize,
    /// Why it stopped.
    pub termination: Termination,
    /// Wall time. s.
    pub seconds: f64,
}

/// A minimiser of problems of type `P`.
pub trait Optimizer<P: ?Sized> {
    /// Short name: `ga`, `lm`.
    fn name(&self) -> &'static str;
    /// Minimise from `start`, reporting to `observer`.
    fn minimize(&mut self, problem: &P, start: &[f64], observer: &mut dyn Observer) -> Result<Solution, OptimizeError>;
}

/// Checks a start point against a dimension.
pub(crate) fn check_start(start: &[f64], dim: usize) -> Result<(), OptimizeError> {
    if start.len() != dim {
        return Err(OptimizeError::DimensionMismatch { start: start.len(), bounds: dim });
    }
    if let Some((index, &value)) = start.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(OptimizeError::StartNotFinite { index, value });
    }
    Ok(())
}
