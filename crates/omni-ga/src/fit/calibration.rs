//! [`calibrate`]: fit a model's parameters to training runs by a [`Plan`], and report how it went.

use crate::error::Error;
use crate::fit::pipeline::{self, Fitted, StageOutcome, Start};
use crate::fit::plan::Plan;
use crate::fit::problem::CalibrationProblem;
use crate::fit::rescale::{self, Rescale};
use crate::fit::search_box::search_box_with;
use crate::optimizer::observe::Observer;
use crate::optimizer::problem::{Bounds, Problem};
use crate::optimizer::{Solution, Termination};
use crate::science::identify::{Identifiability, IdentifyOptions, WEAK_LOADING, WeakDirection};
use omni_kin::cost::{self, CostKind};
use omni_kin::{EffectKind, FittedModel, Run};
use std::time::Instant;

/// The outcome of a calibration.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// The fitted model (with the plan's integration).
    pub fitted: FittedModel,
    /// The start model (with the plan's integration): the design, or a previous fit.
    pub start: FittedModel,
    /// Objective minimised.
    pub objective: CostKind,
    /// Objective at the start.
    pub objective_start: f64,
    /// Objective at the fit.
    pub objective_fitted: f64,
    /// Objective of the start as given (its own integration, which the plan's may replace) on the training
    /// runs: what the fit must not be worse than ([`Calibration::worse_than_start`]).
    pub objective_start_as_given: f64,
    /// Eq. 6 end-pose cost on the training runs at the start.
    pub end_pose_start: f64,
    /// Eq. 6 end-pose cost on the training runs at the fit.
    pub end_pose_fitted: f64,
    /// Cost evaluations (all stages, plus the start's).
    pub evaluations: usize,
    /// Wall time. s.
    pub seconds: f64,
    /// The GA's search box.
    pub bounds: Bounds,
    /// Parameters the GA left on a bound of its box (a trapped fit).
    pub at_bound: Vec<String>,
    /// Parameters the polish moved outside the GA box (the box was too small).
    pub outside_box: Vec<String>,
    /// Every stage run, in order (those within the truncated update's subspace last).
    pub stages: Vec<StageOutcome>,
    /// What the training runs constrain, at the fit.
    pub identifiability: Identifiability,
    /// Directions held at the start by the truncated update ([`crate::fit::Unexcited::Hold`]), as found
    /// after the stages.
    pub held: Vec<WeakDirection>,
    /// When the start's dead reckoning travelled or turned far from the ground truth's (beyond 1.3×), the
    /// ratios it was rescaled by before fitting; the fit started there (and held there what the runs do
    /// not constrain), while [`Self::start`] stays the start as given.
    pub start_rescaled: Option<Rescale>,
}

impl Calibration {
    /// Relative improvement of the Eq. 6 training cost. %.
    pub fn improvement_pct(&self) -> f64 {
        100.0 * (1.0 - self.end_pose_fitted / self.end_pose_start)
    }

    /// Indices of the parameters the truncated update held at the start: those carrying at least
    /// [`WEAK_LOADING`] of a held direction (the identifiability analysis's own rule for a parameter without
    /// a standard error).
    pub fn held_params(&self) -> Vec<usize> {
        (0..self.fitted.params.len())
            .filter(|&i| self.held.iter().any(|w| w.direction.get(i).is_some_and(|v| v.abs() >= WEAK_LOADING)))
            .collect()
    }

    /// The fit when it is worse than its start on its own training runs: its objective above the start's as
    /// given ([`Self::objective_start_as_given`]) by more than `WORSE_TOLERANCE` (1e-9) (relative). The stages
    /// keep the best point, so this happens when the plan's integration misrepresents the runs (a fixed
    /// step that is not their sampling interval): the fit is then worse than the model it started from.
    pub fn worse_than_start(&self) -> Option<WorseThanStart> {
        (self.objective_fitted > self.objective_start_as_given * (1.0 + WORSE_TOLERANCE)).then_some(WorseThanStart {
            objective: self.objective,
            start: self.objective_start_as_given,
            fitted: self.objective_fitted,
        })
    }

    /// The result of the last stage run with optimizer `name` (`ga`, `lm`), if it ran.
    pub fn solution(&self, name: &str) -> Option<&Solution> {
        self.stages.iter().rev().find(|s| s.name == name).map(|s| &s.solution)
    }
}

/// Relative margin above the start's objective within which a fit counts as no worse (the fast route and
/// the walk differ in the last bits).
pub const WORSE_TOLERANCE: f64 = 1e-9;

/// A fit worse than its start on its own training runs ([`Calibration::worse_than_start`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorseThanStart {
    /// The objective compared.
    pub objective: CostKind,
    /// The start's, as given (its own integration).
    pub start: f64,
    /// The fit's.
    pub fitted: f64,
}

