//! Step 2 of a diagnosis: the evidence for one candidate effect — the first-order test at the current fit
//! (how much of the residual it could explain, whether the model already absorbs it) and a refit with it,
//! judged on the held-out runs.

use super::compare::{costs_of, path_kind};
use super::noise::wheel_excitation;
use super::{Candidate, Costs, DiagnoseOptions, NoiseFloor, ParamValue};
use crate::error::Error;
use crate::fit::{BaseFit, Calibration, CalibrationProblem, Plan, refine_on};
use crate::optimizer::observe::NoopObserver;
use crate::optimizer::problem::{Bounds, LeastSquares};
use crate::science::text;
use nalgebra::{DMatrix, DVector};
use omni_kin::effect::{Effect, Stage};
use omni_kin::{EffectKind, FittedModel, Model, Run};

/// Separability below which an effect counts as absorbed by the model.
const ABSORBED: f64 = 0.05;

/// The path-residual problem of `model` over `runs`, with no bounds (the diagnosis explores freely).
pub(crate) fn unbounded<'a>(model: &'a Model, runs: &'a [Run], every: usize) -> Result<CalibrationProblem<'a>, Error> {
    CalibrationProblem::new(model, runs, path_kind(every), Bounds::unbounded(model.n_params()))
}

/// `model`'s parameters, with effect parameters whose value is the lower end of their range (backlash
/// b ≥ 0 at its null value) moved 2 % inside it, where the model is differentiable.
pub fn differentiable_start(model: &FittedModel) -> Vec<f64> {
    crate::fit::differentiable_start(model, model.model.n_base())
}

/// Add `effect` (or nothing) to `current` and refit on `train`, on the path objective at every `every`-th
/// pose: [`crate::fit::refine`] with [`Plan::refit`], the very fit `train --effect` runs after fitting the
/// base — the same start, the same free and held parameters, the same optimizer and stopping — so what
/// diagnose reports is what train delivers.
pub fn refit(
    current: &FittedModel,
    effect: Option<&EffectKind>,
    train: &[Run],
    every: usize,
) -> Result<Calibration, Error> {
    refit_on(current, effect, train, every, BaseFit::TheseRuns)
}

/// [`refit`], saying whether `current` is a fit of `train` ([`BaseFit`]).
pub fn refit_on(
    current: &FittedModel,
    effect: Option<&EffectKind>,
    train: &[Run],
    every: usize,
    base_fit: BaseFit,
) -> Result<Calibration, Error> {
    let effects: Vec<EffectKind> = effect.into_iter().cloned().collect();
    refine_on(current, &effects, train, &Plan::refit(every), &mut NoopObserver, base_fit)
}

/// Relative eigenvalue of the unit-column Gram matrix below which a direction counts as not spanned
/// (singular value 1e-6 of the largest: `JᵀJ` carries rounding at 1e-16 of its largest entry).
const RANK_TOLERANCE: f64 = 1e-12;

/// `‖P_S w‖²`, the squared norm of `w`'s projection onto the span of the Jacobian columns `cols`, from the
/// Gram matrix `jtj = JᵀJ` and `v = J_Sᵀw` (one entry per column of `cols`): `vᵀ (J_SᵀJ_S)⁺ v`, without the
/// tall `J` itself. The pseudo-inverse is taken on the columns scaled to unit norm (the rank decision does
/// not depend on the parameters' units), dropping eigenvalues below [`RANK_TOLERANCE`] of the largest and
/// columns with no sensitivity at all.
fn projected_norm2(jtj: &DMatrix<f64>, cols: &[usize], v: &DVector<f64>) -> f64 {
    let kept: Vec<(usize, f64)> = cols
        .iter()
        .enumerate()
        .filter_map(|(k, &c)| {
            let d = jtj[(c, c)];
            (d > 0.0 && d.is_finite()).then(|| (k, 1.0 / d.sqrt()))
        })
        .collect();
    if kept.is_empty() {
        return 0.0;
    }
    let unit = DMatrix::from_fn(kept.len(), kept.len(), |a, b| {
        let ((ka, sa), (kb, sb)) = (kept[a], kept[b]);
        jtj[(cols[ka], cols[kb])] * sa * sb
    });
    let w = DVector::from_fn(kept.len(), |a, _| v[kept[a].0] * kept[a].1);
    if !unit.iter().chain(w.iter()).all(|x| x.is_finite()) {
        return 0.0;
    }
    let eig = unit.symmetric_eigen();
    let top = eig.eigenvalues.iter().fold(0.0f64, |m, &l| m.max(l));
    (0..eig.eigenvalues.len())
        .filter(|&k| eig.eigenvalues[k] > RANK_TOLERANCE * top)
        .map(|k| eig.eigenvectors.column(k).dot(&w).powi(2) / eig.eigenvalues[k])
        .sum()
}

