//! Step 1 of a diagnosis: compare the model with the design and the measurements — costs on training and
//! held-out runs, per-run errors, per-command-group bias and scatter, and how the error grows along a run.

use super::kinds::{GroupBasis, MotionKind};
use super::unexplained::{GROUP_ALPHA, group_p_value};
use super::{Costs, GroupReport, Growth, RunReport};
use crate::error::Error;
use crate::science::text;
use omni_kin::cost::{self, CostKind};
use omni_kin::evaluate::Evaluator;
use omni_kin::odometry::Selection;
use omni_kin::{FittedModel, PoseError, Run, RunModels};
use std::collections::BTreeMap;

/// Bins of the error-growth profile.
const BINS: usize = 10;

/// Which way a command turns (|ω| ≤ 1e-9 rad/s counts as straight). Ordered as the kinds of path are
/// listed: straight, turning left, turning right.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Turn {
    /// ω = 0.
    Straight,
    /// ω > 0.
    Left,
    /// ω < 0.
    Right,
}

impl Turn {
    /// The turn of a command with turn rate `omega_rad_s`.
    pub fn of(omega_rad_s: f64) -> Self {
        if omega_rad_s > 1e-9 {
            Turn::Left
        } else if omega_rad_s < -1e-9 {
            Turn::Right
        } else {
            Turn::Straight
        }
    }

    /// The kind of path a run follows, from its command, or without one from the net turn its ground
    /// truth shows (`None` for free driving, which turns both ways, and for a run that does not move).
    pub fn of_run(r: &Run) -> Option<Self> {
        match r.command() {
            Some(c) => Some(Self::of(c.omega_rad_s)),
            None => MotionKind::of(r).filter(MotionKind::groups).map(|k| k.turn),
        }
    }
}

/// The path objective with every `every`-th ground-truth pose, heading weighted 1 m/rad.
pub(super) fn path_kind(every: usize) -> CostKind {
    CostKind::Path { every, heading_weight_m_per_rad: 1.0 }
}

/// Costs of a fitted model on train and held-out runs.
pub fn costs_of(f: &FittedModel, train: &[Run], held_out: &[Run], every: usize) -> Result<Costs, Error> {
    costs_of_each(&RunModels::from(f), train, held_out, every)
}

/// [`costs_of`] with each run under its own model (a robot's sets that declare different designs): the
/// pooled figures are the run-weighted means of the runs' own (Eq. 6; the path cost from the mean MSE).
pub fn costs_of_each(models: &RunModels, train: &[Run], held_out: &[Run], every: usize) -> Result<Costs, Error> {
    let kind = path_kind(every);
    let (train, held_out) = (models.errors(train, kind.selection())?, models.errors(held_out, kind.selection())?);
    Ok(Costs {
        train_path: train.path_cost(kind.heading_weight()),
        held_out_path: held_out.path_cost(kind.heading_weight()),
        train_end_pose: train.end_pose_cost(),
        held_out_end_pose: held_out.end_pose_cost(),
    })
}

/// The per-run comparison of a model with the design.
pub(super) struct Comparison {
    pub runs: Vec<RunReport>,
    pub groups: Vec<GroupReport>,
    pub growth: Growth,
}

/// Per-run errors of `f` and of each run's design on `runs`, grouped by command, and the error growth along
/// the runs.
pub(super) fn compare(f: &FittedModel, design: &RunModels, runs: &[Run], every: usize) -> Result<Comparison, Error> {
    let selection = Selection::Path(every);
    let fitted = Evaluator::for_report(&f.model, runs, selection)?.errors(&f.model.resolve(&f.params)?);
    let designed = design.errors(runs, selection)?;
    let mut reports = Vec::new();
    let mut groups: BTreeMap<(GroupBasis, String), Vec<[f64; 3]>> = BTreeMap::new();
    let mut bins = GrowthBins::default();
    for (i, r) in runs.iter().enumerate() {
        let (path, dpath) = (fitted.run(i), designed.run(i));
        let (end, dend) = (fitted.ends()[i], designed.ends()[i]);
        reports.push(RunReport {
            name: r.name().into(),
            command: r.command().map(|c| c.label()),
            path_rms: cost::path_rms(path),
            design_path_rms: cost::path_rms(dpath),
            end_error: end.norm(),
            design_end_error: dend.norm(),
        });
        if let Some(key) = group_key(r) {
            groups.entry(key).or_default().push([end.dx_m, end.dy_m, end.dtheta_rad]);
        }
        bins.add(r, path, &selection.indices(r.truth().len()));
    }
    let groups = groups.into_iter().map(|((basis, group), v)| group_report(basis, group, &v)).collect();
    Ok(Comparison { runs: reports, groups, growth: bins.growth() })
}

