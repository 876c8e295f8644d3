//! Helpers of the OptiOdom tests (`optiodom`, `optiodom_real`; included with `#[path]`): `train` and `eval`
//! on set folders, their JSON read back.

use crate::support::json;
use std::path::Path;

/// `omnical train --json -q ARGS` in `dir`, which must succeed: the summary.
pub fn train(dir: &Path, args: &[&str]) -> serde_json::Value {
    json(&[&["train", "--json", "-q"], args].concat(), dir)
}

/// Eq. 6 and path RMS of `model` on the set folders `sets` (`eval --json`).
pub fn eval_cost(dir: &Path, model: &str, sets: &[&Path]) -> (f64, f64) {
    let mut args = vec!["eval", "--model", model, "--json"];
    args.extend(sets.iter().map(|p| p.to_str().unwrap()));
    let e = json(&args, dir);
    (e["cost"].as_f64().unwrap(), e["path_cost"].as_f64().unwrap())
}
