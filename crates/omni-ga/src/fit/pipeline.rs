//! The fit pipeline: the plan's stages in order over the calibration problem, each from the best point so
//! far, then the truncated update. It knows stages only through [`Stage`]'s interface, so a new optimizer
//! needs no change here.
//!
//! - A stage's result is kept when its cost is no higher than the current point's; the GA box is checked
//!   for parameters left on a bound after each stage that searches within it.
//! - A stage the observer stopped (Ctrl-C, a progress callback) ends the pipeline: the caller wants the best
//!   so far, not the remaining stages.
//! - Truncated update ([`Unexcited::Hold`]): what the runs do not constrain is found at the (unrestricted)
//!   fit, where the residuals measure noise rather than the start's misfit; it is reset to the start, and
//!   the refining stages run again within the constrained subspace.
//! - Scouting (a plan of refining stages only, as diagnose, explore and `train --effect` refine with): the
//!   stages run first with a sixth of their budget ([`Stage::scout`]). Converged within it, that is the fit
//!   (the same iterates). Still going at its end, they are crawling: when the runs leave directions
//!   unconstrained at that point, the truncated update runs from there, instead of after a whole budget
//!   spent along the unconstrained valley (the fit diagnose judged a hardly determined effect with, 2–3×
//!   fewer evaluations on the OptiOdom robots); otherwise the stages run again from the start with their
//!   whole budget, as unscouted.
//! - Refits of a base the runs leave partly unconstrained (a fitted base whose own fit held directions,
//!   with effects added at null): the truncated update at once, with the directions found at the start,
//!   when one of them lies in the base alone. The scout would crawl along them every time.

use crate::error::Error;
use crate::fit::plan::{Plan, Unexcited};
use crate::fit::problem::CalibrationProblem;
use crate::fit::stage::Stage;
use crate::optimizer::problem::{Bounds, LeastSquares, Problem};
use crate::optimizer::subspace::Subspace;
use crate::optimizer::{Observer, Solution, Termination};
use crate::science::identify::{Identifiability, WEAK_LOADING, WeakDirection};
use nalgebra::{DMatrix, DVector};

/// One stage's result within a calibration.
#[derive(Clone, Debug)]
pub struct StageOutcome {
    /// The stage's optimizer (`ga`, `lm`).
    pub name: &'static str,
    /// It ran within the constrained subspace of the truncated update ([`Unexcited::Hold`]); its
    /// parameters are nevertheless the full problem's.
    pub held_subspace: bool,
    /// Its result.
    pub solution: Solution,
}

/// What the pipeline did.
#[derive(Debug)]
pub(crate) struct Fitted {
    /// The parameters it ends at.
    pub x: Vec<f64>,
    /// Cost evaluations of the stages.
    pub evaluations: usize,
    /// Parameters left on a bound of the box by the last stage that searches within it.
    pub at_bound: Vec<String>,
    /// Every stage run, in order.
    pub stages: Vec<StageOutcome>,
    /// Directions held at the start by the truncated update.
    pub held: Vec<WeakDirection>,
    /// The identifiability analysis at `x`, when the truncated update already made it there (it found
    /// nothing to hold): the report takes it instead of building the same normal equations again.
    pub identifiability: Option<Identifiability>,
}

/// Where the pipeline starts.
pub(crate) struct Start<'a> {
    /// The stages' first point.
    pub x: &'a [f64],
    /// Its objective.
    pub objective: f64,
    /// Where the truncated update puts back what the runs do not constrain: `x` itself, or (when `x` was
    /// nudged off a kink, [`crate::fit::refine`]) the model as given.
    pub hold_at: &'a [f64],
    /// How many leading parameters of `x` are already a fit of these runs, the rest added at their null
    /// values (a fitted base with effects added, [`crate::fit::refine`]); 0 for a start that is not a fit.
    pub fitted: usize,
}

impl Fitted {
    /// Nothing run yet, at `x`.
    fn at(x: &[f64]) -> Self {
        Self {
            x: x.to_vec(),
            evaluations: 0,
            at_bound: Vec::new(),
            stages: Vec::new(),
            held: Vec::new(),
            identifiability: None,
        }
    }
}

