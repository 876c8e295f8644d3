//! Levenberg–Marquardt polish of [`LeastSquares`] problems, two ways:
//!
//! - up to [`LmConfig::normal_equations_above`] residuals (fewer with more than [`QR_PARAMS`] parameters:
//!   [`LmConfig::on_normal_equations`]), the `levenberg-marquardt` crate (MINPACK's algorithm: a pivoted QR
//!   of the whole Jacobian each iteration);
//! - beyond, Marquardt's method on the normal equations: `JᵀJ` and `Jᵀr` come from
//!   [`LeastSquares::normal_equations`] (accumulated block by block by problems with many residuals), and
//!   each step solves the `n × n` system
//!   $$\left(\hat A + \mu I\right) y = -D^{-1} J^\top r,\quad \hat A = D^{-1} J^\top J D^{-1},\quad \delta = D^{-1} y$$
//!   by Cholesky, with `D²` the largest diagonal of `JᵀJ` seen so far (MINPACK's scaling). A step is kept
//!   when it lowers `rᵀr`; `μ` follows Nielsen's rule (shrunk by `max(1/3, 1 − (2ρ − 1)³)` on a kept step
//!   with gain ratio `ρ`, doubled-and-growing on a rejected one). Memory: `n × n`, whatever the number of
//!   residuals; forming `JᵀJ` squares the condition number, harmless for the few well-scaled parameters
//!   of a calibration.
//!
//! Unbounded: the calibration layer decides what leaving the GA's box means (it reports it). Guarantee:
//! the returned cost is never higher than the cost at `start` — when the solver fails, returns a worse
//! point or meets a non-finite residual, the start is returned with [`Termination::NoImprovement`]; a
//! solve that spent its budget before a convergence test was met ends with [`Termination::MaxEvaluations`]
//! (its point kept), otherwise [`Termination::LocalMinimum`].
//! `evaluations` counts residual and Jacobian evaluations (as the crate reports them; on the normal
//! equations, each residual vector and each set of normal equations counts one). The observer is called
//! once, after the solve.

use crate::optimizer::error::OptimizeError;
use crate::optimizer::observe::{Iteration, Observer};
use crate::optimizer::problem::{LeastSquares, NormalEquations};
use crate::optimizer::{Optimizer, Solution, Termination, check_start};
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
    /// Number of residuals above which the polish solves the normal equations instead of handing the whole
    /// Jacobian to the crate (see the module docs). Default 50,000 (a 3.6 MB Jacobian at 9 parameters; the
    /// paper-size path objective has 24,000 residuals and keeps the crate). Beyond it the crate's pivoted
    /// QR, one Householder pass over the whole Jacobian per column and iteration, dominated a diagnosis:
    /// on OptiOdom omni4 `080920201715` (140k residuals, 12–20 parameters) 54 % of `diagnose`; `JᵀJ` by
    /// one blocked product takes a fraction of that. Below it, the crate's QR was as fast or faster (a
    /// simulated 108-run set: 3.3 s against 4.1 s for the whole diagnosis on the normal equations).
    #[serde(default = "default_normal_equations_above")]
    pub normal_equations_above: usize,
}

/// The scout's share of a budget ([`LmConfig::scout`]): a sixth, 10 of the default 60 residual evaluations.
/// On the shared OptiOdom robots (`diagnose --auto` on four sets, 50 scouted fits), most fits that converge
/// do so within 8 trial steps (a few take 15–18), while those crawling along directions the runs hardly
/// constrain spend any budget: stopping them at 10 rather than 20 steps halves the scout's cost where it
/// matters (the explorer's 48-parameter `wheel` family: 3.1 of its 5.1 s on omni4) and changed no verdict
/// there. A third (20) until 2026-11-29.
pub const SCOUT_SHARE: usize = 6;

/// Parameters at which [`LmConfig::normal_equations_above`] residuals mark where the crate's QR stops
/// paying ([`LmConfig::on_normal_equations`]): the omni4 base matrix's 12.
pub const QR_PARAMS: usize = 12;

fn default_normal_equations_above() -> usize {
    50_000
}

