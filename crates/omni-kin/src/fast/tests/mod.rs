//! The fast path against the literal walk, through the evaluator (the only caller).
//!
//! - `agreement.rs`: the lane kernel against the literal walk, and what it declines.
//! - `general_walk.rs`: the general fast walk against the literal walk.
//! - `derivatives.rs`: the kernel's and the forward walk's Jacobians against central differences.
//! - `same_bits.rs`: the same bits whatever the route, SIMD path or lane group.
#![allow(clippy::unwrap_used)]

use super::*;
use crate::cost::CostKind;
use crate::effect::EffectKind;
use crate::evaluate::{Evaluator, IkBlock, Route};
use crate::fast::kernel::RESYNC_STEPS;
use crate::geometry::RobotGeometry;
use crate::ik::IkMatrix;
use crate::model::{FittedModel, Integration, Model};
use crate::pose::{Pose2, StampedPose};
use crate::run::RunData;
use crate::simulate::{SimConfig, simulate};

mod agreement;
mod derivatives;
mod general_walk;
mod same_bits;

/// The paper's design IK model with `integration` and the catalogue's effects `ids` (three wheels), and the
/// parameters: the paper's calibrated matrix, then `values` for the effects.
fn paper_with(ids: &[&str], values: &[f64], integration: Integration) -> (Model, Vec<f64>) {
    let mut model = Model::ik(IkMatrix::paper_design()).with_integration(integration);
    for id in ids {
        model = model.with_effect(EffectKind::from_id(id, 3).unwrap());
    }
    let mut p = IkMatrix::paper_calibrated().entries().to_vec();
    p.extend(values);
    (model, p)
}

fn paper_size() -> Vec<Run> {
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    simulate(&SimConfig { seed: 3, ..SimConfig::default() }, &truth, "t/").unwrap()
}

/// Largest difference between the fast and the literal errors over every run and selected pose (and
/// every end pose), and the number of poses compared.
fn max_gap(model: &Model, params: &[f64], runs: &[Run], selection: Selection) -> (f64, usize) {
    let res = model.resolve(params).unwrap();
    let fast = Evaluator::new(model, runs, selection).unwrap();
    assert!(fast.is_fast(&res), "the fast path should serve {selection:?}");
    let walk = Evaluator::with_route(model, runs, selection, Route::Walk).unwrap();
    assert!(!walk.is_fast(&res));
    let (f, w) = (fast.errors(&res), walk.errors(&res));
    let ends = fast.end_pose_errors(&res);
    let (mut gap, mut count) = (0.0f64, 0);
    let mut at = |a: &PoseError, b: &PoseError| {
        gap = gap.max((a.dx_m - b.dx_m).abs()).max((a.dy_m - b.dy_m).abs()).max((a.dtheta_rad - b.dtheta_rad).abs());
    };
    for (i, end) in ends.iter().enumerate() {
        assert_eq!(f.run(i).len(), w.run(i).len());
        for (a, b) in f.run(i).iter().zip(w.run(i)) {
            at(a, b);
            count += 1;
        }
        at(&f.ends()[i], &w.ends()[i]);
        at(end, &w.ends()[i]);
    }
    (gap, count)
}

/// A run of `n` wheels with smooth speeds (100 Hz, 6 s) and ground truth every 0.1 s off the sample
/// stamps (the poses only need to exist: the fast path and the walk are compared with each other).
fn synthetic_run(n: usize, seed: usize) -> Run {
    synthetic_run_of(n, seed, 600)
}

