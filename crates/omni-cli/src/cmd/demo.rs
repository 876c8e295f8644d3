//! `omnical demo`: the whole story on built-in simulated data with a hidden effect — simulate, train,
//! diagnose, add the effect, retrain — printing the error ladder — and write the HTML report.

use super::OutputArgs;
use super::diagnose::print_diagnosis;
use super::sim_spec::apply_effect_spec;
use super::simulate::DEFAULT_SEED;
use super::train::print_summary;
use crate::api::load::{DataOptions, LoadRequest};
use crate::api::simulate::{Format, Sensors, write_robot, write_split};
use crate::api::train::{Fitted, Prepared, Recipe, fit_prepared, write_model};
use crate::design::{design_for, paper_calibrated};
use crate::out_path::{Inputs, OutDir};
use crate::report::{self, ReportInput};
use crate::robot_file::RobotFile;
use crate::{atomic, model_file, progress, robot_file};
use anyhow::Context;
use omni_ga::calibrate::{Plan, Preset};
use omni_ga::diagnose::{DiagnoseOptions, Diagnosis, diagnose};
use omni_kin::simulate::{SimConfig, simulate};
use omni_kin::{BaseKind, FittedModel, IkMatrix, Model, Run};
use serde_json::json;
use std::path::{Path, PathBuf};

/// Arguments of `omnical demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Write everything here: the simulated runs (train/ and validation/, each with its robot.toml), the
    /// true model, the fitted models, diagnosis.json and report.html. The `omnical` commands that repeat
    /// each step on these files are printed at the end. An earlier demo's folder (marked by its
    /// .omnical-demo file, holding nothing else) is replaced; any other folder that holds files is refused
    /// unless --force.
    #[arg(long, default_value = "omnical-demo")]
    pub out: PathBuf,
    /// Replace an --out folder that already holds files (an earlier demo's, say), whole.
    #[arg(long)]
    pub force: bool,
    /// Repetitions of each command.
    #[arg(long, default_value_t = 2)]
    pub runs_per_command: usize,
    /// The hidden effect, NAME=VALUES as for `simulate --effect`.
    #[arg(long, default_value = "time_offset=0.06", help = crate::cli::effect_help(
        "The hidden effect, NAME=VALUES as for `simulate --effect`."
    ))]
    pub hidden: String,
    /// Run the demo on this robot (a robot.toml): its design is the start, the true robot deviates from
    /// it (wheel radii, a diff base's axle) and has the hidden effect. Default: the paper's APR-02 with
    /// its calibrated Eq. 9 as the true robot.
    #[arg(long, value_name = "FILE|apr02")]
    pub robot: Option<String>,
    /// Output options (JSON: the costs, the verdict, the files written and the commands that repeat each
    /// step; the story is not printed).
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The simulated robot of a demo: its true model, the design it starts from, the simulator, and words.
struct Setup {
    truth: FittedModel,
    start: FittedModel,
    config: SimConfig,
    /// The robot description (written beside the runs).
    robot: RobotFile,
    /// Joint names in column order.
    wheels: Vec<String>,
    /// "the paper's Eq. 9 matrix", "robot.toml's design with …".
    true_robot: String,
    /// "36 flower commands", "12 forward/backward arcs and turns".
    commands: String,
    /// The `omnical simulate` options that make the same true robot (before the hidden effect).
    simulate_args: Vec<String>,
}

/// The paper's APR-02: its calibrated Eq. 9 is the true robot, the design Eq. 7 the start.
fn paper_setup(runs_per_command: usize) -> Setup {
    Setup {
        truth: paper_calibrated(),
        start: FittedModel::nominal(Model::ik(IkMatrix::paper_design())),
        config: SimConfig { runs_per_command, seed: DEFAULT_SEED, ..SimConfig::default() },
        robot: RobotFile {
            description: omni_kin::robot::RobotDescription::apr02(),
            source: robot_file::Source::Builtin,
        },
        wheels: omni_kin::geometry::default_wheel_names(3),
        true_robot: "the paper's Eq. 9 matrix".into(),
        commands: "36 flower commands".into(),
        simulate_args: Vec::new(),
    }
}

