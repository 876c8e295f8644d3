//! The built-in effect catalogue. Each effect documents its physics, its parameters (unit, null value,
//! bounds) and its stage. Per-wheel parameters are suffixed with the wheel letter: `a_a`, `a_b`, …

use super::{Effect, ParamSpec, Stage, TwistAt, WheelContext};
use crate::pose::{Pose2, Twist2};
use serde::{Deserialize, Serialize};

fn letter(i: usize) -> char {
    char::from(b'a' + (i % 26) as u8)
}

fn per_wheel(prefix: &str, unit: &str, n: usize, lower: f64, upper: f64) -> Vec<ParamSpec> {
    (0..n).map(|i| ParamSpec::new(format!("{prefix}_{}", letter(i)), unit, 0.0, lower, upper)).collect()
}

/// `sensor_offset`: the ground-truth sensor (a LIDAR running SLAM, a mocap marker set) is not at the
/// rotation centre. Measurement stage: measured pose = body pose ∘ (dx, dy, dyaw).
///
/// Parameters: `dx_m`, `dy_m` (m, null 0, bounds ±0.5 m) and, with `with_yaw`, `dyaw_rad` (rad, ±0.5).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SensorOffset {
    /// Also fit the sensor's yaw relative to the body.
    #[serde(default)]
    pub with_yaw: bool,
}

impl SensorOffset {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "sensor_offset";
    /// The id of the effect with a yaw parameter (`with_yaw`).
    pub const ID_YAW: &'static str = "sensor_offset_yaw";
}

impl Effect for SensorOffset {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "the ground-truth sensor is not at the rotation centre (lever arm)".into()
    }
    fn stage(&self) -> Stage {
        Stage::Measurement
    }
    fn params(&self) -> Vec<ParamSpec> {
        let mut p = vec![ParamSpec::new("dx_m", "m", 0.0, -0.5, 0.5), ParamSpec::new("dy_m", "m", 0.0, -0.5, 0.5)];
        if self.with_yaw {
            p.push(ParamSpec::new("dyaw_rad", "rad", 0.0, -0.5, 0.5));
        }
        p
    }
    fn sensor_from_body(&self, p: &[f64]) -> Pose2 {
        Pose2::new(p[0], p[1], if self.with_yaw { p[2] } else { 0.0 })
    }
}

/// `time_offset`: the wheel-encoder clock lags the ground-truth clock. Clock stage: the wheel sample
/// stamped `t` was measured at `t − τ` on the ground-truth clock.
///
/// Parameter: `tau_s` (s, null 0, bounds ±0.5 s). Invisible to the end-pose cost when the robot rests at
/// both ends of a run; the path residuals see it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TimeOffset {}

impl TimeOffset {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "time_offset";
}

impl Effect for TimeOffset {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "the wheel-encoder clock lags or leads the ground-truth clock".into()
    }
    fn stage(&self) -> Stage {
        Stage::Clock
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("tau_s", "s", 0.0, -0.5, 0.5)]
    }
    fn clock_lag_s(&self, p: &[f64]) -> f64 {
        p[0]
    }
}

/// `wheel_asymmetry`: a wheel's effective radius differs forward and backward. Wheel stage:
/// `ω' = ω (1 + a_i sign ω)`.
///
/// Parameters: `a_<wheel>` (1, null 0, bounds ±0.3), one per wheel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WheelAsymmetry {
    /// Number of wheels.
    pub n_wheels: usize,
}

impl WheelAsymmetry {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "wheel_asymmetry";
}

impl Effect for WheelAsymmetry {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "a wheel's effective radius differs forward vs backward".into()
    }
    fn stage(&self) -> Stage {
        Stage::Wheel
    }
    fn params(&self) -> Vec<ParamSpec> {
        per_wheel("a", "1", self.n_wheels, -0.3, 0.3)
    }
    fn wheel_rates_affine(&self) -> bool {
        true
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        for row in w.chunks_exact_mut(ctx.n_wheels) {
            for (v, a) in row.iter_mut().zip(p) {
                if *v != 0.0 {
                    *v *= 1.0 + a * v.signum();
                }
            }
        }
    }
}

