//! A seeded simulator of the paper's flower benchmark, standing in for a robot.
//!
//! For each run a motion command `(v, α, ω)` is held for `duration_s` between two rests. The robot's
//! controller turns it into wheel-speed targets with the **design** forward kinematics; each wheel follows
//! its target through a first-order lag (`controller_tau_s`). The **true** robot (any [`FittedModel`]:
//! matrix or geometry plus effects) moves the body: its wheel-stage effects act on the true wheel speeds,
//! its IK matrix and twist-stage effects give the twist, and the motion is integrated with exact arcs on a
//! fine step (`fine_step_s`, 1 ms). Encoders count ticks of the motor angle (`ticks_per_rev`); the firmware
//! reports the mean speed over each sample interval (100 Hz, optionally late or dropped samples) plus
//! Gaussian noise, stamped on a clock that lags by the true model's `time_offset`. Ground truth is the
//! sensor pose (true model's `sensor_offset`) at irregular 200–300 ms intervals with SLAM-like noise.
//!
//! Every random draw comes from `ChaCha8Rng::seed_from_u64(seed)` on its own stream per run, so a dataset
//! is the same whatever the thread count.

use crate::effect::WheelContext;
use crate::error::KinError;
use crate::geometry::RobotGeometry;
use crate::model::{FittedModel, Scheme};
use crate::odometry::step;
use crate::pose::{Pose2, StampedPose};
use crate::run::{Command, Run, RunData};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The paper's 36 flower commands: v = 0.2 m/s, α = 0°, 30°, …, 330°, ω ∈ {−0.35, 0, +0.35} rad/s.
pub fn flower_commands() -> Vec<Command> {
    let mut v = Vec::with_capacity(36);
    for omega in [-0.35, 0.0, 0.35] {
        for a in 0..12 {
            v.push(Command { v_m_s: 0.2, alpha_rad: (30.0 * a as f64).to_radians(), omega_rad_s: omega });
        }
    }
    v
}

/// Forward speed of [`diff_commands`]. m/s.
pub const DIFF_SPEED_M_S: f64 = 0.2;
/// Turn rates of [`diff_commands`]' arcs. rad/s.
pub const DIFF_TURN_RATES_RAD_S: [f64; 5] = [-0.7, -0.35, 0.0, 0.35, 0.7];

/// A differential drive's benchmark: the commands it can perform (it cannot move sideways). Forward
/// (α = 0°) and backward (α = 180°) at [`DIFF_SPEED_M_S`] on arcs of each of [`DIFF_TURN_RATES_RAD_S`]
/// (straight, gentle and tight turns both ways: 10 commands), then turns on the spot at ±0.7 rad/s (2):
/// 12 commands, which excite both wheel radii (straight runs: their mean and difference) and the wheel
/// separation (turns).
pub fn diff_commands() -> Vec<Command> {
    let mut v = Vec::with_capacity(12);
    for alpha_deg in [0.0f64, 180.0] {
        for omega in DIFF_TURN_RATES_RAD_S {
            v.push(Command { v_m_s: DIFF_SPEED_M_S, alpha_rad: alpha_deg.to_radians(), omega_rad_s: omega });
        }
    }
    for omega in [0.7, -0.7] {
        v.push(Command { v_m_s: 0.0, alpha_rad: 0.0, omega_rad_s: omega });
    }
    v
}

/// The benchmark commands for a robot: the paper's 36 [`flower_commands`] for a base that drives every
/// planar twist (omni, mecanum, [`RobotGeometry::is_omnidirectional`]), [`diff_commands`] for a base that
/// cannot move sideways (a differential drive).
pub fn benchmark_commands(design: &RobotGeometry) -> Vec<Command> {
    if design.is_omnidirectional() { flower_commands() } else { diff_commands() }
}

/// The twist rank a simulated base of `n_wheels` wheels needs: 2 for two wheels (they drive at most
/// forward and turning, as a differential drive does), 3 (every planar twist) for more: a base of three or
/// more wheels that drives fewer directions is a singular layout (wheels rolling the same way), refused.
pub fn needed_rank(n_wheels: usize) -> usize {
    if n_wheels <= 2 { 2 } else { crate::geometry::PLANAR_TWIST_DIMENSIONS }
}

