//! The odometry evaluator: the one place that chooses between the fast path ([`crate::fast`]) and the
//! literal walk ([`crate::odometry`]), and that turns their errors into what callers want — the Eq. 6
//! end-pose cost, the path cost, per-run errors, the stacked residual vector and its IK Jacobian
//! ([`RunErrors`] holds the aggregation). Training, evaluation, diagnosis, reports, the planner and the
//! Python binding all go through it.
//!
//! The runs are prepared once for the lane kernel when the model integrates fixed steps of 1 to
//! [`crate::fast::MAX_WHEELS`] wheels; each evaluation then takes the kernel when it serves the resolved
//! parameters (built-in twist-stage effects only, no measured stamps, small step angles), else the general
//! fast walk
//! (any model, small step angles), else the literal walk. They agree within 1e-9 m but not to the last
//! bit; [`Route::Walk`] asks for the walk's numbers always. Jacobians: the kernel's forward-mode one with
//! respect to the IK matrix, else the general walk's, which also carries the parameters of twist- and
//! measurement-stage effects and of an affine wheel-stage effect.
//!
//! Runs are evaluated in parallel (rayon) and summed sequentially in run order, so results are
//! bit-identical whatever the thread count.

use crate::cost::{CostKind, check_runs, mean_end_pose_error};
use crate::error::KinError;
use crate::fast::forward::{self, ForwardModel};
use crate::fast::{BLOCK_RUNS, MAX_WHEELS, PreparedRuns, general};
use crate::model::{Model, Resolved, StepMode};
use crate::odometry::{self, Selection};
use crate::plan::{StepPlan, wheel_speeds};
use crate::pose::PoseError;
use crate::position_only;
use crate::run::Run;
use nalgebra::DMatrix;
use rayon::prelude::*;
use std::borrow::Cow;

/// Which odometry an [`Evaluator`] may take.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Route {
    /// The fast path wherever it serves the model, the literal walk elsewhere.
    #[default]
    Fast,
    /// The literal walk always (its numbers to the last bit).
    Walk,
}

/// The route of the numbers a user reads: [`crate::cost::cost`], `eval`, `diagnose`, `report`, `simulate`'s
/// summary, a calibration's Eq. 6 figures and Python's `evaluate` ([`Evaluator::for_report`]). The fast
/// route: its numbers differ from the literal walk's in the last bits only (≤ 1e-14 m, tested), and a
/// diagnosis reads costs of dozens of refits. [`Route::Walk`] gives the walk's bits.
pub const REPORT_ROUTE: Route = Route::Fast;

/// The errors of every run at the selected ground-truth poses and at its end, in run order, and what is
/// computed from them: the one place costs and residuals are aggregated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunErrors {
    /// Every run's errors at its selected poses, in turn.
    errors: Vec<PoseError>,
    /// Where each run's errors start in `errors`; one more entry: the total.
    offsets: Vec<usize>,
    /// End-pose error of each run (the Eq. 6 terms).
    ends: Vec<PoseError>,
}

/// Weights of one run's `(dx, dy, dθ)` residuals: `1/sqrt(n_runs · n_poses)`, times `w` for the heading,
/// so that the squared norm of the stacked residuals is the squared path cost.
pub fn residual_weights(n_runs: usize, n_poses: usize, heading_weight: f64) -> [f64; 3] {
    let scale = 1.0 / (n_runs.max(1) as f64 * n_poses.max(1) as f64).sqrt();
    [scale, scale, heading_weight * scale]
}

impl RunErrors {
    /// Number of runs.
    pub fn n_runs(&self) -> usize {
        self.ends.len()
    }

    /// Run `i`'s errors at its selected poses (ascending time; the last is its end pose).
    pub fn run(&self, i: usize) -> &[PoseError] {
        &self.errors[self.offsets[i]..self.offsets[i + 1]]
    }

    /// The end-pose error of each run (the Eq. 6 terms).
    pub fn ends(&self) -> &[PoseError] {
        &self.ends
    }

    /// The paper's Eq. 6: the mean end-pose error.
    pub fn end_pose_cost(&self) -> f64 {
        mean_end_pose_error(&self.ends)
    }

