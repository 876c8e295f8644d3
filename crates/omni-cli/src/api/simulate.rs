//! Simulated recordings (`omnical simulate`, Python's `omnical.simulate(out=…)`): a split's runs with the
//! sensors simulated beside them (a 2D lidar in a room, an upright gyro), written one file per run with the
//! robot description beside them.
//!
//! The settings are the CLI's flags (`--lidar`, `--lidar-rate`, `--imu-bias`, …, declared in
//! [`super::settings`]); the errors name them so.

use crate::atomic;
use crate::dataset::mcap::ImuTrack;
use crate::dataset::{self, DatasetError, mcap::LidarTrack};
use crate::lidar::{self, Room, ScanSettings};
use crate::robot_file::{self, RobotFile};
use omni_kin::gyro::ImuMount;
use omni_kin::robot::RobotDescription;
use omni_kin::simulate::{SampledRun, SimConfig, simulate, simulate_sampled};
use omni_kin::{FittedModel, KinError, Pose2, Run};
use std::path::{Path, PathBuf};

pub use crate::dataset::mcap::SIM_EPOCH_S;

/// Dataset file format for writing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// omnical CSV, one file per run (docs/formats.md).
    Csv,
    /// ROS 2 MCAP bag, one file per run.
    Mcap,
}

impl Format {
    /// The files' extension (`mcap`).
    pub fn extension(self) -> &'static str {
        match self {
            Self::Csv => "csv",
            Self::Mcap => "mcap",
        }
    }
}

/// Why a simulation with sensors, or its files, could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The room of `--lidar` could not be read.
    #[error("--lidar")]
    Room(#[source] DatasetError),
    /// The lidar's settings are out of range.
    #[error("--lidar settings")]
    ScanSettings(#[source] KinError),
    /// A run comes too close to a wall of the lidar's room.
    #[error(
        "--lidar {room}: run {run} leaves the room: at t = {t_s:.1} s its base is at ({x_m:.2}, {y_m:.2}) m, less \
         than {clearance_m} m from a wall or obstacle (every run starts at the room's origin heading +x); shorten \
         --duration, slow the --commands, or give a larger room"
    )]
    LeavesRoom {
        /// The room as given.
        room: String,
        /// The run.
        run: String,
        /// When. s.
        t_s: f64,
        /// Where: x. m.
        x_m: f64,
        /// Where: y. m.
        y_m: f64,
        /// The clearance it violates ([`lidar::CLEARANCE_M`]). m.
        clearance_m: f64,
    },
    /// `--imu-rate` out of range.
    #[error("--imu-rate {rate_hz}: expected 1 to 10000 Hz")]
    ImuRate {
        /// The rate given. Hz.
        rate_hz: f64,
    },
    /// `--imu-bias` or `--imu-noise` not finite, or a negative noise.
    #[error("--imu-bias {bias_rad_s} / --imu-noise {noise_rad_s}: expected finite values, the noise ≥ 0")]
    ImuNoise {
        /// The bias given. rad/s.
        bias_rad_s: f64,
        /// The noise given. rad/s.
        noise_rad_s: f64,
    },
    /// The simulator refused its inputs.
    #[error(transparent)]
    Kin(#[from] KinError),
    /// A run's file could not be written.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// A folder could not be created.
    #[error("creating {}", path.display())]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The robot description could not be written.
    #[error("writing {}", path.display())]
    WriteRobot {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// A simulated 2D lidar: the room it casts rays in, the room's name as given, its mount and scan settings.
#[derive(Clone, Debug)]
pub struct Lidar {
    /// The room (walls and obstacles). m.
    pub room: Room,
    /// The room as given (`room`, `corridor` or a room file).
    pub name: String,
    /// The lidar's true pose in the base frame. m, rad.
    pub base_from_sensor: Pose2,
    /// The mount the recordings' `/tf_static` states (`None`: none written). m, rad.
    pub stated: Option<Pose2>,
    /// Rate, beams, range, noise, dropout, sweep.
    pub settings: ScanSettings,
}

impl Lidar {
    /// The lidar in the room `room` names (a built-in room or a room file, [`lidar::room_from_arg`]), its
    /// settings checked.
    pub fn new(
        room: &str,
        base_from_sensor: Pose2,
        stated: Option<Pose2>,
        settings: ScanSettings,
    ) -> Result<Self, SimulateError> {
        let read = lidar::room_from_arg(room).map_err(SimulateError::Room)?;
        settings.check().map_err(SimulateError::ScanSettings)?;
        Ok(Self { room: read, name: room.to_string(), base_from_sensor, stated, settings })
    }
}

/// A mount written `X,Y,YAW_DEG` (m, m, degrees; `--lidar-mount 0.2,0,5`) as a pose; `None` unless it
/// is three finite numbers.
pub fn mount_from_text(text: &str) -> Option<Pose2> {
    let v: Vec<f64> = text.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().ok()?;
    (v.len() == 3 && v.iter().all(|x| x.is_finite())).then(|| Pose2::new(v[0], v[1], v[2].to_radians()))
}

/// A simulated IMU: a gyro on the base measuring the yaw rate, mounted upright or otherwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Imu {
    /// Messages per second. Hz. Default 100.
    pub rate_hz: f64,
    /// The gyro's bias. rad/s. Default 0.005.
    pub bias_rad_s: f64,
    /// Gaussian noise of each yaw-rate sample. rad/s. Default 0.002.
    pub noise_rad_s: f64,
    /// How the IMU sits on the base (`--imu-mount`): its messages give the angular velocity in its frame.
    /// Default upright.
    pub mount: ImuMount,
    /// The mount the recordings' `/tf_static` states (`--imu-tf`; `None`: none written). Default upright.
    pub stated: Option<ImuMount>,
}

impl Default for Imu {
    fn default() -> Self {
        Self {
            rate_hz: 100.0,
            bias_rad_s: 0.005,
            noise_rad_s: 0.002,
            mount: ImuMount::UPRIGHT,
            stated: Some(ImuMount::UPRIGHT),
        }
    }
}

impl Imu {
    /// The same settings, checked: a rate of 1 to 10 000 Hz, a finite bias, a finite noise ≥ 0.
    pub fn checked(self) -> Result<Self, SimulateError> {
        if !(self.rate_hz.is_finite() && (1.0..=10_000.0).contains(&self.rate_hz)) {
            return Err(SimulateError::ImuRate { rate_hz: self.rate_hz });
        }
        if !(self.bias_rad_s.is_finite() && self.noise_rad_s.is_finite() && self.noise_rad_s >= 0.0) {
            return Err(SimulateError::ImuNoise { bias_rad_s: self.bias_rad_s, noise_rad_s: self.noise_rad_s });
        }
        Ok(self)
    }
}

/// The sensors simulated beside a split's runs, one entry per run: a lidar's track, an IMU's yaw rates.
#[derive(Clone, Debug, Default)]
pub struct SplitSensors {
    /// Each run's lidar track (with a lidar).
    pub lidar: Option<Vec<LidarTrack>>,
    /// Each run's IMU (with an IMU).
    pub imu: Option<Vec<ImuTrack>>,
}

impl SplitSensors {
    /// Borrowed, for [`write_split`].
    pub fn as_sensors(&self) -> Sensors<'_> {
        Sensors { lidar: self.lidar.as_deref(), imu: self.imu.as_deref() }
    }
}

