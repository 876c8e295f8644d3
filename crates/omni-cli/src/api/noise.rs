//! How far to trust the odometry (issue 46) in the front ends: `train` fits the noise model on its
//! training runs ([`omni_kin::noise::fit`]) and writes it into the model file (`[noise]`, and `noise` in
//! the `--json` summary); `eval` checks it on the runs it is given, beside the stock defaults; `export
//! --robot-config` writes it where the ROS stack reads it ([`crate::robot_config`]).

use omni_kin::evaluate::{Evaluator, RunErrors};
use omni_kin::noise::{self, Amcl, Coverage, FitNoiseOptions, Horizon, OdometryNoise, Predictor, RunPoses};
use omni_kin::{FittedModel, KinError, KinematicsKind, Run, Selection};
use serde_json::json;

/// Coverage of the 95 % ellipse below which the model says it trusts the odometry too much.
pub const COVERAGE_LOW: f64 = 0.90;
/// Coverage above which the model says it is too cautious.
pub const COVERAGE_HIGH: f64 = 0.98;

/// Whether the fitted base moves sideways on command (its matrix has a vy row): its odometry strafes. A
/// differential or skid-steer model never does: a skid-steer base's sideways slip follows its turning
/// (`vy = −x_icr ω`), it is not a direction of its own.
pub fn holonomic(fitted: &FittedModel) -> bool {
    match fitted.model.kinematics.kind() {
        KinematicsKind::Diff | KinematicsKind::Skid => false,
        _ => fitted.ik().is_ok_and(|m| m.row(1).iter().any(|v| v.abs() > 1e-12)),
    }
}

/// ros2_controllers' stock pose covariance diagonal (position entries) for the base's controller: 0.1 for
/// mecanum_drive_controller, zeros for diff_drive_controller and omni_wheel_drive_controller. m².
pub fn stock_pose_variance_m2(fitted: &FittedModel) -> f64 {
    if fitted.model.kinematics.kind() == KinematicsKind::Mecanum { 0.1 } else { 0.0 }
}

/// The ground truth and `fitted`'s odometry at the same stamps, for each run.
fn poses(fitted: &FittedModel, runs: &[Run]) -> Result<Vec<RunPoses>, KinError> {
    let errors =
        Evaluator::for_report(&fitted.model, runs, Selection::Path(1))?.errors(&fitted.model.resolve(&fitted.params)?);
    noise::run_poses(runs, &errors)
}