    /// Mean squared error of run `i` over its selected poses, the heading weighted by `w` (m/rad).
    pub fn path_mse(&self, i: usize, w: f64) -> f64 {
        let e = self.run(i);
        let sum: f64 = e
            .iter()
            .map(|e| {
                let th = w * e.dtheta_rad;
                e.dx_m * e.dx_m + e.dy_m * e.dy_m + th * th
            })
            .sum();
        sum / e.len().max(1) as f64
    }

    /// The path cost: `sqrt(mean_runs path_mse)`, each run counting equally whatever its length.
    pub fn path_cost(&self, w: f64) -> f64 {
        let n = self.n_runs();
        if n == 0 {
            return 0.0;
        }
        let per: Vec<f64> = (0..n).map(|i| self.path_mse(i, w)).collect();
        (per.iter().sum::<f64>() / n as f64).sqrt()
    }

    /// The stacked residual vector: per run, in run order, `(dx, dy, w dθ)` of each selected pose scaled
    /// by [`residual_weights`]; its squared norm is the squared path cost.
    pub fn residual_vector(&self, w: f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(3 * self.errors.len());
        for i in 0..self.n_runs() {
            let e = self.run(i);
            let k = residual_weights(self.n_runs(), e.len(), w);
            out.extend(e.iter().flat_map(|e| [e.dx_m * k[0], e.dy_m * k[1], e.dtheta_rad * k[2]]));
        }
        out
    }
}

impl RunErrors {
    /// The errors of `n_runs` runs evaluated in groups (each group under a model of its own), put back in
    /// run order: `parts` pairs each group's run indices with its errors (in that order). Every index in
    /// `0..n_runs` appears once.
    pub fn interleave(n_runs: usize, parts: &[(Vec<usize>, RunErrors)]) -> RunErrors {
        let mut at: Vec<(usize, usize)> = vec![(0, 0); n_runs];
        for (g, (idx, _)) in parts.iter().enumerate() {
            for (k, &i) in idx.iter().enumerate() {
                at[i] = (g, k);
            }
        }
        let mut out = RunErrors { errors: Vec::new(), offsets: vec![0], ends: Vec::with_capacity(n_runs) };
        for (g, k) in at {
            let part = &parts[g].1;
            out.errors.extend_from_slice(part.run(k));
            out.ends.push(part.ends[k]);
            out.offsets.push(out.errors.len());
        }
        out
    }
}

/// One run's part of the least-squares system, as [`Evaluator::ik_jacobian_blocks`] visits it.
#[derive(Clone, Copy, Debug)]
pub struct IkBlock<'a> {
    /// Index of the run.
    pub run: usize,
    /// The run's residuals: its rows of [`RunErrors::residual_vector`].
    pub residuals: &'a [f64],
    /// Their Jacobian with respect to the IK matrix entries (columns in row-major order `m11 … m3N`), then
    /// to the parameters of the model's affine wheel-stage effect (`wheel_columns` of them).
    pub jacobian: &'a DMatrix<f64>,
    /// Columns after the IK entries: the affine wheel-stage effect's parameters, in the effect's order (0
    /// without one).
    pub wheel_columns: usize,
}

/// One run's part of the least-squares system by the forward-mode walk, as
/// [`Evaluator::forward_jacobian_blocks`] visits it.
#[derive(Clone, Copy, Debug)]
pub struct ModelBlock<'a> {
    /// Index of the run.
    pub run: usize,
    /// The run's residuals: its rows of [`Evaluator::residual_vector`].
    pub residuals: &'a [f64],
    /// Their Jacobian: with respect to the IK entries (the first `3 N` columns, row-major `m11 … m3N`),
    /// then to the model's parameters `covered`.
    pub jacobian: &'a DMatrix<f64>,
    /// Indices (in the model's parameter vector) of the effect parameters after the IK entries.
    pub covered: &'a [usize],
}

/// Evaluates models of one structure on a set of runs at one selection of ground-truth poses.
#[derive(Clone, Debug)]
pub struct Evaluator<'a> {
    runs: &'a [Run],
    selection: Selection,
    prepared: Option<PreparedRuns>,
    route: Route,
    /// Whether any run's ground truth is position-only.
    position_only: bool,
}

impl<'a> Evaluator<'a> {
    /// An evaluator of `model`'s structure on `runs` at the ground-truth poses of `selection`, preparing
    /// the runs for the fast path when the model can take it. Checks wheel counts.
    pub fn new(model: &Model, runs: &'a [Run], selection: Selection) -> Result<Self, KinError> {
        Self::with_route(model, runs, selection, Route::Fast)
    }

