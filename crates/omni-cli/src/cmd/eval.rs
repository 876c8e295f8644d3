//! `omnical eval`: the cost of a model on runs, with per-run end-pose errors.

use super::{DataArgs, load_runs, resolve_model};
use omni_kin::cost::CostKind;
use omni_kin::evaluate::Evaluator;
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `omnical eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// `design` (the data's design model, or the paper's Eq. 7) or a model file.
    #[arg(long, default_value = "design")]
    pub model: String,
    /// Run files or folders.
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// Runs `omnical eval`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let (model, as_json) = (a.model.as_str(), a.json);
    let ds = load_runs(&a.runs, &a.data)?;
    let fm = resolve_model(model, &ds)?;
    let evaluator = Evaluator::for_report(&fm.model, &ds.runs, CostKind::PATH.selection())?;
    let all = evaluator.errors(&fm.model.resolve(&fm.params)?);
    let errors = all.ends();
    let c = all.end_pose_cost();
    let path = all.path_cost(CostKind::PATH.heading_weight());
    if as_json {
        let runs: Vec<_> = ds
            .runs
            .iter()
            .zip(errors)
            .map(|(r, e)| {
                json!({
                    "name": r.name(),
                    "command": r.command(),
                    "dx_m": e.dx_m, "dy_m": e.dy_m, "dtheta_rad": e.dtheta_rad, "error": e.norm(),
                })
            })
            .collect();
        let mut out = json!({ "cost": c, "path_cost": path, "model": model, "runs": runs });
        if !ds.ground_truth_clocks.is_empty() {
            out["ground_truth_clock"] = ds.ground_truth_clocks.iter().map(|g| g.to_json()).collect();
        }
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("{:<28} {:>18} {:>9} {:>9} {:>10} {:>9}", "run", "command", "dx m", "dy m", "dθ rad", "error");
    for (r, e) in ds.runs.iter().zip(errors) {
        let cmd = r.command().map(|c| c.label()).unwrap_or_else(|| "-".into());
        println!(
            "{:<28} {:>18} {:>9.4} {:>9.4} {:>10.4} {:>9.4}",
            r.name(),
            cmd,
            e.dx_m,
            e.dy_m,
            e.dtheta_rad,
            e.norm()
        );
    }
    println!("model {model}: cost (Eq. 6) {c:.5} over {} runs; path RMS {path:.5}", ds.runs.len());
    Ok(())
}
