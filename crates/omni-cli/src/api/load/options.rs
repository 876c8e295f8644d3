//! The data options ([`DataOptions`]) and what they resolve to over the robot description: the LaserScan
//! topic of `--gt-scans`, the table of measured end poses, the ground-truth file and its CSV columns, the
//! joints CSV runs are read by; options that do not go together are refused here.

use super::LoadError;
use crate::dataset::{self, Dataset};
use crate::robot_file;
use omni_kin::reference::ReferenceKind;
use std::path::PathBuf;

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
    /// Where the fit starts the sensor's mount of a relative reference (the pose of the sensor in the base
    /// frame), fitted from there; `None`: found from the motions ([`omni_kin::hand_eye`]). A lidar's static
    /// transforms are not used when it is given.
    pub gt_mount_start: Option<omni_kin::Pose2>,
    /// The ground truth from a 2D lidar: this LaserScan topic's scans matched into the sensor's own path, a
    /// relative reference (`--gt-kind relative` is implied).
    pub gt_scans: Option<String>,
    /// Cut MCAP files into runs at standstills at least this long (s).
    pub split_s: Option<f64>,
    /// Cut recordings into runs of this length (s), the last one up to half as long again.
    pub split_every_s: Option<f64>,
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
            gt_mount_start: None,
            gt_scans: None,
            split_s: None,
            split_every_s: None,
            skip_invalid: false,
            ticks_per_rev: None,
            max_file_mb: dataset::DEFAULT_MAX_FILE_BYTES >> 20,
        }
    }
}

impl DataOptions {
    /// The files a read with these options takes, besides the data `paths`: the robot file and the
    /// ground-truth file (for the check that no result folder holds them, [`crate::out_path::Inputs`]).
    pub fn inputs(&self, paths: &[PathBuf]) -> crate::out_path::Inputs {
        let robot = self.robot.as_deref().filter(|r| *r != robot_file::BUILTIN_APR02);
        crate::out_path::Inputs::data(paths).with_some("--robot", robot).with_some("--gt", self.gt.as_ref())
    }

    /// The wheel joint names runs of `ds` were read with: [`DataOptions::joints`], else the robot
    /// description's, else the default `wheel_a`, `wheel_b`, `wheel_c`.
    pub fn wheel_joints(&self, ds: &Dataset) -> Vec<String> {
        let mut mcap =
            dataset::mcap::McapOptions { wheel_joints: self.joints.clone().unwrap_or_default(), ..Default::default() };
        robot_file::fill_mcap_options(&mut mcap, self.joints.is_none(), ds.robot_file.as_ref());
        mcap.wheel_joints
    }
}

/// The LaserScan topic of `--gt-scans`, checked against the other options: a lidar is a relative
/// reference, and the only ground truth.
pub(super) fn scans_topic(data: &DataOptions) -> Result<Option<String>, LoadError> {
    let Some(topic) = &data.gt_scans else { return Ok(None) };
    if data.gt_kind == ReferenceKind::EndPose {
        return Err(LoadError::ScansWithEndPose { topic: topic.clone() });
    }
    // The other option as the library names a setting (`crate::api::settings::named`).
    for (set, flag) in [(data.gt.is_some(), "`gt`"), (data.gt_topic.is_some(), "`gt_topic`")] {
        if set {
            return Err(LoadError::ScansWith { flag, topic: topic.clone() });
        }
    }
    Ok(Some(topic.clone()))
}

/// The measured end-pose table of `--gt-kind end-pose` (its `--gt`), checked against the other options.
pub(super) fn end_pose_file(data: &DataOptions) -> Result<Option<PathBuf>, LoadError> {
    if data.gt_kind != ReferenceKind::EndPose {
        return Ok(None);
    }
    let Some(file) = &data.gt else { return Err(LoadError::EndPoseWithoutTable) };
    let split = data.split_s.is_some() || data.split_every_s.is_some();
    for (set, flag) in [(split, "--split"), (data.gt_topic.is_some(), "--gt-topic")] {
        if set {
            return Err(LoadError::EndPoseWith { flag });
        }
    }
    Ok(Some(file.clone()))
}

/// The joints CSV runs are read by: the joints option, else a robot description file's. The built-in
/// `apr02`'s names are the simulator's placeholders, so with it each file keeps its own column order.
pub(super) fn csv_joints(data: &DataOptions, robot: Option<&robot_file::RobotFile>) -> Vec<String> {
    let from_file = robot.filter(|r| r.source != robot_file::Source::Builtin).map(|r| r.description.joints());
    data.joints.clone().or(from_file).unwrap_or_default()
}

/// `--gt` and its options, over the robot description's `[ground_truth]` (its `file` relative to the
/// description's folder).
pub(super) fn ground_truth_options(
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
    // `--gt-columns t,x,y`: the columns present, by their default names; without `yaw`, positions only.
    let is_listed = |kv: &String| ["t", "x", "y", "yaw"].contains(&kv.trim());
    let listed: Vec<&String> = data.gt_columns.iter().filter(|kv| is_listed(kv)).collect();
    if let Some(kv) =
        data.gt_columns.iter().filter(|kv| !is_listed(kv)).chain(&data.gt_units).find(|kv| !kv.contains('='))
    {
        return Err(LoadError::NotKeyValue { setting: kv.clone() });
    }
    columns.extend(settings(&data.gt_columns));
    let yaw_named = listed.iter().any(|k| k.trim() == "yaw") || columns.iter().any(|(k, _)| k == "yaw");
    if !listed.is_empty() && !yaw_named {
        columns.push(("yaw".into(), dataset::ground_truth::CsvColumns::NO_HEADING.into()));
    }
    units.extend(settings(&data.gt_units));
    for (k, v) in &columns {
        csv.set_column(k, v)?;
    }
    for (k, v) in &units {
        csv.set_unit(k, v)?;
    }
    let time_offset_s = data.gt_time_offset_s.or(from_robot.and_then(|(_, g)| g.time_offset_s));
    Ok(Some(dataset::ground_truth::GroundTruthOptions { path, time_offset_s, csv }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CLI prints an error with its sources joined by `: ` (`{:#}`): a refused column is said once.
    #[test]
    fn a_refused_ground_truth_column_is_said_once() {
        let data =
            DataOptions { gt: Some("truth.csv".into()), gt_units: vec!["angle=grad".into()], ..Default::default() };
        let e = ground_truth_options(&data, None).unwrap_err();
        assert!(matches!(e, LoadError::GroundTruthColumns(_)), "{e:?}");
        assert_eq!(
            format!("{:#}", anyhow::Error::from(e)),
            "unknown ground-truth unit angle=grad (expected time=s|ms|us|ns, length=m|cm|mm, angle=rad|deg)"
        );
    }
}
