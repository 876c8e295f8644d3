//! Identifiability: what the runs can and cannot calibrate.
//!
//! From the Jacobian `J` of the residuals at a fit (rows: residuals, run after run; columns: the model's
//! parameters) and the residuals `r`:
//!
//! - **Scaled Jacobian** `J_s = J D`, with `D` each parameter's scale (IK entries: the largest magnitude in
//!   the design matrix's row, as the GA box; geometry radii and distances: their design values; angles:
//!   1 rad; effects: half their default search range). Its singular values `s_k` and right singular
//!   vectors `v_k` are the directions of parameter space, in "fraction of scale" units; the **condition
//!   number** is `s_max / s_min`.
//! - **Covariance.** `iid`: `σ² (JᵀJ)⁻¹` with `σ² = ‖r‖² / (m − p)`, the textbook estimate that treats
//!   every residual as independent. `per run` (the default standard error): the cluster-robust sandwich
//!   `(JᵀJ)⁻¹ (Σ_runs J_gᵀ r_g r_gᵀ J_g) (JᵀJ)⁻¹ · G/(G − 1) · (m − 1)/(m − p)` over the `G` runs, which
//!   stays honest when the errors along a path are correlated (wheel noise integrates into drift), as
//!   they are in odometry. It needs several runs per parameter; with fewer than `2p` runs the iid estimate
//!   is used (and said).
//! - **Unconstrained directions**: `v_k` whose standard error (in fraction of scale) exceeds
//!   `max_std_error` (default 5 % of scale: the data cannot pin that combination to better than the size of
//!   a typical calibration correction), or whose `s_k` is below `min_excitation · s_max` (default 1 %: the
//!   residuals respond to it 100× less than to the best-excited direction, whatever the noise). Each is named by the
//!   parameters that carry it ("m21 and m22 move together"); for the base kinematics, the direction is
//!   mapped to a change of the IK matrix `ΔM`, whose dominant wheel-speed pattern `u` (`ΔM ≈ a uᵀ`) is
//!   the pattern the runs hardly contain, and whose motion under the design matrix (`M₀ u`) says which
//!   runs to add ("add runs moving sideways (vy ≠ 0)").
//!
//! Pure computation: no I/O.

use nalgebra::{DMatrix, DVector};
use omni_kin::Model;
use omni_kin::effect::Effect;
use serde::{Deserialize, Serialize};

/// Settings of the analysis (scaled units: fractions of each parameter's scale).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdentifyOptions {
    /// A direction whose standard error exceeds this fraction of the parameters' scale is unconstrained.
    /// Default 0.05.
    pub max_std_error: f64,
    /// A direction whose singular value is below this fraction of the largest is unconstrained whatever
    /// the noise: the runs move the residuals along it 100× less than along the best-excited direction.
    /// Default 0.01.
    pub min_excitation: f64,
    /// Singular values below `rcond · s_max` are treated as zero (not excited at all). Default 1e-7 (the
    /// analysis works on `JᵀJ`, whose eigenvalues are the squares).
    pub rcond: f64,
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        Self { max_std_error: 0.05, min_excitation: 0.01, rcond: 1e-7 }
    }
}

/// Which covariance estimate the standard errors use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CovarianceKind {
    /// Cluster-robust over runs (errors may be correlated along a run).
    PerRun,
    /// Independent residuals (too few runs for the robust estimate).
    Iid,
    /// A stated noise level: the Jacobian's rows are already divided by each residual's noise standard
    /// deviation, so the covariance is `(JᵀJ)⁻¹` (planning, before any data).
    Stated,
}

/// One parameter's uncertainty.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ParamUncertainty {
    /// Name (`m21`, `r_a`, `tau_s`, …).
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Value at the fit.
    pub value: f64,
    /// Scale used for the analysis (same unit).
    pub scale: f64,
    /// Standard error (same unit) over the constrained directions; `None` when the parameter is part of
    /// an unconstrained direction (its value is then set by the start, not by the data).
    pub std_error: Option<f64>,
    /// Standard error assuming independent residuals (same unit), over the constrained directions.
    pub std_error_iid: Option<f64>,
}

