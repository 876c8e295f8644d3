//! Diagnosis: compare a model with the measurements, find where it fails, and test which catalogued
//! physical effect is missing — then prove it on held-out runs.
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
//!    and end of runs). A held-out error well above it (3×) means something physical is still missing.
//!
//! Evidence comes from the path (every ground-truth pose), since the end pose alone cannot see some
//! effects (a clock offset when the robot rests at both ends); the paper's Eq. 6 is reported beside it.
//! Parameter uncertainties are `sqrt(diag(s² (JᵀJ)⁻¹))`; residuals along a path are correlated, so they are
//! optimistic.

use crate::calibrate::CalibrateError;
use crate::calibrate::CalibrationProblem;
use crate::identify::{Identifiability, IdentifyOptions};
use crate::lm::{LevenbergMarquardt, LmConfig};
use crate::observe::NoopObserver;
use crate::optimizer::Optimizer;
use crate::problem::{Bounds, LeastSquares, Problem};
use nalgebra::{DMatrix, DVector};
use omni_kin::cost::{self, CostKind};
use omni_kin::effect::{Effect, Stage};
use omni_kin::evaluate::Evaluator;
use omni_kin::odometry::Selection;
use omni_kin::{EffectKind, FittedModel, Run};
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

/// Errors of a group of runs sharing a command direction and turn sign.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GroupReport {
    /// `α=30° ω>0` style label.
    pub group: String,
    /// Runs in it.
    pub runs: usize,
    /// Mean end-pose error vector (dx m, dy m, dθ rad) in the world frame.
    pub mean_end_error: [f64; 3],
    /// Its norm: the systematic part.
    pub bias: f64,
    /// Scatter between runs (RMS deviation from the mean): the random part.
    pub scatter: f64,
    /// `bias > 2 · scatter / sqrt(runs)`.
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
    /// Share of the training residual the effect could explain to first order (0…1).
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
    /// Why the training runs cannot tell this effect (not ranked), when they cannot.
    #[serde(default)]
    pub not_excited: Option<String>,
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
#[derive(Clone, Debug, Serialize, Deserialize)]
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
    /// Stationary poses used.
    pub samples: usize,
}

/// The whole diagnosis.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Effect to add (None: nothing helps beyond `min_gain`).
    pub verdict: Option<String>,
    /// The verdict in words.
    pub verdict_text: String,
    /// How held-out costs were obtained: `validation set` or `2-fold cross-validation over repetitions`.
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
    /// Where it fails, in words.
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
    /// The final model (the input, plus effects added by `auto`).
    #[serde(skip)]
    pub final_model: Option<FittedModel>,
}

fn path_kind(every: usize) -> CostKind {
    CostKind::Path { every, heading_weight_m_per_rad: 1.0 }
}

/// An effect helps enough to be added: separable and the held-out path cost falls by `min_gain`.
fn passes(c: &Candidate, opts: &DiagnoseOptions) -> bool {
    !c.absorbed && c.not_excited.is_none() && c.held_out_gain >= opts.min_gain
}

/// An effect is named with confidence when it also removes at least `min_excess_closed` of the held-out
/// error variance above the noise floor (always, when no floor could be estimated).
fn confident(c: &Candidate, opts: &DiagnoseOptions) -> bool {
    c.excess_closed.is_nan() || c.excess_closed >= opts.min_excess_closed
}

/// Costs of a fitted model on train and held-out runs.
pub fn costs_of(f: &FittedModel, train: &[Run], held_out: &[Run], every: usize) -> Result<Costs, CalibrateError> {
    let kind = path_kind(every);
    let (train, held_out) = (
        Evaluator::for_report(&f.model, train, kind.selection())?,
        Evaluator::for_report(&f.model, held_out, kind.selection())?,
    );
    let res = f.model.resolve(&f.params)?;
    let (train, held_out) = (train.errors(&res), held_out.errors(&res));
    Ok(Costs {
        train_path: train.path_cost(kind.heading_weight()),
        held_out_path: held_out.path_cost(kind.heading_weight()),
        train_end_pose: train.end_pose_cost(),
        held_out_end_pose: held_out.end_pose_cost(),
    })
}

