//! Diagnosis: compare a model with the measurements, find where it fails, and test which catalogued
//! physical effect is missing — then prove it on held-out runs.
//!
//! [`diagnose`] runs named steps: compare (`compare.rs`), gather each candidate's evidence (`evidence.rs`),
//! rank and climb the error ladder (`search.rs`), check the winner on left-out kinds of path, and state
//! findings and verdict as facts (`findings.rs`, with the noise and excitation checks of `noise.rs`), and
//! returns them ([`Diagnosis`], `diagnosis.rs`). The report's sentences are made from those facts in one
//! place, [`crate::science::text`].
//!
//! For each candidate effect not yet in the model:
//! 1. **First-order test** at the current fit: the Jacobian of the path residuals with respect to the
//!    model's parameters (`J_m`) and the effect's (`J_e`, at its null value). The share of the residual
//!    that `[J_m J_e]` explains beyond `J_m` says how much the effect could help; the part of `J_e` outside
//!    the span of `J_m` says whether the data can tell the effect from the model at all. An effect whose
//!    sensitivities lie (to 5 %) in the span of the model's is **absorbed**: the model already expresses it,
//!    and the implied effect values are reported (`min ‖J_e e − J_m (x̂ − x_design)‖`).
//! 2. **Refit** model + effect on the training runs (Levenberg–Marquardt from the current fit) and judge
//!    it on held-out runs (the validation set, or 2-fold cross-validation over repetitions). Candidates are
//!    ranked by the relative fall of the held-out path cost; the verdict is the best one if it falls by at
//!    least `min_gain` (default 5 %) and removes most (≥ 50 %) of the held-out error variance above the
//!    noise floor (otherwise it is reported as helping only in part, and no verdict is claimed).
//! 3. **Noise floor**: the scatter of ground-truth poses while the robot stands still (rests at the start
//!    and end of runs).
//! 4. **Something unexplained?** (`unexplained.rs`) With the accepted effects, the share of command groups
//!    whose mean end-pose error is biased beyond their repeat scatter (a t-test per group, the share judged
//!    against chance); without repeats, the remaining held-out error against the noise floor (3×).
//!
//! Evidence comes from the path (every ground-truth pose), since the end pose alone cannot see some
//! effects (a clock offset when the robot rests at both ends); the paper's Eq. 6 is reported beside it.
//! Parameter uncertainties are those of [`crate::identify`] at the refit (the per-run sandwich, robust to
//! the correlation of residuals along a path; iid only with too few runs), the same numbers `train` reports
//! for the same model on the same runs.

mod clock;
mod compare;
mod diagnosis;
mod evidence;
mod findings;
mod kinds;
mod noise;
pub(crate) mod search;
mod unexplained;

pub use clock::{ClockLag, clock_lag};
pub use compare::{Turn, costs_of, costs_of_each};
pub use diagnosis::{
    Candidate, Costs, Diagnosis, GroupReport, Growth, HeldOut, KindOut, NoiseFloor, NoiseSource, ParamValue, RunReport,
    Rung, RungKind,
};
pub(crate) use evidence::unbounded;
pub use evidence::{differentiable_start, refit, refit_on};
pub use findings::{Conclusion, Explored, Finding, Remaining, Verdict};
pub use kinds::{GroupBasis, MotionKind, Shape};
pub use noise::{ExcitationGap, GapKind, WheelGap, noise_floor, wheel_excitation, wheel_excitation_gap};
pub use unexplained::{DecidedBy, MIN_DOF_TO_CLEAR, UnexplainedEvidence};

use crate::error::Error;
use crate::fit::BaseFit;
use crate::science::coverage::{MotionCoverage, motion_coverage};
use crate::science::explore::{Exploration, ExploreOptions, FamilyResult, explore};
use crate::science::identify::IdentifyOptions;
use crate::science::text;
use compare::compare;
use evidence::{Bench, candidate_effect};
use findings::{Judgement, findings};
use noise::repeatability_floor;
use omni_kin::{EffectKind, FittedModel, Run, RunModels, ToRunModels};
use search::{confident, held_out_kinds, hurts_a_kind, kind_out, passes};
use serde::{Deserialize, Serialize};

