//! `omnical scan-odometry`: a lidar's own path from its scans (scan-to-scan point-to-line ICP), with the
//! match counts and quality; optionally written as TUM for evo.

use super::OutputArgs;
use crate::lidar::{self, DEFAULT_SCAN_TOPIC, MatchSettings, SensorPath};
use crate::out_path;
use crate::report::tum;
use anyhow::{Context, bail};
use omni_kin::{StampedPose, Stats};
use serde_json::json;
use std::path::{Path, PathBuf};

/// Arguments of `omnical scan-odometry`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording: a .mcap, .db3 or .bag file, or a rosbag2 folder.
    #[arg(value_name = "RECORDING")]
    pub recording: PathBuf,
    /// The lidar's sensor_msgs/msg/LaserScan topic.
    #[arg(long, default_value = DEFAULT_SCAN_TOPIC)]
    pub topic: String,
    /// Write the sensor's path as a TUM file (stamps in the recording's time; one file per segment,
    /// FILE's stem + `.segN.tum`, when rejected matches broke the path).
    #[arg(long, value_name = "FILE")]
    pub tum: Option<PathBuf>,
    /// Output options (JSON: counts, quality and segments).
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Length of a path. m.
fn travelled_m(poses: &[StampedPose]) -> f64 {
    poses.windows(2).map(|w| (w[1].pose.x_m - w[0].pose.x_m).hypot(w[1].pose.y_m - w[0].pose.y_m)).sum()
}

/// The TUM files for `path`'s segments: `tum` itself for one, `<stem>.segN.tum` beside it for several.
fn tum_paths(tum: &Path, segments: usize) -> Vec<PathBuf> {
    if segments == 1 {
        return vec![tum.to_path_buf()];
    }
    let stem = tum.file_stem().map_or_else(|| "scan".into(), |s| s.to_string_lossy().into_owned());
    (1..=segments).map(|k| tum.with_file_name(format!("{stem}.seg{k}.tum"))).collect()
}

/// The counts and quality as text lines.
fn summary_text(topic: &str, frame: &str, scans: usize, path: &SensorPath) -> Vec<String> {
    let why: Vec<String> = path.rejected_why.iter().map(|(k, n)| format!("{k} {n}")).collect();
    let why = if why.is_empty() { String::new() } else { format!(" ({})", why.join(", ")) };
    let length: f64 = path.segments.iter().map(|s| travelled_m(s)).sum();
    let mut lines = vec![format!(
        "{topic}: {scans} scans (frame {frame:?}), {} matches accepted, {} rejected{why}; {} segment{}, {:.2} m travelled",
        path.matched,
        path.rejected,
        path.segments.len(),
        if path.segments.len() == 1 { "" } else { "s" },
        length
    )];
    if path.deskewed > 0 {
        lines.push(format!(
            "{} scans de-skewed: their beams are measured over the sweep (LaserScan time_increment), so each was \
             moved to its stamp by the sensor's motion before matching",
            path.deskewed
        ));
    }
    if !path.qualities.is_empty() {
        let rms = Stats::of(path.qualities.iter().map(|q| q.rms_m));
        let share = Stats::of(path.qualities.iter().map(|q| q.inlier_share));
        let cond = Stats::of(path.qualities.iter().map(|q| q.condition));
        lines.push(format!(
            "accepted matches: residual RMS median {:.1} mm (max {:.1}), inlier share median {:.1} %, condition median \
             {:.1} (max {:.1})",
            1e3 * rms.median,
            1e3 * rms.max,
            100.0 * share.median,
            cond.median,
            cond.max
        ));
    }
    lines
}

/// Runs `omnical scan-odometry`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    if let Some(t) = &a.tum {
        out_path::check_file(t, "--tum")?;
    }
    let read = lidar::read_scans(&a.recording, &a.topic)?;
    if let Some(m) = &read.angle_max_mismatch {
        crate::note!("note: {}", m.describe(&a.topic));
    }
    let path = lidar::sensor_path(&read.scans, &MatchSettings::default())
        .with_context(|| format!("{}: topic {:?}", a.recording.display(), a.topic))?;
    if path.segments.is_empty() {
        let why: Vec<String> = path.rejected_why.iter().map(|(k, n)| format!("{k} {n}")).collect();
        bail!(
            "{}: topic {:?}: none of the {} scan matches was accepted ({}; {}); the scans do not constrain the \
             lidar's motion (a corridor, a single wall, an empty room?) or do not overlap: record where walls face \
             several ways",
            a.recording.display(),
            a.topic,
            path.rejected,
            why.join(", "),
            lidar::returns_text(&read.scans, &MatchSettings::default())
        );
    }
    let mut written = Vec::new();
    if let Some(t) = &a.tum {
        for (seg, file) in path.segments.iter().zip(tum_paths(t, path.segments.len())) {
            let comment = format!(
                "omnical scan-odometry: {} on {}, sensor frame {:?}",
                a.topic,
                a.recording.display(),
                read.frame_id
            );
            let text = tum::to_tum_at(&comment, seg, read.origin_s);
            crate::atomic::write_atomic(&file, text.as_bytes())
                .with_context(|| format!("writing {}", file.display()))?;
            written.push(file);
        }
    }
    if a.output.json {
        return super::print_json("scan-odometry", json_doc(a, &read, &path, &written));
    }
    for line in summary_text(&a.topic, &read.frame_id, read.scans.len(), &path) {
        println!("{line}");
    }
    if let Some(m) = read.base_from_sensor {
        println!(
            "mount from static transforms {}: ({:.3}, {:.3}) m, {:.2}°",
            read.chain_text(),
            m.x_m,
            m.y_m,
            m.theta_rad.to_degrees()
        );
    }
    for f in &written {
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// The `--json` document (docs/json.md).
fn json_doc(a: &Args, read: &lidar::ScanRead, path: &SensorPath, written: &[PathBuf]) -> serde_json::Value {
    let stats = |v: Vec<f64>| {
        let s = Stats::of(v);
        json!({ "median": s.median, "max": s.max, "mean": s.mean })
    };
    let segments: Vec<_> = path
        .segments
        .iter()
        .map(|s| {
            json!({
                "start_s": s[0].t_s, "end_s": s[s.len() - 1].t_s, "poses": s.len(), "travelled_m": travelled_m(s),
            })
        })
        .collect();
    json!({
        "recording": a.recording,
        "topic": a.topic,
        "frame_id": read.frame_id,
        "origin_s": read.origin_s,
        "scans": read.scans.len(),
        "matched": path.matched,
        "rejected": path.rejected,
        "rejected_why": path.rejected_why,
        "deskewed": path.deskewed,
        "quality": {
            "rms_m": stats(path.qualities.iter().map(|q| q.rms_m).collect()),
            "inlier_share": stats(path.qualities.iter().map(|q| q.inlier_share).collect()),
            "condition": stats(path.qualities.iter().map(|q| q.condition).collect()),
        },
        "segments": segments,
        "base_from_sensor": read.base_from_sensor.map(|m| json!({ "x_m": m.x_m, "y_m": m.y_m, "theta_rad": m.theta_rad })),
        "mount_chain": read.chain,
        "tum": written,
    })
}
