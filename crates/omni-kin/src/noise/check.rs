//! Checking a noise model on held-out runs: at horizons of driven distance (1 m, 5 m) and at each run's
//! end, the share of windows whose position error lies inside the predicted 95 % ellipse, and the
//! normalised estimation error squared (NEES, `eᵀ Σ⁻¹ e` of the position, 2 on average for a true model).
//!
//! A window starts at a ground-truth pose (starts at least [`START_STRIDE_M`] of motion apart) and ends at
//! the first pose whose driven distance along the ground truth reaches the horizon; the run's-end window
//! goes from the first pose to the last. Its predicted covariance is the noise model's along the window's
//! odometry ([`super::window_basis`]), the ground-truth floor included.
//!
//! The stock defaults are judged the same way ([`stock_defaults`]): ros2_controllers' fixed pose
//! covariance diagonal (zeros for diff_drive and omni_wheel_drive, 0.1 for mecanum_drive: it never grows)
//! and Nav2 AMCL's default `alpha1`…`alpha5` = 0.2 at its default update thresholds; each with the same
//! floor, so only the odometry's part differs.

use super::{
    AMCL_DEFAULT_ALPHA, AMCL_UPDATE_MIN_A_RAD, AMCL_UPDATE_MIN_D_M, Amcl, NoiseRates, RunPoses, covariance,
    window_basis, window_error,
};
use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

/// The driven distances the check reports. m.
pub const HORIZONS_M: [f64; 2] = [1.0, 5.0];
/// Least motion between the starts of two windows (m, turns counted as in the fit). m.
pub const START_STRIDE_M: f64 = 0.1;
/// `χ²` of 2 degrees of freedom at 95 %: `−2 ln 0.05`.
pub const CHI2_2DOF_95: f64 = 5.991_464_547_107_979;

/// Where a window ends.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Horizon {
    /// After this distance driven (ground truth). m.
    DistanceM(f64),
    /// At the run's last ground-truth pose, from its first.
    RunEnd,
}

/// The check at one horizon.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HorizonCheck {
    /// The horizon.
    pub horizon: Horizon,
    /// Windows judged.
    pub windows: usize,
    /// Share of windows inside the 95 % ellipse (0…1; NaN without windows).
    pub coverage: f64,
    /// Mean position NEES (2 for a true model; infinite when the covariance is zero).
    pub nees: f64,
}

/// A predictor's checks at every horizon.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coverage {
    /// What predicted the covariance (`fitted`, `ros2_controllers`, `nav2_amcl`).
    pub predictor: String,
    /// One per horizon: [`HORIZONS_M`], then the run's end.
    pub horizons: Vec<HorizonCheck>,
}

/// How a window's covariance is predicted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Predictor {
    /// A noise model's rates (and floor).
    Rates(NoiseRates),
    /// A fixed pose covariance (position variance per axis, m²) plus the floor: ros2_controllers'.
    Fixed {
        /// Position variance per axis. m².
        position_m2: f64,
        /// The ground-truth floor (position variance per axis at each end). m².
        floor_position_m2: f64,
    },
}

/// The stock defaults for a base: ros2_controllers' fixed diagonal (`stock_pose_variance_m2`: 0, or 0.1 for
/// mecanum_drive) and Nav2 AMCL's defaults, each with `fitted`'s floor.
pub fn stock_defaults(fitted: &NoiseRates, holonomic: bool, stock_pose_variance_m2: f64) -> [(String, Predictor); 2] {
    let amcl = Amcl {
        alpha: [AMCL_DEFAULT_ALPHA; 5],
        update_min_d_m: AMCL_UPDATE_MIN_D_M,
        update_min_a_rad: AMCL_UPDATE_MIN_A_RAD,
    };
    let rates = NoiseRates {
        floor_position_m2: fitted.floor_position_m2,
        floor_heading_rad2: fitted.floor_heading_rad2,
        ..amcl.to_rates(holonomic)
    };
    [
        (
            "ros2_controllers".to_string(),
            Predictor::Fixed { position_m2: stock_pose_variance_m2, floor_position_m2: fitted.floor_position_m2 },
        ),
        ("nav2_amcl".to_string(), Predictor::Rates(rates)),
    ]
}

/// The window end for a start `i` at `horizon`, by the ground truth's driven distance.
fn window_end(run: &RunPoses, i: usize, horizon: Horizon) -> Option<usize> {
    match horizon {
        Horizon::RunEnd => (i == 0 && run.truth.len() > 1).then(|| run.truth.len() - 1),
        Horizon::DistanceM(h) => {
            let mut d = 0.0;
            for k in i + 1..run.truth.len() {
                d += (run.truth[k].x_m - run.truth[k - 1].x_m).hypot(run.truth[k].y_m - run.truth[k - 1].y_m);
                if d >= h {
                    return Some(k);
                }
            }
            None
        }
    }
}

/// Window starts at least [`START_STRIDE_M`] of odometry motion apart.
fn starts(run: &RunPoses) -> Vec<usize> {
    let mut out = vec![0];
    let mut s = 0.0;
    for k in 1..run.odometry.len() {
        let u = super::between(&run.odometry[k - 1], &run.odometry[k]);
        s += u.x_m.hypot(u.y_m) + super::fit::TURN_LEVER_M * u.theta_rad.abs();
        if s >= START_STRIDE_M {
            out.push(k);
            s = 0.0;
        }
    }
    out
}

/// The position error and its predicted 2 × 2 covariance for the window `i → j`.
fn judged(run: &RunPoses, i: usize, j: usize, predictor: &Predictor, holonomic: bool) -> (Vector2<f64>, Matrix2<f64>) {
    let e = window_error(run, i, j);
    let s = match predictor {
        Predictor::Rates(rates) => {
            let c = covariance(&window_basis(run, i, j, holonomic), rates);
            Matrix2::new(c[(0, 0)], c[(0, 1)], c[(1, 0)], c[(1, 1)])
        }
        Predictor::Fixed { position_m2, floor_position_m2 } => {
            Matrix2::identity() * (position_m2 + 2.0 * floor_position_m2)
        }
    };
    (Vector2::new(e[0], e[1]), s)
}

/// The check of one predictor on held-out runs at [`HORIZONS_M`] and the run's end.
pub fn coverage(runs: &[RunPoses], holonomic: bool, label: &str, predictor: &Predictor) -> Coverage {
    let horizons: Vec<Horizon> =
        HORIZONS_M.iter().map(|&h| Horizon::DistanceM(h)).chain(std::iter::once(Horizon::RunEnd)).collect();
    let horizons = horizons
        .into_iter()
        .map(|horizon| {
            let (mut n, mut inside, mut nees) = (0usize, 0usize, 0.0);
            for run in runs {
                for i in starts(run) {
                    let Some(j) = window_end(run, i, horizon) else { continue };
                    let (e, s) = judged(run, i, j, predictor, holonomic);
                    let m2 = s.try_inverse().map_or(f64::INFINITY, |inv| e.dot(&(inv * e)));
                    n += 1;
                    inside += usize::from(m2 <= CHI2_2DOF_95);
                    nees += m2;
                }
            }
            let share = if n == 0 { f64::NAN } else { inside as f64 / n as f64 };
            HorizonCheck { horizon, windows: n, coverage: share, nees: if n == 0 { f64::NAN } else { nees / n as f64 } }
        })
        .collect();
    Coverage { predictor: label.to_string(), horizons }
}