impl LmConfig {
    /// The same settings with a sixth of the budget ([`SCOUT_SHARE`]), when that is smaller than the whole budget on a problem
    /// of `n_params` parameters and `n_residuals` residuals (the crate counts in units of `n + 1`, so a
    /// large `n` leaves nothing to cut); `None` otherwise.
    pub fn scout(&self, n_params: usize, n_residuals: usize) -> Option<LmConfig> {
        let scout = LmConfig { max_evaluations: (self.max_evaluations / SCOUT_SHARE).max(1), ..self.clone() };
        let smaller = if self.on_normal_equations(n_params, n_residuals) {
            scout.max_evaluations < self.max_evaluations
        } else {
            scout.crate_patience(n_params) < self.crate_patience(n_params)
        };
        smaller.then_some(scout)
    }

    /// Whether a problem of `n_params` parameters and `n_residuals` residuals is solved on the normal
    /// equations: beyond [`Self::normal_equations_above`] residuals, or where the crate's pivoted QR (its
    /// cost per iteration grows with residuals × parameters², unblocked) would cost more than it does there
    /// at [`QR_PARAMS`] parameters. Many parameters on a few thousand residuals (the explorer's 48-term
    /// `wheel` family on a simulated 108-run set: 14k residuals, the QR 32 % of the fit) go to the normal
    /// equations; at 12 parameters or fewer the rule is the residual count alone.
    pub fn on_normal_equations(&self, n_params: usize, n_residuals: usize) -> bool {
        let qr_cost = n_residuals.saturating_mul(n_params.saturating_mul(n_params));
        n_residuals > self.normal_equations_above
            || qr_cost > self.normal_equations_above.saturating_mul(QR_PARAMS * QR_PARAMS)
    }

    /// The budget as the crate's patience on `n_params` parameters (it counts in units of `n + 1`).
    fn crate_patience(&self, n_params: usize) -> usize {
        (self.max_evaluations / (n_params.max(1) + 1)).max(1)
    }
}

impl Default for LmConfig {
    fn default() -> Self {
        Self {
            max_evaluations: 60,
            ftol: 1e-9,
            xtol: 1e-9,
            gtol: 1e-12,
            normal_equations_above: default_normal_equations_above(),
        }
    }
}

/// Where a solve ended.
struct Ended {
    /// The point.
    x: Vec<f64>,
    /// Residual and Jacobian evaluations.
    evaluations: usize,
    /// The evaluation budget ran out before a convergence test was met.
    out_of_budget: bool,
}

/// Initial damping of the normal-equations solver, relative to the scaled `JᵀJ`'s unit diagonal.
const INITIAL_DAMPING: f64 = 1e-3;
/// Damping beyond which the normal-equations solver gives up (the step would be nil).
const MAX_DAMPING: f64 = 1e16;

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

impl LevenbergMarquardt {
    /// The crate's solver (QR of the whole Jacobian). Returns the point it ends at, its evaluations and
    /// whether it spent its budget.
    fn solve_with_crate<P: LeastSquares + ?Sized>(&self, problem: &P, start: &[f64]) -> Ended {
        let patience = self.config.crate_patience(start.len());
        let solver = Solver::new()
            .with_ftol(self.config.ftol)
            .with_xtol(self.config.xtol)
            .with_gtol(self.config.gtol)
            .with_patience(patience);
        let (adapter, report) = solver.minimize(Adapter { problem, x: DVector::from_column_slice(start) });
        Ended {
            x: adapter.x.iter().copied().collect(),
            evaluations: report.number_of_evaluations,
            out_of_budget: report.termination == levenberg_marquardt::TerminationReason::LostPatience,
        }
    }

