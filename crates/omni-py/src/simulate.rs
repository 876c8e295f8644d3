//! `simulate`: the benchmark runs of a robot (the paper's flower by default) on a true robot (any model,
//! Python effects included); with `out=`, written as ROS 2 bags with the simulated lidar and IMU
//! ([`omni_cli::api::simulate`], the CLI's code).

use crate::effect::PyEffect;
use crate::errors::{PyResultExt, out_error, value_error};
use crate::model::model_arg;
use crate::robot::{robot_arg, robot_design, robot_error};
use crate::run::PyRun;
use omni_cli::api::imu::mount_from_text as mount_from_text_rpy;
use omni_cli::api::simulate::{Format, Imu, Lidar, mount_from_text, simulate_split, write_robot, write_split};
use omni_cli::lidar::ScanSettings;
use omni_cli::out_path::{Inputs, OutDir};
use omni_cli::robot_file::{self, RobotFile};
use omni_kin::gyro::ImuMount;
use omni_kin::simulate::{SimConfig, benchmark_commands, simulate as rs_simulate};
use omni_kin::{FittedModel, IkMatrix, KinematicsKind, Pose2, Run};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Simulate the benchmark (its commands × ``runs_per_command``) on the true robot ``truth``: the runs
/// ``omnical simulate`` writes into its ``train/`` folder (the same defaults: 5 runs per command of 10 s,
/// seed 7, names ``train/NN-rK``; its ``validation/`` folder is ``seed=8, prefix="validation/"``).
///
/// ``robot``: the simulated base, a ``robot.toml`` path or ``"apr02"`` (as ``omnical simulate --robot``;
/// default ``"apr02"``, the paper's robot): its design turns the commands into wheel targets, and the
/// commands are those it can perform (the 36 flower commands; for a differential drive forward and
/// turning ones, no sideways runs). ``truth`` (default: the paper's Eq. 9 matrix on APR-02, the design
/// itself on any other robot; give a model with effects to hide them in the data) must have the robot's
/// wheel count. Returns the runs, named ``{prefix}{command:02}-r{repetition}``. Deterministic for a
/// ``seed``; the GIL is released.
///
/// ``out``: also write the runs as ROS 2 bags into this folder, one ``NN-rK.mcap`` per run with the
/// ``robot.toml`` beside them, as the CLI's ``OUT/train/`` (``omnical.load(out)`` reads them back). The
/// folder must be new or empty unless ``force=True``, which replaces it whole. The simulated sensors
/// are written into these bags, so they need ``out``; their keywords are the CLI's flags:
///
/// - ``lidar``: a 2D lidar in a room, ``"room"`` (10 × 8 m with boxes and pillars), ``"corridor"``
///   (40 × 5 m) or a room file (TOML polygons in m, docs/formats.md): ``/scan`` (LaserScan, frame
///   ``laser``) and its mount on ``/tf_static``. Every run starts at the room's origin heading +x; a run
///   that comes within 0.25 m of a wall raises ``ValueError``; a room file that does not exist,
///   ``FileNotFoundError``. ``lidar_mount``: the lidar's pose on the base ``(x_m, y_m, yaw_deg)`` or the
///   CLI's ``"X,Y,YAW_DEG"``; ``lidar_tf``: the mount ``/tf_static`` states, the same, or ``"none"``
///   (default: the true mount); ``lidar_rate`` [Hz]; ``lidar_beams`` over ``lidar_fov`` [degrees, centred on
///   the lidar's x axis; 360 all round, 270 a Hokuyo's]; ``lidar_max_range`` [m];
///   ``lidar_noise``: Gaussian range noise [m]; ``lidar_dropout``: share of beams with no return;
///   ``lidar_sweep``: measure each scan's beams over its period, as a spinning lidar; ``lidar_model``:
///   ``"ideal"`` (the settings above), ``"urg04lx"`` or ``"rplidar"`` (scans made as a Hokuyo URG-04LX's
///   or an RPLidar A2's come out: noise growing with range, about half the beams empty, mixed pixels, a
///   sweep; they set the scanner themselves, so another ``lidar_rate`` … ``lidar_sweep`` raises
///   ``ValueError``).
/// - ``imu=True``: a gyro on ``/imu`` (Imu, frame ``imu_link``): the base's true turn rate plus ``imu_bias``
///   [rad/s] and Gaussian noise of ``imu_noise`` [rad/s], ``imu_rate`` [Hz] messages, as the angular velocity
///   in the IMU's frame; ``imu_mount``: how the IMU sits on the base, ``(roll_deg, pitch_deg, yaw_deg)`` or
///   the CLI's ``"ROLL,PITCH,YAW_DEG"`` (URDF's rpy: ``(180, 0, 0)`` upside down); ``imu_tf``: the mount
///   ``/tf_static`` states (``base_link`` → ``imu_link``), the same, or ``"none"`` (default: the true mount).
///
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)  # 36 flower commands, 1 s each
/// >>> len(runs), runs[0].name, runs[0].n_wheels
/// (36, 'train/00-r0', 3)
/// >>> import tempfile
/// >>> out = tempfile.mkdtemp() + "/train"
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=2.0, out=out, lidar="room", imu=True)
/// >>> len(omnical.load(out, gt_scans="/scan")) > 0
/// True
#[pyfunction]
// The defaults are `omnical simulate`'s (SimConfig::default() and its --seed default, 7; the sensors'
// ScanSettings::default() and Imu::default()), spelt out so that help() shows them; tests/test_mirror.py
// and crates/omni-cli/tests/config.rs compare them with the CLI's.
#[pyo3(signature = (truth = None, *, robot = None, runs_per_command = 5, duration_s = 10.0, seed = 7, noise_free = false, prefix = "train/", sample_drop_probability = 0.0, sample_jitter_s = 0.0, out = None, force = false, lidar = None, lidar_mount = MountArg::text("0,0,0"), lidar_tf = None, lidar_rate = 10.0, lidar_beams = 720, lidar_fov = 360.0, lidar_max_range = 12.0, lidar_noise = 0.01, lidar_dropout = 0.01, lidar_sweep = false, lidar_model = "ideal", imu = false, imu_rate = 100.0, imu_bias = 0.005, imu_noise = 0.002, imu_mount = MountArg::text("0,0,0"), imu_tf = None))]
// pyo3 shows a default it cannot spell as `...`: the text signature spells lidar_mount's as the CLI's
// (mypy's stubtest compares it with _omnical.pyi).
#[pyo3(
    text_signature = "(truth=None, *, robot=None, runs_per_command=5, duration_s=10.0, seed=7, noise_free=False, prefix=\"train/\", sample_drop_probability=0.0, sample_jitter_s=0.0, out=None, force=False, lidar=None, lidar_mount=\"0,0,0\", lidar_tf=None, lidar_rate=10.0, lidar_beams=720, lidar_fov=360.0, lidar_max_range=12.0, lidar_noise=0.01, lidar_dropout=0.01, lidar_sweep=False, lidar_model=\"ideal\", imu=False, imu_rate=100.0, imu_bias=0.005, imu_noise=0.002, imu_mount=\"0,0,0\", imu_tf=None)"
)]
// long: one parameter per keyword (the CLI's flags, 28 of them), then the settings built by helpers.
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    truth: Option<&Bound<'_, PyAny>>,
    robot: Option<PathBuf>,
    runs_per_command: usize,
    duration_s: f64,
    seed: u64,
    noise_free: bool,
    prefix: &str,
    sample_drop_probability: f64,
    sample_jitter_s: f64,
    out: Option<PathBuf>,
    force: bool,
    lidar: Option<String>,
    lidar_mount: MountArg,
    lidar_tf: Option<MountArg>,
    lidar_rate: f64,
    lidar_beams: usize,
    lidar_fov: f64,
    lidar_max_range: f64,
    lidar_noise: f64,
    lidar_dropout: f64,
    lidar_sweep: bool,
    lidar_model: &str,
    imu: bool,
    imu_rate: f64,
    imu_bias: f64,
    imu_noise: f64,
    imu_mount: MountArg,
    imu_tf: Option<MountArg>,
) -> PyResult<Vec<PyRun>> {
    let mut config = SimConfig {
        runs_per_command,
        duration_s,
        seed,
        sample_drop_probability,
        sample_jitter_s,
        ..SimConfig::default()
    };
    let robot = robot_arg(robot.as_ref())?;
    let truth_arg = truth.and_then(|t| t.extract::<String>().ok());
    let (truth, adapters) = true_robot(truth, robot.as_ref(), &mut config)?;
    if noise_free {
        config = config.noise_free();
    }
    let settings = ScanSettings {
        rate_hz: lidar_rate,
        beams: lidar_beams,
        fov_rad: lidar_fov.to_radians(),
        range_max_m: lidar_max_range,
        range_noise_m: lidar_noise,
        dropout: lidar_dropout,
        sweeping: lidar_sweep,
        ..ScanSettings::default()
    };
    let settings = of_lidar_model(lidar_model, settings)?;
    let lidar = lidar.map(|room| lidar_in(&room, &lidar_mount, lidar_tf.as_ref(), settings)).transpose()?;
    let imu = imu
        .then(|| {
            imu_on(
                Imu { rate_hz: imu_rate, bias_rad_s: imu_bias, noise_rad_s: imu_noise, ..Imu::default() },
                &imu_mount,
                imu_tf.as_ref(),
            )
        })
        .transpose()?;
    let errors = crate::effect::EffectErrors::new(adapters);
    let runs = match out {
        None if lidar.is_some() || imu.is_some() => {
            return Err(value_error(
                "omnical.simulate: lidar= and imu= write LaserScan and Imu messages into ROS 2 bags: give out=DIR \
                 too (then omnical.load(DIR) reads the runs, gt_scans=\"/scan\" the lidar as their reference)",
            ));
        }
        None => errors.check(py.detach(|| rs_simulate(&config, &truth, prefix)))?.py()?,
        Some(out) => {
            let robot = match robot {
                Some(r) => r,
                None => robot_file::from_arg(robot_file::BUILTIN_APR02).map_err(robot_error)?,
            };
            let sensors = Sensors { lidar: lidar.as_ref(), imu: imu.as_ref() };
            let truth_file = truth_arg.filter(|t| !["paper", "design"].contains(&t.as_str()));
            let inputs = Inputs::new().with_some("robot=", robot.path()).with_some("truth=", truth_file);
            let target = (out.as_path(), force, &inputs);
            errors.check(py.detach(|| write_simulation(&config, &truth, prefix, sensors, &robot, target)))??
        }
    };
    Ok(runs.into_iter().map(|inner| PyRun { inner }).collect())
}