/// The part of each command's twist that the base `design` cannot produce, as a twist error (vx m/s, vy
/// m/s, ω rad/s): the command turned into wheel speeds and back through the design's inverse, minus the
/// command. Zero (to rounding) for every command of an omnidirectional base; a differential drive's is
/// the sideways speed `vy = v sin α` it was asked for.
pub fn unreachable_twists(design: &RobotGeometry, commands: &[Command]) -> Result<Vec<[f64; 3]>, KinError> {
    let fwd = design.wheels_from_twist();
    let ik = design.twist_from_wheels()?;
    Ok(commands
        .iter()
        .map(|c| {
            let (s, co) = c.alpha_rad.sin_cos();
            let twist = [c.v_m_s * co, c.v_m_s * s, c.omega_rad_s];
            let wheels: Vec<f64> =
                (0..design.n_wheels()).map(|i| (0..3).map(|j| fwd[(i, j)] * twist[j]).sum()).collect();
            let back = ik.twist(&wheels);
            [back.vx_m_s - twist[0], back.vy_m_s - twist[1], back.omega_rad_s - twist[2]]
        })
        .collect())
}

/// Largest twist error (m/s or rad/s) [`unreachable_twists`] tolerates: rounding, not a command.
pub const UNREACHABLE_TOL: f64 = 1e-9;

/// Checks that the base `design` can perform every command; the error names the first that it cannot
/// (`commands[i]`) and the speed it cannot produce.
pub fn check_commands(design: &RobotGeometry, commands: &[Command]) -> Result<(), KinError> {
    for (i, c) in commands.iter().enumerate() {
        for (f, v) in [("v_m_s", c.v_m_s), ("alpha_rad", c.alpha_rad), ("omega_rad_s", c.omega_rad_s)] {
            if !v.is_finite() {
                return Err(KinError::Invalid {
                    what: format!("simulator commands[{i}].{f}"),
                    why: format!("{v} is not finite"),
                });
            }
        }
    }
    let misses = unreachable_twists(design, commands)?;
    match misses.iter().position(|m| m.iter().any(|x| x.abs() > UNREACHABLE_TOL)) {
        None => Ok(()),
        Some(i) => Err(KinError::Invalid {
            what: format!("simulator commands[{i}].alpha_rad"),
            why: unreachable_message(design.n_wheels(), &commands[i], &misses[i]),
        }),
    }
}

/// Why a command `c` that misses the twist `miss` (from [`unreachable_twists`]) cannot be driven by a
/// base of `n_wheels` wheels: the command's twist and the components the base cannot produce.
pub fn unreachable_message(n_wheels: usize, c: &Command, miss: &[f64; 3]) -> String {
    let (s, co) = c.alpha_rad.sin_cos();
    let missing: Vec<String> = [("vx", "m/s"), ("vy", "m/s"), ("ω", "rad/s")]
        .iter()
        .zip(miss)
        .filter(|(_, m)| m.abs() > UNREACHABLE_TOL)
        .map(|((name, unit), m)| format!("{name} {:.4} {unit}", -m))
        .collect();
    format!(
        "α = {:.1}° asks for vx {:.4} m/s, vy {:.4} m/s, ω {:.4} rad/s, and a base with {n_wheels} wheels cannot \
         produce {} of it; a differential drive moves forward or backward (α = 0° or 180°) and turns, never \
         sideways",
        c.alpha_rad.to_degrees(),
        c.v_m_s * co,
        c.v_m_s * s,
        c.omega_rad_s,
        missing.join(", "),
    )
}

