//! `omnical simulate`: write a flower-benchmark dataset from a true robot with optional hidden effects.

use super::{OutputArgs, sim_spec};
use crate::api::simulate::{Imu, Lidar, mount_from_text, simulate_split, write_robot, write_split};
use crate::cli::effect_help;
use crate::lidar::{LidarModel, ScanSettings};
use crate::out_path::{Inputs, OutDir};
use crate::robot_file::{self, RobotFile};
use crate::{atomic, dataset, design, model_file};
use anyhow::{Context, bail};
use omni_kin::cost::{self, CostKind};
use omni_kin::simulate::SimConfig;
use omni_kin::{FittedModel, IkMatrix, Model, Pose2, RobotGeometry, Run};
use serde_json::json;
use std::path::{Path, PathBuf};

pub use crate::api::simulate::{Format, SIM_EPOCH_S};

/// Seed of the training split (validation: seed + 1), here and in `demo`.
pub const DEFAULT_SEED: u64 = 7;

/// Arguments of `omnical simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder: writes train/, validation/, truth.json and truth_model.toml. A folder that already
    /// holds files is refused (runs left from before would mix with the new ones) unless --force.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace an --out folder that already holds files, whole (the new folder is written beside it and
    /// renamed into place at the end).
    #[arg(long)]
    pub force: bool,
    /// Seed (training uses it, validation seed + 1).
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub seed: u64,
    /// Repetitions of each command, in each split (train and validation). Default: 5 on the robot's
    /// benchmark; 1 with --commands, whose repetitions column already says how many runs of each command
    /// (`plan --runs 12` then `simulate --commands` gives 12 runs in each split).
    #[arg(long)]
    pub runs_per_command: Option<usize>,
    /// Duration of each command (s).
    #[arg(long = "duration", value_name = "DURATION", default_value_t = SimConfig::default().duration_s)]
    pub duration_s: f64,
    /// Inject an effect into the true robot: NAME=V1,V2,… in the effect's parameter order
    /// (`sample_timing=DROP_PROBABILITY,JITTER_S`); one wheel's: NAME:WHEEL=V (WHEEL: its letter a, b, …
    /// or joint name). The true base: wheel_radius:WHEEL=E (radius 1 + E times the design's),
    /// wheel_separation=E (a diff base's axle), icr_shift=DYL,DYR,DX (a skid-steer base's centres of
    /// rotation moved, m). Repeatable.
    #[arg(long = "effect", value_name = "NAME[:WHEEL]=VALUES", help = effect_help(
        "Inject an effect into the true robot: NAME=V1,V2,… in the effect's parameter order \
         (sample_timing=DROP_PROBABILITY,JITTER_S); one wheel's: NAME:WHEEL=V (WHEEL: its letter a, b, … or \
         joint name). The true base: wheel_radius:WHEEL=E (radius 1 + E times the design's), wheel_separation=E \
         (a diff base's axle), icr_shift=DYL,DYR,DX (a skid-steer base's centres of rotation moved, m). Repeatable."
    ))]
    pub effects: Vec<String>,
    /// Commands to simulate, a `plan --out` CSV (v_m_s,alpha_deg,omega_rad_s,repetitions), instead of the
    /// robot's benchmark (the paper's 36 flower commands; a diff base's 12 forward/backward arcs and turns
    /// on the spot).
    #[arg(long, value_name = "CSV")]
    pub commands: Option<PathBuf>,
    /// True robot: `paper` (Eq. 9, APR-02 only), `design` (the robot's design) or a model file. Default:
    /// `paper` on APR-02, `design` on any other robot.
    #[arg(long)]
    pub truth: Option<String>,
    /// The robot: its design drives the simulated controller and is written as robot.toml beside the
    /// runs. Default: `apr02`, the paper's robot.
    #[arg(long, value_name = "FILE|apr02", default_value = robot_file::BUILTIN_APR02)]
    pub robot: String,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Mcap)]
    pub format: Format,
    /// No encoder quantisation and no noise.
    #[arg(long)]
    pub noise_free: bool,
    /// Write a simulated fleet of N robots instead (`OUT/<robot>/<session>/`, spread geometry, a wearing wheel
    /// and a growing clock lag, OUT/truth.json): the Python wheel's `omnical` only.
    #[arg(long, value_name = "N")]
    pub fleet: Option<usize>,
    /// With --fleet: sessions per robot.
    #[arg(long, value_name = "S", requires = "fleet")]
    pub sessions: Option<usize>,
    /// The simulated lidar.
    #[command(flatten)]
    pub lidar: LidarArgs,
    /// The simulated IMU.
    #[command(flatten)]
    pub imu: ImuArgs,
    /// Output options (JSON: what was written, with the design's and the true robot's costs).
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The simulated 2D lidar (`--lidar`); defaults from [`ScanSettings::default`].
#[derive(Debug, clap::Args)]
#[command(next_help_heading = "Simulated lidar")]
pub struct LidarArgs {
    /// Simulate a 2D lidar in ROOM and write its scans (/scan, sensor_msgs/msg/LaserScan, frame laser) and
    /// its mount (/tf_static base_link → laser) into every MCAP run. ROOM: `room` (10 × 8 m with boxes and
    /// pillars), `corridor` (40 × 5 m: constrains no motion along it) or a room file (TOML polygons,
    /// docs/formats.md). Every run starts at the room's origin heading +x; a run that comes within 0.25 m of
    /// a wall is refused.
    #[arg(long, value_name = "ROOM")]
    pub lidar: Option<String>,
    /// The lidar's pose on the robot, in the base frame: X,Y in metres, YAW in degrees.
    #[arg(long, value_name = "X,Y,YAW_DEG", default_value = "0,0,0", requires = "lidar")]
    pub lidar_mount: String,
    /// The mount the recordings' /tf_static states: X,Y,YAW_DEG as a rough URDF would give it, or `none`
    /// for no /tf_static (a robot without a description). Default: the true mount (--lidar-mount).
    #[arg(long, value_name = "X,Y,YAW_DEG|none", requires = "lidar")]
    pub lidar_tf: Option<String>,
    /// The kind of lidar: `ideal` (the settings below), or one made as a real lidar's scans come out:
    /// `urg04lx` (a Hokuyo URG-04LX: 682 beams over 240° at 10 Hz, 5.6 m, noise growing with range, about
    /// half the beams empty in bursts, on dark walls and at grazing angles, mixed pixels at edges, 0 for no
    /// return, a 0.1 s sweep) or `rplidar` (a Slamtec RPLidar A2: 720 beams over 360°, 12 m, the same
    /// kinds of faults, +inf for no return). A real kind sets every setting below itself.
    #[arg(
        long,
        value_name = "KIND",
        default_value = "ideal",
        value_parser = crate::cli::choice::<LidarModel>(),
        requires = "lidar",
        conflicts_with_all = ["lidar_rate", "lidar_beams", "lidar_fov", "lidar_max_range", "lidar_noise", "lidar_dropout", "lidar_sweep"]
    )]
    pub lidar_model: LidarModel,
    /// Scans per second (Hz).
    #[arg(long, value_name = "HZ", default_value_t = ScanSettings::default().rate_hz, requires = "lidar")]
    pub lidar_rate: f64,
    /// Beams per scan, evenly over the field of view (--lidar-fov).
    #[arg(long, value_name = "N", default_value_t = ScanSettings::default().beams, requires = "lidar")]
    pub lidar_beams: usize,
    /// Field of view (degrees), centred on the lidar's x axis: 360 all round (beams from −180°), or less
    /// (270: a Hokuyo's, beams from −135° to +135° inclusive).
    #[arg(long, value_name = "DEG", default_value_t = ScanSettings::default().fov_rad.to_degrees(), requires = "lidar")]
    pub lidar_fov: f64,
    /// Longest range (m): farther walls give no return (+inf).
    #[arg(long, value_name = "M", default_value_t = ScanSettings::default().range_max_m, requires = "lidar")]
    pub lidar_max_range: f64,
    /// Gaussian range noise (m).
    #[arg(long, value_name = "M", default_value_t = ScanSettings::default().range_noise_m, requires = "lidar")]
    pub lidar_noise: f64,
    /// Share of beams that return nothing (NaN), at random.
    #[arg(long, value_name = "SHARE", default_value_t = ScanSettings::default().dropout, requires = "lidar")]
    pub lidar_dropout: f64,
    /// Measure each scan's beams one after another over its period, as a spinning lidar does
    /// (LaserScan time_increment: the period over the beams of a full turn): a turning robot bends its scans, and readers
    /// de-skew them. Default: each scan at one instant.
    #[arg(long, requires = "lidar")]
    pub lidar_sweep: bool,
}

