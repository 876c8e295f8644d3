//! The analysis behind [`super::analyse`] and [`super::expected`], step by step: the scaled information's
//! spectrum, the covariance of its directions (per-run sandwich or iid), the unconstrained directions, and
//! each parameter's standard error over the constrained ones.

use super::direction::describe;
use super::{CovarianceKind, Identifiability, IdentifyOptions, Moments, ParamUncertainty, param_scales};
use nalgebra::{DMatrix, DVector};
use omni_kin::Model;

/// What the residuals say about the noise: counts, the noise variance and which covariance applies.
pub(super) struct Noise {
    /// Residual rows.
    pub(super) rows: usize,
    /// Runs.
    pub(super) runs: usize,
    /// Clusters of the sandwich: runs, or their segments.
    pub(super) clusters: usize,
    /// `rᵀr`.
    pub(super) rtr: f64,
    /// Residual variance `s²` (1 for a stated noise level).
    pub(super) s2: f64,
    /// The covariance estimate used.
    pub(super) kind: CovarianceKind,
    /// Small-sample factor of the sandwich, `G/(G − 1) · (m − 1)/(m − p)`.
    pub(super) cr1: f64,
}

impl Noise {
    pub(super) fn new(moments: Option<&Moments>, n: usize) -> Self {
        let rows = moments.map_or(0, |mo| mo.rows);
        let runs = moments.map_or(0, |mo| mo.runs);
        let clusters = moments.map_or(0, |mo| mo.scores.len());
        let rtr = moments.map_or(0.0, |mo| mo.rtr);
        let dof = rows.saturating_sub(n).max(1) as f64;
        let s2 = if moments.is_some() { rtr / dof } else { 1.0 };
        let kind = if moments.is_none() {
            CovarianceKind::Stated
        } else if clusters >= n + 2 {
            CovarianceKind::PerRun
        } else {
            CovarianceKind::Iid
        };
        let g = clusters;
        let cr1 = if g > 1 { g as f64 / (g - 1) as f64 * (rows as f64 - 1.0) / dof } else { 1.0 };
        Self { rows, runs, clusters, rtr, s2, kind, cr1 }
    }
}

/// The scaled information `D JᵀJ D = V S² Vᵀ`: `V`'s columns are directions, `S` the scaled Jacobian's
/// singular values.
struct Spectrum {
    /// Singular values, in the eigen-solver's order.
    sv: DVector<f64>,
    /// Directions (columns), same order.
    v: DMatrix<f64>,
    /// Indices of `sv`, largest first.
    order: Vec<usize>,
    /// The largest singular value.
    smax: f64,
}

impl Spectrum {
    /// `None` when the eigen-solver does not converge.
    fn of(jtj_s: DMatrix<f64>) -> Option<Self> {
        let e = jtj_s.try_symmetric_eigen(f64::EPSILON, 10_000)?;
        let sv = e.eigenvalues.map(|l| l.max(0.0).sqrt());
        let mut order: Vec<usize> = (0..sv.len()).collect();
        order.sort_by(|&a, &b| sv[b].total_cmp(&sv[a]));
        let smax = order.first().map_or(0.0, |&k| sv[k]);
        Some(Self { sv, v: e.eigenvectors, order, smax })
    }

    /// `s_k / s_max`, largest first.
    fn relative(&self) -> Vec<f64> {
        self.order.iter().map(|&k| self.relative_of(k)).collect()
    }

    fn relative_of(&self, k: usize) -> f64 {
        if self.smax > 0.0 { self.sv[k] / self.smax } else { 0.0 }
    }

    /// The non-null directions (`s_k > rcond · s_max`), largest first.
    fn alive(&self, rcond: f64) -> Vec<usize> {
        self.order.iter().copied().filter(|&k| self.sv[k] > rcond * self.smax && self.smax > 0.0).collect()
    }
}

/// Covariances of the coordinates along the alive directions, in scaled space:
/// `S⁻² (Vᵀ B V) S⁻²` (per-run sandwich) and `s² S⁻²` (iid).
struct DirectionCovariances {
    robust: DMatrix<f64>,
    iid: DMatrix<f64>,
}

