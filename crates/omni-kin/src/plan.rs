//! The step plan of one run: which wheel samples odometry integrates, over which fraction of their
//! interval, and where the selected ground-truth poses fall between them. It is built once per run (and
//! clock lag) and read by both the literal walk ([`crate::odometry`]) and the fast path ([`crate::fast`]),
//! so the two take the same steps by construction.
//!
//! Timing. Wheel sample `k`, stamped `t_k`, is taken at `s_k = t_k − τ` on the ground-truth clock (τ is
//! the clock lag) and covers the interval `(s_{k−1}, s_k]` (the first sample covers one median interval
//! before `s_0`). Integration starts at the first ground-truth stamp and stops at the last: the first and
//! last steps cover only the part of their interval inside that span (their fraction), every other step
//! its whole interval (fraction 1). A ground-truth pose inside an interval is predicted by the matching
//! fraction of its step; before the first and after the last sample the robot is taken to be at rest.

use crate::effect::{Effect, WheelContext};
use crate::model::Resolved;
use crate::run::Run;
use std::borrow::Cow;

/// One selected ground-truth pose in a plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryPoint {
    /// Index of the ground-truth pose in the run.
    pub truth_index: usize,
    /// Whole steps taken before it.
    pub step: usize,
    /// Fraction of step `step` that reaches it; `None` where the robot is at rest (before the first or
    /// after the last sample): the pose after `step` whole steps.
    pub fraction: Option<f64>,
}

/// The steps of one run and where its selected ground-truth poses fall.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepPlan {
    /// Wheel sample of the first step; step `i` integrates sample `first_sample + i`.
    pub first_sample: usize,
    /// Number of steps.
    pub steps: usize,
    /// Steps whose fraction of their interval is not 1, ascending: `(step, fraction)`.
    pub partial: Vec<(usize, f64)>,
    /// The selected ground-truth poses, in ascending time.
    pub queries: Vec<QueryPoint>,
    /// Clock lag the plan was built for. s.
    pub clock_lag_s: f64,
}

/// Start and end of sample `k`'s interval on the ground-truth clock. s.
#[inline]
pub fn interval(t_s: &[f64], lag_s: f64, median_dt_s: f64, k: usize) -> (f64, f64) {
    let s_k = t_s[k] - lag_s;
    let a_k = if k == 0 { s_k - median_dt_s } else { t_s[k - 1] - lag_s };
    (a_k, s_k)
}

impl StepPlan {
    /// The plan of `run` for a clock lag of `lag_s` seconds and the ground-truth poses `queries` (indices,
    /// ascending).
    pub fn new(run: &Run, lag_s: f64, queries: &[usize]) -> Self {
        let t = run.wheel_t_s();
        let median = run.median_dt_s();
        let truth = run.truth();
        let start = truth[0].t_s;
        let g_last = truth[truth.len() - 1].t_s;
        let mut plan = StepPlan { clock_lag_s: lag_s, ..Default::default() };
        let mut q = 0;
        while q < queries.len() && truth[queries[q]].t_s <= start {
            plan.queries.push(QueryPoint { truth_index: queries[q], step: 0, fraction: None });
            q += 1;
        }
        plan.first_sample = t.partition_point(|&tk| tk - lag_s <= start);
        let mut cursor = start;
        for k in plan.first_sample..t.len() {
            let step = k - plan.first_sample;
            let (a_k, s_k) = interval(t, lag_s, median, k);
            let len = s_k - a_k;
            let from = a_k.max(cursor);
            while q < queries.len() && truth[queries[q]].t_s <= s_k {
                let f = ((truth[queries[q]].t_s - from) / len).clamp(0.0, 1.0);
                plan.queries.push(QueryPoint { truth_index: queries[q], step, fraction: Some(f) });
                q += 1;
            }
            let last = s_k >= g_last;
            let f = ((if last { g_last } else { s_k } - from) / len).clamp(0.0, 1.0);
            if f != 1.0 {
                plan.partial.push((step, f));
            }
            plan.steps = step + 1;
            if last {
                break;
            }
            cursor = s_k;
        }
        // After the last sample: at rest.
        for &i in &queries[q..] {
            plan.queries.push(QueryPoint { truth_index: i, step: plan.steps, fraction: None });
        }
        plan
    }

    /// The fraction of each step, in order (1 but for the [`Self::partial`] ones).
    pub fn fractions(&self) -> impl Iterator<Item = f64> + '_ {
        let mut partial = self.partial.iter().peekable();
        (0..self.steps).map(move |i| match partial.peek() {
            Some(&&(k, f)) if k == i => {
                partial.next();
                f
            }
            _ => 1.0,
        })
    }
}

/// The wheel speeds odometry integrates: the run's own, or a copy rewritten by `res`'s wheel-stage
/// effects (which see the sample instants on the ground-truth clock and each sample's step length).
pub fn wheel_speeds<'r>(res: &Resolved<'_>, run: &'r Run) -> Cow<'r, [f64]> {
    if res.wheel_effects.is_empty() {
        return Cow::Borrowed(run.wheel_rad_s());
    }
    let (s, h) = sample_times(run, res.clock_lag_s, res.fixed_dt_s, res.stamps);
    let mut w = run.wheel_rad_s().to_vec();
    let ctx = WheelContext { n_wheels: run.n_wheels(), t_s: &s, dt_s: &h, start_angle_rad: run.wheel_start_rad() };
    for (e, p) in &res.wheel_effects {
        e.wheel_rates(p, &ctx, &mut w);
    }
    Cow::Owned(w)
}

/// What a wheel-stage effect sees of `run`'s timing for a clock lag of `lag_s`: each sample's instant on
/// the ground-truth clock and the step it is integrated over (`fixed_dt_s`, else the run's median
/// interval; with `stamps`, the measured interval). s.
pub fn sample_times(run: &Run, lag_s: f64, fixed_dt_s: Option<f64>, stamps: bool) -> (Vec<f64>, Vec<f64>) {
    let median = run.median_dt_s();
    let fixed = fixed_dt_s.unwrap_or(median);
    let s: Vec<f64> = run.wheel_t_s().iter().map(|t| t - lag_s).collect();
    let h: Vec<f64> = (0..s.len())
        .map(|k| {
            if !stamps {
                fixed
            } else if k == 0 {
                median
            } else {
                s[k] - s[k - 1]
            }
        })
        .collect();
    (s, h)
}
