//! Calibration: fit a model's parameters to training runs, the paper's way (`Preset::Paper`) or ours
//! (`Preset::Default`).
//!
//! | | `paper` (reproduces the paper) | `default` (ours) |
//! |---|---|---|
//! | objective | Eq. 6 end-pose cost | path cost (every ground-truth pose, 1 m/rad) |
//! | odometry | Eq. 1, Euler, 10 ms fixed step | exact arcs, each run's median step |
//! | search | MATLAB-default GA, 200 individuals, stall 50 generations, tol 1e-6 divided by max(1, \|best\|) | small GA (24 × ≤ 30 generations, scale-aware stall rule) then Levenberg–Marquardt |
//! | bounds | ±10 % of each design value (pins zero entries, e.g. m12 = 0, as Eq. 9) | GA: ±10 % of each row's largest magnitude; the polish is unbounded |
//! | unconstrained directions ([`crate::identify`]) | move freely | held at the start: truncated update ([`Unexcited::Hold`]) |
//!
//! Every fit reports the parameters that ended on a GA bound and those the polish moved outside the box,
//! so a trapped fit is never silent. The polish never returns a higher objective than its start.

use crate::error::OptimizeError;
use crate::ga::{Ga, GaConfig, StallRule};
use crate::identify::{self, Identifiability, IdentifyOptions, WeakDirection};
use crate::lm::{LevenbergMarquardt, LmConfig};
use crate::observe::Observer;
use crate::optimizer::{Optimizer, Solution, Termination};
use crate::problem::{
    Bounds, LeastSquares, NormalEquations, Problem, finite_difference_columns, finite_difference_jacobian,
};
use nalgebra::DMatrix;
use omni_kin::cost::{self, CostKind};
use omni_kin::evaluate::Evaluator;
use omni_kin::{FittedModel, Integration, KinError, Model, Run};
use serde::{Deserialize, Serialize};
use std::time::Instant;
use thiserror::Error;

/// A calibration failed.
#[derive(Debug, Error)]
pub enum CalibrateError {
    /// The model or runs are not usable.
    #[error(transparent)]
    Kin(#[from] KinError),
    /// The optimizer refused its inputs.
    #[error(transparent)]
    Optimize(#[from] OptimizeError),
    /// Nothing to fit.
    #[error("no training runs")]
    NoRuns,
}

/// Which recipe to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// The paper's method, reproduced.
    Paper,
    /// Ours: path cost, exact arcs, short GA + LM polish.
    Default,
}

omni_kin::choice!(Preset, default = Default, {
    Paper => "paper": "The paper's method, reproduced: Eq. 6 end-pose cost, Eq. 1 Euler at 10 ms, MATLAB-default GA, ±10 % box",
    Default => "default": "Ours: path cost, exact arcs, short GA then Levenberg–Marquardt",
});

/// How the GA's search box is set around the start.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxRule {
    /// ±fraction of each start value (zero entries pinned). Paper: 0.10.
    PerValue(f64),
    /// ±fraction of each base parameter's scale at the start (the kinematics' `param_scales`: for `ik` the
    /// largest magnitude in the entry's matrix row; for `geometry` the value of r, R, and 1 rad for
    /// angles). Default: 0.10.
    PerRow(f64),
}

/// What a fit does along directions of parameter space the training runs do not constrain
/// ([`crate::identify`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Unexcited {
    /// Truncated update (default preset): after the GA, the parameters are projected back onto the start
    /// along every unconstrained direction, and the polish moves only within the constrained subspace, so
    /// the fit keeps the start (design) values where the data cannot tell, and is never worse than the
    /// start on motions the training runs did not contain.
    Hold,
    /// Move freely (the paper's GA): unconstrained directions end wherever the search left them.
    Move,
}

omni_kin::choice!(Unexcited, default = Hold, {
    Hold => "hold": "Keep the start (design) values there: truncated update (default preset)",
    Move => "move": "Let the optimizer move them (paper preset)",
});

