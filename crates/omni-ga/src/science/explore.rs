//! The explorer: which family of physical features explains the error a model leaves, when no
//! catalogued effect does.
//!
//! For each family ([`omni_kin::effect::Family`]: wheel, body, world, time, ground truth) the model gets
//! the learned correction `learned:<family>` at θ = 0, and everything is refitted on the training runs by
//! [`crate::fit::refine`] with [`Plan::refit`]: Levenberg–Marquardt on train's objective (the path
//! residuals at every [`ExploreOptions::every`]-th ground-truth pose), then the truncated update, which holds
//! the terms the runs do not constrain at 0. That is the very fit `omnical train --effect learned:<family>`
//! runs after fitting the base, so a family's predicted held-out gain is what following the advice delivers
//! (exactly, when the model is train's fit on the same runs), with the terms train would hold held. The
//! baseline is the same refit without a family, so a family's gain is what its terms add, not what a refit
//! of the base gives.
//!
//! Every family is fitted or says why not ([`FamilyStatus`]): `not_excited` (the runs do not move the
//! residuals along its terms at all), `singular` (they do, but cannot tell its terms from the base
//! kinematics or from each other: every term is held), `not_converged` (the optimizer ran out of
//! evaluations, or no step lowered the training cost). Only a fitted family can pass.
//!
//! Standard errors are cluster-robust over runs ([`crate::identify`]'s `per run`, as `train` reports them).
//! A family is judged on the held-out runs: its held-out gain is `1 − C_family / C_baseline` with `C` the
//! held-out path cost (every ground-truth pose, 1 m/rad); its standard error is that of the per-run
//! gains' mean. **A family passes** when it is fitted, its held-out gain is at least
//! [`ExploreOptions::min_gain`] (5 %) and larger than [`ExploreOptions::min_gain_std_errors`] (2) standard
//! errors.
//!
//! `unexplained`: the one decision of diagnose ([`crate::science::diagnose::remains`]) on the error that
//! remains with the best passing family (or the baseline, when none passes): far above the noise floor, or
//! biased beyond the scatter of repeated runs (or runs of one kind of path), or above 3× the noise floor
//! when the runs have no groups to test.
//!
//! No I/O; the words are made in [`crate::science::text`].

use crate::error::Error;
use crate::fit::{Calibration, CalibrationProblem, Plan, Stage, refine};
use crate::optimizer::observe::NoopObserver;
use crate::optimizer::problem::{Bounds, LeastSquares};
use crate::optimizer::{LmConfig, Termination};
use crate::science::coverage::{MotionCoverage, motion_coverage};
use crate::science::diagnose::KindOut;
use crate::science::diagnose::search::{by_kind_of_path, hurts_a_kind};
use crate::science::diagnose::{UnexplainedEvidence, remains};
use crate::science::heaviest_first;
use crate::science::identify::WEAK_LOADING;
use omni_kin::effect::{Effect, EffectKind, Family, Learned};
use omni_kin::evaluate::Evaluator;
use omni_kin::{CostKind, FittedModel, Run, Selection};
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// Settings of [`explore`].
#[derive(Clone, Debug, PartialEq)]
pub struct ExploreOptions {
    /// Families to try, in order (default: all).
    pub families: Vec<Family>,
    /// Smallest held-out gain that passes. Default 0.05 (5 %).
    pub min_gain: f64,
    /// The held-out gain must exceed this many of its standard errors. Default 2.
    pub min_gain_std_errors: f64,
    /// Training residuals at every k-th ground-truth pose: train's objective. Default 1
    /// ([`CostKind::PATH_EVERY`]).
    pub every: usize,
}

impl Default for ExploreOptions {
    fn default() -> Self {
        Self { families: Family::ALL.to_vec(), min_gain: 0.05, min_gain_std_errors: 2.0, every: CostKind::PATH_EVERY }
    }
}

