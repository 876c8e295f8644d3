//! What an unconstrained direction is, as facts: the parameters carrying it and, for the base kinematics,
//! the wheel-speed pattern the runs hardly contain, its design motion and which runs to add. The words are
//! made from these facts by [`crate::science::text`].

use super::{Advice, Combination, MotionParts, PatternPresence, WeakDirection, WheelEvidence};
use crate::science::text;
use nalgebra::{DMatrix, DVector};
use omni_kin::Model;
use omni_kin::effect::Effect;

/// Share of the wheel motion from which a pattern counts as present in the runs.
const PRESENT_SHARE: f64 = 0.25;
/// Share of the largest component from which a component of a direction or motion is named.
const NOTABLE: f64 = 0.3;

/// Name a direction: its parameters, and for the base kinematics the wheel pattern and motion it needs.
pub(super) fn describe(
    model: &Model,
    params: &[f64],
    scales: &[f64],
    mut dir: Vec<f64>,
    relative_singular_value: f64,
    std_error: Option<f64>,
    wheel_moment: Option<&DMatrix<f64>>,
) -> WeakDirection {
    // Sign convention: the largest component positive.
    let big = dir.iter().copied().fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
    if big < 0.0 {
        dir.iter_mut().for_each(|x| *x = -*x);
    }
    let specs = model.params();
    let top = dir.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let mut loadings: Vec<(String, f64)> = dir
        .iter()
        .enumerate()
        .filter(|(_, d)| d.abs() >= NOTABLE * top)
        .map(|(i, d)| (specs[i].name.clone(), *d))
        .collect();
    loadings.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    let combination = kinematic_combination(model, params, scales, &dir);
    let pattern = if combination.is_some() { None } else { wheel_pattern(model, params, scales, &dir, wheel_moment) };
    let remedy = match (&pattern, combination) {
        (_, Some(c)) => Advice::OneCombination(c),
        (Some(p), None) if p.evidence.moves_nowhere => Advice::HeldAtDesign,
        (Some(p), None) if matches!(p.evidence.presence, PatternPresence::Present(_)) => Advice::PathObjective,
        (Some(p), None) => {
            Advice::AddRuns { motion: p.evidence.motion, alpha_deg: p.motion[1].atan2(p.motion[0]).to_degrees() }
        }
        (None, None) => {
            let effects: Vec<String> = model
                .effects
                .iter()
                .zip(model.effect_ranges())
                .filter(|(_, r)| r.clone().any(|i| dir[i].abs() >= NOTABLE * top))
                .map(|(e, _)| e.id().to_string())
                .collect();
            if effects.is_empty() { Advice::OtherMotions } else { Advice::ExerciseEffects(effects) }
        }
    };
    let (wheel_pattern, motion, evidence) = match pattern {
        Some(p) => (Some(p.u), Some(p.motion), Some(p.evidence)),
        None => (None, None, None),
    };
    let mut w = WeakDirection {
        direction: dir,
        loadings,
        relative_singular_value,
        std_error,
        wheel_pattern,
        motion,
        text: String::new(),
        advice: String::new(),
        evidence,
        remedy,
    };
    w.text = text::weak_direction(&w);
    w.advice = text::advice(&w.remedy);
    w
}

/// Relative change of the IK matrix below which a direction leaves it unchanged (rounding of the
/// analytic derivative).
const UNCHANGED: f64 = 1e-7;

/// The combination of base parameters a direction moves without changing the IK matrix at all (its change
/// `∂M/∂p · D dir` below [`UNCHANGED`] of the largest single parameter's): no run can separate them. `None`
/// when the direction is mostly outside the base kinematics or changes the matrix.
fn kinematic_combination(model: &Model, params: &[f64], scales: &[f64], dir: &[f64]) -> Option<Combination> {
    let nb = model.n_base();
    if dir[..nb].iter().map(|x| x * x).sum::<f64>() < 0.9 {
        return None;
    }
    let jac = model.kinematics.twist_from_wheels_jacobian(&params[..nb]).ok()?;
    let scaled = DMatrix::from_fn(jac.nrows(), nb, |r, c| jac[(r, c)] * scales[c]);
    let largest = (0..nb).map(|c| scaled.column(c).norm()).fold(0.0f64, f64::max);
    let change = (&scaled * DVector::from_column_slice(&dir[..nb])).norm();
    if largest == 0.0 || change > UNCHANGED * largest {
        return None;
    }
    let specs = model.params();
    let top = dir[..nb].iter().fold(0.0f64, |a, b| a.max(b.abs()));
    // In parameter order (lx before ly), as the combination is written.
    let carried: Vec<usize> = (0..nb).filter(|&i| dir[i].abs() >= NOTABLE * top).collect();
    let names = carried.iter().map(|&i| specs[i].name.clone()).collect();
    // In parameter units the direction is d = D dir; `a + k b` is constant along it when k = −d_a / d_b.
    let sum = match carried[..] {
        [a, b] => {
            let k = -(dir[a] * scales[a]) / (dir[b] * scales[b]);
            Some(([1.0, k], params[a] + k * params[b]))
        }
        _ => None,
    };
    Some(Combination { names, unit: specs[carried[0]].unit.clone(), sum })
}