/// A calibration recipe.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Plan {
    /// The preset it came from.
    pub preset: Preset,
    /// Objective minimised.
    pub objective: CostKind,
    /// Odometry integration used during the fit (and stored in the fitted model).
    pub integration: Integration,
    /// GA settings (`None`: skip the GA).
    pub ga: Option<GaConfig>,
    /// Run Levenberg–Marquardt from the GA result.
    pub polish: bool,
    /// Search box of the GA.
    pub box_rule: BoxRule,
    /// What to do along unconstrained directions.
    #[serde(default)]
    pub unexcited: Unexcited,
    /// When a direction counts as unconstrained.
    #[serde(default)]
    pub identify: IdentifyOptions,
}

impl Plan {
    /// The recipe of a preset for a model with `n_params` parameters.
    pub fn preset(preset: Preset, n_params: usize) -> Self {
        match preset {
            Preset::Paper => Plan {
                preset,
                objective: CostKind::EndPose,
                integration: Integration::PAPER,
                ga: Some(GaConfig::matlab_defaults(n_params)),
                polish: false,
                box_rule: BoxRule::PerValue(0.10),
                unexcited: Unexcited::Move,
                identify: IdentifyOptions::default(),
            },
            Preset::Default => {
                let mut ga = GaConfig::matlab_defaults(n_params);
                ga.population = 24;
                ga.elite = 2;
                ga.stall_generations = 8;
                ga.function_tolerance = 1e-4;
                ga.stall_rule = StallRule::Relative;
                ga.max_generations = 30;
                Plan {
                    preset,
                    objective: CostKind::PATH,
                    integration: Integration::DEFAULT,
                    ga: Some(ga),
                    polish: true,
                    box_rule: BoxRule::PerRow(0.10),
                    unexcited: Unexcited::Hold,
                    identify: IdentifyOptions::default(),
                }
            }
        }
    }

    /// The same plan with another GA seed.
    pub fn seed(mut self, seed: u64) -> Self {
        if let Some(ga) = &mut self.ga {
            ga.seed = seed;
        }
        self
    }
}

/// The fitting problem: a model structure, training runs and an objective.
///
/// Costs, residuals and the IK part of the Jacobian come from one [`Evaluator`]: the fast kernel where it
/// serves the parameters, the literal walk otherwise (a clock lag, twist-stage effects).
///
/// Its residuals are grouped by run; [`Self::for_each_run_block`] visits each run's residuals with their
/// Jacobian rows, and the normal equations are accumulated from those blocks, so the Levenberg–Marquardt
/// polish of a large dataset never holds the whole Jacobian.
#[derive(Debug)]
pub struct CalibrationProblem<'a> {
    model: &'a Model,
    runs: &'a [Run],
    objective: CostKind,
    bounds: Bounds,
    evaluator: Evaluator<'a>,
    /// Where each run's residuals start in [`LeastSquares::residuals`]; one more entry: the total.
    row_offsets: Vec<usize>,
}

/// One run's part of the least-squares system, as [`CalibrationProblem::for_each_run_block`] visits it.
#[derive(Clone, Copy, Debug)]
pub struct RunBlock<'a> {
    /// Index of the run.
    pub run: usize,
    /// Its residuals: rows `row_offset..row_offset + residuals.len()` of [`LeastSquares::residuals`].
    pub residuals: &'a [f64],
    /// Where they start in the stacked residual vector.
    pub row_offset: usize,
    /// Their Jacobian with respect to every parameter (`residuals.len() × n_params`): the same rows as
    /// [`LeastSquares::jacobian`].
    pub jacobian: &'a DMatrix<f64>,
}

impl<'a> CalibrationProblem<'a> {
    /// A problem over `runs`. Checks wheel counts.
    pub fn new(model: &'a Model, runs: &'a [Run], objective: CostKind, bounds: Bounds) -> Result<Self, CalibrateError> {
        if runs.is_empty() {
            return Err(CalibrateError::NoRuns);
        }
        let evaluator = Evaluator::for_cost(model, runs, objective)?;
        let selection = objective.selection();
        let mut row_offsets = Vec::with_capacity(runs.len() + 1);
        let mut rows = 0;
        row_offsets.push(rows);
        for r in runs {
            rows += 3 * selection.indices(r.truth().len()).len();
            row_offsets.push(rows);
        }
        Ok(Self { model, runs, objective, bounds, evaluator, row_offsets })
    }