/// [`synthetic_run`] of `samples` wheel samples (at least 100).
fn synthetic_run_of(n: usize, seed: usize, samples: usize) -> Run {
    let wheel_t_s: Vec<f64> = (0..samples).map(|k| 0.01 * k as f64).collect();
    let wheel_rad_s = (wheel_t_s.iter())
        .flat_map(|t| (0..n).map(move |j| 1.0 + 2.0 * (0.7 * t + j as f64 + seed as f64).sin()))
        .collect();
    let truth = (0..samples / 10 - 2)
        .map(|k| {
            let t = 0.003 + 0.1 * k as f64;
            StampedPose { t_s: t, pose: Pose2::new(0.1 * t, 0.01 * t * t, 0.05 * t) }
        })
        .collect();
    let data =
        RunData { name: format!("n{n}-{seed}"), wheel_t_s, wheel_rad_s, n_wheels: n, truth, ..Default::default() };
    Run::new(data).unwrap()
}

/// An IK matrix of `n` wheels spread around the base (3 × n; small step angles).
fn spread_ik(n: usize) -> IkMatrix {
    let angle = |j: usize| 2.0 * std::f64::consts::PI * j as f64 / n as f64 + 0.3;
    let entries = (0..3 * n)
        .map(|i| match i / n {
            0 => 0.03 * angle(i % n).cos(),
            1 => 0.03 * angle(i % n).sin(),
            _ => 0.08 + 0.001 * (i % n) as f64,
        })
        .collect();
    IkMatrix::new(n, entries).unwrap()
}

/// A user's twist-stage effect: a yaw rate added while the robot moves (the lane kernel has no lane form
/// of it; the general walk calls its hook).
#[derive(Debug)]
struct Spin;

impl crate::effect::Effect for Spin {
    fn id(&self) -> &str {
        "spin"
    }
    fn describe(&self) -> String {
        "a yaw rate".into()
    }
    fn stage(&self) -> crate::effect::Stage {
        crate::effect::Stage::Twist
    }
    fn params(&self) -> Vec<crate::effect::ParamSpec> {
        vec![crate::effect::ParamSpec::new("rate", "rad/s", 0.0, -0.1, 0.1)]
    }
    fn twist(&self, p: &[f64], t: crate::pose::Twist2, _w: &[f64]) -> crate::pose::Twist2 {
        crate::pose::Twist2 { omega_rad_s: t.omega_rad_s + p[0], ..t }
    }
}

/// The robot-type models off their design values: a differential drive as robot.toml describes one (left
/// wheel first, at +y, driving backward at positive speed; 2 wheels) and a slightly asymmetric mecanum base
/// (4 wheels).
fn robot_type_models() -> Vec<(Model, Vec<f64>)> {
    use crate::geometry::Wheel;
    use crate::kinematics::KinematicsKind;
    use std::f64::consts::{FRAC_PI_2, PI};
    let wheel = |r, angle, offset| Wheel {
        radius_m: r,
        distance_m: 0.105,
        angle_rad: angle,
        drive_offset_rad: offset,
        roller_angle_rad: 0.0,
    };
    let wheels = vec![wheel(0.041, FRAC_PI_2, PI), wheel(0.043, -FRAC_PI_2, 0.0)];
    let diff = RobotGeometry { wheel_names: vec!["left".into(), "right".into()], wheels };
    let mut mecanum = RobotGeometry::mecanum4(0.05, 0.2, 0.15);
    mecanum.wheels[1].radius_m = 0.051;
    let off_design = |kind, g: &RobotGeometry| {
        let model = Model::design(kind, Some(g)).unwrap().with_integration(Integration::DEFAULT);
        let p: Vec<f64> =
            model.nominal().iter().enumerate().map(|(i, v)| v * (1.0 + 0.02 * (i as f64 - 1.5))).collect();
        (model, p)
    };
    vec![off_design(KinematicsKind::Diff, &diff), off_design(KinematicsKind::Mecanum, &mecanum)]
}

/// Runs with late samples (jittered stamps), so that measured stamps differ from the fixed step.
fn jittered_runs(n: usize) -> Vec<Run> {
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    let cfg = SimConfig { seed: 5, sample_jitter_s: 0.003, duration_s: 4.0, ..SimConfig::default() };
    simulate(&cfg, &truth, "j/").unwrap().into_iter().step_by(5).take(n).collect()
}