/// The entries `rows` of `v`.
fn entries(v: &DVector<f64>, rows: &[usize]) -> DVector<f64> {
    DVector::from_iterator(rows.len(), rows.iter().map(|&i| v[i]))
}

/// The first-order test of one effect at the current fit.
struct FirstOrder {
    /// Share of the training residual the effect could explain (0…1; without parameters, the exact share
    /// switching it on removes; NaN when that changes no residual).
    explained: f64,
    /// Smallest share of the effect's sensitivity outside the model's (NaN: not excited at all).
    separability: f64,
    /// Effect values the model's change from design implies.
    implied: Vec<ParamValue>,
}

/// First-order evidence of one effect at the current fit.
fn first_order(
    current: &FittedModel,
    design: &FittedModel,
    effect: &EffectKind,
    train: &[Run],
    every: usize,
) -> Result<FirstOrder, Error> {
    let ext = current.with_effect(effect.clone());
    let (n, nm) = (ext.params.len(), current.params.len());
    let problem = unbounded(&ext.model, train, every)?;
    // Everything below is a projection onto spans of Jacobian columns: the normal equations hold all it
    // needs (`JᵀJ`, `Jᵀr`, `rᵀr`), at the cost of one Jacobian pass and no tall matrix.
    let ne = problem.normal_equations(&ext.params);
    let (model_cols, all_cols): (Vec<usize>, Vec<usize>) = ((0..nm).collect(), (0..n).collect());
    let rr = ne.rtr.max(1e-300);
    let explained_by = |cols: &[usize]| projected_norm2(&ne.jtj, cols, &entries(&ne.jtr, cols));
    let explained = ((explained_by(&all_cols) - explained_by(&model_cols)) / rr).clamp(0.0, 1.0);
    // Columns with no sensitivity at all (the runs do not excite the effect) say nothing about
    // separability; if every column is such, the effect is unexcited, not absorbed (NaN).
    let j_norm2 = ne.jtj.trace().max(1e-300);
    let mut separability = f64::INFINITY;
    for c in nm..n {
        let norm2 = ne.jtj[(c, c)];
        if norm2.sqrt() > 1e-12 * j_norm2.sqrt() {
            let inside = projected_norm2(&ne.jtj, &model_cols, &DVector::from_fn(nm, |i, _| ne.jtj[(i, c)]));
            separability = separability.min(((norm2 - inside).max(0.0) / norm2).sqrt());
        }
    }
    if !separability.is_finite() {
        separability = f64::NAN;
    }
    let implied = implied_values(current, design, effect, &ne.jtj);
    Ok(FirstOrder { explained, separability, implied })
}

/// Share of the training residual (0…1) that switching on `effect` (no parameters) at `current`'s fit
/// removes: `1 − ‖r_on‖² / ‖r_off‖²`, clamped at 0 when it adds residual. NaN when it changes no residual
/// beyond rounding (1e-9 of the largest): the runs cannot tell it.
fn switched_on_share(current: &FittedModel, effect: &EffectKind, train: &[Run], every: usize) -> Result<f64, Error> {
    let off = unbounded(&current.model, train, every)?.residuals(&current.params);
    let on_model = current.with_effect(effect.clone());
    let on = unbounded(&on_model.model, train, every)?.residuals(&on_model.params);
    let scale = off.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let changed = on.len() != off.len() || on.iter().zip(&off).any(|(a, b)| (a - b).abs() > 1e-9 * scale);
    if !changed {
        return Ok(f64::NAN);
    }
    let norm2 = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    Ok((1.0 - norm2(&on) / norm2(&off).max(1e-300)).clamp(0.0, 1.0))
}

/// Implied effect values: min ‖J_e e − J_m Δx‖, Δx = fit − design (same base structure only), from the
/// Gram matrix `jtj` of `[J_m J_e]`: the least-norm solution of `J_eᵀJ_e e = J_eᵀJ_m Δx`.
fn implied_values(
    current: &FittedModel,
    design: &FittedModel,
    effect: &EffectKind,
    jtj: &DMatrix<f64>,
) -> Vec<ParamValue> {
    let mut implied = Vec::new();
    let nm = current.params.len();
    if design.params.len() == current.model.n_base() || design.model.n_base() == current.model.n_base() {
        let nb = current.model.n_base();
        let dx = DVector::from_fn(nm, |i, _| if i < nb { current.params[i] - design.params[i] } else { 0.0 });
        let gee = jtj.view((nm, nm), (jtj.nrows() - nm, jtj.ncols() - nm)).into_owned();
        let target = jtj.view((nm, 0), (jtj.nrows() - nm, nm)) * dx;
        let finite = gee.iter().chain(target.iter()).all(|v| v.is_finite());
        if let Some(Ok(sol)) = finite.then(|| gee.svd(true, true).solve(&target, 1e-24)) {
            for (s, v) in effect.params().iter().zip(sol.iter()) {
                implied.push(ParamValue { name: s.name.clone(), value: *v, unit: s.unit.clone(), std_error: None });
            }
        }
    }
    implied
}

