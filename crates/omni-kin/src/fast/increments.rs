//! The increments an evaluation walks, per lane group: the kept ones, ones redone from the runs' wheel speeds
//! into a thread's buffer, ones with an affine wheel-stage effect's parts added, or ones redone from speeds
//! rewritten by the model's wheel-stage effects; and the step-angle bound each must meet.

use super::features::{WheelFeatures, affine_wheel_effect};
use super::prepare::{Group, GroupParts, Increments, max_per_wheel};
use super::{LANES, Lanes, MAX_STEP_ANGLE_RAD, PreparedRuns};
use crate::model::Resolved;
use crate::plan::wheel_speeds;
use crate::run::Run;
use std::borrow::Cow;
use std::cell::RefCell;
use std::sync::Arc;

thread_local! {
    /// Each thread's buffer for increments redone on a walk (datasets beyond [`KEPT_INCREMENTS_MAX_BYTES`]).
    static SCRATCH: RefCell<Vec<Lanes>> = const { RefCell::new(Vec::new()) };
    /// Each thread's buffer for the queries' increments with an affine effect's parts.
    static QUERY_SCRATCH: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

impl PreparedRuns {
    /// The parts of `res`'s affine wheel-stage effect (taken at the first call), when it has one and they
    /// serve it.
    pub(crate) fn wheel_features(&self, res: &Resolved<'_>, runs: &[Run]) -> Option<&WheelFeatures> {
        let e = affine_wheel_effect(res)?;
        let f = self.features.get_or_init(|| Some(Arc::new(WheelFeatures::new(e, runs, self.fixed_dt_s))));
        f.as_deref().filter(|f| f.params(res).is_some())
    }

    /// The wheel speeds of group `g`'s runs (`chunk`) rewritten by `res`'s wheel-stage effects: from the
    /// parts of an affine one ([`WheelFeatures`], taken once), else by the effects themselves.
    fn rewritten_speeds<'r>(
        &self,
        g: &Group,
        chunk: &'r [Run],
        res: &Resolved<'_>,
        runs: &[Run],
    ) -> Vec<Cow<'r, [f64]>> {
        match self.wheel_features(res, runs).and_then(|f| f.params(res).map(|p| (f, p))) {
            Some((f, p)) => {
                chunk.iter().enumerate().map(|(lane, r)| Cow::Owned(f.speeds(g.first_run + lane, r, p))).collect()
            }
            None => chunk.iter().map(|r| wheel_speeds(res, r)).collect(),
        }
    }

    /// Calls `f` with the increments of group `g` for `res`: the kept ones, ones redone from the runs'
    /// wheel speeds into this thread's buffer, or ones redone from speeds rewritten by `res`'s wheel-stage
    /// effects. `None` when a step angle may exceed [`MAX_STEP_ANGLE_RAD`] or `runs` are not the
    /// prepared runs.
    pub(super) fn with_increments<R>(
        &self,
        g: &Group,
        res: &Resolved<'_>,
        runs: &[Run],
        f: impl FnOnce(&Increments<'_>) -> R,
    ) -> Option<R> {
        let m = res.ik.entries();
        let chunk = g.runs(runs)?;
        if let Some(features) = self.wheel_features(res, runs) {
            let p = features.params(res)?;
            if let Some(inc) = g.kept() {
                return with_parts(&inc, g.parts(features), p, (m, g.u_max()), f);
            }
            // Not kept: the same increments and parts, redone (the same bits).
            let wheels: Vec<&[f64]> = chunk.iter().map(Run::wheel_rad_s).collect();
            let mut u = Vec::new();
            g.fill_steps(&wheels, &mut u);
            return with_parts(&g.redone(&u), &g.make_parts(features), p, (m, g.u_max()), f);
        }
        let rewritten = (!res.wheel_effects.is_empty()).then(|| self.rewritten_speeds(g, chunk, res, runs));
        if rewritten.is_none() && !in_range(m, g.u_max()) {
            return None;
        }
        if let (None, Some(inc)) = (&rewritten, g.kept()) {
            return Some(f(&inc));
        }
        SCRATCH.with(|cell| {
            let mut u = cell.take();
            let out = match &rewritten {
                Some(speeds) => {
                    let wheels: Vec<&[f64]> = speeds.iter().map(|w| w.as_ref()).collect();
                    g.fill_steps(&wheels, &mut u);
                    let u_max = max_per_wheel(&u, self.n_wheels);
                    let query_u = g.fill_queries(&wheels);
                    in_range(m, &u_max).then(|| f(&Increments { u: &u, query_u: &query_u }))
                }
                None => {
                    let wheels: Vec<&[f64]> = chunk.iter().map(Run::wheel_rad_s).collect();
                    g.fill_steps(&wheels, &mut u);
                    Some(f(&g.redone(&u)))
                }
            };
            cell.replace(u);
            out
        })
    }
}

/// Calls `f` with the kept increments `inc` plus the parts of an affine wheel-stage effect at parameters
/// `p` (its speeds' change as increments, [`GroupParts`]), in this thread's buffer; `None` when a step angle
/// of IK matrix `m` may exceed [`MAX_STEP_ANGLE_RAD`] (`u_max`: the unchanged increments' bound, widened by
/// the parts').
fn with_parts<R>(
    inc: &Increments<'_>,
    parts: &GroupParts,
    p: &[f64],
    (m, u_max): (&[f64], &[f64]),
    f: impl FnOnce(&Increments<'_>) -> R,
) -> Option<R> {
    let (n, np) = (u_max.len(), parts.keys.len());
    // The parts with a parameter not zero: (index, wheel, value).
    let active: Vec<(usize, usize, f64)> = (parts.keys.iter().enumerate())
        .map(|(i, &(param, wheel))| (i, wheel, p[param]))
        .filter(|a| a.2 != 0.0)
        .collect();
    let mut bound = u_max.to_vec();
    for &(i, wheel, v) in &active {
        bound[wheel] += v.abs() * parts.u_max[i];
    }
    SCRATCH.with(|cell| {
        let mut u = cell.take();
        u.clear();
        u.extend_from_slice(inc.u);
        for (step, row) in u.chunks_exact_mut(n.max(1)).zip(parts.u.chunks_exact(np.max(1))) {
            for &(i, wheel, v) in &active {
                for l in 0..LANES {
                    step[wheel][l] += v * row[i][l];
                }
            }
        }
        let mut query_u = QUERY_SCRATCH.with(|q| q.take());
        query_u.clear();
        query_u.extend_from_slice(inc.query_u);
        for (q, row) in query_u.chunks_exact_mut(n.max(1)).zip(parts.query_u.chunks_exact(np.max(1))) {
            for &(i, wheel, v) in &active {
                q[wheel] += v * row[i];
            }
        }
        let ok = in_range(m, &bound) || in_range(m, &max_per_wheel(&u, n));
        let out = ok.then(|| f(&Increments { u: &u, query_u: &query_u }));
        cell.replace(u);
        QUERY_SCRATCH.with(|q| q.replace(query_u));
        out
    })
}

/// True when no step angle can exceed [`MAX_STEP_ANGLE_RAD`]: `Σ_j |m3j| max|u_j|` bounds it.
pub(super) fn in_range(m: &[f64], u_max: &[f64]) -> bool {
    let n = u_max.len();
    let bound: f64 = (0..n).map(|j| m[2 * n + j].abs() * u_max[j]).sum();
    bound <= MAX_STEP_ANGLE_RAD && bound.is_finite()
}