/// One fitted term of a family.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Term {
    /// Name within the effect: `drift_x`.
    pub name: String,
    /// Value, in `unit`.
    pub value: f64,
    /// Cluster-robust (per run) standard error, in `unit`; NaN when the runs do not determine the term.
    pub std_error: f64,
    /// Unit: `m/s`.
    pub unit: String,
    /// Part of a direction the truncated update held at the start (the runs do not constrain it), as
    /// `train` holds it: its value is set by the start (0), not by the data.
    pub held: bool,
}

impl Term {
    /// `|value| / std_error` (0 when undetermined).
    pub fn z(&self) -> f64 {
        let z = self.value.abs() / self.std_error;
        if z.is_finite() { z } else { 0.0 }
    }
}

/// One bin of the residual against a feature.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bin {
    /// Mean feature in the bin: the residual change one unit of the term causes. m per unit.
    pub feature: f64,
    /// Mean residual without the term's part. m.
    pub residual_m: f64,
    /// Residuals in the bin.
    pub count: usize,
}

/// The residual against the family's strongest term (an added-variable plot): training residuals with
/// that term's part put back, against the term's feature in residual space, binned by equal counts; the
/// fitted line through the origin has slope `value`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeatureCurve {
    /// The term.
    pub term: String,
    /// Its unit.
    pub unit: String,
    /// Its fitted value (the slope).
    pub slope: f64,
    /// Bins, by ascending feature.
    pub bins: Vec<Bin>,
}

/// Why a family's fit did not converge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Unconverged {
    /// Levenberg–Marquardt spent its budget of residual evaluations before the cost settled.
    Budget {
        /// The budget ([`LmConfig::max_evaluations`]).
        evaluations: usize,
    },
    /// No step lowered the training cost from the start (non-finite residuals, or a start at a kink).
    NoStep,
    /// The fit ended with every term at 0 though the runs constrain some of them.
    AtZero,
}

/// Whether a family was fitted, and if not, why not (JSON: [`FamilyStatus::id`] and the [`Unconverged`]
/// reason).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FamilyStatus {
    /// Fitted: the fit moved at least one term (some may be part of held directions: [`Term::held`]).
    Fitted,
    /// The runs do not move the residuals along any of its terms (sensitivity below the analysis's rcond):
    /// every term stays 0.
    NotExcited,
    /// The runs move the residuals along its terms but cannot tell them from the base kinematics or from
    /// each other: the truncated update holds every term at 0, as `train` would, and none moves.
    Singular,
    /// The fit did not converge.
    NotConverged {
        /// Why.
        reason: Unconverged,
    },
}

impl FamilyStatus {
    /// Stable id: `fitted`, `not_excited`, `singular`, `not_converged`.
    pub fn id(&self) -> &'static str {
        match self {
            Self::Fitted => "fitted",
            Self::NotExcited => "not_excited",
            Self::Singular => "singular",
            Self::NotConverged { .. } => "not_converged",
        }
    }
}

/// One family's fit and judgement.
#[derive(Clone, Debug)]
pub struct FamilyResult {
    /// The family.
    pub family: Family,
    /// Whether it was fitted, and if not, why not.
    pub status: FamilyStatus,
    /// `1 − C_family / C_baseline` on the held-out runs (path cost).
    pub held_out_gain: f64,
    /// Standard error of the mean per-run held-out gain (0 with one held-out run).
    pub gain_std_error: f64,
    /// Whether it passes the rule of [`ExploreOptions`].
    pub passes: bool,
    /// Held-out path cost with the family's correction. m.
    pub held_out_cost: f64,
    /// The fitted terms.
    pub terms: Vec<Term>,
    /// Directions the truncated update held (in words), as `train --effect learned:<family>` holds them.
    pub held: Vec<String>,
    /// The model with the learned effect (`learned:<family>`) at its fitted values.
    pub fitted: FittedModel,
    /// The residual against the strongest term.
    pub curve: Option<FeatureCurve>,
    /// The family's fit against the baseline on the held-out runs by the shape of their paths, when it
    /// would pass on its gain: it does not pass when it hurts one kind (diagnose's one test of transfer).
    pub held_out_kinds: Option<KindOut>,
}