    /// Visits each run's residuals and Jacobian rows ([`RunBlock`]), in run order: the numbers of
    /// [`LeastSquares::residuals`] and [`LeastSquares::jacobian`], cut by run (the residuals to rounding:
    /// the fast kernel's differentiating walk is scalar, its cost walk uses FMA). Where the fast kernel serves
    /// `x`, only a few hundred runs' rows are held at a time (plus, for effect parameters, their
    /// finite-difference columns over all runs); otherwise the whole Jacobian is built first and cut.
    /// Parameters that make no valid model give NaN blocks.
    pub fn for_each_run_block(&self, x: &[f64], visit: &mut dyn FnMut(RunBlock<'_>)) {
        if self.analytic_blocks(x, visit).is_some() {
            return;
        }
        let n = x.len();
        let r = self.residuals(x);
        let total = self.row_offsets.last().copied().unwrap_or(0);
        let j = if r.len() == total { self.jacobian(x) } else { DMatrix::from_element(total, n, f64::NAN) };
        let r = if r.len() == total { r } else { vec![f64::NAN; total] };
        for (run, w) in self.row_offsets.windows(2).enumerate() {
            let jacobian = j.rows(w[0], w[1] - w[0]).into_owned();
            visit(RunBlock { run, residuals: &r[w[0]..w[1]], row_offset: w[0], jacobian: &jacobian });
        }
    }

    /// The IK matrix's derivatives with respect to the base parameters (IK entries × base parameters,
    /// the kinematics' `twist_from_wheels_jacobian`); `Some(None)` when the parameters are the
    /// IK entries themselves (the identity), `None` when the model cannot be differentiated at `x`.
    fn ik_from_base(&self, x: &[f64]) -> Option<Option<DMatrix<f64>>> {
        let k = &self.model.kinematics;
        if k.params_are_ik_entries() {
            return Some(None);
        }
        k.twist_from_wheels_jacobian(&x[..self.model.n_base()]).ok().map(Some)
    }

    /// The effect parameters' Jacobian columns over all residuals (finite differences; see
    /// [`LeastSquares::jacobian`]).
    fn effect_columns(&self, x: &[f64]) -> Vec<Vec<f64>> {
        let (nb, n) = (self.model.n_base(), x.len());
        if n <= nb {
            return Vec::new();
        }
        let specs = self.model.params();
        let at_range_end = |i: usize| specs.get(i).is_some_and(|s| s.lower == x[i] && s.upper > s.lower);
        finite_difference_columns(x, nb..n, |y| self.residuals(y), at_range_end)
    }

    /// [`Self::for_each_run_block`] through the fast kernel; `None` (before any visit) when it cannot
    /// serve `x`.
    fn analytic_blocks(&self, x: &[f64], visit: &mut dyn FnMut(RunBlock<'_>)) -> Option<()> {
        let res = self.model.resolve(x).ok()?;
        let dm = self.ik_from_base(x)?;
        let (nb, n) = (self.model.n_base(), x.len());
        let mut effects: Option<Vec<Vec<f64>>> = None;
        self.evaluator.ik_jacobian_blocks(&res, self.objective, &mut |b| {
            let row_offset = self.row_offsets[b.run];
            let rows = b.residuals.len();
            let mut j = DMatrix::zeros(rows, n);
            match &dm {
                None => j.columns_mut(0, nb).copy_from(b.jacobian),
                Some(dm) => j.columns_mut(0, nb).copy_from(&(b.jacobian * dm)),
            }
            // The effect columns come from whole residual vectors: computed once, at the first block.
            let cols = effects.get_or_insert_with(|| self.effect_columns(x));
            for (c, col) in (nb..n).zip(cols.iter()) {
                for (i, v) in col.iter().skip(row_offset).take(rows).enumerate() {
                    j[(i, c)] = *v;
                }
            }
            visit(RunBlock { run: b.run, residuals: b.residuals, row_offset, jacobian: &j });
        })
    }

    /// Residual rows of each run, in run order (3 per selected ground-truth pose).
    pub fn run_rows(&self) -> Vec<usize> {
        self.row_offsets.windows(2).map(|w| w[1] - w[0]).collect()
    }

    /// What the runs constrain at `x` ([`identify::analyse`] on this problem's residuals).
    pub fn identifiability(&self, x: &[f64], opts: &IdentifyOptions) -> Identifiability {
        let mut moments = identify::Moments::new(x.len());
        self.for_each_run_block(x, &mut |b| moments.add_run(b.jacobian, b.residuals));
        identify::analyse(self.model, x, &moments, Some(&self.wheel_moment()), opts)
    }

    /// Mean `w wᵀ` of the training runs' wheel speeds (rad²/s²), every sample weighted equally.
    pub fn wheel_moment(&self) -> DMatrix<f64> {
        let n = self.model.n_wheels();
        let mut s = DMatrix::zeros(n, n);
        let mut count = 0usize;
        for run in self.runs {
            for k in 0..run.n_samples() {
                let w = run.wheel_sample(k);
                for a in 0..n {
                    for b in 0..n {
                        s[(a, b)] += w[a] * w[b];
                    }
                }
            }
            count += run.n_samples();
        }
        if count > 0 {
            s /= count as f64;
        }
        s
    }

    /// The residuals and their Jacobian: the IK (or geometry) columns analytically through the fast
    /// kernel, the effect columns by finite differences. `None` when the fast kernel cannot serve `x`.
    fn analytic(&self, x: &[f64]) -> Option<(Vec<f64>, DMatrix<f64>)> {
        let total = self.row_offsets.last().copied().unwrap_or(0);
        let mut r = Vec::with_capacity(total);
        let mut j = DMatrix::zeros(total, x.len());
        self.analytic_blocks(x, &mut |b| {
            r.extend_from_slice(b.residuals);
            j.rows_mut(b.row_offset, b.residuals.len()).copy_from(b.jacobian);
        })?;
        Some((r, j))
    }
}

impl Problem for CalibrationProblem<'_> {
    fn bounds(&self) -> &Bounds {
        &self.bounds
    }
    /// The objective; `f64::INFINITY` where the parameters make no valid model (e.g. singular geometry).
    fn cost(&self, x: &[f64]) -> f64 {
        match self.model.resolve(x) {
            Ok(res) => self.evaluator.cost(&res, self.objective),
            Err(_) => f64::INFINITY,
        }
    }
}

impl LeastSquares for CalibrationProblem<'_> {
    /// Stacked residuals whose squared norm is the squared path cost (or mean squared end-pose error).
    fn residuals(&self, x: &[f64]) -> Vec<f64> {
        match self.model.resolve(x) {
            Ok(res) => self.evaluator.residual_vector(&res, self.objective),
            Err(_) => vec![f64::NAN; 3 * self.runs.len()],
        }
    }

