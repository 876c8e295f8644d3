//! Odometry: integrate a run's wheel speeds through a resolved model (the paper's Eq. 1 and its exact-arc
//! variant), starting at the run's first ground-truth pose.
//!
//! Timing. Wheel sample `k`, stamped `t_k`, is taken at `s_k = t_k − τ` on the ground-truth clock (τ is
//! the clock lag of the model's effects, 0 without them) and covers the interval `(s_{k−1}, s_k]` (the
//! first sample covers one median interval before `s_0`). It is integrated as one step of length `h_k`:
//! the fixed step (Eq. 1; 10 ms in the paper) or, with measured stamps, `s_k − s_{k−1}`. A ground-truth
//! time inside an interval takes the matching fraction of its step, so odometry can be read at any
//! ground-truth stamp; before the first and after the last sample the robot is taken to be at rest.
//!
//! Steps. Euler (Eq. 1): `p ← p + h R(θ) v`. Exact arc: the twist held over the step, integrated
//! exactly on SE(2): `Δ = [S vx − C vy, C vx + S vy, ω h]` in the body frame with `S = sin(ωh)/ω`,
//! `C = (1 − cos ωh)/ω`.

use crate::effect::{Effect, TwistAt};
use crate::model::{Resolved, Scheme};
use crate::plan::{StepPlan, interval, wheel_speeds};
use crate::pose::{Pose2, PoseError, Twist2};
use crate::run::Run;
use serde::{Deserialize, Serialize};

/// Which ground-truth poses to predict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Selection {
    /// The last ground-truth pose only: the paper's Eq. 6.
    End,
    /// Every `k`-th ground-truth pose after the first, and always the last (`Path(1)` = every pose).
    Path(usize),
}

impl Selection {
    /// Ground-truth indices selected from `n` poses (ascending, never the first, always the last).
    pub fn indices(&self, n: usize) -> Vec<usize> {
        match *self {
            Selection::End => vec![n - 1],
            Selection::Path(k) => {
                let k = k.max(1);
                let mut v: Vec<usize> = (1..n).step_by(k).collect();
                if v.last() != Some(&(n - 1)) {
                    v.push(n - 1);
                }
                v
            }
        }
    }
}

/// A trajectory: poses of the measured point at the sample times (from the first to the last
/// ground-truth stamp).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Trajectory {
    /// Times on the ground-truth clock. s.
    pub t_s: Vec<f64>,
    /// Poses at those times.
    pub poses: Vec<Pose2>,
}

/// One predicted ground-truth pose and its error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Residual {
    /// Index of the ground-truth pose in the run.
    pub truth_index: usize,
    /// Its time. s.
    pub t_s: f64,
    /// Predicted pose of the measured point.
    pub predicted: Pose2,
    /// Predicted minus measured (world frame, heading wrapped).
    pub error: PoseError,
}

/// One integration step of `h` seconds with a constant body twist.
#[inline(always)]
pub fn step(scheme: Scheme, p: Pose2, v: Twist2, h: f64) -> Pose2 {
    let (s, c) = p.theta_rad.sin_cos();
    match scheme {
        Scheme::Euler => Pose2 {
            x_m: p.x_m + h * (c * v.vx_m_s - s * v.vy_m_s),
            y_m: p.y_m + h * (s * v.vx_m_s + c * v.vy_m_s),
            theta_rad: p.theta_rad + h * v.omega_rad_s,
        },
        Scheme::ExactArc => {
            let a = v.omega_rad_s * h;
            let (ss, cc) = if a.abs() < 1e-4 {
                let a2 = a * a;
                (h * (1.0 - a2 / 6.0), h * a * (0.5 - a2 / 24.0))
            } else {
                let (sa, ca) = a.sin_cos();
                (sa / v.omega_rad_s, (1.0 - ca) / v.omega_rad_s)
            };
            let bx = ss * v.vx_m_s - cc * v.vy_m_s;
            let by = cc * v.vx_m_s + ss * v.vy_m_s;
            Pose2 { x_m: p.x_m + c * bx - s * by, y_m: p.y_m + s * bx + c * by, theta_rad: p.theta_rad + a }
        }
    }
}

/// The body twist of sample `w` through the IK matrix and twist-stage effects, for a step that starts
/// at `at`.
#[inline]
pub(crate) fn twist_of(res: &Resolved<'_>, w: &[f64], at: &TwistAt) -> Twist2 {
    let mut t = res.ik.twist(w);
    for (e, p) in &res.twist_effects {
        t = e.twist_at(p, t, w, at);
    }
    t
}

