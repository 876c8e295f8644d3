//! ROS 2 bags in MCAP (`ros2 bag record -s mcap`): runs read from them, and runs written as them.
//!
//! # Reading ([`read_file`])
//! One pass over the messages in file order (zstd/lz4 chunks decompressed, chunk CRCs checked where the
//! file has them), decoding CDR with a serde struct per message type:
//!
//! | role | types | default topic choice |
//! |---|---|---|
//! | wheel speeds | `sensor_msgs/msg/JointState` | the only JointState topic, else the only one carrying all the wheel joints; without JointState, the robot's own odometry through the design ([`McapOptions::wheels_from_twist`]) |
//! | ground truth | `geometry_msgs/msg/PoseStamped`, `PoseWithCovarianceStamped`, `nav_msgs/msg/Odometry`, one parent → child pair of `tf2_msgs/msg/TFMessage`, or `geometry_msgs/msg/PointStamped` (positions only: a tracker, UWB, a total station) or `sensor_msgs/msg/NavSatFix` (GNSS: positions east and north of the recording's first fix, WGS 84) | the only source outside the robot's frames (see below) |
//! | recorded odometry | `nav_msgs/msg/Odometry` in frame `odom` | `/odom`, else the only one |
//! | command | `geometry_msgs/msg/Twist`, `TwistStamped` | `/cmd_vel`, else the only one |
//!
//! - **Wheels.** Joints are mapped **by name** to [`McapOptions::wheel_joints`] (their order is the wheel
//!   order). Velocity is rad/s; when messages have no velocity, the speeds are differences of position over
//!   `header.stamp` (sample `k` covers `(t_{k−1}, t_k]`, omni-kin's convention), and a note says so.
//!   Positions at a run's first sample become [`RunData::wheel_start_rad`](omni_kin::RunData).
//! - **Ground truth** is a `map`/`world`/motion-capture source, never the robot's own odometry: a pose
//!   topic whose `header.frame_id` is `odom`, `base_link` or `base_footprint` is not a candidate (REP-105),
//!   and Odometry in frame `odom` is kept as recorded odometry instead. A TF pair is a candidate when its
//!   parent is a root of the TF tree (nobody's child) and neither frame is `odom`, or when it is exactly
//!   [`McapOptions::truth_parent_frame`] → [`McapOptions::truth_child_frame`]. The frames, when given, also
//!   filter and check pose topics. Yaw comes from the quaternion, unwrapped so the heading is continuous;
//!   each run's first heading lies in (−π, π]. Poses outside the wheel data's time span are dropped (with a
//!   note), so ordinary bags pass `Run::new`'s coverage check.
//! - **Command.** [`RunData::command`](omni_kin::RunData) is the **first non-zero** command of the run:
//!   `v = hypot(vx, vy)`, `α = atan2(vy, vx)`, `ω = wz` (body frame). Twist has no header, so its time is
//!   the log time (a note says so); it matters only for [`McapOptions::split`].
//! - **Times.** From `header.stamp`, in seconds since [`McapRead::origin_s`], the whole second of the
//!   first wheel message (exact to the nanosecond; a float64 epoch time would not be).
//! - **Topics** are chosen automatically when that is unambiguous; otherwise the error lists the candidates
//!   and the flag that chooses (`--joints-topic`, `--gt-topic`, `--gt-parent-frame`, `--gt-child-frame`).
//!   The chosen topics must have schema encoding `ros2msg` (or `ros2idl`, the same types and CDR layout)
//!   and message encoding `cdr`.
//! - **Runs.** One file is one run named after the file stem; with [`McapOptions::split`] it is cut at
//!   standstills (see [`split`]) into runs `<stem>#1`, `<stem>#2`, …, each with the ground truth, odometry
//!   and command of its own span.
//!
//! Every error names the file and, where it applies, the topic, the message (0-based index within its
//! topic, in file order), the field and the run: `a.mcap: topic "/joint_states", message 5: wheel joint
//! "wheel_c" is missing (names: wheel_a, wheel_b)`. A problem on a topic that is not used does not stop
//! the read.
//!
//! # Writing ([`write_run`])
//! Exactly the topics `/joint_states` (JointState at the wheel rate: velocity rad/s, position the wheel
//! angle integrated from [`Run::wheel_start_rad`] or 0), `/ground_truth/pose` (PoseStamped in frame
//! `map`), `/cmd_vel` (Twist, body frame, when the run has a command: the command at the first wheel
//! sample and a zero twist at the last) and `/odom` (Odometry, frame `odom`, child `base_link`, from
//! [`WriteOptions::design_odometry`], twist from pose differences in the body frame), and the recording's
//! own transforms, URDF and commands as recorded ([`WriteOptions::copied`], [`copy`]). Stamps are
//! [`WriteOptions::origin_s`] + `t_s`, rounded to the nanosecond; log time = stamp. The file is written to a
//! temporary name beside the target and renamed, so a reader never sees half a bag.
//!
//! Reading a written bag gives the run back (values exact, stamps to 1 ns) when its first wheel time lies
//! in [0, 1) s, as simulated runs do; otherwise times come back shifted by whole seconds.
//!
//! # Performance
//! Reading 180 bags of 1050 JointState + 40 PoseStamped messages each (11.6 MB, zstd) takes 0.17–0.19 s in
//! release mode on one core of a 2-core machine (`tests/mcap_speed.rs`).

