//! The explorer's results as the JSON document `omnical explore --json` prints and Python's
//! `Exploration` holds.

use omni_ga::explore::{Exploration, FamilyResult, FamilyStatus};
use omni_ga::science::text;
use serde_json::{Value, json};

/// Version of the `--json` layout: the one of every command's (docs/json.md).
pub const SCHEMA_VERSION: u32 = super::JSON_SCHEMA_VERSION;

/// One family in JSON: `{family, effect, status, status_reason, status_text, held_out_gain, gain_std_error,
/// passes, held_out_cost_m, terms, held, hint, curve, held_out_kinds}`.
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
        "held_out_kinds": f.held_out_kinds,
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
