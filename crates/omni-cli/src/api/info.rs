//! What the inputs hold (a ROS recording as `ros2 bag info` shows it; a CSV run or an OptiOdom set, which
//! have no topics) and what a read with given data options makes of them: each topic's role and why, the runs (samples, rates, gaps, the ground truth's clock), the read's
//! notes, or the error that stops it. `omnical info` prints it ([`RecordingInfo`]) or its JSON
//! ([`to_json`]); Python's `omnical.info` returns the JSON as a dict.

use super::load::{DataOptions, LoadError, LoadRequest};
use crate::dataset::mcap::{Inventory, Role, TopicReview};
use crate::dataset::{self, Dataset, InputKind};
use omni_kin::Run;
use serde::Serialize;
use serde_json::json;
use std::path::{Path, PathBuf};

/// A gap between samples is reported when it is this many times the median interval.
pub const GAP_FACTOR: f64 = 5.0;

/// One topic: the recording's facts and omnical's verdict.
#[derive(Clone, Debug, Serialize)]
pub struct TopicInfo {
    /// The topic's name.
    pub topic: String,
    /// Its message type (`sensor_msgs/msg/JointState`).
    #[serde(rename = "type")]
    pub msg_type: String,
    /// Messages recorded on it.
    pub messages: u64,
    /// Median message rate. Hz. `None` for fewer than two messages.
    pub rate_hz: Option<f64>,
    /// The joint names of a JointState topic.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub joint_names: Vec<String>,
    /// The role a read gives it.
    pub role: Role,
    /// Why it has that role.
    pub why: String,
}

/// One run of a read: its samples, rates and gaps.
#[derive(Clone, Debug, Serialize)]
pub struct RunInfo {
    /// The run's name.
    pub name: String,
    /// From the first to the last wheel sample. s.
    pub duration_s: f64,
    /// Wheel samples.
    pub wheel_samples: usize,
    /// Median wheel sampling rate. Hz (NaN for fewer than two samples).
    pub wheel_rate_hz: f64,
    /// Largest interval between wheel samples. s.
    pub largest_wheel_gap_s: f64,
    /// Ground-truth poses.
    pub truth_poses: usize,
    /// Median ground-truth rate. Hz.
    pub truth_rate_hz: Option<f64>,
    /// Largest interval between ground-truth poses. s.
    pub largest_truth_gap_s: Option<f64>,
    /// Length of the ground-truth path. m.
    pub path_length_m: f64,
}

impl RunInfo {
    /// A run's samples, rates and gaps.
    pub fn of(run: &Run) -> Self {
        let t = run.wheel_t_s();
        let (wheel_rate_hz, largest_wheel_gap_s) = rate_and_gap(t).unwrap_or((f64::NAN, f64::NAN));
        let truth_t: Vec<f64> = run.truth().iter().map(|p| p.t_s).collect();
        let truth = rate_and_gap(&truth_t);
        Self {
            name: run.name().to_string(),
            duration_s: t.last().copied().unwrap_or(0.0) - t.first().copied().unwrap_or(0.0),
            wheel_samples: run.n_samples(),
            wheel_rate_hz,
            largest_wheel_gap_s,
            truth_poses: truth_t.len(),
            truth_rate_hz: truth.map(|t| t.0),
            largest_truth_gap_s: truth.map(|t| t.1),
            path_length_m: run.path_length_m(),
        }
    }
}

/// Median sampling rate (Hz) and largest interval (s) of increasing stamps; `None` for fewer than two.
fn rate_and_gap(t_s: &[f64]) -> Option<(f64, f64)> {
    let mut dt: Vec<f64> = t_s.windows(2).map(|w| w[1] - w[0]).collect();
    if dt.is_empty() {
        return None;
    }
    let largest = dt.iter().copied().fold(0.0, f64::max);
    dt.sort_by(f64::total_cmp);
    let median = dt[dt.len() / 2];
    (median > 0.0).then(|| (1.0 / median, largest))
}

/// What one input holds and what a read makes of it: a ROS recording's messages and topics, or a CSV run
/// or OptiOdom set, which have no topics.
#[derive(Debug)]
pub struct RecordingInfo {
    /// The input.
    pub path: PathBuf,
    /// What kind of input it is.
    pub kind: InputKind,
    /// Its first message's stamp. Unix time, s. `None` but for a ROS recording.
    pub start_unix_s: Option<f64>,
    /// From its first to its last message. s. `None` but for a ROS recording.
    pub duration_s: Option<f64>,
    /// Messages on all topics. `None` but for a ROS recording.
    pub messages: Option<u64>,
    /// Its topics, in the recording's order (none but for a ROS recording).
    pub topics: Vec<TopicInfo>,
    /// The read's runs, notes and clocks, or its error (the CLI's `error:` text).
    pub read: Result<Dataset, String>,
}

fn topics(inv: &Inventory, review: Vec<TopicReview>) -> Vec<TopicInfo> {
    inv.topics
        .iter()
        .map(|t| {
            let verdict = review.iter().find(|r| r.topic == t.topic);
            TopicInfo {
                topic: t.topic.clone(),
                msg_type: t.msg_type.clone(),
                messages: t.count,
                rate_hz: t.rate_hz(),
                joint_names: t.joint_names.clone(),
                role: verdict.map_or(Role::Unused, |r| r.role),
                why: verdict.map_or_else(|| "not read by omnical".into(), |r| r.why.clone()),
            }
        })
        .collect()
}

