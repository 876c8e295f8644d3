//! The explorer: which family of physical features explains the error a model leaves, when no
//! catalogued effect does.
//!
//! For each family ([`omni_kin::effect::Family`]: wheel, body, world, time, ground truth) the model gets
//! the learned correction `learned:<family>` at θ = 0, and θ is fitted together with the base kinematics
//! on the training runs by Gauss–Newton on the path residuals (the model's predicted pose minus the
//! measured one at the ground-truth poses, world frame; at most [`ExploreOptions::poses_per_run`] poses
//! per run), with a forward-difference Jacobian. The baseline is the same fit of the base kinematics
//! alone, so a family's gain is what its terms add, not what a refit of the base gives.
//!
//! Standard errors are cluster-robust over runs (the sandwich of [`crate::identify`]'s `per run`). A
//! family is judged on the held-out runs: its held-out gain is `1 − C_family / C_baseline` with `C` the
//! held-out path cost (every ground-truth pose, 1 m/rad); its standard error is that of the per-run
//! gains' mean. **A family passes** when its held-out gain is at least [`ExploreOptions::min_gain`] (5 %)
//! and larger than [`ExploreOptions::min_gain_std_errors`] (2) standard errors.
//!
//! `unexplained`: no family passes, and the baseline's held-out path RMS is more than
//! [`ExploreOptions::noise_ratio`] (3) times the held-out runs' measurement noise floor (or the noise floor
//! is unknown): an error remains that no family's features explain.
//!
//! No I/O; the words are made in [`crate::science::text`].

use crate::error::Error;
use crate::science::coverage::{MotionCoverage, motion_coverage};
use crate::science::diagnose::noise_floor;
use crate::science::identify::{self, Moments};
use nalgebra::{DMatrix, DVector};
use omni_kin::effect::{Effect, EffectKind, Family, Learned};
use omni_kin::evaluate::Evaluator;
use omni_kin::{CostKind, FittedModel, Model, Run, Selection};
use serde::{Deserialize, Serialize};

/// Settings of [`explore`].
#[derive(Clone, Debug, PartialEq)]
pub struct ExploreOptions {
    /// Families to try, in order (default: all).
    pub families: Vec<Family>,
    /// Smallest held-out gain that passes. Default 0.05 (5 %).
    pub min_gain: f64,
    /// The held-out gain must exceed this many of its standard errors. Default 2.
    pub min_gain_std_errors: f64,
    /// Training residuals: at most about this many ground-truth poses per run (every k-th). Default 200.
    pub poses_per_run: usize,
    /// Gauss–Newton iterations. Default 3.
    pub iterations: usize,
    /// `unexplained` needs the held-out path RMS above this many noise floors. Default 3.
    pub noise_ratio: f64,
}

