//! `omnical export`: trajectories for other tools — TUM files for evo, MCAP bags with the calibrated
//! odometry for Foxglove.

use super::{DataArgs, OutputArgs, load_runs_with_odometry, resolve_model, wheel_joints};
use crate::dataset::mcap::{WriteOptions, write_run};
use crate::design::{design_for, designs_for};
use crate::out_path::{self, OutDir};
use crate::report::tum;
use crate::{atomic, robot_config};
use anyhow::Context;
use omni_kin::odometry::{self, Selection};
use omni_kin::{FittedModel, Run, RunModels, StampedPose};
use std::path::{Path, PathBuf};

/// Arguments of `omnical export`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (from `train --out`) or `design`.
    #[arg(long)]
    pub model: String,
    /// Run files or folders.
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Write `<run>.gt.tum`, `<run>.design.tum` and `<run>.calibrated.tum` into this folder (new or empty,
    /// unless --force).
    #[arg(long, value_name = "DIR")]
    pub tum: Option<PathBuf>,
    /// Write one MCAP bag per run into this folder, with the calibrated odometry added (new or empty,
    /// unless --force).
    #[arg(long, value_name = "DIR")]
    pub mcap: Option<PathBuf>,
    /// Replace a --tum or --mcap folder that already holds files, whole (files of other runs left in it
    /// would be taken for this export's).
    #[arg(long)]
    pub force: bool,
    /// Write the calibration for the robot into this folder: the matrix as ROS 2 parameters
    /// (omnical_odometry.yaml) and as a C header (omnical_odometry.h), and the parameters of the
    /// matching ros2_controllers drive controller (ros2_controllers.yaml) from the nearest parametric fit,
    /// with the accuracy it gives up on the runs (docs/applying.md). Other files in the folder stay.
    #[arg(long, value_name = "DIR")]
    pub robot_config: Option<PathBuf>,
    /// Drive controller for --robot-config (default: the one that matches the base).
    #[arg(long, value_name = "NAME", value_parser = crate::cli::choice::<omni_kin::controller::ControllerKind>())]
    pub controller: Option<omni_kin::controller::ControllerKind>,
    /// Output options (JSON: the files written).
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// The odometry of the measured point: every wheel-sample step plus the exact predictions at the
/// ground-truth stamps (so tools that match poses by time find an exact match), in time order.
pub fn odometry_poses(model: &FittedModel, run: &Run) -> anyhow::Result<Vec<StampedPose>> {
    let res = model.model.resolve(&model.params).with_context(|| format!("run {}", run.name()))?;
    let dense = odometry::integrate(&res, run);
    let mut poses: Vec<StampedPose> =
        dense.t_s.iter().zip(&dense.poses).map(|(&t_s, &pose)| StampedPose { t_s, pose }).collect();
    let at_truth = odometry::residuals(&res, run, Selection::Path(1));
    poses.retain(|p| !at_truth.iter().any(|r| (r.t_s - p.t_s).abs() < 1e-9));
    poses.extend(at_truth.iter().map(|r| StampedPose { t_s: r.t_s, pose: r.predicted }));
    poses.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
    Ok(poses)
}

/// The output folders of `export`, claimed before the work: `--tum` and `--mcap` are new or emptied
/// ([`OutDir`]), `--robot-config` is created if missing. Refuses one folder named twice.
fn claim_folders(a: &Args) -> anyhow::Result<(Option<OutDir>, Option<OutDir>)> {
    let named = [("--tum", &a.tum), ("--mcap", &a.mcap), ("--robot-config", &a.robot_config)];
    for (i, (flag, dir)) in named.iter().enumerate() {
        for (other, same) in &named[i + 1..] {
            if let (Some(d), Some(s)) = (dir, same)
                && d.components().eq(s.components())
            {
                anyhow::bail!("{flag} and {other} name the same folder {}: give each its own", d.display());
            }
        }
    }
    if let Some(dir) = &a.robot_config {
        out_path::prepare_dir(dir, "--robot-config")?;
    }
    let tum = a.tum.as_deref().map(|d| OutDir::claim(d, "--tum", a.force)).transpose()?;
    let mcap = a.mcap.as_deref().map(|d| OutDir::claim(d, "--mcap", a.force)).transpose()?;
    Ok((tum, mcap))
}

/// Runs `omnical export`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    if a.tum.is_none() && a.mcap.is_none() && a.robot_config.is_none() {
        anyhow::bail!("nothing to export: give --tum DIR and/or --mcap DIR (or --robot-config DIR)");
    }
    let (tum_dir, mcap_dir) = claim_folders(a)?;
    let ds = load_runs_with_odometry(&a.runs, &a.data)?;
    let model = resolve_model(&a.model, &ds)?;
    // Each run's own input's design (for the design's odometry and accuracy); `--model design` is each
    // run's own in the trajectories too.
    let designs = designs_for(&model, &[&ds]);
    let design = design_for(&model);
    let models = crate::design::resolve_each(&a.model, &[&ds])?;
    let mut doc = serde_json::json!({ "model": a.model, "runs": ds.runs.len() });
    if let Some(out) = tum_dir {
        let dir = out.target().to_path_buf();
        let mut files = Vec::new();
        for run in &ds.runs {
            files.extend(
                write_tum(out.path(), run, designs.for_run(run)?, models.for_run(run)?, &a.model)?
                    .iter()
                    .map(|f| out.shown(f)),
            );
        }
        out.commit()?;
        doc["tum"] = serde_json::json!({ "dir": dir, "files": files });
        if !a.output.json {
            println!(
                "wrote {} × 3 TUM files (ground truth, design, calibrated) to {}; e.g. evo_ape tum {}",
                crate::units::count(ds.runs.len(), "run"),
                dir.display(),
                ds.runs.first().map_or_else(String::new, |r| {
                    let s = tum::file_stem(r.name());
                    format!("{0}/{s}.gt.tum {0}/{s}.calibrated.tum", dir.display())
                })
            );
        }
    }
    if let Some(out) = mcap_dir {
        let files: Vec<PathBuf> = write_mcaps(out.path(), a, &ds, &models)?.iter().map(|f| out.shown(f)).collect();
        let dir = out.target().to_path_buf();
        out.commit()?;
        doc["mcap"] = serde_json::json!({ "dir": dir, "files": files });
        if !a.output.json {
            println!(
                "wrote {} to {} (topics /joint_states, /ground_truth/pose, /omnical/odometry, …)",
                crate::units::count(ds.runs.len(), "MCAP file"),
                dir.display()
            );
        }
    }
    if let Some(dir) = &a.robot_config {
        let request = robot_config::Request {
            model: &model,
            design: &design,
            designs: &designs,
            spec: &a.model,
            runs: &ds.runs,
            wheel_names: joint_names(&model, &wheel_joints(&a.data, &ds)),
            controller: a.controller,
        };
        let config = robot_config::build(&request)?;
        robot_config::write(dir, &config)?;
        for w in robot_config::warning_lines(&config) {
            tracing::warn!("{w}");
        }
        if a.output.json {
            doc["robot_config"] = robot_config_json(&config, dir);
        } else {
            print!("{}", robot_config::summary(&config, dir));
        }
    }
    if a.output.json {
        return super::print_json("export", doc);
    }
    Ok(())
}

