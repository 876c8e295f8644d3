//! Subcommand implementations: load, call the library, format.

pub mod config;
pub mod demo;
pub mod diagnose;
pub mod eval;
pub mod explore;
pub mod export;
pub mod imu;
pub mod info;
pub mod init;
pub mod plan;
pub mod report;
pub mod scan_odometry;
pub mod shell;
pub mod sim_spec;
pub mod simulate;
pub mod train;

use crate::api::load::{DataOptions, LoadRequest};
use crate::dataset;
use omni_kin::reference::ReferenceKind;
use std::path::PathBuf;

/// Arguments of `omnical fleet`, which the Python wheel's console command runs (omnical.fleet, on Dask):
/// declared here once, parsed for it by `omni_cli::argv::fleet_request`; the native binary only
/// says where to find it.
#[derive(Debug, clap::Args)]
#[command(after_help = "Needs dask[distributed] (pip install \"omnical[fleet]\").")]
pub struct FleetArgs {
    /// The fleet: one folder per robot, one per session inside (`FLEET_DIR/<robot>/<session>/`); a
    /// robot.toml per robot folder or one in FLEET_DIR describes the robots.
    #[arg(value_name = "FLEET_DIR")]
    pub fleet_dir: PathBuf,
    /// Output folder: `OUT/<robot>/<session>/model.toml`, `OUT/fleet.csv` and `OUT/fleet.html`.
    #[arg(long)]
    pub out: PathBuf,
    /// A Dask scheduler (default: a local cluster).
    #[arg(long, value_name = "ADDRESS")]
    pub scheduler: Option<String>,
    /// Local worker processes.
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub workers: usize,
    /// Train's recipe (default, paper).
    #[arg(long, value_name = "NAME", default_value = "default")]
    pub preset: String,
    /// GA seed of every session.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,
    /// Base model to fit.
    #[arg(long, value_name = "KIND", default_value = "ik")]
    pub model: String,
    /// Which sessions to diagnose (auto: those whose cost is off).
    #[arg(long, value_parser = ["auto", "all", "none"], default_value = "auto")]
    pub diagnose: String,
    /// Arguments after `--` go to every `omnical train`; their data options (`--gt-scans /scan`, …) also
    /// to every diagnosis, so a session is diagnosed on the reference it was trained on.
    #[arg(last = true, value_name = "TRAIN_ARGS")]
    pub train_args: Vec<String>,
}

/// The error of a Python-side command asked of the native binary.
pub fn python_only(what: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "{what} runs on Dask from the Python wheel: `pip install \"omnical[fleet]\"` (or `pip install \".[fleet]\"` \
         from the repository) and run the `omnical` command it installs; this native binary has no Python"
    )
}

pub use crate::api::JSON_SCHEMA_VERSION;

/// Commands that produce no results of their own, so take no `--json`: `fleet` (the Python wheel's),
/// `completions` and `man` (their output is a script and a man page).
/// Every other subcommand flattens [`OutputArgs`]; tests/json.rs checks both lists against the parser.
pub const WITHOUT_RESULTS: &[&str] = &["fleet", "completions", "man"];

/// The output options of every command that produces results (one definition, flattened into each).
#[derive(Debug, Default, Clone, Copy, clap::Args)]
pub struct OutputArgs {
    /// Print the results as one JSON document on stdout instead of text (`schema_version`, `command`, and
    /// the command's fields, SI units: docs/json.md). Notes and progress stay on stderr.
    #[arg(long)]
    pub json: bool,
}

/// Prints `doc` (a JSON object) on stdout, pretty, with `schema_version` and `command` added.
pub fn print_json(command: &str, doc: serde_json::Value) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(&json_document(command, doc)?)?);
    Ok(())
}

/// `doc` with `schema_version` ([`JSON_SCHEMA_VERSION`]) and `command` added.
pub fn json_document(command: &str, doc: serde_json::Value) -> anyhow::Result<serde_json::Value> {
    let serde_json::Value::Object(mut fields) = doc else {
        anyhow::bail!("the --json document of {command} is not an object (a bug)");
    };
    fields.insert("schema_version".into(), JSON_SCHEMA_VERSION.into());
    fields.insert("command".into(), command.into());
    Ok(serde_json::Value::Object(fields))
}

/// The help heading of [`DataArgs`].
pub const DATA_OPTIONS: &str = "Data options";