    /// Marquardt's method on the normal equations (see the module docs). Returns the last kept point (the
    /// start when no step lowered `rᵀr`), the evaluations (at most `max_evaluations` residual vectors,
    /// plus one set of normal equations per kept step) and whether it spent its budget.
    fn solve_normal_equations<P: LeastSquares + ?Sized>(&self, problem: &P, start: &[f64]) -> Ended {
        let cfg = &self.config;
        let ne = problem.normal_equations(start);
        let mut evaluations = 1;
        let mut trials = 0;
        if !ne.is_finite() || start.is_empty() {
            return Ended { x: start.to_vec(), evaluations, out_of_budget: false };
        }
        let mut m = Marquardt::new(start, ne);
        let out_of_budget = loop {
            if trials >= cfg.max_evaluations {
                break true;
            }
            if m.converged(cfg.gtol) {
                break false;
            }
            let t = match m.propose(cfg.xtol) {
                Proposal::Nothing => break false,
                // Not positive definite at this damping (rounding on a near-singular JᵀJ): damp more.
                Proposal::Singular if m.damp_more() => continue,
                Proposal::Singular => break false,
                Proposal::Step(t) => t,
            };
            let f = m.ne.rtr;
            let f_new = sum_of_squares(&problem.residuals(t.x.as_slice()));
            evaluations += 1;
            trials += 1;
            if f_new < f && t.predicted > 0.0 {
                let rho = (f - f_new) / t.predicted;
                let converged = f - f_new <= cfg.ftol * f || t.small;
                let next = problem.normal_equations(t.x.as_slice());
                evaluations += 1;
                if !next.is_finite() {
                    m.x = t.x;
                    break false;
                }
                m.accept(t.x, next, rho);
                if converged {
                    break false;
                }
            } else if t.small || !m.damp_more() {
                break false;
            }
        };
        Ended { x: m.x.iter().copied().collect(), evaluations, out_of_budget }
    }
}

/// `rᵀr`, or `inf` when a residual is not finite.
fn sum_of_squares(r: &[f64]) -> f64 {
    if r.iter().all(|v| v.is_finite()) { r.iter().map(|v| v * v).sum::<f64>() } else { f64::INFINITY }
}

/// The state of Marquardt's method on the normal equations: the point, its normal equations, the largest
/// diagonal of `JᵀJ` seen so far (`D²`) and the damping `μ` with its growth factor `ν`.
struct Marquardt {
    x: DVector<f64>,
    ne: NormalEquations,
    scale: DVector<f64>,
    mu: f64,
    nu: f64,
}

/// A damped step to try.
struct Trial {
    /// The point it leads to.
    x: DVector<f64>,
    /// Decrease of `rᵀr` the linear model predicts.
    predicted: f64,
    /// The step is below `xtol` (relative, scaled).
    small: bool,
}

/// What the damped system gives at the current damping.
enum Proposal {
    /// `J = 0`: nothing moves the residuals.
    Nothing,
    /// The damped matrix is not positive definite.
    Singular,
    /// A step to try.
    Step(Trial),
}

impl Marquardt {
    fn new(start: &[f64], ne: NormalEquations) -> Self {
        let scale = DVector::from_fn(start.len(), |i, _| ne.jtj[(i, i)]);
        Self { x: DVector::from_column_slice(start), ne, scale, mu: INITIAL_DAMPING, nu: 2.0 }
    }

    /// Converged when `rᵀr = 0` or the residuals are orthogonal to every column of J (MINPACK's gtol test).
    fn converged(&self, gtol: f64) -> bool {
        let (ne, f) = (&self.ne, self.ne.rtr);
        let cosine = (0..self.x.len())
            .filter(|&i| ne.jtj[(i, i)] > 0.0)
            .map(|i| ne.jtr[i].abs() / (ne.jtj[(i, i)] * f).sqrt())
            .fold(0.0f64, f64::max);
        f == 0.0 || cosine <= gtol
    }

    /// The step solving `(Â + μI) y = −D⁻¹Jᵀr` (see the module docs).
    fn propose(&self, xtol: f64) -> Proposal {
        let (n, ne) = (self.x.len(), &self.ne);
        let top = self.scale.max();
        if top <= 0.0 {
            return Proposal::Nothing;
        }
        let d = self.scale.map(|v| v.max(f64::EPSILON * top).sqrt());
        let b = DVector::from_fn(n, |i, _| -ne.jtr[i] / d[i]);
        let mut a = DMatrix::from_fn(n, n, |i, j| ne.jtj[(i, j)] / (d[i] * d[j]));
        for i in 0..n {
            a[(i, i)] += self.mu;
        }
        let Some(y) = a.cholesky().map(|c| c.solve(&b)) else { return Proposal::Singular };
        let step = DVector::from_fn(n, |i, _| y[i] / d[i]);
        let scaled_x = self.x.component_mul(&d).norm();
        let small = y.norm() <= xtol * scaled_x.max(xtol);
        // Predicted decrease of rᵀr by the linear model: yᵀb + μ yᵀy.
        let predicted = y.dot(&b) + self.mu * y.dot(&y);
        Proposal::Step(Trial { x: &self.x + &step, predicted, small })
    }