impl WorseThanStart {
    /// How many times the start's objective the fit's is.
    pub fn ratio(&self) -> f64 {
        self.fitted / self.start
    }
}

/// Fit `start`'s parameters to `train` following `plan`: its stages, then its truncated update.
pub fn calibrate(
    start: &FittedModel,
    train: &[Run],
    plan: &Plan,
    observer: &mut dyn Observer,
) -> Result<Calibration, Error> {
    let t0 = Instant::now();
    let model = start.model.clone().with_integration(plan.integration);
    let (from_model, start_rescaled) = match rescaled(start, &model, train, plan)? {
        Some((m, r)) => (m, Some(r)),
        None => (start.clone(), None),
    };
    // A direction along which the data move the fit well away from the start as given is not held (the
    // rescaling is the data's too: the ground truth's travel).
    let identify = IdentifyOptions { start: Some(start.params.clone()), ..plan.identify.clone() };
    let plan = &Plan { identify, ..plan.clone() };
    let bounds = search_box_with(&model, &from_model.params, plan.box_rule, &plan.half_widths)?;
    let problem = CalibrationProblem::new(&model, train, plan.objective, bounds.clone())?;
    let objective_from = problem.cost(&from_model.params);
    let names: Vec<String> = model.params().into_iter().map(|p| p.name).collect();
    let from = Start { x: &from_model.params, objective: objective_from, hold_at: &from_model.params, fitted: 0 };
    let mut fit = pipeline::run(&problem, plan, from, &names, observer)?;
    let objective_start = if start_rescaled.is_some() { problem.cost(&start.params) } else { objective_from };
    let start_as_given = objective_as_given(start, train, plan, objective_start)?;
    let identifiability = fit.identifiability.take();
    let mut c = Outcome { fit, identifiability, start_as_given }.report(
        &problem,
        &plan.identify,
        &start.params,
        objective_start,
        t0,
    )?;
    c.start_rescaled = start_rescaled;
    Ok(c)
}

/// The start rescaled to the ground truth's travel ([`crate::fit::rescale`]), for a plan with a local
/// polish (one that can leave the GA's box: the paper's GA alone keeps its box around the design), when
/// that lowers the plan's objective on `train`.
fn rescaled(
    start: &FittedModel,
    model: &omni_kin::Model,
    train: &[Run],
    plan: &Plan,
) -> Result<Option<(FittedModel, Rescale)>, Error> {
    if !plan.stages.iter().any(|s| s.refines_held()) {
        return Ok(None);
    }
    let Some((moved, how)) = rescale::rescaled_start(start, train) else { return Ok(None) };
    let before = cost::cost(model, &start.params, train, plan.objective)?;
    let after = cost::cost(model, &moved.params, train, plan.objective)?;
    Ok((after < before).then_some((moved, how)))
}

/// The objective of `start` as given (its own integration, which the plan's may replace) on `train`:
/// `objective_start` (the plan's integration) when the two integrations are the same.
fn objective_as_given(start: &FittedModel, train: &[Run], plan: &Plan, objective_start: f64) -> Result<f64, Error> {
    if start.model.integration == plan.integration {
        Ok(objective_start)
    } else {
        Ok(cost::cost(&start.model, &start.params, train, plan.objective)?)
    }
}

/// Adds `effects`, at their null values, to the fitted model `base` and refits every parameter: the plan's
/// refining stages (Levenberg–Marquardt, unbounded) from there, then its truncated update, which puts back
/// what the runs do not constrain to `base` and the effects' null values. No GA: the base is already fitted
/// and the effects start at null. The one fit behind `train --effect E` (after the base's own calibration,
/// [`calibrate_with_effects`]), diagnose's candidate refit and the explorer's family fit, so the three agree
/// to the bit on the same runs (issue 25). With no effects, the base refitted alone. The model keeps its
/// integration; the plan's objective is fitted. An effect parameter at the lower end of its range (backlash
/// at 0, where the model uses `|b|`) starts 2 % inside it (`differentiable_start`); it is held back at
/// its null value.
pub fn refine(
    base: &FittedModel,
    effects: &[EffectKind],
    train: &[Run],
    plan: &Plan,
    observer: &mut dyn Observer,
) -> Result<Calibration, Error> {
    refine_on(base, effects, train, plan, observer, BaseFit::TheseRuns)
}

/// Whether the base given to [`refine_on`] is a fit of the runs it is refitted on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaseFit {
    /// Fitted on these very runs (`train --effect`, diagnose with a validation set, explore): the
    /// directions they leave unconstrained in the base are found at its start and held at once.
    TheseRuns,
    /// Fitted on other runs (a subset left out for cross-validation, a kind of path left out): those
    /// directions are judged where the refit has moved, as for any start.
    OtherRuns,
}