/// A direction of parameter space the runs do not constrain.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WeakDirection {
    /// Unit vector in scaled parameter space (one entry per parameter).
    pub direction: Vec<f64>,
    /// Parameters carrying it, largest first, with their signed share of the direction.
    pub loadings: Vec<(String, f64)>,
    /// Its singular value relative to the largest.
    pub relative_singular_value: f64,
    /// Standard error along it, in fraction of scale (`None`: not excited at all).
    pub std_error: Option<f64>,
    /// The wheel-speed pattern the runs hardly contain (unit vector, one entry per wheel), when the
    /// direction changes the base kinematics.
    pub wheel_pattern: Option<Vec<f64>>,
    /// The design twist of that pattern per unit wheel speed: (vx m/s, vy m/s, ω rad/s).
    pub motion: Option<[f64; 3]>,
    /// The direction in words.
    pub text: String,
    /// Which runs to add, in words.
    pub advice: String,
}

/// The identifiability of a model on a set of runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Identifiability {
    /// Runs.
    pub runs: usize,
    /// Residuals (rows of the Jacobian).
    pub residuals: usize,
    /// Residual RMS per component (x, y, weighted heading), in the objective's unit (m): the noise level
    /// the iid covariance uses.
    pub residual_rms: f64,
    /// Which covariance the standard errors use.
    pub covariance_kind: CovarianceKind,
    /// Condition number of the scaled Jacobian (`inf` when a direction is not excited at all).
    pub condition_number: f64,
    /// Singular values of the scaled Jacobian, largest first, relative to the largest.
    pub relative_singular_values: Vec<f64>,
    /// Per parameter.
    pub params: Vec<ParamUncertainty>,
    /// Parameter covariance in parameter units (the chosen estimate; over constrained directions only).
    pub covariance: Vec<Vec<f64>>,
    /// Directions the runs do not constrain (empty: every parameter is determined).
    pub weak: Vec<WeakDirection>,
}

impl Identifiability {
    /// True when every direction is constrained.
    pub fn well_posed(&self) -> bool {
        self.weak.is_empty()
    }

    /// One warning line per unconstrained direction.
    pub fn warnings(&self) -> Vec<String> {
        self.weak.iter().map(|w| format!("{}; {}", w.text, w.advice)).collect()
    }

    /// The unconstrained directions as columns of an `n × k` matrix in scaled parameter space.
    pub fn weak_basis(&self) -> DMatrix<f64> {
        let n = self.params.len();
        DMatrix::from_fn(n, self.weak.len(), |r, c| self.weak[c].direction[r])
    }

    /// The parameters' scales.
    pub fn scales(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.scale).collect()
    }
}

/// Each parameter's scale for `model` (see the module docs).
pub fn param_scales(model: &Model) -> Vec<f64> {
    let specs = model.params();
    let nb = model.n_base();
    let nominal: Vec<f64> = specs[..nb].iter().map(|s| s.null).collect();
    let base = model.kinematics.param_scales(&nominal);
    specs
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let scale = if i < nb {
                base[i]
            } else if s.lower.is_finite() && s.upper.is_finite() && s.upper > s.lower {
                0.5 * (s.upper - s.lower)
            } else {
                s.null.abs()
            };
            if scale > 0.0 && scale.is_finite() { scale } else { 1.0 }
        })
        .collect()
}

/// What the analysis needs from the residuals `r` and their Jacobian `J`, accumulated run by run so the
/// full Jacobian never has to be held: `JᵀJ`, each run's score `J_gᵀ r_g`, `rᵀr` and the row count.
#[derive(Clone, Debug)]
pub struct Moments {
    /// `JᵀJ` (parameter units).
    pub jtj: DMatrix<f64>,
    /// Per run, `J_gᵀ r_g`.
    pub scores: Vec<DVector<f64>>,
    /// `rᵀr`.
    pub rtr: f64,
    /// Residual rows.
    pub rows: usize,
    /// Every entry seen was finite.
    pub finite: bool,
}

impl Moments {
    /// Empty, for `n` parameters.
    pub fn new(n: usize) -> Self {
        Self { jtj: DMatrix::zeros(n, n), scores: Vec::new(), rtr: 0.0, rows: 0, finite: true }
    }