/// The robot the data was recorded on (docs/formats.md, "Robot description").
#[derive(Debug, Default, clap::Args)]
pub struct RobotArgs {
    /// The robot description: a robot.toml file, or `apr02` for the paper's robot. Default: a robot.toml
    /// beside the data (the first RUNS argument's folder) or in the working directory.
    #[arg(long, value_name = "FILE|apr02")]
    pub robot: Option<String>,
}

/// Options shared by commands that read runs, listed under "Data options" in every command's help.
#[derive(Debug, clap::Args)]
#[command(next_help_heading = DATA_OPTIONS)]
pub struct DataArgs {
    /// The robot description (design geometry, joint names, topics).
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Wheel joint names in wheel order (MCAP JointState), comma-separated. Default: the robot
    /// description's joints, else wheel_a,wheel_b,wheel_c.
    #[arg(long, value_delimiter = ',')]
    pub joints: Option<Vec<String>>,
    /// MCAP topic of the wheel JointState (default: the only one).
    #[arg(long)]
    pub joints_topic: Option<String>,
    /// MCAP topic of the ground truth (default: the only map/world-frame pose source).
    #[arg(long)]
    pub gt_topic: Option<String>,
    /// Parent frame of the ground truth in a TF topic (MCAP), e.g. `map`.
    #[arg(long)]
    pub gt_parent_frame: Option<String>,
    /// Child frame of the ground truth in a TF topic (MCAP), e.g. `base_link`.
    #[arg(long)]
    pub gt_child_frame: Option<String>,
    /// Ground truth from a separate file instead of a topic: a TUM (`t x y z qx qy qz qw`) or CSV file for
    /// one recording, or a folder of files named after the recordings (`rec.tum`, `rec.csv`). Default: the
    /// robot description's `[ground_truth] file`, else a topic of the recording.
    #[arg(long, value_name = "FILE|DIR")]
    pub gt: Option<PathBuf>,
    /// Clock offset of the `--gt` file: wheel time = ground-truth time + SECONDS (s). Default: estimated from
    /// the data (reported with its standard error).
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    pub gt_time_offset: Option<f64>,
    /// CSV columns of the `--gt` file, e.g. `t=stamp_ns,x=pos_x_mm,y=pos_y_mm,yaw=heading_deg` (default t, x,
    /// y, yaw, or a quaternion qx, qy, qz, qw).
    #[arg(long, value_delimiter = ',', value_name = "KEY=COLUMN")]
    pub gt_columns: Vec<String>,
    /// Units of the `--gt` CSV columns, e.g. `time=ns,length=mm,angle=deg` (default s, m, rad).
    #[arg(long, value_delimiter = ',', value_name = "KEY=UNIT")]
    pub gt_units: Vec<String>,
    /// What the ground truth measures: `absolute`, the pose of a point on the robot in a fixed world frame
    /// (motion capture); `relative`, a sensor's own motion (lidar or visual odometry) at an unknown mount,
    /// compared over windows (`--gt-window`), the mount fitted with the wheels; `end-pose`, hand-measured
    /// end poses (a tape measure, no motion capture): --gt names a table run,x_m,y_m,yaw_deg, each in the
    /// frame of the run's start (`plan --umbmark --out` writes one to fill in). Default absolute.
    #[arg(long, value_name = "KIND", value_parser = crate::cli::choice::<ReferenceKind>())]
    pub gt_kind: Option<ReferenceKind>,
    /// The window of a relative reference (s): the model's motion is compared with the sensor's over
    /// windows this long, so that the reference's drift stays small. Default 4.
    #[arg(long, value_name = "SECONDS")]
    pub gt_window: Option<f64>,
    /// The measured point's pose in the base frame, when known (from the robot's URDF or a tape measure):
    /// X,Y in metres, YAW in degrees. The ground truth is moved to the base by it, and no mount is fitted.
    #[arg(long, value_name = "X,Y,YAW_DEG", value_parser = parse_mount, allow_hyphen_values = true)]
    pub gt_mount: Option<omni_kin::Pose2>,
    /// Where the fit starts the sensor's mount of a relative reference (`--gt-kind relative`, `--gt-scans`),
    /// which it then fits with the wheels: X,Y in metres, YAW in degrees. Default: found from the motions
    /// (the sensor's against the design's dead reckoning, any yaw); a lidar's static transforms are not used.
    #[arg(long, value_name = "X,Y,YAW_DEG", value_parser = parse_mount, allow_hyphen_values = true, conflicts_with = "gt_mount")]
    pub gt_mount_start: Option<omni_kin::Pose2>,
    /// The ground truth from a 2D lidar without motion capture: the scans of this LaserScan topic (e.g.
    /// `/scan`) matched scan to scan into the lidar's own path, a relative reference (`--gt-kind relative`
    /// implied); its mount from the recording's static transforms when there (/tf_static, or fixed pairs
    /// republished on /tf; from base_link, else base_footprint), corrected by the fit.
    #[arg(long, value_name = "TOPIC")]
    pub gt_scans: Option<String>,
    /// Cut recordings into runs: a bare number at standstills at least this long (s); a length with its
    /// unit (20s, 2min) into pieces of that length, for a robot that never stops.
    #[arg(long, value_name = "N|LENGTH", value_parser = parse_split)]
    pub split: Option<Split>,
    /// Skip runs that fail to load (they are listed) instead of stopping.
    #[arg(long)]
    pub skip_invalid: bool,
    /// Encoder ticks per wheel revolution, for CSV files with tick columns.
    #[arg(long)]
    pub ticks_per_rev: Option<f64>,
    /// Refuse input files (CSV, MCAP) larger than this (MiB); each is read into memory whole.
    #[arg(long, value_name = "MIB", default_value_t = dataset::DEFAULT_MAX_FILE_BYTES >> 20)]
    pub max_file_mb: u64,
}

