//! `omnical explore`: which family of physical features (wheel, body, world, time, ground truth) explains
//! the error a model leaves, each fitted on the training runs and judged on the held-out runs.

use super::{DataArgs, OutputArgs};
use crate::api::ModelSpec;
use crate::api::explore::to_json;
use crate::api::load::load_with_held_out;
use crate::{atomic, model_file};
use anyhow::Context;
use omni_ga::explore::{Exploration, ExploreOptions, explore};
use omni_ga::science::text;
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `omnical explore`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (from `train --out`) or `design`.
    #[arg(long)]
    pub model: ModelSpec,
    /// Training runs (the families are fitted on them).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Held-out runs (the families are judged on them): a file or folder; repeat for more
    /// (`--validate A --validate B`).
    #[arg(long, value_name = "PATH", required = true)]
    pub validate: Vec<PathBuf>,
    /// Smallest held-out gain (a fraction of the held-out path cost) for a family to pass; it must also
    /// exceed twice its standard error.
    #[arg(long, default_value_t = ExploreOptions::default().min_gain)]
    pub min_gain: f64,
    /// Write the model with the best passing family's learned effect (`learned:<family>`) here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Output options (JSON: top level `families`, `unexplained`, …).
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// Runs `omnical explore`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    if let Some(out) = &a.out {
        crate::out_path::check_file(out, "--out")?;
    }
    let (ds, val) = load_with_held_out(&a.runs, &a.validate, &a.data.options())?;
    let model = a.model.resolve(&ds)?;
    let val = val.map(|v| v.runs).unwrap_or_default();
    crate::api::held_out::check("explore", &a.runs, &ds.runs, &val)?;
    let opts = ExploreOptions { min_gain: a.min_gain, ..ExploreOptions::default() };
    let e = explore(&model, &ds.runs, &val, &opts)?;
    if let Some(out) = &a.out {
        let Some(best) = e.best() else {
            anyhow::bail!(
                "--out {}: no family passes on the held-out runs, so there is no model to write",
                out.display()
            );
        };
        let text = model_file::to_toml(&best.fitted, None)?;
        atomic::write_atomic(out, text.as_bytes()).with_context(|| format!("writing {}", out.display()))?;
    }
    if a.output.json {
        let mut doc = to_json(&e);
        doc["out"] = json!(a.out.as_ref().map(|p| p.display().to_string()));
        super::print_json("explore", doc)?;
    } else {
        print_exploration(&e, a.min_gain);
    }
    Ok(())
}

/// Human-readable exploration: the ranking, the best family's terms, the conclusion.
pub fn print_exploration(e: &Exploration, min_gain: f64) {
    println!(
        "explore: {} training runs, {} held-out runs; baseline (base kinematics refitted) held-out path {:.4} m",
        e.runs.0, e.runs.1, e.baseline_held_out_cost
    );
    println!("passes: held-out gain ≥ {:.0} % and > 2 standard errors (per held-out run)", 100.0 * min_gain);
    let lines = text::exploration(e);
    let (conclusion, ranking) = lines.split_last().map_or((None, &lines[..]), |(c, r)| (Some(c), r));
    for l in ranking {
        println!("  {l}");
    }
    if let Some(best) = e.best() {
        println!("  learned:{} terms (value ± standard error per run):", best.family.id());
        for t in &best.terms {
            let held = if t.held { "  (held: the runs do not constrain it)" } else { "" };
            println!("    {:<16} {:+.6} ± {:.6} {}{held}", t.name, t.value, t.std_error, t.unit);
        }
    }
    println!("motions: {}", text::motion_coverage(&e.coverage));
    if let Some(c) = conclusion {
        println!("{c}");
    }
}
