//! Subcommand implementations: load, call the library, format.

pub mod demo;
pub mod diagnose;
pub mod eval;
pub mod export;
pub mod init;
pub mod plan;
pub mod report;
pub mod simulate;
pub mod train;

use crate::cli::DataArgs;
use crate::dataset::{self, Dataset, LoadOptions};
use crate::robot_file::{self, Design};
use anyhow::Context;
use omni_kin::{FittedModel, IkMatrix, KinematicsKind, Model, RobotGeometry};
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
    let robot = robot_file::resolve(data.robot.robot.as_deref(), paths)?;
    if let Some(r) = &robot {
        robot_file::announce(&r.source);
    }
    let mut mcap = dataset::mcap::McapOptions {
        wheel_joints: data.joints.clone().unwrap_or_default(),
        joints_topic: data.joints_topic.clone(),
        truth_topic: data.gt_topic.clone(),
        truth_parent_frame: data.gt_parent_frame.clone(),
        truth_child_frame: data.gt_child_frame.clone(),
        split: data.split,
        skip_invalid: data.skip_invalid,
        recorded_odometry,
        ..Default::default()
    };
    robot_file::fill_mcap_options(&mut mcap, data.joints.is_none(), robot.as_ref().map(|r| &r.description));
    let opts = LoadOptions {
        skip_invalid: data.skip_invalid,
        ticks_per_rev: data.ticks_per_rev,
        mcap,
        recorded_odometry,
        max_file_bytes: data.max_file_mb.saturating_mul(1 << 20),
        ground_truth: ground_truth_options(data, robot.as_ref())?,
    };
    let mut ds = dataset::load(paths, &opts)?;
    ds.robot_file = robot;
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
    for c in &ds.ground_truth_clocks {
        eprintln!("{}", c.describe());
    }
    Ok(ds)
}

/// `--gt` and its options, over the robot description's `[ground_truth]` (its `file` relative to the
/// description's folder).
fn ground_truth_options(
    data: &DataArgs,
    robot: Option<&robot_file::RobotFile>,
) -> anyhow::Result<Option<dataset::ground_truth::GroundTruthOptions>> {
    let from_robot = robot.and_then(|r| r.description.ground_truth.as_ref().map(|g| (r, g)));
    let path = match (&data.gt, from_robot.and_then(|(r, g)| g.file.as_ref().map(|f| (r, f)))) {
        (Some(p), _) => p.clone(),
        (None, Some((r, file))) => match &r.source {
            robot_file::Source::Flag(p) | robot_file::Source::Discovered(p) => {
                p.parent().unwrap_or(Path::new("")).join(file)
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
    for kv in data.gt_columns.iter().chain(&data.gt_units) {
        anyhow::ensure!(kv.contains('='), "--gt-columns/--gt-units {kv:?}: expected KEY=VALUE");
    }
    columns.extend(settings(&data.gt_columns));
    units.extend(settings(&data.gt_units));
    for (k, v) in &columns {
        csv.set_column(k, v).map_err(anyhow::Error::msg)?;
    }
    for (k, v) in &units {
        csv.set_unit(k, v).map_err(anyhow::Error::msg)?;
    }
    let time_offset_s = data.gt_time_offset.or(from_robot.and_then(|(_, g)| g.time_offset_s));
    Ok(Some(dataset::ground_truth::GroundTruthOptions { path, time_offset_s, csv }))
}

/// The design model of `kind` for a dataset's robot: `--robot`, else the data's own geometry (OptiOdom), else
/// a found robot.toml; none of them is an error saying how to describe the robot. A robot description's
/// `ik` design is its design matrix (the paper's Eq. 7 for APR-02; the closed form for diff).
pub fn design_model(kind: KinematicsKind, ds: &Dataset) -> anyhow::Result<Model> {
    match robot_file::design(ds) {
        Some(Design::File(f)) if kind == KinematicsKind::Ik => {
            Ok(Model::ik(f.description.design_ik().with_context(|| format!("robot {}", f.source))?))
        }
        Some(Design::File(f)) => {
            let g = f.description.to_geometry().with_context(|| format!("robot {}", f.source))?;
            Ok(Model::design(kind, Some(&g))?)
        }
        Some(Design::Data(g)) => Ok(Model::design(kind, Some(g))?),
        None => Err(robot_file::no_design("the design model")),
    }
}

/// The design geometry of a dataset's robot (`--robot`, the data's geometry, or a found robot.toml).
pub fn design_geometry(ds: &Dataset) -> anyhow::Result<RobotGeometry> {
    match robot_file::design(ds) {
        Some(Design::File(f)) => f.description.to_geometry().with_context(|| format!("robot {}", f.source)),
        Some(Design::Data(g)) => Ok(g.clone()),
        None => Err(robot_file::no_design("the design geometry")),
    }
}

/// `design` / `paper` or a model file.
pub fn resolve_model(spec: &str, ds: &Dataset) -> anyhow::Result<FittedModel> {
    match spec {
        "design" => match robot_file::design(ds) {
            Some(Design::File(_)) => Ok(FittedModel::nominal(design_model(KinematicsKind::Ik, ds)?)),
            // A two-wheel base (OptiOdom's diff) has no omnidirectional geometry model: its own.
            Some(Design::Data(g)) if g.n_wheels() == 2 => {
                Ok(FittedModel::nominal(Model::design(KinematicsKind::Diff, Some(g))?))
            }
            Some(Design::Data(g)) => Ok(FittedModel::nominal(Model::geometry(g.clone()))),
            None => Err(robot_file::no_design("--model design")),
        },
        "paper" => Ok(FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))),
        path => crate::model_file::read(Path::new(path)).context("reading the model"),
    }
}

/// The wheel joint names the runs were read with: `--joints`, else the robot description's, else the
/// default `wheel_a`, `wheel_b`, `wheel_c`.
pub fn wheel_joints(data: &DataArgs, ds: &Dataset) -> Vec<String> {
    let mut mcap =
        dataset::mcap::McapOptions { wheel_joints: data.joints.clone().unwrap_or_default(), ..Default::default() };
    robot_file::fill_mcap_options(&mut mcap, data.joints.is_none(), ds.robot_file.as_ref().map(|r| &r.description));
    mcap.wheel_joints
}
