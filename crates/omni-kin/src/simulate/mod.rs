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
//!
//! - `commands.rs`: the benchmark commands, the check that a base can perform them, and runs of several legs.
//! - `motion.rs`: one run on its random stream: controller, true motion, encoders, ground truth, noise.

mod commands;
mod motion;

pub use commands::{
    DIFF_SPEED_M_S, DIFF_TURN_RATES_RAD_S, Leg, UNREACHABLE_TOL, benchmark_commands, check_commands, diff_commands,
    figure_eight_legs, flower_commands, square_legs, unreachable_message, unreachable_twists,
};
use motion::simulate_motion;

use crate::error::{KinError, Settings};
use crate::geometry::RobotGeometry;
use crate::model::FittedModel;
use crate::pose::StampedPose;
use crate::run::{Command, Run};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

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
    /// Slip of the base that the encoders do not see: a random walk of the true motion with the variance
    /// rates of an odometry noise model ([`crate::noise::NoiseRates`]; its floor is not used: the ground
    /// truth's noise is `truth_noise_*`), drawn per fine step along, across (holonomic designs) and in
    /// heading. Default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slip_noise: Option<crate::noise::NoiseRates>,
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
            slip_noise: None,
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
        let bad = |field: &str, why: &str| {
            Err(KinError::Setting { of: Settings::Simulator, field: field.into(), why: why.into() })
        };
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
        self.design.validate_for(self.design.twist_dof())?;
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
        return Err(KinError::Setting {
            of: Settings::Simulator,
            field: "sampling period".into(),
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
    let bad = |why: &str| KinError::Setting { of: Settings::Simulator, field: "legs".into(), why: why.into() };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::{CostKind, cost};
    use crate::geometry::RobotGeometry;
    use crate::ik::IkMatrix;
    use crate::model::Model;
    use std::f64::consts::PI;

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
