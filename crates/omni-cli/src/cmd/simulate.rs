//! `omnical simulate`: write a flower-benchmark dataset from a true robot with optional hidden effects.

use crate::robot_file::{self, RobotFile};
use crate::{atomic, dataset, design, model_file};
use anyhow::{Context, bail};
use omni_kin::cost::{self, CostKind};
use omni_kin::effect::Effect;
use omni_kin::simulate::{SimConfig, simulate};
use omni_kin::{EffectKind, FittedModel, IkMatrix, Model, RobotGeometry, Run};
use serde_json::json;
use std::path::{Path, PathBuf};

/// ROS time of the simulator's t = 0 in MCAP output (2023-11-14T22:13:20Z). s.
pub const SIM_EPOCH_S: i64 = 1_700_000_000;

/// Seed of the training split (validation: seed + 1), here and in `demo`.
pub const DEFAULT_SEED: u64 = 7;

/// Dataset file format for writing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// omnical CSV, one file per run (docs/formats.md).
    Csv,
    /// ROS 2 MCAP bag, one file per run.
    Mcap,
}

/// Arguments of `omnical simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder: writes train/, validation/, truth.json and truth_model.toml.
    #[arg(long)]
    pub out: PathBuf,
    /// Seed (training uses it, validation seed + 1).
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub seed: u64,
    /// Repetitions of each of the 36 commands.
    #[arg(long, default_value_t = SimConfig::default().runs_per_command)]
    pub runs_per_command: usize,
    /// Duration of each command. s.
    #[arg(long = "duration", value_name = "DURATION", default_value_t = SimConfig::default().duration_s)]
    pub duration_s: f64,
    /// Inject an effect into the true robot: NAME=V1,V2,… in the effect's parameter order
    /// (`sample_timing=DROP_PROBABILITY,JITTER_S`). Repeatable.
    #[arg(long = "effect", value_name = "NAME=VALUES")]
    pub effects: Vec<String>,
    /// True robot: `paper` (Eq. 9, APR-02 only), `design` (the robot's design) or a model file.
    #[arg(long, default_value = "paper")]
    pub truth: String,
    /// The robot: its design drives the simulated controller and is written as robot.toml beside the
    /// runs. Default: `apr02`, the paper's robot.
    #[arg(long, value_name = "FILE|apr02", default_value = robot_file::BUILTIN_APR02)]
    pub robot: String,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Mcap)]
    pub format: Format,
    /// No encoder quantisation and no noise.
    #[arg(long)]
    pub noise_free: bool,
}

/// Parse `NAME=V1,V2,…` and add the effect to `truth` (or, for `sample_timing`, to the simulator config).
pub fn apply_effect_spec(spec: &str, truth: &mut FittedModel, config: &mut SimConfig) -> anyhow::Result<()> {
    let (name, values) = spec.split_once('=').unwrap_or((spec, ""));
    let values: Vec<f64> = values
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse::<f64>().with_context(|| format!("--effect {spec}: {s:?} is not a number")))
        .collect::<anyhow::Result<_>>()?;
    let n_wheels = truth.model.n_wheels();
    let id = if name == "sensor_offset" && values.len() == 3 { "sensor_offset_yaw" } else { name };
    let effect = EffectKind::from_id(id, n_wheels).with_context(|| format!("--effect {spec}"))?;
    if id == "sample_timing" {
        if values.is_empty() || values.len() > 2 {
            bail!("--effect {spec}: sample_timing takes DROP_PROBABILITY[,JITTER_S], e.g. sample_timing=0.05,0.002");
        }
        config.sample_drop_probability = values[0];
        config.sample_jitter_s = values.get(1).copied().unwrap_or(0.0);
        *truth = truth.with_effect(effect);
        return Ok(());
    }
    let specs = effect.params();
    if values.len() != specs.len() {
        let names: Vec<String> = specs.iter().map(|p| format!("{} ({})", p.name, p.unit)).collect();
        bail!("--effect {spec}: {id} takes {} values: {}", specs.len(), names.join(", "));
    }
    let start = truth.params.len();
    *truth = truth.with_effect(effect);
    truth.params[start..].copy_from_slice(&values);
    Ok(())
}

fn write_split(dir: &Path, runs: &[Run], format: Format, wheel_names: &[String]) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for r in runs {
        let stem = r.name().rsplit('/').next().unwrap_or(r.name());
        match format {
            Format::Csv => dataset::csv::write_run(&dir.join(format!("{stem}.csv")), r, wheel_names)?,
            Format::Mcap => {
                let w = dataset::mcap::WriteOptions {
                    wheel_joints: wheel_names.to_vec(),
                    design_odometry: Some(r.recorded_odometry().to_vec()),
                    // Simulated clocks start at 0 s (wheel data from −0.5 s): put them at a plausible epoch.
                    origin_s: SIM_EPOCH_S,
                    ..Default::default()
                };
                dataset::mcap::write_run(&dir.join(format!("{stem}.mcap")), r, &w)?
            }
        }
    }
    Ok(())
}

