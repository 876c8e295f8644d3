//! Fast odometry: the same steps as [`crate::odometry`] (every route reads the runs'
//! [`crate::plan::StepPlan`]s; the numbers agree within rounding, checked to 1e-9 m against the literal walk
//! in tests), with no `sin_cos` per step. [`crate::evaluate::Evaluator`] chooses a route whenever one serves
//! a model and aggregates the errors; nothing else calls these modules.
//!
//! - `prepare.rs`: what depends only on the data, done once in [`PreparedRuns::new`]: each step's fraction
//!   is folded into its wheel-angle increment `u_k = f_k h w_k` (rad), so with the IK matrix `M` a step's
//!   body displacement is `M u_k` — 3 × N multiply-adds — for both Eq. 1 (Euler) and exact arcs. The
//!   increments are kept up to [`KEPT_INCREMENTS_MAX_BYTES`] (8 B per wheel and sample); for larger
//!   datasets each walk redoes a lane group's increments from the runs' own wheel columns (the same
//!   products, so the same numbers). Runs are interleaved eight to a lane group (struct of arrays). A clock
//!   lag takes lane groups prepared for it (the last 4 lags are kept).
//! - `increments.rs`: the increments a walk reads, per lane group: kept, redone into a thread's buffer, with an
//!   affine wheel-stage effect's parts added, or from speeds the wheel-stage effects rewrote; and the step-angle
//!   bound they must meet.
//! - `features.rs`: the parts of an affine wheel-stage effect (each parameter's change of the speeds),
//!   taken once; an evaluation adds them to the increments instead of running the effect.
//! - `lanes.rs`: the eight lanes' arithmetic and its [`SimdPath`]: one AVX-512 vector, two passes of one
//!   AVX2 + FMA vector, or plain arrays with fused multiply-adds, the widest the CPU has (checked at run time through
//!   `pulp`, no `-C target-cpu` needed) under a ceiling ([`limit_simd_path`], `OMNICAL_SIMD` on the command
//!   line). Every path gives the same bits.
//! - `kernel.rs`: the step loop; the heading's cosine and sine advance by polynomial rotations.
//! - `twist.rs`: the built-in twist-stage effects per lane (the hooks' formulas), a step loop with them,
//!   and their exact slopes.
//! - `jacobian.rs`: the forward-mode Jacobian of the kernel with respect to the IK matrix and the
//!   parameters of an affine wheel-stage effect.
//! - `general.rs`: the general fast walk, one run at a time (scalar), for what the lanes do not serve: a
//!   user's twist-stage effects (through their own hooks) and measured stamps; the kernel's polynomial steps.
//! - `forward.rs`: the forward-mode Jacobian along the general walk, with respect to the IK matrix and the
//!   parameters of twist- and measurement-stage effects and of the affine wheel-stage effect.
//!
//! Scope of the lane kernel: fixed steps with no measured stamps, 1 to [`MAX_WHEELS`] wheels; any clock
//! lag, measurement-stage effects, wheel-stage effects (affine ones from their parts, others by rewriting the
//! speeds on each evaluation) and the built-in twist-stage effects. The general walk serves any model.
//! Either returns `None` for a step angle above [`MAX_STEP_ANGLE_RAD`], and the evaluator takes the literal
//! walk.
//!
//! Results are deterministic: groups and runs are evaluated in parallel and collected in run order, so they
//! do not depend on the thread count. The lane kernel's paths ([`SimdPath`]) give the same bits; a run's
//! numbers do not depend on the runs that share its group.

mod features;
pub(crate) mod forward;
pub(crate) mod general;
mod increments;
mod jacobian;
mod kernel;
mod lanes;
mod prepare;
mod twist;

use crate::model::{Resolved, Scheme};
use crate::odometry::Selection;
use crate::pose::PoseError;
use crate::run::Run;
use features::WheelFeatures;
use increments::in_range;
pub use lanes::{SimdPath, limit_simd_path};
use nalgebra::DMatrix;
use prepare::Group;
use rayon::prelude::*;
use std::sync::{Arc, Mutex, OnceLock};

/// Runs per lane group (one AVX-512 vector of f64; the same grouping on every [`SimdPath`], so the same
/// numbers).
pub const LANES: usize = 8;
/// Largest step angle the polynomials serve. rad.
pub const MAX_STEP_ANGLE_RAD: f64 = 0.1;
/// Largest wheel count the fast path serves (its kernels are compiled for 1 to 8 wheels; more take the
/// literal walk).
pub const MAX_WHEELS: usize = 8;
/// Runs whose Jacobian rows [`PreparedRuns::ik_jacobian_rows`] holds at once (a multiple of [`LANES`]).
pub const BLOCK_RUNS: usize = 256;
/// Largest size of the increments [`PreparedRuns::new`] keeps (8 B per wheel and sample: 64 MB holds
/// 2.8 M samples of 3 wheels, 13 × the paper-size set). Beyond, each walk of a lane group redoes its
/// increments from the runs' wheel speeds (the same products, so the same numbers) into a buffer of
/// the group's size: no copy of the dataset, at some speed.
pub const KEPT_INCREMENTS_MAX_BYTES: usize = 64 << 20;

