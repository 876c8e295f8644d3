//! [`calibrate`]: fit a model's parameters to training runs by a [`Plan`], and report how it went.

use crate::error::Error;
use crate::fit::pipeline::{self, StageOutcome};
use crate::fit::plan::Plan;
use crate::fit::problem::CalibrationProblem;
use crate::fit::search_box::search_box_with;
use crate::optimizer::Solution;
use crate::optimizer::observe::Observer;
use crate::optimizer::problem::{Bounds, Problem};
use crate::science::identify::{Identifiability, WeakDirection};
use omni_kin::cost::{self, CostKind};
use omni_kin::{FittedModel, Run};
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
}

impl Calibration {
    /// Relative improvement of the Eq. 6 training cost. %.
    pub fn improvement_pct(&self) -> f64 {
        100.0 * (1.0 - self.end_pose_fitted / self.end_pose_start)
    }

    /// The result of the last stage run with optimizer `name` (`ga`, `lm`), if it ran.
    pub fn solution(&self, name: &str) -> Option<&Solution> {
        self.stages.iter().rev().find(|s| s.name == name).map(|s| &s.solution)
    }
}

/// Fit `start`'s parameters to `train` following `plan`.
pub fn calibrate(
    start: &FittedModel,
    train: &[Run],
    plan: &Plan,
    observer: &mut dyn Observer,
) -> Result<Calibration, Error> {
    let t0 = Instant::now();
    let model = start.model.clone().with_integration(plan.integration);
    let start_fm = FittedModel::new(model.clone(), start.params.clone())?;
    let bounds = search_box_with(&model, &start.params, plan.box_rule, &plan.half_widths)?;
    let problem = CalibrationProblem::new(&model, train, plan.objective, bounds.clone())?;
    let objective_start = problem.cost(&start.params);
    let names: Vec<String> = model.params().into_iter().map(|p| p.name).collect();
    let fit = pipeline::run(&problem, plan, &start.params, objective_start, &names, observer)?;
    let outside_box = names
        .iter()
        .enumerate()
        .filter(|&(i, _)| fit.x[i] < bounds.lower[i] || fit.x[i] > bounds.upper[i])
        .map(|(_, n)| n.clone())
        .collect();
    let fitted = FittedModel::new(model.clone(), fit.x)?;
    let objective_fitted = problem.cost(&fitted.params);
    let identifiability = problem.identifiability(&fitted.params, &plan.identify);
    let end_pose_start = cost::cost(&model, &start.params, train, CostKind::EndPose)?;
    let end_pose_fitted = cost::cost(&model, &fitted.params, train, CostKind::EndPose)?;
    Ok(Calibration {
        fitted,
        start: start_fm,
        objective: plan.objective,
        objective_start,
        objective_fitted,
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
    })
}
