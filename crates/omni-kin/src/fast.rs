//! Fast fixed-step odometry over prepared runs: the same numbers as [`crate::odometry`] (within rounding,
//! checked to 1e-9 m against the literal loop in tests) at close to the arithmetic limit.
//!
//! What depends only on the data is done once, in [`PreparedRuns::new`]: each sample's step fraction is
//! folded into its wheel-angle increment `u_k = f_k h w_k` (rad), so with the IK matrix `M` a step's body
//! displacement is `M u_k` — 3 × N multiply-adds — for both Eq. 1 (Euler) and exact arcs. The heading's
//! cosine and sine are advanced by a rotation whose `sin a`, `cos a` come from short polynomials in the step
//! angle `a` (exact to < 1e-16 for `|a| ≤ 0.1` rad; the cosine and sine are re-taken from the summed heading
//! every 1024 steps). The increments are kept up to [`KEPT_INCREMENTS_MAX_BYTES`] (8 B per wheel and
//! sample); for larger datasets each walk redoes a lane group's increments from the runs' own wheel
//! columns (the same products, so the same numbers) instead of holding a second copy of the dataset.
//! Runs are interleaved four to a lane group (struct of arrays), so the step loop runs
//! four runs at once in SIMD lanes; on x86-64 CPUs with AVX2 and FMA (checked at run time through `pulp`,
//! no `-C target-cpu` needed) the loop is compiled for them, otherwise plainly.
//!
//! Scope. The fast path serves models whose odometry is a fixed step with no clock lag, no wheel- or
//! twist-stage effects and no measured stamps; a sensor offset (measurement stage) is allowed. Anything
//! else — or a step angle above 0.1 rad — returns `None` and the caller uses the general walk.
//!
//! Results are deterministic: groups are evaluated in parallel, collected in order and summed in run
//! order, so they do not depend on the thread count. With FMA the last bits differ from a CPU without it.

use crate::cost::CostKind;
use crate::effect::{Effect, WheelContext};
use crate::model::{Resolved, Scheme};
use crate::odometry::Selection;
use crate::pose::{Pose2, PoseError, wrap_angle};
use crate::run::Run;
use nalgebra::DMatrix;
use rayon::prelude::*;
use std::cell::RefCell;

/// Runs per lane group.
pub const LANES: usize = 4;
/// Largest step angle the polynomials serve. rad.
pub const MAX_STEP_ANGLE_RAD: f64 = 0.1;
/// Steps between re-taking the heading's cosine and sine from the summed heading.
const RESYNC_STEPS: usize = 1024;

type Lanes = [f64; LANES];

thread_local! {
    /// Each thread's buffer for increments redone on a walk (datasets beyond [`KEPT_INCREMENTS_MAX_BYTES`]).
    static SCRATCH: RefCell<Vec<Lanes>> = const { RefCell::new(Vec::new()) };
}

/// One ground-truth pose to predict: after `step` steps of `lane`, a partial step `u` (`n_wheels` entries
/// in [`Group::query_u`]).
#[derive(Clone, Debug)]
struct Query {
    step: usize,
    lane: usize,
    /// Output slot within the group (runs' queries are contiguous, in run order).
    slot: usize,
    truth: Pose2,
}

/// Four runs interleaved.
#[derive(Clone, Debug)]
struct Group {
    /// Index of the group's first run.
    first_run: usize,
    /// Per lane: steps and where they come from (to redo the increments from rewritten wheel speeds).
    sources: Vec<(usize, StepSource)>,
    /// Per query (in `queries` order): sample and fraction.
    query_source: Vec<(usize, f64)>,
    /// Step length of each lane. s.
    h: Lanes,
    /// Real runs in the group (the other lanes are padding with zero increments).
    lanes: usize,
    /// Steps (the longest run's; shorter runs are padded with zero increments).
    steps: usize,
    /// Wheel-angle increments, `steps × n_wheels` lane vectors: `u[k n_wheels + j][lane]`. rad.
    u: Vec<Lanes>,
    /// Largest |increment| per wheel over the group (bounds the step angle). rad.
    u_max: Vec<f64>,
    /// First ground-truth pose of each lane (where odometry starts).
    start: [Pose2; LANES],
    /// Last ground-truth pose of each lane (the Eq. 6 reference).
    end: [Pose2; LANES],
    /// Queries sorted by step (path selections only).
    queries: Vec<Query>,
    /// Partial-step increments of the queries, `n_wheels` each. rad.
    query_u: Vec<f64>,
    /// Queries of each lane.
    query_count: [usize; LANES],
}

/// Runs whose Jacobian rows [`PreparedRuns::ik_jacobian_blocks`] holds at once (a multiple of [`LANES`]).
pub const BLOCK_RUNS: usize = 256;

/// One run's part of the least-squares system, as [`PreparedRuns::ik_jacobian_blocks`] visits it.
#[derive(Clone, Copy, Debug)]
pub struct IkBlock<'a> {
    /// Index of the run.
    pub run: usize,
    /// The run's residuals: its rows of [`PreparedRuns::residual_vector`].
    pub residuals: &'a [f64],
    /// Their Jacobian with respect to the IK matrix entries (columns in row-major order `m11 … m3N`).
    pub jacobian: &'a DMatrix<f64>,
}

/// Runs prepared for fast repeated evaluation at one step rule and one selection of ground-truth poses.
#[derive(Clone, Debug)]
pub struct PreparedRuns {
    n_runs: usize,
    n_wheels: usize,
    fixed_dt_s: Option<f64>,
    selection: Selection,
    groups: Vec<Group>,
    /// Whether the groups keep their increments ([`KEPT_INCREMENTS_MAX_BYTES`]); otherwise each walk redoes
    /// them from the runs' wheel speeds.
    increments_kept: bool,
}

/// Largest size of the increments [`PreparedRuns::new`] keeps (8 B per wheel and sample: 64 MB holds
/// 2.8 M samples of 3 wheels, 13 × the paper-size set). Beyond, each walk of a lane group redoes its
/// increments from the runs' wheel speeds (the same products, so the same numbers) into a buffer of
/// the group's size: no copy of the dataset, at some speed.
pub const KEPT_INCREMENTS_MAX_BYTES: usize = 64 << 20;

/// A query of one run: before step `.0`, a partial step of increments `.1`, predicting truth pose `.2`,
/// taken from sample `.3` with fraction `.4`.
type RunQuery = (usize, Vec<f64>, usize, usize, f64);

/// Where a run's steps come from: the first sample (steps take consecutive samples) and the steps whose
/// fraction of the step length is not 1.
#[derive(Clone, Debug, Default)]
struct StepSource {
    first_sample: usize,
    partial: Vec<(usize, f64)>,
}

