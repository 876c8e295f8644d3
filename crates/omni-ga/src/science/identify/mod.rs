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
//!   they are in odometry. It needs more clusters than parameters (`p + 2`): with fewer runs, each run is
//!   cut by time into segments of at least [`MIN_SEGMENT_S`] (a few long runs — a square, a circle, a
//!   figure-eight — become a dozen or more clusters; [`segment_poses`]); with still too few clusters the
//!   iid estimate is used (and said).
//! - **Unconstrained directions**: `v_k` whose standard error (in fraction of scale) exceeds
//!   `max_std_error` (default 5 % of scale: the data cannot pin that combination to better than the size of
//!   a typical calibration correction), or — when the standard error is not the per-run (cluster) estimate
//!   and so not to be trusted alone — whose `s_k` is below `min_excitation · s_max` (default 1 %: the
//!   residuals respond to it 100× less than to the best-excited direction). A direction whose per-run
//!   standard error is small is never unconstrained, however weakly it is excited against the others (a
//!   wheel-radius difference against the wheel separation). Each is named by the
//!   parameters that carry it ("m21 and m22 move together"); for the base kinematics, the direction is
//!   mapped to a change of the IK matrix `ΔM`, whose dominant wheel-speed pattern `u` (`ΔM ≈ a uᵀ`) is
//!   the pattern the runs hardly contain, and whose motion under the design matrix (`M₀ u`) says which
//!   runs to add ("add runs moving sideways (vy ≠ 0)").
//!
//! Pure computation: no I/O.

mod analysis;
mod direction;
mod moments;

pub use moments::{ANCHOR_SHARE, MIN_SEGMENT_S, Moments, ROWS_PER_POSE, column_std_errors, segment_poses};

use crate::science::text;
use nalgebra::DMatrix;
use omni_kin::Model;
use serde::{Deserialize, Serialize};

/// Share of an unconstrained direction (unit vector in scaled space) from which a parameter counts as part
/// of it: it then has no standard error, and the truncated update holds it.
pub const WEAK_LOADING: f64 = 0.1;

/// Settings of the analysis (scaled units: fractions of each parameter's scale).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdentifyOptions {
    /// A direction whose standard error exceeds this fraction of the parameters' scale is unconstrained.
    /// Default 0.05.
    pub max_std_error: f64,
    /// Without the per-run (cluster) standard errors, a direction whose singular value is below this
    /// fraction of the largest is unconstrained: the runs move the residuals along it 100× less than along
    /// the best-excited direction, and an iid (or stated-noise) standard error alone is no basis for
    /// trusting it. With per-run standard errors, `max_std_error` alone decides. Default 0.01.
    pub min_excitation: f64,
    /// Singular values below `rcond · s_max` are treated as zero (not excited at all). Default 1e-7 (the
    /// analysis works on `JᵀJ`, whose eigenvalues are the squares).
    pub rcond: f64,
    /// The fit's start (parameter units), when the analysis judges a fit against it: an excited direction
    /// along which the fit lies more than [`START_REJECTED_SIGMAS`] standard errors from the start is
    /// constrained whatever its standard error (the data reject the start along it: a metric reference's
    /// scale against a design 2× off), so it is given a standard error and not held there. `None`: the
    /// standard error and the excitation alone decide. Default `None`.
    #[serde(skip)]
    pub start: Option<Vec<f64>>,
}

/// A direction along which the fit lies more than this many standard errors from its start is constrained
/// ([`IdentifyOptions::start`]): the data reject the start at about 95 %.
pub const START_REJECTED_SIGMAS: f64 = 2.0;

impl Default for IdentifyOptions {
    fn default() -> Self {
        Self { max_std_error: 0.05, min_excitation: 0.01, rcond: 1e-7, start: None }
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
    /// The direction in words ([`crate::science::text::weak_direction`], from the fields above and
    /// `evidence`).
    pub text: String,
    /// Which runs to add, in words ([`crate::science::text::advice`], from `remedy`).
    pub advice: String,
    /// What the runs say about the wheel pattern, when the direction changes the base kinematics.
    #[serde(skip)]
    pub evidence: Option<WheelEvidence>,
    /// What would constrain the direction.
    #[serde(skip)]
    pub remedy: Advice,
}

/// The notable components of a design motion (at least 30 % of the largest; the turn rate weighted by a
/// typical wheel lever arm).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MotionParts {
    /// Forward/backward (vx).
    pub forward: bool,
    /// Sideways (vy).
    pub sideways: bool,
    /// Rotating (ω).
    pub rotating: bool,
}

/// How much of the runs' wheel motion lies along a wheel-speed pattern (the RMS share, 0…1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PatternPresence {
    /// The runs contain it (at least 25 % of the wheel motion), but the residuals barely respond to it.
    Present(f64),
    /// The runs hardly contain it (less than 25 %).
    Scarce(f64),
    /// Unknown: the runs' wheel speeds were not given (planning).
    Unknown,
}