    /// Analytic (forward-mode) columns for the IK matrix or geometry when the fast kernel serves `x`;
    /// otherwise, and for effect parameters, central differences (step `1e-6 · max(|x_i|, 1e-3)`), except
    /// forward differences for a parameter sitting on the lower end of its physical range (e.g. backlash at
    /// 0, whose model uses `|b|`), where a central difference would see a symmetric kink and report zero
    /// sensitivity.
    fn jacobian(&self, x: &[f64]) -> DMatrix<f64> {
        if let Some((_, j)) = self.analytic(x) {
            return j;
        }
        let specs = self.model.params();
        let at_range_end = |i: usize| specs.get(i).is_some_and(|s| s.lower == x[i] && s.upper > s.lower);
        finite_difference_jacobian(x, |y| self.residuals(y), at_range_end)
    }

    fn residual_count(&self, _x: &[f64]) -> usize {
        self.row_offsets.last().copied().unwrap_or(0)
    }

    /// Accumulated run by run ([`Self::for_each_run_block`]), in run order.
    fn normal_equations(&self, x: &[f64]) -> NormalEquations {
        let mut ne = NormalEquations::zeros(x.len());
        self.for_each_run_block(x, &mut |b| ne.add_rows(b.residuals, b.jacobian));
        ne
    }
}

