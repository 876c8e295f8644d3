//! A run: one recorded trajectory — wheel-speed samples, ground-truth poses, and what was commanded.
//!
//! A `Run` is built only through [`Run::new`], which rejects what would make the cost meaningless (NaN,
//! stamps that do not strictly increase, fewer than 2 samples or poses, wheel data that does not cover the
//! ground truth), so the hot loop never has to check. It also rejects finite values no recording can hold
//! (a corrupted or misscaled field would otherwise give a silently wrong fit): magnitudes above
//! [`MAX_T_S`], [`MAX_WHEEL_RAD_S`], [`MAX_POSITION_M`] and [`MAX_HEADING_RAD`].

use crate::error::{KinError, Sample};
use crate::pose::{Pose2, StampedPose};
use serde::{Deserialize, Serialize};

/// The motion command of a run, as in the paper's (v, α, ω): translate at `v` in direction `α` of the
/// robot frame while turning at `ω`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Command {
    /// Translational speed. m/s.
    pub v_m_s: f64,
    /// Direction of translation in the robot frame, from x towards y. rad.
    pub alpha_rad: f64,
    /// Yaw rate. rad/s.
    pub omega_rad_s: f64,
}

impl Command {
    /// A short label such as `v0.20 a30 w+0.35` (α in degrees).
    pub fn label(&self) -> String {
        format!("v{:.2} a{:.0} w{:+.2}", self.v_m_s, self.alpha_rad.to_degrees(), self.omega_rad_s)
    }
}

/// Everything needed to build a [`Run`]; checked by [`Run::new`].
#[derive(Clone, Debug, Default)]
pub struct RunData {
    /// Run name (file name or `train/run-003`), used in every message about it.
    pub name: String,
    /// Wheel-sample stamps. s.
    pub wheel_t_s: Vec<f64>,
    /// Wheel speeds, row-major: `n_samples × n_wheels`. rad/s.
    pub wheel_rad_s: Vec<f64>,
    /// Number of wheels (columns of `wheel_rad_s`).
    pub n_wheels: usize,
    /// Ground-truth poses of the measured point (the sensor), in a world frame.
    pub truth: Vec<StampedPose>,
    /// The command, when known.
    pub command: Option<Command>,
    /// Repetition index of the same command (0-based), when known.
    pub repetition: Option<u32>,
    /// The robot's own odometry as recorded (for comparison only; never ground truth).
    pub recorded_odometry: Vec<StampedPose>,
    /// Wheel angles at the first sample, one per wheel, when the log has them (JointState position). rad.
    /// Empty when unknown.
    pub wheel_start_rad: Vec<f64>,
    /// The ground truth measures positions only (UWB, GNSS, a tracker without heading): its headings are
    /// placeholders (set to 0 by [`Run::new`]), never compared, and every cost aligns the run's start heading
    /// ([`crate::position_only`]).
    pub truth_position_only: bool,
}

/// A validated run. Immutable once built; only [`Run::new`] makes one (no `Deserialize`, so nothing can
/// skip the checks).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Run {
    name: String,
    n_wheels: usize,
    wheel_t_s: Vec<f64>,
    wheel_rad_s: Vec<f64>,
    truth: Vec<StampedPose>,
    command: Option<Command>,
    repetition: Option<u32>,
    recorded_odometry: Vec<StampedPose>,
    wheel_start_rad: Vec<f64>,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    truth_position_only: bool,
    /// Median wheel-sample interval, computed once (the integrator needs it on every evaluation). s.
    median_dt_s: f64,
}

/// The largest time stamp magnitude accepted (about the year 2286 as seconds since 1970). s.
pub const MAX_T_S: f64 = 1.0e10;
/// The largest wheel speed magnitude accepted (about 95 000 rpm). rad/s.
pub const MAX_WHEEL_RAD_S: f64 = 1.0e4;
/// The largest ground-truth coordinate magnitude accepted (ten times UTM's largest northing). m.
pub const MAX_POSITION_M: f64 = 1.0e8;
/// The largest (unwrapped) heading magnitude accepted: about 160 000 turns, where float64 still resolves
/// 1e-10 rad. rad.
pub const MAX_HEADING_RAD: f64 = 1.0e6;