/// The simulated IMU (`--imu`): a gyro on the base, upright unless `--imu-mount` says otherwise.
#[derive(Debug, clap::Args)]
#[command(next_help_heading = "Simulated IMU")]
pub struct ImuArgs {
    /// Write an IMU's angular velocity (/imu, sensor_msgs/msg/Imu, frame imu_link: the base's true turn
    /// rate plus the bias and noise below, in the IMU's frame) and its mount (/tf_static base_link →
    /// imu_link) into every MCAP run.
    #[arg(long)]
    pub imu: bool,
    /// IMU messages per second (Hz).
    #[arg(long, value_name = "HZ", default_value_t = 100.0, requires = "imu")]
    pub imu_rate: f64,
    /// The gyro's bias (rad/s).
    #[arg(long, value_name = "RAD_S", default_value_t = 0.005, requires = "imu", allow_hyphen_values = true)]
    pub imu_bias: f64,
    /// Gaussian noise of each yaw-rate sample (rad/s).
    #[arg(long, value_name = "RAD_S", default_value_t = 0.002, requires = "imu")]
    pub imu_noise: f64,
    /// How the IMU sits on the base: ROLL,PITCH,YAW in degrees (URDF's rpy: 180,0,0 upside down, 90,0,0 on
    /// its side).
    #[arg(
        long,
        value_name = "ROLL,PITCH,YAW_DEG",
        default_value = "0,0,0",
        requires = "imu",
        allow_hyphen_values = true
    )]
    pub imu_mount: String,
    /// The mount the recordings' /tf_static states: ROLL,PITCH,YAW_DEG, or `none` for no /tf_static (a
    /// robot without a description). Default: the true mount (--imu-mount).
    #[arg(long, value_name = "ROLL,PITCH,YAW_DEG|none", requires = "imu", allow_hyphen_values = true)]
    pub imu_tf: Option<String>,
}