    /// Add one run's Jacobian rows and residuals.
    pub fn add_run(&mut self, j: &DMatrix<f64>, r: &[f64]) {
        self.finite &= j.iter().all(|v| v.is_finite()) && r.iter().all(|v| v.is_finite());
        if !self.finite {
            return;
        }
        self.jtj += j.transpose() * j;
        self.scores.push(j.transpose() * DVector::from_column_slice(r));
        self.rtr += r.iter().map(|v| v * v).sum::<f64>();
        self.rows += r.len();
    }

    /// From a stacked Jacobian and residuals; `run_rows[g]` rows per run, in order.
    pub fn from_dense(j: &DMatrix<f64>, r: &[f64], run_rows: &[usize]) -> Self {
        let mut m = Self::new(j.ncols());
        let mut row = 0;
        for &k in run_rows {
            let k = k.min(j.nrows().saturating_sub(row)).min(r.len().saturating_sub(row));
            m.add_run(&j.rows(row, k).into_owned(), &r[row..row + k]);
            row += k;
        }
        m
    }
}

/// Analyse `model` at `params` from the residuals' [`Moments`]; `wheel_moment` is the runs' mean `w wᵀ`
/// of the wheel speeds (rad²/s², `N × N`), used to say whether a wheel pattern is missing from the runs
/// or present but unseen by the residuals.
pub fn analyse(
    model: &Model,
    params: &[f64],
    moments: &Moments,
    wheel_moment: Option<&DMatrix<f64>>,
    opts: &IdentifyOptions,
) -> Identifiability {
    analyse_core(model, params, &moments.jtj, Some(moments), wheel_moment, opts)
}

/// The expected identifiability for a stated noise level: `info` is `JᵀJ` of the residuals' sensitivities
/// each divided by its noise standard deviation, so the covariance is `info⁻¹`
/// ([`CovarianceKind::Stated`]).
pub fn expected(
    model: &Model,
    params: &[f64],
    info: &DMatrix<f64>,
    wheel_moment: Option<&DMatrix<f64>>,
    opts: &IdentifyOptions,
) -> Identifiability {
    analyse_core(model, params, info, None, wheel_moment, opts)
}