/// The simulated robot's design (from `--robot`) and its true model (from `--truth`).
fn design_and_truth(a: &Args) -> anyhow::Result<(RobotFile, RobotGeometry, FittedModel, FittedModel)> {
    let robot = robot_file::from_arg(&a.robot).context("--robot")?;
    let geometry = robot.description.to_geometry().with_context(|| format!("--robot {}", robot.source))?;
    let design_ik = robot.description.design_ik().with_context(|| format!("--robot {}", robot.source))?;
    let design = FittedModel::nominal(Model::ik(design_ik.clone()));
    let truth = match a.truth.as_str() {
        "paper" if design_ik != IkMatrix::paper_design() => bail!(
            "--truth paper is the paper's Eq. 9, a calibration of APR-02, and --robot {} is another robot: give \
             --truth design (the design itself) or --truth FILE (a model file)",
            robot.source
        ),
        "paper" => design::paper_calibrated(),
        "design" => design.clone(),
        path => model_file::read(Path::new(path)).context("reading --truth")?,
    };
    let joints = robot.description.joints();
    if truth.model.n_wheels() != joints.len() {
        bail!(
            "--truth has {} wheels and --robot {} has {} ({})",
            truth.model.n_wheels(),
            robot.source,
            joints.len(),
            joints.join(", ")
        );
    }
    Ok((robot, geometry, design, truth))
}

/// Writes `robot.toml` into a split's folder, so that commands reading the runs find the robot.
fn write_robot(dir: &Path, robot: &RobotFile) -> anyhow::Result<()> {
    let comments = robot_file::Comments {
        header: vec![format!(
            "The robot these simulated runs were made with (omnical simulate --robot {}): its design, joint names \
             and topics. Commands reading this folder use it.",
            robot.source
        )],
        ..Default::default()
    };
    let path = dir.join(robot_file::FILE_NAME);
    let text = robot_file::to_toml(&robot.description, &comments);
    atomic::write_atomic(&path, text.as_bytes()).with_context(|| format!("writing {}", path.display()))
}

/// Runs `omnical simulate`; `quiet` hides the progress display.
pub fn run(a: &Args, quiet: bool) -> anyhow::Result<()> {
    let (robot, geometry, design, mut truth) = design_and_truth(a)?;
    let mut config = SimConfig {
        design: geometry,
        runs_per_command: a.runs_per_command,
        duration_s: a.duration_s,
        ..SimConfig::default()
    };
    if a.noise_free {
        config = config.noise_free();
    }
    for spec in &a.effects {
        apply_effect_spec(spec, &mut truth, &mut config)?;
    }
    let wheel_names = robot.description.joints();
    let mut summary = serde_json::Map::new();
    for (split, seed) in [("train", a.seed), ("validation", a.seed.wrapping_add(1))] {
        let cfg = SimConfig { seed, ..config.clone() };
        let spinner = crate::progress::spinner(format!("simulating and writing {split} runs"), quiet);
        let runs = simulate(&cfg, &truth, &format!("{split}/"))?;
        write_split(&a.out.join(split), &runs, a.format, &wheel_names)?;
        write_robot(&a.out.join(split), &robot)?;
        spinner.finish_and_clear();
        let costs: Vec<(String, f64)> = [CostKind::EndPose, CostKind::PATH]
            .iter()
            .flat_map(|&k| {
                let d = cost::cost(&design.model, &design.params, &runs, k);
                let o = cost::cost(&truth.model, &truth.params, &runs, k);
                [(format!("design_{}", k.name()), d), (format!("oracle_{}", k.name()), o)]
            })
            .map(|(n, c)| c.map(|c| (n, c)))
            .collect::<Result<_, _>>()?;
        let entry: serde_json::Map<String, serde_json::Value> = costs
            .iter()
            .map(|(n, c)| (n.clone(), json!(c)))
            .chain([("seed".to_string(), json!(seed)), ("runs".to_string(), json!(runs.len()))])
            .collect();
        // The summary prints whatever --quiet says (it only hides progress).
        println!(
            "{split}: {} runs, design cost {:.4}, oracle cost {:.4} (Eq. 6; path: {:.4} vs {:.4})",
            runs.len(),
            costs[0].1,
            costs[1].1,
            costs[2].1,
            costs[3].1
        );
        summary.insert(split.into(), serde_json::Value::Object(entry));
    }
    let truth_toml = model_file::to_toml(&truth, None).map_err(anyhow::Error::msg)?;
    atomic::write_atomic(&a.out.join("truth_model.toml"), truth_toml.as_bytes())
        .with_context(|| format!("writing {}", a.out.join("truth_model.toml").display()))?;
    let doc = json!({
        "design_cost": { "train": summary["train"]["design_end_pose"], "validation": summary["validation"]["design_end_pose"] },
        "oracle_cost": { "train": summary["train"]["oracle_end_pose"], "validation": summary["validation"]["oracle_end_pose"] },
        "splits": summary,
        "true_model": model_file::ModelFile::from_fitted(&truth, None)?,
        "effects": a.effects,
        "seed": a.seed,
        "simulator": config,
        "cost": "design_cost and oracle_cost are the paper's Eq. 6 with exact-arc odometry; path costs are RMS over every ground-truth pose",
    });
    let text = serde_json::to_string_pretty(&doc)?;
    atomic::write_atomic(&a.out.join("truth.json"), text.as_bytes())
        .with_context(|| format!("writing {}", a.out.join("truth.json").display()))?;
    println!("wrote {}", a.out.display());
    Ok(())
}
