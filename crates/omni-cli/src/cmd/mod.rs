//! Subcommand implementations: load, call the library, format.

pub mod demo;
pub mod diagnose;
pub mod eval;
pub mod export;
pub mod plan;
pub mod report;
pub mod simulate;
pub mod train;

use crate::cli::DataArgs;
use crate::dataset::{self, Dataset, LoadOptions};
use anyhow::Context;
use omni_kin::{FittedModel, IkMatrix, Model};
use std::path::{Path, PathBuf};

/// Load runs from files/folders, printing what was skipped or noticed on stderr. The runs' recorded
/// odometry is left out (no command but `export` shows it, and it would take as much memory as the wheel
/// data).
pub fn load_runs(paths: &[PathBuf], data: &DataArgs) -> anyhow::Result<Dataset> {
    load(paths, data, false)
}

/// [`load_runs`], keeping the runs' recorded odometry.
pub fn load_runs_with_odometry(paths: &[PathBuf], data: &DataArgs) -> anyhow::Result<Dataset> {
    load(paths, data, true)
}

fn load(paths: &[PathBuf], data: &DataArgs, recorded_odometry: bool) -> anyhow::Result<Dataset> {
    let mcap = dataset::mcap::McapOptions {
        wheel_joints: data.joints.clone(),
        joints_topic: data.joints_topic.clone(),
        truth_topic: data.gt_topic.clone(),
        truth_parent_frame: data.gt_parent_frame.clone(),
        truth_child_frame: data.gt_child_frame.clone(),
        split: data.split,
        skip_invalid: data.skip_invalid,
        recorded_odometry,
    };
    let opts = LoadOptions {
        skip_invalid: data.skip_invalid,
        ticks_per_rev: data.ticks_per_rev,
        mcap,
        recorded_odometry,
        max_file_bytes: data.max_file_mb.saturating_mul(1 << 20),
    };
    let ds = dataset::load(paths, &opts)?;
    // The same note from many files is printed once, with a count.
    let mut seen: Vec<(String, String, usize)> = Vec::new();
    for n in &ds.notes {
        let key = n.split_once(": ").map_or(n.as_str(), |(_, rest)| rest).to_string();
        match seen.iter_mut().find(|(k, _, _)| *k == key) {
            Some(entry) => entry.2 += 1,
            None => seen.push((key, n.clone(), 1)),
        }
    }
    for (_, first, count) in &seen {
        if *count > 1 {
            eprintln!("note: {first} (and {} more files)", count - 1);
        } else {
            eprintln!("note: {first}");
        }
    }
    for s in &ds.skipped {
        eprintln!("skipped {}: {}", s.source, s.reason);
    }
    Ok(ds)
}

/// `design` / `paper` or a model file.
pub fn resolve_model(spec: &str, ds: &Dataset) -> anyhow::Result<FittedModel> {
    match spec {
        "design" => Ok(match &ds.robot {
            Some(g) => FittedModel::nominal(Model::geometry(g.clone())),
            None => FittedModel::paper_design(),
        }),
        "paper" => Ok(FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))),
        path => crate::model_file::read(Path::new(path)).context("reading the model"),
    }
}