/// A least-squares problem restricted to `origin + basis · z` (the truncated update's subspace).
struct Subspace<'p, P: LeastSquares> {
    inner: &'p P,
    origin: Vec<f64>,
    /// `n × k`, parameter units.
    basis: DMatrix<f64>,
    bounds: Bounds,
}

impl<'p, P: LeastSquares> Subspace<'p, P> {
    fn new(inner: &'p P, origin: Vec<f64>, basis: DMatrix<f64>) -> Result<Self, OptimizeError> {
        let k = basis.ncols();
        let bounds = Bounds::new(vec![f64::NEG_INFINITY; k], vec![f64::INFINITY; k])?;
        Ok(Self { inner, origin, basis, bounds })
    }
    fn point(&self, z: &[f64]) -> Vec<f64> {
        let dz = &self.basis * nalgebra::DVector::from_column_slice(z);
        self.origin.iter().zip(dz.iter()).map(|(o, d)| o + d).collect()
    }
}

impl<P: LeastSquares> Problem for Subspace<'_, P> {
    fn bounds(&self) -> &Bounds {
        &self.bounds
    }
    fn cost(&self, z: &[f64]) -> f64 {
        self.inner.cost(&self.point(z))
    }
}

impl<P: LeastSquares> LeastSquares for Subspace<'_, P> {
    fn residuals(&self, z: &[f64]) -> Vec<f64> {
        self.inner.residuals(&self.point(z))
    }
    fn jacobian(&self, z: &[f64]) -> DMatrix<f64> {
        self.inner.jacobian(&self.point(z)) * &self.basis
    }
    fn residual_count(&self, z: &[f64]) -> usize {
        self.inner.residual_count(&self.point(z))
    }
    /// The inner problem's normal equations (blockwise for a `CalibrationProblem`) projected on the basis
    /// `B`: `BᵀJᵀJB`, `BᵀJᵀr`.
    fn normal_equations(&self, z: &[f64]) -> NormalEquations {
        let ne = self.inner.normal_equations(&self.point(z));
        NormalEquations {
            jtj: self.basis.tr_mul(&ne.jtj) * &self.basis,
            jtr: self.basis.tr_mul(&ne.jtr),
            rtr: ne.rtr,
            rows: ne.rows,
        }
    }
}

/// The truncated update: `x` with its component along the unconstrained directions `weak` (scaled space,
/// orthonormal columns) reset to `start`'s, and a basis (parameter units) of the constrained subspace.
fn hold_unexcited(x: &[f64], start: &[f64], scales: &[f64], weak: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let n = x.len();
    let d = nalgebra::DVector::from_fn(n, |i, _| (x[i] - start[i]) / scales[i]);
    let kept = &d - weak * (weak.transpose() * &d);
    let projected = (0..n).map(|i| start[i] + scales[i] * kept[i]).collect();
    // Orthonormal complement of `weak`: eigenvectors of I − W Wᵀ with eigenvalue 1.
    let p = DMatrix::identity(n, n) - weak * weak.transpose();
    let eig = p.symmetric_eigen();
    let cols: Vec<usize> = (0..n).filter(|&i| eig.eigenvalues[i] > 0.5).collect();
    let basis = DMatrix::from_fn(n, cols.len(), |r, c| eig.eigenvectors[(r, cols[c])] * scales[r]);
    (projected, basis)
}