/// `speed_scale`: the effective radius changes with wheel speed (tyre deformation). Wheel stage:
/// `ω' = ω (1 + k_i |ω|)`.
///
/// Parameters: `k_<wheel>` (s/rad, null 0, bounds ±0.2), one per wheel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpeedScale {
    /// Number of wheels.
    pub n_wheels: usize,
}

impl SpeedScale {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "speed_scale";
}

impl Effect for SpeedScale {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "the effective wheel radius changes with wheel speed (tyre deformation)".into()
    }
    fn stage(&self) -> Stage {
        Stage::Wheel
    }
    fn params(&self) -> Vec<ParamSpec> {
        per_wheel("k", "s/rad", self.n_wheels, -0.2, 0.2)
    }
    fn wheel_rates_affine(&self) -> bool {
        true
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        for row in w.chunks_exact_mut(ctx.n_wheels) {
            for (v, k) in row.iter_mut().zip(p) {
                *v *= 1.0 + k * v.abs();
            }
        }
    }
}

/// `rotation_slip`: slip coupled to rotating while translating. Twist stage: the translation is turned
/// by the angle `k ω`: `(vx, vy) ← R(k ω) (vx, vy)`.
///
/// Parameter: `k_s` (s, null 0, bounds ±0.5).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RotationSlip {}

impl RotationSlip {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "rotation_slip";
}

impl Effect for RotationSlip {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "slip coupled to rotating while translating turns the translation by k·ω".into()
    }
    fn stage(&self) -> Stage {
        Stage::Twist
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("k_s", "s", 0.0, -0.5, 0.5)]
    }
    fn twist(&self, p: &[f64], t: Twist2, _w: &[f64]) -> Twist2 {
        if p[0] == 0.0 {
            return t;
        }
        let (s, c) = (p[0] * t.omega_rad_s).sin_cos();
        Twist2 { vx_m_s: c * t.vx_m_s - s * t.vy_m_s, vy_m_s: s * t.vx_m_s + c * t.vy_m_s, omega_rad_s: t.omega_rad_s }
    }
}

/// `turn_scrub`: the turn rate depends on how fast the robot translates meanwhile — tyres (or rollers)
/// scrub and slip sideways when the robot turns while it drives, so it turns less (or more) than its wheels
/// say, and more so the faster it drives; on the spot or driving straight nothing changes. Twist stage:
/// `ω ← ω (1 + k |v|)`, `|v| = hypot(vx, vy)`. Runs that never translate and rotate at once (squares:
/// sides, then turns on the spot) cannot see it.
///
/// Parameter: `k_s_m` (s/m, null 0, bounds ±1: at 0.2 m/s, ±20 % of the turn rate).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TurnScrub {}

impl TurnScrub {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "turn_scrub";
}

impl Effect for TurnScrub {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "tyre scrub while turning and driving at once scales the turn rate by 1 + k·|v|".into()
    }
    fn stage(&self) -> Stage {
        Stage::Twist
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("k_s_m", "s/m", 0.0, -1.0, 1.0)]
    }
    fn twist(&self, p: &[f64], t: Twist2, _w: &[f64]) -> Twist2 {
        if p[0] == 0.0 {
            return t;
        }
        Twist2 { omega_rad_s: t.omega_rad_s * (1.0 + p[0] * t.vx_m_s.hypot(t.vy_m_s)), ..t }
    }
}

/// Window of the moving average that `accel_slip` differentiates. s.
pub const ACCEL_SLIP_WINDOW_S: f64 = 0.05;
/// Acceleration below which tyres keep traction (`accel_slip`). rad/s².
pub const ACCEL_SLIP_THRESHOLD_RAD_S2: f64 = 2.0;