impl ImuArgs {
    /// The checked settings (`None` without `--imu`).
    fn settings(&self, format: Format) -> anyhow::Result<Option<Imu>> {
        if !self.imu {
            return Ok(None);
        }
        if format != Format::Mcap {
            bail!("--imu writes Imu messages into ROS 2 bags: use --format mcap (the default)");
        }
        let mount = imu_mount_arg(&self.imu_mount, "--imu-mount")?;
        let stated = match self.imu_tf.as_deref() {
            None => Some(mount),
            Some("none") => None,
            Some(tf) => Some(imu_mount_arg(tf, "--imu-tf")?),
        };
        let imu = Imu { rate_hz: self.imu_rate, bias_rad_s: self.imu_bias, noise_rad_s: self.imu_noise, mount, stated };
        Ok(Some(imu.checked()?))
    }
}

/// `ROLL,PITCH,YAW_DEG` (degrees) of option `flag` as an IMU mount.
fn imu_mount_arg(text: &str, flag: &str) -> anyhow::Result<omni_kin::gyro::ImuMount> {
    crate::api::imu::mount_from_text(text).with_context(|| {
        format!("{flag} {text:?}: expected ROLL,PITCH,YAW_DEG (three numbers in degrees, e.g. 180,0,0)")
    })
}