/// Diagnosis settings.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DiagnoseOptions {
    /// Candidate effect ids (default: the whole catalogue).
    pub candidates: Vec<String>,
    /// Minimum relative fall of the held-out path cost for an effect to be recommended. Default 0.05.
    pub min_gain: f64,
    /// Add effects greedily while they pass `min_gain` (the error ladder).
    pub auto: bool,
    /// At most this many effects added by `auto`. Default 3.
    pub max_added: usize,
    /// Use every k-th ground-truth pose for residuals. Default 1.
    pub every: usize,
    /// Share of the excess error variance (above the noise floor) an effect must remove to be named with
    /// confidence ("explains most of it"). Default 0.5.
    pub min_excess_closed: f64,
    /// User effects (`EffectKind::Custom`, e.g. from Python) tried as candidates after `candidates`, by
    /// their ids. Default none.
    #[serde(skip)]
    pub custom: Vec<EffectKind>,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            candidates: omni_kin::effect::CATALOGUE.iter().map(|s| s.to_string()).collect(),
            min_gain: 0.05,
            auto: false,
            max_added: 3,
            every: 1,
            min_excess_closed: 0.5,
            custom: Vec::new(),
        }
    }
}

/// The fitting and held-out runs, and how they were chosen.
fn held_out_sets(train: &[Run], validation: Option<&[Run]>) -> (Vec<Run>, Vec<Run>, HeldOut) {
    match validation {
        Some(v) if !v.is_empty() => (train.to_vec(), v.to_vec(), HeldOut::ValidationSet),
        _ => {
            let (a, b) = split_held_out(train);
            if a.is_empty() || b.is_empty() {
                (train.to_vec(), train.to_vec(), HeldOut::TrainingRuns)
            } else {
                (a, b, HeldOut::CrossValidation)
            }
        }
    }
}

/// Even repetitions (or run indices) for fitting, odd ones held out.
fn split_held_out(train: &[Run]) -> (Vec<Run>, Vec<Run>) {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for (i, r) in train.iter().enumerate() {
        let key = r.repetition().map(|x| x as usize).unwrap_or(i);
        if key % 2 == 0 { a.push(r.clone()) } else { b.push(r.clone()) }
    }
    (a, b)
}

/// The recommended effect: the best candidate if it passes with confidence and also helps on kinds of
/// path it was not fitted on (when the runs have several); and that check. A `time_offset` whose fitted
/// lag the model-free estimate `lag` confirms skips the kinds check: a clock does not depend on the kind of
/// path, and a fit on fewer kinds determines it worse, not differently. Returns that estimate too.
fn recommend(
    model: &FittedModel,
    ranking: &[Candidate],
    (train, held): (&[Run], &[Run]),
    every: usize,
    opts: &DiagnoseOptions,
) -> Result<Recommendation, Error> {
    // A clock offset between the wheels and the reference, measured without a model.
    let lag = clock::clock_lag(train);
    let Some(winner) = ranking.first().filter(|c| passes(c, opts) && confident(c, opts)) else {
        return Ok(Recommendation { effect: None, kind_check: None, held_kinds: None, lag });
    };
    // Transfer is part of passing: the winner's own refit must not hurt a kind of held-out path.
    let held_kinds = held_out_kinds(model, winner, held, every)?;
    if held_kinds.as_ref().is_some_and(hurts_a_kind) {
        return Ok(Recommendation { effect: None, kind_check: None, held_kinds, lag });
    }
    let confirmed = lag.as_ref().is_some_and(|l| {
        winner.effect == omni_kin::effect::TimeOffset::ID
            && l.named()
            && winner.params.first().is_some_and(|p| l.confirms(p.value, p.std_error))
    });
    if confirmed {
        return Ok(Recommendation { effect: Some(winner.effect.clone()), kind_check: None, held_kinds, lag });
    }
    let effect = candidate_effect(&winner.effect, model.model.n_wheels(), opts)?;
    let kind_check = kind_out(model, &effect, train, every)?;
    let failed = kind_check.as_ref().is_some_and(hurts_a_kind);
    Ok(Recommendation { effect: (!failed).then(|| winner.effect.clone()), kind_check, held_kinds, lag })
}

/// What [`recommend`] decides: the effect, the left-out-kinds check when it ran, and the model-free clock
/// estimate.
struct Recommendation {
    effect: Option<String>,
    kind_check: Option<KindOut>,
    held_kinds: Option<KindOut>,
    lag: Option<ClockLag>,
}