/// The path-residual problem of `model` over `runs`, with no bounds (the diagnosis explores freely).
fn unbounded<'a>(
    model: &'a omni_kin::Model,
    runs: &'a [Run],
    every: usize,
) -> Result<CalibrationProblem<'a>, CalibrateError> {
    let n = model.n_params();
    let bounds = Bounds::new(vec![f64::NEG_INFINITY; n], vec![f64::INFINITY; n])?;
    CalibrationProblem::new(model, runs, path_kind(every), bounds)
}

/// `model`'s parameters, with effect parameters whose value is the lower end of their range (backlash
/// b ≥ 0 at its null value) moved 2 % inside it, where the model is differentiable.
pub fn differentiable_start(model: &FittedModel) -> Vec<f64> {
    let mut x = model.params.clone();
    for (i, s) in model.model.params().iter().enumerate() {
        if i >= model.model.n_base() && x[i] == s.lower && s.upper > s.lower {
            x[i] = s.lower + 0.02 * (s.upper - s.lower);
        }
    }
    x
}

/// Refit all parameters of `start` on `train` by Levenberg–Marquardt on the path residuals.
pub fn refit(start: &FittedModel, train: &[Run], every: usize) -> Result<FittedModel, CalibrateError> {
    let x0 = differentiable_start(start);
    let problem = unbounded(&start.model, train, every)?;
    let mut lm = LevenbergMarquardt { config: LmConfig::default() };
    let s = lm.minimize(&problem, &x0, &mut NoopObserver)?;
    // LM never returns worse than its start; also never worse than the given parameters.
    let params = if problem.cost(&s.params) <= problem.cost(&start.params) { s.params } else { start.params.clone() };
    Ok(FittedModel::new(start.model.clone(), params)?)
}

/// Projection residual: ‖(I − Q Qᵀ) v‖ for an orthonormal basis Q.
fn orth_residual(q: &DMatrix<f64>, v: &DVector<f64>) -> DVector<f64> {
    if q.ncols() == 0 {
        return v.clone();
    }
    v - q * (q.transpose() * v)
}

/// Orthonormal basis of the column space (SVD, relative tolerance 1e-9).
fn basis(m: &DMatrix<f64>) -> DMatrix<f64> {
    if m.ncols() == 0 {
        return DMatrix::zeros(m.nrows(), 0);
    }
    if !m.iter().all(|v| v.is_finite()) {
        return DMatrix::zeros(m.nrows(), 0);
    }
    let svd = m.clone().svd(true, false);
    let Some(u) = svd.u else { return DMatrix::zeros(m.nrows(), 0) };
    let smax = svd.singular_values.iter().fold(0.0f64, |a, &b| a.max(b));
    let keep: Vec<usize> = (0..svd.singular_values.len()).filter(|&i| svd.singular_values[i] > 1e-9 * smax).collect();
    DMatrix::from_fn(m.nrows(), keep.len(), |r, c| u[(r, keep[c])])
}

/// Standard errors `sqrt(diag(s² (JᵀJ)⁻¹))` with `s² = ‖r‖² / (m − p)`.
pub fn standard_errors(j: &DMatrix<f64>, r: &[f64]) -> Option<Vec<f64>> {
    let (m, p) = (j.nrows(), j.ncols());
    if m <= p {
        return None;
    }
    let s2 = r.iter().map(|v| v * v).sum::<f64>() / (m - p) as f64;
    let jtj = j.transpose() * j;
    let inv = jtj.try_inverse()?;
    Some((0..p).map(|i| (s2 * inv[(i, i)]).max(0.0).sqrt()).collect())
}

/// Whether the runs can tell a wheel-stage effect: every wheel must turn both ways (≥ 5 % of its moving
/// samples each way) and at several distinct speeds (90th/10th percentile of |speed| ≥ 1.5). `None` when
/// they can, else the reason.
pub fn wheel_excitation_gap(runs: &[Run], wheel_names: &[String]) -> Option<String> {
    const MOVING_RAD_S: f64 = 0.05;
    let mut gaps = Vec::new();
    for (w, name) in wheel_names.iter().enumerate() {
        let mut speeds: Vec<f64> = Vec::new();
        let (mut pos, mut neg) = (0usize, 0usize);
        for r in runs {
            for k in 0..r.n_samples() {
                let v = r.wheel_sample(k).get(w).copied().unwrap_or(0.0);
                if v > MOVING_RAD_S {
                    pos += 1;
                } else if v < -MOVING_RAD_S {
                    neg += 1;
                } else {
                    continue;
                }
                speeds.push(v.abs());
            }
        }
        let moving = (pos + neg).max(1) as f64;
        if (pos as f64) < 0.05 * moving || (neg as f64) < 0.05 * moving {
            gaps.push(format!("{name} turns one way only ({:.0} % forward)", 100.0 * pos as f64 / moving));
            continue;
        }
        speeds.sort_by(f64::total_cmp);
        let q = |f: f64| speeds[((speeds.len() - 1) as f64 * f) as usize];
        if q(0.9) < 1.5 * q(0.1) {
            gaps.push(format!("{name} runs at one speed only (|ω| {:.2}–{:.2} rad/s)", q(0.1), q(0.9)));
        }
    }
    (!gaps.is_empty()).then(|| gaps.join("; "))
}

