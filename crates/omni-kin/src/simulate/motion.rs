//! One simulated run on its own random stream: the controller's lag, the true body motion (wheel- and
//! twist-stage effects, exact arcs on the fine step), the encoder samples, the noisy ground truth and the
//! robot's own odometry.

use super::{Leg, SampledRun, SimConfig};
use crate::effect::WheelContext;
use crate::error::KinError;
use crate::model::{FittedModel, Resolved, Scheme};
use crate::odometry::step;
use crate::pose::{Pose2, StampedPose};
use crate::run::{Command, Run, RunData};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::PI;

/// `after` (a fine step from `before` at twist `tw` for `h` s) moved by the slip noise `q`: along and across
/// the motion (across only on a `holonomic` base) and in heading, with the variances of the step's distance
/// and turn. Three draws per step.
fn slipped(
    rng: &mut ChaCha8Rng,
    q: &crate::noise::NoiseRates,
    holonomic: bool,
    before: Pose2,
    after: Pose2,
    tw: crate::pose::Twist2,
    h: f64,
) -> Pose2 {
    let d = tw.vx_m_s.hypot(tw.vy_m_s) * h;
    let phi = tw.omega_rad_s.abs() * h;
    let along = gauss(rng, (q.trans_per_m * d + q.trans_per_rad * phi).sqrt());
    let across_var = if holonomic { q.strafe_per_m * d + q.trans_per_rad * phi } else { 0.0 };
    let across = gauss(rng, across_var.sqrt());
    let heading = gauss(rng, (q.rot_per_rad * phi + q.rot_per_m * d).sqrt());
    let (s, c) = (before.theta_rad + tw.vy_m_s.atan2(tw.vx_m_s)).sin_cos();
    Pose2::new(after.x_m + c * along - s * across, after.y_m + s * along + c * across, after.theta_rad + heading)
}

/// Zero-mean Gaussian noise of standard deviation `sigma` (one draw, always, so streams stay aligned).
fn gauss(rng: &mut ChaCha8Rng, sigma: f64) -> f64 {
    let z: f64 = StandardNormal.sample(rng);
    sigma * z
}

/// Simulate one run of `legs` in a row (their durations sum to `config.duration_s`) on random stream
/// `stream`; the run carries `label` (its command and repetition) when there is one; the true base pose
/// every `base_period_s` over [0, total] comes with it (none without).
///
/// The stages run in the order of the random stream's draws: the controller (clock and wheel speeds), the
/// wheels' start angles, the true body motion (wheel- and twist-stage effects, integration, slip), the
/// encoder samples, the ground truth, then the robot's own odometry.
pub(super) fn simulate_motion(
    config: &SimConfig,
    truth: &FittedModel,
    legs: &[Leg],
    label: Option<(Command, usize)>,
    stream: u64,
    name: String,
    base_period_s: Option<f64>,
) -> Result<SampledRun, KinError> {
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    rng.set_stream(stream);
    let res = truth.model.resolve(&truth.params)?;
    let n_w = config.design.n_wheels();
    let grid = FineGrid::new(config);
    let motor_rad_s = motor_speeds(config, &grid, &leg_targets(config, legs), n_w);
    let start_angle: Vec<f64> = (0..n_w).map(|_| rng.random_range(0.0..2.0 * PI)).collect();
    let effective = effective_speeds(&res, &grid, &motor_rad_s, &start_angle, n_w);
    let body = body_poses(config, &res, &grid, &effective, n_w, &mut rng);
    let motor_angle = motor_angles(&grid, &motor_rad_s, &start_angle, n_w);
    let motion = TrueMotion { grid, n_w, body, motor_angle };
    let encoder = encoder_samples(config, &motion, res.clock_lag_s, &mut rng);
    let truth_poses = truth_samples(config, &motion, &res.sensor_from_body, &mut rng);
    let recorded_odometry = robot_odometry(config, &encoder, n_w)?;
    let base = base_period_s.map_or_else(Vec::new, |p| motion.base_poses(p));
    let run = Run::new(RunData {
        name,
        wheel_t_s: encoder.wheel_t_s,
        wheel_rad_s: encoder.wheel_rad_s,
        n_wheels: n_w,
        truth: truth_poses,
        command: label.map(|(c, _)| c),
        repetition: label.map(|(_, r)| r as u32),
        recorded_odometry,
        wheel_start_rad: encoder.wheel_start_rad,
        truth_position_only: false,
    })?;
    Ok(SampledRun { run, base })
}