/// Simulates a split's runs (named `{prefix}NN-rK`) with the sensors given: the lidar's scans (each run's
/// on its own random stream of `cfg.seed`; a run that comes within [`lidar::CLEARANCE_M`] of a wall is
/// refused) and the gyro's yaw rates (the true base every `1 / rate_hz` s, each run's noise its own stream).
/// The runs are [`simulate`]'s.
pub fn simulate_split(
    cfg: &SimConfig,
    truth: &FittedModel,
    prefix: &str,
    lidar: Option<&Lidar>,
    imu: Option<&Imu>,
) -> Result<(Vec<Run>, SplitSensors), SimulateError> {
    let (runs, lidar) = match lidar {
        None => (simulate(cfg, truth, prefix)?, None),
        Some(l) => {
            let sampled = simulate_sampled(cfg, truth, prefix, 1.0 / l.settings.rate_hz)?;
            let tracks = sampled.iter().enumerate().map(|(i, s)| lidar_track(l, s, cfg.seed, i as u64));
            let tracks = tracks.collect::<Result<Vec<_>, _>>()?;
            (sampled.into_iter().map(|s| s.run).collect(), Some(tracks))
        }
    };
    let imu = match imu {
        None => None,
        Some(i) => {
            let sampled = simulate_sampled(cfg, truth, prefix, 1.0 / i.rate_hz)?;
            let gyro = |(k, s): (usize, &SampledRun)| ImuTrack {
                samples: omni_kin::gyro::simulate_gyro(&s.base, i.bias_rad_s, i.noise_rad_s, cfg.seed, k as u64),
                mount: i.mount,
                stated: i.stated,
            };
            Some(sampled.iter().enumerate().map(gyro).collect())
        }
    };
    Ok((runs, SplitSensors { lidar, imu }))
}