/// The base-kinematics side of an unconstrained direction.
#[derive(Clone, Debug, PartialEq)]
pub struct WheelEvidence {
    /// The wheels' names, in the order of [`WeakDirection::wheel_pattern`].
    pub wheels: Vec<String>,
    /// The notable components of the pattern's design motion ([`WeakDirection::motion`]).
    pub motion: MotionParts,
    /// Whether the runs contain the pattern.
    pub presence: PatternPresence,
    /// Whether the pattern's design twist is negligible (below 5 % of the largest any unit pattern gives):
    /// with more wheels than degrees of freedom, the wheels fighting each other.
    pub moves_nowhere: bool,
}

/// What would constrain an unconstrained direction.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Advice {
    /// The runs contain the motion but the objective does not see it: fit the path objective, or add runs
    /// along different paths.
    PathObjective,
    /// Add runs with this motion (a command along `alpha_deg`).
    AddRuns {
        /// The motion's notable components.
        motion: MotionParts,
        /// Direction of travel of the motion. deg.
        alpha_deg: f64,
    },
    /// Nothing: the wheel pattern moves the robot nowhere (the wheels fighting each other), no command asks
    /// for it, and the fit holds it at the design.
    HeldAtDesign,
    /// Add runs with other motions (the direction touches neither the base kinematics nor an effect).
    #[default]
    OtherMotions,
    /// Add runs that exercise these effects (ids).
    ExerciseEffects(Vec<String>),
    /// Nothing: the parameters enter the kinematics only together, so no run can separate them; read
    /// them as one combination (a mecanum base's `lx` and `ly`, of which only `lx + ly` counts).
    OneCombination(Combination),
}

/// Parameters of the base kinematics that enter the IK matrix only through one combination: along the
/// unconstrained direction the matrix does not change at all, whatever the runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Combination {
    /// The parameters, in parameter order.
    pub names: Vec<String>,
    /// Their unit (the first parameter's).
    pub unit: String,
    /// With two parameters `a`, `b`: the coefficients `(1, k)` of the combination `a + k b` that counts
    /// (orthogonal to the direction in parameter units), and its value at the fit. `None` with more.
    pub sum: Option<([f64; 2], f64)>,
}

/// The identifiability of a model on a set of runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Identifiability {
    /// Runs.
    pub runs: usize,
    /// Clusters of the per-run standard errors: the runs, or their segments by time when the runs are
    /// too few ([`segment_poses`]).
    #[serde(default)]
    pub clusters: usize,
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
        self.weak.iter().map(text::warning).collect()
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
    analysis::analyse_core(model, params, &moments.jtj, Some(moments), wheel_moment, opts)
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
    analysis::analyse_core(model, params, info, None, wheel_moment, opts)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use nalgebra::DVector;
    use omni_kin::IkMatrix;

    #[test]
    fn segments_cut_few_long_runs_and_their_scores_sum_to_the_run_score() {
        // Three 30 s runs at 120 Hz, 4 parameters (fewer than 4 + 2 runs): six segments of 5 s each.
        let times: Vec<Vec<f64>> = (0..3).map(|_| (0..=3600).map(|i| i as f64 / 120.0).collect()).collect();
        let cut = segment_poses(&times, 4);
        assert_eq!(cut, vec![vec![600, 600, 600, 600, 600, 601]; 3]);
        // Enough runs: one cluster each; a short run stays whole.
        assert_eq!(segment_poses(&times, 1), vec![vec![3601]; 3]);
        assert_eq!(segment_poses(&[vec![0.0, 1.0, 2.0]], 4), vec![vec![3]]);
        // The anchored segment scores sum to Jᵀ r (a random walk as residual: the score must not change).
        let poses = 40;
        let j = DMatrix::from_fn(3 * poses, 4, |r, c| ((r * 7 + c * 3) as f64 * 0.37).sin());
        let mut walk = 0.0;
        let r: Vec<f64> = (0..3 * poses)
            .map(|i| {
                walk += ((i * 13 % 7) as f64 - 3.0) * 1e-3;
                walk
            })
            .collect();
        let mut whole = Moments::new(4);
        whole.add_run(&j, &r);
        let mut cut = Moments::new(4);
        cut.add_run_segments(&j, &r, &[30, 30, 30]);
        assert_eq!((cut.scores.len(), cut.runs, cut.rows), (4, 1, 3 * poses));
        let sum = cut.scores.iter().fold(DVector::zeros(4), |a, s| a + s);
        assert!((&sum - &whole.scores[0]).norm() < 1e-12 * whole.scores[0].norm(), "{sum} vs {}", whole.scores[0]);
        assert_eq!(cut.jtj, whole.jtj);
    }

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