/// `X,Y,YAW_DEG` (m, m, degrees) of option `flag` as a pose.
fn mount_arg(text: &str, flag: &str) -> anyhow::Result<Pose2> {
    mount_from_text(text)
        .with_context(|| format!("{flag} {text:?}: expected X,Y,YAW_DEG (three numbers, e.g. 0.2,0,5)"))
}

impl LidarArgs {
    /// The lidar these arguments ask for (`None` without `--lidar`).
    fn lidar(&self, format: Format) -> anyhow::Result<Option<Lidar>> {
        let Some(name) = &self.lidar else { return Ok(None) };
        if format != Format::Mcap {
            bail!("--lidar writes LaserScan messages into ROS 2 bags: use --format mcap (the default)");
        }
        let base_from_sensor = mount_arg(&self.lidar_mount, "--lidar-mount")?;
        let stated = match self.lidar_tf.as_deref() {
            None => Some(base_from_sensor),
            Some("none") => None,
            Some(tf) => Some(mount_arg(tf, "--lidar-tf")?),
        };
        let settings = match self.lidar_model {
            LidarModel::Ideal => ScanSettings {
                rate_hz: self.lidar_rate,
                beams: self.lidar_beams,
                fov_rad: self.lidar_fov.to_radians(),
                range_max_m: self.lidar_max_range,
                range_noise_m: self.lidar_noise,
                dropout: self.lidar_dropout,
                sweeping: self.lidar_sweep,
                ..ScanSettings::default()
            },
            real => ScanSettings::of_model(real),
        };
        Ok(Some(Lidar::new(name, base_from_sensor, stated, settings)?))
    }
}

/// The simulated robot's design (from `--robot`) and its true model (from `--truth`).
fn design_and_truth(a: &Args) -> anyhow::Result<(RobotFile, RobotGeometry, FittedModel, FittedModel)> {
    let robot = robot_file::from_arg(&a.robot).context("--robot")?;
    let geometry = robot.description.to_geometry().with_context(|| format!("--robot {}", robot.source))?;
    let design_ik = robot.description.design_ik().with_context(|| format!("--robot {}", robot.source))?;
    let design = FittedModel::nominal(Model::ik(design_ik.clone()));
    // Default: the paper's calibration on APR-02, the design itself on any other robot.
    let default = if design_ik == IkMatrix::paper_design() { "paper" } else { "design" };
    let truth = match a.truth.as_deref().unwrap_or(default) {
        "paper" if design_ik != IkMatrix::paper_design() => bail!(
            "--truth paper is the paper's Eq. 9, a calibration of APR-02, and --robot {} is another robot: give \
             --truth design (the design itself) or --truth FILE (a model file)",
            robot.source
        ),
        "paper" => design::paper_calibrated(),
        "design" => design.clone(),
        path => model_file::read(Path::new(path)).context("reading --truth")?,
    };
    let joints = robot.description.joints();
    if truth.model.n_wheels() != joints.len() {
        bail!(
            "--truth has {} wheels and --robot {} has {} ({})",
            truth.model.n_wheels(),
            robot.source,
            joints.len(),
            joints.join(", ")
        );
    }
    Ok((robot, geometry, design, truth))
}

/// The design's and the true robot's costs on `runs`: `design_end_pose`, `oracle_end_pose`, `design_path`,
/// `oracle_path` (Eq. 6; path RMS, m), in that order.
fn split_costs(design: &FittedModel, truth: &FittedModel, runs: &[Run]) -> anyhow::Result<Vec<(String, f64)>> {
    [CostKind::EndPose, CostKind::PATH]
        .iter()
        .flat_map(|&k| {
            let d = cost::cost(&design.model, &design.params, runs, k);
            let o = cost::cost(&truth.model, &truth.params, runs, k);
            [(format!("design_{}", k.name()), d), (format!("oracle_{}", k.name()), o)]
        })
        .map(|(n, c)| c.map(|c| (n, c)).map_err(anyhow::Error::from))
        .collect()
}