/// The lidar in `room` on `mount`, `/tf_static` stating `tf` (default: the true mount).
fn lidar_in(room: &str, mount: &MountArg, tf: Option<&MountArg>, settings: ScanSettings) -> PyResult<Lidar> {
    let mount = mount.pose("lidar_mount")?.unwrap_or_default();
    let stated = match tf {
        None => Some(mount),
        Some(tf) => tf.pose("lidar_tf")?,
    };
    Lidar::new(room, mount, stated, settings).py()
}

/// The IMU of `settings` on `mount`, `/tf_static` stating `tf` (default: the true mount), checked.
fn imu_on(settings: Imu, mount: &MountArg, tf: Option<&MountArg>) -> PyResult<Imu> {
    let mount = mount.rpy("imu_mount")?.unwrap_or(ImuMount::UPRIGHT);
    let stated = match tf {
        None => Some(mount),
        Some(tf) => tf.rpy("imu_tf")?,
    };
    Imu { mount, stated, ..settings }.checked().py()
}

/// The true robot (`truth`, else the paper's calibration on APR-02 and the design itself on any other
/// robot, as the CLI), checked against `robot`, whose design and benchmark commands go into `config`.
fn true_robot(
    truth: Option<&Bound<'_, PyAny>>,
    robot: Option<&RobotFile>,
    config: &mut SimConfig,
) -> PyResult<(FittedModel, Vec<Arc<PyEffect>>)> {
    let design = match robot {
        Some(r) => {
            let g = r.description.to_geometry().map_err(|e| value_error(format!("robot {}: {e}", r.source)))?;
            config.commands = benchmark_commands(&g);
            config.design = g;
            Some(robot_design(r, KinematicsKind::Ik)?)
        }
        None => None,
    };
    let (truth, adapters) = match (truth, &design) {
        (Some(t), _) => model_arg(t)?,
        (None, Some(d)) if d.ik().py()? != IkMatrix::paper_design() => (d.clone(), Vec::new()),
        (None, _) => (omni_cli::design::paper_calibrated(), Vec::new()),
    };
    if let Some(r) = robot
        && truth.model.n_wheels() != config.design.n_wheels()
    {
        return Err(value_error(format!(
            "truth has {} wheels and robot {} has {} ({})",
            truth.model.n_wheels(),
            r.source,
            config.design.n_wheels(),
            config.design.wheel_names.join(", ")
        )));
    }
    Ok((truth, adapters))
}