impl DirectionCovariances {
    fn new(sp: &Spectrum, va: &DMatrix<f64>, alive: &[usize], scores: &[DVector<f64>], noise: &Noise) -> Self {
        let inv_s2 = DVector::from_iterator(alive.len(), alive.iter().map(|&k| 1.0 / (sp.sv[k] * sp.sv[k])));
        let mut b = DMatrix::zeros(alive.len(), alive.len());
        for g in scores {
            let p = va.transpose() * g;
            b += &p * p.transpose();
        }
        b *= noise.cr1;
        let robust = DMatrix::from_fn(alive.len(), alive.len(), |a, c| inv_s2[a] * b[(a, c)] * inv_s2[c]);
        let iid = DMatrix::from_diagonal(&inv_s2.map(|x| x * noise.s2));
        Self { robust, iid }
    }

    fn chosen(&self, kind: CovarianceKind) -> &DMatrix<f64> {
        match kind {
            CovarianceKind::PerRun => &self.robust,
            CovarianceKind::Iid | CovarianceKind::Stated => &self.iid,
        }
    }
}

/// The unconstrained directions, largest singular value first: null ones (standard error `None`), and
/// alive ones whose standard error exceeds `max_std_error` or whose excitation is below `min_excitation`.
/// The excitation rule applies only without per-run standard errors (`kind`): a direction whose per-run
/// standard error is small is never unconstrained. Nor is an excited one along which the fit lies more than
/// [`super::START_REJECTED_SIGMAS`] standard errors from the start (`departure`: the fit minus the start,
/// scaled; see [`IdentifyOptions::start`]).
fn unconstrained(
    sp: &Spectrum,
    alive: &[usize],
    chosen: &DMatrix<f64>,
    kind: CovarianceKind,
    opts: &IdentifyOptions,
    departure: Option<&DVector<f64>>,
) -> Vec<(usize, Option<f64>)> {
    let mut weak = Vec::new();
    let by_excitation = kind != CovarianceKind::PerRun;
    for &k in &sp.order {
        match alive.iter().position(|&a| a == k) {
            None => weak.push((k, None)),
            Some(a) => {
                let se = chosen[(a, a)].max(0.0).sqrt();
                let weakly_excited = sp.sv[k] < opts.min_excitation * sp.smax;
                let rejects_start = departure.is_some_and(|d| {
                    !weakly_excited && sp.v.column(k).dot(d).abs() > super::START_REJECTED_SIGMAS * se
                });
                if (se > opts.max_std_error || (by_excitation && weakly_excited)) && !rejects_start {
                    weak.push((k, Some(se)));
                }
            }
        }
    }
    weak
}

/// Everything reported undetermined (non-finite input, or an eigen-solver that did not converge).
fn undetermined(model: &Model, params: &[f64], scales: &[f64], noise: &Noise) -> Identifiability {
    Identifiability {
        runs: noise.runs,
        clusters: noise.clusters,
        residuals: noise.rows,
        residual_rms: f64::NAN,
        covariance_kind: CovarianceKind::Iid,
        condition_number: f64::NAN,
        relative_singular_values: Vec::new(),
        params: uncertainties(model, params, scales, |_| None),
        covariance: Vec::new(),
        weak: Vec::new(),
    }
}

/// One [`ParamUncertainty`] per parameter; `se(i)` gives (standard error, iid standard error).
fn uncertainties(
    model: &Model,
    params: &[f64],
    scales: &[f64],
    se: impl Fn(usize) -> Option<(f64, f64)>,
) -> Vec<ParamUncertainty> {
    model
        .params()
        .iter()
        .enumerate()
        .map(|(i, s)| ParamUncertainty {
            name: s.name.clone(),
            unit: s.unit.clone(),
            value: params[i],
            scale: scales[i],
            std_error: se(i).map(|(c, _)| c),
            std_error_iid: se(i).map(|(_, c)| c),
        })
        .collect()
}