/// The files `simulate` reads: the robot, the commands, the true robot's model file and the room file (the
/// built-in names left out), which no `--out` may hold.
fn inputs(a: &Args) -> Inputs {
    let named = |v: Option<&str>, builtin: &[&str]| v.filter(|v| !builtin.contains(v)).map(PathBuf::from);
    Inputs::new()
        .with_some("--robot", named(Some(a.robot.as_str()), &[robot_file::BUILTIN_APR02]))
        .with_some("--commands", a.commands.as_ref())
        .with_some("--truth", named(a.truth.as_deref(), &["paper", "design"]))
        .with_some("--lidar", named(a.lidar.lidar.as_deref(), &["room", "corridor"]))
}

/// Runs `omnical simulate`; `quiet` hides the progress display.
pub fn run(a: &Args, quiet: bool) -> anyhow::Result<()> {
    if a.fleet.is_some() {
        return Err(super::python_only("omnical simulate --fleet"));
    }
    let (robot, geometry, design, mut truth) = design_and_truth(a)?;
    let wheel_names = robot.description.joints();
    let commands = match &a.commands {
        Some(path) => sim_spec::read_commands(path, &geometry)?,
        None => omni_kin::simulate::benchmark_commands(&geometry),
    };
    let mut config = SimConfig {
        design: geometry,
        commands,
        runs_per_command: a.runs_per_command_or_default(),
        duration_s: a.duration_s,
        ..SimConfig::default()
    };
    if a.noise_free {
        config = config.noise_free();
    }
    for spec in &a.effects {
        sim_spec::apply_effect_spec(spec, &mut truth, &mut config, &wheel_names)?;
    }
    let lidar = a.lidar.lidar(a.format)?;
    let imu = a.imu.settings(a.format)?;
    let out = OutDir::claim(&a.out, "--out", a.force, &inputs(a))?;
    if let (Some(path), false) = (&a.commands, a.output.json) {
        println!("{}", commands_line(path, &config));
    }
    let (mut summary, mut written) = (serde_json::Map::new(), serde_json::Map::new());
    for (split, seed) in [("train", a.seed), ("validation", a.seed.wrapping_add(1))] {
        let cfg = SimConfig { seed, ..config.clone() };
        let spinner = crate::progress::spinner(format!("simulating and writing {split} runs"), quiet);
        let (runs, sensors) = simulate_split(&cfg, &truth, &format!("{split}/"), lidar.as_ref(), imu.as_ref())?;
        let files = write_split(&out.path().join(split), &runs, a.format, &wheel_names, sensors.as_sensors())?;
        write_robot(&out.path().join(split), &robot, a.format)?;
        spinner.finish_and_clear();
        let costs = split_costs(&design, &truth, &runs)?;
        let entry: serde_json::Map<String, serde_json::Value> = costs
            .iter()
            .map(|(n, c)| (n.clone(), json!(c)))
            .chain([("seed".to_string(), json!(seed)), ("runs".to_string(), json!(runs.len()))])
            .collect();
        // The summary prints whatever --quiet says (it only hides progress).
        if !a.output.json {
            println!(
                "{split}: {}, design cost {:.4}, oracle cost {:.4} (Eq. 6; path: {:.4} vs {:.4})",
                crate::units::count(runs.len(), "run"),
                costs[0].1,
                costs[1].1,
                costs[2].1,
                costs[3].1
            );
        }
        let mut listed = entry.clone();
        listed.insert("dir".into(), json!(a.out.join(split)));
        listed.insert("files".into(), json!(files.iter().map(|f| out.shown(f)).collect::<Vec<_>>()));
        listed.insert("robot".into(), json!(a.out.join(split).join(robot_file::FILE_NAME)));
        written.insert(split.into(), listed.into());
        summary.insert(split.into(), serde_json::Value::Object(entry));
    }
    write_truth(a, out.path(), &truth, summary, &config, lidar.as_ref())?;
    out.commit()?;
    if a.output.json {
        let format = a.format.extension();
        let (truth_json, truth_model) = (a.out.join("truth.json"), a.out.join("truth_model.toml"));
        let doc = json!({ "out": a.out, "format": format, "splits": written, "truth_json": truth_json, "truth_model": truth_model });
        return super::print_json("simulate", doc);
    }
    println!("wrote {}", a.out.display());
    Ok(())
}

