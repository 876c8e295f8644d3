//! Reading runs: which inputs, for which robot, with which data options ([`LoadRequest`]); the notes of
//! a load said once on stderr.

use crate::dataset::{self, Dataset, DatasetError, LoadOptions};
use crate::robot_file::{self, RobotFileError};
use omni_kin::KinError;
use omni_kin::reference::ReferenceKind;
use omni_kin::travel::Travel;
use std::path::PathBuf;

/// Why runs could not be read: the robot description, the data, or data options that do not go together
/// (each message names the flags).
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
        "--gt-time-offset {offset_s} changes nothing here: it applies to a --gt file or to a ground-truth topic of \
         a recording (MCAP, rosbag2), and these runs have neither"
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
    #[error("{flag} does not go with --gt-scans {topic}: the lidar's path is the ground truth")]
    ScansWith {
        /// The other option (`--gt`, `--gt-topic`).
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
    /// `--gt-window` without a relative reference.
    #[error(
        "--gt-window {window_s} changes nothing here: it is the window of a relative reference (--gt-kind \
         relative: the ground truth is a sensor's own motion, as lidar or visual odometry)"
    )]
    WindowUnused {
        /// The window given. s.
        window_s: f64,
    },
    /// A relative reference that never moves within a window.
    #[error(
        "the relative reference of these {runs} runs never moves in a window of {window_s} s: nothing to compare \
         the wheels with (drive the robot, or check --gt-topic / --gt names the sensor's path)"
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
        "through the design of {robot}, the wheels of these {runs} runs travel {:.1} m and turn {:.1} rad where \
         their ground truth travels {:.1} m and turns {:.1} rad: {ratio:.2} times, beyond what a calibration \
         corrects. Are the joints in another unit (rpm, deg/s, encoder counts)? Declare it in the robot \
         description's [wheel_data] (docs/formats.md){}; otherwise check its radius_m and distances",
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
        /// Their travel, by the wheels and by the ground truth.
        travel: Travel,
        /// The wheels' distance over the ground truth's.
        ratio: f64,
        /// The unit read as rad/s whose factor the ratio is near, with that factor.
        near_unit: Option<(f64, &'static str)>,
    },
    /// A `--gt-columns` / `--gt-units` setting that is not `KEY=VALUE`.
    #[error("--gt-columns/--gt-units {setting:?}: expected KEY=VALUE")]
    NotKeyValue {
        /// The setting as given.
        setting: String,
    },
    /// A ground-truth column or unit the CSV reader refuses (its own message).
    #[error("{0}")]
    GroundTruthColumns(String),
}

/// The note on a unit near the wheel-scale ratio: ` (… is near …, the factor of velocity = "rpm")`.
fn unit_hint(ratio: f64, near_unit: Option<(f64, &str)>) -> String {
    near_unit.map_or_else(String::new, |(f, u)| format!(" ({ratio:.2} is near {f:.3}, the factor of velocity = {u:?})"))
}

/// How runs are read: the robot description and the options that fill or override it (the command
/// line's "Data options", Python's `load` keywords). `Default` is what no option gives.
#[derive(Clone, Debug, PartialEq)]
pub struct DataOptions {
    /// The robot description: a robot.toml path or `apr02`; `None`: a robot.toml beside the data (the first
    /// input's folder) or in the working directory.
    pub robot: Option<String>,
    /// Wheel joint names in wheel order (MCAP JointState); `None`: the robot description's, else the default.
    pub joints: Option<Vec<String>>,
    /// MCAP topic of the wheel JointState (`None`: the only one).
    pub joints_topic: Option<String>,
    /// MCAP topic of the ground truth (`None`: the only map/world-frame pose source).
    pub gt_topic: Option<String>,
    /// Parent frame of the ground truth in a TF topic.
    pub gt_parent_frame: Option<String>,
    /// Child frame of the ground truth in a TF topic.
    pub gt_child_frame: Option<String>,
    /// Ground truth from a separate file or folder instead of a topic.
    pub gt: Option<PathBuf>,
    /// Clock offset of the ground-truth file: wheel time = ground-truth time + this (s); `None`: estimated.
    pub gt_time_offset_s: Option<f64>,
    /// CSV columns of the ground-truth file, `KEY=COLUMN` each (checked when a file is read).
    pub gt_columns: Vec<String>,
    /// Units of the ground-truth CSV columns, `KEY=UNIT` each (checked when a file is read).
    pub gt_units: Vec<String>,
    /// What the ground truth measures: a fixed world frame's pose (motion capture), or a sensor's own motion
    /// (lidar or visual odometry), compared over windows with the sensor's mount fitted.
    pub gt_kind: ReferenceKind,
    /// The window of a relative reference (s); `None`: [`omni_kin::reference::DEFAULT_WINDOW_S`].
    pub gt_window_s: Option<f64>,
    /// The measured point's (the sensor's, the marker's) pose in the base frame, when known (a URDF, a tape
    /// measure): the ground truth is moved to the base by it, and no fit adds a mount.
    pub gt_mount: Option<omni_kin::Pose2>,
    /// The ground truth from a 2D lidar: this LaserScan topic's scans matched into the sensor's own path, a
    /// relative reference (`--gt-kind relative` is implied).
    pub gt_scans: Option<String>,
    /// Cut MCAP files into runs at standstills at least this long (s).
    pub split_s: Option<f64>,
    /// Skip runs that fail to load (listed) instead of stopping.
    pub skip_invalid: bool,
    /// Encoder ticks per wheel revolution (CSV tick columns).
    pub ticks_per_rev: Option<f64>,
    /// Largest input file (MiB); each is read into memory whole.
    pub max_file_mb: u64,
}