/// Wheel-angle increments of one run's steps, and its queries, exactly as [`crate::odometry`]'s walk
/// takes them with no clock lag and fixed steps.
fn run_steps(run: &Run, fixed_dt_s: Option<f64>, queries: &[usize]) -> (Vec<f64>, Vec<RunQuery>, StepSource) {
    let n_w = run.n_wheels();
    let t = run.wheel_t_s();
    let wheels = run.wheel_rad_s();
    let n = t.len();
    let median = run.median_dt_s();
    let h = fixed_dt_s.unwrap_or(median);
    let truth = run.truth();
    let start = truth[0].t_s;
    let g_last = truth[truth.len() - 1].t_s;
    let mut u = Vec::with_capacity(n_w * n);
    let mut out = Vec::with_capacity(queries.len());
    let mut q = 0;
    let first = t.partition_point(|&tk| tk <= start);
    let mut source = StepSource { first_sample: first, partial: Vec::new() };
    let mut cursor = start;
    let scaled = |k: usize, f: f64| -> Vec<f64> { wheels[k * n_w..(k + 1) * n_w].iter().map(|w| f * h * w).collect() };
    for k in first..n {
        let s_k = t[k];
        let a_k = if k == 0 { s_k - median } else { t[k - 1] };
        let len = s_k - a_k;
        let from = a_k.max(cursor);
        let steps = u.len() / n_w;
        while q < queries.len() && truth[queries[q]].t_s <= s_k {
            let f = ((truth[queries[q]].t_s - from) / len).clamp(0.0, 1.0);
            out.push((steps, scaled(k, f), queries[q], k, f));
            q += 1;
        }
        let f =
            if s_k >= g_last { ((g_last - from) / len).clamp(0.0, 1.0) } else { ((s_k - from) / len).clamp(0.0, 1.0) };
        if f != 1.0 {
            source.partial.push((steps, f));
        }
        u.extend(scaled(k, f));
        if s_k >= g_last {
            break;
        }
        cursor = s_k;
    }
    // Validated runs cover the ground truth, so every query was met; keep the slots filled regardless.
    let steps = u.len() / n_w;
    while q < queries.len() {
        out.push((steps, vec![0.0; n_w], queries[q], 0, 0.0));
        q += 1;
    }
    (u, out, source)
}

impl PreparedRuns {
    /// Prepares `runs` (all with the same wheel count) for fixed steps of `fixed_dt_s` (`None`: each run's
    /// median interval) and the ground-truth poses of `selection`. The increments are kept when they take
    /// at most [`KEPT_INCREMENTS_MAX_BYTES`].
    pub fn new(runs: &[Run], fixed_dt_s: Option<f64>, selection: Selection) -> Self {
        Self::with_increment_budget(runs, fixed_dt_s, selection, KEPT_INCREMENTS_MAX_BYTES)
    }

    /// [`Self::new`], keeping the increments only when they take at most `max_bytes` (8 B per wheel and
    /// sample); `0` never keeps them. The results do not depend on it.
    pub fn with_increment_budget(
        runs: &[Run],
        fixed_dt_s: Option<f64>,
        selection: Selection,
        max_bytes: usize,
    ) -> Self {
        let n_wheels = runs.first().map_or(0, Run::n_wheels);
        let bytes = runs.iter().map(|r| std::mem::size_of_val(r.wheel_rad_s())).sum::<usize>();
        let increments_kept = bytes <= max_bytes;
        let groups = runs
            .par_chunks(LANES)
            .enumerate()
            .map(|(gi, chunk)| {
                let per: Vec<_> = chunk
                    .iter()
                    .map(|r| {
                        let idx = match selection {
                            Selection::End => Vec::new(),
                            Selection::Path(_) => selection.indices(r.truth().len()),
                        };
                        run_steps(r, fixed_dt_s, &idx)
                    })
                    .collect();
                let steps = per.iter().map(|(u, _, _)| u.len() / n_wheels.max(1)).max().unwrap_or(0);
                let mut u = vec![[0.0; LANES]; steps * n_wheels];
                let mut u_max = vec![0.0f64; n_wheels];
                for (lane, (ur, _, _)) in per.iter().enumerate() {
                    for (i, &v) in ur.iter().enumerate() {
                        let (k, j) = (i / n_wheels, i % n_wheels);
                        u[k * n_wheels + j][lane] = v;
                        u_max[j] = u_max[j].max(v.abs());
                    }
                }
                let mut start = [Pose2::IDENTITY; LANES];
                let mut end = [Pose2::IDENTITY; LANES];
                for (lane, r) in chunk.iter().enumerate() {
                    start[lane] = r.start().pose;
                    end[lane] = r.end().pose;
                }
                let mut queries = Vec::new();
                let mut query_u = Vec::new();
                let mut query_count = [0; LANES];
                let mut slot = 0;
                let mut query_source = Vec::new();
                for (lane, ((_, qs, _), r)) in per.iter().zip(chunk).enumerate() {
                    query_count[lane] = qs.len();
                    for (step, qu, ti, sample, f) in qs {
                        let q = Query { step: *step, lane, slot, truth: r.truth()[*ti].pose };
                        queries.push((q, qu.clone(), (*sample, *f)));
                        slot += 1;
                    }
                }
                queries.sort_by_key(|(q, _, _)| (q.step, q.lane));
                let queries = queries
                    .into_iter()
                    .map(|(q, qu, src)| {
                        query_u.extend(qu);
                        query_source.push(src);
                        q
                    })
                    .collect();
                let sources = per.into_iter().map(|(ur, _, src)| (ur.len() / n_wheels.max(1), src)).collect();
                let mut h = [0.0; LANES];
                for (lane, r) in chunk.iter().enumerate() {
                    h[lane] = fixed_dt_s.unwrap_or(r.median_dt_s());
                }
                Group {
                    first_run: gi * LANES,
                    lanes: chunk.len(),
                    steps,
                    u: if increments_kept { u } else { Vec::new() },
                    u_max,
                    start,
                    end,
                    queries,
                    query_u,
                    query_count,
                    sources,
                    query_source,
                    h,
                }
            })
            .collect();
        Self { n_runs: runs.len(), n_wheels, fixed_dt_s, selection, groups, increments_kept }
    }

    /// Number of runs.
    pub fn n_runs(&self) -> usize {
        self.n_runs
    }

    /// The selection of ground-truth poses these runs were prepared for.
    pub fn selection(&self) -> Selection {
        self.selection
    }

    /// True when `res` can use these prepared runs (same fixed step, no clock lag, no twist-stage effects,
    /// no measured stamps, 3 or 4 wheels). Wheel-stage effects are applied to the runs' wheel speeds
    /// before the increments are redone, on each evaluation.
    pub fn supports(&self, res: &Resolved<'_>) -> bool {
        !res.stamps
            && res.clock_lag_s == 0.0
            && res.twist_effects.is_empty()
            && res.fixed_dt_s == self.fixed_dt_s
            && res.ik.n_wheels() == self.n_wheels
            && matches!(self.n_wheels, 3 | 4)
    }

    /// Predicted-minus-measured errors at the selected ground-truth poses, one `Vec` per run in run order
    /// (for [`Selection::End`], one error per run). `None` when `res` needs the general walk.
    pub fn errors(&self, res: &Resolved<'_>, runs: &[Run]) -> Option<Vec<Vec<PoseError>>> {
        if !self.supports(res) {
            return None;
        }
        let per_group: Vec<Option<Vec<Vec<PoseError>>>> =
            self.groups.par_iter().map(|g| self.group_errors(g, res, runs)).collect();
        let mut out = Vec::with_capacity(self.n_runs);
        for g in per_group {
            out.extend(g?);
        }
        Some(out)
    }