/// The kind of path a run follows, from its command: `straight`, `turning left`, `turning right`.
fn path_kind_of(r: &Run) -> Option<&'static str> {
    r.command().map(|c| {
        if c.omega_rad_s > 1e-9 {
            "turning left"
        } else if c.omega_rad_s < -1e-9 {
            "turning right"
        } else {
            "straight"
        }
    })
}

/// Repeat scatter of the end-pose error (see [`Diagnosis::repeatability_floor`]).
fn repeatability_floor(groups: &[GroupReport]) -> Option<f64> {
    let (mut sum, mut count) = (0.0, 0usize);
    for g in groups.iter().filter(|g| g.runs >= 2) {
        let n = g.runs as f64;
        sum += g.scatter * g.scatter * n / (n - 1.0);
        count += 1;
    }
    (count > 0).then(|| (sum / count as f64).sqrt())
}

/// Fit `model + effect` on all kinds but one and compare path costs on the kind left out.
fn kind_out(
    model: &FittedModel,
    effect: &EffectKind,
    runs: &[Run],
    every: usize,
) -> Result<Option<KindOut>, CalibrateError> {
    let mut kinds: Vec<&'static str> = runs.iter().filter_map(path_kind_of).collect();
    kinds.sort();
    kinds.dedup();
    if kinds.len() < 2 || runs.iter().any(|r| path_kind_of(r).is_none()) {
        return Ok(None);
    }
    let (mut before, mut after) = (0.0, 0.0);
    let mut folds = Vec::new();
    for kind in kinds {
        let (test, fit): (Vec<Run>, Vec<Run>) = runs.iter().cloned().partition(|r| path_kind_of(r) == Some(kind));
        let base = refit(model, &fit, every)?;
        let with = refit(&model.with_effect(effect.clone()), &fit, every)?;
        let b = cost::cost(&base.model, &base.params, &test, path_kind(every))?;
        let a = cost::cost(&with.model, &with.params, &test, path_kind(every))?;
        before += b * b;
        after += a * a;
        folds.push((kind.to_string(), b, a));
    }
    Ok(Some(KindOut { effect: effect.id().to_string(), folds, gain: 1.0 - (after / before.max(1e-300)).sqrt() }))
}

fn split_held_out(train: &[Run]) -> (Vec<Run>, Vec<Run>) {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for (i, r) in train.iter().enumerate() {
        let key = r.repetition().map(|x| x as usize).unwrap_or(i);
        if key % 2 == 0 { a.push(r.clone()) } else { b.push(r.clone()) }
    }
    (a, b)
}