impl Default for DataOptions {
    fn default() -> Self {
        Self {
            robot: None,
            joints: None,
            joints_topic: None,
            gt_topic: None,
            gt_parent_frame: None,
            gt_child_frame: None,
            gt: None,
            gt_time_offset_s: None,
            gt_columns: Vec::new(),
            gt_units: Vec::new(),
            gt_kind: ReferenceKind::Absolute,
            gt_window_s: None,
            gt_mount: None,
            gt_scans: None,
            split_s: None,
            skip_invalid: false,
            ticks_per_rev: None,
            max_file_mb: dataset::DEFAULT_MAX_FILE_BYTES >> 20,
        }
    }
}

impl DataOptions {
    /// The wheel joint names runs of `ds` were read with: [`DataOptions::joints`], else the robot
    /// description's, else the default `wheel_a`, `wheel_b`, `wheel_c`.
    pub fn wheel_joints(&self, ds: &Dataset) -> Vec<String> {
        let mut mcap =
            dataset::mcap::McapOptions { wheel_joints: self.joints.clone().unwrap_or_default(), ..Default::default() };
        robot_file::fill_mcap_options(&mut mcap, self.joints.is_none(), ds.robot_file.as_ref());
        mcap.wheel_joints
    }
}

/// Runs to read: the inputs (files and folders), the data options, and whether to keep the runs' recorded
/// odometry (only `export` shows it, and it takes as much memory as the wheel data).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadRequest {
    /// Files and folders.
    pub paths: Vec<PathBuf>,
    /// How to read them.
    pub data: DataOptions,
    /// Keep the runs' recorded odometry.
    pub recorded_odometry: bool,
    /// Read the wheels only, each run's ground truth a placeholder (at rest at the origin at its first and
    /// last wheel sample) for another reference to replace (`omnical imu`).
    pub wheels_only: bool,
}

impl LoadRequest {
    /// `paths` read with `data`, without the recorded odometry.
    pub fn new(paths: &[PathBuf], data: &DataOptions) -> Self {
        Self { paths: paths.to_vec(), data: data.clone(), recorded_odometry: false, wheels_only: false }
    }

    /// The robot description the runs are read for: [`DataOptions::robot`], else one found beside the data
    /// or in the working directory ([`robot_file::resolve`]).
    pub fn robot(&self) -> Result<Option<robot_file::RobotFile>, robot_file::RobotFileError> {
        robot_file::resolve(self.data.robot.as_deref(), &self.paths)
    }

    /// Reads the runs, saying what was skipped or noticed on stderr.
    pub fn load(&self) -> Result<Dataset, LoadError> {
        let ds = self.load_silently()?;
        say_load_notes(&[&ds]);
        Ok(ds)
    }