/// How the demo's true robot on a `--robot` of kind `kind` with `n_wheels` wheels deviates from its design:
/// wheel a 1.5 % larger, the last wheel 1 % smaller, and a differential drive's axle 2 % longer; a
/// skid-steer base turns about centres of rotation 0.1 m further out and 0.03 m ahead (the `simulate
/// --effect` specs).
pub fn demo_deviations(kind: BaseKind, n_wheels: usize) -> Vec<String> {
    if kind == BaseKind::Skid {
        return vec!["icr_shift=0.1,-0.1,0.03".into()];
    }
    let last = char::from(b'a' + ((n_wheels.max(1) - 1) % 26) as u8);
    let mut v = vec!["wheel_radius:a=0.015".to_string(), format!("wheel_radius:{last}=-0.01")];
    if kind == BaseKind::Diff {
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
    let deviations = demo_deviations(robot.description.kind, wheels.len());
    for spec in &deviations {
        apply_effect_spec(spec, &mut truth, &mut config, &wheels)?;
    }
    let commands =
        if config.design.is_omnidirectional() { "36 flower commands" } else { "12 forward/backward arcs and turns" };
    let mut simulate_args = vec!["--robot".to_string(), arg.to_string(), "--truth".into(), "design".into()];
    simulate_args.extend(deviations.iter().flat_map(|d| ["--effect".to_string(), d.clone()]));
    Ok(Setup {
        truth,
        start,
        config,
        true_robot: format!("the design of {} with {}", robot.source, deviations.join(", ")),
        commands: commands.into(),
        robot,
        wheels,
        simulate_args,
    })
}

/// File names of the demo's outputs in `--out`.
const TRAIN: &str = "train";
const VALIDATION: &str = "validation";
const TRUTH_MODEL: &str = "truth_model.toml";
const FITTED_MATRIX: &str = "fitted_matrix.toml";
const FITTED_WITH_EFFECTS: &str = "fitted_with_effects.toml";
const DIAGNOSIS: &str = "diagnosis.json";
const REPORT: &str = "report.html";
/// The marker every demo writes into its `--out`: a folder that holds it and nothing but the demo's own
/// outputs is an earlier demo's, which the next demo replaces without `--force` (`earlier_demo_only`).
pub const MARKER: &str = ".omnical-demo";
/// What the marker says to someone who finds it.
const MARKER_TEXT: &str = "This folder was written by `omnical demo`. The next `omnical demo --out` into it replaces \
                           it whole (it holds no input of yours); a file of yours added here keeps it.\n";

/// Whether `dir` holds only an earlier demo's output: its [`MARKER`], and else only the demo's own names
/// (the runs' folders holding only bags and robot.toml, the models, the diagnosis and the report). Such a
/// folder holds no input of the user's, so a demo may replace it as if `--force` were given; any other
/// folder that holds files is refused as every `--out` is.
fn earlier_demo_only(dir: &Path) -> bool {
    let own = [MARKER, TRAIN, VALIDATION, TRUTH_MODEL, FITTED_MATRIX, FITTED_WITH_EFFECTS, DIAGNOSIS, REPORT];
    let names = |d: &Path| -> Option<Vec<String>> {
        std::fs::read_dir(d).ok()?.map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned())).collect()
    };
    let Some(top) = names(dir) else { return false };
    let runs_only = |split: &str| {
        names(&dir.join(split))
            .is_some_and(|files| files.iter().all(|f| f == robot_file::FILE_NAME || f.ends_with(".mcap")))
    };
    top.iter().any(|n| n == MARKER)
        && top.iter().all(|n| own.contains(&n.as_str()))
        && [TRAIN, VALIDATION].iter().all(|s| !top.iter().any(|n| n == s) || runs_only(s))
}