    /// After a rejected step: more damping. False once it is past [`MAX_DAMPING`] (the step would be nil).
    fn damp_more(&mut self) -> bool {
        self.mu *= self.nu;
        self.nu *= 2.0;
        self.mu <= MAX_DAMPING
    }

    /// Keeps a step with gain ratio `rho`: moves to `x` with its normal equations `ne`, and relaxes the
    /// damping (Nielsen).
    fn accept(&mut self, x: DVector<f64>, ne: NormalEquations, rho: f64) {
        self.x = x;
        self.ne = ne;
        for i in 0..self.x.len() {
            self.scale[i] = self.scale[i].max(self.ne.jtj[(i, i)]);
        }
        self.mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
        self.nu = 2.0;
    }
}

impl<P: LeastSquares + ?Sized> Optimizer<P> for LevenbergMarquardt {
    fn name(&self) -> &'static str {
        "lm"
    }

    fn minimize(&mut self, problem: &P, start: &[f64], observer: &mut dyn Observer) -> Result<Solution, OptimizeError> {
        check_start(start, problem.bounds().len())?;
        let t0 = Instant::now();
        observer.on_start("lm", start.len(), None);
        let start_cost = problem.cost(start);
        let Ended { x, evaluations, out_of_budget } =
            if self.config.on_normal_equations(start.len(), problem.residual_count(start)) {
                self.solve_normal_equations(problem, start)
            } else {
                self.solve_with_crate(problem, start)
            };
        let cost = if x.iter().all(|v| v.is_finite()) { problem.cost(&x) } else { f64::INFINITY };
        let evaluations = evaluations + 2;
        let improved = cost.is_finite() && cost <= start_cost;
        let solution = Solution {
            params: if improved { x } else { start.to_vec() },
            cost: if improved { cost } else { start_cost },
            iterations: 1,
            evaluations,
            termination: match (improved, out_of_budget) {
                (false, _) => Termination::NoImprovement,
                (true, true) => Termination::MaxEvaluations,
                (true, false) => Termination::LocalMinimum,
            },
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
    use crate::optimizer::observe::NoopObserver;
    use crate::optimizer::problem::{Bounds, Problem};

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

    /// Always the normal-equations solver.
    fn on_normal_equations() -> LevenbergMarquardt {
        LevenbergMarquardt { config: LmConfig { normal_equations_above: 0, ..LmConfig::default() } }
    }

    #[test]
    fn normal_equations_fit_a_nonlinear_curve() {
        let s = on_normal_equations().minimize(&decay(false), &[1.0, 0.5, 0.0], &mut NoopObserver).unwrap();
        for (got, want) in s.params.iter().zip([2.5, 1.3, 0.4]) {
            assert!((got - want).abs() < 1e-6, "{:?}", s.params);
        }
        assert_eq!(s.termination, Termination::LocalMinimum);
        let opt = [2.5, 1.3, 0.4];
        let s = on_normal_equations().minimize(&decay(false), &opt, &mut NoopObserver).unwrap();
        assert!(s.cost <= decay(false).cost(&opt));
        let s = on_normal_equations().minimize(&decay(true), &[1.0, 1.0, 1.0], &mut NoopObserver).unwrap();
        assert_eq!(s.termination, Termination::NoImprovement);
        assert_eq!(s.params, vec![1.0, 1.0, 1.0]);
    }

    #[test]
    fn normal_equations_default_matches_the_jacobian() {
        let p = decay(false);
        let x = [2.0, 1.0, 0.1];
        let (r, j) = (p.residuals(&x), p.jacobian(&x));
        let ne = p.normal_equations(&x);
        assert_eq!(ne.rows, 40);
        assert!((ne.jtj.clone() - j.transpose() * &j).abs().max() < 1e-12);
        assert!((ne.jtr.clone() - j.transpose() * DVector::from_vec(r.clone())).abs().max() < 1e-12);
        assert!((ne.rtr - r.iter().map(|v| v * v).sum::<f64>()).abs() < 1e-12);
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