/// Whether something physical is still missing once `model` is used: the one decision of diagnose,
/// explore and the report ([`unexplained`](crate::science::diagnose::DecidedBy)), from `model`'s groups and
/// error growth on the training runs `train`, its remaining held-out path RMS `held_out_m` (m) and the
/// noise floor ([`noise_of`]).
pub fn remains(
    model: &FittedModel,
    train: &[Run],
    held: &[Run],
    held_out_m: f64,
    every: usize,
) -> Result<(bool, UnexplainedEvidence, Option<NoiseFloor>), Error> {
    let cmp = compare(model, &RunModels::from(model), train, every.max(1))?;
    let noise = noise_of(train, held);
    let (missing, evidence) =
        unexplained::decide(&cmp.groups, &cmp.growth, repeatability_floor(&cmp.groups), held_out_m, noise.as_ref());
    Ok((missing, evidence, noise))
}

/// The measurement noise floor of the training runs, or of the held-out runs when the training runs
/// show none.
pub fn noise_of(train: &[Run], held: &[Run]) -> Option<NoiseFloor> {
    noise_floor(train).or_else(|| noise_floor(held))
}

/// What the held-out runs add to `facts` about `model` (against `design`) fitted on `fit_runs`: how many
/// held-out runs end worse than the design (after the first finding) and, with a validation set, the motions
/// the training runs lack (first: it bounds what any fit on them can learn). Returns the motion coverage
/// (with a validation set).
fn held_out_findings(
    facts: &mut Vec<Finding>,
    (model, design): (&FittedModel, &FittedModel),
    (fit_runs, held_runs): (&[Run], &[Run]),
    protocol: HeldOut,
    every: usize,
) -> Result<Option<MotionCoverage>, Error> {
    if protocol != HeldOut::TrainingRuns {
        let (worse, runs) = compare::worse_than_design(model, design, held_runs, every)?;
        if worse > 0 {
            facts.insert(facts.len().min(1), Finding::WorseThanDesign { worse, runs });
        }
    }
    let coverage = match protocol {
        HeldOut::ValidationSet => Some(motion_coverage(model, fit_runs, held_runs)?),
        _ => None,
    };
    if let Some(c) = coverage.as_ref().filter(|c| c.lacking()) {
        facts.insert(0, Finding::MissingMotions(c.clone()));
    }
    Ok(coverage)
}

/// The model with the accepted effects, whose repeat structure the verdict reads: the verdict's (refitted),
/// or those `auto` added; `None` when none was accepted.
fn accepted(verdict: bool, climb: &search::Climb, auto: bool) -> Option<&FittedModel> {
    match (verdict, climb.ranking.first(), auto) {
        (true, Some(Candidate { fitted: Some(f), .. }), false) => Some(f),
        (_, _, true) if climb.ladder.len() > 2 => Some(&climb.top),
        _ => None,
    }
}