/// One MCAP bag per run in `dir`, with the calibrated odometry; returns the paths.
fn write_mcaps(dir: &Path, a: &Args, ds: &crate::dataset::Dataset, models: &RunModels) -> anyhow::Result<Vec<PathBuf>> {
    let mut files = Vec::with_capacity(ds.runs.len());
    for run in &ds.runs {
        files.push(write_mcap(dir, run, models.for_run(run)?, &wheel_joints(&a.data, ds))?);
    }
    Ok(files)
}

/// `--robot-config` in JSON: the files, the controller and its parameters (SI units, unit-suffixed keys),
/// and the accuracy of each model on the runs (Eq. 6; path RMS, m).
fn robot_config_json(c: &robot_config::RobotConfig, dir: &Path) -> serde_json::Value {
    use omni_kin::controller::ControllerParams as P;
    let params = match c.fit.model.params {
        P::DiffDrive { wheel_separation_m, left_wheel_radius_m, right_wheel_radius_m } => serde_json::json!({
            "wheel_separation_m": wheel_separation_m, "left_wheel_radius_m": left_wheel_radius_m,
            "right_wheel_radius_m": right_wheel_radius_m,
        }),
        P::MecanumDrive { wheels_radius_m, lx_plus_ly_m } => {
            serde_json::json!({ "wheels_radius_m": wheels_radius_m, "lx_plus_ly_m": lx_plus_ly_m })
        }
        P::OmniWheelDrive { wheel_radius_m, robot_radius_m, wheel_offset_rad } => serde_json::json!({
            "wheel_radius_m": wheel_radius_m, "robot_radius_m": robot_radius_m, "wheel_offset_rad": wheel_offset_rad,
        }),
    };
    let acc = |a: &robot_config::Accuracy| serde_json::json!({ "end_pose": a.end_pose, "path_rms_m": a.path_rms });
    let files: Vec<PathBuf> =
        [robot_config::ODOMETRY_YAML, robot_config::ODOMETRY_HEADER, robot_config::CONTROLLER_YAML]
            .iter()
            .map(|f| dir.join(f))
            .collect();
    serde_json::json!({
        "dir": dir,
        "files": files,
        "controller": c.kind().id(),
        "controller_params": params,
        "accuracy": {
            "runs": c.n_runs,
            "design": acc(&c.design_accuracy),
            "model": acc(&c.model_accuracy),
            "matrix": c.matrix_accuracy.as_ref().map(acc),
            "controller": acc(&c.controller_accuracy),
        },
    })
}

