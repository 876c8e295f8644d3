//! Why runs could not be read ([`LoadError`]).

use crate::api::settings::{named, named_with};
use crate::dataset::DatasetError;
use crate::dataset::ground_truth::CsvColumnsError;
use crate::robot_file::{self, RobotFileError};
use omni_kin::KinError;
use omni_kin::travel::Travel;
use std::path::PathBuf;

/// Why runs could not be read: the robot description, the data, or data options that do not go together
/// (each message names the settings: [`named`]).
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The robot description could not be read.
    #[error(transparent)]
    Robot(#[from] RobotFileError),
    /// A data file could not be read as runs.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// A run moved to the base, or given its measured end pose, is no valid run.
    #[error(transparent)]
    Run(#[from] KinError),
    /// A run could not be cut into the windows of a relative reference.
    #[error("run {run}")]
    Windows {
        /// The run.
        run: String,
        /// Why.
        source: KinError,
    },
    /// `--gt-time-offset` on runs that have no ground-truth clock to shift.
    #[error(
        "{} changes nothing here: it applies to a {} file or to a ground-truth topic of a recording (MCAP, \
         rosbag2), and these runs have neither",
        named_with("gt_time_offset", offset_s),
        named("gt")
    )]
    OffsetUnused {
        /// The offset given. s.
        offset_s: f64,
    },
    /// `--gt-scans` with `--gt-kind end-pose`.
    #[error("--gt-scans {topic} does not go with --gt-kind end-pose: a lidar's path is a relative reference")]
    ScansWithEndPose {
        /// The LaserScan topic.
        topic: String,
    },
    /// `--gt-scans` with another source of ground truth (`flag`).
    #[error("{flag} does not go with {}: the lidar's path is the ground truth", named_with("gt_scans", topic))]
    ScansWith {
        /// The other option, named (`` `gt` ``, `` `gt_topic` ``).
        flag: &'static str,
        /// The LaserScan topic.
        topic: String,
    },
    /// `--gt-kind end-pose` without the table of measured end poses.
    #[error(
        "--gt-kind end-pose needs --gt FILE: the table of measured end poses (a header run,x_m,y_m,yaw_deg and one \
         row per recording; docs/formats.md, \"Measured end poses\"; `omnical plan --umbmark` writes one to fill in)"
    )]
    EndPoseWithoutTable,
    /// `--gt-kind end-pose` with an option (`flag`) that makes runs of something else than whole recordings.
    #[error(
        "{flag} does not go with --gt-kind end-pose: each recording is one run from its start mark to where it \
         stopped, measured by hand"
    )]
    EndPoseWith {
        /// The option (`--split`, `--gt-topic`).
        flag: &'static str,
    },
    /// A row of the end-pose table names no run read.
    #[error(
        "{}: line {line}: run {run:?} is not among the recordings read ({}): name each row after its recording's \
         file name without extension",
        file.display(),
        runs.join(", ")
    )]
    EndPoseOfNoRun {
        /// The end-pose table.
        file: PathBuf,
        /// The row's line (1-based).
        line: usize,
        /// The run it names.
        run: String,
        /// The runs read.
        runs: Vec<String>,
    },
    /// A run read has no row in the end-pose table.
    #[error(
        "run {run} has no measured end pose in {}: add its row (run,x_m,y_m,yaw_deg), or leave the recording out",
        file.display()
    )]
    NoEndPose {
        /// The run.
        run: String,
        /// The end-pose table.
        file: PathBuf,
    },
    /// A measured end pose far from where the wheels put its run (a value in another unit than its
    /// column's).
    #[error("{}: line {line}, column {column}: {what}", file.display())]
    EndPoseOff {
        /// The end-pose table.
        file: PathBuf,
        /// The row's line (1-based).
        line: usize,
        /// The column whose value is off.
        column: String,
        /// How far off, and the unit the value fits.
        what: String,
    },
    /// `--gt-window` without a relative reference.
    #[error(
        "{} changes nothing here: it is the window of a relative reference ({}: the ground truth is a sensor's \
         own motion, as lidar or visual odometry)",
        named_with("gt_window", window_s),
        named_with("gt_kind", "relative")
    )]
    WindowUnused {
        /// The window given. s.
        window_s: f64,
    },
    /// A relative reference that never moves within a window.
    #[error(
        "the relative reference of these {runs} runs never moves in a window of {window_s} s: nothing to compare \
         the wheels with (drive the robot, or check {} / {} names the sensor's path)",
        named("gt_topic"),
        named("gt")
    )]
    NeverMoves {
        /// The runs read.
        runs: usize,
        /// The window. s.
        window_s: f64,
    },
    /// The wheels, through the robot description's design, travel and turn far more or less than the ground
    /// truth: wheel data in another unit, or a design far from the robot.
    #[error(
        "through the design of {robot}, the wheels of {} travel {:.1} m and turn {:.1} rad where \
         their ground truth travels {:.1} m and turns {:.1} rad: {ratio:.2} times, beyond what a calibration \
         corrects. Are the joints in another unit (rpm, deg/s, encoder counts)? Declare it in the robot \
         description's [wheel_data] (docs/formats.md){}; otherwise check its radius_m and distances",
        run.as_ref().map_or_else(|| format!("these {runs} runs"), |r| format!("run {r}")),
        travel.wheels_m,
        travel.wheels_rad,
        travel.truth_m,
        travel.truth_rad,
        unit_hint(*ratio, *near_unit)
    )]
    WheelScale {
        /// The robot description.
        robot: robot_file::Source,
        /// The runs read.
        runs: usize,
        /// The one run judged, when all together were not off.
        run: Option<String>,
        /// Their travel, by the wheels and by the ground truth (boxed: the error stays small).
        travel: Box<Travel>,
        /// The wheels' distance over the ground truth's.
        ratio: f64,
        /// The unit read as rad/s whose factor the ratio is near, with that factor.
        near_unit: Option<(f64, &'static str)>,
    },
    /// `--gt-mount-start` where no mount is fitted.
    #[error(
        "{} does not go with {flag}: it starts the fit of a relative reference's sensor mount ({}, {})",
        named("gt_mount_start"),
        named_with("gt_kind", "relative"),
        named("gt_scans")
    )]
    MountStartWith {
        /// What it was given with: `` `gt_mount` `` (named), or an absolute reference.
        flag: &'static str,
    },
    /// A relative reference whose turning goes against the wheels': its frame is mirrored.
    #[error(
        "{reference} of {recordings}: the sensor's path turns against the wheels (its turn per turn of the design's \
         dead reckoning is {slope:.2}, explaining {:.0} % of its turning, over {pairs} stretches of about 1 s): its \
         frame is mirrored. {}",
        100.0 * explained,
        mirrored_fix(*lidar)
    )]
    MirroredReference {
        /// The reference: its topic or file, with its option.
        reference: String,
        /// The recordings or files it was read from, named.
        recordings: String,
        /// The reference is a lidar's scans (`--gt-scans`).
        lidar: bool,
        /// Sensor turn per base turn (least squares through zero).
        slope: f64,
        /// Share of the sensor's turning the slope explains.
        explained: f64,
        /// Stretches compared.
        pairs: usize,
    },
    /// A sensor's mount stated (`--gt-mount`, the recordings' static transforms) that its motion contradicts.
    #[error(
        "{reference} of {recordings}: the mount of {stated} contradicts the sensor's motion: against the design's \
         dead reckoning the sensor sits a further x {:.3} m, y {:.3} m, yaw {:.1}° (± {:.1} mm, ± {:.2}°) from where \
         it puts it. Fix it (a static transform: the URDF joint that robot_state_publisher publishes), or give the \
         mount: --gt-mount-start X,Y,YAW_DEG to fit it from there, --gt-mount X,Y,YAW_DEG to keep it as given \
         (either replaces the static transforms)",
        correction.x_m,
        correction.y_m,
        correction.theta_rad.to_degrees(),
        1e3 * position_std_m,
        yaw_std_rad.to_degrees()
    )]
    MountContradicts {
        /// The reference: its topic, with its option.
        reference: String,
        /// Where the contradicted mount came from: `--gt-mount`, the recordings' static transform.
        stated: &'static str,
        /// The recordings it was read from, named.
        recordings: String,
        /// The mount the motions give, on top of the stated one.
        correction: omni_kin::Pose2,
        /// Its position's standard error. m.
        position_std_m: f64,
        /// Its yaw's standard error. rad.
        yaw_std_rad: f64,
    },
    /// A `--gt-columns` / `--gt-units` setting that is not `KEY=VALUE`.
    #[error(
        "--gt-columns/--gt-units {setting:?}: expected KEY=VALUE (or, for --gt-columns, the list of columns present: t,x,y for positions only)"
    )]
    NotKeyValue {
        /// The setting as given.
        setting: String,
    },
    /// A ground-truth column or unit the CSV reader refuses.
    #[error(transparent)]
    GroundTruthColumns(#[from] CsvColumnsError),
}

/// What to do about a mirrored reference: a lidar's mount on /tf_static, another sensor's frame.
fn mirrored_fix(lidar: bool) -> &'static str {
    if lidar {
        "The lidar is mounted upside down and the recordings' static transform says upright (or none is \
         recorded), or the reverse: publish its true mount on /tf_static (base_link → the scans' frame, roll 180° \
         when upside down, as robot_state_publisher does from the URDF), so that its scans are read mirrored"
    } else {
        "The sensor is mounted upside down, or its odometry is published in a left-handed frame: flip its y axis \
         and its heading (y → −y, yaw → −yaw) before giving it as the reference"
    }
}

/// The note on a unit near the wheel-scale ratio: ` (… is near …, the factor of velocity = "rpm")`.
fn unit_hint(ratio: f64, near_unit: Option<(f64, &str)>) -> String {
    near_unit.map_or_else(String::new, |(f, u)| format!(" ({ratio:.2} is near {f:.3}, the factor of velocity = {u:?})"))
}