/// A candidate by id: a user effect from `opts.custom`, else the built-in catalogue's.
pub(super) fn candidate_effect(
    id: &str,
    n_wheels: usize,
    opts: &DiagnoseOptions,
) -> Result<EffectKind, omni_kin::KinError> {
    match opts.custom.iter().find(|e| e.id() == id) {
        Some(e) => Ok(e.clone()),
        None => EffectKind::from_id(id, n_wheels),
    }
}

/// Where a candidate is judged: the current model, the runs and the noise floor.
pub(super) struct Bench<'a> {
    /// The design model (for implied values).
    pub design: &'a FittedModel,
    /// Runs fitted on.
    pub fit_runs: &'a [Run],
    /// Runs judged on.
    pub held_runs: &'a [Run],
    /// Every k-th ground-truth pose.
    pub every: usize,
    /// The measurement noise floor, when the data has standstills.
    pub noise: Option<&'a NoiseFloor>,
    /// Whether the model judged is a fit of `fit_runs` (not when they are a cross-validation subset).
    pub base_fit: BaseFit,
}

impl Bench<'_> {
    /// All the evidence for `effect` (id `id`) added to `current`, whose costs are `current_costs`.
    pub(super) fn assess(
        &self,
        id: &str,
        effect: &EffectKind,
        current: &FittedModel,
        current_costs: &Costs,
    ) -> Result<Candidate, Error> {
        let fo = if effect.params().is_empty() {
            // Nothing to fit and nothing the model could absorb: the exact share of the training residual
            // that switching the effect on removes (NaN: it changes no residual at all).
            let explained = switched_on_share(current, effect, self.fit_runs, self.every)?;
            FirstOrder { explained, separability: 1.0, implied: Vec::new() }
        } else {
            first_order(current, self.design, effect, self.fit_runs, self.every)?
        };
        let absorbed = fo.separability < ABSORBED;
        let gap = if effect.stage() == Stage::Wheel {
            wheel_excitation(self.fit_runs, &current.model.kinematics.wheel_names())
        } else {
            None
        };
        let mut cand = Candidate {
            effect: id.to_string(),
            physics: effect.describe(),
            first_order_explained: fo.explained,
            separability: fo.separability,
            absorbed,
            implied: if absorbed { fo.implied } else { Vec::new() },
            refit: None,
            held_out_gain: 0.0,
            excess_closed: f64::NAN,
            params: Vec::new(),
            not_excited: match &gap {
                Some(g) => Some(text::excitation_gap(g)),
                None if fo.explained.is_nan() => Some(text::changes_nothing(effect.uses_stamps())),
                None => None,
            },
            excitation_gap: gap,
            held: Vec::new(),
            fitted: None,
        };
        if !absorbed
            && cand.not_excited.is_none()
            && let Ok(fit) = refit_on(current, Some(effect), self.fit_runs, self.every, self.base_fit)
        {
            self.judge_refit(&mut cand, effect, &fit, current_costs)?;
        }
        Ok(cand)
    }

    /// The held-out gain, the share of the excess error closed and the effect's parameters (with
    /// standard errors, and those the truncated update held at their null values) of a refit with the
    /// effect.
    fn judge_refit(
        &self,
        cand: &mut Candidate,
        effect: &EffectKind,
        fit: &Calibration,
        current_costs: &Costs,
    ) -> Result<(), Error> {
        let c = costs_of(&fit.fitted, self.fit_runs, self.held_runs, self.every)?;
        cand.held_out_gain = 1.0 - c.held_out_path / current_costs.held_out_path.max(1e-300);
        if let Some(nf) = self.noise {
            let (b, a, f) = (current_costs.held_out_path, c.held_out_path, nf.path_rms);
            cand.excess_closed = (b * b - a * a) / (b * b - f * f).max(1e-300);
        }
        // Standard errors of the effect parameters at the refit: the identifiability analysis's (per-run
        // sandwich), the same computation `train` reports.
        let n = fit.fitted.params.len();
        let r = fit.fitted.model.effect_ranges().last().cloned().unwrap_or(n..n);
        let held = fit.held_params();
        cand.held = effect
            .params()
            .iter()
            .zip(r.clone())
            .filter(|(_, i)| held.contains(i))
            .map(|(s, _)| s.name.clone())
            .collect();
        cand.params = effect
            .params()
            .iter()
            .zip(r)
            .map(|(s, i)| ParamValue {
                name: s.name.clone(),
                value: fit.fitted.params[i],
                unit: s.unit.clone(),
                std_error: fit.identifiability.params.get(i).and_then(|u| u.std_error),
            })
            .collect();
        cand.refit = Some(c);
        cand.fitted = Some(fit.fitted.clone());
        Ok(())
    }
}