fn implausible(
    run: &str,
    what: Sample,
    index: usize,
    field: impl Into<String>,
    value: f64,
    limit: f64,
) -> Result<(), KinError> {
    if value.abs() > limit {
        return Err(KinError::Implausible { run: run.into(), what, index, field: field.into(), value, limit });
    }
    Ok(())
}

fn check_stamps(run: &str, what: Sample, t: impl Iterator<Item = f64>) -> Result<(), KinError> {
    let mut prev = f64::NEG_INFINITY;
    for (i, t) in t.enumerate() {
        if !t.is_finite() {
            return Err(KinError::NonFinite { run: run.into(), what, index: i, field: "t_s".into(), value: t });
        }
        implausible(run, what, i, "t_s", t, MAX_T_S)?;
        if t <= prev {
            return Err(KinError::NotIncreasing { run: run.into(), what, index: i, t_s: t, prev_s: prev });
        }
        prev = t;
    }
    Ok(())
}

impl Run {
    /// Validates and builds a run.
    ///
    /// long: a flat list of checks, each with its own error naming the run and field; read top to bottom.
    pub fn new(mut d: RunData) -> Result<Self, KinError> {
        let run = d.name.as_str();
        if d.n_wheels == 0 {
            return Err(KinError::Invalid { what: format!("run {run}"), why: "has no wheel columns".into() });
        }
        if d.wheel_rad_s.len() != d.wheel_t_s.len() * d.n_wheels {
            return Err(KinError::Shape {
                what: format!("run {run}: wheel speeds"),
                got: d.wheel_rad_s.len(),
                expected: d.wheel_t_s.len() * d.n_wheels,
            });
        }
        if d.wheel_t_s.len() < 2 {
            return Err(KinError::TooShort { run: run.into(), what: "wheel samples", got: d.wheel_t_s.len(), min: 2 });
        }
        if d.truth.len() < 2 {
            return Err(KinError::TooShort { run: run.into(), what: "ground-truth poses", got: d.truth.len(), min: 2 });
        }
        check_stamps(run, Sample::Wheel, d.wheel_t_s.iter().copied())?;
        if let Some(i) = d.wheel_rad_s.iter().position(|v| !v.is_finite()) {
            return Err(KinError::NonFinite {
                run: run.into(),
                what: Sample::Wheel,
                index: i / d.n_wheels,
                field: format!("wheel_rad_s[{}]", i % d.n_wheels),
                value: d.wheel_rad_s[i],
            });
        }
        for (i, v) in d.wheel_rad_s.iter().enumerate() {
            let field = format!("wheel_rad_s[{}]", i % d.n_wheels);
            implausible(run, Sample::Wheel, i / d.n_wheels, field, *v, MAX_WHEEL_RAD_S)?;
        }
        check_stamps(run, Sample::Truth, d.truth.iter().map(|p| p.t_s))?;
        for (i, p) in d.truth.iter().enumerate() {
            for (field, value, limit) in [
                ("x_m", p.pose.x_m, MAX_POSITION_M),
                ("y_m", p.pose.y_m, MAX_POSITION_M),
                ("theta_rad", p.pose.theta_rad, MAX_HEADING_RAD),
            ] {
                if !value.is_finite() {
                    return Err(KinError::NonFinite {
                        run: run.into(),
                        what: Sample::Truth,
                        index: i,
                        field: field.into(),
                        value,
                    });
                }
                implausible(run, Sample::Truth, i, field, value, limit)?;
            }
        }
        let (w0, w1) = (d.wheel_t_s[0], d.wheel_t_s[d.wheel_t_s.len() - 1]);
        let (g0, g1) = (d.truth[0].t_s, d.truth[d.truth.len() - 1].t_s);
        if w0 > g0 || w1 < g1 {
            return Err(KinError::Coverage {
                run: run.into(),
                wheel_start_s: w0,
                wheel_end_s: w1,
                truth_start_s: g0,
                truth_end_s: g1,
            });
        }
        if !d.wheel_start_rad.is_empty() && d.wheel_start_rad.len() != d.n_wheels {
            return Err(KinError::Shape {
                what: format!("run {run}: wheel start angles"),
                got: d.wheel_start_rad.len(),
                expected: d.n_wheels,
            });
        }
        if let Some(v) = d.wheel_start_rad.iter().find(|v| !v.is_finite()) {
            return Err(KinError::Invalid {
                what: format!("run {run}: wheel start angle"),
                why: format!("{v} is not finite"),
            });
        }
        if let Some(c) = &d.command
            && !(c.v_m_s.is_finite() && c.alpha_rad.is_finite() && c.omega_rad_s.is_finite())
        {
            return Err(KinError::Invalid {
                what: format!("run {run}: command"),
                why: "has a non-finite value".into(),
            });
        }
        let mut dts: Vec<f64> = d.wheel_t_s.windows(2).map(|w| w[1] - w[0]).collect();
        dts.sort_by(f64::total_cmp);
        let median_dt_s = dts[dts.len() / 2];
        // A run lives as long as its dataset: give back what the reader's growing buffers over-allocated
        // (up to half of a pushed `Vec`).
        d.wheel_t_s.shrink_to_fit();
        d.wheel_rad_s.shrink_to_fit();
        d.truth.shrink_to_fit();
        d.recorded_odometry.shrink_to_fit();
        if d.truth_position_only {
            d.truth.iter_mut().for_each(|p| p.pose.theta_rad = 0.0);
        }
        Ok(Self {
            median_dt_s,
            name: d.name,
            n_wheels: d.n_wheels,
            wheel_t_s: d.wheel_t_s,
            wheel_rad_s: d.wheel_rad_s,
            truth: d.truth,
            command: d.command,
            repetition: d.repetition,
            recorded_odometry: d.recorded_odometry,
            wheel_start_rad: d.wheel_start_rad,
            truth_position_only: d.truth_position_only,
        })
    }

