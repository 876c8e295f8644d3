//! Diagnosis: compare a model with the measurements, find where it fails, and test which catalogued
//! physical effect is missing — then prove it on held-out runs.
//!
//! [`diagnose`] runs named steps: compare (`compare.rs`), gather each candidate's evidence (`evidence.rs`),
//! rank and climb the error ladder (`search.rs`), check the winner on left-out kinds of path, and state
//! findings and verdict as facts (`findings.rs`, with the noise and excitation checks of `noise.rs`). The
//! report's sentences are made from those facts in one place, [`crate::science::text`].
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
mod evidence;
mod findings;
mod kinds;
mod noise;
pub(crate) mod search;
mod unexplained;

pub use clock::{ClockLag, clock_lag};
pub use compare::{Turn, costs_of, costs_of_each};
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
use crate::science::identify::{Identifiability, IdentifyOptions};
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

/// Costs of a model on training and held-out runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Costs {
    /// Path RMS on training runs. m (heading 1 m/rad).
    pub train_path: f64,
    /// Path RMS on held-out runs.
    pub held_out_path: f64,
    /// Eq. 6 on training runs.
    pub train_end_pose: f64,
    /// Eq. 6 on held-out runs.
    pub held_out_end_pose: f64,
}

/// Per-run comparison.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunReport {
    /// Run name.
    pub name: String,
    /// Command label, when known.
    pub command: Option<String>,
    /// Path RMS of the model. m.
    pub path_rms: f64,
    /// Path RMS of the design model. m.
    pub design_path_rms: f64,
    /// End-pose error (Eq. 6 term) of the model.
    pub end_error: f64,
    /// End-pose error of the design model.
    pub design_end_error: f64,
}

/// Errors of a group of runs sharing a command direction and turn sign, or (runs without a command) the
/// same kind of path ([`MotionKind`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GroupReport {
    /// `α=30° ω>0` style label, or the kind of path (`arcs, net turn left, ~0.20 m/s, ~4.00 m`).
    pub group: String,
    /// Whether the runs repeat one command or only share a kind of path.
    #[serde(default)]
    pub basis: GroupBasis,
    /// Runs in it.
    pub runs: usize,
    /// Mean end-pose error vector (dx m, dy m, dθ rad) in the world frame.
    pub mean_end_error: [f64; 3],
    /// Its norm: the systematic part.
    pub bias: f64,
    /// Scatter between runs (RMS deviation from the mean): the random part.
    pub scatter: f64,
    /// Smallest two-sided p-value of the t-tests of the mean's components (dx, dy, dθ) against their
    /// standard errors from the repeats, Bonferroni-corrected (×3); `None` for a single run.
    pub p_value: Option<f64>,
    /// The bias is beyond the repeat scatter: `p_value` below 5 % (never for a single run).
    pub systematic: bool,
}

/// How the error grows along the runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Growth {
    /// Fraction of run time at the bin centres (0…1).
    pub fraction: Vec<f64>,
    /// Mean position error in each bin. m.
    pub position_m: Vec<f64>,
    /// Mean |heading error| in each bin. rad.
    pub heading_rad: Vec<f64>,
}

/// One candidate effect's evidence.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Candidate {
    /// Effect id.
    pub effect: String,
    /// Physics in one line.
    pub physics: String,
    /// Share of the training residual the effect could explain to first order (0…1); for an effect without
    /// parameters (`sample_timing`), the exact share switching it on removes; NaN (JSON null) when switching
    /// it on changes no residual (then `not_excited` says so).
    pub first_order_explained: f64,
    /// Smallest share of the effect's sensitivity outside the model's (0 = fully absorbed).
    pub separability: f64,
    /// The model already expresses it (separability < 5 %).
    pub absorbed: bool,
    /// Effect values the model's change from design implies (when absorbed).
    pub implied: Vec<ParamValue>,
    /// Costs after refitting with the effect (None when absorbed or the refit failed).
    pub refit: Option<Costs>,
    /// Relative fall of the held-out path cost (positive = better).
    pub held_out_gain: f64,
    /// Share of the held-out excess variance over the noise floor that the effect removes:
    /// `(before² − after²) / (before² − floor²)` (NaN without a noise floor).
    pub excess_closed: f64,
    /// Fitted effect parameters with standard errors.
    pub params: Vec<ParamValue>,
    /// Why the training runs cannot tell this effect (not ranked), when they cannot: `excitation_gap` in
    /// words.
    #[serde(default)]
    pub not_excited: Option<String>,
    /// Why the training runs cannot tell this effect, as facts.
    #[serde(skip)]
    pub excitation_gap: Option<ExcitationGap>,
    /// The effect's parameters the refit held at their null values (truncated update: the runs do not
    /// constrain them), as `train --effect` holds them; the held-out gain is with them held.
    #[serde(default)]
    pub held: Vec<String>,
    /// The refit model with the effect (None when absorbed, not excited or the refit failed).
    #[serde(skip)]
    pub fitted: Option<FittedModel>,
}

/// A named value with unit and optional standard error.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ParamValue {
    /// Name.
    pub name: String,
    /// Value.
    pub value: f64,
    /// Unit.
    pub unit: String,
    /// Standard error (same unit), when estimated.
    pub std_error: Option<f64>,
}