/// [`refine`], saying whether `base` is a fit of `train` ([`BaseFit`]).
pub fn refine_on(
    base: &FittedModel,
    effects: &[EffectKind],
    train: &[Run],
    plan: &Plan,
    observer: &mut dyn Observer,
    base_fit: BaseFit,
) -> Result<Calibration, Error> {
    let t0 = Instant::now();
    let start = effects.iter().fold(base.clone(), |m, e| m.with_effect(e.clone()));
    let nudged = differentiable_start(&start, base.params.len());
    let problem = CalibrationProblem::new(&start.model, train, plan.objective, Bounds::unbounded(nudged.len()))?;
    let names: Vec<String> = start.model.params().into_iter().map(|p| p.name).collect();
    let refining = Plan { stages: plan.stages.iter().filter(|s| s.refines_held()).cloned().collect(), ..plan.clone() };
    let objective = problem.cost(&nudged);
    let fitted = if base_fit == BaseFit::TheseRuns { base.params.len() } else { 0 };
    let from = Start { x: &nudged, objective, hold_at: &start.params, fitted };
    let mut fit = pipeline::run(&problem, &refining, from, &names, observer)?;
    let objective_start = problem.cost(&start.params);
    // The model keeps its own integration: the start as given is the start fitted from.
    let identifiability = fit.identifiability.take();
    let outcome = Outcome { fit, identifiability, start_as_given: objective_start };
    outcome.report(&problem, &plan.identify, &start.params, objective_start, t0)
}

/// `start`'s parameters, with those from `first` on whose value is the lower end of their range (backlash
/// b ≥ 0 at its null value) moved 2 % inside it, where the model is differentiable.
pub(crate) fn differentiable_start(start: &FittedModel, first: usize) -> Vec<f64> {
    let mut x = start.params.clone();
    for (i, s) in start.model.params().iter().enumerate().skip(first) {
        if x[i] == s.lower && s.upper > s.lower {
            x[i] = s.lower + 0.02 * (s.upper - s.lower);
        }
    }
    x
}

/// `omnical train`: calibrate `start`'s own parameters by `plan` ([`calibrate`]: its stages and truncated
/// update), then add each of `effects` in turn by [`refine`] — one effect at a time, as diagnose's error
/// ladder adds them, so that `train --effect E` is the fit diagnose and explore judged. A plan without a
/// refining stage (the paper's GA alone) fits everything at once instead, as the paper does; so does a fit
/// the observer stopped (Ctrl-C keeps the base's best so far, the effects at their null values).
pub fn calibrate_with_effects(
    start: &FittedModel,
    effects: &[EffectKind],
    train: &[Run],
    plan: &Plan,
    observer: &mut dyn Observer,
) -> Result<Calibration, Error> {
    let with_all = |m: &FittedModel| effects.iter().fold(m.clone(), |m, e| m.with_effect(e.clone()));
    if effects.is_empty() || !plan.stages.iter().any(|s| s.refines_held()) {
        return calibrate(&with_all(start), train, plan, observer);
    }
    let t0 = Instant::now();
    let base = calibrate(start, train, plan, observer)?;
    let stopped = base.stages.iter().any(|s| s.solution.termination == Termination::Stopped);
    let mut fit = Fitted {
        x: Vec::new(),
        evaluations: base.evaluations - 1,
        at_bound: base.at_bound,
        stages: base.stages,
        held: base.held,
        identifiability: None,
    };
    let mut current = base.fitted;
    let mut identifiability = None;
    for e in effects {
        if stopped {
            current = current.with_effect(e.clone());
            continue;
        }
        let step = refine(&current, std::slice::from_ref(e), train, plan, observer)?;
        fit.evaluations += step.evaluations - 1;
        fit.stages.extend(step.stages);
        fit.held = step.held;
        identifiability = Some(step.identifiability);
        current = step.fitted;
    }
    fit.x = current.params;
    let full = with_all(start);
    let model = full.model.clone().with_integration(plan.integration);
    let bounds = search_box_with(&model, &full.params, plan.box_rule, &plan.half_widths)?;
    let problem = CalibrationProblem::new(&model, train, plan.objective, bounds)?;
    let objective_start = problem.cost(&full.params);
    let start_as_given = objective_as_given(&full, train, plan, objective_start)?;
    Outcome { fit, identifiability, start_as_given }.report(&problem, &plan.identify, &full.params, objective_start, t0)
}

/// What a fit ended with, before its report: the pipeline's result and, when already computed at its point,
/// the identifiability there.
struct Outcome {
    fit: Fitted,
    identifiability: Option<Identifiability>,
    /// The start's objective as given ([`Calibration::objective_start_as_given`]).
    start_as_given: f64,
}

