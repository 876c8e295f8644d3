//! Step 3 of a diagnosis: rank the candidate effects by held-out gain and, with `auto`, climb the error
//! ladder (add the best one, refit, rank again); then check the winner on kinds of path left out of its fit.

use super::compare::{Turn, costs_of, path_kind};
use super::evidence::{Bench, candidate_effect, refit_on};
use super::kinds::MotionKind;
use super::{Candidate, Costs, DiagnoseOptions, KindOut, Rung, RungKind};
use crate::error::Error;
use crate::fit::BaseFit;
use crate::science::{heaviest_first, text};
use omni_kin::cost;
use omni_kin::effect::Effect;
use omni_kin::{EffectKind, FittedModel, Run};
use rayon::prelude::*;

/// An effect helps enough to be added: separable and the held-out path cost falls by `min_gain`.
pub(super) fn passes(c: &Candidate, opts: &DiagnoseOptions) -> bool {
    !c.absorbed && c.not_excited.is_none() && c.held_out_gain >= opts.min_gain
}

/// A candidate the next rung of the ladder assesses again: separable, excited, and its refit lowered the
/// held-out path cost at all. One below `min_gain` stays (another effect can mask it: a clock lag beside an
/// unequal wheel gains little until the wheel is modelled).
fn worth_retrying(c: &Candidate) -> bool {
    !c.absorbed && c.not_excited.is_none() && c.held_out_gain > 0.0
}

/// An effect is named with confidence when it also removes at least `min_excess_closed` of the held-out
/// error variance above the noise floor (always, when no floor could be estimated).
pub(super) fn confident(c: &Candidate, opts: &DiagnoseOptions) -> bool {
    c.excess_closed.is_nan() || c.excess_closed >= opts.min_excess_closed
}

/// What the search found.
pub(super) struct Climb {
    /// The candidates for the model as given, best held-out gain first.
    pub ranking: Vec<Candidate>,
    /// Design, model, then each effect added by `auto`.
    pub ladder: Vec<Rung>,
    /// The model at the top of the ladder.
    pub top: FittedModel,
}

/// A rung of the ladder.
pub(super) fn rung(kind: RungKind, costs: &Costs) -> Rung {
    Rung { label: text::rung(&kind), costs: costs.clone() }
}

/// Ranks the candidates for `model` (costs `costs`); with `opts.auto`, adds the best passing one and
/// ranks again, up to `opts.max_added` effects. A later rung assesses only the candidates that helped at
/// the rung before ([`worth_retrying`]); one that made the simpler model's held-out error worse, or that
/// the runs cannot tell, is not refitted again (each rung's refits cost as much as the first ranking's).
pub(super) fn climb(
    bench: &Bench<'_>,
    model: &FittedModel,
    costs: &Costs,
    design_costs: &Costs,
    opts: &DiagnoseOptions,
) -> Result<Climb, Error> {
    let mut ladder = vec![rung(RungKind::Design, design_costs), rung(RungKind::Model, costs)];
    let mut current = model.clone();
    let mut current_costs = costs.clone();
    let mut first_ranking: Option<Vec<Candidate>> = None;
    let mut added = 0;
    let mut eligible: Option<Vec<String>> = None;
    loop {
        let ranking = rank(bench, &current, &current_costs, opts, eligible.as_deref())?;
        // The best passing candidate, unless it hurts a kind of held-out path (then none is added).
        let best = match ranking.first().filter(|c| passes(c, opts)) {
            Some(c) if held_out_kinds(&current, c, bench.held_runs, bench.every)?.is_some_and(|k| hurts_a_kind(&k)) => {
                None
            }
            best => best.cloned(),
        };
        eligible = Some(ranking.iter().filter(|c| worth_retrying(c)).map(|c| c.effect.clone()).collect());
        if first_ranking.is_none() {
            first_ranking = Some(ranking);
        }
        match best {
            Some(b) if opts.auto && added < opts.max_added => {
                // The candidate's own refit is the next rung: `assess` fitted `current + effect` on the same
                // runs from the same start and judged it with `costs_of`, so it is taken as is (the same
                // bits; refitting it again cost as much as the whole first ranking's slowest candidate).
                (current, current_costs) = match (b.fitted, b.refit) {
                    (Some(fitted), Some(costs)) => (fitted, costs),
                    _ => {
                        let effect = candidate_effect(&b.effect, current.model.n_wheels(), opts)?;
                        let next =
                            refit_on(&current, Some(&effect), bench.fit_runs, bench.every, bench.base_fit)?.fitted;
                        let costs = costs_of(&next, bench.fit_runs, bench.held_runs, bench.every)?;
                        (next, costs)
                    }
                };
                ladder.push(rung(RungKind::Added(b.effect), &current_costs));
                added += 1;
            }
            _ => break,
        }
        if !opts.auto {
            break;
        }
    }
    Ok(Climb { ranking: first_ranking.unwrap_or_default(), ladder, top: current })
}