/// The GA search box around `start` for `model`.
pub fn search_box(model: &Model, start: &[f64], rule: BoxRule) -> Result<Bounds, OptimizeError> {
    let specs = model.params();
    let nb = model.n_base();
    let scales = model.kinematics.param_scales(&start[..nb]);
    let mut lower = Vec::with_capacity(specs.len());
    let mut upper = Vec::with_capacity(specs.len());
    for (i, s) in specs.iter().enumerate() {
        let v = start[i];
        let half = if i >= nb {
            // Effects: their own bounds, widened to contain the start.
            lower.push(s.lower.min(v));
            upper.push(s.upper.max(v));
            continue;
        } else {
            match rule {
                BoxRule::PerValue(f) => f * v.abs(),
                BoxRule::PerRow(f) => f * scales[i],
            }
        };
        lower.push(v - half);
        upper.push(v + half);
    }
    Bounds::new(lower, upper)
}

/// The outcome of a calibration.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// The fitted model (with the plan's integration).
    pub fitted: FittedModel,
    /// The start model (with the plan's integration): the design, or a previous fit.
    pub start: FittedModel,
    /// Objective minimised.
    pub objective: CostKind,
    /// Objective at the start.
    pub objective_start: f64,
    /// Objective at the fit.
    pub objective_fitted: f64,
    /// Eq. 6 end-pose cost on the training runs at the start.
    pub end_pose_start: f64,
    /// Eq. 6 end-pose cost on the training runs at the fit.
    pub end_pose_fitted: f64,
    /// Cost evaluations (GA + polish).
    pub evaluations: usize,
    /// Wall time. s.
    pub seconds: f64,
    /// The GA's search box.
    pub bounds: Bounds,
    /// Parameters the GA left on a bound of its box (a trapped fit).
    pub at_bound: Vec<String>,
    /// Parameters the polish moved outside the GA box (the box was too small).
    pub outside_box: Vec<String>,
    /// The GA's result, when it ran.
    pub ga: Option<Solution>,
    /// The polish's result, when it ran.
    pub polish: Option<Solution>,
    /// What the training runs constrain, at the fit.
    pub identifiability: Identifiability,
    /// Directions held at the start by the truncated update ([`Unexcited::Hold`]), as found after the GA.
    pub held: Vec<WeakDirection>,
}

impl Calibration {
    /// Relative improvement of the Eq. 6 training cost. %.
    pub fn improvement_pct(&self) -> f64 {
        100.0 * (1.0 - self.end_pose_fitted / self.end_pose_start)
    }
}