/// Estimate the ground-truth noise from poses while every wheel is still.
pub fn noise_floor(runs: &[Run]) -> Option<NoiseFloor> {
    const STILL_RAD_S: f64 = 0.02;
    let (mut sp, mut sth, mut dof) = (0.0, 0.0, 0usize);
    let mut used = 0;
    for r in runs {
        let t = r.wheel_t_s();
        let moving: Vec<usize> =
            (0..r.n_samples()).filter(|&k| r.wheel_sample(k).iter().any(|w| w.abs() > STILL_RAD_S)).collect();
        let (Some(&first), Some(&last)) = (moving.first(), moving.last()) else { continue };
        let (t_start, t_end) = (t[first] - 0.05, t[last] + 0.05);
        for window in [
            r.truth().iter().filter(|p| p.t_s < t_start).collect::<Vec<_>>(),
            r.truth().iter().filter(|p| p.t_s > t_end).collect(),
        ] {
            if window.len() < 2 {
                continue;
            }
            let n = window.len() as f64;
            let mx = window.iter().map(|p| p.pose.x_m).sum::<f64>() / n;
            let my = window.iter().map(|p| p.pose.y_m).sum::<f64>() / n;
            let mt = window.iter().map(|p| p.pose.theta_rad).sum::<f64>() / n;
            for p in &window {
                sp += (p.pose.x_m - mx).powi(2) + (p.pose.y_m - my).powi(2);
                sth += (p.pose.theta_rad - mt).powi(2);
            }
            dof += window.len() - 1;
            used += window.len();
        }
    }
    if dof == 0 {
        return None;
    }
    let position_m = (sp / (2.0 * dof as f64)).sqrt();
    let heading_rad = (sth / dof as f64).sqrt();
    let one = 2.0 * position_m * position_m + heading_rad * heading_rad;
    Some(NoiseFloor { position_m, heading_rad, path_rms: (2.0 * one).sqrt(), samples: used })
}

fn group_label(r: &Run) -> String {
    match r.command() {
        Some(c) => {
            let turn = if c.omega_rad_s > 1e-9 {
                "ω>0"
            } else if c.omega_rad_s < -1e-9 {
                "ω<0"
            } else {
                "ω=0"
            };
            format!("α={:.0}° {turn}", c.alpha_rad.to_degrees().rem_euclid(360.0))
        }
        None => "all".into(),
    }
}

fn compare(
    f: &FittedModel,
    design: &FittedModel,
    runs: &[Run],
    every: usize,
) -> Result<(Vec<RunReport>, Vec<GroupReport>, Growth), CalibrateError> {
    let selection = Selection::Path(every);
    let fitted = Evaluator::for_report(&f.model, runs, selection)?.errors(&f.model.resolve(&f.params)?);
    let designed =
        Evaluator::for_report(&design.model, runs, selection)?.errors(&design.model.resolve(&design.params)?);
    let mut reports = Vec::new();
    let mut groups: std::collections::BTreeMap<String, Vec<[f64; 3]>> = Default::default();
    const BINS: usize = 10;
    let (mut gp, mut gh, mut gn) = (vec![0.0; BINS], vec![0.0; BINS], vec![0usize; BINS]);
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
        groups.entry(group_label(r)).or_default().push([end.dx_m, end.dy_m, end.dtheta_rad]);
        let (t0, dur) = (r.start().t_s, r.truth_duration_s().max(1e-9));
        for (e, ti) in path.iter().zip(selection.indices(r.truth().len())) {
            let b = (((r.truth()[ti].t_s - t0) / dur) * BINS as f64).floor().clamp(0.0, (BINS - 1) as f64) as usize;
            gp[b] += e.position_m();
            gh[b] += e.dtheta_rad.abs();
            gn[b] += 1;
        }
    }
    let group_reports = groups
        .into_iter()
        .map(|(group, v)| {
            let n = v.len() as f64;
            let mean = [0, 1, 2].map(|i| v.iter().map(|e| e[i]).sum::<f64>() / n);
            let bias = mean.iter().map(|m| m * m).sum::<f64>().sqrt();
            let scatter =
                (v.iter().map(|e| (0..3).map(|i| (e[i] - mean[i]).powi(2)).sum::<f64>()).sum::<f64>() / n).sqrt();
            GroupReport {
                group,
                runs: v.len(),
                mean_end_error: mean,
                bias,
                scatter,
                systematic: bias > 2.0 * scatter / n.sqrt(),
            }
        })
        .collect();
    let growth = Growth {
        fraction: (0..BINS).map(|b| (b as f64 + 0.5) / BINS as f64).collect(),
        position_m: (0..BINS).map(|b| if gn[b] > 0 { gp[b] / gn[b] as f64 } else { 0.0 }).collect(),
        heading_rad: (0..BINS).map(|b| if gn[b] > 0 { gh[b] / gn[b] as f64 } else { 0.0 }).collect(),
    };
    Ok((reports, group_reports, growth))
}

