//! One ROS recording at a time, whatever its storage (a `.mcap`, `.db3` or `.bag` file, a rosbag2 folder):
//! what `omnical init` inspects, what `omnical info` reviews, the topics an export copies, and the message
//! feed behind the lidar and IMU readers. Runs are read by [`super::load`].

use super::{DatasetError, Input, Inputs, check_size, mcap, ros1, rosbag2};
use std::path::{Path, PathBuf};

/// The error for an input that is no ROS recording (a run CSV, an OptiOdom set) where one is needed.
fn not_a_recording(p: &Path) -> DatasetError {
    DatasetError::file(p, "not a ROS recording (.mcap, .db3, .bag or a rosbag2 folder)")
}

/// What `omnical init` inspected: one ROS recording and what it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Inspected {
    /// The recording inspected: the first under the path given, in the order [`super::load`] reads them.
    pub recording: PathBuf,
    /// Its topics, joint names and URDF.
    pub inventory: mcap::Inventory,
    /// How many ROS recordings the path holds (1 for a file or a recording folder).
    pub recordings: usize,
}

/// Inspects the first ROS recording under `path` (a `.mcap` or `.db3` file, a rosbag2 recording folder, or
/// a folder of them: whatever [`super::load`] reads as recordings), reading it whole; each file at most
/// `max_file_bytes` long.
pub fn inspect(path: &Path, max_file_bytes: u64) -> Result<Inspected, DatasetError> {
    let mut recordings = Vec::new();
    for input in Inputs::of(&[path.to_path_buf()]).list {
        match input? {
            i @ (Input::Mcap(_) | Input::Db3(_) | Input::Recording(_) | Input::Ros1(_)) => recordings.push(i),
            Input::Csv(_) | Input::OptiOdom(_) => {}
        }
    }
    let Some(first) = recordings.first() else {
        return Err(DatasetError::file(
            path,
            "no ROS 2 recording here (init reads .mcap and .db3 files and rosbag2 recording folders with a \
             metadata.yaml)",
        ));
    };
    let inventory = match first {
        Input::Db3(p) => rosbag2::inspect_db3(p, max_file_bytes)?,
        Input::Recording(p) => rosbag2::inspect_recording(p, max_file_bytes)?,
        Input::Ros1(p) => ros1::inspect(p)?,
        mcap => mcap::inspect(mcap.path(), max_file_bytes)?,
    };
    Ok(Inspected { recording: first.path().to_path_buf(), inventory, recordings: recordings.len() })
}

/// One ROS recording at `path` looked at for `omnical info`: its topics, and the role each would play in a
/// read with `opts` ([`mcap::TopicReview`]); `truth_elsewhere` says where the ground truth comes from when
/// it is not a topic.
pub fn review(
    path: &Path,
    max_file_bytes: u64,
    opts: &mcap::McapOptions,
    truth_elsewhere: Option<&str>,
) -> Result<(mcap::Inventory, Vec<mcap::TopicReview>), DatasetError> {
    let inventory = feed_ros(path, max_file_bytes, |zstd| {
        let mut sink = mcap::InventorySink::new(path);
        sink.zstd_messages = zstd;
        sink
    })?
    .finish()?;
    let rec = feed_ros(path, max_file_bytes, |zstd| {
        let mut rec = mcap::recording::Recording::new(&opts.wheel_joints);
        rec.zstd_messages = zstd;
        rec
    })?;
    Ok((inventory, mcap::review::review(path, rec, opts, truth_elsewhere)))
}

/// The topics of the ROS recording at `path` that an export carries over as recorded (transforms, the
/// URDF, the commands: [`mcap::copy`]).
pub fn recorded_topics(path: &Path, max_file_bytes: u64) -> Result<Vec<mcap::copy::CopiedTopic>, DatasetError> {
    let sink = feed_ros(path, max_file_bytes, mcap::copy::CopySink::new)?;
    Ok(sink.finish())
}