/// Runs `plan`'s stages on `problem` from `start`; `names` are the parameters' names.
pub(crate) fn run(
    problem: &CalibrationProblem<'_>,
    plan: &Plan,
    start: Start<'_>,
    names: &[String],
    observer: &mut dyn Observer,
) -> Result<Fitted, Error> {
    let mut fit = Fitted::at(start.x);
    if plan.unexcited == Unexcited::Hold && start.fitted > 0 && plan.stages.iter().all(Stage::refines_held) {
        // A refit of a base the runs leave partly unconstrained: the stages would only crawl along the base's
        // own unconstrained directions (on the OptiOdom robots, ten accepted steps of ~0.5 % each, half of
        // every refit), so the truncated update runs at once, with the directions found at the start. Only
        // when one of them lies in the fitted base alone: otherwise a direction that needs the added
        // parameters is judged where they have been fitted (the scout below), since their misfit at null
        // inflates it.
        let id = problem.identifiability(start.x, &plan.identify);
        let in_base = |w: &WeakDirection| w.direction[start.fitted..].iter().all(|v| v.abs() < WEAK_LOADING);
        if id.weak.iter().any(in_base) {
            let mut base_only = id.clone();
            base_only.weak.retain(in_base);
            let needs_added = base_only.weak.len() < id.weak.len();
            hold_and_refine(problem, plan, start.hold_at, id, &mut fit, observer)?;
            if needs_added {
                // A direction that needs the added parameters was judged at their null, where their misfit
                // inflates its standard error (issue 45: a turn_scrub that circles in training determine to
                // ±0.3 % of its scale was ±5.8 % at null, just over the limit, and held at 0). Released
                // from there with the base's own directions still held, it is kept when the runs then
                // determine every added direction, the added parameters stay within their physical range
                // (their search box: on squares turn_scrub wanders to k = −5 s/m, where it cancels every
                // turn while driving at 0.2 m/s, a "determined" value of no physics) and the cost falls.
                let mut released = Fitted { evaluations: 0, ..Fitted::at(&fit.x) };
                hold_and_refine(problem, plan, start.hold_at, base_only, &mut released, observer)?;
                fit.evaluations += released.evaluations;
                let at = problem.identifiability(&released.x, &plan.identify);
                let specs = problem.model().params();
                let physical = (start.fitted..released.x.len())
                    .all(|i| specs.get(i).is_none_or(|p| (p.lower..=p.upper).contains(&released.x[i])));
                if physical && at.weak.iter().all(in_base) && problem.cost(&released.x) < problem.cost(&fit.x) {
                    fit.stages.append(&mut released.stages);
                    (fit.x, fit.held) = (released.x, released.held);
                }
            }
            return Ok(fit);
        }
    }
    if plan.unexcited == Unexcited::Hold
        && let (n, m) = (start.x.len(), problem.residual_count(start.x))
        && let Some(scout) = plan.stages.iter().map(|s| s.scout(n, m)).collect::<Option<Vec<_>>>()
    {
        let stopped = run_stages(problem, &scout, start.objective, names, &mut fit, observer)?;
        let crawling = fit.stages.last().is_some_and(|s| s.solution.termination == Termination::MaxEvaluations);
        if stopped || !crawling {
            // Converged within the scout's budget: the very iterates the full budget would have taken.
            if !stopped {
                hold(problem, plan, start.hold_at, &mut fit, observer)?;
            }
            return Ok(fit);
        }
        let id = problem.identifiability(&fit.x, &plan.identify);
        if !id.weak.is_empty() {
            // The crawl is abandoned as the truncated update abandons a free fit: the held fit is the fit.
            fit.stages.clear();
            hold_and_refine(problem, plan, start.hold_at, id, &mut fit, observer)?;
            return Ok(fit);
        }
        // Still moving in directions the runs constrain: the stages with their whole budget, from the start
        // (so the fit is the one they give unscouted; the scout's evaluations are the price of the check).
        fit = Fitted { evaluations: fit.evaluations, ..Fitted::at(start.x) };
    }
    let stopped = run_stages(problem, &plan.stages, start.objective, names, &mut fit, observer)?;
    if plan.unexcited == Unexcited::Hold && !stopped {
        hold(problem, plan, start.hold_at, &mut fit, observer)?;
    }
    Ok(fit)
}