fn analyse_core(
    model: &Model,
    params: &[f64],
    jtj: &DMatrix<f64>,
    moments: Option<&Moments>,
    wheel_moment: Option<&DMatrix<f64>>,
    opts: &IdentifyOptions,
) -> Identifiability {
    let n = jtj.ncols();
    let m = moments.map_or(0, |mo| mo.rows);
    let groups = moments.map_or(0, |mo| mo.scores.len());
    let specs = model.params();
    let scales = param_scales(model);
    let rr = moments.map_or(0.0, |mo| mo.rtr);
    let dof = m.saturating_sub(n).max(1) as f64;
    let s2 = if moments.is_some() { rr / dof } else { 1.0 };
    // The residual vector's squared norm is a mean over runs of the mean squared pose error (three
    // components), as `CalibrationProblem` stacks it.
    let residual_rms = (rr / 3.0).sqrt();

    // Scaled information D JᵀJ D = V S² Vᵀ: V's columns are directions, S the scaled Jacobian's singular
    // values. Non-finite sensitivities or residuals (a failed effect hook, a singular model) say nothing,
    // and an eigen-solver may not converge on them: everything is then reported undetermined, nothing held.
    let jtj_s = DMatrix::from_fn(n, n, |a, b| jtj[(a, b)] * scales[a] * scales[b]);
    let finite = moments.is_none_or(|mo| mo.finite) && jtj_s.iter().all(|v| v.is_finite());
    let eig = if finite { jtj_s.clone().try_symmetric_eigen(f64::EPSILON, 10_000) } else { None };
    let Some((sv, v)) = eig.map(|e| (e.eigenvalues.map(|l| l.max(0.0).sqrt()), e.eigenvectors)) else {
        return Identifiability {
            runs: groups,
            residuals: m,
            residual_rms: f64::NAN,
            covariance_kind: CovarianceKind::Iid,
            condition_number: f64::NAN,
            relative_singular_values: Vec::new(),
            params: specs
                .iter()
                .enumerate()
                .map(|(i, s)| ParamUncertainty {
                    name: s.name.clone(),
                    unit: s.unit.clone(),
                    value: params[i],
                    scale: scales[i],
                    std_error: None,
                    std_error_iid: None,
                })
                .collect(),
            covariance: Vec::new(),
            weak: Vec::new(),
        };
    };
    let mut order: Vec<usize> = (0..sv.len()).collect();
    order.sort_by(|&a, &b| sv[b].total_cmp(&sv[a]));
    let smax = order.first().map_or(0.0, |&k| sv[k]);
    let relative: Vec<f64> = order.iter().map(|&k| if smax > 0.0 { sv[k] / smax } else { 0.0 }).collect();

    // Per-run scores in scaled space, g_g = D J_gᵀ r_g, for the sandwich.
    let scores: Vec<DVector<f64>> = moments
        .map(|mo| mo.scores.iter().map(|g| DVector::from_fn(n, |i, _| g[i] * scales[i])).collect())
        .unwrap_or_default();
    let kind = if moments.is_none() {
        CovarianceKind::Stated
    } else if groups >= n + 2 {
        CovarianceKind::PerRun
    } else {
        CovarianceKind::Iid
    };
    let cr1 = if groups > 1 { groups as f64 / (groups - 1) as f64 * (m as f64 - 1.0) / dof } else { 1.0 };

    // Covariances in scaled space over the non-null directions: C = V S⁻² (Vᵀ B V) S⁻² Vᵀ.
    let alive: Vec<usize> = order.iter().copied().filter(|&k| sv[k] > opts.rcond * smax && smax > 0.0).collect();
    let va = DMatrix::from_fn(n, alive.len(), |r, c| v[(r, alive[c])]);
    let inv_s2 = DVector::from_iterator(alive.len(), alive.iter().map(|&k| 1.0 / (sv[k] * sv[k])));
    let mut b = DMatrix::zeros(alive.len(), alive.len());
    for g in &scores {
        let p = va.transpose() * g;
        b += &p * p.transpose();
    }
    b *= cr1;
    let robust_dir = DMatrix::from_fn(alive.len(), alive.len(), |a, c| inv_s2[a] * b[(a, c)] * inv_s2[c]);
    let iid_dir = DMatrix::from_diagonal(&inv_s2.map(|x| x * s2));
    let chosen_dir = match kind {
        CovarianceKind::PerRun => &robust_dir,
        CovarianceKind::Iid | CovarianceKind::Stated => &iid_dir,
    };

    // Unconstrained directions.
    let mut weak_k: Vec<(usize, Option<f64>)> = Vec::new();
    for &k in &order {
        match alive.iter().position(|&a| a == k) {
            None => weak_k.push((k, None)),
            Some(a) => {
                let se = chosen_dir[(a, a)].max(0.0).sqrt();
                if se > opts.max_std_error || sv[k] < opts.min_excitation * smax {
                    weak_k.push((k, Some(se)));
                }
            }
        }
    }
    // Directions that stay: covariance restricted to the constrained subspace.
    let strong: Vec<usize> = (0..alive.len()).filter(|&a| !weak_k.iter().any(|&(k, _)| k == alive[a])).collect();
    let vs = DMatrix::from_fn(n, strong.len(), |r, c| va[(r, strong[c])]);
    let sub = |c: &DMatrix<f64>| DMatrix::from_fn(strong.len(), strong.len(), |a, b| c[(strong[a], strong[b])]);
    let to_params = |c: &DMatrix<f64>| {
        let cs = &vs * sub(c) * vs.transpose();
        DMatrix::from_fn(n, n, |a, b| cs[(a, b)] * scales[a] * scales[b])
    };
    let cov = to_params(chosen_dir);
    let cov_iid = to_params(&iid_dir);
    let weak_loading = |i: usize| weak_k.iter().map(|&(k, _)| v[(i, k)].abs()).fold(0.0f64, f64::max);

    let uncertainties = specs
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let determined = weak_loading(i) < 0.1;
            ParamUncertainty {
                name: s.name.clone(),
                unit: s.unit.clone(),
                value: params[i],
                scale: scales[i],
                std_error: determined.then(|| cov[(i, i)].max(0.0).sqrt()),
                std_error_iid: determined.then(|| cov_iid[(i, i)].max(0.0).sqrt()),
            }
        })
        .collect();

    let weak = weak_k
        .iter()
        .map(|&(k, se)| {
            let dir: Vec<f64> = (0..n).map(|i| v[(i, k)]).collect();
            describe(model, params, &scales, dir, if smax > 0.0 { sv[k] / smax } else { 0.0 }, se, wheel_moment)
        })
        .collect();

    Identifiability {
        runs: groups,
        residuals: m,
        residual_rms,
        covariance_kind: kind,
        condition_number: if alive.len() == n && n > 0 {
            smax / sv[*alive.last().unwrap_or(&0)].max(f64::MIN_POSITIVE)
        } else {
            f64::INFINITY
        },
        relative_singular_values: relative,
        params: uncertainties,
        covariance: (0..n).map(|a| (0..n).map(|b| cov[(a, b)]).collect()).collect(),
        weak,
    }
}