impl Default for ExploreOptions {
    fn default() -> Self {
        Self {
            families: Family::ALL.to_vec(),
            min_gain: 0.05,
            min_gain_std_errors: 2.0,
            poses_per_run: 200,
            iterations: 3,
            noise_ratio: 3.0,
        }
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

/// One family's fit and judgement.
#[derive(Clone, Debug)]
pub struct FamilyResult {
    /// The family.
    pub family: Family,
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
    /// The model with the learned effect (`learned:<family>`) at its fitted values.
    pub fitted: FittedModel,
    /// The residual against the strongest term.
    pub curve: Option<FeatureCurve>,
}

/// What the explorer found.
#[derive(Clone, Debug)]
pub struct Exploration {
    /// Every family, by held-out gain, largest first.
    pub families: Vec<FamilyResult>,
    /// Held-out path cost of the baseline (the base kinematics refitted alone). m.
    pub baseline_held_out_cost: f64,
    /// The held-out runs' measurement noise floor (path RMS from pose noise alone), when measurable. m.
    pub noise_floor_path_rms: Option<f64>,
    /// No family passes and an error above the noise remains (module docs).
    pub unexplained: bool,
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

/// A Gauss–Newton fit: the parameters, and at them the Jacobian (free columns) and residuals.
struct Fit {
    params: Vec<f64>,
    jacobian: DMatrix<f64>,
    residuals: Vec<f64>,
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
    let longest = train.iter().map(|r| r.truth().len()).max().unwrap_or(1);
    let kind =
        CostKind::Path { every: longest.div_ceil(opts.poses_per_run.max(1)).max(1), heading_weight_m_per_rad: 1.0 };
    let base_free: Vec<usize> = (0..model.model.n_base()).collect();
    let baseline = gauss_newton(&model.model, &model.params, &base_free, train, kind, opts.iterations)?;
    let baseline = FittedModel::new(model.model.clone(), baseline.params)?;
    let (base_cost, base_runs) = held_out(&baseline, validate)?;
    let mut families = Vec::new();
    for &family in &opts.families {
        families.push(fit_family(&baseline, family, train, validate, kind, (base_cost, &base_runs), opts)?);
    }
    families.sort_by(|a, b| b.held_out_gain.total_cmp(&a.held_out_gain));
    let noise = noise_floor(validate).map(|n| n.path_rms);
    let remains = noise.is_none_or(|n| base_cost > opts.noise_ratio * n);
    let unexplained = !families.iter().any(|f| f.passes) && remains;
    Ok(Exploration {
        families,
        baseline_held_out_cost: base_cost,
        noise_floor_path_rms: noise,
        unexplained,
        runs: (train.len(), validate.len()),
        coverage: motion_coverage(model, train, validate)?,
    })
}

/// Fit one family on `train` (with the base kinematics) and judge it on `validate` against the baseline's
/// held-out cost and per-run mean squared errors.
fn fit_family(
    baseline: &FittedModel,
    family: Family,
    train: &[Run],
    validate: &[Run],
    kind: CostKind,
    (base_cost, base_runs): (f64, &[f64]),
    opts: &ExploreOptions,
) -> Result<FamilyResult, Error> {
    let learned = EffectKind::Learned(Learned { family, n_wheels: baseline.model.n_wheels() });
    let specs = learned.params();
    let start = baseline.with_effect(learned);
    let n = start.params.len();
    let first = n - specs.len();
    let free: Vec<usize> = (0..baseline.model.n_base()).chain(first..n).collect();
    let fit = gauss_newton(&start.model, &start.params, &free, train, kind, opts.iterations)?;
    let run_rows = run_rows(&start.model, train, kind)?;
    let se = cluster_std_errors(&fit.jacobian, &fit.residuals, &run_rows);
    let nb = baseline.model.n_base();
    let terms: Vec<Term> = specs
        .iter()
        .enumerate()
        .map(|(k, s)| Term {
            name: s.name.clone(),
            value: fit.params[first + k],
            std_error: se[nb + k],
            unit: s.unit.clone(),
        })
        .collect();
    let curve = strongest(&terms).map(|k| feature_curve(&fit, &run_rows, nb + k, &terms[k]));
    let fitted = FittedModel::new(start.model, fit.params)?;
    let (cost, per_run) = held_out(&fitted, validate)?;
    let gain = 1.0 - cost / base_cost;
    let gains: Vec<f64> = per_run.iter().zip(base_runs).map(|(c, b)| 1.0 - (c / b).sqrt()).collect();
    let gain_std_error = mean_std_error(&gains);
    let passes = gain.is_finite() && gain >= opts.min_gain && gain > opts.min_gain_std_errors * gain_std_error;
    Ok(FamilyResult { family, held_out_gain: gain, gain_std_error, passes, held_out_cost: cost, terms, fitted, curve })
}

/// Held-out path cost (every pose, 1 m/rad) and each run's path mean squared error.
fn held_out(model: &FittedModel, runs: &[Run]) -> Result<(f64, Vec<f64>), Error> {
    let ev = Evaluator::for_report(&model.model, runs, Selection::Path(1))?;
    let errors = ev.errors(&model.model.resolve(&model.params)?);
    let per_run = (0..errors.n_runs()).map(|i| errors.path_mse(i, 1.0)).collect();
    Ok((errors.path_cost(1.0), per_run))
}

/// Residual rows of each run at the selection of `kind`.
fn run_rows(model: &Model, runs: &[Run], kind: CostKind) -> Result<Vec<usize>, Error> {
    let ev = Evaluator::for_cost(model, runs, kind)?;
    Ok((0..runs.len()).map(|i| 3 * ev.indices(i).len()).collect())
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

/// Gauss–Newton over the `free` parameters of `model` from `start` on the stacked path residuals of
/// `kind`, forward differences, steps halved until the cost falls; the Jacobian and residuals at the end.
fn gauss_newton(
    model: &Model,
    start: &[f64],
    free: &[usize],
    runs: &[Run],
    kind: CostKind,
    iterations: usize,
) -> Result<Fit, Error> {
    let ev = Evaluator::for_cost(model, runs, kind)?;
    let residuals = |x: &[f64]| -> Result<Vec<f64>, Error> { Ok(ev.residual_vector(&model.resolve(x)?, kind)) };
    let specs = model.params();
    let steps: Vec<f64> = free
        .iter()
        .map(|&j| {
            let width = specs[j].upper - specs[j].lower;
            if width.is_finite() && width > 0.0 { 1e-6 * width } else { 1e-7 }
        })
        .collect();
    let mut x = start.to_vec();
    let mut r = residuals(&x)?;
    let mut jac = jacobian(&residuals, &x, &r, free, &steps)?;
    for _ in 0..iterations {
        let delta = solve(&jac, &r);
        let cost = sq(&r);
        let mut accepted = false;
        let mut t = 1.0;
        for _ in 0..6 {
            let mut y = x.clone();
            for (k, &j) in free.iter().enumerate() {
                y[j] += t * delta[k];
            }
            // A step to parameters the model refuses (a negative wheel radius) counts as a worse one.
            if let Ok(ry) = residuals(&y)
                && sq(&ry) < cost
            {
                (x, r, accepted) = (y, ry, true);
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
        jac = jacobian(&residuals, &x, &r, free, &steps)?;
    }
    Ok(Fit { params: x, jacobian: jac, residuals: r })
}

fn sq(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Forward-difference Jacobian of `f` at `x` (with `f(x) = r`) over the `free` columns.
fn jacobian(
    f: &impl Fn(&[f64]) -> Result<Vec<f64>, Error>,
    x: &[f64],
    r: &[f64],
    free: &[usize],
    steps: &[f64],
) -> Result<DMatrix<f64>, Error> {
    let mut jac = DMatrix::zeros(r.len(), free.len());
    for (k, (&j, &h)) in free.iter().zip(steps).enumerate() {
        let mut y = x.to_vec();
        y[j] += h;
        let ry = f(&y)?;
        for (i, (a, b)) in ry.iter().zip(r).enumerate() {
            jac[(i, k)] = (a - b) / h;
        }
    }
    Ok(jac)
}

/// Relative singular value below which a direction of the unit-column Jacobian counts as undetermined.
const RCOND: f64 = 1e-7;

/// Column norms of `j` (1 for an empty column, which then stays out of the solution).
fn column_scales(j: &DMatrix<f64>) -> Vec<f64> {
    j.column_iter().map(|c| c.norm()).map(|n| if n > 0.0 && n.is_finite() { n } else { 1.0 }).collect()
}

/// Least-squares step `δ` minimising `|r + J δ|`, on unit-norm columns, singular values below
/// [`RCOND`] of the largest dropped (directions the runs do not determine stay put).
fn solve(j: &DMatrix<f64>, r: &[f64]) -> Vec<f64> {
    let d = column_scales(j);
    let mut js = j.clone();
    for (k, mut c) in js.column_iter_mut().enumerate() {
        c /= d[k];
    }
    let svd = js.svd(true, true);
    let rhs = -DVector::from_column_slice(r);
    let tol = RCOND * svd.singular_values.max();
    match svd.solve(&rhs, tol) {
        Ok(z) => z.iter().zip(&d).map(|(z, d)| if z.is_finite() { z / d } else { 0.0 }).collect(),
        Err(_) => vec![0.0; j.ncols()],
    }
}

/// Standard errors of every column of `j`, residuals `r`, `run_rows` rows per run: the one computation
/// of [`crate::identify`] ([`identify::column_std_errors`], per-run sandwich). NaN where undetermined.
fn cluster_std_errors(j: &DMatrix<f64>, r: &[f64], run_rows: &[usize]) -> Vec<f64> {
    identify::column_std_errors(&Moments::from_dense(j, r, run_rows), RCOND)
}

/// The term with the largest `|value| / std_error`.
fn strongest(terms: &[Term]) -> Option<usize> {
    (0..terms.len()).filter(|&k| terms[k].z() > 0.0).max_by(|&a, &b| terms[a].z().total_cmp(&terms[b].z()))
}

/// Number of bins of a [`FeatureCurve`].
const CURVE_BINS: usize = 10;

/// The added-variable curve of column `col` (term `term`): the feature `x = −J_col` and the residual
/// with the term's part put back, `y = r_final − J_col θ`, both unweighted (m), in equal-count bins.
fn feature_curve(fit: &Fit, run_rows: &[usize], col: usize, term: &Term) -> FeatureCurve {
    let g = run_rows.len().max(1) as f64;
    let mut points = Vec::with_capacity(fit.residuals.len());
    let mut row = 0;
    for &rows in run_rows {
        // Undo the path cost's weight 1/sqrt(G · poses) of this run.
        let unweight = (g * (rows / 3).max(1) as f64).sqrt();
        for i in row..(row + rows).min(fit.residuals.len()) {
            let x = -fit.jacobian[(i, col)] * unweight;
            let y = (fit.residuals[i] - fit.jacobian[(i, col)] * term.value) * unweight;
            if x != 0.0 {
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
    FeatureCurve { term: term.name.clone(), unit: term.unit.clone(), slope: term.value, bins }
}