/// Core loop: walks the steps of `plan` (built for `res`'s clock lag), calling `on_query` for each of its
/// ground-truth poses (ascending) with the measured point's predicted pose, and `on_sample` after each
/// step.
pub(crate) fn walk(
    res: &Resolved<'_>,
    run: &Run,
    plan: &StepPlan,
    mut on_query: impl FnMut(usize, Pose2),
    mut on_sample: impl FnMut(f64, Pose2),
) {
    let n_w = run.n_wheels();
    let t = run.wheel_t_s();
    let lag = plan.clock_lag_s;
    let median = run.median_dt_s();
    let fixed = res.fixed_dt_s.unwrap_or(median);
    let truth = run.truth();
    let sensor = res.sensor_from_body;
    let g_last = truth[truth.len() - 1].t_s;
    let wheels = wheel_speeds(res, run);

    let mut body = truth[0].pose.compose(&sensor.inverse());
    on_sample(truth[0].t_s, body.compose(&sensor));
    let mut queries = plan.queries.iter().peekable();
    for (i, f) in plan.fractions().enumerate() {
        let k = plan.first_sample + i;
        let (a_k, s_k) = interval(t, lag, median, k);
        let h = if res.stamps { s_k - a_k } else { fixed };
        let at = TwistAt { pose: body, since_start_s: (0.5 * (a_k + s_k) - truth[0].t_s).max(0.0) };
        let v = twist_of(res, &wheels[k * n_w..(k + 1) * n_w], &at);
        while let Some(q) = queries.next_if(|q| q.step == i) {
            let at = match q.fraction {
                Some(f) => step(res.scheme, body, v, f * h),
                None => body,
            };
            on_query(q.truth_index, at.compose(&sensor));
        }
        body = step(res.scheme, body, v, f * h);
        on_sample(if s_k >= g_last { g_last } else { s_k }, body.compose(&sensor));
    }
    // After the last sample: at rest.
    for q in queries {
        on_query(q.truth_index, body.compose(&sensor));
    }
}

/// Predicted measured poses at the selected ground-truth stamps, with their errors.
pub fn residuals(res: &Resolved<'_>, run: &Run, selection: Selection) -> Vec<Residual> {
    let idx = selection.indices(run.truth().len());
    let mut out = Vec::with_capacity(idx.len());
    let truth = run.truth();
    walk(
        res,
        run,
        &StepPlan::new(run, res.clock_lag_s, &idx),
        |i, p| {
            out.push(Residual { truth_index: i, t_s: truth[i].t_s, predicted: p, error: p.error_to(&truth[i].pose) })
        },
        |_, _| {},
    );
    if run.truth_position_only() {
        let mut errors: Vec<PoseError> = out.iter().map(|r| r.error).collect();
        let (delta, _) = crate::position_only::align(truth, &idx, &mut errors, None);
        for (r, e) in out.iter_mut().zip(errors) {
            r.predicted = turned_about_start(run, delta, r.predicted);
            r.error = e;
        }
    }
    out
}

/// `p` turned by `delta` about the run's start position: a position-only run's path after the start
/// rotation that lays it best on the measured positions ([`crate::position_only`]).
fn turned_about_start(run: &Run, delta: f64, p: Pose2) -> Pose2 {
    let o = run.start().pose;
    let (s, c) = delta.sin_cos();
    let (x, y) = (p.x_m - o.x_m, p.y_m - o.y_m);
    Pose2::new(o.x_m + c * x - s * y, o.y_m + s * x + c * y, p.theta_rad + delta)
}

/// The error of the predicted pose at the last ground-truth stamp (the term of the paper's Eq. 6).
pub fn end_pose_error(res: &Resolved<'_>, run: &Run) -> PoseError {
    let truth = run.truth();
    let last = truth.len() - 1;
    let mut err = PoseError::default();
    walk(
        res,
        run,
        &StepPlan::new(run, res.clock_lag_s, &[last]),
        |_, p| err = p.error_to(&truth[last].pose),
        |_, _| {},
    );
    err
}

/// The whole odometry path of the measured point, at the sample times from the first to the last
/// ground-truth stamp; for a position-only run, turned by the start rotation that lays it best on the
/// measured positions ([`crate::position_only`]).
pub fn integrate(res: &Resolved<'_>, run: &Run) -> Trajectory {
    let mut tr = integrate_from_start(res, run);
    if run.truth_position_only() {
        let idx = Selection::Path(1).indices(run.truth().len());
        let mut errors: Vec<PoseError> = residuals_unaligned(res, run, &idx);
        let (delta, _) = crate::position_only::align(run.truth(), &idx, &mut errors, None);
        tr.poses.iter_mut().for_each(|p| *p = turned_about_start(run, delta, *p));
    }
    tr
}

/// The errors of the walk at ground-truth poses `idx`, as walked.
fn residuals_unaligned(res: &Resolved<'_>, run: &Run, idx: &[usize]) -> Vec<PoseError> {
    let truth = run.truth();
    let mut out = Vec::with_capacity(idx.len());
    walk(res, run, &StepPlan::new(run, res.clock_lag_s, idx), |i, p| out.push(p.error_to(&truth[i].pose)), |_, _| {});
    out
}