/// `accel_slip`: traction is lost while a wheel speeds up faster than tyre friction allows. Wheel stage:
/// with `ā` the rate of increase of `|ω|` (moving average over 50 ms, differentiated),
/// `ω' = ω − k_i sign(ω) max(0, ā − 2 rad/s²)`.
///
/// Parameters: `k_<wheel>` (s, null 0, bounds ±0.2), one per wheel. The friction threshold (2 rad/s²) and
/// the window keep encoder noise from counting as acceleration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AccelSlip {
    /// Number of wheels.
    pub n_wheels: usize,
}

impl AccelSlip {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "accel_slip";
}

impl Effect for AccelSlip {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "traction lost while a wheel accelerates".into()
    }
    fn stage(&self) -> Stage {
        Stage::Wheel
    }
    fn params(&self) -> Vec<ParamSpec> {
        per_wheel("k", "s", self.n_wheels, -0.2, 0.2)
    }
    fn wheel_rates_affine(&self) -> bool {
        true
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        let n = ctx.n_wheels;
        let samples = ctx.t_s.len();
        for (i, &k) in p.iter().enumerate().take(n) {
            if k == 0.0 {
                continue;
            }
            // Moving average of |ω| over the trailing window, by time (running sums, O(n)).
            let mut start = 0;
            let mut sum = 0.0;
            let mut prev_avg = None;
            let orig: Vec<f64> = (0..samples).map(|s| w[s * n + i]).collect();
            for s in 0..samples {
                sum += orig[s].abs();
                while ctx.t_s[s] - ctx.t_s[start] >= ACCEL_SLIP_WINDOW_S - 1e-9 && start < s {
                    sum -= orig[start].abs();
                    start += 1;
                }
                let avg = sum / (s - start + 1) as f64;
                if let Some(prev) = prev_avg {
                    let acc = (avg - prev) / ctx.dt_s[s];
                    if acc > ACCEL_SLIP_THRESHOLD_RAD_S2 {
                        w[s * n + i] = orig[s] - k * orig[s].signum() * (acc - ACCEL_SLIP_THRESHOLD_RAD_S2);
                    }
                }
                prev_avg = Some(avg);
            }
        }
    }
}

/// `backlash`: lost motion after a wheel reverses. Wheel stage: the wheel angle follows the encoder angle
/// through a dead band of width `b_i` (a play operator starting centred), and `ω'` is the wheel angle's
/// rate.
///
/// Parameters: `b_<wheel>` (rad, null 0, bounds 0 … 0.5), one per wheel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Backlash {
    /// Number of wheels.
    pub n_wheels: usize,
}

impl Backlash {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "backlash";
}

impl Effect for Backlash {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "lost motion after a wheel reverses (gear play)".into()
    }
    fn stage(&self) -> Stage {
        Stage::Wheel
    }
    fn params(&self) -> Vec<ParamSpec> {
        per_wheel("b", "rad", self.n_wheels, 0.0, 0.5)
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        let n = ctx.n_wheels;
        for (i, &b) in p.iter().enumerate().take(n) {
            if b == 0.0 {
                continue;
            }
            let half = 0.5 * b.abs();
            let (mut motor, mut wheel) = (0.0f64, 0.0f64);
            for s in 0..ctx.t_s.len() {
                let h = ctx.dt_s[s];
                motor += w[s * n + i] * h;
                let next = wheel.clamp(motor - half, motor + half);
                w[s * n + i] = (next - wheel) / h;
                wheel = next;
            }
        }
    }
}

/// `wheel_eccentricity`: an out-of-round wheel whose radius varies with its angle φ. Wheel stage:
/// `ω' = ω (1 + c_i cos φ + s_i sin φ)`, amplitude `hypot(c_i, s_i)` and phase `atan2(s_i, c_i)`; φ starts
/// at the run's recorded wheel angle (0 when unknown) and follows the integrated wheel speed.
///
/// Parameters: `c_<wheel>`, `s_<wheel>` (1, null 0, bounds ±0.2), two per wheel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WheelEccentricity {
    /// Number of wheels.
    pub n_wheels: usize,
}