/// The ROS recordings at `paths` (files, rosbag2 folders, folders of them), in the order `load` reads them;
/// anything else is an error naming it.
pub(crate) fn ros_recordings(paths: &[PathBuf]) -> Result<Vec<PathBuf>, DatasetError> {
    Inputs::of(paths)
        .list
        .into_iter()
        .map(|i| match i? {
            Input::Csv(p) | Input::OptiOdom(p) => Err(not_a_recording(&p)),
            i => Ok(i.path().to_path_buf()),
        })
        .collect()
}

/// What kind of input a path of `omnical info` is, as [`super::load`] reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// A ROS recording (`.mcap`, `.db3`, `.bag`, a rosbag2 folder): its topics are reviewed.
    Ros,
    /// An omnical CSV run.
    CsvRun,
    /// An OptiOdom set folder (its metadata and run CSVs with motion capture).
    OptiOdom,
}

impl InputKind {
    /// The id `omnical info --json` gives it (`ros`, `csv`, `optiodom`).
    pub fn id(self) -> &'static str {
        match self {
            Self::Ros => "ros",
            Self::CsvRun => "csv",
            Self::OptiOdom => "optiodom",
        }
    }

    /// What it is, in words.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Ros => "a ROS recording",
            Self::CsvRun => "an omnical CSV run (t_s, wheel speeds, ground-truth pose per row: docs/formats.md)",
            Self::OptiOdom => {
                "an OptiOdom set (its metadata CSV declares the robot's type and geometry; one CSV per run with \
                 wheel speeds and motion capture)"
            }
        }
    }
}

/// Every input at `paths` (files or folders, expanded as [`super::load`] expands them) with its kind.
pub(crate) fn inputs(paths: &[PathBuf]) -> Result<Vec<(PathBuf, InputKind)>, DatasetError> {
    Inputs::of(paths)
        .list
        .into_iter()
        .map(|i| {
            Ok(match i? {
                Input::Csv(p) => (p, InputKind::CsvRun),
                Input::OptiOdom(p) => (p, InputKind::OptiOdom),
                Input::Mcap(p) | Input::Db3(p) | Input::Recording(p) | Input::Ros1(p) => (p, InputKind::Ros),
            })
        })
        .collect()
}

/// Feeds every message of the one ROS recording at `path` (a `.mcap`, `.db3` or `.bag` file, or a rosbag2
/// recording folder; each storage file at most `max_file_bytes` long) into the sink `make(zstd_messages)`
/// makes (`zstd_messages`: rosbag2's per-message compression, which the sink undoes).
pub(crate) fn feed_ros<S: mcap::recording::MessageSink>(
    path: &Path,
    max_file_bytes: u64,
    make: impl FnOnce(bool) -> S,
) -> Result<S, DatasetError> {
    let mut inputs = Inputs::of(&[path.to_path_buf()]).list;
    let not_one = |found: String| {
        DatasetError::file(
            path,
            format!("expected one ROS recording (a .mcap, .db3 or .bag file, or a rosbag2 folder), found {found}"),
        )
    };
    let input = match inputs.len() {
        1 => inputs.pop().ok_or_else(|| not_one("none".into()))??,
        0 => return Err(not_one("none".into())),
        n => return Err(not_one(format!("{n} inputs"))),
    };
    match input {
        Input::Recording(dir) => rosbag2::feed_recording(&dir, max_file_bytes, make),
        Input::Mcap(p) => {
            check_size(&p, max_file_bytes)?;
            let buf = std::fs::read(&p).map_err(|e| DatasetError::io(&p, e))?;
            let mut sink = make(false);
            mcap::framing::feed_mcap(&p, &buf, &mut sink)?;
            Ok(sink)
        }
        Input::Db3(p) => {
            let mut sink = make(false);
            rosbag2::feed_db3(&p, max_file_bytes, &mut sink)?;
            Ok(sink)
        }
        Input::Ros1(p) => {
            check_size(&p, max_file_bytes)?;
            let mut sink = make(false);
            ros1::feed(&p, &mut sink)?;
            Ok(sink)
        }
        Input::Csv(p) | Input::OptiOdom(p) => Err(not_a_recording(&p)),
    }
}