/// Simulator settings. Defaults stand in for the paper's APR-02 recordings.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SimConfig {
    /// Design geometry the robot's controller uses to turn commands into wheel targets. Default APR-02.
    pub design: RobotGeometry,
    /// Commands, each run `runs_per_command` times. Default: the 36 flower commands.
    pub commands: Vec<Command>,
    /// Repetitions of each command. Default 5 (paper).
    pub runs_per_command: usize,
    /// How long each command is held. s. Default 10.
    pub duration_s: f64,
    /// Rest before and after the motion (long enough for two ground-truth poses, which the noise-floor estimate uses). s. Default 0.4.
    pub rest_s: f64,
    /// Wheel sample rate. Hz. Default 100 (paper: 10 ms).
    pub wheel_rate_hz: f64,
    /// Time constant of the wheel-speed controllers. s. Default 0.05.
    pub controller_tau_s: f64,
    /// Encoder ticks per wheel revolution (`None`: no quantisation). Default 49152 (1024 lines × 4 × 12:1).
    pub ticks_per_rev: Option<f64>,
    /// Gaussian noise on each reported wheel speed. rad/s. Default 0.005.
    pub wheel_noise_rad_s: f64,
    /// Ground-truth intervals are uniform in this range. s. Default (0.2, 0.3) (paper's LIDAR).
    pub truth_interval_s: (f64, f64),
    /// Ground-truth position noise (per axis). m. Default 0.002.
    pub truth_noise_m: f64,
    /// Ground-truth heading noise. rad. Default 0.003 (≈ 0.17°).
    pub truth_noise_rad: f64,
    /// Step of the true motion. s. Default 0.001.
    pub fine_step_s: f64,
    /// Probability that a wheel sample is dropped (the next one then covers both intervals). Default 0.
    pub sample_drop_probability: f64,
    /// Uniform jitter of sample times (late samples). s. Default 0.
    pub sample_jitter_s: f64,
    /// Seed of every random draw.
    pub seed: u64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            design: RobotGeometry::apr02(),
            commands: flower_commands(),
            runs_per_command: 5,
            duration_s: 10.0,
            rest_s: 0.4,
            wheel_rate_hz: 100.0,
            controller_tau_s: 0.05,
            ticks_per_rev: Some(49152.0),
            wheel_noise_rad_s: 0.005,
            truth_interval_s: (0.2, 0.3),
            truth_noise_m: 0.002,
            truth_noise_rad: 0.003,
            fine_step_s: 0.001,
            sample_drop_probability: 0.0,
            sample_jitter_s: 0.0,
            seed: 0,
        }
    }
}

impl SimConfig {
    /// The defaults on the robot `design`, with its [`benchmark_commands`].
    pub fn for_robot(design: RobotGeometry) -> Self {
        Self { commands: benchmark_commands(&design), design, ..Self::default() }
    }

    /// A noise-free configuration (no quantisation, no noise): the model should then fit to integration
    /// error only.
    pub fn noise_free(mut self) -> Self {
        self.ticks_per_rev = None;
        self.wheel_noise_rad_s = 0.0;
        self.truth_noise_m = 0.0;
        self.truth_noise_rad = 0.0;
        self
    }

    fn validate(&self) -> Result<(), KinError> {
        let bad = |what: &str, why: &str| Err(KinError::Invalid { what: format!("simulator {what}"), why: why.into() });
        if self.commands.is_empty() || self.runs_per_command == 0 {
            return bad("commands", "at least one command and one repetition are needed");
        }
        if !(self.duration_s > 0.0 && self.duration_s.is_finite()) {
            return bad("duration_s", "must be > 0");
        }
        if !(self.wheel_rate_hz > 0.0 && self.fine_step_s > 0.0 && self.fine_step_s < 1.0 / self.wheel_rate_hz) {
            return bad("rates", "need wheel_rate_hz > 0 and 0 < fine_step_s < the wheel interval");
        }
        if !(self.truth_interval_s.0 > 0.0 && self.truth_interval_s.1 >= self.truth_interval_s.0) {
            return bad("truth_interval_s", "need 0 < low ≤ high");
        }
        if !(0.0..0.9).contains(&self.sample_drop_probability) {
            return bad("sample_drop_probability", "must be in [0, 0.9)");
        }
        if !(self.sample_jitter_s >= 0.0 && self.sample_jitter_s < 0.4 / self.wheel_rate_hz) {
            return bad("sample_jitter_s", "must be ≥ 0 and below 40 % of the wheel interval");
        }
        if self.controller_tau_s <= 0.0 || self.rest_s < 0.0 {
            return bad("controller_tau_s / rest_s", "need tau > 0 and rest ≥ 0");
        }
        self.design.validate_for(needed_rank(self.design.n_wheels()))?;
        check_commands(&self.design, &self.commands)
    }
}