/// Name a direction: its parameters, and for the base kinematics the wheel pattern and motion it needs.
fn describe(
    model: &Model,
    params: &[f64],
    scales: &[f64],
    mut dir: Vec<f64>,
    relative_singular_value: f64,
    std_error: Option<f64>,
    wheel_moment: Option<&DMatrix<f64>>,
) -> WeakDirection {
    // Sign convention: the largest component positive.
    let big = dir.iter().copied().fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
    if big < 0.0 {
        dir.iter_mut().for_each(|x| *x = -*x);
    }
    let specs = model.params();
    let top = dir.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let mut loadings: Vec<(String, f64)> = dir
        .iter()
        .enumerate()
        .filter(|(_, d)| d.abs() >= 0.3 * top)
        .map(|(i, d)| (specs[i].name.clone(), *d))
        .collect();
    loadings.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    let names: Vec<&str> = loadings.iter().map(|(n, _)| n.as_str()).collect();
    let same_sign = loadings.iter().all(|(_, d)| *d > 0.0);
    let who = match names.len() {
        1 => format!("{} is", names[0]),
        2 if same_sign => format!("{} and {} move together and are", names[0], names[1]),
        2 => format!("{} and {} trade off (one up, the other down) and are", names[0], names[1]),
        _ => {
            let signed: Vec<String> =
                loadings.iter().map(|(n, d)| format!("{}{n}", if *d > 0.0 { "+" } else { "−" })).collect();
            format!("the combination {} is", signed.join(" "))
        }
    };
    let how = match std_error {
        None => "not excited at all".to_string(),
        Some(se) => format!("poorly constrained (±{:.1} % of scale)", 100.0 * se),
    };
    let (wheel_pattern, motion, physical) = wheel_pattern(model, params, scales, &dir, wheel_moment);
    let mut text = format!("{who} {how}");
    if let Some(p) = &physical {
        text.push_str(&format!(": {p}"));
    }
    let present = wheel_pattern.as_ref().and_then(|u| pattern_share(u, wheel_moment)).is_some_and(|s| s >= 0.25);
    let advice = match &motion {
        Some(_) if present => {
            "fit the path objective (every ground-truth pose), or add runs along different paths".to_string()
        }
        Some(t) => format!("add runs {}", motion_words(t, model)),
        None => {
            let effects: Vec<String> = model
                .effects
                .iter()
                .zip(model.effect_ranges())
                .filter(|(_, r)| r.clone().any(|i| dir[i].abs() >= 0.3 * top))
                .map(|(e, _)| e.id().to_string())
                .collect();
            if effects.is_empty() {
                "add runs with other motions (see `omnical plan`)".into()
            } else {
                format!("add runs that exercise {} (see `omnical plan --effect …`)", effects.join(", "))
            }
        }
    };
    WeakDirection { direction: dir, loadings, relative_singular_value, std_error, wheel_pattern, motion, text, advice }
}