/// Every candidate not yet in `current` (and, given `eligible`, among those), assessed, best held-out gain
/// first.
fn rank(
    bench: &Bench<'_>,
    current: &FittedModel,
    current_costs: &Costs,
    opts: &DiagnoseOptions,
    eligible: Option<&[String]>,
) -> Result<Vec<Candidate>, Error> {
    let present: Vec<String> = current.model.effects.iter().map(|e| e.id().replace("_yaw", "")).collect();
    let ids = opts.candidates.iter().cloned().chain(opts.custom.iter().map(|e| e.id().to_string()));
    let ids: Vec<String> = ids
        .filter(|id| !present.iter().any(|p| p == id))
        .filter(|id| eligible.is_none_or(|e| e.contains(id)))
        .collect();
    // The candidates are independent: assessed in parallel (those with the most parameters, the costliest
    // refits, first), collected in catalogue order (the first error in that order is the one returned), so
    // the ranking does not depend on the thread count.
    let effects: Vec<(&String, Result<EffectKind, omni_kin::KinError>)> =
        ids.iter().map(|id| (id, candidate_effect(id, current.model.n_wheels(), opts))).collect();
    let weight = |(_, e): &(&String, Result<EffectKind, _>)| e.as_ref().map_or(0, |e| e.params().len());
    let assessed = heaviest_first::map(&effects, weight, |(id, effect)| {
        let effect = effect.as_ref().map_err(|e| Error::from(e.clone()))?;
        bench.assess(id, effect, current, current_costs)
    });
    let mut ranking = assessed.into_iter().collect::<Result<Vec<_>, _>>()?;
    ranking.sort_by(|a, b| b.held_out_gain.total_cmp(&a.held_out_gain));
    Ok(ranking)
}

/// The largest rise of the path RMS on one kind of path that an effect may cause and still pass: issue 45's
/// "no motion kind gets worse by more than 2 %".
pub const TRANSFER_TOLERANCE: f64 = 0.02;

/// Whether a kinds check finds the effect hurting: the kinds' pooled path cost rises, or one kind's path
/// RMS rises by more than [`TRANSFER_TOLERANCE`]. The one test of transfer for `diagnose`, its verdict and
/// `--auto`.
pub fn hurts_a_kind(k: &KindOut) -> bool {
    k.gain < 0.0 || k.folds.iter().any(|(_, before, after)| *after > before * (1.0 + TRANSFER_TOLERANCE))
}

/// `candidate`'s refit against `model` on the held-out runs, by the shape of their paths (straight, turning
/// on the spot, sides then turns, arcs, free driving; from each run's ground truth): the per-kind path RMS
/// before and after, and the pooled gain. No refit: the candidate's own, judged on motions that may differ
/// from the ones it was fitted on. `None` without a refit or when no held-out run has a kind.
pub(super) fn held_out_kinds(
    model: &FittedModel,
    candidate: &Candidate,
    held: &[Run],
    every: usize,
) -> Result<Option<KindOut>, Error> {
    let Some(fitted) = candidate.fitted.as_ref() else { return Ok(None) };
    by_kind_of_path(&candidate.effect, (model, fitted), held, every)
}