    /// The Eq. 6 terms: the end-pose error of every run, in run order (any selection). `None` when `res`
    /// needs the general walk.
    pub fn end_pose_errors(&self, res: &Resolved<'_>, runs: &[Run]) -> Option<Vec<PoseError>> {
        if !self.supports(res) {
            return None;
        }
        let per_group: Vec<Option<([PoseError; LANES], usize)>> = self
            .groups
            .par_iter()
            .map(|g| self.walk_group(g, res, runs, &mut |_, _| {}).map(|ends| (ends, g.lanes)))
            .collect();
        let mut out = Vec::with_capacity(self.n_runs);
        for g in per_group {
            let (ends, lanes) = g?;
            out.extend_from_slice(&ends[..lanes]);
        }
        Some(out)
    }

    /// The cost `kind` (as [`crate::cost::cost_resolved`]): the Eq. 6 end-pose cost with any selection, the
    /// path cost when these runs were prepared for `Selection::Path(every)` of the same `every`. `None` when
    /// `res` or `kind` needs the general walk.
    pub fn cost(&self, res: &Resolved<'_>, runs: &[Run], kind: CostKind) -> Option<f64> {
        match kind {
            CostKind::EndPose => {
                let e = self.end_pose_errors(res, runs)?;
                Some(crate::cost::mean_end_pose_error(&e))
            }
            CostKind::Path { every, heading_weight_m_per_rad: w } => {
                if self.selection != Selection::Path(every) {
                    return None;
                }
                let per: Vec<f64> = self.errors(res, runs)?.iter().map(|e| mse(e, w)).collect();
                if per.is_empty() {
                    return Some(0.0);
                }
                Some((per.iter().sum::<f64>() / per.len() as f64).sqrt())
            }
        }
    }

    /// The stacked residual vector of [`crate::cost::residual_vector`]. `None` when `res` or `kind` needs
    /// the general walk.
    pub fn residual_vector(&self, res: &Resolved<'_>, runs: &[Run], kind: CostKind) -> Option<Vec<f64>> {
        let w = self.heading_weight(kind)?;
        let errors = self.errors(res, runs)?;
        let n_runs = self.n_runs.max(1) as f64;
        let mut out = Vec::with_capacity(3 * errors.iter().map(Vec::len).sum::<usize>());
        for e in &errors {
            let scale = 1.0 / (n_runs * e.len().max(1) as f64).sqrt();
            for e in e {
                out.extend([e.dx_m * scale, e.dy_m * scale, w * e.dtheta_rad * scale]);
            }
        }
        Some(out)
    }

    /// Residual vector (as [`Self::residual_vector`]) and its Jacobian with respect to the IK matrix
    /// entries (columns in row-major order `m11 … m3N`), by forward-mode differentiation of the step
    /// recurrence (closed forms, no finite differences). The sensor pose is held fixed. `None` when `res`
    /// or `kind` needs the general walk. The blocks of [`Self::ik_jacobian_blocks`], stacked.
    pub fn residuals_and_ik_jacobian(
        &self,
        res: &Resolved<'_>,
        runs: &[Run],
        kind: CostKind,
    ) -> Option<(Vec<f64>, DMatrix<f64>)> {
        let poses = match self.selection {
            Selection::End => self.n_runs,
            Selection::Path(_) => self.groups.iter().map(|g| g.queries.len()).sum(),
        };
        let n_rows = 3 * poses;
        let mut r = Vec::with_capacity(n_rows);
        let mut jac = DMatrix::zeros(n_rows, 3 * self.n_wheels);
        self.ik_jacobian_blocks(res, runs, kind, &mut |b| {
            let row = r.len();
            r.extend_from_slice(b.residuals);
            jac.rows_mut(row, b.residuals.len()).copy_from(b.jacobian);
        })?;
        Some((r, jac))
    }