    /// Back to plain data (to edit and re-validate).
    pub fn into_data(self) -> RunData {
        RunData {
            name: self.name,
            wheel_t_s: self.wheel_t_s,
            wheel_rad_s: self.wheel_rad_s,
            n_wheels: self.n_wheels,
            truth: self.truth,
            command: self.command,
            repetition: self.repetition,
            recorded_odometry: self.recorded_odometry,
            wheel_start_rad: self.wheel_start_rad,
            truth_position_only: self.truth_position_only,
        }
    }

    /// The same run without its recorded odometry, for callers that never read it (it takes as much
    /// memory as the wheel data).
    pub fn without_recorded_odometry(mut self) -> Self {
        self.recorded_odometry = Vec::new();
        self
    }

    /// Run name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Number of wheels.
    pub fn n_wheels(&self) -> usize {
        self.n_wheels
    }
    /// Number of wheel samples.
    pub fn n_samples(&self) -> usize {
        self.wheel_t_s.len()
    }
    /// Wheel-sample stamps. s.
    pub fn wheel_t_s(&self) -> &[f64] {
        &self.wheel_t_s
    }
    /// All wheel speeds, row-major `n_samples × n_wheels`. rad/s.
    pub fn wheel_rad_s(&self) -> &[f64] {
        &self.wheel_rad_s
    }
    /// Wheel speeds of sample `k`. rad/s.
    pub fn wheel_sample(&self, k: usize) -> &[f64] {
        &self.wheel_rad_s[k * self.n_wheels..(k + 1) * self.n_wheels]
    }
    /// Ground-truth poses.
    pub fn truth(&self) -> &[StampedPose] {
        &self.truth
    }
    /// First ground-truth pose: where odometry starts.
    pub fn start(&self) -> StampedPose {
        self.truth[0]
    }
    /// Last ground-truth pose: the reference of the paper's end-pose cost.
    pub fn end(&self) -> StampedPose {
        self.truth[self.truth.len() - 1]
    }
    /// The command, when known.
    pub fn command(&self) -> Option<Command> {
        self.command
    }
    /// Repetition index, when known.
    pub fn repetition(&self) -> Option<u32> {
        self.repetition
    }
    /// The robot's own recorded odometry (may be empty).
    pub fn recorded_odometry(&self) -> &[StampedPose] {
        &self.recorded_odometry
    }
    /// Wheel angles at the first sample (empty when unknown). rad.
    pub fn wheel_start_rad(&self) -> &[f64] {
        &self.wheel_start_rad
    }
    /// Whether the ground truth measures positions only (its headings are placeholders).
    pub fn truth_position_only(&self) -> bool {
        self.truth_position_only
    }
    /// Median wheel-sample interval. s.
    pub fn median_dt_s(&self) -> f64 {
        self.median_dt_s
    }
    /// Ground-truth path length. m.
    pub fn path_length_m(&self) -> f64 {
        self.truth.windows(2).map(|w| (w[1].pose.x_m - w[0].pose.x_m).hypot(w[1].pose.y_m - w[0].pose.y_m)).sum()
    }
    /// Duration of the ground truth. s.
    pub fn truth_duration_s(&self) -> f64 {
        self.end().t_s - self.start().t_s
    }
    /// Ground-truth pose interpolated at `t_s` (clamped to the span; heading interpolated on the shortest arc).
    pub fn truth_at(&self, t_s: f64) -> Pose2 {
        interpolate(&self.truth, t_s)
    }
}