impl Outcome {
    /// The [`Calibration`] of this fit of `problem` from `start` (objective `objective_start`), begun at `t0`;
    /// `identify` decides what the runs constrain at the fit.
    fn report(
        self,
        problem: &CalibrationProblem<'_>,
        identify: &IdentifyOptions,
        start: &[f64],
        objective_start: f64,
        t0: Instant,
    ) -> Result<Calibration, Error> {
        let (model, train, fit) = (problem.model(), problem.runs(), self.fit);
        let bounds = problem.bounds().clone();
        let names: Vec<String> = model.params().into_iter().map(|p| p.name).collect();
        let outside_box = names
            .iter()
            .enumerate()
            .filter(|&(i, _)| fit.x[i] < bounds.lower[i] || fit.x[i] > bounds.upper[i])
            .map(|(_, n)| n.clone())
            .collect();
        let fitted = FittedModel::new(model.clone(), fit.x)?;
        let objective_fitted = problem.cost(&fitted.params);
        let identifiability = self.identifiability.unwrap_or_else(|| problem.identifiability(&fitted.params, identify));
        let end_pose_start = cost::cost(model, start, train, CostKind::EndPose)?;
        let end_pose_fitted = cost::cost(model, &fitted.params, train, CostKind::EndPose)?;
        Ok(Calibration {
            fitted,
            start: FittedModel::new(model.clone(), start.to_vec())?,
            objective: problem.objective(),
            objective_start,
            objective_fitted,
            objective_start_as_given: self.start_as_given,
            end_pose_start,
            end_pose_fitted,
            evaluations: 1 + fit.evaluations,
            seconds: t0.elapsed().as_secs_f64(),
            bounds,
            at_bound: fit.at_bound,
            outside_box,
            stages: fit.stages,
            identifiability,
            held: fit.held,
            start_rescaled: None,
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::fit::plan::Preset;
    use crate::optimizer::observe::NoopObserver;
    use omni_kin::simulate::{SimConfig, flower_commands, simulate};
    use omni_kin::{IkMatrix, Model};

    /// Runs of the paper's robot (Eq. 9) sampled every 40 ms, as OptiOdom's omni3 data is.
    fn runs_at_40_ms() -> Vec<Run> {
        let config = SimConfig {
            commands: flower_commands().into_iter().step_by(3).collect(),
            runs_per_command: 1,
            duration_s: 4.0,
            wheel_rate_hz: 25.0,
            ..SimConfig::default()
        };
        simulate(&config, &FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated())), "r/").unwrap()
    }

    /// The paper's fixed 10 ms step on 40 ms data: the step check says so up front (factor 0.25), and the
    /// fit (which cannot scale the matrix 4× within its box) ends worse than the design it started from,
    /// which the calibration reports with both objectives.
    #[test]
    fn a_fit_worse_than_its_start_is_reported() {
        let runs = runs_at_40_ms();
        let design = FittedModel::paper_design();
        let mut plan = Plan::preset(Preset::Paper, design.model.n_params());
        plan.ga_mut().unwrap().max_generations = 5;
        let m = plan.step_mismatch(&runs).unwrap();
        assert_eq!(m.step_s, 0.010);
        assert!((m.median_interval_s - 0.040).abs() < 1e-9, "{m:?}");
        assert!((m.factor() - 0.25).abs() < 1e-9);
        let c = calibrate(&design, &runs, &plan, &mut NoopObserver).unwrap();
        let w = c.worse_than_start().expect("the fit is worse than the design on its own training runs");
        assert_eq!(w.objective, CostKind::EndPose);
        let own = cost::cost(&design.model, &design.params, &runs, CostKind::EndPose).unwrap();
        assert_eq!(w.start, own, "the start is compared as given: each run's own steps");
        assert_eq!(w.fitted, c.objective_fitted);
        assert!(w.ratio() > 2.0, "fitted {} vs start {}", w.fitted, w.start);
        // Within the plan's own integration the stages still kept their best point.
        assert!(c.objective_fitted <= c.objective_start);
    }

    /// Each run's own step (the default preset): no mismatch, and the fit beats its start.
    #[test]
    fn a_fit_on_the_runs_own_steps_is_not_worse() {
        let runs = runs_at_40_ms();
        let design = FittedModel::paper_design();
        let mut plan = Plan::preset(Preset::Default, design.model.n_params());
        plan.ga_mut().unwrap().max_generations = 5;
        assert_eq!(plan.step_mismatch(&runs), None);
        let c = calibrate(&design, &runs, &plan, &mut NoopObserver).unwrap();
        assert_eq!(c.objective_start_as_given, c.objective_start);
        assert_eq!(c.worse_than_start(), None, "fitted {} vs start {}", c.objective_fitted, c.objective_start);
        assert!(c.objective_fitted < 0.5 * c.objective_start);
    }
}