/// A direction's base-kinematics side.
struct Pattern {
    /// The wheel-speed pattern (unit vector, one entry per wheel).
    u: Vec<f64>,
    /// Its design twist per unit wheel speed: (vx m/s, vy m/s, ω rad/s).
    motion: [f64; 3],
    evidence: WheelEvidence,
}

/// The change of the IK matrix along `dir` (scaled), its dominant wheel pattern, and that pattern's design
/// motion. `None` when the direction hardly touches the base kinematics.
fn wheel_pattern(
    model: &Model,
    params: &[f64],
    scales: &[f64],
    dir: &[f64],
    wheel_moment: Option<&DMatrix<f64>>,
) -> Option<Pattern> {
    let nb = model.n_base();
    let base_share: f64 = dir[..nb].iter().map(|x| x * x).sum::<f64>();
    if base_share < 0.25 {
        return None;
    }
    let base = model.kinematics.unexcited(&params[..nb], &dir[..nb], &scales[..nb])?;
    let (u, motion) = (base.wheel_pattern, base.motion);
    let lever = model.kinematics.lever_arm_m();
    let presence = match pattern_share(&u, wheel_moment) {
        Some(share) if share >= PRESENT_SHARE => PatternPresence::Present(share),
        Some(share) => PatternPresence::Scarce(share),
        None => PatternPresence::Unknown,
    };
    let evidence = WheelEvidence {
        wheels: model.kinematics.wheel_names(),
        motion: motion_parts(&motion, lever),
        presence,
        moves_nowhere: moves_nowhere(model, &motion, lever),
    };
    Some(Pattern { u, motion, evidence })
}

/// Whether the design twist of a unit wheel pattern (`motion`) is negligible: below 5 % of the largest
/// twist any unit wheel pattern gives under the design (translations in m/s and ω·lever in m/s compared
/// alike). With more wheels than degrees of freedom such patterns exist (the wheels push against each
/// other); a base with N ≤ 3 full-rank wheels has none.
fn moves_nowhere(model: &Model, motion: &[f64; 3], lever: f64) -> bool {
    let nominal: Vec<f64> = model.kinematics.params().iter().map(|s| s.null).collect();
    let Ok(design) = model.kinematics.twist_from_wheels(&nominal) else {
        return false;
    };
    let nw = design.n_wheels();
    let m = DMatrix::from_fn(3, nw, |r, c| design.entries()[r * nw + c] * if r == 2 { lever } else { 1.0 });
    let largest = m.singular_values().iter().copied().fold(0.0f64, f64::max);
    let size = (motion[0].powi(2) + motion[1].powi(2) + (motion[2] * lever).powi(2)).sqrt();
    largest > 0.0 && size < 0.05 * largest
}

/// RMS share of the wheel motion along the unit pattern `u`: `sqrt(uᵀ S u / tr S)`.
fn pattern_share(u: &[f64], wheel_moment: Option<&DMatrix<f64>>) -> Option<f64> {
    let s = wheel_moment?;
    if s.nrows() != u.len() || s.ncols() != u.len() {
        return None;
    }
    let uv = DVector::from_column_slice(u);
    let tr = s.trace();
    (tr > 0.0).then(|| ((uv.transpose() * s * &uv)[(0, 0)] / tr).max(0.0).sqrt())
}

/// The components of a design twist that matter (at least 30 % of the largest, the turn rate weighted by
/// the lever arm `lever` m).
fn motion_parts(t: &[f64; 3], lever: f64) -> MotionParts {
    let key = [t[0].abs(), t[1].abs(), (t[2] * lever).abs()];
    let top = key.iter().copied().fold(0.0f64, f64::max);
    let notable = |v: f64| v >= NOTABLE * top && top > 0.0;
    MotionParts { forward: notable(key[0]), sideways: notable(key[1]), rotating: notable(key[2]) }
}