impl Args {
    /// `--runs-per-command`, else 1 with `--commands` (its repetitions column counts the runs) and the
    /// simulator's default on the benchmark.
    pub fn runs_per_command_or_default(&self) -> usize {
        self.runs_per_command.unwrap_or(if self.commands.is_some() { 1 } else { SimConfig::default().runs_per_command })
    }
}

/// How a `--commands` file becomes runs: its commands counted with their repetitions, times
/// `--runs-per-command`, in each split (train and validation: two sets of the same size).
fn commands_line(path: &Path, config: &SimConfig) -> String {
    let (commands, k) = (config.commands.len(), config.runs_per_command);
    format!(
        "{}: {} (with their repetitions) × {k} run{} per command = {} in each of train and validation",
        path.display(),
        crate::units::count(commands, "command"),
        if k == 1 { "" } else { "s" },
        crate::units::count(commands * k, "run")
    )
}

/// Writes `truth_model.toml` and `truth.json` (the costs of each split in `summary`, the true model, the
/// simulator's settings) into `dir` (the `--out` folder being written).
fn write_truth(
    a: &Args,
    dir: &Path,
    truth: &FittedModel,
    summary: serde_json::Map<String, serde_json::Value>,
    config: &SimConfig,
    lidar: Option<&Lidar>,
) -> anyhow::Result<()> {
    let truth_toml = model_file::to_toml(truth, None)?;
    atomic::write_atomic(&dir.join("truth_model.toml"), truth_toml.as_bytes())
        .with_context(|| format!("writing {}", a.out.join("truth_model.toml").display()))?;
    let doc = json!({
        "design_cost": { "train": summary["train"]["design_end_pose"], "validation": summary["validation"]["design_end_pose"] },
        "oracle_cost": { "train": summary["train"]["oracle_end_pose"], "validation": summary["validation"]["oracle_end_pose"] },
        "splits": summary,
        "true_model": model_file::ModelFile::from_fitted(truth, None)?,
        "effects": a.effects,
        "seed": a.seed,
        "simulator": config,
        "cost": "design_cost and oracle_cost are the paper's Eq. 6 with exact-arc odometry; path costs are RMS over every ground-truth pose",
    });
    let mut doc = doc;
    if let Some(l) = lidar {
        let m = &l.base_from_sensor;
        doc["lidar"] = json!({
            "room": l.name,
            "polygons_m": l.room.polygons(),
            "base_from_sensor": { "x_m": m.x_m, "y_m": m.y_m, "theta_rad": m.theta_rad },
            "scans": l.settings,
            "tf_static": l.stated.map(|m| json!({ "x_m": m.x_m, "y_m": m.y_m, "theta_rad": m.theta_rad })),
            "topic": dataset::mcap::SCAN_TOPIC,
            "frame": dataset::mcap::LASER_FRAME,
        });
    }
    let text = serde_json::to_string_pretty(&doc)?;
    atomic::write_atomic(&dir.join("truth.json"), text.as_bytes())
        .with_context(|| format!("writing {}", a.out.join("truth.json").display()))
}