/// Checks the settings and that `truth` drives the configured robot (its wheel count, a valid model).
fn check_truth(config: &SimConfig, truth: &FittedModel) -> Result<(), KinError> {
    config.validate()?;
    if truth.model.n_wheels() != config.design.n_wheels() {
        return Err(KinError::WheelCount {
            run: "true model".into(),
            got: truth.model.n_wheels(),
            expected: config.design.n_wheels(),
        });
    }
    truth.model.resolve(&truth.params)?;
    Ok(())
}

/// Simulate every command × repetition. Run `i` uses random stream `i` of `config.seed`. Run names are
/// `{prefix}{command index:02}-r{repetition}` and carry their command and repetition.
pub fn simulate(config: &SimConfig, truth: &FittedModel, prefix: &str) -> Result<Vec<Run>, KinError> {
    Ok(simulate_jobs(config, truth, prefix, None)?.into_iter().map(|s| s.run).collect())
}

/// A simulated run with its true base pose every `period_s` on the true clock, for simulated sensors.
#[derive(Clone, Debug)]
pub struct SampledRun {
    /// The run, exactly as [`simulate`] makes it.
    pub run: Run,
    /// The true `world_from_base` (the run's start: the identity) at t = 0, `period_s`, 2 `period_s`, …
    /// up to the end of the rest after the motion (the ground truth's span), noise-free. s, m, rad.
    pub base: Vec<StampedPose>,
}

/// [`simulate`], each run with its true base pose every `period_s` (s, > 0). The runs are the same as
/// [`simulate`]'s (sampling draws no random numbers).
pub fn simulate_sampled(
    config: &SimConfig,
    truth: &FittedModel,
    prefix: &str,
    period_s: f64,
) -> Result<Vec<SampledRun>, KinError> {
    if !(period_s > 0.0 && period_s.is_finite()) {
        return Err(KinError::Invalid {
            what: "simulator sampling period".into(),
            why: format!("{period_s} s is not > 0"),
        });
    }
    simulate_jobs(config, truth, prefix, Some(period_s))
}

fn simulate_jobs(
    config: &SimConfig,
    truth: &FittedModel,
    prefix: &str,
    period_s: Option<f64>,
) -> Result<Vec<SampledRun>, KinError> {
    check_truth(config, truth)?;
    let jobs: Vec<(usize, Command, usize)> = config
        .commands
        .iter()
        .enumerate()
        .flat_map(|(ci, c)| (0..config.runs_per_command).map(move |r| (ci, *c, r)))
        .collect();
    jobs.par_iter()
        .enumerate()
        .map(|(i, &(ci, c, rep))| {
            let legs = [Leg { command: c, duration_s: config.duration_s }];
            let name = format!("{prefix}{ci:02}-r{rep}");
            simulate_motion(config, truth, &legs, Some((c, rep)), i as u64, name, period_s)
        })
        .collect()
}

/// One leg of a run with several motions: a command held for a while.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Leg {
    /// The command.
    pub command: Command,
    /// How long it is held. s.
    pub duration_s: f64,
}

/// A square of side `side_m` driven the way a differential drive (or UMBmark) drives it: forward along a
/// side at `speed_m_s`, then a quarter turn on the spot at `omega_rad_s` (its sign: which way), four times.
/// It never translates and rotates at once.
pub fn square_legs(side_m: f64, speed_m_s: f64, omega_rad_s: f64) -> Vec<Leg> {
    let side =
        Leg { command: Command { v_m_s: speed_m_s, alpha_rad: 0.0, omega_rad_s: 0.0 }, duration_s: side_m / speed_m_s };
    let turn =
        Leg { command: Command { v_m_s: 0.0, alpha_rad: 0.0, omega_rad_s }, duration_s: 0.5 * PI / omega_rad_s.abs() };
    [side, turn].repeat(4)
}