/// Joint names in the model's column order: the model's own, or `--joints` when the model only has the
/// default names `wheel_a`, `wheel_b`, ….
fn joint_names(model: &FittedModel, joints: &[String]) -> Vec<String> {
    let names = model.model.kinematics.wheel_names();
    if names == omni_kin::geometry::default_wheel_names(names.len()) && joints.len() == names.len() {
        joints.to_vec()
    } else {
        names
    }
}

/// Writes one run's MCAP bag `DIR/<run>.mcap` (`--mcap`): its wheel data (joints `wheel_joints`), ground
/// truth, recorded odometry if any, and `model`'s odometry on /omnical/odometry; a run whose clock starts
/// before 0 s (a simulated one) is put at the simulator's epoch. Returns the path.
pub fn write_mcap(dir: &Path, run: &Run, model: &FittedModel, wheel_joints: &[String]) -> anyhow::Result<PathBuf> {
    let opts = WriteOptions {
        wheel_joints: wheel_joints.to_vec(),
        design_odometry: (!run.recorded_odometry().is_empty()).then(|| run.recorded_odometry().to_vec()),
        calibrated_odometry: Some(odometry_poses(model, run)?),
        // Simulated clocks start before 0 s (as `simulate` does): put them at its epoch.
        origin_s: if run.wheel_t_s().first().is_some_and(|&t| t < 0.0) { super::simulate::SIM_EPOCH_S } else { 0 },
    };
    let path = dir.join(format!("{}.mcap", tum::file_stem(run.name())));
    write_run(&path, run, &opts)?;
    Ok(path)
}

/// Writes one run's TUM files (`--tum`): `DIR/<run>.gt.tum`, `.design.tum` and `.calibrated.tum`, the
/// latter two the odometry of `design` and of `model` (named `spec` in the header). Returns the paths.
pub fn write_tum(
    dir: &Path,
    run: &Run,
    design: &FittedModel,
    model: &FittedModel,
    spec: &str,
) -> anyhow::Result<Vec<PathBuf>> {
    let stem = tum::file_stem(run.name());
    let files = [
        ("gt", format!("run {}: ground truth", run.name()), run.truth().to_vec()),
        ("design", format!("run {}: odometry of the design model", run.name()), odometry_poses(design, run)?),
        ("calibrated", format!("run {}: odometry of {spec}", run.name()), odometry_poses(model, run)?),
    ];
    let mut written = Vec::with_capacity(files.len());
    for (kind, comment, poses) in files {
        let path = dir.join(format!("{stem}.{kind}.tum"));
        let text = tum::to_tum(&format!("{comment}\ntimestamp tx ty tz qx qy qz qw (s, m, unit quaternion)"), &poses);
        atomic::write_atomic(&path, text.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}