/// [`integrate`] from the run's start pose as it is.
fn integrate_from_start(res: &Resolved<'_>, run: &Run) -> Trajectory {
    let mut tr = Trajectory::default();
    walk(
        res,
        run,
        &StepPlan::new(run, res.clock_lag_s, &[]),
        |_, _| {},
        |t, p| {
            tr.t_s.push(t);
            tr.poses.push(p);
        },
    );
    tr
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::RobotGeometry;
    use crate::ik::IkMatrix;
    use crate::model::{Integration, Model, StepMode};
    use crate::pose::StampedPose;
    use crate::run::RunData;
    use approx::assert_relative_eq;

    /// A run commanding a constant twist through the design forward kinematics.
    fn constant_twist_run(twist: [f64; 3], seconds: f64, dt: f64) -> Run {
        let g = RobotGeometry::apr02();
        let fwd = g.wheels_from_twist();
        let w: Vec<f64> = (0..3).map(|i| (0..3).map(|j| fwd[(i, j)] * twist[j]).sum()).collect();
        let n = (seconds / dt).round() as usize;
        let wheel_t_s: Vec<f64> = (0..=n).map(|k| k as f64 * dt).collect();
        let wheel_rad_s = wheel_t_s.iter().flat_map(|_| w.clone()).collect();
        Run::new(RunData {
            name: "const".into(),
            wheel_t_s,
            wheel_rad_s,
            n_wheels: 3,
            truth: vec![
                StampedPose { t_s: 0.0, pose: Pose2::IDENTITY },
                StampedPose { t_s: n as f64 * dt, pose: Pose2::IDENTITY },
            ],
            ..Default::default()
        })
        .unwrap()
    }

    fn design(scheme: Scheme) -> Model {
        let ik = RobotGeometry::apr02().twist_from_wheels().unwrap();
        Model::ik(ik).with_integration(Integration { step: StepMode::Fixed { dt_s: Some(0.01) }, scheme })
    }

    fn end_pose(model: &Model, run: &Run) -> Pose2 {
        let p = model.nominal();
        let res = model.resolve(&p).unwrap();
        residuals(&res, run, Selection::End)[0].predicted
    }

    #[test]
    fn rotation_in_place() {
        let run = constant_twist_run([0.0, 0.0, 0.35], 4.0, 0.01);
        for scheme in [Scheme::Euler, Scheme::ExactArc] {
            let p = end_pose(&design(scheme), &run);
            assert_relative_eq!(p.theta_rad, 0.35 * 4.0, epsilon = 1e-12);
            assert_relative_eq!(p.x_m, 0.0, epsilon = 1e-12);
            assert_relative_eq!(p.y_m, 0.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn straight_line_at_alpha() {
        let alpha = 30f64.to_radians();
        let run = constant_twist_run([0.2 * alpha.cos(), 0.2 * alpha.sin(), 0.0], 5.0, 0.01);
        let p = end_pose(&design(Scheme::Euler), &run);
        assert_relative_eq!(p.x_m, 1.0 * alpha.cos(), epsilon = 1e-12);
        assert_relative_eq!(p.y_m, 1.0 * alpha.sin(), epsilon = 1e-12);
        assert_relative_eq!(p.theta_rad, 0.0, epsilon = 1e-12);
    }

    #[test]
    fn constant_twist_follows_the_arc() {
        // Closed form: a circle of radius v/ω.
        let (v, w, t) = (0.2, 0.35, 10.0);
        let run = constant_twist_run([v, 0.0, w], t, 0.01);
        let exact = Pose2::new(v / w * (w * t).sin(), v / w * (1.0 - (w * t).cos()), w * t);
        let arc = end_pose(&design(Scheme::ExactArc), &run);
        assert_relative_eq!(arc.x_m, exact.x_m, epsilon = 1e-9);
        assert_relative_eq!(arc.y_m, exact.y_m, epsilon = 1e-9);
        let euler = end_pose(&design(Scheme::Euler), &run);
        let err = (euler.x_m - exact.x_m).hypot(euler.y_m - exact.y_m);
        // Eq. 1 uses the heading at the start of each step, on average ω·dt/2 behind: the end point is the
        // exact displacement turned by that angle, an error of |chord| × ω dt / 2 (bounded by path length ×
        // ω dt / 2 = 3.5 mm here).
        let chord = exact.x_m.hypot(exact.y_m);
        let expected = chord * w * 0.01 / 2.0;
        assert!((err - expected).abs() < 0.02 * expected, "Euler error {err} vs expected {expected}");
        assert!(err < v * t * w * 0.01 / 2.0);
    }

    #[test]
    fn queries_between_samples_interpolate() {
        let run = constant_twist_run([0.2, 0.0, 0.0], 1.0, 0.01);
        let mut d = run.into_data();
        d.truth =
            vec![StampedPose { t_s: 0.003, pose: Pose2::IDENTITY }, StampedPose { t_s: 0.5055, pose: Pose2::IDENTITY }];
        let run = Run::new(d).unwrap();
        let p = end_pose(&design(Scheme::Euler), &run);
        assert_relative_eq!(p.x_m, 0.2 * (0.5055 - 0.003), epsilon = 1e-12);
        let _ = IkMatrix::paper_design();
    }
}