    /// [`Self::new`] for the poses cost `kind` reads.
    pub fn for_cost(model: &Model, runs: &'a [Run], kind: CostKind) -> Result<Self, KinError> {
        Self::new(model, runs, kind.selection())
    }

    /// [`Self::new`] on [`REPORT_ROUTE`], for numbers a user reads.
    pub fn for_report(model: &Model, runs: &'a [Run], selection: Selection) -> Result<Self, KinError> {
        Self::with_route(model, runs, selection, REPORT_ROUTE)
    }

    /// [`Self::new`] restricted to `route`.
    pub fn with_route(model: &Model, runs: &'a [Run], selection: Selection, route: Route) -> Result<Self, KinError> {
        check_runs(model, runs)?;
        let prepared = match model.integration.step {
            StepMode::Fixed { dt_s } if route == Route::Fast && (1..=MAX_WHEELS).contains(&model.n_wheels()) => {
                Some(PreparedRuns::new(runs, dt_s, selection))
            }
            _ => None,
        };
        let position_only = runs.iter().any(Run::truth_position_only);
        Ok(Self { runs, selection, prepared, route, position_only })
    }

    /// The runs.
    pub fn runs(&self) -> &'a [Run] {
        self.runs
    }

    /// The selection of ground-truth poses.
    pub fn selection(&self) -> Selection {
        self.selection
    }

    /// The selected ground-truth indices of run `i`.
    pub fn indices(&self, i: usize) -> Vec<usize> {
        self.selection.indices(self.runs[i].truth().len())
    }

    /// Whether the fast path serves `res` (else the literal walk runs).
    pub fn is_fast(&self, res: &Resolved<'_>) -> bool {
        self.prepared.as_ref().is_some_and(|p| p.supports(res))
    }

    /// Errors at the selected poses and at each run's end.
    pub fn errors(&self, res: &Resolved<'_>) -> RunErrors {
        let e = self.fast_errors(res).unwrap_or_else(|| self.unprepared_errors(res, self.selection));
        self.aligned(e, self.selection)
    }

    /// `e` (at the poses of `selection`) with every position-only run's errors aligned by its best start
    /// rotation ([`crate::position_only`]); the others as they are.
    fn aligned(&self, mut e: RunErrors, selection: Selection) -> RunErrors {
        if !self.position_only {
            return e;
        }
        for (i, run) in self.runs.iter().enumerate().filter(|(_, r)| r.truth_position_only()) {
            let idx = selection.indices(run.truth().len());
            let (a, b) = (e.offsets[i], e.offsets[i + 1]);
            position_only::align(run.truth(), &idx, &mut e.errors[a..b], Some(&mut e.ends[i]));
        }
        e
    }

    /// Errors at the poses of `selection` without the prepared runs: the general fast walk on
    /// [`Route::Fast`] (where its step angles stay small), else the literal walk.
    fn unprepared_errors(&self, res: &Resolved<'_>, selection: Selection) -> RunErrors {
        let general = (self.route == Route::Fast).then(|| general_errors(res, self.runs, selection)).flatten();
        general.unwrap_or_else(|| walk_errors(res, self.runs, selection))
    }

    fn fast_errors(&self, res: &Resolved<'_>) -> Option<RunErrors> {
        let fast = self.prepared.as_ref()?.errors(res, self.runs)?;
        let errors = if self.selection == Selection::End { fast.ends.clone() } else { fast.at_queries };
        Some(RunErrors { errors, offsets: self.offsets(), ends: fast.ends })
    }

    /// Where each run's errors start in the stacked errors; one more entry: the total.
    fn offsets(&self) -> Vec<usize> {
        let mut offsets = Vec::with_capacity(self.runs.len() + 1);
        offsets.push(0);
        for r in self.runs {
            offsets.push(offsets[offsets.len() - 1] + self.selection.indices(r.truth().len()).len());
        }
        offsets
    }

    /// The end-pose error of every run (the Eq. 6 terms), in run order.
    pub fn end_pose_errors(&self, res: &Resolved<'_>) -> Vec<PoseError> {
        if self.position_only {
            // Aligned over the path the evaluator selects.
            return self.errors(res).ends;
        }
        if let Some(e) = self.prepared.as_ref().and_then(|p| p.end_pose_errors(res, self.runs)) {
            return e;
        }
        self.unprepared_errors(res, Selection::End).ends
    }

    /// The cost `kind` of `res`: the Eq. 6 cost from any selection; a path cost from this selection when it
    /// is the path's, else from a literal walk at the path's poses.
    pub fn cost(&self, res: &Resolved<'_>, kind: CostKind) -> f64 {
        match kind {
            CostKind::EndPose => mean_end_pose_error(&self.end_pose_errors(res)),
            CostKind::Path { heading_weight_m_per_rad: w, .. } => self.errors_for(res, kind).path_cost(w),
        }
    }

    /// The stacked residual vector of cost `kind` ([`RunErrors::residual_vector`]; for the end pose, the
    /// end errors with heading weight 1).
    pub fn residual_vector(&self, res: &Resolved<'_>, kind: CostKind) -> Vec<f64> {
        self.errors_for(res, kind).residual_vector(kind.heading_weight())
    }

    fn errors_for(&self, res: &Resolved<'_>, kind: CostKind) -> RunErrors {
        if kind.selection() == self.selection {
            self.errors(res)
        } else {
            self.aligned(self.unprepared_errors(res, kind.selection()), kind.selection())
        }
    }

    /// Visits, in run order, each run's residuals (its rows of [`Self::residual_vector`]) and their
    /// Jacobian with respect to the IK matrix entries, by the fast path's forward-mode differentiation;
    /// only a few hundred runs' rows are held at a time. `None` (before any visit) when the fast path
    /// cannot serve `res` or `kind` is not this evaluator's selection.
    pub fn ik_jacobian_blocks(
        &self,
        res: &Resolved<'_>,
        kind: CostKind,
        visit: &mut dyn FnMut(IkBlock<'_>),
    ) -> Option<()> {
        let prepared = self.prepared.as_ref().filter(|_| kind.selection() == self.selection)?;
        let w = kind.heading_weight();
        let n_runs = self.runs.len();
        let mut r = Vec::new();
        let mut errors = Vec::new();
        prepared.ik_jacobian_rows(res, self.runs, &mut |rows| {
            let k = residual_weights(n_runs, rows.errors.len(), w);
            let (run, jacobian) = (rows.run, rows.jacobian);
            errors.clear();
            errors.extend_from_slice(rows.errors);
            self.align_block(run, &mut errors, jacobian);
            r.clear();
            r.extend(errors.iter().flat_map(|e| [e.dx_m * k[0], e.dy_m * k[1], e.dtheta_rad * k[2]]));
            scale_rows(jacobian, &k);
            visit(IkBlock { run, residuals: &r, jacobian, wheel_columns: rows.wheel_columns });
        })
    }

    /// Visits, in run order, each run's residuals (its rows of [`Self::residual_vector`]) and their
    /// Jacobian with respect to the IK entries and to the effect parameters the forward-mode walk carries
    /// (twist- and measurement-stage effects, the one affine wheel-stage
    /// effect), for `model` at `params`; the other parameters are the caller's to difference. Only a few
    /// hundred runs' rows are held at a time. `None` (before any visit) on [`Route::Walk`], when `kind` is
    /// not this evaluator's selection or a step angle leaves the polynomials' range.
    pub fn forward_jacobian_blocks(
        &self,
        model: &Model,
        params: &[f64],
        kind: CostKind,
        visit: &mut dyn FnMut(ModelBlock<'_>),
    ) -> Option<()> {
        if self.route != Route::Fast || kind.selection() != self.selection {
            return None;
        }
        let res = model.resolve(params).ok()?;
        let parts = self.prepared.as_ref().and_then(|p| p.wheel_features(&res, self.runs));
        let fm = ForwardModel::new(model, parts);
        // Several batches: make sure every step angle is in range before the first visit.
        if self.runs.len() > BLOCK_RUNS && general_errors(&res, self.runs, self.selection).is_none() {
            return None;
        }
        let (w, n_runs) = (kind.heading_weight(), self.runs.len());
        let end_only = self.selection == Selection::End;
        let indexed: Vec<(usize, &Run)> = self.runs.iter().enumerate().collect();
        let mut r = Vec::new();
        for batch in indexed.chunks(BLOCK_RUNS) {
            let rows: Option<Vec<forward::RunRows>> = (batch.par_iter())
                .map(|&(index, run)| {
                    let idx = if end_only { Vec::new() } else { self.selection.indices(run.truth().len()) };
                    let plan = StepPlan::new(run, res.clock_lag_s, &idx);
                    let wheels = match parts.and_then(|f| f.params(&res)) {
                        Some(p) => Cow::Owned(parts?.speeds(index, run, p)),
                        None => wheel_speeds(&res, run),
                    };
                    let input =
                        forward::RunInput { res: &res, params, run, index, plan: &plan, wheels: &wheels, end_only };
                    forward::run_rows(&fm, &input)
                })
                .collect();
            for (&(run, _), mut rows) in batch.iter().zip(rows?) {
                let k = residual_weights(n_runs, rows.errors.len(), w);
                self.align_block(run, &mut rows.errors, &mut rows.jacobian);
                r.clear();
                r.extend(rows.errors.iter().flat_map(|e| [e.dx_m * k[0], e.dy_m * k[1], e.dtheta_rad * k[2]]));
                scale_rows(&mut rows.jacobian, &k);
                visit(ModelBlock { run, residuals: &r, jacobian: &rows.jacobian, covered: &fm.covered });
            }
        }
        Some(())
    }

    /// Run `run`'s errors at this selection and their Jacobian (unscaled rows), aligned by its best start
    /// rotation when its ground truth is position-only ([`crate::position_only`]).
    fn align_block(&self, run: usize, errors: &mut [PoseError], jacobian: &mut DMatrix<f64>) {
        let r = &self.runs[run];
        if !r.truth_position_only() {
            return;
        }
        let idx = self.selection.indices(r.truth().len());
        let (delta, ra) = position_only::align(r.truth(), &idx, errors, None);
        position_only::project_jacobian(jacobian, delta, &ra);
    }

    /// The route this evaluator may take.
    pub fn route(&self) -> Route {
        self.route
    }
}

/// Errors of the general fast walk ([`crate::fast::general`]) at the poses of `selection` (one run per
/// task, in parallel); `None` when a step angle of some run leaves the polynomials' range.
pub(crate) fn general_errors(res: &Resolved<'_>, runs: &[Run], selection: Selection) -> Option<RunErrors> {
    let per: Vec<Option<(Vec<PoseError>, PoseError)>> = runs
        .par_iter()
        .map(|r| {
            let idx = match selection {
                Selection::End => Vec::new(),
                Selection::Path(_) => selection.indices(r.truth().len()),
            };
            let plan = StepPlan::new(r, res.clock_lag_s, &idx);
            general::run_errors(res, r, &plan, &wheel_speeds(res, r))
        })
        .collect();
    let mut out = RunErrors { errors: Vec::new(), offsets: vec![0], ends: Vec::with_capacity(runs.len()) };
    for e in per {
        let (at, end) = e?;
        match selection {
            Selection::End => out.errors.push(end),
            Selection::Path(_) => out.errors.extend(at),
        }
        out.ends.push(end);
        out.offsets.push(out.errors.len());
    }
    Some(out)
}

/// Errors of the literal walk at the poses of `selection` (one walk per run, in parallel).
fn walk_errors(res: &Resolved<'_>, runs: &[Run], selection: Selection) -> RunErrors {
    let per: Vec<Vec<PoseError>> = runs
        .par_iter()
        .map(|r| {
            let idx = selection.indices(r.truth().len());
            let truth = r.truth();
            let mut e = Vec::with_capacity(idx.len());
            let plan = StepPlan::new(r, res.clock_lag_s, &idx);
            odometry::walk(res, r, &plan, |i, p| e.push(p.error_to(&truth[i].pose)), |_, _| {});
            e
        })
        .collect();
    let mut out = RunErrors { errors: Vec::new(), offsets: vec![0], ends: Vec::with_capacity(runs.len()) };
    for e in per {
        out.ends.push(e.last().copied().unwrap_or_default());
        out.errors.extend(e);
        out.offsets.push(out.errors.len());
    }
    out
}

/// Scales row `i` of a Jacobian by `k[i % 3]` (the residual weights of a pose's x, y and heading rows),
/// walking it column by column: the storage's order (a row is strided).
fn scale_rows(jacobian: &mut DMatrix<f64>, k: &[f64; 3]) {
    for mut column in jacobian.column_iter_mut() {
        for (i, v) in column.iter_mut().enumerate() {
            *v *= k[i % 3];
        }
    }
}