    /// Reads the runs as [`LoadRequest::load`] does, notes left in the dataset.
    fn load_silently(&self) -> Result<Dataset, LoadError> {
        let started = std::time::Instant::now();
        let robot = self.robot()?;
        if let Some(r) = &robot {
            robot_file::announce(&r.source);
        }
        let ds = self.read_for_robot(robot)?;
        tracing::info!(
            "read {} run{} from {} in {:.2} s",
            ds.runs.len(),
            if ds.runs.len() == 1 { "" } else { "s" },
            self.paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
            started.elapsed().as_secs_f64()
        );
        Ok(ds)
    }

    /// Reads the runs for the robot `robot` (resolved by [`LoadRequest::robot`]: its joints, topics and
    /// ground-truth file fill what the data options leave open), printing nothing: notes, skipped inputs and
    /// ground-truth clocks stay in the dataset. The Python binding's `load`.
    pub fn read_for_robot(&self, robot: Option<robot_file::RobotFile>) -> Result<Dataset, LoadError> {
        let data = &self.data;
        let recorded_odometry = self.recorded_odometry;
        let mcap = self.mcap_options(robot.as_ref())?;
        let scans = scans_topic(data)?;
        let end_poses = end_pose_file(data)?;
        let ground_truth = if mcap.wheels_only { None } else { ground_truth_options(data, robot.as_ref())? };
        let opts = LoadOptions {
            skip_invalid: data.skip_invalid,
            ticks_per_rev: data.ticks_per_rev,
            mcap,
            recorded_odometry,
            max_file_bytes: data.max_file_mb.saturating_mul(1 << 20),
            ground_truth,
            csv_joints: csv_joints(data, robot.as_ref()),
            scans: scans.map(|t| (t, crate::lidar::MatchSettings::default())),
        };
        let mut ds = dataset::load(&self.paths, &opts)?;
        // An option that changes nothing is an error: the offset applies to a --gt file or to the ground-truth
        // topic of a recording, and every run so read reports its clock.
        if let Some(offset_s) = data.gt_time_offset_s
            && ds.ground_truth_clocks.is_empty()
        {
            return Err(LoadError::OffsetUnused { offset_s });
        }
        if let Some(file) = &end_poses {
            set_end_poses(&mut ds, file)?;
        } else if let Some(r) = &robot {
            check_wheel_scale(&ds, r)?;
        }
        ds.robot_file = robot;
        move_to_base(&mut ds, data)?;
        cut_into_windows(&mut ds, data)?;
        Ok(ds)
    }

    /// How the ROS recordings are read for the robot `robot`: the data options over the robot description's
    /// joints, topics and wheel units.
    pub fn mcap_options(&self, robot: Option<&robot_file::RobotFile>) -> Result<dataset::mcap::McapOptions, LoadError> {
        let data = &self.data;
        let mut mcap = dataset::mcap::McapOptions {
            wheel_joints: data.joints.clone().unwrap_or_default(),
            joints_topic: data.joints_topic.clone(),
            truth_topic: data.gt_topic.clone(),
            truth_parent_frame: data.gt_parent_frame.clone(),
            truth_child_frame: data.gt_child_frame.clone(),
            split: data.split_s,
            skip_invalid: data.skip_invalid,
            recorded_odometry: self.recorded_odometry,
            ..Default::default()
        };
        robot_file::fill_mcap_options(&mut mcap, data.joints.is_none(), robot);
        mcap.wheels_only = self.wheels_only || scans_topic(data)?.is_some() || end_pose_file(data)?.is_some();
        if mcap.wheels_only || ground_truth_options(data, robot)?.is_none() {
            mcap.truth_time_offset_s = data.gt_time_offset_s;
        }
        Ok(mcap)
    }

    /// Where the ground truth comes from when it is not a topic of the recordings (a `--gt` file, the
    /// robot description's ground-truth file, `--gt-scans`, measured end poses), in words; `None`: a topic.
    pub fn truth_elsewhere(&self, robot: Option<&robot_file::RobotFile>) -> Result<Option<String>, LoadError> {
        let data = &self.data;
        if let Some(topic) = scans_topic(data)? {
            return Ok(Some(format!("the lidar's path from scan matching (--gt-scans {topic})")));
        }
        if let Some(file) = end_pose_file(data)? {
            return Ok(Some(format!("the measured end poses in {}", file.display())));
        }
        Ok(ground_truth_options(data, robot)?.map(|g| format!("the file {}", g.path.display())))
    }
}

