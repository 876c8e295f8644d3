//! `omnical demo`: the whole story on built-in simulated data with a hidden effect — simulate, train,
//! diagnose, add the effect, retrain — printing the error ladder.

use super::diagnose::{design_for, print_diagnosis};
use super::simulate::apply_effect_spec;
use super::train::print_summary;
use crate::{atomic, model_file};
use anyhow::Context;
use omni_ga::calibrate::{Plan, Preset, calibrate};
use omni_ga::diagnose::{DiagnoseOptions, diagnose};
use omni_ga::observe::NoopObserver;
use omni_kin::simulate::{SimConfig, simulate};
use omni_kin::{FittedModel, IkMatrix, Model};
use std::path::PathBuf;

/// Runs `omnical demo`.
pub fn run(out: Option<PathBuf>, runs_per_command: usize, hidden: &str) -> anyhow::Result<()> {
    let mut truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    let mut config = SimConfig { runs_per_command, seed: 7, ..SimConfig::default() };
    apply_effect_spec(hidden, &mut truth, &mut config)?;
    println!("== simulate: true robot = the paper's Eq. 9 matrix + a hidden effect ({hidden})");
    let train = simulate(&config, &truth, "train/")?;
    let val = simulate(&SimConfig { seed: 8, ..config.clone() }, &truth, "validation/")?;
    println!("   {} training and {} validation runs", train.len(), val.len());
    println!("== train: fit the 9-entry IK matrix (preset default)");
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let plan = Plan::preset(Preset::Default, 9).seed(0);
    let fit = calibrate(&start, &train, &plan, &mut NoopObserver)?;
    print_summary(&fit, "default", train.len());
    println!("== diagnose: which physical effect is missing? (--auto: add effects while held-out error falls)");
    let opts = DiagnoseOptions { auto: true, ..DiagnoseOptions::default() };
    let d = diagnose(&fit.fitted, &design_for(&fit.fitted), &train, Some(&val), &opts)?;
    print_diagnosis(&d);
    if let Some(dir) = out {
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
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
        println!("wrote {}", dir.display());
    }
    Ok(())
}