pub(crate) mod assembly;
mod common;
pub mod copy;
pub(crate) mod framing;
mod imu;
mod inspect;
mod joint_state;
mod laser_scan;
mod odom_wheels;
mod odometry;
mod pose_stamped;
mod poses;
mod qos;
pub(crate) mod recording;
pub(crate) mod review;
pub(crate) mod selection;
pub mod split;
mod statics;
mod tf;
mod twist;
mod write;

use crate::dataset::DatasetError;
use crate::dataset::ground_truth::{ExternalTruth, GtClock};
use omni_kin::{Run, StampedPose};
use std::path::Path;

pub(crate) use imu::ImuSink;
pub use imu::{BASE_FRAMES as IMU_BASE_FRAMES, GyroRead, ImuRate, StatedMount};
pub(crate) use inspect::InventorySink;
pub use inspect::{Inventory, ROBOT_DESCRIPTION_TOPIC, TopicSummary, inspect, inspect_bytes};
pub(crate) use laser_scan::ScanSink;
pub use laser_scan::{AngleMaxMismatch, ScanRead};
pub use review::{Role, TopicReview};
pub use write::{COMMAND_TOPIC, IMU_TOPIC, JOINTS_TOPIC, LASER_FRAME, SCAN_TOPIC, TF_STATIC_TOPIC, TRUTH_TOPIC};

/// ROS time of the simulator's t = 0 in MCAP output (2023-11-14T22:13:20Z). s.
pub const SIM_EPOCH_S: i64 = 1_700_000_000;

/// The default wheel joint names, in wheel order.
pub const DEFAULT_WHEEL_JOINTS: [&str; 3] = ["wheel_a", "wheel_b", "wheel_c"];

/// How to read a bag.
#[derive(Clone, Debug, PartialEq)]
pub struct McapOptions {
    /// JointState names of the wheels; their order is the wheel order. Default `wheel_a`, `wheel_b`,
    /// `wheel_c`.
    pub wheel_joints: Vec<String>,
    /// The JointState topic of the wheels (`--joints-topic`). Default: chosen automatically.
    pub joints_topic: Option<String>,
    /// The ground-truth topic (`--gt-topic`). Default: chosen automatically.
    pub truth_topic: Option<String>,
    /// The ground truth's world frame (`--gt-parent-frame`): selects the TF pair, and must match the pose
    /// topic's `header.frame_id`. Default: any.
    pub truth_parent_frame: Option<String>,
    /// The ground truth's tracked frame (`--gt-child-frame`): selects the TF pair, and must match an
    /// Odometry's `child_frame_id`. Default: any.
    pub truth_child_frame: Option<String>,
    /// The robot's base frame (`[frames] base`): a tracked frame and a lidar are moved to it through static
    /// transforms. Default: `base_link`, else `base_footprint`.
    pub base_frame: Option<String>,
    /// The command topic (Twist or TwistStamped). Default: `/cmd_vel`, else the only one.
    pub command_topic: Option<String>,
    /// Cut the file into runs at standstills of at least this long. s. Default: one run per file.
    pub split: Option<f64>,
    /// Cut each recording into runs of this length instead (`--split 20s`): s. The last piece takes what is
    /// left when that is less than half a length.
    pub split_every_s: Option<f64>,
    /// Collect runs that fail validation in [`McapRead::skipped`] instead of failing. Default false.
    pub skip_invalid: bool,
    /// Keep the robot's recorded odometry in [`Run::recorded_odometry`]. Calibration never reads it and it
    /// takes as much memory as the wheel data (a pose per `/odom` message), so commands that do not show
    /// it turn this off. Default true.
    pub recorded_odometry: bool,
    /// Force the clock offset of a ground-truth topic (`--gt-time-offset` without `--gt`): `t_wheel =
    /// t_truth + offset`. s. Default: the stamps as recorded, unless the topic is found on another clock.
    pub truth_time_offset_s: Option<f64>,
    /// The units of the wheel joints' values (`[wheel_data]` in robot.toml). Default rad and rad/s.
    pub wheel_data: omni_kin::robot::WheelData,
    /// Read the wheels only: each run's ground truth is a placeholder, the start at rest at the origin at the
    /// first wheel sample and the same pose at the last, for measured end poses to replace
    /// (`--gt-kind end-pose`). Default false.
    pub wheels_only: bool,
    /// The design's forward kinematics, a row per wheel (in wheel order): wheel speed (rad/s) per body vx,
    /// vy (m/s) and ω (rad/s). With it, a recording without JointState takes its wheel speeds from the
    /// robot's own odometry (`/odom`) through the design (module `odom_wheels`); so does a `joints_topic` that
    /// names an Odometry topic. Set from the robot description. Default: none (JointState is needed).
    pub wheels_from_twist: Option<Vec<[f64; 3]>>,
    /// Where the topics and frames above were set, for messages. Default: their flags.
    pub origins: Origins,
    /// A LaserScan topic whose scans (and static transforms, for the lidar's mount from [`Self::base_frame`])
    /// are gathered in the same pass over the recording as the wheels ([`McapRead::scans`]): the lidar
    /// reference (`--gt-scans`). Default: none.
    pub scan_topic: Option<String>,
}

