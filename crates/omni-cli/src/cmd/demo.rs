//! `omnical demo`: the whole story on built-in simulated data with a hidden effect — simulate, train,
//! diagnose, add the effect, retrain — printing the error ladder — and write the HTML report.

use super::diagnose::print_diagnosis;
use super::simulate::{DEFAULT_SEED, apply_effect_spec};
use super::train::print_summary;
use crate::design::{design_for, paper_calibrated};
use crate::report::{self, ReportInput};
use crate::{atomic, model_file, progress};
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
    /// Repetitions of each of the 36 commands.
    #[arg(long, default_value_t = 2)]
    pub runs_per_command: usize,
    /// The hidden effect, NAME=VALUES as for `simulate --effect`.
    #[arg(long, default_value = "time_offset=0.06")]
    pub hidden: String,
}

/// Runs `omnical demo`; `quiet` hides the progress display.
pub fn run(a: &Args, quiet: bool) -> anyhow::Result<()> {
    let (dir, runs_per_command, hidden) = (a.out.as_path(), a.runs_per_command, a.hidden.as_str());
    let mut truth = paper_calibrated();
    let mut config = SimConfig { runs_per_command, seed: DEFAULT_SEED, ..SimConfig::default() };
    apply_effect_spec(hidden, &mut truth, &mut config)?;
    println!("== simulate: true robot = the paper's Eq. 9 matrix + a hidden effect ({hidden})");
    let spinner = progress::spinner("simulating", quiet);
    let train = simulate(&config, &truth, "train/")?;
    let val = simulate(&SimConfig { seed: DEFAULT_SEED + 1, ..config.clone() }, &truth, "validation/")?;
    spinner.finish_and_clear();
    println!("   {} training and {} validation runs", train.len(), val.len());
    println!("== train: fit the 9-entry IK matrix (preset default)");
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let preset = Preset::Default;
    let plan = Plan::preset(preset, 9).seed(0);
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
        title: format!("omnical demo: Eq. 9 robot with a hidden {hidden}"),
        models: report::models_for(&design, &fit.fitted, Some(&d)),
        train: &train,
        held_out: &val,
        diagnosis: Some(&d),
        sources: vec![format!(
            "simulated: 36 flower commands × {runs_per_command} (train seed {DEFAULT_SEED}, validation seed {}), \
             hidden {hidden}",
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