/// Simulates the training (seed 7) and validation (seed 8) runs, writes them as MCAP bags with the robot's
/// robot.toml into `dir`/train and `dir`/validation as `omnical simulate` does, and reads them back as the
/// other commands read them, so that every step repeated on the files sees the same runs.
fn simulate_and_keep(setup: &Setup, dir: &Path, quiet: bool) -> anyhow::Result<(Vec<Run>, Vec<Run>)> {
    let spinner = progress::spinner("simulating", quiet);
    let mut splits = Vec::with_capacity(2);
    for (split, seed) in [(TRAIN, DEFAULT_SEED), (VALIDATION, DEFAULT_SEED + 1)] {
        let runs = simulate(&SimConfig { seed, ..setup.config.clone() }, &setup.truth, &format!("{split}/"))?;
        write_split(&dir.join(split), &runs, Format::Mcap, &setup.wheels, Sensors::default())?;
        write_robot(&dir.join(split), &setup.robot, Format::Mcap)?;
        let paths = [dir.join(split)];
        let robot = robot_file::resolve(None, &paths)?;
        splits.push(LoadRequest::new(&paths, &DataOptions::default()).read_for_robot(robot)?.runs);
    }
    spinner.finish_and_clear();
    let val = splits.pop().unwrap_or_default();
    Ok((splits.pop().unwrap_or_default(), val))
}

