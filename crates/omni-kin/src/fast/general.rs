//! The general fast walk: what the lane kernel does not serve — a clock lag, twist-stage effects, measured
//! stamps — one run at a time. It takes exactly the literal walk's steps ([`crate::odometry`]: the same
//! [`StepPlan`], step lengths, twists and effect hooks), but advances the pose as the kernel does: the arc
//! factors and the heading's rotation from short polynomials in the step angle, the heading's cosine and
//! sine carried along (re-taken every [`RESYNC_STEPS`] steps), so no step calls `sin_cos`. A step angle
//! above [`MAX_STEP_ANGLE_RAD`] gives `None` (the caller takes the literal walk).

use super::MAX_STEP_ANGLE_RAD;
use super::kernel::{LaneState, RESYNC_STEPS, measured_error, step_lane};
use crate::effect::TwistAt;
use crate::model::{Resolved, Scheme};
use crate::odometry::twist_of;
use crate::plan::{StepPlan, interval};
use crate::pose::{Pose2, PoseError, Twist2};
use crate::run::Run;

/// The pose after holding twist `v` for `h` seconds from `st`; `None` when the step angle exceeds
/// [`MAX_STEP_ANGLE_RAD`] (or is not finite).
#[inline(always)]
fn advance(arc: bool, st: LaneState, v: &Twist2, h: f64) -> Option<LaneState> {
    let a = h * v.omega_rad_s;
    if a.is_nan() || a.abs() > MAX_STEP_ANGLE_RAD {
        return None;
    }
    let (dx, dy) = (h * v.vx_m_s, h * v.vy_m_s);
    Some(if arc { step_lane::<true>(st, dx, dy, a) } else { step_lane::<false>(st, dx, dy, a) })
}

/// Errors of `run` at the ground-truth poses of `plan` (built for `res`'s clock lag; in the plan's order)
/// and at its end, from the wheel speeds `wheels` (the run's own, or rewritten by wheel-stage effects).
/// `None` when a step angle exceeds [`MAX_STEP_ANGLE_RAD`].
pub(crate) fn run_errors(
    res: &Resolved<'_>,
    run: &Run,
    plan: &StepPlan,
    wheels: &[f64],
) -> Option<(Vec<PoseError>, PoseError)> {
    let n_w = run.n_wheels();
    let t = run.wheel_t_s();
    let (lag, median) = (plan.clock_lag_s, run.median_dt_s());
    let fixed = res.fixed_dt_s.unwrap_or(median);
    let truth = run.truth();
    let (sensor, arc) = (res.sensor_from_body, res.scheme == Scheme::ExactArc);
    let body = truth[0].pose.compose(&sensor.inverse());
    let (s, c) = body.theta_rad.sin_cos();
    let mut st = LaneState { x: body.x_m, y: body.y_m, th: body.theta_rad, c, s };
    let mut out = Vec::with_capacity(plan.queries.len());
    let mut queries = plan.queries.iter().peekable();
    for (i, f) in plan.fractions().enumerate() {
        let k = plan.first_sample + i;
        let (a_k, s_k) = interval(t, lag, median, k);
        let h = if res.stamps { s_k - a_k } else { fixed };
        let at =
            TwistAt { pose: Pose2::new(st.x, st.y, st.th), since_start_s: (0.5 * (a_k + s_k) - truth[0].t_s).max(0.0) };
        let v = twist_of(res, &wheels[k * n_w..(k + 1) * n_w], &at);
        while let Some(q) = queries.next_if(|q| q.step == i) {
            let p = match q.fraction {
                Some(fq) => advance(arc, st, &v, fq * h)?,
                None => st,
            };
            out.push(measured_error(p, sensor, &truth[q.truth_index].pose));
        }
        st = advance(arc, st, &v, f * h)?;
        if i % RESYNC_STEPS == RESYNC_STEPS - 1 {
            (st.s, st.c) = st.th.sin_cos();
        }
    }
    // After the last sample: at rest.
    for q in queries {
        out.push(measured_error(st, sensor, &truth[q.truth_index].pose));
    }
    let end = measured_error(st, sensor, &truth[truth.len() - 1].pose);
    Some((out, end))
}