/// Looks at one recording with `data`'s options.
fn look_at(data: &DataOptions, path: &Path) -> Result<RecordingInfo, LoadError> {
    let request = LoadRequest::new(std::slice::from_ref(&path.to_path_buf()), data);
    let robot = request.robot()?;
    let opts = request.mcap_options(robot.as_ref())?;
    let elsewhere = request.truth_elsewhere(robot.as_ref())?;
    let max_bytes = data.max_file_mb.saturating_mul(1 << 20);
    let (inv, review) = dataset::review(path, max_bytes, &opts, elsewhere.as_deref())?;
    let first_ns = inv.topics.iter().map(|t| t.first_ns).min().unwrap_or(0);
    let last_ns = inv.topics.iter().map(|t| t.last_ns).max().unwrap_or(0);
    Ok(RecordingInfo {
        path: path.to_path_buf(),
        kind: InputKind::Ros,
        start_unix_s: Some(first_ns as f64 * 1e-9),
        duration_s: Some(last_ns.saturating_sub(first_ns) as f64 * 1e-9),
        messages: Some(inv.topics.iter().map(|t| t.count).sum()),
        topics: topics(&inv, review),
        read: request.read_for_robot(robot).map_err(|e| format!("{e:#}")),
    })
}

/// Looks at one CSV run or OptiOdom set with `data`'s options: no topics, the read as `train` makes it.
fn look_at_file_input(data: &DataOptions, path: &Path, kind: InputKind) -> Result<RecordingInfo, LoadError> {
    let request = LoadRequest::new(std::slice::from_ref(&path.to_path_buf()), data);
    let robot = request.robot()?;
    Ok(RecordingInfo {
        path: path.to_path_buf(),
        kind,
        start_unix_s: None,
        duration_s: None,
        messages: None,
        topics: Vec::new(),
        read: request.read_for_robot(robot).map_err(|e| format!("{e:#}")),
    })
}

/// Every input at `paths` that the loader reads (ROS recordings, rosbag2 folders, CSV runs, OptiOdom sets,
/// or folders of them), each looked at with `data`'s options. A path that is no input or cannot be opened is
/// an error naming it; an input that opens but makes no runs has its error in [`RecordingInfo::read`].
pub fn info(paths: &[PathBuf], data: &DataOptions) -> Result<Vec<RecordingInfo>, LoadError> {
    let inputs = dataset::inputs(paths)?;
    if inputs.is_empty() {
        return Err(no_recording(paths).into());
    }
    inputs
        .iter()
        .map(|(path, kind)| match kind {
            InputKind::Ros => look_at(data, path),
            _ => look_at_file_input(data, path, *kind),
        })
        .collect()
}

/// The error for paths (folders) that hold no input: what was looked for, and what is there.
fn no_recording(paths: &[PathBuf]) -> dataset::DatasetError {
    let what = paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
    let mut entries: Vec<String> = paths
        .iter()
        .filter_map(|p| std::fs::read_dir(p).ok())
        .flat_map(|d| d.filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned())))
        .collect();
    entries.sort();
    let held = match &entries[..] {
        [] => "the folder is empty".to_string(),
        [one] => format!("it holds only {one}"),
        [first, ..] => format!("it holds {} entries (first {first}), none of them a recording", entries.len()),
    };
    dataset::DatasetError::file(
        Path::new(&what),
        format!(
            "no ROS recording here: looked for .mcap, .db3 and .bag files and rosbag2 recording folders \
             (metadata.yaml), CSV runs and OptiOdom sets, in the folder and its subfolders; {held}"
        ),
    )
}

/// The JSON of one recording's info (`omnical info --json`'s `recordings` entries).
pub fn to_json(info: &RecordingInfo) -> serde_json::Value {
    let read = match &info.read {
        Ok(ds) => json!({
            "ok": true,
            "runs": ds.runs.iter().map(RunInfo::of).collect::<Vec<_>>(),
            "notes": ds.notes,
            "skipped": ds.skipped.iter().map(|s| json!({"source": s.source, "reason": s.reason})).collect::<Vec<_>>(),
            "clocks": ds.ground_truth_clocks.iter().map(|c| json!({
                "recording": c.recording, "source": c.file.display().to_string(), "offset_s": c.offset_s,
                "std_error_s": c.estimate.as_ref().map(|e| e.std_error_s),
            })).collect::<Vec<_>>(),
        }),
        Err(e) => json!({ "ok": false, "error": e }),
    };
    json!({
        "path": info.path.display().to_string(),
        "kind": info.kind.id(),
        "declared": declared_json(info),
        "start_unix_s": info.start_unix_s,
        "duration_s": info.duration_s,
        "messages": info.messages,
        "topics": info.topics,
        "read": read,
    })
}

/// The robot an input declares (an OptiOdom set's type and wheel count), else null.
fn declared_json(info: &RecordingInfo) -> serde_json::Value {
    match info.read.as_ref().ok().and_then(|ds| ds.declared.first()) {
        Some(d) => json!({ "type": d.kind, "wheels": d.geometry.n_wheels() }),
        None => serde_json::Value::Null,
    }
}

/// The whole `omnical info --json` document: `{"recordings": […], "schema_version": …, "command": "info"}`
/// (docs/json.md).
pub fn document(infos: &[RecordingInfo]) -> serde_json::Value {
    let mut doc = serde_json::Map::new();
    doc.insert("recordings".into(), infos.iter().map(to_json).collect());
    doc.insert("schema_version".into(), super::JSON_SCHEMA_VERSION.into());
    doc.insert("command".into(), "info".into());
    serde_json::Value::Object(doc)
}