/// First-order evidence of one effect at the current fit.
fn first_order(
    current: &FittedModel,
    design: &FittedModel,
    effect: &EffectKind,
    train: &[Run],
    every: usize,
) -> Result<(f64, f64, Vec<ParamValue>), CalibrateError> {
    let ext = current.with_effect(effect.clone());
    let n = ext.params.len();
    let nm = current.params.len();
    let problem = unbounded(&ext.model, train, every)?;
    let r = DVector::from_vec(problem.residuals(&ext.params));
    let j = problem.jacobian(&ext.params);
    let jm = j.columns(0, nm).into_owned();
    let je = j.columns(nm, n - nm).into_owned();
    let qm = basis(&jm);
    let rm = orth_residual(&qm, &r);
    let q_all = basis(&j);
    let r_all = orth_residual(&q_all, &r);
    let rr = r.norm_squared().max(1e-300);
    let explained = ((rm.norm_squared() - r_all.norm_squared()) / rr).clamp(0.0, 1.0);
    // Columns with no sensitivity at all (the runs do not excite the effect) say nothing about
    // separability; if every column is such, the effect is unexcited, not absorbed (NaN).
    let mut separability = f64::INFINITY;
    for c in 0..je.ncols() {
        let col = je.column(c).into_owned();
        let norm = col.norm();
        if norm > 1e-12 * j.norm().max(1e-300) {
            separability = separability.min(orth_residual(&qm, &col).norm() / norm);
        }
    }
    if !separability.is_finite() {
        separability = f64::NAN;
    }
    // Implied effect values: min ‖J_e e − J_m Δx‖, Δx = fit − design (same base structure only).
    let mut implied = Vec::new();
    if design.params.len() == current.model.n_base() || design.model.n_base() == current.model.n_base() {
        let nb = current.model.n_base();
        let dx = DVector::from_fn(nm, |i, _| if i < nb { current.params[i] - design.params[i] } else { 0.0 });
        let target = &jm * dx;
        let finite = je.iter().chain(target.iter()).all(|v| v.is_finite());
        if let Some(Ok(sol)) = finite.then(|| je.clone().svd(true, true).solve(&target, 1e-12)) {
            for (s, v) in effect.params().iter().zip(sol.iter()) {
                implied.push(ParamValue { name: s.name.clone(), value: *v, unit: s.unit.clone(), std_error: None });
            }
        }
    }
    Ok((explained, separability, implied))
}

/// A candidate by id: a user effect from `opts.custom`, else the built-in catalogue's.
fn candidate_effect(id: &str, n_wheels: usize, opts: &DiagnoseOptions) -> Result<EffectKind, omni_kin::KinError> {
    match opts.custom.iter().find(|e| e.id() == id) {
        Some(e) => Ok(e.clone()),
        None => EffectKind::from_id(id, n_wheels),
    }
}