/// How `--split` cuts recordings into runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Split {
    /// At standstills at least this long (a bare number). s.
    Standstill(f64),
    /// Into pieces of this length (a number with its unit, `20s`, `2min`). s.
    Every(f64),
}

impl std::fmt::Display for Split {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Standstill(s) => write!(f, "at standstills of {s} s"),
            Self::Every(s) => write!(f, "into pieces of {s} s"),
        }
    }
}

/// `N` (standstills of N s) or `Ns` / `Nmin` (pieces of that length).
fn parse_split(text: &str) -> Result<Split, String> {
    let t = text.trim();
    let (number, seconds_per_unit, every) = if let Some(n) = t.strip_suffix("min") {
        (n, 60.0, true)
    } else if let Some(n) = t.strip_suffix('s') {
        (n, 1.0, true)
    } else {
        (t, 1.0, false)
    };
    let v: f64 = number.trim().parse().map_err(|_| {
        format!("{text:?}: expected a number of seconds (standstills that long) or a length with its unit (20s, 2min)")
    })?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("{text:?}: the length must be a finite number > 0"));
    }
    Ok(if every { Split::Every(v * seconds_per_unit) } else { Split::Standstill(v) })
}

/// `X,Y,YAW_DEG` (m, m, degrees) as a pose.
fn parse_mount(s: &str) -> Result<omni_kin::Pose2, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|_| format!("{x:?} is not a number")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, yaw] if v.iter().all(|v| v.is_finite()) => Ok(omni_kin::Pose2::new(x, y, yaw.to_radians())),
        _ => Err(format!("expected X,Y,YAW_DEG (metres, metres, degrees), got {} values", v.len())),
    }
}

impl DataArgs {
    /// The data options these flags give.
    pub fn options(&self) -> DataOptions {
        DataOptions {
            robot: self.robot.robot.clone(),
            joints: self.joints.clone(),
            joints_topic: self.joints_topic.clone(),
            gt_topic: self.gt_topic.clone(),
            gt_parent_frame: self.gt_parent_frame.clone(),
            gt_child_frame: self.gt_child_frame.clone(),
            gt: self.gt.clone(),
            gt_time_offset_s: self.gt_time_offset,
            gt_columns: self.gt_columns.clone(),
            gt_units: self.gt_units.clone(),
            gt_kind: self.gt_kind.unwrap_or_default(),
            gt_window_s: self.gt_window,
            gt_mount: self.gt_mount,
            gt_mount_start: self.gt_mount_start,
            gt_scans: self.gt_scans.clone(),
            split_s: match self.split {
                Some(Split::Standstill(s)) => Some(s),
                _ => None,
            },
            split_every_s: match self.split {
                Some(Split::Every(s)) => Some(s),
                _ => None,
            },
            skip_invalid: self.skip_invalid,
            ticks_per_rev: self.ticks_per_rev,
            max_file_mb: self.max_file_mb,
        }
    }

    /// The runs at `paths`, read with these options.
    pub fn request(&self, paths: &[PathBuf]) -> LoadRequest {
        LoadRequest::new(paths, &self.options())
    }
}
