//! A start rescaled to the ground truth's travel: when the start's dead reckoning goes or turns far more,
//! or less, than the ground truth (a wheel separation a quarter of the robot's, radii in the wrong unit,
//! a gear ratio left out), a local polish from it falls into a path that curls the wrong way. The
//! distance and turning ratios ([`omni_kin::travel::Travel`]) say by how much: the start's base parameters
//! are moved to the IK matrix whose translation rows are divided by the distance ratio and whose rotation
//! row by the turning ratio (the nearest in least squares, for a parametric base), and the fit starts from
//! there when that lowers the objective. The design stays the start every report compares with.

use nalgebra::{DMatrix, DVector};
use omni_kin::travel::Travel;
use omni_kin::{FittedModel, IkMatrix, Run};

/// Ground truth must have gone this far (m) to judge the distance ratio.
const MIN_DISTANCE_M: f64 = 1.0;
/// Ground truth must have turned this much (rad) to judge the turning ratio.
const MIN_TURNING_RAD: f64 = std::f64::consts::PI;
/// Ratios within this factor of 1 are a calibration's business: the start is kept.
const RESCALE_FACTOR: f64 = 1.3;
/// Gauss–Newton iterations of the projection onto a parametric base.
const ITERATIONS: usize = 50;

/// How the start was rescaled before fitting ([`crate::fit::Calibration::start_rescaled`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rescale {
    /// The start's dead-reckoned distance over the ground truth's (1 when it could not be told).
    pub distance_ratio: f64,
    /// The start's dead-reckoned turning over the ground truth's (1 when it could not be told).
    pub turning_ratio: f64,
}

/// `start` with its base parameters moved so that its dead reckoning travels and turns as far as the
/// ground truth of `runs`, when either ratio lies beyond [`RESCALE_FACTOR`]; `None` when both are within
/// it, cannot be told, or no parameters give the rescaled matrix.
pub(crate) fn rescaled_start(start: &FittedModel, runs: &[Run]) -> Option<(FittedModel, Rescale)> {
    let ik = start.ik().ok()?;
    let travel = Travel::of(runs, &ik);
    let d = travel.distance_ratio(MIN_DISTANCE_M).filter(|r| r.is_finite() && *r > 0.0);
    let t = travel.turning_ratio(MIN_TURNING_RAD).filter(|r| r.is_finite() && *r > 0.0);
    let off = |r: Option<f64>| r.is_some_and(|r| !(1.0 / RESCALE_FACTOR..=RESCALE_FACTOR).contains(&r));
    if !off(d) && !off(t) {
        return None;
    }
    let rescale = Rescale { distance_ratio: d.unwrap_or(1.0), turning_ratio: t.unwrap_or(1.0) };
    let n = ik.n_wheels();
    let target: Vec<f64> = ik
        .entries()
        .iter()
        .enumerate()
        .map(|(i, v)| if i / n == 2 { v / rescale.turning_ratio } else { v / rescale.distance_ratio })
        .collect();
    let base = nearest_base(start, &target)?;
    let mut params = start.params.clone();
    params[..base.len()].copy_from_slice(&base);
    Some((FittedModel { model: start.model.clone(), params }, rescale))
}

