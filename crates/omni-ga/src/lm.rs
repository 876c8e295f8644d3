//! Levenberg–Marquardt polish, adapting the `levenberg-marquardt` crate (MINPACK's algorithm) to
//! [`LeastSquares`] problems.
//!
//! Unbounded: the calibration layer decides what leaving the GA's box means (it reports it). Guarantee:
//! the returned cost is never higher than the cost at `start` — when the solver fails, returns a worse
//! point or meets a non-finite residual, the start is returned with [`Termination::NoImprovement`].
//! `evaluations` counts residual and Jacobian evaluations as the crate reports them. The observer is called
//! once, after the solve.

use crate::error::OptimizeError;
use crate::observe::{Iteration, Observer};
use crate::optimizer::{Optimizer, Solution, Termination, check_start};
use crate::problem::LeastSquares;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt as Solver};
use nalgebra::storage::Owned;
use nalgebra::{DMatrix, DVector, Dyn};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Solver settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LmConfig {
    /// Budget of residual evaluations (the crate counts in units of `n + 1`; each also needs a Jacobian,
    /// `2n` residual evaluations by central differences). Default 60.
    pub max_evaluations: usize,
    /// Relative reduction of the sum of squares that counts as converged. Default 1e-9.
    pub ftol: f64,
    /// Relative step that counts as converged. Default 1e-9.
    pub xtol: f64,
    /// Gradient orthogonality that counts as converged. Default 1e-12.
    pub gtol: f64,
}

impl Default for LmConfig {
    fn default() -> Self {
        Self { max_evaluations: 60, ftol: 1e-9, xtol: 1e-9, gtol: 1e-12 }
    }
}

/// The Levenberg–Marquardt optimizer.
#[derive(Clone, Debug, Default)]
pub struct LevenbergMarquardt {
    /// Settings.
    pub config: LmConfig,
}

struct Adapter<'a, P: LeastSquares + ?Sized> {
    problem: &'a P,
    x: DVector<f64>,
}

impl<P: LeastSquares + ?Sized> LeastSquaresProblem<f64, Dyn, Dyn> for Adapter<'_, P> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.x.copy_from(x);
    }
    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }
    fn residuals(&self) -> Option<DVector<f64>> {
        let r = self.problem.residuals(self.x.as_slice());
        if r.iter().all(|v| v.is_finite()) { Some(DVector::from_vec(r)) } else { None }
    }
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let j = self.problem.jacobian(self.x.as_slice());
        if j.iter().all(|v| v.is_finite()) { Some(j) } else { None }
    }
}

impl<P: LeastSquares + ?Sized> Optimizer<P> for LevenbergMarquardt {
    fn name(&self) -> &'static str {
        "lm"
    }

    fn minimize(&mut self, problem: &P, start: &[f64], observer: &mut dyn Observer) -> Result<Solution, OptimizeError> {
        check_start(start, problem.bounds().len())?;
        let t0 = Instant::now();
        observer.on_start("lm", start.len());
        let start_cost = problem.cost(start);
        let n = start.len().max(1);
        let patience = (self.config.max_evaluations / (n + 1)).max(1);
        let solver = Solver::new()
            .with_ftol(self.config.ftol)
            .with_xtol(self.config.xtol)
            .with_gtol(self.config.gtol)
            .with_patience(patience);
        let (adapter, report) = solver.minimize(Adapter { problem, x: DVector::from_column_slice(start) });
        let x: Vec<f64> = adapter.x.iter().copied().collect();
        let cost = if x.iter().all(|v| v.is_finite()) { problem.cost(&x) } else { f64::INFINITY };
        let evaluations = report.number_of_evaluations + 2;
        let improved = cost.is_finite() && cost <= start_cost;
        let solution = Solution {
            params: if improved { x } else { start.to_vec() },
            cost: if improved { cost } else { start_cost },
            iterations: 1,
            evaluations,
            termination: if improved { Termination::LocalMinimum } else { Termination::NoImprovement },
            seconds: t0.elapsed().as_secs_f64(),
        };
        observer.on_iteration(&Iteration {
            optimizer: "lm",
            iteration: 1,
            best_cost: solution.cost,
            mean_cost: solution.cost,
            evaluations,
            elapsed_s: solution.seconds,
            best_params: solution.params.clone(),
        });
        observer.on_finish(&solution);
        Ok(solution)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observe::NoopObserver;
    use crate::problem::{Bounds, Problem};

    /// Fit y = a·exp(−b·t) + c.
    struct Decay {
        b: Bounds,
        t: Vec<f64>,
        y: Vec<f64>,
        nan: bool,
    }
    impl Problem for Decay {
        fn bounds(&self) -> &Bounds {
            &self.b
        }
        fn cost(&self, x: &[f64]) -> f64 {
            self.residuals(x).iter().map(|r| r * r).sum()
        }
    }
    impl LeastSquares for Decay {
        fn residuals(&self, x: &[f64]) -> Vec<f64> {
            if self.nan {
                return vec![f64::NAN; self.t.len()];
            }
            self.t.iter().zip(&self.y).map(|(t, y)| x[0] * (-x[1] * t).exp() + x[2] - y).collect()
        }
    }

    fn decay(nan: bool) -> Decay {
        let t: Vec<f64> = (0..40).map(|i| i as f64 * 0.1).collect();
        let y = t.iter().map(|t| 2.5 * (-1.3 * t).exp() + 0.4).collect();
        Decay { b: Bounds::new(vec![f64::NEG_INFINITY; 3], vec![f64::INFINITY; 3]).unwrap(), t, y, nan }
    }

    #[test]
    fn fits_a_nonlinear_curve() {
        let s = LevenbergMarquardt::default().minimize(&decay(false), &[1.0, 0.5, 0.0], &mut NoopObserver).unwrap();
        for (got, want) in s.params.iter().zip([2.5, 1.3, 0.4]) {
            assert!((got - want).abs() < 1e-6, "{:?}", s.params);
        }
    }

    #[test]
    fn fd_jacobian_matches_analytic() {
        let p = decay(false);
        let x = [2.0, 1.0, 0.1];
        let j = p.jacobian(&x);
        for (r, t) in p.t.iter().enumerate() {
            let e = (-x[1] * t).exp();
            let analytic = [e, -x[0] * t * e, 1.0];
            for c in 0..3 {
                assert!((j[(r, c)] - analytic[c]).abs() <= 1e-6 * analytic[c].abs().max(1.0));
            }
        }
    }

    #[test]
    fn never_worse_than_start() {
        let opt = [2.5, 1.3, 0.4];
        let s = LevenbergMarquardt::default().minimize(&decay(false), &opt, &mut NoopObserver).unwrap();
        assert!(s.cost <= decay(false).cost(&opt));
        let s = LevenbergMarquardt::default().minimize(&decay(true), &[1.0, 1.0, 1.0], &mut NoopObserver).unwrap();
        assert_eq!(s.termination, Termination::NoImprovement);
        assert_eq!(s.params, vec![1.0, 1.0, 1.0]);
    }
}