/// The stages on the whole problem. Returns whether the observer stopped one.
fn run_stages(
    problem: &CalibrationProblem<'_>,
    stages: &[Stage],
    objective_start: f64,
    names: &[String],
    fit: &mut Fitted,
    observer: &mut dyn Observer,
) -> Result<bool, Error> {
    let mut moved = false;
    for stage in stages {
        let s = stage.minimize(problem, &fit.x, observer)?;
        fit.evaluations += s.evaluations;
        let current = if moved { problem.cost(&fit.x) } else { objective_start };
        if s.cost <= current {
            fit.x = s.params.clone();
            moved = true;
        }
        if stage.within_box() {
            fit.at_bound = at_bound(names, problem.bounds(), &fit.x);
        }
        let stopped = s.termination == Termination::Stopped;
        fit.stages.push(StageOutcome { name: stage.name(), held_subspace: false, solution: s });
        if stopped {
            return Ok(true);
        }
    }
    Ok(false)
}

/// The truncated update: unconstrained directions back to `start`, then the refining stages within the
/// constrained subspace.
fn hold(
    problem: &CalibrationProblem<'_>,
    plan: &Plan,
    start: &[f64],
    fit: &mut Fitted,
    observer: &mut dyn Observer,
) -> Result<(), Error> {
    let id = problem.identifiability(&fit.x, &plan.identify);
    if id.weak.is_empty() {
        fit.identifiability = Some(id);
        return Ok(());
    }
    hold_and_refine(problem, plan, start, id, fit, observer)
}

/// The truncated update with `id`'s unconstrained directions: reset to `start` along them, then the refining
/// stages within the constrained subspace.
fn hold_and_refine(
    problem: &CalibrationProblem<'_>,
    plan: &Plan,
    start: &[f64],
    id: Identifiability,
    fit: &mut Fitted,
    observer: &mut dyn Observer,
) -> Result<(), Error> {
    let (projected, basis) = hold_unexcited(&fit.x, start, &id.scales(), &id.weak_basis());
    fit.x = projected;
    fit.held = id.weak;
    for stage in plan.stages.iter().filter(|s| s.refines_held()) {
        let sub = Subspace::new(problem, fit.x.clone(), basis.clone());
        let s = stage.minimize(&sub, &vec![0.0; sub.dim()], observer)?;
        fit.evaluations += s.evaluations;
        let xs = sub.point(&s.params);
        if s.cost <= problem.cost(&fit.x) {
            fit.x = xs.clone();
        }
        fit.stages.push(StageOutcome {
            name: stage.name(),
            held_subspace: true,
            solution: Solution { params: xs, ..s },
        });
    }
    Ok(())
}

/// The names of the parameters of `x` on a bound of `bounds` (to a relative 1e-9 of the interval; fixed
/// parameters excepted).
fn at_bound(names: &[String], bounds: &Bounds, x: &[f64]) -> Vec<String> {
    names
        .iter()
        .enumerate()
        .filter(|&(i, _)| {
            let (lo, hi) = (bounds.lower[i], bounds.upper[i]);
            let tol = 1e-9 * (hi - lo).abs().max(1e-12);
            hi > lo && (x[i] - lo <= tol || hi - x[i] <= tol)
        })
        .map(|(_, n)| n.clone())
        .collect()
}

/// The truncated update: `x` with its component along the unconstrained directions `weak` (scaled space,
/// orthonormal columns) reset to `start`'s, and a basis (parameter units) of the constrained subspace.
fn hold_unexcited(x: &[f64], start: &[f64], scales: &[f64], weak: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let n = x.len();
    let d = DVector::from_fn(n, |i, _| (x[i] - start[i]) / scales[i]);
    let kept = &d - weak * (weak.transpose() * &d);
    let projected = (0..n).map(|i| start[i] + scales[i] * kept[i]).collect();
    // Orthonormal complement of `weak`: eigenvectors of I − W Wᵀ with eigenvalue 1.
    let p = DMatrix::identity(n, n) - weak * weak.transpose();
    let eig = p.symmetric_eigen();
    let cols: Vec<usize> = (0..n).filter(|&i| eig.eigenvalues[i] > 0.5).collect();
    let basis = DMatrix::from_fn(n, cols.len(), |r, c| eig.eigenvectors[(r, cols[c])] * scales[r]);
    (projected, basis)
}