/// The base parameters whose IK matrix is nearest `target` (row-major entries), by damped Gauss–Newton
/// from the start's with central differences: one step for a free matrix, a few for a parametric base.
fn nearest_base(start: &FittedModel, target: &[f64]) -> Option<Vec<f64>> {
    let n_base = start.model.n_base();
    let kin = &start.model.kinematics;
    let entries = |p: &[f64]| kin.twist_from_wheels(p).ok().map(|m: IkMatrix| m.entries().to_vec());
    let residual = |p: &[f64]| -> Option<DVector<f64>> {
        let e = entries(p)?;
        Some(DVector::from_iterator(e.len(), e.iter().zip(target).map(|(a, b)| a - b)))
    };
    let mut p = start.params[..n_base].to_vec();
    let mut r = residual(&p)?;
    let mut damping = 1e-9;
    for _ in 0..ITERATIONS {
        let mut jac = DMatrix::zeros(r.len(), n_base);
        for j in 0..n_base {
            let h = 1e-6 * p[j].abs().max(1e-3);
            let (mut up, mut down) = (p.clone(), p.clone());
            up[j] += h;
            down[j] -= h;
            let column = (residual(&up)? - residual(&down)?) / (2.0 * h);
            jac.set_column(j, &column);
        }
        let normal = jac.transpose() * &jac;
        let gradient = jac.transpose() * &r;
        let scale = DMatrix::from_diagonal(&normal.diagonal().map(|v| v.max(1e-12)));
        let step = (&normal + &scale * damping).lu().solve(&(-gradient))?;
        let tried: Vec<f64> = p.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
        match residual(&tried) {
            Some(rt) if rt.norm() < r.norm() => {
                let done = r.norm() - rt.norm() <= 1e-12 * (1.0 + r.norm());
                (p, r) = (tried, rt);
                damping = (damping / 10.0).max(1e-12);
                if done {
                    break;
                }
            }
            _ => damping *= 10.0,
        }
        if damping > 1e6 {
            break;
        }
    }
    p.iter().all(|v| v.is_finite()).then_some(p)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use omni_kin::simulate::{SimConfig, simulate};
    use omni_kin::{IkMatrix, KinematicsKind, Model, RobotGeometry};

    /// A differential drive (r 0.033 m, b 0.287 m) simulated, and its start with the separation a quarter.
    fn quarter_separation() -> (FittedModel, FittedModel, Vec<Run>) {
        let truth_geometry = RobotGeometry::diff_drive(0.033, 0.033, 0.287);
        let kind = KinematicsKind::Diff;
        let truth = FittedModel::nominal(Model::design(kind, Some(&truth_geometry)).unwrap());
        let cfg = SimConfig { duration_s: 3.0, runs_per_command: 1, ..SimConfig::for_robot(truth_geometry) };
        let runs = simulate(&cfg, &truth, "q/").unwrap();
        let narrow = RobotGeometry::diff_drive(0.033, 0.033, 0.287 / 4.0);
        let start = FittedModel::nominal(Model::design(kind, Some(&narrow)).unwrap());
        (truth, start, runs)
    }

    #[test]
    fn a_quarter_separation_is_rescaled_to_the_robots() {
        let (truth, start, runs) = quarter_separation();
        let (rescaled, how) = rescaled_start(&start, &runs).unwrap();
        // The ground truth's noise (2 mm, 3 mrad a pose) lengthens its path a little: a start, not a fit.
        assert!((how.distance_ratio - 1.0).abs() < 0.1, "{how:?}");
        assert!((how.turning_ratio / 4.0 - 1.0).abs() < 0.1, "{how:?}");
        let (got, want) = (rescaled.ik().unwrap(), truth.ik().unwrap());
        for (g, w) in got.entries().iter().zip(want.entries()) {
            assert!((g - w).abs() <= 0.1 * w.abs().max(1e-3), "{:?} against {:?}", got.entries(), want.entries());
        }
    }

    #[test]
    fn a_start_near_the_robot_is_kept() {
        let (truth, _, runs) = quarter_separation();
        assert!(rescaled_start(&truth, &runs).is_none());
    }

    #[test]
    fn a_free_matrix_in_rpm_is_divided_row_by_row() {
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let cfg = SimConfig { duration_s: 3.0, runs_per_command: 1, ..SimConfig::default() };
        let runs = simulate(&cfg, &truth, "f/").unwrap();
        let rpm = 60.0 / std::f64::consts::TAU;
        let scaled: Vec<f64> = IkMatrix::paper_calibrated().entries().iter().map(|v| v * rpm).collect();
        let start = FittedModel::nominal(Model::ik(IkMatrix::new(3, scaled).unwrap()));
        let (rescaled, how) = rescaled_start(&start, &runs).unwrap();
        assert!((how.distance_ratio / rpm - 1.0).abs() < 0.1 && (how.turning_ratio / rpm - 1.0).abs() < 0.1, "{how:?}");
        let (got, want) = (rescaled.ik().unwrap(), truth.ik().unwrap());
        for (g, w) in got.entries().iter().zip(want.entries()) {
            assert!((g - w).abs() <= 0.1 * w.abs().max(1e-3), "{:?} against {:?}", got.entries(), want.entries());
        }
    }
}