    /// Visits, in run order, each run's residuals (its rows of [`Self::residual_vector`]) and their
    /// Jacobian with respect to the IK matrix entries, as [`Self::residuals_and_ik_jacobian`] but holding
    /// only [`BLOCK_RUNS`] runs' rows at a time: the memory does not grow with the number of runs. The
    /// runs of a batch are differentiated in parallel and visited sequentially, so sums over the blocks
    /// are deterministic. `None` (before any visit) when `res` or `kind` needs the general walk.
    pub fn ik_jacobian_blocks(
        &self,
        res: &Resolved<'_>,
        runs: &[Run],
        kind: CostKind,
        visit: &mut dyn FnMut(IkBlock<'_>),
    ) -> Option<()> {
        let w = self.heading_weight(kind)?;
        if !self.supports(res) || !res.wheel_effects.is_empty() || runs.len() != self.n_runs {
            return None;
        }
        let m = res.ik.entries();
        let n = self.n_wheels;
        let within_range = |g: &Group| {
            let bound: f64 = (0..n).map(|j| m[2 * n + j].abs() * g.u_max[j]).sum();
            bound <= MAX_STEP_ANGLE_RAD && bound.is_finite()
        };
        if !self.groups.iter().all(within_range) {
            return None;
        }
        let arc = res.scheme == Scheme::ExactArc;
        let sensor = res.sensor_from_body;
        let n_cols = 3 * n;
        let n_runs = self.n_runs.max(1) as f64;
        let mut r = Vec::new();
        for batch in self.groups.chunks(BLOCK_RUNS / LANES) {
            let rows: Option<Vec<Vec<Vec<Row>>>> = batch
                .par_iter()
                .map(|g| {
                    self.with_increments(g, runs, |u| {
                        (0..g.lanes)
                            .map(|lane| match (n, arc) {
                                (3, true) => jacobian_lane::<3, true>(g, u, lane, m, sensor, self.selection),
                                (3, false) => jacobian_lane::<3, false>(g, u, lane, m, sensor, self.selection),
                                (4, true) => jacobian_lane::<4, true>(g, u, lane, m, sensor, self.selection),
                                _ => jacobian_lane::<4, false>(g, u, lane, m, sensor, self.selection),
                            })
                            .collect()
                    })
                })
                .collect();
            // Only fails for runs other than the prepared ones, which the length check above excludes.
            let rows = rows?;
            for (g, lanes) in batch.iter().zip(&rows) {
                for (lane, rows) in lanes.iter().enumerate() {
                    let scale = 1.0 / (n_runs * rows.len().max(1) as f64).sqrt();
                    let weights = [scale, scale, w * scale];
                    r.clear();
                    let mut jac = DMatrix::zeros(3 * rows.len(), n_cols);
                    for (k, q) in rows.iter().enumerate() {
                        for (i, wi) in weights.iter().enumerate() {
                            r.push(q.error[i] * wi);
                            for c in 0..n_cols {
                                jac[(3 * k + i, c)] = q.d[i][c] * wi;
                            }
                        }
                    }
                    visit(IkBlock { run: g.first_run + lane, residuals: &r, jacobian: &jac });
                }
            }
        }
        Some(())
    }

    fn heading_weight(&self, kind: CostKind) -> Option<f64> {
        match (kind, self.selection) {
            (CostKind::EndPose, Selection::End) => Some(1.0),
            (CostKind::Path { every, heading_weight_m_per_rad }, Selection::Path(k)) if k == every => {
                Some(heading_weight_m_per_rad)
            }
            _ => None,
        }
    }

    /// Calls `f` with the increments of group `g`: the kept ones, or ones redone from the runs' wheel speeds
    /// (`u = f h w`, the products [`PreparedRuns::new`] takes, so the same numbers) into this thread's
    /// buffer. `None` when `runs` are not the prepared runs.
    fn with_increments<R>(&self, g: &Group, runs: &[Run], f: impl FnOnce(&[Lanes]) -> R) -> Option<R> {
        if self.increments_kept {
            return Some(f(&g.u));
        }
        SCRATCH.with(|cell| {
            let mut u = cell.take();
            let out = self.redo_increments(g, runs, &mut u).map(|()| f(&u));
            cell.replace(u);
            out
        })
    }

    /// Writes group `g`'s increments into `u` (`steps × n_wheels` lane vectors), a step's four lanes at a
    /// time.
    fn redo_increments(&self, g: &Group, runs: &[Run], u: &mut Vec<Lanes>) -> Option<()> {
        let n = self.n_wheels;
        let total = g.steps * n;
        // Each lane's wheel speeds over its steps (none for padding lanes).
        let mut w: [&[f64]; LANES] = [&[]; LANES];
        for (lane, (steps, src)) in g.sources.iter().enumerate() {
            let speeds = runs.get(g.first_run + lane)?.wheel_rad_s();
            w[lane] = speeds.get(src.first_sample * n..(src.first_sample + steps) * n)?;
        }
        let h = g.h;
        u.clear();
        u.reserve(total);
        // Whole steps: f = 1, and (1 · h) · w = h · w exactly.
        let common = w.iter().map(|s| s.len()).min().unwrap_or(0);
        let [a, b, c, d] = w.map(|s| &s[..common]);
        for (((a, b), c), d) in a.iter().zip(b).zip(c).zip(d) {
            u.push([h[0] * a, h[1] * b, h[2] * c, h[3] * d]);
        }
        for i in common..total {
            u.push(std::array::from_fn(|l| w[l].get(i).map_or(0.0, |v| h[l] * v)));
        }
        for (lane, (_, src)) in g.sources.iter().enumerate() {
            for &(k, f) in &src.partial {
                for j in 0..n {
                    u[k * n + j][lane] = f * h[lane] * w[lane][k * n + j];
                }
            }
        }
        Some(())
    }

    /// The group with its increments redone from wheel speeds rewritten by `res`'s wheel-stage effects
    /// (as the general walk applies them: sample stamps, fixed steps, the runs' start angles).
    fn with_wheel_effects(&self, g: &Group, res: &Resolved<'_>, runs: &[Run]) -> Option<Group> {
        let n = self.n_wheels;
        let mut u = vec![[0.0; LANES]; g.steps * n];
        let mut u_max = vec![0.0f64; n];
        let mut query_u = vec![0.0; g.query_u.len()];
        for (lane, (steps, src)) in g.sources.iter().enumerate() {
            let run = runs.get(g.first_run + lane)?;
            let h = g.h[lane];
            let dt = vec![h; run.n_samples()];
            let ctx =
                WheelContext { n_wheels: n, t_s: run.wheel_t_s(), dt_s: &dt, start_angle_rad: run.wheel_start_rad() };
            let mut w = run.wheel_rad_s().to_vec();
            for (e, p) in &res.wheel_effects {
                e.wheel_rates(p, &ctx, &mut w);
            }
            let mut partial = src.partial.iter().peekable();
            for i in 0..*steps {
                let f = match partial.peek() {
                    Some(&&(k, f)) if k == i => {
                        partial.next();
                        f
                    }
                    _ => 1.0,
                };
                let sample = src.first_sample + i;
                for j in 0..n {
                    let v = f * h * w[sample * n + j];
                    u[i * n + j][lane] = v;
                    u_max[j] = u_max[j].max(v.abs());
                }
            }
            for (qi, q) in g.queries.iter().enumerate().filter(|(_, q)| q.lane == lane) {
                let _ = q;
                let (sample, f) = g.query_source[qi];
                for j in 0..n {
                    query_u[qi * n + j] = f * h * w.get(sample * n + j).copied().unwrap_or(0.0);
                }
            }
        }
        Some(Group {
            first_run: g.first_run,
            sources: Vec::new(),
            query_source: Vec::new(),
            h: g.h,
            lanes: g.lanes,
            steps: g.steps,
            u,
            u_max,
            start: g.start,
            end: g.end,
            queries: g.queries.clone(),
            query_u,
            query_count: g.query_count,
        })
    }

    fn group_errors(&self, g: &Group, res: &Resolved<'_>, runs: &[Run]) -> Option<Vec<Vec<PoseError>>> {
        match self.selection {
            Selection::End => {
                let ends = self.walk_group(g, res, runs, &mut |_, _| {})?;
                Some(ends[..g.lanes].iter().map(|e| vec![*e]).collect())
            }
            Selection::Path(_) => {
                let mut flat = vec![PoseError::default(); g.queries.len()];
                self.walk_group(g, res, runs, &mut |slot, e| flat[slot] = e)?;
                let mut out = Vec::with_capacity(g.lanes);
                let mut at = 0;
                for lane in 0..g.lanes {
                    out.push(flat[at..at + g.query_count[lane]].to_vec());
                    at += g.query_count[lane];
                }
                Some(out)
            }
        }
    }

    /// Walks one group: calls `on_query(slot, error)` for each query and returns the end-pose errors.
    fn walk_group(
        &self,
        g: &Group,
        res: &Resolved<'_>,
        runs: &[Run],
        on_query: &mut dyn FnMut(usize, PoseError),
    ) -> Option<[PoseError; LANES]> {
        let rewritten;
        let (g, kept) = if res.wheel_effects.is_empty() {
            (g, self.increments_kept)
        } else {
            rewritten = self.with_wheel_effects(g, res, runs)?;
            (&rewritten, true)
        };
        let m = res.ik.entries();
        let n = self.n_wheels;
        let bound: f64 = (0..n).map(|j| m[2 * n + j].abs() * g.u_max[j]).sum();
        if bound > MAX_STEP_ANGLE_RAD || !bound.is_finite() {
            return None;
        }
        let arc = res.scheme == Scheme::ExactArc;
        let sensor = res.sensor_from_body;
        let mut walk = |u: &[Lanes]| match (n, arc) {
            (3, true) => dispatch::<3, true>(g, u, m, sensor, on_query),
            (3, false) => dispatch::<3, false>(g, u, m, sensor, on_query),
            (4, true) => dispatch::<4, true>(g, u, m, sensor, on_query),
            _ => dispatch::<4, false>(g, u, m, sensor, on_query),
        };
        if kept { Some(walk(&g.u)) } else { self.with_increments(g, runs, walk) }
    }
}

/// Lane-wise arithmetic on four runs: AVX2 + FMA vectors where the CPU has them, plain arrays otherwise.
trait LaneOps: Copy {
    type V: Copy;
    fn splat(self, v: f64) -> Self::V;
    fn load(self, a: Lanes) -> Self::V;
    fn store(self, v: Self::V) -> Lanes;
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a b + c` (fused where available).
    fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    /// `c − a b` (fused where available).
    fn neg_mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
}

/// Plain `[f64; 4]` arithmetic (no FMA), for CPUs without AVX2 + FMA.
#[derive(Clone, Copy)]
struct Portable;

impl LaneOps for Portable {
    type V = Lanes;
    #[inline(always)]
    fn splat(self, v: f64) -> Lanes {
        [v; LANES]
    }
    #[inline(always)]
    fn load(self, a: Lanes) -> Lanes {
        a
    }
    #[inline(always)]
    fn store(self, v: Lanes) -> Lanes {
        v
    }
    #[inline(always)]
    fn add(self, a: Lanes, b: Lanes) -> Lanes {
        std::array::from_fn(|l| a[l] + b[l])
    }
    #[inline(always)]
    fn mul(self, a: Lanes, b: Lanes) -> Lanes {
        std::array::from_fn(|l| a[l] * b[l])
    }
    #[inline(always)]
    fn mul_add(self, a: Lanes, b: Lanes, c: Lanes) -> Lanes {
        std::array::from_fn(|l| a[l] * b[l] + c[l])
    }
    #[inline(always)]
    fn neg_mul_add(self, a: Lanes, b: Lanes, c: Lanes) -> Lanes {
        std::array::from_fn(|l| c[l] - a[l] * b[l])
    }
}

#[cfg(target_arch = "x86_64")]
impl LaneOps for pulp::x86::V3 {
    type V = pulp::f64x4;
    #[inline(always)]
    fn splat(self, v: f64) -> Self::V {
        pulp::f64x4(v, v, v, v)
    }
    #[inline(always)]
    fn load(self, a: Lanes) -> Self::V {
        pulp::f64x4(a[0], a[1], a[2], a[3])
    }
    #[inline(always)]
    fn store(self, v: Self::V) -> Lanes {
        [v.0, v.1, v.2, v.3]
    }
    #[inline(always)]
    fn add(self, a: Self::V, b: Self::V) -> Self::V {
        pulp::Simd::add_f64s(self, a, b)
    }
    #[inline(always)]
    fn mul(self, a: Self::V, b: Self::V) -> Self::V {
        pulp::Simd::mul_f64s(self, a, b)
    }
    #[inline(always)]
    fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V {
        pulp::Simd::mul_add_e_f64s(self, a, b, c)
    }
    #[inline(always)]
    fn neg_mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V {
        pulp::Simd::negate_mul_add_e_f64s(self, a, b, c)
    }
}

// Series of sin(a)/a and (1 − cos a)/a: truncation error below 3e-18 for |a| ≤ 0.1.
const S1: f64 = -1.0 / 6.0;
const S2: f64 = 1.0 / 120.0;
const S3: f64 = -1.0 / 5040.0;
const S4: f64 = 1.0 / 362_880.0;
const C0: f64 = 0.5;
const C1: f64 = -1.0 / 24.0;
const C2: f64 = 1.0 / 720.0;
const C3: f64 = -1.0 / 40_320.0;
const C4: f64 = 1.0 / 3_628_800.0;

/// `sin(a)/a` and `(1 − cos a)/a` for small `a`.
#[inline(always)]
fn arc_factors(a: f64) -> (f64, f64) {
    let a2 = a * a;
    let sinc = 1.0 + a2 * (S1 + a2 * (S2 + a2 * (S3 + a2 * S4)));
    let cosc = a * (C0 + a2 * (C1 + a2 * (C2 + a2 * (C3 + a2 * C4))));
    (sinc, cosc)
}

/// One lane's state: body pose and the heading's cosine and sine.
#[derive(Clone, Copy, Debug)]
struct LaneState {
    x: f64,
    y: f64,
    th: f64,
    c: f64,
    s: f64,
}

/// One step of one lane by the body displacement `(dx, dy)` and turn `a` (scalar; for queries).
#[inline(always)]
fn step_lane<const ARC: bool>(st: LaneState, dx: f64, dy: f64, a: f64) -> LaneState {
    let (sinc, cosc) = arc_factors(a);
    let (bx, by) = if ARC { (sinc * dx - cosc * dy, cosc * dx + sinc * dy) } else { (dx, dy) };
    let (sa, cm1) = (a * sinc, -a * cosc); // sin a, cos a − 1
    LaneState {
        x: st.x + st.c * bx - st.s * by,
        y: st.y + st.s * bx + st.c * by,
        th: st.th + a,
        c: st.c + st.c * cm1 - st.s * sa,
        s: st.s + st.s * cm1 + st.c * sa,
    }
}

/// The body displacement `M u` of a step (scalar).
#[inline(always)]
fn displacement<const N: usize>(m: &[f64], u: &[f64]) -> (f64, f64, f64) {
    let (mut dx, mut dy, mut a) = (0.0, 0.0, 0.0);
    for j in 0..N {
        dx += m[j] * u[j];
        dy += m[N + j] * u[j];
        a += m[2 * N + j] * u[j];
    }
    (dx, dy, a)
}

/// `wrap_angle`, with the common case (already within (−π, π]) first.
#[inline(always)]
fn wrap(d: f64) -> f64 {
    if d > -std::f64::consts::PI && d <= std::f64::consts::PI { d } else { wrap_angle(d) }
}

/// The measured pose of a lane (body ∘ sensor) and its error to `truth`.
#[inline(always)]
fn measured_error(st: LaneState, sensor: Pose2, truth: &Pose2) -> PoseError {
    PoseError {
        dx_m: st.x + st.c * sensor.x_m - st.s * sensor.y_m - truth.x_m,
        dy_m: st.y + st.s * sensor.x_m + st.c * sensor.y_m - truth.y_m,
        dtheta_rad: wrap(st.th + sensor.theta_rad - truth.theta_rad),
    }
}

/// Walks group `g` with increments `u` (its own or redone).
fn dispatch<const N: usize, const ARC: bool>(
    g: &Group,
    u: &[Lanes],
    m: &[f64],
    sensor: Pose2,
    on_query: &mut dyn FnMut(usize, PoseError),
) -> [PoseError; LANES] {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        return simd.vectorize(|| kernel::<_, N, ARC>(simd, g, u, m, sensor, on_query));
    }
    kernel::<_, N, ARC>(Portable, g, u, m, sensor, on_query)
}

/// The lane states of a group, unpacked.
#[inline(always)]
fn unpack<O: LaneOps>(o: O, v: &[O::V; 5]) -> [LaneState; LANES] {
    let [x, y, th, c, s] = v.map(|v| o.store(v));
    std::array::from_fn(|l| LaneState { x: x[l], y: y[l], th: th[l], c: c[l], s: s[l] })
}

#[inline(always)]
fn kernel<O: LaneOps, const N: usize, const ARC: bool>(
    o: O,
    g: &Group,
    u: &[Lanes],
    m: &[f64],
    sensor: Pose2,
    on_query: &mut dyn FnMut(usize, PoseError),
) -> [PoseError; LANES] {
    let inv = sensor.inverse();
    let mut init = [[0.0; LANES]; 5];
    for l in 0..LANES {
        let body = g.start[l].compose(&inv);
        let (s, c) = body.theta_rad.sin_cos();
        for (v, value) in init.iter_mut().zip([body.x_m, body.y_m, body.theta_rad, c, s]) {
            v[l] = value;
        }
    }
    let [mut x, mut y, mut th, mut c, mut s] = init.map(|v| o.load(v));
    let mx: [O::V; N] = std::array::from_fn(|j| o.splat(m[j]));
    let my: [O::V; N] = std::array::from_fn(|j| o.splat(m[N + j]));
    let ma: [O::V; N] = std::array::from_fn(|j| o.splat(m[2 * N + j]));
    let (s1, s2, s3, s4) = (o.splat(S1), o.splat(S2), o.splat(S3), o.splat(S4));
    let (c0, c1, c2, c3, c4) = (o.splat(C0), o.splat(C1), o.splat(C2), o.splat(C3), o.splat(C4));
    let one = o.splat(1.0);
    let mut qi = 0;
    let mut next_query = g.queries.first().map_or(usize::MAX, |q| q.step);
    let mut answer = |qi: &mut usize, next_query: &mut usize, v: &[O::V; 5]| {
        let lanes = unpack(o, v);
        while *qi < g.queries.len() && g.queries[*qi].step == *next_query {
            let q = &g.queries[*qi];
            let (dx, dy, a) = displacement::<N>(m, &g.query_u[*qi * N..(*qi + 1) * N]);
            on_query(q.slot, measured_error(step_lane::<ARC>(lanes[q.lane], dx, dy, a), sensor, &q.truth));
            *qi += 1;
        }
        *next_query = g.queries.get(*qi).map_or(usize::MAX, |q| q.step);
    };
    for (k, uk) in u[..g.steps * N].chunks_exact(N).enumerate() {
        if k == next_query {
            answer(&mut qi, &mut next_query, &[x, y, th, c, s]);
        }
        let u: [O::V; N] = std::array::from_fn(|j| o.load(uk[j]));
        let mut dx = o.mul(mx[0], u[0]);
        let mut dy = o.mul(my[0], u[0]);
        let mut a = o.mul(ma[0], u[0]);
        for j in 1..N {
            dx = o.mul_add(mx[j], u[j], dx);
            dy = o.mul_add(my[j], u[j], dy);
            a = o.mul_add(ma[j], u[j], a);
        }
        let a2 = o.mul(a, a);
        let p = o.mul_add(a2, s4, s3);
        let p = o.mul_add(a2, p, s2);
        let p = o.mul_add(a2, p, s1);
        let sinc = o.mul_add(a2, p, one);
        let q = o.mul_add(a2, c4, c3);
        let q = o.mul_add(a2, q, c2);
        let q = o.mul_add(a2, q, c1);
        let cosc = o.mul(a, o.mul_add(a2, q, c0));
        let (bx, by) = if ARC {
            (o.neg_mul_add(cosc, dy, o.mul(sinc, dx)), o.mul_add(cosc, dx, o.mul(sinc, dy)))
        } else {
            (dx, dy)
        };
        x = o.mul_add(c, bx, o.neg_mul_add(s, by, x));
        y = o.mul_add(s, bx, o.mul_add(c, by, y));
        let sa = o.mul(a, sinc);
        let ac = o.mul(a, cosc); // 1 − cos a
        let c_next = o.neg_mul_add(c, ac, o.neg_mul_add(s, sa, c));
        s = o.neg_mul_add(s, ac, o.mul_add(c, sa, s));
        c = c_next;
        th = o.add(th, a);
        if k % RESYNC_STEPS == RESYNC_STEPS - 1 {
            let t = o.store(th);
            let sc = t.map(f64::sin_cos);
            s = o.load(sc.map(|v| v.0));
            c = o.load(sc.map(|v| v.1));
        }
    }
    let v = [x, y, th, c, s];
    if qi < g.queries.len() {
        answer(&mut qi, &mut next_query, &v);
    }
    let lanes = unpack(o, &v);
    std::array::from_fn(|l| measured_error(lanes[l], sensor, &g.end[l]))
}

/// Mean squared path error of one run's errors (weighted heading), as [`crate::cost::run_path_mse`].
fn mse(e: &[PoseError], w: f64) -> f64 {
    let sum: f64 = e
        .iter()
        .map(|e| {
            let th = w * e.dtheta_rad;
            e.dx_m * e.dx_m + e.dy_m * e.dy_m + th * th
        })
        .sum();
    sum / e.len().max(1) as f64
}

/// One predicted pose's error `(dx, dy, dθ)` and its derivatives with respect to the IK entries (up to
/// 4 wheels: 12 columns).
#[derive(Clone, Copy, Debug)]
struct Row {
    error: [f64; 3],
    d: [[f64; 12]; 3],
}

/// Forward-mode sums along a walk, per wheel `j` (see [`jacobian_lane`]).
#[derive(Clone, Copy, Debug)]
struct Tangents<const N: usize> {
    /// Σ u_j (p_x, p_y): world displacement per unit body-x displacement, weighted by the increment.
    d: [[f64; 2]; N],
    /// Σ u_j R B'(a) b: the change of the arc's shape with its angle.
    g: [[f64; 2]; N],
    /// Σ u_j (= ∂θ/∂m3j).
    u: [f64; N],
    /// Σ u_j x_after, Σ u_j y_after.
    p: [[f64; 2]; N],
}

/// Derivatives of `sin(a)/a` and `(1 − cos a)/a`.
#[inline(always)]
fn arc_factor_slopes(a: f64) -> (f64, f64) {
    let a2 = a * a;
    let ds = a * (2.0 * S1 + a2 * (4.0 * S2 + a2 * (6.0 * S3 + a2 * 8.0 * S4)));
    let dc = C0 + a2 * (3.0 * C1 + a2 * (5.0 * C2 + a2 * (7.0 * C3 + a2 * 9.0 * C4)));
    (ds, dc)
}

/// One step of a lane with its tangents.
#[inline(always)]
fn step_with_tangents<const N: usize, const ARC: bool>(
    st: LaneState,
    t: &mut Tangents<N>,
    m: &[f64],
    u: &[f64],
) -> LaneState {
    let (dx, dy, a) = displacement::<N>(m, u);
    let (sinc, cosc) = arc_factors(a);
    let (sb, cb) = if ARC { (sinc, cosc) } else { (1.0, 0.0) };
    let (px, py) = (st.c * sb - st.s * cb, st.s * sb + st.c * cb);
    let (gx, gy) = if ARC {
        let (ds, dc) = arc_factor_slopes(a);
        let (bx, by) = (ds * dx - dc * dy, dc * dx + ds * dy);
        (st.c * bx - st.s * by, st.s * bx + st.c * by)
    } else {
        (0.0, 0.0)
    };
    let next = step_lane::<ARC>(st, dx, dy, a);
    for (j, &uj) in u.iter().enumerate().take(N) {
        t.d[j][0] += uj * px;
        t.d[j][1] += uj * py;
        t.g[j][0] += uj * gx;
        t.g[j][1] += uj * gy;
        t.u[j] += uj;
        t.p[j][0] += uj * next.x;
        t.p[j][1] += uj * next.y;
    }
    next
}

/// The measured pose's error and derivatives at lane state `st` with tangents `t`.
///
/// With `Θ_j = Σ u_j` the heading's derivative, a step's world displacement `Δ = R(θ) B(a) b` moves by
/// `Θ_j J Δ` through the heading, so `∂x/∂m3j = −Σ_k Θ_jk Δy_k + g_jx = −(y Θ_j − Σ u_j y_after) + g_jx` (and
/// likewise for y); the first two rows act on `b` only: `∂(x, y)/∂m1j = d_j`, `∂(x, y)/∂m2j = J d_j`.
fn tangent_row<const N: usize>(st: LaneState, t: &Tangents<N>, sensor: Pose2, truth: &Pose2) -> Row {
    let e = measured_error(st, sensor, truth);
    let mut d = [[0.0; 12]; 3];
    // The sensor's lever arm turns with the heading.
    let (lx, ly) = (-st.s * sensor.x_m - st.c * sensor.y_m, st.c * sensor.x_m - st.s * sensor.y_m);
    for j in 0..N {
        d[0][j] = t.d[j][0];
        d[1][j] = t.d[j][1];
        d[0][N + j] = -t.d[j][1];
        d[1][N + j] = t.d[j][0];
        let th = t.u[j];
        d[0][2 * N + j] = -(st.y * th - t.p[j][1]) + t.g[j][0] + th * lx;
        d[1][2 * N + j] = (st.x * th - t.p[j][0]) + t.g[j][1] + th * ly;
        d[2][2 * N + j] = th;
    }
    Row { error: [e.dx_m, e.dy_m, e.dtheta_rad], d }
}

/// The rows of one lane (one run): its queries in slot order, or its end pose.
fn jacobian_lane<const N: usize, const ARC: bool>(
    g: &Group,
    increments: &[Lanes],
    lane: usize,
    m: &[f64],
    sensor: Pose2,
    selection: Selection,
) -> Vec<Row> {
    let body = g.start[lane].compose(&sensor.inverse());
    let (s, c) = body.theta_rad.sin_cos();
    let mut st = LaneState { x: body.x_m, y: body.y_m, th: body.theta_rad, c, s };
    let mut t = Tangents::<N> { d: [[0.0; 2]; N], g: [[0.0; 2]; N], u: [0.0; N], p: [[0.0; 2]; N] };
    let mine: Vec<(usize, &Query)> = g.queries.iter().enumerate().filter(|(_, q)| q.lane == lane).collect();
    let first_slot = mine.iter().map(|(_, q)| q.slot).min().unwrap_or(0);
    let mut rows = vec![Row { error: [0.0; 3], d: [[0.0; 12]; 3] }; mine.len()];
    let mut next = 0;
    let mut u = [0.0; N];
    for k in 0..=g.steps {
        while next < mine.len() && mine[next].1.step == k {
            let (qi, q) = mine[next];
            let mut tq = t;
            let sq = step_with_tangents::<N, ARC>(st, &mut tq, m, &g.query_u[qi * N..(qi + 1) * N]);
            rows[q.slot - first_slot] = tangent_row(sq, &tq, sensor, &q.truth);
            next += 1;
        }
        if k == g.steps {
            break;
        }
        for (j, v) in u.iter_mut().enumerate() {
            *v = increments[k * N + j][lane];
        }
        st = step_with_tangents::<N, ARC>(st, &mut t, m, &u);
        if k % RESYNC_STEPS == RESYNC_STEPS - 1 {
            (st.s, st.c) = st.th.sin_cos();
        }
    }
    match selection {
        Selection::End => vec![tangent_row(st, &t, sensor, &g.end[lane])],
        Selection::Path(_) => rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effect::EffectKind;
    use crate::ik::IkMatrix;
    use crate::model::{FittedModel, Integration, Model};
    use crate::odometry;
    use crate::simulate::{SimConfig, simulate};

    fn paper_size() -> Vec<Run> {
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        simulate(&SimConfig { seed: 3, ..SimConfig::default() }, &truth, "t/").unwrap()
    }

    /// Largest difference between the fast and the literal errors over every run and selected pose.
    fn max_gap(model: &Model, params: &[f64], runs: &[Run], selection: Selection) -> (f64, usize) {
        let res = model.resolve(params).unwrap();
        let fixed = match model.integration.step {
            crate::model::StepMode::Fixed { dt_s } => dt_s,
            crate::model::StepMode::Stamps => unreachable!(),
        };
        let prepared = PreparedRuns::new(runs, fixed, selection);
        let fast = prepared.errors(&res, runs).unwrap();
        let ends = prepared.end_pose_errors(&res, runs).unwrap();
        let (mut gap, mut count) = (0.0f64, 0);
        let runs: &[Run] = runs;
        for ((run, f), end) in runs.iter().zip(&fast).zip(&ends) {
            let literal = odometry::residuals(&res, run, selection);
            assert_eq!(literal.len(), f.len());
            for (l, f) in literal.iter().zip(f) {
                gap = gap.max((l.error.dx_m - f.dx_m).abs()).max((l.error.dy_m - f.dy_m).abs());
                gap = gap.max((l.error.dtheta_rad - f.dtheta_rad).abs());
                count += 1;
            }
            let le = odometry::end_pose_error(&res, run);
            gap = gap.max((le.dx_m - end.dx_m).abs()).max((le.dy_m - end.dy_m).abs());
            gap = gap.max((le.dtheta_rad - end.dtheta_rad).abs());
        }
        (gap, count)
    }

    #[test]
    fn agrees_with_the_literal_walk_on_a_paper_size_set() {
        let runs = paper_size();
        assert_eq!(runs.len(), 180);
        for ik in [IkMatrix::paper_design(), IkMatrix::paper_calibrated(), IkMatrix::paper_parametric()] {
            for integration in [Integration::PAPER, Integration::DEFAULT] {
                let model = Model::ik(ik.clone()).with_integration(integration);
                let p = model.nominal();
                for selection in [Selection::End, Selection::Path(1), Selection::Path(4)] {
                    let (gap, count) = max_gap(&model, &p, &runs, selection);
                    eprintln!("{:?} {selection:?}: largest gap {gap:.1e} m", integration.scheme);
                    assert!(gap < 1e-9, "{integration:?} {selection:?}: gap {gap:e} m");
                    assert!(count >= 180);
                }
            }
        }
    }

    #[test]
    fn agrees_with_a_sensor_offset() {
        let runs: Vec<Run> = paper_size().into_iter().take(9).collect();
        let model =
            Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("sensor_offset_yaw", 3).unwrap());
        let mut p = model.nominal();
        p[9..].copy_from_slice(&[0.03, -0.02, 0.1]);
        let (gap, count) = max_gap(&model, &p, &runs, Selection::Path(1));
        assert!(gap < 1e-9, "gap {gap:e}");
        assert!(count > 9 * 30, "{count} poses");
    }

    #[test]
    fn agrees_with_wheel_stage_effects() {
        let runs: Vec<Run> = paper_size().into_iter().take(10).collect();
        for (id, values) in [
            ("wheel_asymmetry", vec![0.05, -0.03, 0.02]),
            ("speed_scale", vec![0.01, -0.02, 0.015]),
            ("accel_slip", vec![0.05, 0.02, -0.03]),
            ("backlash", vec![0.02, 0.01, 0.03]),
            ("wheel_eccentricity", vec![0.02, -0.01, 0.01, 0.015, 0.0, -0.02]),
        ] {
            let model = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id(id, 3).unwrap());
            let mut p = model.nominal();
            p[9..].copy_from_slice(&values);
            for selection in [Selection::End, Selection::Path(1)] {
                let (gap, _) = max_gap(&model, &p, &runs, selection);
                assert!(gap < 1e-9, "{id} {selection:?}: gap {gap:e}");
            }
        }
    }

    #[test]
    fn declines_what_it_cannot_do() {
        let runs: Vec<Run> = paper_size().into_iter().take(5).collect();
        let prepared = PreparedRuns::new(&runs, None, Selection::End);
        let lagged = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("time_offset", 3).unwrap());
        let mut p = lagged.nominal();
        assert!(prepared.errors(&lagged.resolve(&p).unwrap(), &runs).is_some(), "no lag at τ = 0");
        p[9] = 0.01;
        assert!(prepared.errors(&lagged.resolve(&p).unwrap(), &runs).is_none());
        let twist = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("rotation_slip", 3).unwrap());
        assert!(prepared.errors(&twist.resolve(&twist.nominal()).unwrap(), &runs).is_none());
        let paper_step = Model::ik(IkMatrix::paper_design()).with_integration(Integration::PAPER);
        assert!(prepared.errors(&paper_step.resolve(&paper_step.nominal()).unwrap(), &runs).is_none(), "other step");
        // A step angle beyond the polynomials' range.
        let fast = Model::ik(IkMatrix::new(3, vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 50.0, 50.0, 50.0]).unwrap());
        assert!(prepared.errors(&fast.resolve(&fast.nominal()).unwrap(), &runs).is_none());
    }

    #[test]
    fn redone_increments_give_the_same_bits_as_kept_ones() {
        let runs: Vec<Run> = paper_size().into_iter().take(23).collect();
        for (effect, values) in [(None, vec![]), (Some("speed_scale"), vec![0.01, -0.02, 0.015])] {
            let mut model = Model::ik(IkMatrix::paper_design()).with_integration(Integration::DEFAULT);
            if let Some(id) = effect {
                model = model.with_effect(EffectKind::from_id(id, 3).unwrap());
            }
            let mut p = IkMatrix::paper_calibrated().entries().to_vec();
            p.extend(&values);
            let res = model.resolve(&p).unwrap();
            for (sel, kind) in [(Selection::End, CostKind::EndPose), (Selection::Path(1), CostKind::PATH)] {
                let kept = PreparedRuns::new(&runs, None, sel);
                let redone = PreparedRuns::with_increment_budget(&runs, None, sel, 0);
                assert!(kept.increments_kept && !redone.increments_kept);
                let bits = |e: Vec<Vec<PoseError>>| -> Vec<u64> {
                    e.iter().flatten().flat_map(|e| [e.dx_m, e.dy_m, e.dtheta_rad].map(f64::to_bits)).collect()
                };
                assert_eq!(bits(kept.errors(&res, &runs).unwrap()), bits(redone.errors(&res, &runs).unwrap()));
                let ends = |p: &PreparedRuns| bits(vec![p.end_pose_errors(&res, &runs).unwrap()]);
                assert_eq!(ends(&kept), ends(&redone));
                assert_eq!(
                    kept.cost(&res, &runs, kind).unwrap().to_bits(),
                    redone.cost(&res, &runs, kind).unwrap().to_bits()
                );
                if effect.is_none() {
                    let (rk, jk) = kept.residuals_and_ik_jacobian(&res, &runs, kind).unwrap();
                    let (rr, jr) = redone.residuals_and_ik_jacobian(&res, &runs, kind).unwrap();
                    assert_eq!(rk, rr);
                    assert_eq!(jk, jr);
                }
            }
        }
    }

    #[test]
    fn jacobian_blocks_come_in_run_order_across_batches() {
        let runs: Vec<Run> = paper_size().into_iter().cycle().take(BLOCK_RUNS + 2 * LANES + 1).collect();
        let model = Model::ik(IkMatrix::paper_design());
        let fixed = match model.integration.step {
            crate::model::StepMode::Fixed { dt_s } => dt_s,
            crate::model::StepMode::Stamps => unreachable!(),
        };
        let prepared = PreparedRuns::new(&runs, fixed, Selection::Path(1));
        let x = IkMatrix::paper_calibrated().entries().to_vec();
        let res = model.resolve(&x).unwrap();
        let full = prepared.residual_vector(&res, &runs, CostKind::PATH).unwrap();
        let (mut next, mut row) = (0, 0);
        prepared
            .ik_jacobian_blocks(&res, &runs, CostKind::PATH, &mut |b| {
                assert_eq!(b.run, next);
                let rows = 3 * (runs[b.run].truth().len() - 1);
                assert_eq!((b.residuals.len(), b.jacobian.nrows(), b.jacobian.ncols()), (rows, rows, 9));
                for (a, f) in b.residuals.iter().zip(&full[row..row + rows]) {
                    assert!((a - f).abs() < 1e-15, "run {}: {a} vs {f}", b.run);
                }
                next += 1;
                row += rows;
            })
            .unwrap();
        assert_eq!((next, row), (runs.len(), full.len()));
    }

    #[test]
    fn ik_jacobian_matches_central_differences() {
        let runs: Vec<Run> = paper_size().into_iter().step_by(15).collect();
        for (integration, kind, sel) in [
            (Integration::PAPER, CostKind::EndPose, Selection::End),
            (Integration::DEFAULT, CostKind::EndPose, Selection::End),
            (Integration::DEFAULT, CostKind::PATH, Selection::Path(1)),
            (Integration::PAPER, CostKind::Path { every: 3, heading_weight_m_per_rad: 0.5 }, Selection::Path(3)),
        ] {
            let model = Model::ik(IkMatrix::paper_design())
                .with_integration(integration)
                .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap());
            let fixed = match integration.step {
                crate::model::StepMode::Fixed { dt_s } => dt_s,
                crate::model::StepMode::Stamps => unreachable!(),
            };
            let prepared = PreparedRuns::new(&runs, fixed, sel);
            let mut x = IkMatrix::paper_calibrated().entries().to_vec();
            x.extend([0.02, -0.01]);
            let res = model.resolve(&x).unwrap();
            let (r, j) = prepared.residuals_and_ik_jacobian(&res, &runs, kind).unwrap();
            let fast = prepared.residual_vector(&res, &runs, kind).unwrap();
            assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "residuals differ");
            assert_eq!(j.ncols(), 9);
            let mut worst = 0.0f64;
            for c in 0..9 {
                let h = 1e-6 * x[c].abs().max(0.05);
                let mut xp = x.clone();
                xp[c] += h;
                let mut xm = x.clone();
                xm[c] -= h;
                let rp = prepared.residual_vector(&model.resolve(&xp).unwrap(), &runs, kind).unwrap();
                let rm = prepared.residual_vector(&model.resolve(&xm).unwrap(), &runs, kind).unwrap();
                // Relative to the column's largest entry: tiny entries carry the differences' rounding noise.
                let col_max = (0..r.len()).map(|i| j[(i, c)].abs()).fold(0.0f64, f64::max);
                assert!(col_max > 1e-3, "column {c} is flat");
                for i in 0..r.len() {
                    let fd = (rp[i] - rm[i]) / (2.0 * h);
                    let err = (fd - j[(i, c)]).abs() / col_max;
                    worst = worst.max(err);
                }
            }
            assert!(worst < 1e-6, "{integration:?} {kind:?}: worst relative gap {worst:e}");
        }
    }
}