/// Why a fit has no noise model.
#[derive(Debug, thiserror::Error)]
pub enum NoNoise {
    /// The reference measures no heading: the noise model's heading and turning terms need one.
    #[error("the reference gives positions only, and the noise model's heading terms need a measured heading")]
    PositionOnly,
    /// The runs are too short to fit it.
    #[error(transparent)]
    Fit(#[from] noise::NoiseFitError),
}

/// The noise model of `fitted`'s odometry on its training runs: `Ok(Err(_))` when the runs cannot give one
/// (the model file then has none; `train` says why). `train` and `diagnose --out` fit it here.
pub fn fit(fitted: &FittedModel, runs: &[Run]) -> Result<Result<OdometryNoise, NoNoise>, KinError> {
    if runs.iter().any(Run::truth_position_only) {
        return Ok(Err(NoNoise::PositionOnly));
    }
    Ok(noise::fit(&poses(fitted, runs)?, holonomic(fitted), &FitNoiseOptions::default()).map_err(NoNoise::from))
}

/// Adds the noise model of a fit to `train`'s summary `s` (`noise`, which the model file holds as `[noise]`),
/// or a warning when it cannot be fitted.
pub fn add_to_summary(s: &mut serde_json::Value, fitted: &FittedModel, runs: &[Run]) -> Result<(), KinError> {
    match fit(fitted, runs)? {
        Ok(n) => s["noise"] = serde_json::to_value(&n).unwrap_or_default(),
        Err(e) => {
            if let Some(list) = s["warnings"].as_array_mut() {
                list.push(json!(format!("no odometry noise model: {e}")));
            }
        }
    }
    Ok(())
}

/// The noise model in `train`'s summary, as the model file holds it.
pub fn from_summary(s: &serde_json::Value) -> Option<OdometryNoise> {
    serde_json::from_value(s.get("noise")?.clone()).ok()
}

/// The fitted model's check and the stock defaults' on the runs `errors` were taken on (an evaluator at
/// [`Selection::Path`]`(1)`): fitted first, then ros2_controllers', then Nav2 AMCL's.
pub fn check(
    n: &OdometryNoise,
    fitted: &FittedModel,
    runs: &[Run],
    errors: &RunErrors,
) -> Result<Vec<Coverage>, KinError> {
    let poses = noise::run_poses(runs, errors)?;
    let mut out = vec![noise::coverage(&poses, n.holonomic, "fitted", &Predictor::Rates(n.rates))];
    for (label, p) in noise::stock_defaults(&n.rates, n.holonomic, stock_pose_variance_m2(fitted)) {
        out.push(noise::coverage(&poses, n.holonomic, &label, &p));
    }
    Ok(out)
}

/// What is wrong with a fitted model's coverage at 1 m or 5 m, in words (`None`: within 90–98 %).
pub fn verdict(n: &OdometryNoise, fitted: &Coverage) -> Option<String> {
    let off: Vec<String> = fitted
        .horizons
        .iter()
        .filter(|h| matches!(h.horizon, Horizon::DistanceM(_)) && h.windows > 0)
        .filter(|h| !(COVERAGE_LOW..=COVERAGE_HIGH).contains(&h.coverage))
        .map(|h| format!("{:.1} % at {}", 100.0 * h.coverage, horizon_text(h.horizon)))
        .collect();
    if off.is_empty() {
        return None;
    }
    let low = fitted.horizons.iter().any(|h| h.windows > 0 && h.coverage < COVERAGE_LOW);
    let why = if low {
        format!(
            "the errors on these runs are larger than the noise model allows: usually a systematic error the \
             calibrated model still misses (on the training runs {:.0} % of the position error was systematic); \
             `omnical diagnose` names it, and `train --effect` fits it",
            100.0 * n.systematic.position_share
        )
    } else {
        "the noise model is too cautious on these runs: their errors are smaller than the training runs' (a \
         noisier training set, a ground truth less noisy here, or paths that close on themselves, such as squares \
         driven round, over which a direction-dependent error cancels where the odometry's noise would not)"
            .to_string()
    };
    Some(format!(
        "coverage of the 95 % ellipse is {} (outside {:.0}–{:.0} %): {why}",
        off.join(" and "),
        100.0 * COVERAGE_LOW,
        100.0 * COVERAGE_HIGH
    ))
}

/// `1 m`, `5 m` or `the run's end`.
pub fn horizon_text(h: Horizon) -> String {
    match h {
        Horizon::DistanceM(d) => format!("{d} m"),
        Horizon::RunEnd => "the run's end".to_string(),
    }
}

/// The checks as JSON: per predictor, per horizon (`distance_m`: null at the run's end).
pub fn coverage_json(checks: &[Coverage]) -> serde_json::Value {
    checks
        .iter()
        .map(|c| {
            let horizons: Vec<_> = c
                .horizons
                .iter()
                .map(|h| {
                    let d = match h.horizon {
                        Horizon::DistanceM(d) => Some(d),
                        Horizon::RunEnd => None,
                    };
                    let finite = |v: f64| v.is_finite().then_some(v);
                    json!({ "distance_m": d, "windows": h.windows, "coverage": finite(h.coverage), "nees": finite(h.nees) })
                })
                .collect();
            json!({ "predictor": c.predictor, "horizons": horizons })
        })
        .collect()
}

/// AMCL's alphas of a noise model at Nav2's default update thresholds.
pub fn amcl(n: &OdometryNoise) -> Amcl {
    Amcl::from_rates(&n.rates, n.holonomic, noise::AMCL_UPDATE_MIN_D_M, noise::AMCL_UPDATE_MIN_A_RAD)
}

/// The noise model in one line: the rates as standard deviations per metre and per radian, AMCL's alphas.
pub fn describe(n: &OdometryNoise) -> String {
    let r = &n.rates;
    let a = amcl(n);
    let alphas: Vec<String> = a.alpha.iter().map(|x| format!("{x:.3e}")).collect();
    format!(
        "odometry noise (fitted on {} windows of {} runs): along {:.2} cm/√m, across {:.2} cm/√m, heading {:.3}°/√m \
         and {:.3}°/√rad; from run to run the distance scale varies by {:.2} %, the heading drift by {:.3}°/m \
         and the turn scale by {:.2} %, and the heading wanders by {:.2}°; Nav2 AMCL alpha1…5 = {} (update_min_d \
         {} m, update_min_a {} rad; the run-to-run and wandering parts are not in them)",
        n.windows,
        n.runs,
        100.0 * r.trans_per_m.sqrt(),
        100.0 * r.strafe_per_m.sqrt(),
        r.rot_per_m.sqrt().to_degrees(),
        r.rot_per_rad.sqrt().to_degrees(),
        100.0 * r.run_scale_var.sqrt(),
        r.run_drift_var.sqrt().to_degrees(),
        100.0 * r.run_turn_scale_var.sqrt(),
        r.heading_wander_rad2.sqrt().to_degrees(),
        alphas.join(", "),
        a.update_min_d_m,
        a.update_min_a_rad
    )
}
