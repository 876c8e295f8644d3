//! `omnical info`: what a ROS recording holds (as `ros2 bag info` shows it) and what omnical would make of
//! it with the options given: each topic's role and why, the runs a read gives (samples, rates, gaps, the
//! ground truth's clock), its notes, or the error that stops it.

use super::{DataArgs, OutputArgs};
use crate::dataset::mcap::{Inventory, Role, TopicReview};
use crate::dataset::{self, Dataset};
use omni_kin::Run;
use serde::Serialize;
use serde_json::json;
use std::path::{Path, PathBuf};

/// A gap between samples is reported when it is this many times the median interval.
pub const GAP_FACTOR: f64 = 5.0;

/// Arguments of `omnical info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// ROS recordings (.mcap, .db3 or .bag files, rosbag2 folders, or folders of them).
    #[arg(value_name = "RECORDING", required = true)]
    pub recordings: Vec<PathBuf>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options: the read `info` describes is the one other commands make with them.
    #[command(flatten)]
    pub data: DataArgs,
}

/// One topic: the recording's facts and omnical's verdict.
#[derive(Debug, Serialize)]
struct TopicInfo {
    topic: String,
    #[serde(rename = "type")]
    msg_type: String,
    messages: u64,
    rate_hz: Option<f64>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    joint_names: Vec<String>,
    role: Role,
    why: String,
}

/// One run of a read: its samples, rates and gaps.
#[derive(Debug, Serialize)]
struct RunInfo {
    name: String,
    duration_s: f64,
    wheel_samples: usize,
    wheel_rate_hz: f64,
    largest_wheel_gap_s: f64,
    truth_poses: usize,
    truth_rate_hz: Option<f64>,
    largest_truth_gap_s: Option<f64>,
    path_length_m: f64,
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

fn run_info(run: &Run) -> RunInfo {
    let t = run.wheel_t_s();
    let (wheel_rate_hz, largest_wheel_gap_s) = rate_and_gap(t).unwrap_or((f64::NAN, f64::NAN));
    let truth_t: Vec<f64> = run.truth().iter().map(|p| p.t_s).collect();
    let truth = rate_and_gap(&truth_t);
    RunInfo {
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

/// What one recording holds and what a read makes of it.
struct RecordingInfo {
    path: PathBuf,
    start_unix_s: f64,
    duration_s: f64,
    messages: u64,
    topics: Vec<TopicInfo>,
    /// The read's runs, notes and clocks, or its error.
    read: Result<Dataset, String>,
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

fn look_at(a: &Args, path: &Path) -> anyhow::Result<RecordingInfo> {
    let request = a.data.request(std::slice::from_ref(&path.to_path_buf()));
    let robot = request.robot()?;
    let opts = request.mcap_options(robot.as_ref())?;
    let elsewhere = request.truth_elsewhere(robot.as_ref())?;
    let max_bytes = a.data.max_file_mb.saturating_mul(1 << 20);
    let (inv, review) = dataset::review(path, max_bytes, &opts, elsewhere.as_deref())?;
    let first_ns = inv.topics.iter().map(|t| t.first_ns).min().unwrap_or(0);
    let last_ns = inv.topics.iter().map(|t| t.last_ns).max().unwrap_or(0);
    Ok(RecordingInfo {
        path: path.to_path_buf(),
        start_unix_s: first_ns as f64 * 1e-9,
        duration_s: last_ns.saturating_sub(first_ns) as f64 * 1e-9,
        messages: inv.topics.iter().map(|t| t.count).sum(),
        topics: topics(&inv, review),
        read: request.read_for_robot(robot).map_err(|e| format!("{e:#}")),
    })
}

/// Runs `omnical info`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let mut infos = Vec::new();
    for path in dataset::ros_recordings(&a.recordings)? {
        infos.push(look_at(a, &path)?);
    }
    if a.output.json {
        let recordings: Vec<serde_json::Value> = infos.iter().map(to_json).collect();
        return super::print_json("info", json!({ "recordings": recordings }));
    }
    for (k, info) in infos.iter().enumerate() {
        if k > 0 {
            println!();
        }
        print_info(info);
    }
    Ok(())
}

fn to_json(info: &RecordingInfo) -> serde_json::Value {
    let read = match &info.read {
        Ok(ds) => json!({
            "ok": true,
            "runs": ds.runs.iter().map(run_info).collect::<Vec<_>>(),
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
        "start_unix_s": info.start_unix_s,
        "duration_s": info.duration_s,
        "messages": info.messages,
        "topics": info.topics,
        "read": read,
    })
}

fn print_info(info: &RecordingInfo) {
    println!("{}", info.path.display());
    println!("  {} messages over {:.3} s, from Unix time {:.3} s", info.messages, info.duration_s, info.start_unix_s);
    println!("  topics:");
    for t in &info.topics {
        let rate = t.rate_hz.map_or_else(String::new, |r| format!(", {r:.1} Hz"));
        let plural = if t.messages == 1 { "" } else { "s" };
        println!("    {} ({}, {} message{plural}{rate})", t.topic, t.msg_type, t.messages);
        if !t.joint_names.is_empty() {
            println!("      joints: {}", t.joint_names.join(", "));
        }
        println!("      {}: {}", role_word(t.role), t.why);
    }
    match &info.read {
        Ok(ds) => print_read(ds),
        Err(e) => println!("  omnical cannot read it with these options: {e}"),
    }
}

fn role_word(role: Role) -> &'static str {
    match role {
        Role::Wheels => "wheels",
        Role::GroundTruth => "ground truth",
        Role::Candidate => "ground-truth candidate",
        Role::RecordedOdometry => "recorded odometry",
        Role::Command => "command",
        Role::StaticTransforms => "static transforms",
        Role::Lidar => "lidar",
        Role::Imu => "IMU",
        Role::Urdf => "URDF",
        Role::Unused => "not used",
    }
}

fn print_read(ds: &Dataset) {
    println!("  omnical reads {} run{}:", ds.runs.len(), if ds.runs.len() == 1 { "" } else { "s" });
    for r in ds.runs.iter().map(run_info) {
        let truth = match (r.truth_rate_hz, r.largest_truth_gap_s) {
            (Some(rate), Some(gap)) => {
                format!("{} ground-truth poses at {rate:.1} Hz, largest gap {gap:.3} s", r.truth_poses)
            }
            _ => format!("{} ground-truth poses", r.truth_poses),
        };
        println!(
            "    {}: {:.2} s, {} wheel samples at {:.1} Hz (largest gap {:.3} s), {truth}, path {:.2} m",
            r.name, r.duration_s, r.wheel_samples, r.wheel_rate_hz, r.largest_wheel_gap_s, r.path_length_m
        );
        if r.largest_wheel_gap_s * r.wheel_rate_hz > GAP_FACTOR {
            println!(
                "      the wheel data stops for {:.3} s ({:.0}x its median interval)",
                r.largest_wheel_gap_s,
                r.largest_wheel_gap_s * r.wheel_rate_hz
            );
        }
    }
    for c in &ds.ground_truth_clocks {
        println!("  clock: {}", c.describe());
    }
    for s in &ds.skipped {
        println!("  skipped {}: {}", s.source, s.reason);
    }
    for n in &ds.notes {
        println!("  note: {n}");
    }
}