/// The fine time line of the true motion, on the true clock: the robot moves in [rest, rest + duration],
/// and the simulation runs a margin either side.
struct FineGrid {
    /// The first fine instant (the margin before the run's start). s.
    t0_s: f64,
    /// The fine step. s.
    h_s: f64,
    /// Every fine instant, `t0_s + k h_s`. s.
    t_s: Vec<f64>,
    /// The run's length on the true clock, both rests included. s.
    total_s: f64,
    /// The time simulated beyond each end of the run. s.
    margin_s: f64,
}

impl FineGrid {
    /// The grid over [-margin, total + margin] at `config.fine_step_s`.
    fn new(config: &SimConfig) -> Self {
        let total = 2.0 * config.rest_s + config.duration_s;
        let margin = 0.5;
        let h = config.fine_step_s;
        let t0 = -margin;
        let n_fine = ((total + 2.0 * margin) / h).ceil() as usize + 1;
        let t_s = (0..n_fine).map(|k| t0 + k as f64 * h).collect();
        FineGrid { t0_s: t0, h_s: h, t_s, total_s: total, margin_s: margin }
    }

    /// The number of fine instants.
    fn len(&self) -> usize {
        self.t_s.len()
    }

    /// The fine instant at or before `t` and the fraction of the way to the next one (clamped to the grid).
    fn locate(&self, t: f64) -> (usize, f64) {
        let n_fine = self.len();
        let x = ((t - self.t0_s) / self.h_s).clamp(0.0, (n_fine - 1) as f64);
        let k = (x.floor() as usize).min(n_fine - 2);
        (k, x - k as f64)
    }
}

/// One leg's wheel-speed targets and when the leg ends.
struct LegTarget {
    /// When the leg ends, since the motion started. s.
    end_s: f64,
    /// The design's wheel speeds for the leg's command, one per wheel. rad/s.
    wheel_rad_s: Vec<f64>,
}

/// Each leg's wheel-speed targets: the design's wheels from the commanded twist.
fn leg_targets(config: &SimConfig, legs: &[Leg]) -> Vec<LegTarget> {
    let n_w = config.design.n_wheels();
    let fwd = config.design.wheels_from_twist();
    let mut leg_end_s = 0.0;
    legs.iter()
        .map(|leg| {
            let c = leg.command;
            let (s, co) = c.alpha_rad.sin_cos();
            leg_end_s += leg.duration_s;
            let wheels = (0..n_w)
                .map(|i| fwd[(i, 0)] * c.v_m_s * co + fwd[(i, 1)] * c.v_m_s * s + fwd[(i, 2)] * c.omega_rad_s)
                .collect();
            LegTarget { end_s: leg_end_s, wheel_rad_s: wheels }
        })
        .collect()
}

/// The clock and wheel-speed stage: true wheel (motor) speeds on the fine grid through the first-order
/// controller (exact discretisation of the lag), `n_w` per instant. rad/s.
fn motor_speeds(config: &SimConfig, grid: &FineGrid, targets: &[LegTarget], n_w: usize) -> Vec<f64> {
    let target_at = |since_start_s: f64| -> &[f64] {
        let i = targets.iter().position(|leg| since_start_s < leg.end_s).unwrap_or(targets.len() - 1);
        &targets[i].wheel_rad_s
    };
    let alpha = 1.0 - (-grid.h_s / config.controller_tau_s).exp();
    let mut speed = vec![0.0; n_w];
    let mut motor_rad_s = vec![0.0; grid.len() * n_w];
    for (k, &t) in grid.t_s.iter().enumerate() {
        let on = t >= config.rest_s && t < config.rest_s + config.duration_s;
        let target = target_at(t - config.rest_s);
        for i in 0..n_w {
            let goal = if on { target[i] } else { 0.0 };
            speed[i] += alpha * (goal - speed[i]);
            motor_rad_s[k * n_w + i] = speed[i];
        }
    }
    motor_rad_s
}

