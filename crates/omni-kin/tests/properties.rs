//! Property tests of the kinematics core.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use omni_kin::effect::{CATALOGUE, Effect};
use omni_kin::odometry::{Selection, residuals};
use omni_kin::{EffectKind, FittedModel, IkMatrix, Model, Pose2, Run, RunData, StampedPose};
use proptest::prelude::*;

fn run_from(wheels: &[[f64; 3]], start: Pose2) -> Run {
    let n = wheels.len();
    let wheel_t_s: Vec<f64> = (0..n).map(|k| 0.01 * (k + 1) as f64).collect();
    Run::new(RunData {
        name: "p".into(),
        wheel_t_s,
        wheel_rad_s: wheels.iter().flatten().copied().collect(),
        n_wheels: 3,
        truth: vec![
            StampedPose { t_s: 0.01, pose: start },
            StampedPose { t_s: 0.01 * n as f64 / 2.0, pose: start },
            StampedPose { t_s: 0.01 * n as f64, pose: start },
        ],
        wheel_start_rad: vec![0.3, 1.0, 2.0],
        ..RunData::default()
    })
    .unwrap()
}

fn predicted(f: &FittedModel, run: &Run) -> Vec<Pose2> {
    let res = f.model.resolve(&f.params).unwrap();
    residuals(&res, run, Selection::Path(1)).iter().map(|r| r.predicted).collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// An effect at its null parameters leaves the trajectory bit-identical.
    #[test]
    fn null_effects_change_nothing(wheels in prop::collection::vec(prop::array::uniform3(-3.0f64..3.0), 10..60)) {
        let run = run_from(&wheels, Pose2::new(0.2, -0.1, 0.4));
        let base = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
        let reference = predicted(&base, &run);
        for id in CATALOGUE.iter().filter(|id| **id != "sample_timing") {
            let with = base.with_effect(EffectKind::from_id(id, 3).unwrap());
            let got = predicted(&with, &run);
            for (a, b) in got.iter().zip(&reference) {
                prop_assert_eq!(a.x_m.to_bits(), b.x_m.to_bits(), "{}", id);
                prop_assert_eq!(a.y_m.to_bits(), b.y_m.to_bits(), "{}", id);
                prop_assert_eq!(a.theta_rad.to_bits(), b.theta_rad.to_bits(), "{}", id);
            }
            prop_assert_eq!(with.model.effects[0].id(), *id);
        }
    }

    /// Moving the start pose moves the whole odometry path rigidly.
    #[test]
    fn start_pose_moves_path_rigidly(
        wheels in prop::collection::vec(prop::array::uniform3(-3.0f64..3.0), 10..60),
        x in -5.0f64..5.0, y in -5.0f64..5.0, th in -3.0f64..3.0,
    ) {
        let f = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let at_origin = predicted(&f, &run_from(&wheels, Pose2::IDENTITY));
        let moved_start = Pose2::new(x, y, th);
        let moved = predicted(&f, &run_from(&wheels, moved_start));
        for (a, b) in at_origin.iter().zip(&moved) {
            let expect = moved_start.compose(a);
            prop_assert!((expect.x_m - b.x_m).abs() < 1e-9);
            prop_assert!((expect.y_m - b.y_m).abs() < 1e-9);
            prop_assert!((expect.theta_rad - b.theta_rad).abs() < 1e-9);
        }
    }
}

/// A run with the given wheel samples (stamps 10 ms apart from 0.01 s) whose ground truth is `truth`
/// at the given sample indices.
fn run_with_truth(wheels: &[[f64; 3]], truth: Vec<StampedPose>) -> Run {
    Run::new(RunData {
        name: "p".into(),
        wheel_t_s: (0..wheels.len()).map(|k| 0.01 * (k + 1) as f64).collect(),
        wheel_rad_s: wheels.iter().flatten().copied().collect(),
        n_wheels: 3,
        truth,
        ..RunData::default()
    })
    .unwrap()
}

/// The odometry of `f` over `run`, at every sample from the first ground-truth stamp.
fn trajectory(f: &FittedModel, run: &Run) -> omni_kin::Trajectory {
    omni_kin::odometry::integrate(&f.model.resolve(&f.params).unwrap(), run)
}

