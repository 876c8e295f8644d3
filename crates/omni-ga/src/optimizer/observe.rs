//! Observers: called by the optimizers once per iteration (GA generation); they can stop a run. The hook
//! for progress bars, logs and Python callbacks.

use crate::optimizer::Solution;
use serde::{Deserialize, Serialize};

/// What an optimizer reports each iteration.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Iteration {
    /// `ga` or `lm`.
    pub optimizer: &'static str,
    /// Iteration (generation) number, from 1.
    pub iteration: usize,
    /// Best cost so far.
    pub best_cost: f64,
    /// Mean finite cost of this iteration's population (the best cost for LM).
    pub mean_cost: f64,
    /// Cost evaluations so far.
    pub evaluations: usize,
    /// Wall time since the start. s.
    pub elapsed_s: f64,
    /// Best parameters so far.
    pub best_params: Vec<f64>,
}

/// Whether to go on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    /// Keep going.
    Continue,
    /// Stop now and return the best so far.
    Stop,
}

/// Receives progress; every method has a do-nothing default.
pub trait Observer {
    /// Called once before the first iteration: the optimizer's name (`ga`, `lm`), the number of parameters,
    /// and its iteration budget when it has one (the GA's generations; `None` for a solver that stops on
    /// convergence, such as Levenberg–Marquardt), so that a progress display needs no knowledge of optimizers.
    fn on_start(&mut self, _optimizer: &str, _dim: usize, _max_iterations: Option<usize>) {}
    /// Called after each iteration; `Control::Stop` ends the run.
    fn on_iteration(&mut self, _it: &Iteration) -> Control {
        Control::Continue
    }
    /// Called once with the result.
    fn on_finish(&mut self, _solution: &Solution) {}
}

/// An observer that does nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoopObserver;

impl Observer for NoopObserver {}

/// An observer from a closure over each iteration.
pub struct FnObserver<F: FnMut(&Iteration) -> Control>(pub F);

impl<F: FnMut(&Iteration) -> Control> Observer for FnObserver<F> {
    fn on_iteration(&mut self, it: &Iteration) -> Control {
        (self.0)(it)
    }
}