/// How many of `runs` `f` follows worse than `design` (path RMS), of how many.
pub(super) fn worse_than_design(
    f: &FittedModel,
    design: &FittedModel,
    runs: &[Run],
    every: usize,
) -> Result<(usize, usize), Error> {
    let selection = Selection::Path(every);
    let fitted = Evaluator::for_report(&f.model, runs, selection)?.errors(&f.model.resolve(&f.params)?);
    let designed =
        Evaluator::for_report(&design.model, runs, selection)?.errors(&design.model.resolve(&design.params)?);
    let worse = (0..runs.len()).filter(|&i| cost::path_rms(fitted.run(i)) > cost::path_rms(designed.run(i))).count();
    Ok((worse, runs.len()))
}

/// The group of run `r`: its command, or without one the kind of path its ground truth shows (`None` for
/// free driving and runs that do not move: no other run is like them).
fn group_key(r: &Run) -> Option<(GroupBasis, String)> {
    match r.command() {
        Some(c) => {
            let group = (c.alpha_rad.to_degrees().rem_euclid(360.0), Turn::of(c.omega_rad_s));
            Some((GroupBasis::Command, text::command_group(Some(group))))
        }
        None => MotionKind::of(r).filter(MotionKind::groups).map(|k| (GroupBasis::Motion, k.label())),
    }
}

/// Bias and scatter of the end-pose errors `v` (dx m, dy m, dθ rad) of one group, and whether the bias is
/// beyond the scatter between its runs ([`group_p_value`]).
fn group_report(basis: GroupBasis, group: String, v: &[[f64; 3]]) -> GroupReport {
    let n = v.len() as f64;
    let mean = [0, 1, 2].map(|i| v.iter().map(|e| e[i]).sum::<f64>() / n);
    let bias = mean.iter().map(|m| m * m).sum::<f64>().sqrt();
    let scatter = (v.iter().map(|e| (0..3).map(|i| (e[i] - mean[i]).powi(2)).sum::<f64>()).sum::<f64>() / n).sqrt();
    let sd = [0, 1, 2].map(|i| (v.iter().map(|e| (e[i] - mean[i]).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt());
    let p_value = group_p_value(&mean, &sd, v.len());
    GroupReport {
        group,
        basis,
        runs: v.len(),
        mean_end_error: mean,
        bias,
        scatter,
        p_value,
        systematic: p_value.is_some_and(|p| p < GROUP_ALPHA),
    }
}

/// Position and heading errors summed per bin of run time.
#[derive(Default)]
struct GrowthBins {
    position: [f64; BINS],
    heading: [f64; BINS],
    count: [usize; BINS],
}

impl GrowthBins {
    /// Adds run `r`'s errors `path` at its ground-truth poses `truth_indices`.
    fn add(&mut self, r: &Run, path: &[PoseError], truth_indices: &[usize]) {
        let (t0, dur) = (r.start().t_s, r.truth_duration_s().max(1e-9));
        for (e, &ti) in path.iter().zip(truth_indices) {
            let b = (((r.truth()[ti].t_s - t0) / dur) * BINS as f64).floor().clamp(0.0, (BINS - 1) as f64) as usize;
            self.position[b] += e.position_m();
            self.heading[b] += e.dtheta_rad.abs();
            self.count[b] += 1;
        }
    }

    fn growth(&self) -> Growth {
        let mean = |sum: &[f64; BINS], b: usize| if self.count[b] > 0 { sum[b] / self.count[b] as f64 } else { 0.0 };
        Growth {
            fraction: (0..BINS).map(|b| (b as f64 + 0.5) / BINS as f64).collect(),
            position_m: (0..BINS).map(|b| mean(&self.position, b)).collect(),
            heading_rad: (0..BINS).map(|b| mean(&self.heading, b)).collect(),
        }
    }
}
