//! Reading runs: which inputs, for which robot, with which data options ([`LoadRequest`]); the notes of
//! a load said once on stderr.
//!
//! # Submodules
//! - `error.rs`: [`LoadError`], every way a load fails.
//! - `options.rs`: [`DataOptions`], and what they resolve to over the robot description: the ground-truth
//!   file, `--gt-scans`, the measured end poses, the CSV joints.
//! - `reference.rs`: the ground truth of the runs read: measured end poses set, moved to the base, cut into
//!   the windows of a relative reference; the wheel-scale check.

mod end_pose_check;
mod error;
mod options;
mod reference;

pub use error::LoadError;
pub use options::DataOptions;

use crate::api::settings::named_with;
use crate::dataset::{self, Dataset, LoadOptions, Note};
use crate::robot_file;
use options::{csv_joints, end_pose_file, ground_truth_options, scans_topic};
use reference::{check_wheel_scale, cut_into_windows, move_to_base, set_end_poses, start_sensor_mount};
use std::path::PathBuf;

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
            paths_text(&self.paths),
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
            scan_mount_given: data.gt_mount.is_some() || data.gt_mount_start.is_some(),
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
            set_end_poses(&mut ds, file, robot.as_ref())?;
        } else if let Some(r) = &robot {
            check_wheel_scale(&mut ds, r)?;
        }
        ds.robot_file = robot;
        move_to_base(&mut ds, data)?;
        cut_into_windows(&mut ds, data)?;
        start_sensor_mount(&mut ds, data)?;
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
            split_every_s: data.split_every_s,
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
            return Ok(Some(format!("the lidar's path from scan matching ({})", named_with("gt_scans", &topic))));
        }
        if let Some(file) = end_pose_file(data)? {
            return Ok(Some(format!("the measured end poses in {}", file.display())));
        }
        Ok(ground_truth_options(data, robot)?.map(|g| format!("the file {}", g.path.display())))
    }
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

/// Says the datasets' notes on stderr, each distinct note once (by its text: the same note from many files
/// differs only in its source) with the count of the files that raised it, then skipped inputs (shown even
/// with `-q`) and ground-truth clocks.
fn say_load_notes(sets: &[&Dataset]) {
    let mut seen: Vec<(&Note, usize)> = Vec::new();
    for n in sets.iter().flat_map(|ds| &ds.notes) {
        match seen.iter_mut().find(|(first, _)| first.text == n.text) {
            Some(entry) => entry.1 += 1,
            None => seen.push((n, 1)),
        }
    }
    for (first, count) in seen {
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

/// The paths a load read, for `-v`: all of them, or the first and last of more than
/// [`dataset::READ_LINES_PER_FOLDER`] (`180 paths: sim/a.mcap … sim/z.mcap`; a shell glob gives many).
fn paths_text(paths: &[PathBuf]) -> String {
    match paths {
        [first, .., last] if paths.len() > crate::dataset::READ_LINES_PER_FOLDER => {
            format!("{} paths: {} … {}", paths.len(), first.display(), last.display())
        }
        _ => paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
    }
}