/// Fit `start`'s parameters to `train` following `plan`.
pub fn calibrate(
    start: &FittedModel,
    train: &[Run],
    plan: &Plan,
    observer: &mut dyn Observer,
) -> Result<Calibration, CalibrateError> {
    let t0 = Instant::now();
    let model = start.model.clone().with_integration(plan.integration);
    let start_fm = FittedModel::new(model.clone(), start.params.clone())?;
    let bounds = search_box(&model, &start.params, plan.box_rule)?;
    let problem = CalibrationProblem::new(&model, train, plan.objective, bounds.clone())?;
    let objective_start = problem.cost(&start.params);
    let mut x = start.params.clone();
    let mut evaluations = 1;
    let mut ga_solution = None;
    if let Some(cfg) = &plan.ga {
        let mut ga = Ga { config: cfg.clone() };
        let s = ga.minimize(&problem, &x, observer)?;
        evaluations += s.evaluations;
        if s.cost <= objective_start {
            x = s.params.clone();
        }
        ga_solution = Some(s);
    }
    let names: Vec<String> = model.params().into_iter().map(|p| p.name).collect();
    let at_bound = names
        .iter()
        .enumerate()
        .filter(|&(i, _)| {
            let (lo, hi) = (bounds.lower[i], bounds.upper[i]);
            let tol = 1e-9 * (hi - lo).abs().max(1e-12);
            hi > lo && plan.ga.is_some() && (x[i] - lo <= tol || hi - x[i] <= tol)
        })
        .map(|(_, n)| n.clone())
        .collect();
    let mut polish_solution = None;
    // An observer that stopped the GA (Ctrl-C, a progress callback) wants the best so far, not a polish.
    let stopped = ga_solution.as_ref().is_some_and(|s: &Solution| s.termination == Termination::Stopped);
    if plan.polish && !stopped {
        let mut lm = LevenbergMarquardt { config: LmConfig::default() };
        let s = lm.minimize(&problem, &x, observer)?;
        evaluations += s.evaluations;
        if s.cost <= problem.cost(&x) {
            x = s.params.clone();
        }
        polish_solution = Some(s);
    }
    // Truncated update: find what the runs do not constrain, at the (unrestricted) fit, where the
    // residuals measure noise rather than the start's misfit; hold it at the start and re-polish within
    // the constrained subspace.
    let mut held = Vec::new();
    if plan.unexcited == Unexcited::Hold && !stopped {
        let id = problem.identifiability(&x, &plan.identify);
        if !id.weak.is_empty() {
            let (projected, basis) = hold_unexcited(&x, &start.params, &id.scales(), &id.weak_basis());
            x = projected;
            held = id.weak;
            if plan.polish {
                let mut lm = LevenbergMarquardt { config: LmConfig::default() };
                let k = basis.ncols();
                let sub = Subspace::new(&problem, x.clone(), basis)?;
                let s = lm.minimize(&sub, &vec![0.0; k], observer)?;
                evaluations += s.evaluations;
                let xs = sub.point(&s.params);
                if s.cost <= problem.cost(&x) {
                    x = xs.clone();
                }
                polish_solution = Some(Solution { params: xs, ..s });
            }
        }
    }
    let outside_box = names
        .iter()
        .enumerate()
        .filter(|&(i, _)| x[i] < bounds.lower[i] || x[i] > bounds.upper[i])
        .map(|(_, n)| n.clone())
        .collect();
    let fitted = FittedModel::new(model.clone(), x)?;
    let objective_fitted = problem.cost(&fitted.params);
    let identifiability = problem.identifiability(&fitted.params, &plan.identify);
    let end_pose_start = cost::cost(&model, &start.params, train, CostKind::EndPose)?;
    let end_pose_fitted = cost::cost(&model, &fitted.params, train, CostKind::EndPose)?;
    Ok(Calibration {
        fitted,
        start: start_fm,
        objective: plan.objective,
        objective_start,
        objective_fitted,
        end_pose_start,
        end_pose_fitted,
        evaluations,
        seconds: t0.elapsed().as_secs_f64(),
        bounds,
        at_bound,
        outside_box,
        ga: ga_solution,
        polish: polish_solution,
        identifiability,
        held,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use omni_kin::IkMatrix;
    use omni_kin::simulate::{SimConfig, simulate};

    #[test]
    fn subspace_normal_equations_are_the_projected_ones() {
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let cfg = SimConfig { duration_s: 2.0, runs_per_command: 1, ..SimConfig::default() };
        let runs: Vec<Run> = simulate(&cfg, &truth, "t/").unwrap().into_iter().step_by(4).collect();
        let model = Model::ik(IkMatrix::paper_design()).with_integration(Integration::DEFAULT);
        let x = IkMatrix::paper_calibrated().entries().to_vec();
        let bounds = search_box(&model, &x, BoxRule::PerRow(0.1)).unwrap();
        let problem = CalibrationProblem::new(&model, &runs, CostKind::PATH, bounds).unwrap();
        let basis = DMatrix::from_fn(9, 2, |r, c| if r % 2 == c { 0.01 } else { 0.002 * r as f64 });
        let sub = Subspace::new(&problem, x, basis).unwrap();
        let z = [0.3, -0.2];
        let ne = sub.normal_equations(&z);
        let full = NormalEquations::from_rows(&sub.residuals(&z), &sub.jacobian(&z));
        assert_eq!(sub.residual_count(&z), full.rows);
        assert!((ne.jtj - &full.jtj).abs().max() <= 1e-10 * full.jtj.abs().max());
        assert!((ne.jtr - &full.jtr).abs().max() <= 1e-10 * full.jtr.abs().max());
        assert!((ne.rtr - full.rtr).abs() <= 1e-12 * full.rtr);
    }
}