/// See [`super::analyse`]; `moments` is `None` for a stated noise level.
pub(super) fn analyse_core(
    model: &Model,
    params: &[f64],
    jtj: &DMatrix<f64>,
    moments: Option<&Moments>,
    wheel_moment: Option<&DMatrix<f64>>,
    opts: &IdentifyOptions,
) -> Identifiability {
    let n = jtj.ncols();
    let scales = param_scales(model);
    let noise = Noise::new(moments, n);
    // The residual vector's squared norm is a mean over runs of the mean squared pose error (three
    // components), as `CalibrationProblem` stacks it.
    let residual_rms = (noise.rtr / 3.0).sqrt();
    // Non-finite sensitivities or residuals (a failed effect hook, a singular model) say nothing, and an
    // eigen-solver may not converge on them: everything is then reported undetermined, nothing held.
    let jtj_s = DMatrix::from_fn(n, n, |a, b| jtj[(a, b)] * scales[a] * scales[b]);
    let finite = moments.is_none_or(|mo| mo.finite) && jtj_s.iter().all(|v| v.is_finite());
    let Some(sp) = (if finite { Spectrum::of(jtj_s) } else { None }) else {
        return undetermined(model, params, &scales, &noise);
    };
    // Per-run scores in scaled space, g_g = D J_gᵀ r_g, for the sandwich.
    let scores: Vec<DVector<f64>> = moments
        .map(|mo| mo.scores.iter().map(|g| DVector::from_fn(n, |i, _| g[i] * scales[i])).collect())
        .unwrap_or_default();
    let alive = sp.alive(opts.rcond);
    let va = DMatrix::from_fn(n, alive.len(), |r, c| sp.v[(r, alive[c])]);
    let dirs = DirectionCovariances::new(&sp, &va, &alive, &scores, &noise);
    let departure = opts
        .start
        .as_ref()
        .filter(|s| s.len() == n)
        .map(|s| DVector::from_fn(n, |i, _| (params[i] - s[i]) / scales[i]));
    let weak_k = unconstrained(&sp, &alive, dirs.chosen(noise.kind), noise.kind, opts, departure.as_ref());
    // Directions that stay: covariance restricted to the constrained subspace, in parameter units.
    let strong: Vec<usize> = (0..alive.len()).filter(|&a| !weak_k.iter().any(|&(k, _)| k == alive[a])).collect();
    let vs = DMatrix::from_fn(n, strong.len(), |r, c| va[(r, strong[c])]);
    let to_params = |c: &DMatrix<f64>| {
        let sub = DMatrix::from_fn(strong.len(), strong.len(), |a, b| c[(strong[a], strong[b])]);
        let cs = &vs * sub * vs.transpose();
        DMatrix::from_fn(n, n, |a, b| cs[(a, b)] * scales[a] * scales[b])
    };
    let cov = to_params(dirs.chosen(noise.kind));
    let cov_iid = to_params(&dirs.iid);
    let weak_loading = |i: usize| weak_k.iter().map(|&(k, _)| sp.v[(i, k)].abs()).fold(0.0f64, f64::max);
    let determined = |i: usize| {
        (weak_loading(i) < super::WEAK_LOADING).then(|| (cov[(i, i)].max(0.0).sqrt(), cov_iid[(i, i)].max(0.0).sqrt()))
    };
    let weak = weak_k
        .iter()
        .map(|&(k, se)| {
            let dir: Vec<f64> = (0..n).map(|i| sp.v[(i, k)]).collect();
            describe(model, params, &scales, dir, sp.relative_of(k), se, wheel_moment)
        })
        .collect();
    Identifiability {
        runs: noise.runs,
        clusters: noise.clusters,
        residuals: noise.rows,
        residual_rms,
        covariance_kind: noise.kind,
        condition_number: if alive.len() == n && n > 0 {
            sp.smax / sp.sv[*alive.last().unwrap_or(&0)].max(f64::MIN_POSITIVE)
        } else {
            f64::INFINITY
        },
        relative_singular_values: sp.relative(),
        params: uncertainties(model, params, &scales, determined),
        covariance: (0..n).map(|a| (0..n).map(|b| cov[(a, b)]).collect()).collect(),
        weak,
    }
}