/// What the explorer found.
#[derive(Clone, Debug)]
pub struct Exploration {
    /// Every family, by held-out gain, largest first.
    pub families: Vec<FamilyResult>,
    /// Held-out path cost of the baseline (the model refitted without a family, the same way). m.
    pub baseline_held_out_cost: f64,
    /// The held-out runs' measurement noise floor (path RMS from pose noise alone), when measurable. m.
    pub noise_floor_path_rms: Option<f64>,
    /// Something physical is still missing with the best passing family (or none): the one decision of
    /// diagnose (module docs).
    pub unexplained: bool,
    /// The figures behind `unexplained`.
    pub evidence: UnexplainedEvidence,
    /// Training and held-out run counts.
    pub runs: (usize, usize),
    /// The training runs' motions against the held-out runs': what the training runs lack.
    pub coverage: MotionCoverage,
}

impl Exploration {
    /// The passing family with the largest held-out gain.
    pub fn best(&self) -> Option<&FamilyResult> {
        self.families.iter().find(|f| f.passes)
    }
}

/// Explore `model` (fitted on `train`): fit every family on `train`, judge it on `validate`.
pub fn explore(
    model: &FittedModel,
    train: &[Run],
    validate: &[Run],
    opts: &ExploreOptions,
) -> Result<Exploration, Error> {
    if train.is_empty() || validate.is_empty() {
        return Err(Error::NoRuns);
    }
    let plan = Plan::refit(opts.every);
    // The baseline and the families are independent fits: in parallel (the families with the most terms
    // first), collected in the options' order (the first error in that order is the one returned; the
    // same results whatever the thread count), each family then judged against the baseline.
    let weight =
        |&family: &Family| EffectKind::Learned(Learned { family, n_wheels: model.model.n_wheels() }).params().len();
    let (baseline, fitted) = rayon::join(
        || refine(model, &[], train, &plan, &mut NoopObserver),
        || heaviest_first::map(&opts.families, weight, |&family| fit_family(model, family, train, validate, &plan)),
    );
    let baseline = baseline?;
    let (base_cost, base_runs) = held_out(&baseline.fitted, validate)?;
    let fitted: Vec<Result<FamilyResult, Error>> =
        fitted.into_iter().map(|f| f.map(|f| f.judged((base_cost, &base_runs), opts))).collect();
    let mut families = fitted.into_iter().collect::<Result<Vec<_>, _>>()?;
    // Transfer is part of passing: a family that hurts a kind of held-out path does not pass.
    for f in families.iter_mut().filter(|f| f.passes) {
        let id = format!("learned:{}", f.family.id());
        f.held_out_kinds = by_kind_of_path(&id, (&baseline.fitted, &f.fitted), validate, 1)?;
        f.passes = !f.held_out_kinds.as_ref().is_some_and(hurts_a_kind);
    }
    families.sort_by(|a, b| b.held_out_gain.total_cmp(&a.held_out_gain));
    let (with, held_out_m) = match families.iter().find(|f| f.passes) {
        Some(f) => (&f.fitted, f.held_out_cost),
        None => (&baseline.fitted, base_cost),
    };
    let (unexplained, evidence, noise) = remains(with, train, validate, held_out_m, 1)?;
    Ok(Exploration {
        families,
        baseline_held_out_cost: base_cost,
        noise_floor_path_rms: noise.map(|n| n.path_rms),
        unexplained,
        evidence,
        runs: (train.len(), validate.len()),
        coverage: motion_coverage(model, train, validate)?,
    })
}

/// A family fitted, with its held-out cost and per-run mean squared errors, before it is judged against
/// the baseline ([`FamilyFit::judged`]).
struct FamilyFit {
    /// The result, its gain and whether it passes still to be set.
    result: FamilyResult,
    /// Held-out mean squared error of each run.
    per_run: Vec<f64>,
}