type Lanes = [f64; LANES];

/// Calls `$f::<N, ARC>($args)` for the wheel count `$n` (1 to [`MAX_WHEELS`]) and scheme flag `$arc`:
/// `Some(result)`, or `None` for other wheel counts.
macro_rules! by_wheels {
    ($n:expr, $arc:expr, $($f:ident)::+ ($($a:expr),* $(,)?)) => {
        match ($n, $arc) {
            (1, false) => Some($($f)::+::<1, false>($($a),*)),
            (1, true) => Some($($f)::+::<1, true>($($a),*)),
            (2, false) => Some($($f)::+::<2, false>($($a),*)),
            (2, true) => Some($($f)::+::<2, true>($($a),*)),
            (3, false) => Some($($f)::+::<3, false>($($a),*)),
            (3, true) => Some($($f)::+::<3, true>($($a),*)),
            (4, false) => Some($($f)::+::<4, false>($($a),*)),
            (4, true) => Some($($f)::+::<4, true>($($a),*)),
            (5, false) => Some($($f)::+::<5, false>($($a),*)),
            (5, true) => Some($($f)::+::<5, true>($($a),*)),
            (6, false) => Some($($f)::+::<6, false>($($a),*)),
            (6, true) => Some($($f)::+::<6, true>($($a),*)),
            (7, false) => Some($($f)::+::<7, false>($($a),*)),
            (7, true) => Some($($f)::+::<7, true>($($a),*)),
            (8, false) => Some($($f)::+::<8, false>($($a),*)),
            (8, true) => Some($($f)::+::<8, true>($($a),*)),
            _ => None,
        }
    };
}

/// The errors the fast path computed, in run order.
#[derive(Clone, Debug, Default)]
pub struct FastErrors {
    /// Errors at the selected ground-truth poses, every run's in turn (empty for [`Selection::End`]).
    pub at_queries: Vec<PoseError>,
    /// End-pose error of each run (the Eq. 6 terms).
    pub ends: Vec<PoseError>,
}

/// One run's errors at its selected poses and their unscaled IK Jacobian, as
/// [`PreparedRuns::ik_jacobian_rows`] visits them (the Jacobian is the visitor's to scale in place).
#[derive(Debug)]
pub struct JacobianRows<'a> {
    /// Index of the run.
    pub run: usize,
    /// Errors at the selected poses (for [`Selection::End`], the end pose).
    pub errors: &'a [PoseError],
    /// `3 × errors.len()` rows (dx, dy, dθ of each pose) by the IK entries `m11 … m3N`, then the
    /// parameters of the affine wheel-stage effect (`wheel_columns` of them, in the effect's order).
    pub jacobian: &'a mut DMatrix<f64>,
    /// Columns after the IK entries: the affine wheel-stage effect's parameters (0 without one).
    pub wheel_columns: usize,
}

/// Runs prepared for fast repeated evaluation at one step rule and one selection of ground-truth poses.
#[derive(Clone, Debug)]
pub struct PreparedRuns {
    n_runs: usize,
    n_wheels: usize,
    fixed_dt_s: Option<f64>,
    selection: Selection,
    /// Keep the increments (else each walk redoes them).
    keep: bool,
    /// The groups without clock lag.
    groups: Vec<Group>,
    /// The groups of the last few other clock lags.
    lagged: LagCache,
    /// The parts of the models' affine wheel-stage effect, taken at the first evaluation with one.
    features: OnceLock<Option<Arc<WheelFeatures>>>,
}

/// Lagged group sets kept at once: a fit evaluates one lag several times (residuals, Jacobian rows) and its
/// finite differences two more.
const LAGS_KEPT: usize = 4;

/// The groups prepared for the last [`LAGS_KEPT`] clock lags other than 0, newest last, by the lag's bits.
/// Each set is a pure function of the runs and the lag, so the cache never changes a result.
#[derive(Debug, Default)]
struct LagCache(Mutex<Vec<(u64, Arc<Vec<Group>>)>>);

