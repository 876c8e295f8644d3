//! The GA's search box around a start point.

use crate::optimizer::error::OptimizeError;
use crate::optimizer::problem::Bounds;
use omni_kin::Model;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// How the GA's search box is set around the start.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxRule {
    /// ±fraction of each start value (zero entries pinned). Paper: 0.10.
    PerValue(f64),
    /// ±fraction of each base parameter's scale at the start (the kinematics' `param_scales`: for `ik` the
    /// largest magnitude in the entry's matrix row; for `geometry` the value of r, R, and 1 rad for
    /// angles). Default: 0.10.
    PerRow(f64),
}

/// The GA search box around `start` for `model`.
pub fn search_box(model: &Model, start: &[f64], rule: BoxRule) -> Result<Bounds, OptimizeError> {
    search_box_with(model, start, rule, &BTreeMap::new())
}

/// [`search_box`], where the base parameters named in `half_widths` get the start ± their half-width
/// (their unit; a robot description's priors, [`omni_kin::robot::Priors`]) instead of `rule`'s.
pub fn search_box_with(
    model: &Model,
    start: &[f64],
    rule: BoxRule,
    half_widths: &BTreeMap<String, f64>,
) -> Result<Bounds, OptimizeError> {
    let specs = model.params();
    let nb = model.n_base();
    let scales = model.kinematics.param_scales(&start[..nb]);
    let mut lower = Vec::with_capacity(specs.len());
    let mut upper = Vec::with_capacity(specs.len());
    for (i, s) in specs.iter().enumerate() {
        let v = start[i];
        let half = if i >= nb {
            // Effects: their own bounds; a start outside them (a sensor's mount turned 90°, found before the
            // fit) gets their width centred on it.
            if (s.lower..=s.upper).contains(&v) {
                lower.push(s.lower);
                upper.push(s.upper);
            } else {
                let half = 0.5 * (s.upper - s.lower);
                lower.push(v - half);
                upper.push(v + half);
            }
            continue;
        } else if let Some(h) = half_widths.get(&s.name) {
            *h
        } else {
            match rule {
                BoxRule::PerValue(f) => f * v.abs(),
                BoxRule::PerRow(f) => f * scales[i],
            }
        };
        lower.push(v - half);
        upper.push(v + half);
    }
    Bounds::new(lower, upper)
}