/// Linear interpolation of a stamped pose sequence at `t_s`, clamped at the ends.
pub fn interpolate(poses: &[StampedPose], t_s: f64) -> Pose2 {
    debug_assert!(!poses.is_empty());
    let i = poses.partition_point(|p| p.t_s <= t_s);
    if i == 0 {
        return poses[0].pose;
    }
    if i >= poses.len() {
        return poses[poses.len() - 1].pose;
    }
    let (a, b) = (&poses[i - 1], &poses[i]);
    let f = (t_s - a.t_s) / (b.t_s - a.t_s);
    let dth = crate::pose::wrap_angle(b.pose.theta_rad - a.pose.theta_rad);
    Pose2::new(
        a.pose.x_m + f * (b.pose.x_m - a.pose.x_m),
        a.pose.y_m + f * (b.pose.y_m - a.pose.y_m),
        a.pose.theta_rad + f * dth,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> RunData {
        RunData {
            name: "r1".into(),
            wheel_t_s: vec![0.0, 0.01, 0.02],
            wheel_rad_s: vec![0.0; 9],
            n_wheels: 3,
            truth: vec![
                StampedPose { t_s: 0.0, pose: Pose2::IDENTITY },
                StampedPose { t_s: 0.02, pose: Pose2::IDENTITY },
            ],
            ..Default::default()
        }
    }

    #[test]
    fn accepts_valid() {
        assert!(Run::new(base()).is_ok());
    }

    #[test]
    fn messages_locate_the_problem() {
        let mut d = base();
        d.wheel_rad_s[7] = f64::NAN;
        assert_eq!(Run::new(d).unwrap_err().to_string(), "run r1: wheel sample 2 has non-finite wheel_rad_s[1] NaN");
        let mut d = base();
        d.wheel_t_s[2] = 0.01;
        assert_eq!(
            Run::new(d).unwrap_err().to_string(),
            "run r1: wheel sample 2 has time 0.01 s, not after the previous 0.01 s (stamps must strictly increase)"
        );
        let mut d = base();
        d.truth[1].t_s = 0.5;
        assert_eq!(
            Run::new(d).unwrap_err().to_string(),
            "run r1: wheel samples span 0..0.02 s but ground truth spans 0..0.5 s (wheel data must cover the ground truth)"
        );
        let mut d = base();
        d.truth.pop();
        assert_eq!(
            Run::new(d).unwrap_err().to_string(),
            "run r1: ground-truth poses has 1 entries, at least 2 are needed"
        );
    }
}