/// The change of the IK matrix along `dir` (scaled), its dominant wheel pattern, and that pattern's design
/// motion. `None` when the direction hardly touches the base kinematics.
fn wheel_pattern(
    model: &Model,
    params: &[f64],
    scales: &[f64],
    dir: &[f64],
    wheel_moment: Option<&DMatrix<f64>>,
) -> (Option<Vec<f64>>, Option<[f64; 3]>, Option<String>) {
    let nb = model.n_base();
    let base_share: f64 = dir[..nb].iter().map(|x| x * x).sum::<f64>();
    if base_share < 0.25 {
        return (None, None, None);
    }
    let Some(base) = model.kinematics.unexcited(&params[..nb], &dir[..nb], &scales[..nb]) else {
        return (None, None, None);
    };
    let (u, motion) = (base.wheel_pattern, base.motion);
    let lever = model.kinematics.lever_arm_m();
    let pattern: Vec<String> = u.iter().map(|x| format!("{x:+.2}")).collect();
    let wheels = model.kinematics.wheel_names();
    let named: Vec<String> = wheels.iter().zip(&pattern).map(|(w, p)| format!("{w} {p}")).collect();
    let moves = if moves_nowhere(model, &motion, lever) {
        "the wheels fighting each other, a pattern that moves the robot nowhere".to_string()
    } else {
        motion_name(&motion, lever)
    };
    let physical = match pattern_share(&u, wheel_moment) {
        Some(share) if share >= 0.25 => format!(
            "the runs contain the wheel-speed pattern ({}) — {} under the design matrix — ({:.0} % of the wheel motion), but the residuals barely respond to how the robot answers it",
            named.join(", "),
            moves,
            100.0 * share
        ),
        Some(share) => format!(
            "the runs hardly contain the wheel-speed pattern ({}) — {} under the design matrix — ({:.0} % of the wheel motion), so the robot's response to it is not measured",
            named.join(", "),
            moves,
            100.0 * share
        ),
        None => format!(
            "the robot's response to the wheel-speed pattern ({}) — {} under the design matrix — is not measured",
            named.join(", "),
            moves
        ),
    };
    (Some(u), Some(motion), Some(physical))
}

/// Whether the design twist of a unit wheel pattern (`motion`) is negligible: below 5 % of the largest
/// twist any unit wheel pattern gives under the design (translations in m/s and ω·lever in m/s compared
/// alike). With more wheels than degrees of freedom such patterns exist (the wheels push against each
/// other); a base with N ≤ 3 full-rank wheels has none.
fn moves_nowhere(model: &Model, motion: &[f64; 3], lever: f64) -> bool {
    let nominal: Vec<f64> = model.kinematics.params().iter().map(|s| s.null).collect();
    let Ok(design) = model.kinematics.twist_from_wheels(&nominal) else {
        return false;
    };
    let nw = design.n_wheels();
    let m = DMatrix::from_fn(3, nw, |r, c| design.entries()[r * nw + c] * if r == 2 { lever } else { 1.0 });
    let largest = m.singular_values().iter().copied().fold(0.0f64, f64::max);
    let size = (motion[0].powi(2) + motion[1].powi(2) + (motion[2] * lever).powi(2)).sqrt();
    largest > 0.0 && size < 0.05 * largest
}

/// RMS share of the wheel motion along the unit pattern `u`: `sqrt(uᵀ S u / tr S)`.
fn pattern_share(u: &[f64], wheel_moment: Option<&DMatrix<f64>>) -> Option<f64> {
    let s = wheel_moment?;
    if s.nrows() != u.len() || s.ncols() != u.len() {
        return None;
    }
    let uv = DVector::from_column_slice(u);
    let tr = s.trace();
    (tr > 0.0).then(|| ((uv.transpose() * s * &uv)[(0, 0)] / tr).max(0.0).sqrt())
}