/// The sensors asked for.
#[derive(Clone, Copy)]
struct Sensors<'a> {
    lidar: Option<&'a Lidar>,
    imu: Option<&'a Imu>,
}

/// Simulates the runs with their sensors and writes them into the folder `out` (the CLI's `OUT/train/`: one
/// MCAP bag per run, the robot.toml beside them), claimed apart from `inputs` and replaced if `force`.
fn write_simulation(
    config: &SimConfig,
    truth: &FittedModel,
    prefix: &str,
    sensors: Sensors<'_>,
    robot: &RobotFile,
    (out, force, inputs): (&Path, bool, &Inputs),
) -> PyResult<Vec<Run>> {
    let dir = OutDir::claim(out, "out=", force, inputs).map_err(out_error)?;
    let (runs, simulated) = simulate_split(config, truth, prefix, sensors.lidar, sensors.imu).py()?;
    let joints = robot.description.joints();
    write_split(dir.path(), &runs, Format::Mcap, &joints, simulated.as_sensors()).py()?;
    write_robot(dir.path(), robot, Format::Mcap).py()?;
    dir.commit().map_err(out_error)?;
    Ok(runs)
}

/// A mount keyword: ``(x_m, y_m, yaw_deg)`` or the CLI's text ``"X,Y,YAW_DEG"`` (m, m, degrees); for
/// ``lidar_tf`` also ``"none"`` (no ``/tf_static``).
#[derive(FromPyObject)]
pub enum MountArg {
    /// `(x_m, y_m, yaw_deg)`.
    Pose((f64, f64, f64)),
    /// `"X,Y,YAW_DEG"` or `"none"`.
    Text(String),
}