impl WheelEccentricity {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "wheel_eccentricity";
}

impl Effect for WheelEccentricity {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "an out-of-round wheel: its radius varies with the wheel's angle".into()
    }
    fn stage(&self) -> Stage {
        Stage::Wheel
    }
    fn params(&self) -> Vec<ParamSpec> {
        let mut v = per_wheel("c", "1", self.n_wheels, -0.2, 0.2);
        v.extend(per_wheel("s", "1", self.n_wheels, -0.2, 0.2));
        v
    }
    fn wheel_rates_affine(&self) -> bool {
        true
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        let n = ctx.n_wheels;
        for i in 0..n {
            let (c, s) = (p[i], p[n + i]);
            if c == 0.0 && s == 0.0 {
                continue;
            }
            let mut phi = ctx.start_angle_rad.get(i).copied().unwrap_or(0.0);
            for k in 0..ctx.t_s.len() {
                let v = w[k * n + i];
                let h = ctx.dt_s[k];
                // Angle at the middle of the step.
                let mid = phi + 0.5 * v * h;
                let (sn, cs) = mid.sin_cos();
                w[k * n + i] = v * (1.0 + c * cs + s * sn);
                phi += v * h;
            }
        }
    }
}

/// `world_drift`: a constant velocity in the world frame while the robot moves — a tilted floor the robot
/// creeps down, or a ground-truth frame that moves (a mocap or SLAM map drifting). Twist stage, with the
/// heading ψ at the start of each step ([`Effect::twist_at`]): while the robot moves ([`super::moving`]:
/// the body twist from the wheels faster than 5 mm/s or 0.02 rad/s; the measured wheel speeds in the
/// odometry, the true ones in the simulator), the world-frame velocity `(drift_x, drift_y)` is turned into
/// the body frame and added to the body twist: `(vx, vy) += R(−ψ) (drift_x, drift_y)`. At rest it does
/// nothing.
///
/// Parameters: `drift_x_m_s`, `drift_y_m_s` (m/s, world frame, null 0, bounds ±0.1).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorldDrift {}

impl WorldDrift {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "world_drift";
}

impl Effect for WorldDrift {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "a constant world-frame drift while moving (a tilted floor, or a moving ground-truth frame)".into()
    }
    fn stage(&self) -> Stage {
        Stage::Twist
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("drift_x_m_s", "m/s", 0.0, -0.1, 0.1), ParamSpec::new("drift_y_m_s", "m/s", 0.0, -0.1, 0.1)]
    }
    fn twist(&self, p: &[f64], t: Twist2, w: &[f64]) -> Twist2 {
        self.twist_at(p, t, w, &TwistAt::default())
    }
    fn twist_at(&self, p: &[f64], t: Twist2, _w: &[f64], at: &TwistAt) -> Twist2 {
        if (p[0] == 0.0 && p[1] == 0.0) || !super::moving(&t) {
            return t;
        }
        let (s, c) = at.pose.theta_rad.sin_cos();
        Twist2 { vx_m_s: t.vx_m_s + c * p[0] + s * p[1], vy_m_s: t.vy_m_s - s * p[0] + c * p[1], ..t }
    }
}

/// `sample_timing`: late or dropped encoder samples. Integration stage: each sample is integrated over its
/// measured interval instead of the fixed nominal step. No parameters.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SampleTiming {}

impl SampleTiming {
    /// Its id in model files, the CLI and Python: the one place it is spelt.
    pub const ID: &'static str = "sample_timing";
}

impl Effect for SampleTiming {
    fn id(&self) -> &str {
        Self::ID
    }
    fn describe(&self) -> String {
        "late or dropped encoder samples: integrate with measured stamps instead of a fixed step".into()
    }
    fn stage(&self) -> Stage {
        Stage::Integration
    }
    fn params(&self) -> Vec<ParamSpec> {
        Vec::new()
    }
    fn uses_stamps(&self) -> bool {
        true
    }
}
