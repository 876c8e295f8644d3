//! `omnical info`: what an input holds (a ROS recording as `ros2 bag info` shows it; a CSV run or an
//! OptiOdom set) and what omnical would make of it with the options given ([`crate::api::info`] computes it), printed as text or JSON.

use super::{DataArgs, OutputArgs};
use crate::api::info::{self as api, RecordingInfo, RunInfo};
use crate::api::settings::as_flags;
use crate::dataset::Dataset;
use crate::dataset::mcap::Role;
use std::path::PathBuf;

pub use crate::api::info::GAP_FACTOR;

/// Arguments of `omnical info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Inputs as `train` reads them: ROS recordings (.mcap, .db3 or .bag files, rosbag2 folders), omnical
    /// CSV runs, OptiOdom set folders, or folders of them.
    #[arg(value_name = "RECORDING", required = true)]
    pub recordings: Vec<PathBuf>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options: the read `info` describes is the one other commands make with them.
    #[command(flatten)]
    pub data: DataArgs,
}

/// Runs `omnical info`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let infos = api::info(&a.recordings, &a.data.options())?;
    if a.output.json {
        println!("{}", as_flags(&serde_json::to_string_pretty(&api::document(&infos))?));
        return Ok(());
    }
    for (k, info) in infos.iter().enumerate() {
        if k > 0 {
            println!();
        }
        print_info(info);
    }
    Ok(())
}

fn print_info(info: &RecordingInfo) {
    println!("{}", info.path.display());
    if let (Some(messages), Some(duration_s), Some(start_unix_s)) = (info.messages, info.duration_s, info.start_unix_s)
    {
        println!("  {messages} messages over {duration_s:.3} s, from Unix time {start_unix_s:.3} s");
    } else {
        println!("  {}", info.kind.describe());
    }
    if let Some(d) = info.read.as_ref().ok().and_then(|ds| ds.declared.first()) {
        println!("  declares a {} robot with {} wheels (its design geometry)", d.kind, d.geometry.n_wheels());
    }
    if info.topics.is_empty() {
        return print_read_or_error(info);
    }
    println!("  topics:");
    for t in &info.topics {
        let rate = t.rate_hz.map_or_else(String::new, |r| format!(", {r:.1} Hz"));
        let plural = if t.messages == 1 { "" } else { "s" };
        println!("    {} ({}, {} message{plural}{rate})", t.topic, t.msg_type, t.messages);
        if !t.joint_names.is_empty() {
            println!("      joints: {}", t.joint_names.join(", "));
        }
        println!("      {}: {}", role_word(t.role), as_flags(&t.why));
    }
    print_read_or_error(info);
}

fn print_read_or_error(info: &RecordingInfo) {
    match &info.read {
        Ok(ds) => print_read(ds),
        Err(e) => println!("  omnical cannot read it with these options: {}", as_flags(&e.to_string())),
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
    for r in ds.runs.iter().map(RunInfo::of) {
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
        println!("  skipped {}: {}", s.source, as_flags(&s.reason));
    }
    for n in &ds.notes {
        println!("  note: {}", as_flags(&n.to_string()));
    }
}