impl MountArg {
    /// The CLI's text form (a default spelt as the flag's).
    pub fn text(t: &str) -> Self {
        Self::Text(t.to_string())
    }

    /// The pose (`None` for `"none"`, allowed for `lidar_tf` only); `ValueError` naming `keyword`.
    fn pose(&self, keyword: &str) -> PyResult<Option<Pose2>> {
        let parsed = match self {
            Self::Text(t) if t == "none" && keyword == "lidar_tf" => return Ok(None),
            Self::Text(t) => mount_from_text(t),
            Self::Pose((x, y, yaw)) => mount_from_text(&format!("{x},{y},{yaw}")),
        };
        let none = if keyword == "lidar_tf" { " or \"none\"" } else { "" };
        let shown = match self {
            Self::Text(t) => format!("{t:?}"),
            Self::Pose(p) => format!("{p:?}"),
        };
        parsed.map(Some).ok_or_else(|| {
            value_error(format!("{keyword} {shown}: expected (x_m, y_m, yaw_deg) or \"X,Y,YAW_DEG\"{none}"))
        })
    }
}

impl MountArg {
    /// An IMU mount, ``(roll_deg, pitch_deg, yaw_deg)`` or ``"ROLL,PITCH,YAW_DEG"`` (`None` for `"none"`,
    /// allowed for `imu_tf` only); `ValueError` naming `keyword`.
    pub fn rpy(&self, keyword: &str) -> PyResult<Option<ImuMount>> {
        let parsed = match self {
            Self::Text(t) if t == "none" && keyword == "imu_tf" => return Ok(None),
            Self::Text(t) => mount_from_text_rpy(t),
            Self::Pose((r, p, y)) => mount_from_text_rpy(&format!("{r},{p},{y}")),
        };
        let none = if keyword == "imu_tf" { " or \"none\"" } else { "" };
        parsed.map(Some).ok_or_else(|| {
            let shown = match self {
                Self::Text(t) => format!("{t:?}"),
                Self::Pose(p) => format!("{p:?}"),
            };
            value_error(format!(
                "{keyword} {shown}: expected (roll_deg, pitch_deg, yaw_deg) or \"ROLL,PITCH,YAW_DEG\"{none}"
            ))
        })
    }
}

/// The scanner `lidar_model` names: `ideal` keeps `given` (the keywords' settings); a real kind sets the
/// scanner itself, so a keyword set away from its default is refused, as the CLI's flags conflict.
fn of_lidar_model(lidar_model: &str, given: ScanSettings) -> PyResult<ScanSettings> {
    use omni_cli::lidar::LidarModel;
    use omni_kin::choice::Choice;
    let model = LidarModel::from_id(lidar_model).map_err(|e| value_error(format!("lidar_model {e}")))?;
    if model == LidarModel::Ideal {
        return Ok(given);
    }
    if given != ScanSettings::default() {
        return Err(value_error(format!(
            "lidar_model={lidar_model:?} sets the scanner itself: leave lidar_rate, lidar_beams, lidar_fov, \
             lidar_max_range, lidar_noise, lidar_dropout and lidar_sweep at their defaults"
        )));
    }
    Ok(ScanSettings::of_model(model))
}
