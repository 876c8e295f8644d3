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
