//! `omnical demo`: the whole story on built-in simulated data with a hidden effect — simulate, train,
//! diagnose, add the effect, retrain — printing the error ladder — and write the HTML report.

use super::diagnose::print_diagnosis;
use super::sim_spec::apply_effect_spec;
use super::simulate::DEFAULT_SEED;
use super::train::print_summary;
use crate::design::{design_for, paper_calibrated};
use crate::report::{self, ReportInput};
use crate::{atomic, model_file, progress, robot_file};
use anyhow::Context;
use omni_ga::calibrate::{Plan, Preset, calibrate};
use omni_ga::diagnose::{DiagnoseOptions, diagnose};
use omni_kin::simulate::{SimConfig, simulate};
use omni_kin::{FittedModel, IkMatrix, Model};
use std::path::PathBuf;

/// Arguments of `omnical demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Write the models, the diagnosis and the HTML report (report.html) here.
    #[arg(long, default_value = "omnical-demo")]
    pub out: PathBuf,
    /// Repetitions of each command.
    #[arg(long, default_value_t = 2)]
    pub runs_per_command: usize,
    /// The hidden effect, NAME=VALUES as for `simulate --effect`.
    #[arg(long, default_value = "time_offset=0.06")]
    pub hidden: String,
    /// Run the demo on this robot (a robot.toml): its design is the start, the true robot deviates from
    /// it (wheel radii, a diff base's axle) and has the hidden effect. Default: the paper's APR-02 with
    /// its calibrated Eq. 9 as the true robot.
    #[arg(long, value_name = "FILE|apr02")]
    pub robot: Option<String>,
}

/// The simulated robot of a demo: its true model, the design it starts from, the simulator, and words.
struct Setup {
    truth: FittedModel,
    start: FittedModel,
    config: SimConfig,
    /// Joint names in column order.
    wheels: Vec<String>,
    /// "the paper's Eq. 9 matrix", "robot.toml's design with …".
    true_robot: String,
    /// "36 flower commands", "12 forward/backward arcs and turns".
    commands: String,
}

/// The paper's APR-02: its calibrated Eq. 9 is the true robot, the design Eq. 7 the start.
fn paper_setup(runs_per_command: usize) -> Setup {
    Setup {
        truth: paper_calibrated(),
        start: FittedModel::nominal(Model::ik(IkMatrix::paper_design())),
        config: SimConfig { runs_per_command, seed: DEFAULT_SEED, ..SimConfig::default() },
        wheels: omni_kin::geometry::default_wheel_names(3),
        true_robot: "the paper's Eq. 9 matrix".into(),
        commands: "36 flower commands".into(),
    }
}

/// How the demo's true robot on a `--robot` deviates from its design: wheel a 1.5 % larger, the last
/// wheel 1 % smaller, and a two-wheel base's axle 2 % longer (the `simulate --effect` specs).
pub fn demo_deviations(n_wheels: usize) -> Vec<String> {
    let last = char::from(b'a' + ((n_wheels.max(1) - 1) % 26) as u8);
    let mut v = vec!["wheel_radius:a=0.015".to_string(), format!("wheel_radius:{last}=-0.01")];
    if n_wheels == 2 {
        v.push("wheel_separation=0.02".into());
    }
    v
}

/// A robot description: its design matrix is the start, the true robot deviates by [`demo_deviations`].
fn robot_setup(arg: &str, runs_per_command: usize) -> anyhow::Result<Setup> {
    let robot = robot_file::from_arg(arg).context("--robot")?;
    let geometry = robot.description.to_geometry().with_context(|| format!("--robot {}", robot.source))?;
    let design = robot.description.design_ik().with_context(|| format!("--robot {}", robot.source))?;
    let start = FittedModel::nominal(Model::ik(design));
    let wheels = robot.description.joints();
    let mut truth = start.clone();
    let mut config = SimConfig { runs_per_command, seed: DEFAULT_SEED, ..SimConfig::for_robot(geometry) };
    let deviations = demo_deviations(wheels.len());
    for spec in &deviations {
        apply_effect_spec(spec, &mut truth, &mut config, &wheels)?;
    }
    let commands = if wheels.len() == 2 { "12 forward/backward arcs and turns" } else { "36 flower commands" };
    Ok(Setup {
        truth,
        start,
        config,
        true_robot: format!("the design of {} with {}", robot.source, deviations.join(", ")),
        commands: commands.into(),
        wheels,
    })
}

