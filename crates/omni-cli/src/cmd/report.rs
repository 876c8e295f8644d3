//! `omnical report`: the HTML report of a model on runs (diagnosis included unless `--no-diagnose`).

use super::{DataArgs, OutputArgs};
use crate::api::ModelSpec;
use crate::api::load::load_with_held_out;
use crate::design::designs_for;
use crate::progress;
use crate::report::{self, ReportInput};
use omni_ga::diagnose::{DiagnoseOptions, diagnose};
use std::path::PathBuf;

/// Arguments of `omnical report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (from `train --out`) or `design`.
    #[arg(long)]
    pub model: ModelSpec,
    /// Training runs (the ones the model was fitted on).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Held-out runs: a file or folder; repeat for more (`--validate A --validate B`). The figures use
    /// them (default: the training runs, 2-fold cross-validation in the diagnosis).
    #[arg(long, value_name = "PATH")]
    pub validate: Vec<PathBuf>,
    /// The HTML file to write.
    #[arg(long, default_value = "report.html")]
    pub out: PathBuf,
    /// Also write each figure as PNG into this folder (`<figure>.png`; other files in it stay, figures an
    /// earlier report wrote that this one does not draw are removed).
    #[arg(long, value_name = "DIR")]
    pub png: Option<PathBuf>,
    /// Skip the diagnosis (faster; no ranking, ladder of the given model only).
    #[arg(long)]
    pub no_diagnose: bool,
    /// Add the explorer's section (which family of features explains the remaining error; needs
    /// `--validate`). The diagnosis runs the explorer whenever `--validate` is given; with `--no-diagnose`
    /// this runs it alone, from the model given.
    #[arg(long)]
    pub explore: bool,
    /// Output options (JSON: the files written and each model's costs).
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// Runs `omnical report`; `quiet` hides the progress display.
pub fn run(a: &Args, quiet: bool) -> anyhow::Result<()> {
    crate::out_path::check_file(&a.out, "--out")?;
    if let Some(dir) = &a.png {
        crate::out_path::prepare_dir(dir, "--png")?;
    }
    let (ds, val_ds) = load_with_held_out(&a.runs, &a.validate, &a.data.options())?;
    let model = a.model.resolve(&ds)?;
    // Each run is compared with its own input's design.
    let design = designs_for(&model, &[Some(&ds), val_ds.as_ref()].into_iter().flatten().collect::<Vec<_>>());
    let val = val_ds.map(|v| v.runs).unwrap_or_default();
    crate::api::held_out::check("report", &a.runs, &ds.runs, &val)?;
    let diagnosis = if a.no_diagnose {
        None
    } else {
        let spinner = progress::spinner("diagnosing: refitting each candidate effect, then the explorer", quiet);
        let opts = DiagnoseOptions { auto: true, ..DiagnoseOptions::default() };
        let held_out = if val.is_empty() { None } else { Some(val.as_slice()) };
        let d = diagnose(&model, &design, &ds.runs, held_out, &opts)?;
        spinner.finish_and_clear();
        Some(d)
    };
    // The noise model `train` wrote into the model file, for the figures of how far to trust the odometry.
    let noise = match a.model.file() {
        Some(path) => crate::model_file::read_noise(path)?,
        None => None,
    };
    let mut sources: Vec<String> = a.runs.iter().map(|p| format!("train: {}", p.display())).collect();
    sources.extend(a.validate.iter().map(|p| format!("validation: {}", p.display())));
    sources.push(format!("model: {}", a.model));
    let input = ReportInput {
        title: format!("omnical report: {}", a.model),
        models: report::models_for(&design, &model, noise, diagnosis.as_ref()),
        train: &ds.runs,
        held_out: &val,
        diagnosis: diagnosis.as_ref(),
        sources,
    };
    // The diagnosis (`auto`) ran the explorer when held-out runs are given, and its headline names the
    // family the explorer passed: the section shows that exploration. `--explore` runs it alone otherwise.
    let extra = match (diagnosis.as_ref().and_then(|d| d.exploration.as_ref()), a.explore) {
        (Some(e), _) => report::explore::section(e),
        (None, true) => {
            if val.is_empty() {
                anyhow::bail!(
                    "--explore: the explorer judges each family on held-out runs; give them with --validate PATH"
                );
            }
            let spinner = progress::spinner("exploring: fitting each family of features", quiet);
            let e = omni_ga::explore::explore(&model, &ds.runs, &val, &omni_ga::explore::ExploreOptions::default())?;
            spinner.finish_and_clear();
            report::explore::section(&e)
        }
        (None, false) => String::new(),
    };
    let spinner = progress::spinner("drawing the report", quiet);
    let w = report::write_with(&input, &a.out, a.png.as_deref(), &extra)?;
    spinner.finish_and_clear();
    if a.output.json {
        return super::print_json("report", written_json(&w, &a.out));
    }
    print_written(&w, &a.out);
    Ok(())
}

/// What [`print_written`] says, as JSON: `html` (the page), `figures` (their ids), `png` (the PNG files),
/// and `models` (label, matrix, parameters, `costs`: path RMS m and Eq. 6 on training and held-out runs).
pub fn written_json(w: &report::Written, html: &std::path::Path) -> serde_json::Value {
    serde_json::json!({ "html": html, "figures": w.figures, "png": w.png, "models": w.report.models })
}

/// One line per model and the files written.
pub fn print_written(w: &report::Written, html: &std::path::Path) {
    println!("{:<36} {:>16} {:>16}", "model", "held-out path m", "held-out Eq. 6");
    for m in &w.report.models {
        println!("{:<36} {:>16.5} {:>16.5}", m.label, m.costs.held_out_path, m.costs.held_out_end_pose);
    }
    println!("report written to {} ({} figures: {})", html.display(), w.figures.len(), w.figures.join(", "));
    if let Some(first) = w.png.first() {
        println!(
            "{} PNG figures in {}",
            w.png.len(),
            first.parent().map_or_else(String::new, |p| p.display().to_string())
        );
    }
}