/// A figure-eight: a full circle to the left at `speed_m_s` and `omega_rad_s`, then one to the right.
pub fn figure_eight_legs(speed_m_s: f64, omega_rad_s: f64) -> Vec<Leg> {
    let circle = 2.0 * PI / omega_rad_s.abs();
    let left = Command { v_m_s: speed_m_s, alpha_rad: 0.0, omega_rad_s: omega_rad_s.abs() };
    let right = Command { omega_rad_s: -omega_rad_s.abs(), ..left };
    vec![Leg { command: left, duration_s: circle }, Leg { command: right, duration_s: circle }]
}

/// Simulate one run whose motion is several legs in a row (a square: sides and turns on the spot; a
/// figure-eight), between two rests, on random stream `stream` of `config.seed`; `config.commands`,
/// `runs_per_command` and `duration_s` are not used. The run carries no command (like a recording).
pub fn simulate_legs(
    config: &SimConfig,
    truth: &FittedModel,
    legs: &[Leg],
    stream: u64,
    name: String,
) -> Result<Run, KinError> {
    let bad = |why: &str| KinError::Invalid { what: "simulator legs".into(), why: why.into() };
    if legs.is_empty() {
        return Err(bad("at least one leg is needed"));
    }
    if legs.iter().any(|l| !(l.duration_s > 0.0 && l.duration_s.is_finite())) {
        return Err(bad("every leg's duration_s must be finite and > 0"));
    }
    let duration_s = legs.iter().map(|l| l.duration_s).sum();
    let commands = legs.iter().map(|l| l.command).collect();
    let config = SimConfig { commands, runs_per_command: 1, duration_s, ..config.clone() };
    check_truth(&config, truth)?;
    Ok(simulate_motion(&config, truth, legs, None, stream, name, None)?.run)
}

/// Zero-mean Gaussian noise of standard deviation `sigma` (one draw, always, so streams stay aligned).
fn gauss(rng: &mut ChaCha8Rng, sigma: f64) -> f64 {
    let z: f64 = StandardNormal.sample(rng);
    sigma * z
}

/// Simulate one run on random stream `stream`: `command` held for `config.duration_s`.
pub fn simulate_run(
    config: &SimConfig,
    truth: &FittedModel,
    command: Command,
    repetition: usize,
    stream: u64,
    name: String,
) -> Result<Run, KinError> {
    let legs = [Leg { command, duration_s: config.duration_s }];
    Ok(simulate_motion(config, truth, &legs, Some((command, repetition)), stream, name, None)?.run)
}