impl FamilyFit {
    /// The family judged against the baseline's held-out cost and per-run mean squared errors.
    fn judged(self, (base_cost, base_runs): (f64, &[f64]), opts: &ExploreOptions) -> FamilyResult {
        let mut r = self.result;
        r.held_out_gain = 1.0 - r.held_out_cost / base_cost;
        let gains: Vec<f64> = self.per_run.iter().zip(base_runs).map(|(c, b)| 1.0 - (c / b).sqrt()).collect();
        r.gain_std_error = mean_std_error(&gains);
        r.passes = r.status == FamilyStatus::Fitted
            && r.held_out_gain.is_finite()
            && r.held_out_gain >= opts.min_gain
            && r.held_out_gain > opts.min_gain_std_errors * r.gain_std_error;
        r
    }
}

/// Fit one family on `train` (with everything else, as `train --effect` does) and measure it on `validate`.
fn fit_family(
    model: &FittedModel,
    family: Family,
    train: &[Run],
    validate: &[Run],
    plan: &Plan,
) -> Result<FamilyFit, Error> {
    let learned = EffectKind::Learned(Learned { family, n_wheels: model.model.n_wheels() });
    let specs = learned.params();
    let c = refine(model, std::slice::from_ref(&learned), train, plan, &mut NoopObserver)?;
    let first = model.params.len();
    let range = first..c.fitted.params.len();
    let held = c.held_params();
    let terms: Vec<Term> = specs
        .iter()
        .zip(range.clone())
        .map(|(s, i)| Term {
            name: s.name.clone(),
            value: c.fitted.params[i],
            std_error: c.identifiability.params.get(i).and_then(|u| u.std_error).unwrap_or(f64::NAN),
            unit: s.unit.clone(),
            held: held.contains(&i),
        })
        .collect();
    let status = status_of(&c, plan, &terms, range.clone());
    let curve = match strongest(&terms) {
        Some(k) if status == FamilyStatus::Fitted => {
            Some(feature_curve(&c, train, plan.objective, first + k, &terms[k])?)
        }
        _ => None,
    };
    let (cost, per_run) = held_out(&c.fitted, validate)?;
    let result = FamilyResult {
        family,
        status,
        held_out_gain: f64::NAN,
        gain_std_error: f64::NAN,
        passes: false,
        held_out_cost: cost,
        terms,
        held: c.held.iter().map(|w| w.text.clone()).collect(),
        fitted: c.fitted,
        curve,
        held_out_kinds: None,
    };
    Ok(FamilyFit { result, per_run })
}

/// Largest change of a term, in fractions of its scale (the identifiability analysis's), below which the
/// fit counts as having left the family at its start.
const UNMOVED: f64 = 1e-9;

/// Whether the family's terms (parameters `range` of the fit `c`) were fitted, and if not, why not.
fn status_of(c: &Calibration, plan: &Plan, terms: &[Term], range: Range<usize>) -> FamilyStatus {
    let moved = range.clone().zip(terms).any(|(i, t)| {
        let scale = c.identifiability.params.get(i).map_or(1.0, |u| u.scale);
        t.value.abs() > UNMOVED * scale
    });
    if !moved && terms.iter().all(|t| t.held) {
        // Every term in a held direction and none moved: not excited at all when each of those directions
        // is null (no standard error), else excited but inseparable.
        let null = |i: usize| {
            c.held
                .iter()
                .filter(|w| w.direction.get(i).is_some_and(|v| v.abs() >= WEAK_LOADING))
                .all(|w| w.std_error.is_none())
        };
        return if range.clone().all(null) { FamilyStatus::NotExcited } else { FamilyStatus::Singular };
    }
    // The first stage is the free fit; those after it run within the held subspace.
    match c.stages.first().map(|s| s.solution.termination) {
        Some(Termination::MaxEvaluations) => {
            let evaluations = plan.stages.iter().find_map(|s| match s {
                Stage::Lm(LmConfig { max_evaluations, .. }) => Some(*max_evaluations),
                Stage::Ga(_) => None,
            });
            let evaluations = evaluations.unwrap_or(0);
            FamilyStatus::NotConverged { reason: Unconverged::Budget { evaluations } }
        }
        Some(Termination::NoImprovement) => FamilyStatus::NotConverged { reason: Unconverged::NoStep },
        _ if !moved => FamilyStatus::NotConverged { reason: Unconverged::AtZero },
        _ => FamilyStatus::Fitted,
    }
}