/// The wheel stage: the true model's wheel-stage effects, in order, on the true motor speeds. rad/s.
fn effective_speeds(
    res: &Resolved<'_>,
    grid: &FineGrid,
    motor_rad_s: &[f64],
    start_angle: &[f64],
    n_w: usize,
) -> Vec<f64> {
    let mut effective = motor_rad_s.to_vec();
    if !res.wheel_effects.is_empty() {
        let dts = vec![grid.h_s; grid.len()];
        let ctx = WheelContext { n_wheels: n_w, t_s: &grid.t_s, dt_s: &dts, start_angle_rad: start_angle };
        for (e, p) in &res.wheel_effects {
            crate::effect::Effect::wheel_rates(*e, p, &ctx, &mut effective);
        }
    }
    effective
}

/// The twist and integration stages: the true body pose at each fine instant, from IK on the effective
/// speeds, the twist-stage effects, an exact arc per fine step and the slip noise (when configured).
fn body_poses(
    config: &SimConfig,
    res: &Resolved<'_>,
    grid: &FineGrid,
    effective: &[f64],
    n_w: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Pose2> {
    // A base whose wheels can push it sideways slips sideways too.
    let holonomic = res.ik.row(1).iter().any(|v| v.abs() > 1e-12);
    let h = grid.h_s;
    let mut body = vec![Pose2::IDENTITY; grid.len()];
    let mut pose = Pose2::IDENTITY;
    for (k, body_k) in body.iter_mut().enumerate() {
        // Speed held over (t_{k-1}, t_k]: pose[k] is the pose at t_k.
        if k > 0 {
            let w = &effective[k * n_w..(k + 1) * n_w];
            let mut tw = res.ik.twist(w);
            // Ground truth starts at t = 0 on the true clock.
            let at = crate::effect::TwistAt { pose, since_start_s: (grid.t_s[k] - 0.5 * h).max(0.0) };
            for (e, p) in &res.twist_effects {
                tw = crate::effect::Effect::twist_at(*e, p, tw, w, &at);
            }
            let before = pose;
            pose = step(Scheme::ExactArc, pose, tw, h);
            if let Some(q) = &config.slip_noise {
                pose = slipped(rng, q, holonomic, before, pose, tw, h);
            }
        }
        *body_k = pose;
    }
    body
}

/// Each motor's angle at each fine instant from its start angle (trapezoid on the fine grid is exact
/// enough at 1 ms), `n_w` per instant. rad.
fn motor_angles(grid: &FineGrid, motor_rad_s: &[f64], start_angle: &[f64], n_w: usize) -> Vec<f64> {
    let n_fine = grid.len();
    let mut motor_angle = vec![0.0; n_fine * n_w];
    for i in 0..n_w {
        let mut a = start_angle[i];
        for k in 0..n_fine {
            if k > 0 {
                a += motor_rad_s[k * n_w + i] * grid.h_s;
            }
            motor_angle[k * n_w + i] = a;
        }
    }
    motor_angle
}

/// The true motion on the fine grid, read at any true time by linear interpolation.
struct TrueMotion {
    /// The fine time line.
    grid: FineGrid,
    /// Wheels per instant.
    n_w: usize,
    /// The true body pose at each fine instant.
    body: Vec<Pose2>,
    /// Each motor's angle at each fine instant, `n_w` per instant. rad.
    motor_angle: Vec<f64>,
}

impl TrueMotion {
    /// The true body pose at true time `t`.
    fn body_at(&self, t: f64) -> Pose2 {
        let (k, f) = self.grid.locate(t);
        let (a, b) = (self.body[k], self.body[k + 1]);
        Pose2::new(
            a.x_m + f * (b.x_m - a.x_m),
            a.y_m + f * (b.y_m - a.y_m),
            a.theta_rad + f * (b.theta_rad - a.theta_rad),
        )
    }

    /// Motor `i`'s angle at true time `t`. rad.
    fn angle_at(&self, t: f64, i: usize) -> f64 {
        let (k, f) = self.grid.locate(t);
        let (n_w, angle) = (self.n_w, &self.motor_angle);
        angle[k * n_w + i] + f * (angle[(k + 1) * n_w + i] - angle[k * n_w + i])
    }

    /// The true base pose every `period_s` over [0, total].
    fn base_poses(&self, period_s: f64) -> Vec<StampedPose> {
        let total = self.grid.total_s;
        (0..)
            .map(|k| k as f64 * period_s)
            .take_while(|&t| t <= total + 1e-9 * period_s)
            .map(|t| StampedPose { t_s: t, pose: self.body_at(t) })
            .collect()
    }
}

/// What the wheel encoders recorded.
struct EncoderSamples {
    /// Each sample's stamp on the wheel clock (the true time plus the clock lag). s.
    wheel_t_s: Vec<f64>,
    /// The speed over each sample's interval from the counts, with noise, `n_w` per sample. rad/s.
    wheel_rad_s: Vec<f64>,
    /// Each wheel's (quantised) angle at the first fine instant. rad.
    wheel_start_rad: Vec<f64>,
    /// The nominal sample interval. s.
    dt_s: f64,
}

/// The sensor stage: encoder samples on the true clock, from just after the margin's start to the end,
/// with jitter, drops, quantisation to ticks and speed noise; stamped `lag_s` late.
fn encoder_samples(config: &SimConfig, motion: &TrueMotion, lag_s: f64, rng: &mut ChaCha8Rng) -> EncoderSamples {
    let (t0, n_w) = (motion.grid.t0_s, motion.n_w);
    let dt = 1.0 / config.wheel_rate_hz;
    let first = t0 + dt;
    let last = motion.grid.total_s + motion.grid.margin_s - dt;
    let n_nominal = ((last - first) / dt).floor() as usize + 1;
    let quantise = |a: f64| match config.ticks_per_rev {
        Some(tpr) => (a * tpr / (2.0 * PI)).floor() * 2.0 * PI / tpr,
        None => a,
    };
    let mut wheel_t_s = Vec::with_capacity(n_nominal);
    let mut wheel_rad_s = Vec::with_capacity(n_nominal * n_w);
    let mut prev_t = t0;
    let mut prev_counts: Vec<f64> = (0..n_w).map(|i| quantise(motion.angle_at(t0, i))).collect();
    let wheel_start_rad = prev_counts.clone();
    for k in 0..n_nominal {
        let nominal = first + k as f64 * dt;
        let jitter = if config.sample_jitter_s > 0.0 { rng.random_range(0.0..config.sample_jitter_s) } else { 0.0 };
        let t = nominal + jitter;
        let dropped = config.sample_drop_probability > 0.0
            && k + 1 < n_nominal
            && rng.random_range(0.0..1.0) < config.sample_drop_probability;
        if dropped {
            continue;
        }
        let counts: Vec<f64> = (0..n_w).map(|i| quantise(motion.angle_at(t, i))).collect();
        let interval = t - prev_t;
        for i in 0..n_w {
            wheel_rad_s.push((counts[i] - prev_counts[i]) / interval + gauss(rng, config.wheel_noise_rad_s));
        }
        wheel_t_s.push(t + lag_s);
        prev_t = t;
        prev_counts = counts;
    }
    EncoderSamples { wheel_t_s, wheel_rad_s, wheel_start_rad, dt_s: dt }
}

/// The ground truth: the sensor's pose at irregular intervals over [0, total], with noise.
fn truth_samples(
    config: &SimConfig,
    motion: &TrueMotion,
    sensor_from_body: &Pose2,
    rng: &mut ChaCha8Rng,
) -> Vec<StampedPose> {
    let total = motion.grid.total_s;
    let (lo, hi) = config.truth_interval_s;
    let mut times = vec![0.0];
    loop {
        let next = times[times.len() - 1] + if hi > lo { rng.random_range(lo..hi) } else { lo };
        if next >= total {
            break;
        }
        times.push(next);
    }
    if total - times[times.len() - 1] < 0.5 * lo {
        times.pop();
    }
    times.push(total);
    times
        .iter()
        .map(|&t| {
            let p = motion.body_at(t).compose(sensor_from_body);
            StampedPose {
                t_s: t,
                pose: Pose2::new(
                    p.x_m + gauss(rng, config.truth_noise_m),
                    p.y_m + gauss(rng, config.truth_noise_m),
                    p.theta_rad + gauss(rng, config.truth_noise_rad),
                ),
            }
        })
        .collect()
}

/// The robot's own odometry: the design matrix, Eq. 1 at the nominal step, from the odom origin.
fn robot_odometry(config: &SimConfig, encoder: &EncoderSamples, n_w: usize) -> Result<Vec<StampedPose>, KinError> {
    let design_ik = config.design.twist_from_wheels()?;
    let mut odom = Pose2::IDENTITY;
    Ok(encoder
        .wheel_t_s
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            let w = &encoder.wheel_rad_s[k * n_w..(k + 1) * n_w];
            odom = step(Scheme::Euler, odom, design_ik.twist(w), encoder.dt_s);
            StampedPose { t_s: t, pose: odom }
        })
        .collect())
}