/// Where an option was set, for messages that name it.
#[derive(Clone, Debug, PartialEq)]
pub enum Origin {
    /// A command-line flag (`--joints-topic`); omnical.toml sets the flags' defaults.
    Flag(&'static str),
    /// A key of a robot description: the key (`[topics] joint_states`) and where it is (`robot.toml, line 31`).
    RobotFile {
        /// `[topics] joint_states`.
        key: String,
        /// `robot.toml, line 31`.
        at: String,
    },
}

impl Origin {
    /// The option with its value, as a message names it: `--joints-topic /x`, or
    /// `[topics] joint_states = "/x" (robot.toml, line 31)`.
    pub fn naming(&self, value: &str) -> String {
        match self {
            Self::Flag(flag) => format!("{flag} {value}"),
            Self::RobotFile { key, at } => format!("{key} = {value:?} ({at})"),
        }
    }
}

/// Where [`McapOptions`]'s topics and frames were set.
#[derive(Clone, Debug, PartialEq)]
pub struct Origins {
    /// Of [`McapOptions::joints_topic`].
    pub joints_topic: Origin,
    /// Of [`McapOptions::truth_topic`].
    pub truth_topic: Origin,
    /// Of [`McapOptions::truth_parent_frame`].
    pub truth_parent_frame: Origin,
    /// Of [`McapOptions::truth_child_frame`].
    pub truth_child_frame: Origin,
}

impl Default for Origins {
    fn default() -> Self {
        Self {
            joints_topic: Origin::Flag("--joints-topic"),
            truth_topic: Origin::Flag("--gt-topic"),
            truth_parent_frame: Origin::Flag("--gt-parent-frame"),
            truth_child_frame: Origin::Flag("--gt-child-frame"),
        }
    }
}

impl Default for McapOptions {
    fn default() -> Self {
        Self {
            wheel_joints: DEFAULT_WHEEL_JOINTS.map(String::from).to_vec(),
            joints_topic: None,
            truth_topic: None,
            truth_parent_frame: None,
            truth_child_frame: None,
            base_frame: None,
            command_topic: None,
            split: None,
            split_every_s: None,
            wheels_only: false,
            wheels_from_twist: None,
            skip_invalid: false,
            recorded_odometry: true,
            truth_time_offset_s: None,
            wheel_data: Default::default(),
            origins: Origins::default(),
            scan_topic: None,
        }
    }
}

/// What one bag gave.
#[derive(Clone, Debug, PartialEq)]
pub struct McapRead {
    /// The runs, in time order.
    pub runs: Vec<Run>,
    /// Things the user should know, each naming the file (and topic).
    pub notes: Vec<crate::dataset::Note>,
    /// Runs left out under [`McapOptions::skip_invalid`]: run name and the full error message.
    pub skipped: Vec<(String, String)>,
    /// Run times are seconds since this instant: the whole second (`header.stamp.sec`) of the first wheel
    /// message. s since the epoch (or since sim-time start).
    pub origin_s: i64,
    /// The clock offset of a ground truth read from a separate file ([`read_file_with_truth`]).
    pub ground_truth_clock: Option<GtClock>,
    /// The scans of [`McapOptions::scan_topic`], read in the same pass as the wheels.
    pub scans: Option<ScanRead>,
}

/// How to write a bag.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteOptions {
    /// JointState names of the wheels, in wheel order; as many as the run has wheels. Default `wheel_a`,
    /// `wheel_b`, `wheel_c`.
    pub wheel_joints: Vec<String>,
    /// The robot's own odometry (the design model's), published on `/odom`. Default none.
    pub design_odometry: Option<Vec<StampedPose>>,
    /// Odometry of a calibrated model, published on `/omnical/odometry` (`omnical export --mcap`). Default
    /// none.
    pub calibrated_odometry: Option<Vec<StampedPose>>,
    /// Stamps are this many seconds plus the run's `t_s`. s. Default 0 (sim time).
    pub origin_s: i64,
    /// A lidar's scans, on `/scan` (LaserScan, frame `laser`), and its mount on `/tf_static`
    /// (`base_link` → `laser`). Default none.
    pub lidar: Option<LidarTrack>,
    /// An IMU, on `/imu` (`sensor_msgs/msg/Imu`, frame `imu_link`), and its mount on `/tf_static`
    /// (`base_link` → `imu_link`). Default none.
    pub imu: Option<ImuTrack>,
    /// The recording's own topics carried over as recorded ([`copy`]: transforms, the URDF, the commands),
    /// each on its own topic; a recorded command topic replaces the run's written one. A topic whose name
    /// the file already writes otherwise is left out. Default none.
    pub copied: Vec<copy::CopiedTopic>,
}