/// Simulate one run of `legs` in a row (their durations sum to `config.duration_s`) on random stream
/// `stream`; the run carries `label` (its command and repetition) when there is one; the true base pose
/// every `base_period_s` over [0, total] comes with it (none without).
///
/// long: one fine-step loop applying every effect stage in order (clock, wheel speeds, twist, integration,
/// measurement) on shared per-step state; to split into stage helpers (issue 15 leftover).
fn simulate_motion(
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
    let fwd = config.design.wheels_from_twist();
    // Each leg's wheel-speed targets and when it ends (since the motion started). s.
    let mut leg_end_s = 0.0;
    let targets: Vec<(f64, Vec<f64>)> = legs
        .iter()
        .map(|leg| {
            let c = leg.command;
            let (s, co) = c.alpha_rad.sin_cos();
            leg_end_s += leg.duration_s;
            let wheels = (0..n_w)
                .map(|i| fwd[(i, 0)] * c.v_m_s * co + fwd[(i, 1)] * c.v_m_s * s + fwd[(i, 2)] * c.omega_rad_s)
                .collect();
            (leg_end_s, wheels)
        })
        .collect();
    let target_at = |since_start_s: f64| -> &[f64] {
        let i = targets.iter().position(|(end, _)| since_start_s < *end).unwrap_or(targets.len() - 1);
        &targets[i].1
    };

    // Time line (true clock): the robot moves in [rest, rest + duration]; we simulate a margin either side.
    let total = 2.0 * config.rest_s + config.duration_s;
    let margin = 0.5;
    let h = config.fine_step_s;
    let t0 = -margin;
    let n_fine = ((total + 2.0 * margin) / h).ceil() as usize + 1;
    let fine_t: Vec<f64> = (0..n_fine).map(|k| t0 + k as f64 * h).collect();

    // True wheel (motor) speeds through the first-order controller; exact discretisation of the lag.
    let alpha = 1.0 - (-h / config.controller_tau_s).exp();
    let mut speed = vec![0.0; n_w];
    let mut motor_rad_s = vec![0.0; n_fine * n_w];
    for (k, &t) in fine_t.iter().enumerate() {
        let on = t >= config.rest_s && t < config.rest_s + config.duration_s;
        let target = target_at(t - config.rest_s);
        for i in 0..n_w {
            let goal = if on { target[i] } else { 0.0 };
            speed[i] += alpha * (goal - speed[i]);
            motor_rad_s[k * n_w + i] = speed[i];
        }
    }
    let start_angle: Vec<f64> = (0..n_w).map(|_| rng.random_range(0.0..2.0 * PI)).collect();

    // True body motion: wheel effects on the true speeds, then IK, twist effects, exact arcs.
    let mut effective = motor_rad_s.clone();
    if !res.wheel_effects.is_empty() {
        let dts = vec![h; n_fine];
        let ctx = WheelContext { n_wheels: n_w, t_s: &fine_t, dt_s: &dts, start_angle_rad: &start_angle };
        for (e, p) in &res.wheel_effects {
            crate::effect::Effect::wheel_rates(*e, p, &ctx, &mut effective);
        }
    }
    let mut body = vec![Pose2::IDENTITY; n_fine];
    let mut pose = Pose2::IDENTITY;
    for k in 0..n_fine {
        // Speed held over (t_{k-1}, t_k]: pose[k] is the pose at t_k.
        if k > 0 {
            let w = &effective[k * n_w..(k + 1) * n_w];
            let mut tw = res.ik.twist(w);
            // Ground truth starts at t = 0 on the true clock.
            let at = crate::effect::TwistAt { pose, since_start_s: (fine_t[k] - 0.5 * h).max(0.0) };
            for (e, p) in &res.twist_effects {
                tw = crate::effect::Effect::twist_at(*e, p, tw, w, &at);
            }
            pose = step(Scheme::ExactArc, pose, tw, h);
        }
        body[k] = pose;
    }
    let body_at = |t: f64| -> Pose2 {
        let x = ((t - t0) / h).clamp(0.0, (n_fine - 1) as f64);
        let k = (x.floor() as usize).min(n_fine - 2);
        let f = x - k as f64;
        let (a, b) = (body[k], body[k + 1]);
        Pose2::new(
            a.x_m + f * (b.x_m - a.x_m),
            a.y_m + f * (b.y_m - a.y_m),
            a.theta_rad + f * (b.theta_rad - a.theta_rad),
        )
    };
    // Motor angle at any true time (trapezoid on the fine grid is exact enough at 1 ms).
    let mut motor_angle = vec![0.0; n_fine * n_w];
    for i in 0..n_w {
        let mut a = start_angle[i];
        for k in 0..n_fine {
            if k > 0 {
                a += motor_rad_s[k * n_w + i] * h;
            }
            motor_angle[k * n_w + i] = a;
        }
    }
    let angle_at = |t: f64, i: usize| -> f64 {
        let x = ((t - t0) / h).clamp(0.0, (n_fine - 1) as f64);
        let k = (x.floor() as usize).min(n_fine - 2);
        let f = x - k as f64;
        motor_angle[k * n_w + i] + f * (motor_angle[(k + 1) * n_w + i] - motor_angle[k * n_w + i])
    };

    // Encoder samples on the true clock, from just after the margin start to the end.
    let dt = 1.0 / config.wheel_rate_hz;
    let first = t0 + dt;
    let last = total + margin - dt;
    let n_nominal = ((last - first) / dt).floor() as usize + 1;
    let lag = res.clock_lag_s;
    let quantise = |a: f64| match config.ticks_per_rev {
        Some(tpr) => (a * tpr / (2.0 * PI)).floor() * 2.0 * PI / tpr,
        None => a,
    };
    let mut wheel_t_s = Vec::with_capacity(n_nominal);
    let mut wheel_rad_s = Vec::with_capacity(n_nominal * n_w);
    let mut prev_t = t0;
    let mut prev_counts: Vec<f64> = (0..n_w).map(|i| quantise(angle_at(t0, i))).collect();
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
        let counts: Vec<f64> = (0..n_w).map(|i| quantise(angle_at(t, i))).collect();
        let interval = t - prev_t;
        for i in 0..n_w {
            wheel_rad_s.push((counts[i] - prev_counts[i]) / interval + gauss(&mut rng, config.wheel_noise_rad_s));
        }
        wheel_t_s.push(t + lag);
        prev_t = t;
        prev_counts = counts;
    }

    // Ground truth: sensor pose at irregular intervals over [0, total], with noise.
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
    let truth_poses = times
        .iter()
        .map(|&t| {
            let p = body_at(t).compose(&res.sensor_from_body);
            StampedPose {
                t_s: t,
                pose: Pose2::new(
                    p.x_m + gauss(&mut rng, config.truth_noise_m),
                    p.y_m + gauss(&mut rng, config.truth_noise_m),
                    p.theta_rad + gauss(&mut rng, config.truth_noise_rad),
                ),
            }
        })
        .collect();

    // The robot's own odometry: the design matrix, Eq. 1 at the nominal step, from the odom origin.
    let design_ik = config.design.twist_from_wheels()?;
    let mut odom = Pose2::IDENTITY;
    let recorded_odometry = wheel_t_s
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            odom = step(Scheme::Euler, odom, design_ik.twist(&wheel_rad_s[k * n_w..(k + 1) * n_w]), dt);
            StampedPose { t_s: t, pose: odom }
        })
        .collect();

    let base = base_period_s.map_or_else(Vec::new, |p| {
        (0..)
            .map(|k| k as f64 * p)
            .take_while(|&t| t <= total + 1e-9 * p)
            .map(|t| StampedPose { t_s: t, pose: body_at(t) })
            .collect()
    });
    let run = Run::new(RunData {
        name,
        wheel_t_s,
        wheel_rad_s,
        n_wheels: n_w,
        truth: truth_poses,
        command: label.map(|(c, _)| c),
        repetition: label.map(|(_, r)| r as u32),
        recorded_odometry,
        wheel_start_rad,
    })?;
    Ok(SampledRun { run, base })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::{CostKind, cost};
    use crate::geometry::RobotGeometry;
    use crate::ik::IkMatrix;
    use crate::model::Model;

    fn small(seed: u64) -> SimConfig {
        let commands = flower_commands().into_iter().step_by(5).collect();
        SimConfig { commands, runs_per_command: 1, seed, ..SimConfig::default() }
    }

    #[test]
    fn noise_free_true_model_fits_to_integration_error() {
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let runs = simulate(&small(1).noise_free(), &truth, "t").unwrap();
        let c = cost(&truth.model, &truth.params, &runs, CostKind::EndPose).unwrap();
        assert!(c < 1e-3, "oracle cost on noise-free data {c}");
        let design = FittedModel::paper_design();
        let d = cost(&design.model, &design.params, &runs, CostKind::EndPose).unwrap();
        assert!(d > 0.05, "design cost {d}");
    }

    #[test]
    fn a_diff_drive_runs_its_own_benchmark_and_refuses_sideways_commands() {
        let design = RobotGeometry::diff_drive(0.033, 0.033, 0.287);
        let commands = benchmark_commands(&design);
        assert_eq!(commands, diff_commands());
        assert_eq!(commands.len(), 12);
        // Every command is forward/backward or a turn on the spot: no sideways speed.
        assert!(commands.iter().all(|c| (c.v_m_s * c.alpha_rad.sin()).abs() < 1e-15));
        assert!(unreachable_twists(&design, &commands).unwrap().iter().flatten().all(|m| m.abs() < 1e-12));
        // The true robot: right wheel 1.5 % larger than the design (its IK column 1.5 % larger).
        let ik = design.twist_from_wheels().unwrap().with_column_scaled(1, 1.015);
        assert_eq!(ik.row(1), [0.0, 0.0]);
        let truth = FittedModel::nominal(Model::ik(ik));
        let config =
            SimConfig { runs_per_command: 1, duration_s: 4.0, seed: 2, ..SimConfig::for_robot(design.clone()) };
        let runs = simulate(&config.clone().noise_free(), &truth, "d/").unwrap();
        assert_eq!(runs.len(), 12);
        let oracle = cost(&truth.model, &truth.params, &runs, CostKind::EndPose).unwrap();
        let nominal = FittedModel::nominal(Model::ik(design.twist_from_wheels().unwrap()));
        let d = cost(&nominal.model, &nominal.params, &runs, CostKind::EndPose).unwrap();
        assert!(oracle < 1e-3 && d > 20.0 * oracle, "oracle {oracle}, design {d}");
        // A sideways command is refused, naming it.
        let mut sideways = config;
        sideways.commands[3].alpha_rad = 90f64.to_radians();
        let e = simulate(&sideways, &truth, "d/").unwrap_err().to_string();
        assert_eq!(
            e,
            "simulator commands[3].alpha_rad: α = 90.0° asks for vx 0.0000 m/s, vy 0.2000 m/s, ω 0.3500 rad/s, and a \
             base with 2 wheels cannot produce vy 0.2000 m/s of it; a differential drive moves forward or backward \
             (α = 0° or 180°) and turns, never sideways"
        );
    }

    #[test]
    fn omnidirectional_bases_run_the_flower_on_any_wheel_count() {
        for n in [3, 4, 6] {
            let design = RobotGeometry::omni_regular(n, 0.05, 0.2, 0.3);
            assert_eq!(benchmark_commands(&design), flower_commands());
            assert!(unreachable_twists(&design, &flower_commands()).unwrap().iter().flatten().all(|m| m.abs() < 1e-12));
        }
    }

    #[test]
    fn a_run_of_one_leg_is_the_command_held_and_a_square_closes() {
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let cfg = small(5);
        let command = cfg.commands[2];
        let held = simulate_run(&cfg, &truth, command, 0, 3, "a".into()).unwrap();
        let leg = [Leg { command, duration_s: cfg.duration_s }];
        let one = simulate_legs(&cfg, &truth, &leg, 3, "a".into()).unwrap();
        assert_eq!(held.wheel_rad_s(), one.wheel_rad_s());
        assert_eq!(held.truth(), one.truth());
        assert_eq!((held.command(), one.command()), (Some(command), None));
        // A 1 m square (sides at 0.2 m/s, quarter turns at 0.5 rad/s) on the true robot, noise free: back at
        // the start, one turn further on.
        let quiet = SimConfig { design: RobotGeometry::apr02(), ..small(5).noise_free() };
        let truth = FittedModel::nominal(Model::ik(quiet.design.twist_from_wheels().unwrap()));
        let legs = square_legs(1.0, 0.2, 0.5);
        assert_eq!(legs.len(), 8);
        let run = simulate_legs(&quiet, &truth, &legs, 0, "square".into()).unwrap();
        let end = run.end().pose;
        // The controller's lag (50 ms) shortens each leg by a little: centimetres after four sides.
        assert!(end.x_m.hypot(end.y_m) < 0.03, "{end:?}");
        assert!((end.theta_rad - 2.0 * PI).abs() < 0.05, "{end:?}");
        let eight = simulate_legs(&quiet, &truth, &figure_eight_legs(0.2, 0.4), 0, "eight".into()).unwrap();
        assert!((eight.truth_duration_s() - (2.0 * 2.0 * PI / 0.4 + 2.0 * quiet.rest_s)).abs() < 1e-9);
        let e = simulate_legs(&quiet, &truth, &[], 0, "none".into()).unwrap_err().to_string();
        assert_eq!(e, "simulator legs: at least one leg is needed");
    }

    #[test]
    fn same_seed_same_data_different_seed_different_data() {
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let a = simulate(&small(3), &truth, "t").unwrap();
        let b = simulate(&small(3), &truth, "t").unwrap();
        let c = simulate(&small(4), &truth, "t").unwrap();
        assert_eq!(a, b);
        assert_ne!(a[0].wheel_rad_s(), c[0].wheel_rad_s());
    }
}