/// A path as a shell word: quoted when it holds anything but letters, digits and `_./:=,+-`.
fn shell_word(s: &str) -> String {
    if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "_./:=,+-".contains(c)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// The `omnical` commands that repeat each step of the demo on the files in `dir`: (step, command line).
fn repeat_commands(a: &Args, setup: &Setup, dir: &Path, with_effects: bool) -> Vec<(&'static str, String)> {
    let p = |name: &str| shell_word(&dir.join(name).display().to_string());
    let out = shell_word(&dir.display().to_string());
    // --force: the folder holds this demo's files, which the repeated steps write again.
    let mut simulate = format!("omnical simulate --out {out} --force --runs-per-command {}", a.runs_per_command);
    for w in &setup.simulate_args {
        simulate.push(' ');
        simulate.push_str(&shell_word(w));
    }
    simulate.push_str(&format!(" --effect {}", shell_word(&a.hidden)));
    let mut v = vec![
        ("simulate", simulate),
        ("train", format!("omnical train {} --out {}", p(TRAIN), p(FITTED_MATRIX))),
        (
            "diagnose",
            format!(
                "omnical diagnose --model {} {} --validate {} --auto --out {}",
                p(FITTED_MATRIX),
                p(TRAIN),
                p(VALIDATION),
                p(FITTED_WITH_EFFECTS)
            ),
        ),
    ];
    if with_effects {
        v.push(("eval", format!("omnical eval --model {} {}", p(FITTED_WITH_EFFECTS), p(VALIDATION))));
    }
    v.push((
        "report",
        format!(
            "omnical report --model {} {} --validate {} --out {}",
            p(FITTED_MATRIX),
            p(TRAIN),
            p(VALIDATION),
            p(REPORT)
        ),
    ));
    v
}

/// Writes the true model, the fitted models and the diagnosis into `dir`.
/// The fitted matrix's file is `omnical train`'s, with its `[fit]` summary `fitted.1`.
fn write_models(
    dir: &Path,
    truth: &FittedModel,
    fitted: (&FittedModel, &serde_json::Value),
    d: &Diagnosis,
) -> anyhow::Result<()> {
    let write = |name: &str, fm: &FittedModel| -> anyhow::Result<()> {
        let text = model_file::to_toml(fm, None)?;
        atomic::write_atomic(&dir.join(name), text.as_bytes()).with_context(|| format!("writing {name}"))
    };
    write(TRUTH_MODEL, truth)?;
    write_model(fitted.0, fitted.1, &dir.join(FITTED_MATRIX)).with_context(|| format!("writing {FITTED_MATRIX}"))?;
    if let Some(f) = &d.final_model {
        write(FITTED_WITH_EFFECTS, f)?;
    }
    atomic::write_atomic(&dir.join(DIAGNOSIS), serde_json::to_string_pretty(d)?.as_bytes())
        .with_context(|| format!("writing {DIAGNOSIS}"))
}

/// Runs `omnical demo`: on the paper's APR-02, or on `--robot` (a robot.toml; `apr02` is the paper's);
/// `quiet` hides the progress display.
///
/// long: the story's steps in order (simulate, train, diagnose, report, the commands), each printing.
pub fn run(a: &Args, quiet: bool) -> anyhow::Result<()> {
    let (runs_per_command, hidden, robot) = (a.runs_per_command, a.hidden.as_str(), a.robot.as_deref());
    let text = !a.output.json;
    let mut setup = match robot {
        None | Some(robot_file::BUILTIN_APR02) => paper_setup(runs_per_command),
        Some(arg) => robot_setup(arg, runs_per_command)?,
    };
    apply_effect_spec(hidden, &mut setup.truth, &mut setup.config, &setup.wheels)?;
    // Everything is written into a staging folder that becomes --out at the end; an earlier demo's folder
    // is replaced as with --force (never one that holds the --robot file read).
    let robot_file = robot.filter(|r| *r != robot_file::BUILTIN_APR02);
    let inputs = Inputs::new().with_some("--robot", robot_file);
    let out = OutDir::claim(&a.out, "--out", a.force || earlier_demo_only(&a.out), &inputs)?;
    let dir = out.path();
    atomic::write_atomic(&dir.join(MARKER), MARKER_TEXT.as_bytes()).with_context(|| format!("writing {MARKER}"))?;
    if text {
        println!("== simulate: true robot = {} + a hidden effect ({hidden})", setup.true_robot);
    }
    let (train, val) = simulate_and_keep(&setup, dir, quiet)?;
    let n_base = setup.start.model.n_base();
    if text {
        println!(
            "   {} and {} in {}",
            crate::units::count(train.len(), "training run"),
            crate::units::count(val.len(), "validation run"),
            a.out.display()
        );
        println!("== train: fit the {n_base}-entry IK matrix (preset default)");
    }
    let preset = Preset::Default;
    // `omnical train`'s sequence (api::train::fit_prepared) on the runs read back from train/, so that
    // fitted_matrix.toml is the file `omnical train train/ --out fitted_matrix.toml` writes.
    let prepared = Prepared {
        ds: crate::dataset::Dataset { runs: train, ..Default::default() },
        start: setup.start.clone(),
        effects: Vec::new(),
        plan: Plan::preset(preset, n_base).seed(0),
        priors: Vec::new(),
    };
    let recipe = Recipe { preset, seed: 0, from_design: true };
    let mut bar = progress::ProgressObserver::new(quiet);
    let Fitted { calibration: fit, summarized, warning } = fit_prepared(&prepared, recipe, true, &mut bar)?;
    bar.finish();
    if let Some(w) = warning {
        tracing::warn!("{w}");
    }
    let train = &prepared.ds.runs;
    if text {
        print_summary(&fit, preset.id(), train.len());
        println!("== diagnose: which physical effect is missing? (--auto: add effects while held-out error falls)");
    }
    let opts = DiagnoseOptions { auto: true, ..DiagnoseOptions::default() };
    let spinner = progress::spinner("diagnosing: refitting each candidate effect", quiet);
    let design = design_for(&fit.fitted);
    let d = diagnose(&fit.fitted, &design, train, Some(&val), &opts)?;
    spinner.finish_and_clear();
    if text {
        print_diagnosis(&d);
    }
    write_models(dir, &setup.truth, (&fit.fitted, &summarized.summary), &d)?;
    let spinner = progress::spinner("drawing the report", quiet);
    let input = ReportInput {
        title: match robot {
            None | Some(robot_file::BUILTIN_APR02) => format!("omnical demo: Eq. 9 robot with a hidden {hidden}"),
            Some(_) => format!("omnical demo: {} with a hidden {hidden}", setup.true_robot),
        },
        models: report::models_for(
            &design,
            &fit.fitted,
            crate::api::noise::from_summary(&summarized.summary),
            Some(&d),
        ),
        train,
        held_out: &val,
        diagnosis: Some(&d),
        sources: vec![format!(
            "simulated: {} × {runs_per_command} (train seed {DEFAULT_SEED}, validation seed {}), hidden {hidden}",
            setup.commands,
            DEFAULT_SEED + 1
        )],
    };
    let w = report::write(&input, &dir.join(REPORT), None)?;
    spinner.finish_and_clear();
    out.commit()?;
    let (dir, html) = (a.out.as_path(), a.out.join(REPORT));
    let commands = repeat_commands(a, &setup, dir, d.final_model.is_some());
    if !text {
        let doc = demo_json(a, &setup, (train, &val), &fit, &d, &w, &commands)?;
        return super::print_json("demo", doc);
    }
    println!("== report");
    super::report::print_written(&w, &html);
    println!("runs, models and {DIAGNOSIS} written to {}", dir.display());
    println!("== repeat each step by hand on these files:");
    for (_, c) in &commands {
        println!("   {c}");
    }
    println!("{}", hidden_and_found(hidden, &d));
    Ok(())
}

/// The demo's last line, as the Python quickstart's: the hidden effect and what the diagnosis found of it
/// (the parameters of the same effect in the final model, or what it concluded instead).
fn hidden_and_found(hidden: &str, d: &Diagnosis) -> String {
    let (head, _) = hidden.split_once('=').unwrap_or((hidden, ""));
    let learned = head.starts_with(omni_kin::effect::learned::PREFIX);
    let id = if learned { head } else { head.split(':').next().unwrap_or(head) };
    use omni_kin::effect::SensorOffset;
    let id = if id == SensorOffset::ID_YAW { SensorOffset::ID } else { id };
    let found: Vec<String> = d
        .final_model
        .iter()
        .flat_map(|f| f.model.params().into_iter().zip(f.params.clone()))
        .filter(|(p, _)| p.name.split_once('.').is_some_and(|(effect, _)| effect == id))
        .map(|(p, v)| format!("{} = {}", p.name, crate::units::value_text(v, &p.unit).trim_start()))
        .collect();
    if found.is_empty() {
        format!("hidden {hidden} → not found; the diagnosis: {}", d.verdict_text)
    } else {
        format!("hidden {hidden} → found {} (in {FITTED_WITH_EFFECTS})", found.join(", "))
    }
}

/// The `--json` document of `omnical demo`.
fn demo_json(
    a: &Args,
    setup: &Setup,
    (train, val): (&[Run], &[Run]),
    fit: &omni_ga::calibrate::Calibration,
    d: &Diagnosis,
    w: &report::Written,
    commands: &[(&str, String)],
) -> anyhow::Result<serde_json::Value> {
    let dir = &a.out;
    let fitted_with_effects = d.final_model.as_ref().map(|_| dir.join(FITTED_WITH_EFFECTS));
    Ok(json!({
        "out": dir,
        "hidden": a.hidden,
        "true_robot": setup.true_robot,
        "runs": { "train": train.len(), "validation": val.len() },
        "train": crate::api::train::summary(fit, Preset::Default.id(), 0, train.len())?,
        "diagnosis": { "verdict": d.verdict, "verdict_text": d.verdict_text, "costs": d.costs, "ladder": d.ladder },
        "report": super::report::written_json(w, &dir.join(REPORT)),
        "written": {
            "train": dir.join(TRAIN), "validation": dir.join(VALIDATION), "truth_model": dir.join(TRUTH_MODEL),
            "fitted_matrix": dir.join(FITTED_MATRIX), "fitted_with_effects": fitted_with_effects,
            "diagnosis": dir.join(DIAGNOSIS), "report": dir.join(REPORT),
        },
        "commands": commands.iter().map(|(step, c)| json!({ "step": step, "command": c })).collect::<Vec<_>>(),
    }))
}
