//! `omnical export`: trajectories for other tools — TUM files for evo, MCAP bags with the calibrated
//! odometry for Foxglove.

use super::{DataArgs, OutputArgs};
use crate::api::ModelSpec;
use crate::api::load::{DataOptions, LoadRequest};
use crate::design::{design_for, designs_for};
use crate::export::{RecordedTopics, joint_names, write_mcap, write_tum};
use crate::out_path::{self, OutDir};
use crate::report::tum;
use crate::robot_config;
use omni_kin::RunModels;
use std::path::{Path, PathBuf};

/// Arguments of `omnical export`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (from `train --out`) or `design`.
    #[arg(long)]
    pub model: ModelSpec,
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
    /// would be taken for this export's); with --robot-config, also export a model marked interrupted
    /// (a `train` stopped by Ctrl-C), which is refused without it.
    #[arg(long)]
    pub force: bool,
    /// Write the calibration for the robot into this folder: the matrix as ROS 2 parameters
    /// (omnical_odometry.yaml) and as a C header (omnical_odometry.h), and the parameters of the
    /// matching ros2_controllers drive controller (ros2_controllers.yaml) from the nearest parametric fit,
    /// with the accuracy it gives up on the runs (docs/applying.md). Other files in the folder stay.
    #[arg(long, value_name = "DIR")]
    pub robot_config: Option<PathBuf>,
    /// Drive controller for --robot-config (default: the one that matches the base).
    #[arg(long, value_name = "NAME", value_parser = crate::cli::choice::<crate::controller::ControllerKind>())]
    pub controller: Option<crate::controller::ControllerKind>,
    /// Output options (JSON: the files written).
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
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
    let inputs = a.data.options().inputs(&a.runs).with_some("--model", a.model.file());
    if let Some(dir) = &a.robot_config {
        out_path::check_apart(dir, "--robot-config", &inputs)?;
    }
    let tum = a.tum.as_deref().map(|d| OutDir::claim(d, "--tum", a.force, &inputs)).transpose()?;
    let mcap = a.mcap.as_deref().map(|d| OutDir::claim(d, "--mcap", a.force, &inputs)).transpose()?;
    if let Some(dir) = &a.robot_config {
        out_path::prepare_dir(dir, "--robot-config")?;
    }
    Ok((tum, mcap))
}