impl Clone for LagCache {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// The groups an evaluation walks: the prepared ones, or a set prepared for its clock lag.
enum Groups<'a> {
    Unlagged(&'a [Group]),
    Lagged(Arc<Vec<Group>>),
}

impl std::ops::Deref for Groups<'_> {
    type Target = [Group];
    fn deref(&self) -> &[Group] {
        match self {
            Groups::Unlagged(g) => g,
            Groups::Lagged(g) => g,
        }
    }
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
        let keep = bytes <= max_bytes;
        let groups = make_groups(runs, fixed_dt_s, selection, 0.0, keep);
        let (lagged, features) = (LagCache::default(), OnceLock::new());
        Self { n_runs: runs.len(), n_wheels, fixed_dt_s, selection, keep, groups, lagged, features }
    }

    /// The groups for a clock lag of `lag_s` (prepared now, or kept from an earlier evaluation); `None` when
    /// `runs` are not the prepared runs.
    fn groups_for(&self, lag_s: f64, runs: &[Run]) -> Option<Groups<'_>> {
        if runs.len() != self.n_runs {
            return None;
        }
        if lag_s == 0.0 {
            return Some(Groups::Unlagged(&self.groups));
        }
        let key = lag_s.to_bits();
        let kept = |cache: &Vec<(u64, Arc<Vec<Group>>)>| cache.iter().find(|(k, _)| *k == key).map(|(_, g)| g.clone());
        if let Some(g) = self.lagged.0.lock().ok().and_then(|c| kept(&c)) {
            return Some(Groups::Lagged(g));
        }
        let groups = Arc::new(make_groups(runs, self.fixed_dt_s, self.selection, lag_s, self.keep));
        if let Ok(mut cache) = self.lagged.0.lock() {
            if cache.len() == LAGS_KEPT {
                cache.remove(0);
            }
            cache.push((key, groups.clone()));
        }
        Some(Groups::Lagged(groups))
    }

    /// Number of runs.
    pub fn n_runs(&self) -> usize {
        self.n_runs
    }

    /// The selection of ground-truth poses these runs were prepared for.
    pub fn selection(&self) -> Selection {
        self.selection
    }

    /// Whether the increments are kept (else each walk redoes them).
    pub fn increments_kept(&self) -> bool {
        self.groups.iter().all(|g| g.kept().is_some())
    }

    /// True when `res` can use these prepared runs (same fixed step, no twist-stage effects, no measured
    /// stamps, 1 to [`MAX_WHEELS`] wheels). Wheel-stage effects are applied to the runs' wheel speeds
    /// before the increments are redone, on each evaluation; a clock lag takes groups prepared for it.
    pub fn supports(&self, res: &Resolved<'_>) -> bool {
        !res.stamps
            && res.clock_lag_s.is_finite()
            && (res.twist_effects.is_empty() || twist::lane_twists(res).is_some())
            && res.fixed_dt_s == self.fixed_dt_s
            && res.ik.n_wheels() == self.n_wheels
            && (1..=MAX_WHEELS).contains(&self.n_wheels)
    }

    /// Errors at the selected ground-truth poses and at each run's end, in run order. `None` when `res`
    /// needs the literal walk (or `runs` are not the prepared runs).
    pub fn errors(&self, res: &Resolved<'_>, runs: &[Run]) -> Option<FastErrors> {
        self.errors_on(SimdPath::selected(), res, runs)
    }

    /// [`Self::errors`] on the lane arithmetic of `path` (or the widest narrower one this CPU has): the
    /// same bits on every path.
    pub fn errors_on(&self, path: SimdPath, res: &Resolved<'_>, runs: &[Run]) -> Option<FastErrors> {
        if !self.supports(res) {
            return None;
        }
        let groups = self.groups_for(res.clock_lag_s, runs)?;
        let per_group: Vec<Option<(Vec<PoseError>, [PoseError; LANES])>> = (groups.par_iter())
            .map(|g| {
                let mut at = vec![PoseError::default(); g.queries.len()];
                let ends = self.walk_group(g, (res, path), runs, &mut |slot, e| at[slot] = e)?;
                Some((at, ends))
            })
            .collect();
        let mut out = FastErrors { at_queries: Vec::new(), ends: Vec::with_capacity(self.n_runs) };
        for (g, r) in groups.iter().zip(per_group) {
            let (at, ends) = r?;
            out.at_queries.extend(at);
            out.ends.extend_from_slice(&ends[..g.lanes]);
        }
        Some(out)
    }

    /// The end-pose error of every run (the Eq. 6 terms), in run order (any selection). `None` when `res`
    /// needs the literal walk.
    pub fn end_pose_errors(&self, res: &Resolved<'_>, runs: &[Run]) -> Option<Vec<PoseError>> {
        if !self.supports(res) {
            return None;
        }
        let (groups, path) = (self.groups_for(res.clock_lag_s, runs)?, SimdPath::selected());
        let per_group: Vec<Option<[PoseError; LANES]>> =
            groups.par_iter().map(|g| self.walk_group(g, (res, path), runs, &mut |_, _| {})).collect();
        let mut out = Vec::with_capacity(self.n_runs);
        for (g, ends) in groups.iter().zip(per_group) {
            out.extend_from_slice(&ends?[..g.lanes]);
        }
        Some(out)
    }

    /// Visits, in run order, each run's errors at the selected poses and their Jacobian with respect to the
    /// IK matrix entries (3 rows per pose: dx, dy, dθ; columns in row-major order `m11 … m3N`), unscaled,
    /// by forward-mode differentiation of the step recurrence; the sensor pose is held fixed. Only
    /// [`BLOCK_RUNS`] runs' rows are held at a time; the runs of a batch are differentiated in parallel
    /// and visited sequentially; with wheel-stage effects, along the rewritten speeds (the effects do not
    /// depend on the IK matrix). `None` (before any visit) when `res` needs the literal walk.
    pub fn ik_jacobian_rows(
        &self,
        res: &Resolved<'_>,
        runs: &[Run],
        visit: &mut dyn FnMut(JacobianRows<'_>),
    ) -> Option<()> {
        let m = res.ik.entries();
        let ok = self.supports(res) && res.twist_effects.is_empty() && runs.len() == self.n_runs;
        let groups = if ok { self.groups_for(res.clock_lag_s, runs)? } else { return None };
        // Every step angle in range before the first visit: on the runs' own speeds by their bound; on
        // rewritten ones by rewriting them (each batch checks its own before visiting, so only needed
        // when there are several).
        let in_range = if res.wheel_effects.is_empty() {
            groups.iter().all(|g| in_range(m, g.u_max()))
        } else {
            groups.len() <= BLOCK_RUNS / LANES
                || groups.par_iter().all(|g| self.with_increments(g, res, runs, |_| ()).is_some())
        };
        if !in_range {
            return None;
        }
        let (arc, sensor, n) = (res.scheme == Scheme::ExactArc, res.sensor_from_body, self.n_wheels);
        // An affine wheel-stage effect's parameters are differentiated along with the IK entries.
        let features = self.wheel_features(res, runs);
        let wheel_columns = features.map_or(0, |f| f.n_params());
        for batch in groups.chunks(BLOCK_RUNS / LANES) {
            let rows: Option<Vec<Vec<jacobian::LaneRows>>> = (batch.par_iter())
                .map(|g| {
                    let parts = features.map(|f| (g.parts(f), f.n_params()));
                    self.with_increments(g, res, runs, |inc| {
                        (0..g.lanes)
                            .map(|lane| {
                                by_wheels!(n, arc, jacobian::lane_rows(g, inc, lane, m, sensor, self.selection, parts))
                            })
                            .collect::<Option<Vec<_>>>()
                    })?
                })
                .collect();
            for (g, mut lanes) in batch.iter().zip(rows?) {
                for (lane, r) in lanes.iter_mut().enumerate() {
                    let (errors, jacobian) = (&r.errors, &mut r.jacobian);
                    visit(JacobianRows { run: g.first_run + lane, errors, jacobian, wheel_columns });
                }
            }
        }
        Some(())
    }

    /// Walks one group on `path`: calls `on_query(slot, error)` for each query and returns the end-pose
    /// errors.
    fn walk_group(
        &self,
        g: &Group,
        (res, path): (&Resolved<'_>, SimdPath),
        runs: &[Run],
        on_query: &mut dyn FnMut(usize, PoseError),
    ) -> Option<[PoseError; LANES]> {
        if !self.supports(res) {
            return None;
        }
        let (m, arc, sensor) = (res.ik.entries(), res.scheme == Scheme::ExactArc, res.sensor_from_body);
        if res.twist_effects.is_empty() {
            return self.with_increments(g, res, runs, |inc| {
                by_wheels!(self.n_wheels, arc, kernel::walk(path, g, inc, m, sensor, on_query))
            })?;
        }
        let twists = twist::lane_twists(res)?;
        let times = g.times(g.runs(runs)?);
        self.with_increments(g, res, runs, |inc| {
            by_wheels!(self.n_wheels, arc, twist::walk(g, inc, times, (m, sensor), &twists, on_query))
        })??
    }
}

/// The lane groups of `runs` (see [`PreparedRuns::with_increment_budget`]) for a wheel-clock lag of `lag_s`.
fn make_groups(runs: &[Run], fixed_dt_s: Option<f64>, selection: Selection, lag_s: f64, keep: bool) -> Vec<Group> {
    (runs.par_chunks(LANES).enumerate())
        .map(|(gi, chunk)| Group::new(gi * LANES, chunk, fixed_dt_s, selection, lag_s, keep))
        .collect()
}

#[cfg(test)]
mod tests;