/// Diagnose `model` on `train`, holding out `validation` (or cross-validating over repetitions).
pub fn diagnose(
    model: &FittedModel,
    design: &FittedModel,
    train: &[Run],
    validation: Option<&[Run]>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, CalibrateError> {
    if train.is_empty() {
        return Err(CalibrateError::NoRuns);
    }
    let every = opts.every.max(1);
    // Held-out protocol.
    let (fit_runs, held_runs, held_label): (Vec<Run>, Vec<Run>, String) = match validation {
        Some(v) if !v.is_empty() => (train.to_vec(), v.to_vec(), "validation set".into()),
        _ => {
            let (a, b) = split_held_out(train);
            if a.is_empty() || b.is_empty() {
                (train.to_vec(), train.to_vec(), "training runs (too few to hold any out)".into())
            } else {
                (a, b, "2-fold cross-validation over repetitions (even → odd)".into())
            }
        }
    };
    let costs = costs_of(model, &fit_runs, &held_runs, every)?;
    let design_costs = costs_of(design, &fit_runs, &held_runs, every)?;
    let (runs, groups, growth) = compare(model, design, train, every)?;
    let noise = noise_floor(train);

    let mut ladder = vec![
        Rung { label: "design".into(), costs: design_costs.clone() },
        Rung { label: "model".into(), costs: costs.clone() },
    ];
    let mut current = model.clone();
    let mut current_costs = costs.clone();
    let mut first_ranking: Option<Vec<Candidate>> = None;
    let mut added: Vec<String> = Vec::new();
    loop {
        let present: Vec<String> = current.model.effects.iter().map(|e| e.id().replace("_yaw", "")).collect();
        let mut ranking = Vec::new();
        let ids = opts.candidates.iter().cloned().chain(opts.custom.iter().map(|e| e.id().to_string()));
        for id in &ids.collect::<Vec<_>>() {
            if present.iter().any(|p| p == id) {
                continue;
            }
            let effect = candidate_effect(id, current.model.n_wheels(), opts)?;
            let (explained, separability, implied) = if effect.params().is_empty() {
                (f64::NAN, 1.0, Vec::new())
            } else {
                first_order(&current, design, &effect, &fit_runs, every)?
            };
            let absorbed = separability < 0.05;
            let mut cand = Candidate {
                effect: id.clone(),
                physics: effect.describe(),
                first_order_explained: explained,
                separability,
                absorbed,
                implied: if absorbed { implied } else { Vec::new() },
                refit: None,
                held_out_gain: 0.0,
                excess_closed: f64::NAN,
                params: Vec::new(),
                not_excited: None,
            };
            if effect.stage() == Stage::Wheel {
                cand.not_excited = wheel_excitation_gap(&fit_runs, &current.model.kinematics.wheel_names());
            }
            if !absorbed && cand.not_excited.is_none() {
                let ext = current.with_effect(effect.clone());
                if let Ok(fit) = refit(&ext, &fit_runs, every) {
                    let c = costs_of(&fit, &fit_runs, &held_runs, every)?;
                    cand.held_out_gain = 1.0 - c.held_out_path / current_costs.held_out_path.max(1e-300);
                    if let Some(nf) = &noise {
                        let (b, a, f) = (current_costs.held_out_path, c.held_out_path, nf.path_rms);
                        cand.excess_closed = (b * b - a * a) / (b * b - f * f).max(1e-300);
                    }
                    // Standard errors of the effect parameters at the refit.
                    let n = fit.params.len();
                    let p = unbounded(&fit.model, &fit_runs, every)?;
                    let se = standard_errors(&p.jacobian(&fit.params), &p.residuals(&fit.params));
                    let r = fit.model.effect_ranges().last().cloned().unwrap_or(n..n);
                    cand.params = effect
                        .params()
                        .iter()
                        .zip(r.clone())
                        .map(|(s, i)| ParamValue {
                            name: s.name.clone(),
                            value: fit.params[i],
                            unit: s.unit.clone(),
                            std_error: se.as_ref().map(|v| v[i]),
                        })
                        .collect();
                    cand.refit = Some(c);
                }
            }
            ranking.push(cand);
        }
        ranking.sort_by(|a, b| b.held_out_gain.total_cmp(&a.held_out_gain));
        let best = ranking.first().filter(|c| passes(c, opts)).cloned();
        if first_ranking.is_none() {
            first_ranking = Some(ranking.clone());
        }
        match best {
            Some(b) if opts.auto && added.len() < opts.max_added => {
                let effect = candidate_effect(&b.effect, current.model.n_wheels(), opts)?;
                current = refit(&current.with_effect(effect), &fit_runs, every)?;
                current_costs = costs_of(&current, &fit_runs, &held_runs, every)?;
                ladder.push(Rung { label: format!("+ {}", b.effect), costs: current_costs.clone() });
                added.push(b.effect);
            }
            _ => break,
        }
        if !opts.auto {
            break;
        }
    }
    let ranking = first_ranking.unwrap_or_default();
    let mut verdict = ranking.first().filter(|c| passes(c, opts) && confident(c, opts)).map(|c| c.effect.clone());
    // The winner must also help on kinds of path it was not fitted on, when the runs have several.
    let kind_check = match &verdict {
        Some(v) => kind_out(model, &candidate_effect(v, model.model.n_wheels(), opts)?, train, every)?,
        None => None,
    };
    let kind_failed = kind_check.as_ref().is_some_and(|k| k.gain < 0.0);
    if kind_failed {
        verdict = None;
    }
    let identifiability = unbounded(&model.model, &fit_runs, every)
        .ok()
        .map(|p| p.identifiability(&model.params, &IdentifyOptions::default()));
    let repeat_floor = repeatability_floor(&groups);

    let mut findings = Vec::new();
    let mut worst: Vec<&RunReport> = runs.iter().collect();
    worst.sort_by(|a, b| b.path_rms.total_cmp(&a.path_rms));
    if let Some(w) = worst.first() {
        findings.push(format!(
            "worst run {} ({}): path RMS {:.4} m (design {:.4})",
            w.name,
            w.command.clone().unwrap_or_else(|| "-".into()),
            w.path_rms,
            w.design_path_rms
        ));
    }
    let sys: Vec<&GroupReport> = groups.iter().filter(|g| g.systematic && g.runs > 1).collect();
    if !sys.is_empty() {
        let mut s = sys.clone();
        s.sort_by(|a, b| b.bias.total_cmp(&a.bias));
        findings.push(format!(
            "{} of {} command groups end with a systematic error (bias beyond the repeat scatter); largest: {} bias {:.4}, scatter {:.4}",
            sys.len(),
            groups.len(),
            s[0].group,
            s[0].bias,
            s[0].scatter
        ));
    }
    if let (Some(first), Some(last)) = (growth.position_m.first(), growth.position_m.last()) {
        findings.push(format!("position error grows from {:.4} m early to {:.4} m late in the runs", first, last));
    }
    for c in ranking.iter().filter(|c| c.absorbed) {
        let vals: Vec<String> = c.implied.iter().map(|p| format!("{} = {:.4} {}", p.name, p.value, p.unit)).collect();
        findings.push(format!(
            "{}: indistinguishable from the model on these runs (absorbed by it, or not excited: equivalent {})",
            c.effect,
            vals.join(", ")
        ));
    }
    for c in ranking.iter().filter(|c| c.not_excited.is_some()) {
        findings.push(format!(
            "{}: not tested, the training runs do not excite it ({})",
            c.effect,
            c.not_excited.clone().unwrap_or_default()
        ));
    }
    if let Some(id) = &identifiability {
        for w in id.warnings() {
            findings.push(format!("the model itself: {w}"));
        }
    }
    if let Some(f) = repeat_floor {
        findings.push(format!(
            "repeatability floor: end-pose errors scatter by {f:.4} between repeats of the same command (no deterministic effect removes that part)"
        ));
    }
    let final_costs = ladder.last().map(|r| r.costs.clone()).unwrap_or(costs.clone());
    let mut verdict_text = match &verdict {
        Some(v) => {
            let c = &ranking[0];
            format!(
                "add {v}: held-out path cost falls {:.1} % ({:.4} → {:.4} m)",
                100.0 * c.held_out_gain,
                costs.held_out_path,
                c.refit.as_ref().map(|r| r.held_out_path).unwrap_or(f64::NAN)
            )
        }
        None => match ranking.first().filter(|c| passes(c, opts)) {
            Some(c) => format!(
                "no catalogued effect explains most of the remaining error ({} helps: held-out path cost −{:.1} %, but it removes only {:.0} % of the error above the noise floor)",
                c.effect,
                100.0 * c.held_out_gain,
                100.0 * c.excess_closed
            ),
            None => "no catalogued effect explains the remaining error".into(),
        },
    };
    if let (true, Some(k)) = (kind_failed, &kind_check) {
        verdict_text = format!(
            "{} helps on repeats of the training paths but not on new kinds of path (left-out kinds: path cost {:+.1} %), so it is not recommended",
            k.effect,
            -100.0 * k.gain
        );
    }
    // The error that would remain: after the recommended effect (or the ladder's last rung).
    let remaining = match (&verdict, opts.auto) {
        (Some(_), false) => ranking[0].refit.as_ref().map_or(final_costs.held_out_path, |c| c.held_out_path),
        _ => final_costs.held_out_path,
    };
    if let Some(nf) = &noise {
        let ratio = remaining / nf.path_rms.max(1e-12);
        if ratio > 3.0 {
            verdict_text.push_str(&format!(
                "; the remaining held-out error ({remaining:.4} m) is {ratio:.1}× the measurement noise floor ({:.4} m): something physical is still missing",
                nf.path_rms
            ));
        } else {
            verdict_text.push_str(&format!(
                "; the remaining held-out error ({remaining:.4} m) is close to the measurement noise floor ({:.4} m, ratio {ratio:.1})",
                nf.path_rms
            ));
        }
    }
    Ok(Diagnosis {
        verdict,
        verdict_text,
        held_out: held_label,
        costs,
        design_costs,
        runs,
        groups,
        growth,
        findings,
        ranking,
        noise_floor: noise,
        ladder,
        identifiability,
        repeatability_floor: repeat_floor,
        kind_out: kind_check,
        final_model: Some(current),
    })
}