/// Runs `omnical export`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    if a.tum.is_none() && a.mcap.is_none() && a.robot_config.is_none() {
        anyhow::bail!("nothing to export: give --tum DIR and/or --mcap DIR (or --robot-config DIR)");
    }
    if a.robot_config.is_some() && !a.force && a.model.interrupted() {
        anyhow::bail!(
            "--robot-config: {}: {}; a robot should get a finished fit: train again without stopping it, or \
             give --force to export this one anyway",
            a.model,
            crate::model_file::INTERRUPTED_REASON
        );
    }
    let (tum_dir, mcap_dir) = claim_folders(a)?;
    let data = a.data.options();
    let (mut ds, against) = load(a, &data)?;
    let model = a.model.resolve(&ds)?;
    // Each run's own input's design (for the design's odometry and accuracy); `--model design` is each
    // run's own in the trajectories too.
    let designs = designs_for(&model, &[&ds]);
    let design = design_for(&model);
    let models = a.model.resolve_each(&[&ds])?;
    if against == robot_config::Against::ModelOdometry {
        ds.runs = with_model_odometry(ds.runs, &models)?;
    }
    let spec = a.model.to_string();
    let mut doc = serde_json::json!({ "model": spec, "runs": ds.runs.len() });
    if let Some(out) = tum_dir {
        doc["tum"] = export_tum(out, &ds, (&designs, &models), &spec, a.output.json)?;
    }
    if let Some(out) = mcap_dir {
        let files: Vec<PathBuf> = write_mcaps(out.path(), &data, &ds, &models)?.iter().map(|f| out.shown(f)).collect();
        let dir = out.target().to_path_buf();
        out.commit()?;
        doc["mcap"] = serde_json::json!({ "dir": dir, "files": files });
        if !a.output.json {
            println!(
                "wrote {} to {} (topics /joint_states, /ground_truth/pose, /omnical/odometry, and the recording's \
                 /tf, /tf_static, /robot_description, /cmd_vel where it has them)",
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
            spec: &spec,
            runs: &ds.runs,
            against,
            wheel_names: joint_names(&model, &data.wheel_joints(&ds)),
            controller: a.controller,
            noise: match &a.model {
                crate::api::ModelSpec::File(path) => crate::model_file::read_noise(path)?,
                _ => None,
            },
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

/// The runs to export. `--robot-config` alone needs no ground truth: when the runs cannot be read with it
/// but can without it (their wheels alone), they are, and a note says that the accuracy figures are against
/// the calibrated model's own odometry. `--tum` and `--mcap` export the ground truth, so they need it.
fn load(a: &Args, data: &DataOptions) -> anyhow::Result<(crate::dataset::Dataset, robot_config::Against)> {
    let request = LoadRequest { recorded_odometry: true, ..LoadRequest::new(&a.runs, data) };
    let with_truth = match request.load() {
        Ok(ds) => return Ok((ds, robot_config::Against::GroundTruth)),
        Err(e) if a.tum.is_none() && a.mcap.is_none() => e,
        Err(e) => return Err(e.into()),
    };
    let Ok(ds) = LoadRequest { wheels_only: true, ..request }.load() else {
        return Err(with_truth.into());
    };
    crate::note!(
        "note: the runs have no ground truth ({with_truth:#}): --robot-config is exported from the model, and its \
         accuracy figures are measured against the model's own odometry"
    );
    Ok((ds, robot_config::Against::ModelOdometry))
}

/// `runs` with their reference poses replaced by the odometry of their own model in `models` (for runs
/// without ground truth).
fn with_model_odometry(runs: Vec<omni_kin::Run>, models: &RunModels) -> anyhow::Result<Vec<omni_kin::Run>> {
    runs.into_iter()
        .map(|run| {
            let poses = crate::export::odometry_poses(models.for_run(&run)?, &run)?;
            let mut data = run.into_data();
            data.truth = poses;
            Ok(omni_kin::Run::new(data)?)
        })
        .collect()
}

/// `--tum`: three TUM files per run (ground truth, each run's design, the calibrated `models`) in `out`,
/// committed; their JSON (folder and files), and a line on stdout unless `json`.
fn export_tum(
    out: OutDir,
    ds: &crate::dataset::Dataset,
    (designs, models): (&RunModels, &RunModels),
    spec: &str,
    json: bool,
) -> anyhow::Result<serde_json::Value> {
    let dir = out.target().to_path_buf();
    let mut files = Vec::new();
    for run in &ds.runs {
        let origin_s = ds.time_origins_s.get(run.name()).copied();
        let written = write_tum(out.path(), run, designs.for_run(run)?, models.for_run(run)?, spec, origin_s)?;
        files.extend(written.iter().map(|f| out.shown(f)));
    }
    out.commit()?;
    if !json {
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
    Ok(serde_json::json!({ "dir": dir, "files": files }))
}

/// One MCAP bag per run in `dir`, with the calibrated odometry and the recording's transforms, URDF and
/// commands; returns the paths.
fn write_mcaps(
    dir: &Path,
    data: &DataOptions,
    ds: &crate::dataset::Dataset,
    models: &RunModels,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut files = Vec::with_capacity(ds.runs.len());
    let mut recorded = RecordedTopics::new(&ds.recordings, data.max_file_mb.saturating_mul(1 << 20));
    for run in &ds.runs {
        let origin_s = ds.time_origins_s.get(run.name()).copied();
        let topics = recorded.for_run(run)?;
        files.push(write_mcap(dir, run, models.for_run(run)?, &data.wheel_joints(ds), origin_s, topics)?);
    }
    Ok(files)
}

/// `--robot-config` in JSON: the files, the controller and its parameters (SI units, unit-suffixed keys),
/// and the accuracy of each model on the runs (Eq. 6; path RMS, m).
fn robot_config_json(c: &robot_config::RobotConfig, dir: &Path) -> serde_json::Value {
    use crate::controller::ControllerParams as P;
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
            "against": c.against.id(),
            "design": acc(&c.design_accuracy),
            "model": acc(&c.model_accuracy),
            "matrix": c.matrix_accuracy.as_ref().map(acc),
            "controller": acc(&c.controller_accuracy),
        },
    })
}