/// The paper's calibrated matrix with our default integration (exact arcs, fixed steps).
fn calibrated() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()).with_integration(omni_kin::Integration::DEFAULT))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Driving the wheels backwards, in reverse order, from the end pose retraces the path to the start:
    /// an exact-arc step with the opposite twist is the inverse motion.
    #[test]
    fn reversed_wheel_speeds_retrace_the_path(
        wheels in prop::collection::vec(prop::array::uniform3(-3.0f64..3.0), 10..60),
        x in -5.0f64..5.0, y in -5.0f64..5.0, th in -3.0f64..3.0,
    ) {
        let f = calibrated();
        let n = wheels.len();
        let forward = trajectory(&f, &run_from(&wheels, Pose2::new(x, y, th)));
        prop_assert_eq!(forward.poses.len(), n);
        let end = forward.poses[n - 1];
        // Sample k covers (t_{k-1}, t_k]; the first sample lies before the start and is not integrated.
        let mut back: Vec<[f64; 3]> = vec![wheels[0]];
        back.extend(wheels[1..].iter().rev().map(|w| [-w[0], -w[1], -w[2]]));
        let backward = trajectory(&f, &run_from(&back, end));
        for (j, p) in backward.poses.iter().enumerate() {
            let q = forward.poses[n - 1 - j];
            prop_assert!((p.x_m - q.x_m).abs() < 1e-9, "x at {}: {} vs {}", j, p.x_m, q.x_m);
            prop_assert!((p.y_m - q.y_m).abs() < 1e-9, "y at {}: {} vs {}", j, p.y_m, q.y_m);
            prop_assert!((p.theta_rad - q.theta_rad).abs() < 1e-9, "θ at {}: {} vs {}", j, p.theta_rad, q.theta_rad);
        }
    }

    /// The cost is never negative, is 0 when the ground truth is the model's own odometry, and positive
    /// for another model on the same runs.
    #[test]
    fn cost_is_nonnegative_and_zero_against_itself(
        wheels in prop::collection::vec(prop::array::uniform3(-3.0f64..3.0), 10..60),
        noise in prop::collection::vec(-0.05f64..0.05, 3),
    ) {
        let f = calibrated();
        let n = wheels.len();
        let own = trajectory(&f, &run_from(&wheels, Pose2::new(0.3, -0.2, 0.1)));
        let truth: Vec<StampedPose> = own.t_s.iter().zip(&own.poses).step_by(3)
            .chain(std::iter::once((&own.t_s[n - 1], &own.poses[n - 1])))
            .map(|(&t_s, &pose)| StampedPose { t_s, pose })
            .collect();
        let mut truth_dedup = truth.clone();
        truth_dedup.dedup_by(|a, b| a.t_s == b.t_s);
        let itself = run_with_truth(&wheels, truth_dedup.clone());
        let design = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
        for kind in [omni_kin::CostKind::EndPose, omni_kin::CostKind::PATH] {
            let zero = omni_kin::cost::cost(&f.model, &f.params, std::slice::from_ref(&itself), kind).unwrap();
            prop_assert!((0.0..1e-12).contains(&zero), "{:?} against itself: {}", kind, zero);
            let other = omni_kin::cost::cost(&design.model, &design.params, std::slice::from_ref(&itself), kind).unwrap();
            prop_assert!(other >= 0.0 && other.is_finite(), "{:?}: {}", kind, other);
            // A disturbed ground truth: still ≥ 0, and > 0 once the end pose moved.
            let mut moved = truth_dedup.clone();
            let last = moved.len() - 1;
            moved[last].pose = Pose2::new(
                moved[last].pose.x_m + noise[0] + 0.06, moved[last].pose.y_m + noise[1], moved[last].pose.theta_rad + noise[2]);
            let run = run_with_truth(&wheels, moved);
            let c = omni_kin::cost::cost(&f.model, &f.params, std::slice::from_ref(&run), kind).unwrap();
            prop_assert!(c > 1e-3, "{:?} with a moved end pose: {}", kind, c);
        }
    }
}