/// The LaserScan topic of `--gt-scans`, checked against the other options: a lidar is a relative
/// reference, and the only ground truth.
fn scans_topic(data: &DataOptions) -> Result<Option<String>, LoadError> {
    let Some(topic) = &data.gt_scans else { return Ok(None) };
    if data.gt_kind == ReferenceKind::EndPose {
        return Err(LoadError::ScansWithEndPose { topic: topic.clone() });
    }
    for (set, flag) in [(data.gt.is_some(), "--gt"), (data.gt_topic.is_some(), "--gt-topic")] {
        if set {
            return Err(LoadError::ScansWith { flag, topic: topic.clone() });
        }
    }
    Ok(Some(topic.clone()))
}

/// The measured end-pose table of `--gt-kind end-pose` (its `--gt`), checked against the other options.
fn end_pose_file(data: &DataOptions) -> Result<Option<PathBuf>, LoadError> {
    if data.gt_kind != ReferenceKind::EndPose {
        return Ok(None);
    }
    let Some(file) = &data.gt else { return Err(LoadError::EndPoseWithoutTable) };
    for (set, flag) in [(data.split_s.is_some(), "--split"), (data.gt_topic.is_some(), "--gt-topic")] {
        if set {
            return Err(LoadError::EndPoseWith { flag });
        }
    }
    Ok(Some(file.clone()))
}

/// Each run's placeholder end replaced by its measured end pose from `file`; a row naming no run read, or a
/// run without a row, is an error naming both.
fn set_end_poses(ds: &mut Dataset, file: &std::path::Path) -> Result<(), LoadError> {
    let measured = dataset::end_poses::read(file)?;
    let names: Vec<&str> = ds.runs.iter().map(omni_kin::Run::name).collect();
    if let Some(e) = measured.iter().find(|e| !names.contains(&e.run.as_str())) {
        return Err(LoadError::EndPoseOfNoRun {
            file: file.to_path_buf(),
            line: e.line,
            run: e.run.clone(),
            runs: names.iter().map(|n| n.to_string()).collect(),
        });
    }
    let runs = std::mem::take(&mut ds.runs);
    ds.runs = runs
        .into_iter()
        .map(|run| {
            let Some(e) = measured.iter().find(|e| e.run == run.name()) else {
                return Err(LoadError::NoEndPose { run: run.name().to_string(), file: file.to_path_buf() });
            };
            let mut d = run.into_data();
            d.truth[1].pose = e.pose;
            Ok(omni_kin::Run::new(d)?)
        })
        .collect::<Result<_, LoadError>>()?;
    ds.notes.push(format!(
        "measured end poses: {} runs from {}, each from rest at the origin at its first wheel sample to its measured \
         pose at its last (the end-pose cost)",
        ds.runs.len(),
        file.display()
    ));
    ds.reference = ReferenceKind::EndPose;
    Ok(())
}

/// The ground truth of every run moved from the measured point to the base by `--gt-mount`, with a note.
fn move_to_base(ds: &mut Dataset, data: &DataOptions) -> Result<(), LoadError> {
    let Some(mount) = data.gt_mount else { return Ok(()) };
    let to_base = mount.inverse();
    let runs = std::mem::take(&mut ds.runs);
    ds.runs = runs
        .into_iter()
        .map(|run| {
            let mut d = run.into_data();
            for p in &mut d.truth {
                p.pose = p.pose.compose(&to_base);
            }
            omni_kin::Run::new(d)
        })
        .collect::<Result<_, _>>()?;
    ds.notes.push(format!(
        "ground truth moved to the base from the measured point at x {:.4} m, y {:.4} m, yaw {:.3}° (--gt-mount)",
        mount.x_m,
        mount.y_m,
        mount.theta_rad.to_degrees()
    ));
    ds.mount = Some(mount);
    Ok(())
}

