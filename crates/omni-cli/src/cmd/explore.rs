//! `omnical explore`: which family of physical features (wheel, body, world, time, ground truth) explains
//! the error a model leaves, each fitted on the training runs and judged on the held-out runs.

use super::{DataArgs, OutputArgs, load_with_held_out, resolve_model};
use crate::{atomic, model_file};
use anyhow::Context;
use omni_ga::explore::{Exploration, ExploreOptions, FamilyResult, FamilyStatus, explore};
use omni_ga::science::text;
use serde_json::{Value, json};
use std::path::PathBuf;

/// Version of the `--json` layout: the one of every command's (docs/json.md).
pub const SCHEMA_VERSION: u32 = super::JSON_SCHEMA_VERSION;

/// Arguments of `omnical explore`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (from `train --out`) or `design`.
    #[arg(long)]
    pub model: String,
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
    let (ds, val) = load_with_held_out(&a.runs, &a.validate, &a.data)?;
    let model = resolve_model(&a.model, &ds)?;
    let val = val.map(|v| v.runs).unwrap_or_default();
    super::held_out::check("explore", &a.runs, &ds.runs, &val)?;
    let opts = ExploreOptions { min_gain: a.min_gain, ..ExploreOptions::default() };
    let e = explore(&model, &ds.runs, &val, &opts)?;
    if let Some(out) = &a.out {
        let Some(best) = e.best() else {
            anyhow::bail!(
                "--out {}: no family passes on the held-out runs, so there is no model to write",
                out.display()
            );
        };
        let text = model_file::to_toml(&best.fitted, None).map_err(anyhow::Error::msg)?;
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

/// One family in JSON: `{family, effect, status, status_reason, status_text, held_out_gain, gain_std_error,
/// passes, held_out_cost_m, terms, held, hint, curve}`.
fn family_json(f: &FamilyResult) -> Value {
    let reason = match f.status {
        FamilyStatus::NotConverged { reason } => serde_json::to_value(reason).unwrap_or(Value::Null),
        _ => Value::Null,
    };
    json!({
        "family": f.family.id(),
        "effect": format!("learned:{}", f.family.id()),
        "status": f.status.id(),
        "status_reason": reason,
        "status_text": text::family_status(f),
        "held_out_gain": f.held_out_gain,
        "gain_std_error": f.gain_std_error,
        "passes": f.passes,
        "held_out_cost_m": f.held_out_cost,
        "terms": f.terms.iter().map(|t| json!({
            "name": t.name,
            "value": t.value,
            "std_error": if t.std_error.is_finite() { json!(t.std_error) } else { Value::Null },
            "unit": t.unit,
            "held": t.held,
        })).collect::<Vec<_>>(),
        "held": f.held,
        "hint": text::explore_hint(f),
        "curve": f.curve,
    })
}

/// The `--json` document.
pub fn to_json(e: &Exploration) -> Value {
    json!({
        "schema_version": SCHEMA_VERSION,
        "families": e.families.iter().map(family_json).collect::<Vec<_>>(),
        "unexplained": e.unexplained,
        "unexplained_evidence": e.evidence,
        "best": e.best().map(|f| f.family.id()),
        "baseline_held_out_cost_m": e.baseline_held_out_cost,
        "noise_floor_path_rms_m": e.noise_floor_path_rms,
        "runs": { "train": e.runs.0, "held_out": e.runs.1 },
        "coverage": e.coverage,
        "coverage_text": text::motion_coverage(&e.coverage),
        "conclusion": text::explore_conclusion(e),
    })
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