/// A lidar to write into a bag: its scans (stamps on the run's clock) and where it sits on the robot.
#[derive(Clone, Debug, PartialEq)]
pub struct LidarTrack {
    /// The scans, in time order.
    pub scans: Vec<omni_kin::lidar::Scan>,
    /// The lidar's pose in the base frame that `/tf_static` states (m, rad); `None`: no `/tf_static`.
    pub base_from_sensor: Option<omni_kin::Pose2>,
}

/// An IMU to write into a bag: the base's yaw rates it senses (stamps on the run's clock) and how it sits on
/// the robot.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuTrack {
    /// The base's yaw rates, in time order; written as the angular velocity in the IMU's frame.
    pub samples: Vec<omni_kin::gyro::GyroSample>,
    /// The IMU's true mount.
    pub mount: omni_kin::gyro::ImuMount,
    /// The mount `/tf_static` states (`base_link` → `imu_link`); `None`: none.
    pub stated: Option<omni_kin::gyro::ImuMount>,
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self {
            wheel_joints: DEFAULT_WHEEL_JOINTS.map(String::from).to_vec(),
            design_odometry: None,
            calibrated_odometry: None,
            origin_s: 0,
            lidar: None,
            imu: None,
            copied: Vec::new(),
        }
    }
}

/// Reads the runs of one ROS 2 MCAP bag.
///
/// ```no_run
/// use omni_cli::dataset::mcap::{McapOptions, read_file};
/// let read = read_file("data/run-01.mcap".as_ref(), &McapOptions::default())?;
/// for note in &read.notes {
///     eprintln!("note: {note}");
/// }
/// println!("{} runs, the first has {} wheel samples", read.runs.len(), read.runs[0].n_samples());
/// # Ok::<(), omni_cli::dataset::DatasetError>(())
/// ```
pub fn read_file(path: &Path, opts: &McapOptions) -> Result<McapRead, DatasetError> {
    assembly::read_file(path, opts, None)
}

/// [`read_file`] with the ground truth from a separate file (`--gt`) instead of a topic: its clock offset is
/// forced or estimated ([`omni_kin::clock`]) and reported in [`McapRead::ground_truth_clock`].
pub fn read_file_with_truth(
    path: &Path,
    opts: &McapOptions,
    truth: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    assembly::read_file(path, opts, truth)
}

/// Reads the runs of one ROS 2 MCAP bag held in memory: as [`read_file`], with `path` only naming the bag
/// in messages and runs (the file stem is the run name).
pub fn read_bytes(path: &Path, bytes: &[u8], opts: &McapOptions) -> Result<McapRead, DatasetError> {
    assembly::read_bytes(path, bytes, opts, None)
}

/// Writes one run as a ROS 2 MCAP bag, atomically (temporary file, then rename).
pub fn write_run(path: &Path, run: &Run, w: &WriteOptions) -> Result<(), DatasetError> {
    write::write_run(path, run, w)
}