/// Runs `omnical demo`: on the paper's APR-02, or on `--robot` (a robot.toml; `apr02` is the paper's);
/// `quiet` hides the progress display.
pub fn run(a: &Args, quiet: bool) -> anyhow::Result<()> {
    let (dir, runs_per_command, hidden, robot) =
        (a.out.as_path(), a.runs_per_command, a.hidden.as_str(), a.robot.as_deref());
    let Setup { mut truth, start, mut config, wheels, true_robot, commands } = match robot {
        None | Some(robot_file::BUILTIN_APR02) => paper_setup(runs_per_command),
        Some(arg) => robot_setup(arg, runs_per_command)?,
    };
    apply_effect_spec(hidden, &mut truth, &mut config, &wheels)?;
    println!("== simulate: true robot = {true_robot} + a hidden effect ({hidden})");
    let spinner = progress::spinner("simulating", quiet);
    let train = simulate(&config, &truth, "train/")?;
    let val = simulate(&SimConfig { seed: DEFAULT_SEED + 1, ..config.clone() }, &truth, "validation/")?;
    spinner.finish_and_clear();
    println!("   {} training and {} validation runs", train.len(), val.len());
    let n_base = start.model.n_base();
    println!("== train: fit the {n_base}-entry IK matrix (preset default)");
    let preset = Preset::Default;
    let plan = Plan::preset(preset, n_base).seed(0);
    let mut bar = progress::ProgressObserver::new(plan.ga().map_or(0, |g| g.max_generations), quiet);
    let fit = calibrate(&start, &train, &plan, &mut bar)?;
    bar.finish();
    print_summary(&fit, preset.id(), train.len());
    println!("== diagnose: which physical effect is missing? (--auto: add effects while held-out error falls)");
    let opts = DiagnoseOptions { auto: true, ..DiagnoseOptions::default() };
    let spinner = progress::spinner("diagnosing: refitting each candidate effect", quiet);
    let design = design_for(&fit.fitted);
    let d = diagnose(&fit.fitted, &design, &train, Some(&val), &opts)?;
    spinner.finish_and_clear();
    print_diagnosis(&d);
    {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let write = |name: &str, fm: &FittedModel| -> anyhow::Result<()> {
            let text = model_file::to_toml(fm, None).map_err(anyhow::Error::msg)?;
            atomic::write_atomic(&dir.join(name), text.as_bytes()).with_context(|| format!("writing {name}"))
        };
        write("truth_model.toml", &truth)?;
        write("fitted_matrix.toml", &fit.fitted)?;
        if let Some(f) = &d.final_model {
            write("fitted_with_effects.toml", f)?;
        }
        atomic::write_atomic(&dir.join("diagnosis.json"), serde_json::to_string_pretty(&d)?.as_bytes())?;
    }
    println!("== report");
    let spinner = progress::spinner("drawing the report", quiet);
    let input = ReportInput {
        title: match robot {
            None | Some(robot_file::BUILTIN_APR02) => format!("omnical demo: Eq. 9 robot with a hidden {hidden}"),
            Some(_) => format!("omnical demo: {true_robot} with a hidden {hidden}"),
        },
        models: report::models_for(&design, &fit.fitted, Some(&d)),
        train: &train,
        held_out: &val,
        diagnosis: Some(&d),
        sources: vec![format!(
            "simulated: {commands} × {runs_per_command} (train seed {DEFAULT_SEED}, validation seed {}), hidden \
             {hidden}",
            DEFAULT_SEED + 1
        )],
    };
    let html = dir.join("report.html");
    let w = report::write(&input, &html, None)?;
    spinner.finish_and_clear();
    super::report::print_written(&w, &html);
    println!("models and diagnosis.json written to {}", dir.display());
    Ok(())
}