/// `after` (a fit with `effect`) against `before` on the `held` runs by the shape of their paths: the
/// per-kind path RMS (every `every`-th pose) before and after, and the pooled gain; `None` when no run has a
/// kind. What [`hurts_a_kind`] judges, for diagnose's candidates and the explorer's families alike.
pub(crate) fn by_kind_of_path(
    effect: &str,
    (before, after): (&FittedModel, &FittedModel),
    held: &[Run],
    every: usize,
) -> Result<Option<KindOut>, Error> {
    let (model, fitted) = (before, after);
    let mut kinds: Vec<(&'static str, Vec<Run>)> = Vec::new();
    for r in held {
        let Some(k) = MotionKind::of(r) else { continue };
        match kinds.iter_mut().find(|(label, _)| *label == k.shape_label()) {
            Some((_, runs)) => runs.push(r.clone()),
            None => kinds.push((k.shape_label(), vec![r.clone()])),
        }
    }
    if kinds.is_empty() {
        return Ok(None);
    }
    kinds.sort_by_key(|(label, _)| *label);
    let mut folds = Vec::with_capacity(kinds.len());
    for (label, runs) in &kinds {
        let b = cost::cost(&model.model, &model.params, runs, path_kind(every))?;
        let a = cost::cost(&fitted.model, &fitted.params, runs, path_kind(every))?;
        folds.push((format!("{label} ({})", runs.len()), b, a));
    }
    let before: f64 = folds.iter().map(|f| f.1 * f.1).sum();
    let after: f64 = folds.iter().map(|f| f.2 * f.2).sum();
    Ok(Some(KindOut { effect: effect.to_string(), folds, gain: 1.0 - (after / before.max(1e-300)).sqrt() }))
}

/// Fit `model + effect` on all kinds of path but one and compare path costs on the kind left out (`None`
/// when the runs have fewer than two kinds, or a run has no command).
pub(super) fn kind_out(
    model: &FittedModel,
    effect: &EffectKind,
    runs: &[Run],
    every: usize,
) -> Result<Option<KindOut>, Error> {
    let mut kinds: Vec<Turn> = runs.iter().filter_map(Turn::of_run).collect();
    kinds.sort();
    kinds.dedup();
    if kinds.len() < 2 || runs.iter().any(|r| Turn::of_run(r).is_none()) {
        return Ok(None);
    }
    // The model was fitted on every kind: on a fold's runs it is a fit of other runs.
    const OTHER: BaseFit = BaseFit::OtherRuns;
    // The folds (and each fold's two refits) are independent: fitted in parallel, collected in kind order
    // and summed in that order (the same bits whatever the thread count; the first error in that order).
    let folds = kinds
        .par_iter()
        .map(|&kind| {
            let (test, fit): (Vec<Run>, Vec<Run>) = runs.iter().cloned().partition(|r| Turn::of_run(r) == Some(kind));
            let (base, with) = rayon::join(
                || refit_on(model, None, &fit, every, OTHER),
                || refit_on(model, Some(effect), &fit, every, OTHER),
            );
            let (base, with) = (base?.fitted, with?.fitted);
            let b = cost::cost(&base.model, &base.params, &test, path_kind(every))?;
            let a = cost::cost(&with.model, &with.params, &test, path_kind(every))?;
            Ok((text::path_kind(kind).to_string(), b, a))
        })
        .collect::<Vec<Result<_, Error>>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    let before: f64 = folds.iter().map(|f| f.1 * f.1).sum();
    let after: f64 = folds.iter().map(|f| f.2 * f.2).sum();
    Ok(Some(KindOut { effect: effect.id().to_string(), folds, gain: 1.0 - (after / before.max(1e-300)).sqrt() }))
}