/// The components of a design twist that matter, in words: "moving sideways (vy)" etc.
fn motion_parts(t: &[f64; 3], lever: f64) -> Vec<&'static str> {
    let key = [t[0].abs(), t[1].abs(), (t[2] * lever).abs()];
    let top = key.iter().copied().fold(0.0f64, f64::max);
    let mut parts = Vec::new();
    if key[0] >= 0.3 * top && top > 0.0 {
        parts.push("forward/backward (vx)");
    }
    if key[1] >= 0.3 * top && top > 0.0 {
        parts.push("sideways (vy)");
    }
    if key[2] >= 0.3 * top && top > 0.0 {
        parts.push("rotating (ω)");
    }
    parts
}

fn motion_name(t: &[f64; 3], lever: f64) -> String {
    let parts = motion_parts(t, lever);
    let translate: Vec<&str> = parts.iter().copied().filter(|p| !p.starts_with("rotating")).collect();
    let rotate = parts.len() > translate.len();
    match (translate.is_empty(), rotate) {
        (true, true) => "rotating on the spot (ω)".into(),
        (false, false) => format!("moving {}", translate.join(" and ")),
        (false, true) => format!("moving {} while rotating (ω)", translate.join(" and ")),
        (true, false) => "no motion".into(),
    }
}

/// Advice: which runs excite a motion.
fn motion_words(t: &[f64; 3], model: &Model) -> String {
    let lever = model.kinematics.lever_arm_m();
    let parts = motion_parts(t, lever);
    let translate: Vec<&str> = parts.iter().copied().filter(|p| !p.starts_with("rotating")).collect();
    let rotate = parts.iter().any(|p| p.starts_with("rotating"));
    let what = match (translate.is_empty(), rotate) {
        (true, true) => "turning on the spot in both directions (ω ≠ 0)".to_string(),
        (false, false) => format!("translating {} in both directions", translate.join(" and ")),
        (false, true) => format!("with ω ≠ 0 while translating {}", translate.join(" and ")),
        (true, false) => "with other motions".to_string(),
    };
    let alpha = t[1].atan2(t[0]).to_degrees();
    format!("{what} (e.g. a command along α ≈ {alpha:.0}°{})", if rotate { " with rotation" } else { "" })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use omni_kin::IkMatrix;

    /// A linear toy: residuals r = J x − y with a chosen J; the analysis must find the null direction.
    #[test]
    fn non_finite_input_is_undetermined_not_a_hang() {
        let model = Model::ik(IkMatrix::paper_design());
        let mut j = DMatrix::from_fn(30, 9, |r, c| ((r * 9 + c) as f64).sin());
        j[(3, 4)] = f64::NAN;
        let moments = Moments::from_dense(&j, &[0.0; 30], &[30]);
        let id = analyse(&model, &model.nominal(), &moments, None, &IdentifyOptions::default());
        assert!(id.weak.is_empty() && id.params.iter().all(|p| p.std_error.is_none()));
        assert!(id.condition_number.is_nan());
    }

    #[test]
    fn finds_a_null_direction_and_names_it() {
        let model = Model::ik(IkMatrix::paper_design());
        let n = 9;
        // Columns for m31, m32, m33 identical (only their sum is seen): two null directions among them.
        let m = 60;
        let j = DMatrix::from_fn(m, n, |r, c| {
            let x = (((r * 31 + c * 17) as f64 * 12.9898).sin() * 43758.5453).fract();
            if c >= 6 { (r as f64 * 0.11).cos() } else { x }
        });
        let r: Vec<f64> = (0..m).map(|i| 1e-4 * ((i * 7 % 11) as f64 - 5.0)).collect();
        let moments = Moments::from_dense(&j, &r, &[20, 20, 20]);
        let id = analyse(&model, &model.nominal(), &moments, None, &IdentifyOptions::default());
        assert_eq!(id.weak.len(), 2, "{:?}", id.weak.iter().map(|w| &w.text).collect::<Vec<_>>());
        for w in &id.weak {
            assert!(w.std_error.is_none());
            for (name, _) in &w.loadings {
                assert!(name.starts_with("m3"), "{}", w.text);
            }
        }
        assert!(id.condition_number.is_infinite());
        for p in &id.params[..6] {
            assert!(p.std_error.is_some());
        }
        for p in &id.params[6..] {
            assert!(p.std_error.is_none());
        }
    }
}