/// Diagnose `model` on `train`, holding out `validation` (or cross-validating over repetitions).
///
/// `design`: the design each run is compared with — one model (a `&FittedModel`) or a model per run
/// (a `&RunModels`, when a robot's sets declare different designs; it must know every training and
/// validation run). Its design costs are the run-weighted means of the runs' own; the implied effect values
/// are taken against its first model.
pub fn diagnose(
    model: &FittedModel,
    design: &impl ToRunModels,
    train: &[Run],
    validation: Option<&[Run]>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, Error> {
    if train.is_empty() {
        return Err(Error::NoRuns);
    }
    let designs = design.to_run_models();
    let every = opts.every.max(1);
    let (fit_runs, held_runs, protocol) = held_out_sets(train, validation);
    let costs = costs_of(model, &fit_runs, &held_runs, every)?;
    let design_costs = costs_of_each(&designs, &fit_runs, &held_runs, every)?;
    let cmp = compare(model, &designs, train, every)?;
    let noise = noise_of(train, &held_runs);
    // Each candidate's evidence, ranked; with `auto`, the error ladder.
    let design = designs.first();
    // With a validation set (or none at all) the model is judged on the runs it was fitted on; a
    // cross-validation subset is other runs.
    let base_fit = if protocol == HeldOut::CrossValidation { BaseFit::OtherRuns } else { BaseFit::TheseRuns };
    let bench = Bench { design, fit_runs: &fit_runs, held_runs: &held_runs, every, noise: noise.as_ref(), base_fit };
    let climb = search::climb(&bench, model, &costs, &design_costs, opts)?;
    let Recommendation { effect: verdict, kind_check, held_kinds, lag } =
        recommend(model, &climb.ranking, (train, &held_runs), every, opts)?;
    // What the runs constrain in the model as given, and where it fails.
    let identifiability = unbounded(&model.model, &fit_runs, every)
        .ok()
        .map(|p| p.identifiability(&model.params, &IdentifyOptions::default()));
    let repeat_floor = repeatability_floor(&cmp.groups);
    let mut facts =
        findings(&cmp.runs, &cmp.groups, &cmp.growth, &climb.ranking, identifiability.as_ref(), repeat_floor);
    facts.splice(0..0, lag.filter(ClockLag::named).map(Finding::ClockLag));
    let coverage = held_out_findings(&mut facts, (model, design), (&fit_runs, &held_runs), protocol, every)?;
    let after =
        accepted(verdict.is_some(), &climb, opts.auto).map(|f| compare(f, &designs, train, every)).transpose()?;
    let (groups_after, growth_after) = after.as_ref().map_or((&cmp.groups, &cmp.growth), |c| (&c.groups, &c.growth));
    let mut conclusion = Judgement {
        ranking: &climb.ranking,
        verdict: verdict.as_deref(),
        kind_check: kind_check.as_ref(),
        held_kinds: held_kinds.as_ref(),
        costs: &costs,
        top: climb.ladder.last().map_or(&costs, |r| &r.costs),
        noise: noise.as_ref(),
        groups: groups_after,
        growth: growth_after,
        repeat_floor: repeatability_floor(groups_after),
    }
    .verdict(opts);
    let (top, exploration) = explore_stage(climb.top, train, validation, opts, &mut conclusion)?;
    Ok(Diagnosis {
        verdict,
        verdict_text: text::verdict(&conclusion),
        unexplained: conclusion.unexplained,
        unexplained_evidence: conclusion.evidence.clone(),
        held_out: text::held_out(protocol).to_string(),
        costs,
        design_costs,
        runs: cmp.runs,
        groups: cmp.groups,
        growth: cmp.growth,
        findings: facts.iter().map(text::finding).collect(),
        ranking: climb.ranking,
        noise_floor: noise,
        ladder: climb.ladder,
        identifiability,
        repeatability_floor: repeat_floor,
        kind_out: kind_check,
        held_out_kinds: held_kinds,
        coverage,
        explored: conclusion.explored.clone(),
        final_model: Some(top),
        exploration,
        protocol,
        facts,
        conclusion,
    })
}

/// `auto` with held-out runs: the explorer from the ladder's model `top`; when a family passes, the verdict
/// names it and is judged with it, and the final model carries it. Returns the final model and the
/// exploration.
fn explore_stage(
    top: FittedModel,
    train: &[Run],
    validation: Option<&[Run]>,
    opts: &DiagnoseOptions,
    conclusion: &mut Verdict,
) -> Result<(FittedModel, Option<Exploration>), Error> {
    let (true, Some(v)) = (opts.auto, validation) else { return Ok((top, None)) };
    let e = explore(&top, train, v, &ExploreOptions { every: opts.every.max(1), ..ExploreOptions::default() })?;
    let Some(best) = e.best() else { return Ok((top, Some(e))) };
    conclusion.explored = Some(explored(&e, best));
    conclusion.unexplained = e.unexplained;
    conclusion.evidence = e.evidence.clone();
    let ev = &conclusion.evidence;
    if let (Some(floor_m), Some(ratio)) = (ev.noise_floor_m, ev.ratio) {
        let (held_out_m, missing) = (ev.remaining_held_out_m, ratio > unexplained::MISSING_RATIO);
        conclusion.remaining = Some(Remaining { held_out_m, floor_m, ratio, missing });
    }
    let fitted = best.fitted.clone();
    Ok((fitted, Some(e)))
}

/// The explorer's best passing family `f`, as the verdict names it.
fn explored(e: &Exploration, f: &FamilyResult) -> Explored {
    Explored {
        effect: format!("{}{}", omni_kin::effect::learned::PREFIX, f.family.id()),
        gain: f.held_out_gain,
        before_m: e.baseline_held_out_cost,
        after_m: f.held_out_cost,
        hint: text::explore_hint(f),
    }
}
