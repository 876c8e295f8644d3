//! One stage of a fit: an optimizer of the optimizer layer with its own settings (and so its own stopping
//! rules). To add an optimizer to training, add it to the optimizer layer and a variant here; the pipeline
//! ([`crate::fit::pipeline`]) runs any stage through [`Stage::minimize`] and asks it the two questions
//! below.

use crate::optimizer::error::OptimizeError;
use crate::optimizer::ga::{Ga, GaConfig};
use crate::optimizer::lm::{LevenbergMarquardt, LmConfig};
use crate::optimizer::observe::Observer;
use crate::optimizer::problem::LeastSquares;
use crate::optimizer::{Optimizer, Solution};
use serde::{Deserialize, Serialize};

/// An optimizer and its settings, as a step of a [`crate::fit::Plan`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// The bounded genetic algorithm: a global search within the plan's box.
    Ga(GaConfig),
    /// Levenberg–Marquardt: an unbounded local polish of the residuals.
    Lm(LmConfig),
}

impl Stage {
    /// The optimizer's short name (`ga`, `lm`), as observers see it.
    pub fn name(&self) -> &'static str {
        match self {
            Stage::Ga(_) => "ga",
            Stage::Lm(_) => "lm",
        }
    }

    /// True when the stage searches within the plan's box, so that ending on a bound of it says the box
    /// was too small (reported as `at_bound`).
    pub fn within_box(&self) -> bool {
        matches!(self, Stage::Ga(_))
    }

    /// True when the stage runs again within the constrained subspace after the truncated update
    /// ([`crate::fit::Unexcited::Hold`]): a local method that needs no box.
    pub fn refines_held(&self) -> bool {
        matches!(self, Stage::Lm(_))
    }

    /// The same stage with a sixth of its evaluation budget on a problem of `n_params` parameters and
    /// `n_residuals` residuals, to scout with: a local method that has not converged within it is crawling
    /// (the fit pipeline's scouting, [`crate::fit::refine`]). `None` for a stage without such a budget, or
    /// when the cut leaves the budget as it is ([`LmConfig::scout`]).
    pub fn scout(&self, n_params: usize, n_residuals: usize) -> Option<Stage> {
        match self {
            Stage::Lm(c) => c.scout(n_params, n_residuals).map(Stage::Lm),
            Stage::Ga(_) => None,
        }
    }

    /// Sets the seed of a stage that draws random numbers.
    pub fn set_seed(&mut self, seed: u64) {
        match self {
            Stage::Ga(c) => c.seed = seed,
            Stage::Lm(_) => {}
        }
    }

    /// Minimise `problem` from `start` with this stage's optimizer.
    pub fn minimize<P: LeastSquares + ?Sized>(
        &self,
        problem: &P,
        start: &[f64],
        observer: &mut dyn Observer,
    ) -> Result<Solution, OptimizeError> {
        match self {
            Stage::Ga(config) => Ga { config: config.clone() }.minimize(problem, start, observer),
            Stage::Lm(config) => LevenbergMarquardt { config: config.clone() }.minimize(problem, start, observer),
        }
    }
}