/// A relative reference's runs replaced by their windows ([`omni_kin::reference::windows`]), with a note;
/// `--gt-window` without `--gt-kind relative` is an error (it would change nothing).
fn cut_into_windows(ds: &mut Dataset, data: &DataOptions) -> Result<(), LoadError> {
    use omni_kin::reference::{DEFAULT_WINDOW_S, windows};
    if data.gt_kind != ReferenceKind::Relative && data.gt_scans.is_none() {
        if let Some(window_s) = data.gt_window_s {
            return Err(LoadError::WindowUnused { window_s });
        }
        return Ok(());
    }
    let window_s = data.gt_window_s.unwrap_or(DEFAULT_WINDOW_S);
    let (mut runs, mut still, mut gaps) = (Vec::new(), 0, 0);
    let mut renamed: Vec<(String, Vec<String>)> = Vec::new();
    for run in &ds.runs {
        let w = windows(run, window_s).map_err(|source| LoadError::Windows { run: run.name().to_string(), source })?;
        still += w.still;
        gaps += w.gaps;
        renamed.push((run.name().to_string(), w.runs.iter().map(|r| r.name().to_string()).collect()));
        runs.extend(w.runs);
    }
    if runs.is_empty() {
        return Err(LoadError::NeverMoves { runs: ds.runs.len(), window_s });
    }
    for d in &mut ds.declared {
        d.runs = d
            .runs
            .iter()
            .flat_map(|n| renamed.iter().filter(move |(r, _)| r == n).flat_map(|(_, w)| w.clone()))
            .collect();
    }
    for (run, names) in &renamed {
        if let Some(origin) = ds.time_origins_s.remove(run) {
            ds.time_origins_s.extend(names.iter().map(|n| (n.clone(), origin)));
        }
        if let Some(recording) = ds.recordings.remove(run) {
            ds.recordings.extend(names.iter().map(|n| (n.clone(), recording.clone())));
        }
    }
    ds.notes.push(format!(
        "relative reference: {} runs cut into {} windows of at most {window_s} s ({still} where the reference stands \
         still dropped{}){}",
        ds.runs.len(),
        runs.len(),
        if gaps > 0 { format!(", {gaps} gaps in the reference") } else { String::new() },
        if ds.mount.is_none() { "; the sensor's mount is fitted with the wheels" } else { "" },
    ));
    ds.runs = runs;
    ds.reference = ReferenceKind::Relative;
    Ok(())
}

/// Ground truth must have gone this far (m) or turned this much (rad) to judge the wheels' scale.
const SCALE_MIN_M: f64 = 1.0;
const SCALE_MIN_RAD: f64 = std::f64::consts::PI;
/// A calibration corrects a few per cent; the wheels' distance or turning off by more than this factor
/// from the ground truth's is wheel data in another unit, or a design far from the robot.
const SCALE_MAX_FACTOR: f64 = 3.0;

/// Refuses runs whose wheels, through the robot description's design, travel and turn more than
/// [`SCALE_MAX_FACTOR`] times more, or less, than their ground truth (both measurable, both off):
/// joints in rpm, degrees or counts read as rad/s, or a radius in the wrong unit.
fn check_wheel_scale(ds: &Dataset, robot: &robot_file::RobotFile) -> Result<(), LoadError> {
    use std::f64::consts::TAU;
    let Ok(ik) = robot.description.design_ik() else { return Ok(()) };
    let travel = omni_kin::travel::Travel::of(&ds.runs, &ik);
    let (Some(ratio), Some(turning)) = (travel.distance_ratio(SCALE_MIN_M), travel.turning_ratio(SCALE_MIN_RAD)) else {
        return Ok(());
    };
    // A unit scales distance and turning alike; one alone off is the data's or the design's own business.
    let (lo, hi) = (1.0 / SCALE_MAX_FACTOR, SCALE_MAX_FACTOR);
    if !(ratio > hi && turning > hi || ratio < lo && turning < lo) {
        return Ok(());
    }
    // The factor of a unit read as rad/s, within what a calibration corrects besides.
    let units = [(60.0 / TAU, "rpm"), (360.0 / TAU, "deg_s"), (TAU.recip(), "rev_s")];
    let near_unit = units.into_iter().find(|(f, _)| (ratio / f - 1.0).abs() < 0.15);
    Err(LoadError::WheelScale { robot: robot.source.clone(), runs: ds.runs.len(), travel, ratio, near_unit })
}

/// Training runs and held-out runs (`None` when `held_out` is empty), read as [`LoadRequest::load`] does,
/// with the notes of both said once: a note both sets raise is one line with the count of every file.
pub fn load_with_held_out(
    runs: &[PathBuf],
    held_out: &[PathBuf],
    data: &DataOptions,
) -> Result<(Dataset, Option<Dataset>), LoadError> {
    let train = LoadRequest::new(runs, data).load_silently()?;
    let held = if held_out.is_empty() { None } else { Some(LoadRequest::new(held_out, data).load_silently()?) };
    if let Some(h) = &held {
        dataset::check_same_robot(train.robot_kind.as_ref(), h.robot_kind.as_ref())?;
    }
    say_load_notes(&[Some(&train), held.as_ref()].into_iter().flatten().collect::<Vec<_>>());
    Ok((train, held))
}

