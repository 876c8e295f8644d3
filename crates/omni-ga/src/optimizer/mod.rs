//! The optimizer layer: what is minimised ([`Problem`], [`LeastSquares`] within [`Bounds`]), who minimises
//! it ([`Optimizer`]: the genetic algorithm [`Ga`], Levenberg–Marquardt [`LevenbergMarquardt`]), who
//! watches ([`Observer`]), and what comes back ([`Solution`]).
//!
//! Nothing here knows about robots, runs or models: this layer depends on no other crate of the workspace,
//! so an optimizer is written and tested against plain functions (see the tests of [`ga`] and [`lm`]).
//!
//! [`Ga`]: ga::Ga
//! [`LevenbergMarquardt`]: lm::LevenbergMarquardt
//! [`Observer`]: observe::Observer
//! [`Problem`]: problem::Problem
//! [`LeastSquares`]: problem::LeastSquares

pub mod bounds;
pub mod error;
pub mod ga;
pub mod lm;
pub mod observe;
pub mod problem;
pub mod subspace;

pub use bounds::Bounds;
pub use error::OptimizeError;
pub use ga::{Ga, GaConfig, StallRule};
pub use lm::{LevenbergMarquardt, LmConfig};
pub use observe::{Control, FnObserver, Iteration, NoopObserver, Observer};
pub use problem::{LeastSquares, NormalEquations, Problem};
use serde::{Deserialize, Serialize};
pub use subspace::Subspace;

/// Why an optimizer stopped. The reasons are shared by every optimizer (each reports those that apply to
/// it), so a new optimizer needs no new variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// Its convergence test was met (the GA's stall rule).
    Converged,
    /// Iteration cap (GA generations).
    MaxIterations,
    /// Evaluation cap.
    MaxEvaluations,
    /// Time cap.
    MaxTime,
    /// The observer asked to stop.
    Stopped,
    /// A local method ended at a point no worse than its start (Levenberg–Marquardt).
    LocalMinimum,
    /// It could not improve on its start, which is returned.
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
