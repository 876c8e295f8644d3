//! `omnical init`: inspect a recording, read the robot's URDF, and write a commented robot.toml.

use crate::cli::choice;
use crate::dataset::{
    self,
    mcap::{self, Inventory},
};
use crate::init::{self, UrdfSource, urdf};
use crate::{atomic, robot_file};
use anyhow::{Context, bail};
use omni_kin::robot::BaseKind;
use std::path::{Path, PathBuf};

/// Arguments of `omnical init`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording: a ROS 2 bag (.mcap, .db3), a rosbag2 folder (metadata.yaml), a ROS 1 bag (.bag), or a
    /// folder of them (the first is inspected).
    pub recording: PathBuf,
    /// The robot's URDF (default: the recording's /robot_description topic).
    #[arg(long, value_name = "FILE")]
    pub urdf: Option<PathBuf>,
    /// The file to write.
    #[arg(long, default_value = robot_file::FILE_NAME)]
    pub out: PathBuf,
    /// The base kind, instead of the guess (2 wheels: diff; 4 named mecanum: mecanum; else omni).
    #[arg(long, value_parser = choice::<BaseKind>())]
    pub kind: Option<BaseKind>,
    /// Replace an existing file.
    #[arg(long)]
    pub force: bool,
    /// Refuse a recording larger than this (MiB); it is read into memory whole.
    #[arg(long, value_name = "MIB", default_value_t = dataset::DEFAULT_MAX_FILE_BYTES >> 20)]
    pub max_file_mb: u64,
    /// Output options (JSON: the drafted description's facts and what to check).
    #[command(flatten)]
    pub output: super::OutputArgs,
}

/// The URDF text and where it came from; `recording` is the one inspected.
fn urdf_text(a: &Args, recording: &Path, inv: &Inventory) -> anyhow::Result<(String, UrdfSource, PathBuf)> {
    if let Some(p) = &a.urdf {
        let text = std::fs::read_to_string(p).with_context(|| format!("{}", p.display()))?;
        return Ok((text, UrdfSource { label: p.display().to_string() }, p.clone()));
    }
    match &inv.robot_description {
        Some(text) => Ok((
            text.clone(),
            UrdfSource { label: format!("topic {} of {}", mcap::ROBOT_DESCRIPTION_TOPIC, recording.display()) },
            recording.to_path_buf(),
        )),
        None => bail!(
            "{}: the recording has no {} topic (std_msgs/msg/String) with the robot's URDF; give it with --urdf FILE \
             (for a .xacro, run `xacro robot.urdf.xacro > robot.urdf` first), or, without a URDF, add --kind \
             diff|omni|mecanum for a robot.toml skeleton named after the recording's joints, the values to measure \
             marked",
            recording.display(),
            mcap::ROBOT_DESCRIPTION_TOPIC
        ),
    }
}

/// Runs `omnical init`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    if a.out.exists() && !a.force {
        bail!("{} exists; pass --force to replace it, or --out another file", a.out.display());
    }
    crate::out_path::check_file(&a.out, "--out")?;
    let found = dataset::inspect(&a.recording, a.max_file_mb.saturating_mul(1 << 20))?;
    if found.recordings > 1 && !a.output.json {
        println!(
            "{} holds {} recordings; inspecting the first, {}",
            a.recording.display(),
            found.recordings,
            found.recording.display()
        );
    }
    let inv = found.inventory;
    if let (None, None, Some(kind)) = (&a.urdf, &inv.robot_description, a.kind) {
        return write_skeleton(a, &inv, kind);
    }
    let (text, source, urdf_path) = urdf_text(a, &found.recording, &inv)?;
    let (recordings, inspected) = (found.recordings, found.recording.clone());
    let found = urdf::wheels(&text).map_err(|e| anyhow::anyhow!("{}: {e}", source.label))?;
    let recording = a.recording.display().to_string();
    let d = init::draft(&inv, &recording, &found, &source, a.kind)
        .map_err(|e| anyhow::anyhow!("{}: {e}", urdf_label(&urdf_path, &source)))?;
    let toml = robot_file::to_toml(&d.description, &d.comments);
    // What is written must read back as written.
    robot_file::parse(&toml, &a.out).context("the drafted robot.toml does not read back (a bug)")?;
    atomic::write_atomic(&a.out, toml.as_bytes()).with_context(|| format!("writing {}", a.out.display()))?;
    if a.output.json {
        for w in &d.warnings {
            tracing::warn!("{w}");
        }
        let doc = serde_json::json!({
            "out": a.out,
            "recording": a.recording,
            "recordings": recordings,
            "inspected": inspected,
            "urdf": source.label,
            "kind": d.description.kind.to_string(),
            "joints": d.description.joints(),
            "description": d.description,
            "notes": d.comments.header.iter().filter(|l| !l.starts_with("  CHECK: ")).collect::<Vec<_>>(),
            "warnings": d.warnings,
        });
        return super::print_json("init", doc);
    }
    for line in d.comments.header.iter().filter(|l| !l.starts_with("  CHECK: ")) {
        println!("{line}");
    }
    for w in &d.warnings {
        tracing::warn!("{w}");
    }
    println!(
        "\nwrote {} ({} base, joints {}); check it, then e.g. `omnical eval --robot {} {}`",
        a.out.display(),
        d.description.kind,
        d.description.joints().join(", "),
        a.out.display(),
        a.recording.display()
    );
    Ok(())
}

/// `omnical init REC --kind KIND` without a URDF: the skeleton ([`init::skeleton`]) written, and what to do.
fn write_skeleton(a: &Args, inv: &Inventory, kind: BaseKind) -> anyhow::Result<()> {
    let recording = a.recording.display().to_string();
    let (toml, joints, topic) =
        init::skeleton::skeleton(inv, &recording, kind).map_err(|e| anyhow::anyhow!("{recording}: {e}"))?;
    atomic::write_atomic(&a.out, toml.as_bytes()).with_context(|| format!("writing {}", a.out.display()))?;
    let marks = toml.lines().filter(|l| !l.starts_with('#') && l.contains(init::skeleton::FILL_IN)).count();
    if a.output.json {
        let doc = serde_json::json!({
            "out": a.out, "recording": a.recording, "kind": kind.to_string(), "joints": joints,
            "joint_states": topic, "skeleton": true, "to_fill_in": marks,
        });
        return super::print_json("init", doc);
    }
    println!(
        "wrote {}: a {kind} skeleton with the joints of {topic} ({}); the recording has no URDF, so {marks} values \
         are marked {}: measure them, write them and remove the marks (omnical refuses the file until then)",
        a.out.display(),
        joints.join(", "),
        init::skeleton::FILL_IN
    );
    Ok(())
}

fn urdf_label(path: &Path, source: &UrdfSource) -> String {
    if source.label.starts_with("topic ") { source.label.clone() } else { path.display().to_string() }
}