/// The joints CSV runs are read by: the joints option, else a robot description file's. The built-in
/// `apr02`'s names are the simulator's placeholders, so with it each file keeps its own column order.
fn csv_joints(data: &DataOptions, robot: Option<&robot_file::RobotFile>) -> Vec<String> {
    let from_file = robot.filter(|r| r.source != robot_file::Source::Builtin).map(|r| r.description.joints());
    data.joints.clone().or(from_file).unwrap_or_default()
}

/// Says the datasets' notes on stderr, each distinct note once with the count of the files that raised it
/// (the same note from many files differs only in the file name before its first `: `), then skipped
/// inputs (shown even with `-q`) and ground-truth clocks.
fn say_load_notes(sets: &[&Dataset]) {
    let mut seen: Vec<(&str, &str, usize)> = Vec::new();
    for n in sets.iter().flat_map(|ds| &ds.notes) {
        let key = n.split_once(": ").map_or(n.as_str(), |(_, rest)| rest);
        match seen.iter_mut().find(|(k, _, _)| *k == key) {
            Some(entry) => entry.2 += 1,
            None => seen.push((key, n, 1)),
        }
    }
    for (_, first, count) in seen {
        match count {
            1 => crate::note!("note: {first}"),
            2 => crate::note!("note: {first} (and 1 more file)"),
            _ => crate::note!("note: {first} (and {} more files)", count - 1),
        }
    }
    for s in sets.iter().flat_map(|ds| &ds.skipped) {
        tracing::warn!(target: crate::logging::NOTE, "skipped {}: {}", s.source, s.reason);
    }
    for c in sets.iter().flat_map(|ds| &ds.ground_truth_clocks) {
        crate::note!("{}", c.describe());
    }
}

/// `--gt` and its options, over the robot description's `[ground_truth]` (its `file` relative to the
/// description's folder).
fn ground_truth_options(
    data: &DataOptions,
    robot: Option<&robot_file::RobotFile>,
) -> Result<Option<dataset::ground_truth::GroundTruthOptions>, LoadError> {
    let from_robot = robot.and_then(|r| r.description.ground_truth.as_ref().map(|g| (r, g)));
    let path = match (&data.gt, from_robot.and_then(|(r, g)| g.file.as_ref().map(|f| (r, f)))) {
        (Some(p), _) => p.clone(),
        (None, Some((r, file))) => match &r.source {
            robot_file::Source::Flag(p) | robot_file::Source::Discovered(p) => {
                p.parent().unwrap_or(std::path::Path::new("")).join(file)
            }
            robot_file::Source::Builtin => PathBuf::from(file),
        },
        (None, None) => return Ok(None),
    };
    let mut csv = dataset::ground_truth::CsvColumns::default();
    let settings = |list: &[String]| -> Vec<(String, String)> {
        list.iter()
            .filter_map(|kv| kv.split_once('=').map(|(k, v)| (k.trim().to_string(), v.trim().to_string())))
            .collect()
    };
    let (mut columns, mut units) = (Vec::new(), Vec::new());
    if let Some((_, g)) = from_robot {
        columns.extend(g.columns.iter().map(|(k, v)| (k.clone(), v.clone())));
        units.extend(g.units.iter().map(|(k, v)| (k.clone(), v.clone())));
    }
    if let Some(kv) = data.gt_columns.iter().chain(&data.gt_units).find(|kv| !kv.contains('=')) {
        return Err(LoadError::NotKeyValue { setting: kv.clone() });
    }
    columns.extend(settings(&data.gt_columns));
    units.extend(settings(&data.gt_units));
    for (k, v) in &columns {
        csv.set_column(k, v).map_err(LoadError::GroundTruthColumns)?;
    }
    for (k, v) in &units {
        csv.set_unit(k, v).map_err(LoadError::GroundTruthColumns)?;
    }
    let time_offset_s = data.gt_time_offset_s.or(from_robot.and_then(|(_, g)| g.time_offset_s));
    Ok(Some(dataset::ground_truth::GroundTruthOptions { path, time_offset_s, csv }))
}