/// One run's lidar track (scans on stream `stream` of `seed`), or the refusal of a run that leaves the room.
fn lidar_track(l: &Lidar, s: &SampledRun, seed: u64, stream: u64) -> Result<LidarTrack, SimulateError> {
    if let Some(hit) = lidar::first_collision(&l.room, &s.base, lidar::CLEARANCE_M) {
        return Err(SimulateError::LeavesRoom {
            room: l.name.clone(),
            run: s.run.name().to_string(),
            t_s: hit.t_s,
            x_m: hit.pose.x_m,
            y_m: hit.pose.y_m,
            clearance_m: lidar::CLEARANCE_M,
        });
    }
    let scans = lidar::simulate_scans(&l.room, &s.base, &l.base_from_sensor, &l.settings, seed, stream);
    Ok(LidarTrack { scans, base_from_sensor: l.stated })
}

/// The sensors simulated beside a split's runs, borrowed, one entry per run.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sensors<'a> {
    /// Each run's lidar track.
    pub lidar: Option<&'a [LidarTrack]>,
    /// Each run's IMU.
    pub imu: Option<&'a [ImuTrack]>,
}

/// Writes each run as one file of `format` into `dir` (created), named after the run's last name part
/// (`train/00-r0` → `00-r0.mcap`); an MCAP file carries the run's sensors. Returns the paths.
pub fn write_split(
    dir: &Path,
    runs: &[Run],
    format: Format,
    wheel_names: &[String],
    sensors: Sensors<'_>,
) -> Result<Vec<PathBuf>, SimulateError> {
    let Sensors { lidar, imu } = sensors;
    std::fs::create_dir_all(dir).map_err(|source| SimulateError::CreateDir { path: dir.to_path_buf(), source })?;
    let mut written = Vec::with_capacity(runs.len());
    for (i, r) in runs.iter().enumerate() {
        let stem = r.name().rsplit('/').next().unwrap_or(r.name());
        let path = dir.join(format!("{stem}.{}", format.extension()));
        match format {
            Format::Csv => dataset::csv::write_run(&path, r, wheel_names)?,
            Format::Mcap => {
                let w = dataset::mcap::WriteOptions {
                    wheel_joints: wheel_names.to_vec(),
                    design_odometry: Some(r.recorded_odometry().to_vec()),
                    // Simulated clocks start at 0 s (wheel data from −0.5 s): put them at a plausible epoch.
                    origin_s: SIM_EPOCH_S,
                    lidar: lidar.and_then(|l| l.get(i)).cloned(),
                    imu: imu.and_then(|g| g.get(i)).cloned(),
                    ..Default::default()
                };
                dataset::mcap::write_run(&path, r, &w)?
            }
        }
        written.push(path);
    }
    Ok(written)
}

/// The description with the topics the simulator writes (MCAP): a topic the robot names otherwise (its
/// real recordings' `/tf`, say) is replaced by the simulator's, and the TF frames are dropped with it, so
/// that the robot.toml beside the runs reads them. Topics the robot leaves open stay open.
fn written_topics(d: &RobotDescription, format: Format) -> RobotDescription {
    let mut d = d.clone();
    if format != Format::Mcap {
        return d;
    }
    use dataset::mcap::{COMMAND_TOPIC, JOINTS_TOPIC, TRUTH_TOPIC};
    for (slot, topic) in [
        (&mut d.topics.joint_states, JOINTS_TOPIC),
        (&mut d.topics.ground_truth, TRUTH_TOPIC),
        (&mut d.topics.command, COMMAND_TOPIC),
    ] {
        if slot.as_deref().is_some_and(|t| t != topic) {
            *slot = Some(topic.to_string());
        }
    }
    d.frames = Default::default();
    d
}

/// Writes `robot.toml` into a split's folder, so that commands reading the runs find the robot.
pub fn write_robot(dir: &Path, robot: &RobotFile, format: Format) -> Result<(), SimulateError> {
    let comments = robot_file::Comments {
        header: vec![format!(
            "The robot these simulated runs were made with (omnical simulate --robot {}): its design, joint names \
             and topics. Commands reading this folder use it.",
            robot.source
        )],
        ..Default::default()
    };
    let path = dir.join(robot_file::FILE_NAME);
    let text = robot_file::to_toml(&written_topics(&robot.description, format), &comments);
    atomic::write_atomic(&path, text.as_bytes()).map_err(|source| SimulateError::WriteRobot { path, source })
}
