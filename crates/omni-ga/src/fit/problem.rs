//! The calibration problem: a model structure, training runs and an objective, as a [`Problem`] and a
//! [`LeastSquares`] problem for the optimizer layer.

use crate::error::Error;
use crate::optimizer::problem::{
    Bounds, LeastSquares, NormalEquations, Problem, finite_difference_columns, finite_difference_jacobian,
};
use crate::science::identify::{self, Identifiability, IdentifyOptions};
use nalgebra::DMatrix;
use omni_kin::cost::CostKind;
use omni_kin::effect::{Effect, Stage};
use omni_kin::evaluate::Evaluator;
use omni_kin::{Model, Run};

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
    pub fn new(model: &'a Model, runs: &'a [Run], objective: CostKind, bounds: Bounds) -> Result<Self, Error> {
        if runs.is_empty() {
            return Err(Error::NoRuns);
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

    /// The Jacobian columns `cols` (effect parameters) over all residuals, by finite differences (see
    /// [`LeastSquares::jacobian`]).
    fn effect_columns(&self, x: &[f64], cols: &[usize]) -> Vec<Vec<f64>> {
        let specs = self.model.params();
        let at_range_end = |i: usize| specs.get(i).is_some_and(|s| s.lower == x[i] && s.upper > s.lower);
        let y0: Vec<f64> = cols.iter().map(|&c| x[c]).collect();
        finite_difference_columns(
            &y0,
            0..cols.len(),
            |y| self.residuals(&spread(x, cols, y)),
            |k| at_range_end(cols[k]),
        )
    }

    /// [`Self::for_each_run_block`] through the fast paths: the kernel's IK Jacobian, else the forward-mode
    /// walk (which also carries some effect parameters); the other effect columns by finite differences.
    /// `None` (before any visit) when neither serves `x`.
    fn analytic_blocks(&self, x: &[f64], visit: &mut dyn FnMut(RunBlock<'_>)) -> Option<()> {
        let res = self.model.resolve(x).ok()?;
        let dm = self.ik_from_base(x)?;
        let (nb, n) = (self.model.n_base(), x.len());
        let mut effects: Option<(Vec<usize>, Vec<Vec<f64>>)> = None;
        // Every column of a block is written below: one buffer serves every run, reshaped to each run's rows
        // without keeping its content (a resize that kept it would move every column of the last run's).
        let mut j = DMatrix::zeros(0, n);
        // One run's block: the IK columns (chained to the base parameters), the carried effect columns
        // (`covered`, after the IK entries in `jac`) and the rest by differences, computed once.
        let mut block = |run: usize, residuals: &[f64], jac: &DMatrix<f64>, covered: &[usize]| {
            let row_offset = self.row_offsets[run];
            let rows = residuals.len();
            let nik = jac.ncols() - covered.len();
            if j.nrows() != rows {
                let mut buffer: Vec<f64> = std::mem::replace(&mut j, DMatrix::zeros(0, n)).data.into();
                buffer.resize(rows * n, 0.0);
                j = DMatrix::from_vec(rows, n, buffer);
            }
            match &dm {
                None => j.columns_mut(0, nb).copy_from(&jac.columns(0, nik)),
                Some(dm) => j.columns_mut(0, nb).copy_from(&(jac.columns(0, nik) * dm)),
            }
            for (k, &g) in covered.iter().enumerate() {
                j.column_mut(g).copy_from(&jac.column(nik + k));
            }
            let (rest, cols) = effects.get_or_insert_with(|| {
                let rest: Vec<usize> = (nb..n).filter(|g| !covered.contains(g)).collect();
                let cols = self.effect_columns(x, &rest);
                (rest, cols)
            });
            for (&c, col) in rest.iter().zip(cols.iter()) {
                for (i, v) in col.iter().skip(row_offset).take(rows).enumerate() {
                    j[(i, c)] = *v;
                }
            }
            visit(RunBlock { run, residuals, row_offset, jacobian: &j });
        };
        // The kernel also carries the parameters of a model's one (affine) wheel-stage effect.
        let wheel = self.wheel_parameters();
        let kernel = self.evaluator.ik_jacobian_blocks(&res, self.objective, &mut |b| {
            debug_assert!(b.wheel_columns == 0 || b.wheel_columns == wheel.len());
            let covered = if b.wheel_columns == wheel.len() { wheel.as_slice() } else { &[] };
            block(b.run, b.residuals, b.jacobian, covered)
        });
        kernel.or_else(|| {
            self.evaluator.forward_jacobian_blocks(self.model, x, self.objective, &mut |b| {
                block(b.run, b.residuals, b.jacobian, b.covered)
            })
        })
    }

    /// The model fitted.
    pub fn model(&self) -> &'a Model {
        self.model
    }

    /// The runs fitted on.
    pub fn runs(&self) -> &'a [Run] {
        self.runs
    }

    /// The objective.
    pub fn objective(&self) -> CostKind {
        self.objective
    }

    /// Indices of the parameters of the model's wheel-stage effect, when it has exactly one.
    fn wheel_parameters(&self) -> Vec<usize> {
        let model = self.model;
        let wheel: Vec<_> = (model.effects.iter().zip(model.effect_ranges()))
            .filter(|(e, _)| e.stage() == Stage::Wheel)
            .map(|(_, r)| r)
            .collect();
        match &wheel[..] {
            [r] => r.clone().collect(),
            _ => Vec::new(),
        }
    }

    /// Residual rows of each run, in run order (3 per selected ground-truth pose).
    pub fn run_rows(&self) -> Vec<usize> {
        self.row_offsets.windows(2).map(|w| w[1] - w[0]).collect()
    }

    /// What the runs constrain at `x` ([`identify::analyse`] on this problem's residuals); too few runs are
    /// cut into segments by time for the per-run standard errors ([`identify::segment_poses`]).
    pub fn identifiability(&self, x: &[f64], opts: &IdentifyOptions) -> Identifiability {
        let selection = self.objective.selection();
        let times: Vec<Vec<f64>> = self
            .runs
            .iter()
            .map(|r| selection.indices(r.truth().len()).iter().map(|&i| r.truth()[i].t_s).collect())
            .collect();
        let segments = identify::segment_poses(&times, x.len());
        let mut moments = identify::Moments::new(x.len());
        self.for_each_run_block(x, &mut |b| {
            let rows: Vec<usize> = segments[b.run].iter().map(|&poses| identify::ROWS_PER_POSE * poses).collect();
            moments.add_run_segments(b.jacobian, b.residuals, &rows);
        });
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

/// `x` with the entries `cols` replaced by `y` (one value per entry).
fn spread(x: &[f64], cols: &[usize], y: &[f64]) -> Vec<f64> {
    let mut out = x.to_vec();
    for (&c, &v) in cols.iter().zip(y) {
        out[c] = v;
    }
    out
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