/// Held-out path cost (every pose, 1 m/rad) and each run's path mean squared error.
fn held_out(model: &FittedModel, runs: &[Run]) -> Result<(f64, Vec<f64>), Error> {
    let ev = Evaluator::for_report(&model.model, runs, Selection::Path(1))?;
    let errors = ev.errors(&model.model.resolve(&model.params)?);
    let per_run = (0..errors.n_runs()).map(|i| errors.path_mse(i, 1.0)).collect();
    Ok((errors.path_cost(1.0), per_run))
}

/// Standard error of a mean (0 with fewer than two values).
fn mean_std_error(v: &[f64]) -> f64 {
    let n = v.len();
    if n < 2 {
        return 0.0;
    }
    let m = v.iter().sum::<f64>() / n as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64 / n as f64).sqrt()
}

/// The term with the largest `|value| / std_error`.
fn strongest(terms: &[Term]) -> Option<usize> {
    (0..terms.len()).filter(|&k| terms[k].z() > 0.0).max_by(|&a, &b| terms[a].z().total_cmp(&terms[b].z()))
}

/// Number of bins of a [`FeatureCurve`].
const CURVE_BINS: usize = 10;

/// The added-variable curve of parameter `col` (term `term`) at the fit `c` on `runs` and `objective`: the feature
/// `x = −J_col` (central differences) and the residual with the term's part put back, `y = r − J_col θ`,
/// both unweighted (m), in equal-count bins.
fn feature_curve(
    c: &Calibration,
    runs: &[Run],
    objective: CostKind,
    col: usize,
    term: &Term,
) -> Result<FeatureCurve, Error> {
    let (model, x) = (&c.fitted.model, &c.fitted.params);
    let problem = CalibrationProblem::new(model, runs, objective, Bounds::unbounded(x.len()))?;
    let residuals = problem.residuals(x);
    let h = 1e-6 * x[col].abs().max(1e-3);
    let at = |d: f64| {
        let mut y = x.clone();
        y[col] += d;
        problem.residuals(&y)
    };
    let (up, down) = (at(h), at(-h));
    let column: Vec<f64> = up.iter().zip(&down).map(|(a, b)| (a - b) / (2.0 * h)).collect();
    let run_rows = problem.run_rows();
    let g = run_rows.len().max(1) as f64;
    let mut points = Vec::with_capacity(residuals.len());
    let mut row = 0;
    for &rows in &run_rows {
        // Undo the path cost's weight 1/sqrt(G · poses) of this run.
        let unweight = (g * (rows / 3).max(1) as f64).sqrt();
        for i in row..(row + rows).min(residuals.len()) {
            let x = -column[i] * unweight;
            let y = (residuals[i] - column[i] * term.value) * unweight;
            if x != 0.0 && x.is_finite() && y.is_finite() {
                points.push((x, y));
            }
        }
        row += rows;
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let per = points.len().div_ceil(CURVE_BINS).max(1);
    let bins = points
        .chunks(per)
        .map(|c| {
            let n = c.len() as f64;
            Bin {
                feature: c.iter().map(|p| p.0).sum::<f64>() / n,
                residual_m: c.iter().map(|p| p.1).sum::<f64>() / n,
                count: c.len(),
            }
        })
        .collect();
    Ok(FeatureCurve { term: term.name.clone(), unit: term.unit.clone(), slope: term.value, bins })
}