/// A candidate judged on whole kinds of path it was not fitted on.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct KindOut {
    /// Effect id.
    pub effect: String,
    /// Per kind left out: (kind, path RMS without the effect, with it). m.
    pub folds: Vec<(String, f64, f64)>,
    /// Relative fall of the path cost over all left-out kinds (positive = better).
    pub gain: f64,
}

/// One rung of the error ladder.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Rung {
    /// `design`, `fitted matrix`, `+ time_offset`, …
    pub label: String,
    /// Costs at this rung.
    pub costs: Costs,
}

/// Measurement noise seen while the robot stands still.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct NoiseFloor {
    /// Position noise per axis. m.
    pub position_m: f64,
    /// Heading noise. rad.
    pub heading_rad: f64,
    /// Path RMS expected from this noise alone (start and current pose noise). m.
    pub path_rms: f64,
    /// Poses used (at rest; or third differences, for the jitter estimate).
    pub samples: usize,
    /// Where the estimate comes from.
    #[serde(default)]
    pub source: NoiseSource,
}

/// Where a noise floor comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseSource {
    /// The scatter of the ground truth while the robot stands still (rests at the runs' ends).
    #[default]
    Standstill,
    /// The runs never stand still: the ground truth's sample-to-sample jitter while moving (third
    /// differences).
    Jitter,
}

/// The whole diagnosis.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Effect to add (None: nothing helps beyond `min_gain`).
    pub verdict: Option<String>,
    /// The verdict in words (`conclusion`, worded by [`text::verdict`]).
    pub verdict_text: String,
    /// A systematic error remains that no accepted effect (the verdict's, or those `auto` added) removes:
    /// decided by the share of command groups biased beyond their repeat scatter, or, without repeats, by
    /// the remaining held-out error against the noise floor (see `unexplained_evidence.decided_by`).
    pub unexplained: bool,
    /// The figures behind `unexplained`.
    pub unexplained_evidence: UnexplainedEvidence,
    /// How held-out costs were obtained, in words (`protocol`): `validation set` or `2-fold cross-validation
    /// over repetitions`.
    pub held_out: String,
    /// Costs of the model as given.
    pub costs: Costs,
    /// Costs of the design model.
    pub design_costs: Costs,
    /// Per-run comparison (training runs).
    pub runs: Vec<RunReport>,
    /// Per command group (training runs).
    pub groups: Vec<GroupReport>,
    /// Error growth along the path (training runs, 10 bins).
    pub growth: Growth,
    /// Where it fails, in words (`facts`, worded by [`text::finding`]).
    pub findings: Vec<String>,
    /// Candidates, best held-out gain first.
    pub ranking: Vec<Candidate>,
    /// Measurement noise floor, when the data has standstills.
    pub noise_floor: Option<NoiseFloor>,
    /// Error ladder: design → model → + effects (with `auto`).
    pub ladder: Vec<Rung>,
    /// What the training runs constrain in the model as given (path residuals).
    pub identifiability: Option<Identifiability>,
    /// Scatter of the end-pose error between repeats of the same command (RMS over groups of ≥ 2 runs),
    /// in Eq. 6 units: the part of the error no deterministic effect can remove. `None` without repeats.
    pub repeatability_floor: Option<f64>,
    /// The verdict's effect validated on kinds of path left out of its fit (straight, turning left,
    /// turning right), when the runs have several kinds.
    pub kind_out: Option<KindOut>,
    /// The best candidate's refit on the held-out runs by the shape of their paths (straight, turning on
    /// the spot, sides then turns, arcs, free): it is not recommended when it hurts one
    /// (`hurts_a_kind`: a kind more than 2 % worse, or the kinds pooled worse).
    pub held_out_kinds: Option<KindOut>,
    /// The training runs' motions against the held-out runs' (with a validation set): what the training
    /// runs lack.
    pub coverage: Option<MotionCoverage>,
    /// `auto` with held-out runs: the explorer's best passing family, which the final model carries and
    /// the verdict names (`unexplained` is then judged with it).
    pub explored: Option<Explored>,
    /// The final model (the input, plus effects added by `auto`, plus the family the explorer passed).
    #[serde(skip)]
    pub final_model: Option<FittedModel>,
    /// `auto` with held-out runs: the explorer's families, fitted from the ladder's model on the training
    /// runs and judged on the held-out runs (the verdict names the best passing one).
    #[serde(skip)]
    pub exploration: Option<Exploration>,
    /// How held-out costs were obtained.
    #[serde(skip)]
    pub protocol: HeldOut,
    /// Where it fails, as facts.
    #[serde(skip)]
    pub facts: Vec<Finding>,
    /// The verdict, as facts.
    #[serde(skip)]
    pub conclusion: Verdict,
}

impl Diagnosis {
    /// An error remains that the final model does not remove: something is missing, or the remaining
    /// held-out error is above `MISSING_RATIO` (3×) the noise floor.
    pub fn error_remains(&self) -> bool {
        self.unexplained || self.conclusion.remaining.is_some_and(|r| r.missing)
    }
}

/// How the held-out costs were obtained.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HeldOut {
    /// On the validation runs given.
    #[default]
    ValidationSet,
    /// On the training runs themselves (too few to hold any out).
    TrainingRuns,
    /// By 2-fold cross-validation over repetitions (even → odd).
    CrossValidation,
}

/// What a rung of the error ladder is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RungKind {
    /// The design model.
    Design,
    /// The model as given.
    Model,
    /// The model so far plus this effect, refitted.
    Added(String),
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
