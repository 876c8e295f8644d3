//! The fast path against the literal walk, through the evaluator (the only caller).
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

#[test]
fn agrees_with_the_literal_walk_on_a_paper_size_set() {
    let runs = paper_size();
    assert_eq!(runs.len(), 180);
    for ik in [IkMatrix::paper_design(), IkMatrix::paper_calibrated(), IkMatrix::paper_parametric()] {
        for integration in [Integration::PAPER, Integration::DEFAULT] {
            let model = Model::ik(ik.clone()).with_integration(integration);
            let p = model.nominal();
            for selection in [Selection::End, Selection::Path(1), Selection::Path(4)] {
                let (gap, count) = max_gap(&model, &p, &runs, selection);
                eprintln!("{:?} {selection:?}: largest gap {gap:.1e} m", integration.scheme);
                assert!(gap < 1e-9, "{integration:?} {selection:?}: gap {gap:e} m");
                assert!(count >= 180);
            }
        }
    }
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

#[test]
fn serves_any_wheel_count_as_the_walk_does() {
    for n in [2, 3, 4, 6] {
        let runs: Vec<Run> = (0..6).map(|s| synthetic_run(n, s)).collect();
        for integration in [Integration::PAPER, Integration::DEFAULT] {
            let model = Model::ik(spread_ik(n)).with_integration(integration);
            for selection in [Selection::End, Selection::Path(1), Selection::Path(3)] {
                let (gap, count) = max_gap(&model, &model.nominal(), &runs, selection);
                assert!(gap < 1e-9, "{n} wheels {integration:?} {selection:?}: gap {gap:e} m");
                assert!(count >= 6, "{count} poses");
            }
        }
    }
}

#[test]
fn serves_simulated_four_and_six_wheel_robots() {
    for n in [4, 6] {
        let design = RobotGeometry::omni_regular(n, 0.05, 0.2, 0.4);
        let truth = FittedModel::nominal(Model::ik(design.twist_from_wheels().unwrap()));
        let cfg = SimConfig { design, duration_s: 3.0, runs_per_command: 1, ..SimConfig::default() };
        let runs = simulate(&cfg, &truth, "s/").unwrap();
        let model = truth.model.clone().with_integration(Integration::DEFAULT);
        let (gap, _) = max_gap(&model, &truth.params, &runs, Selection::Path(1));
        assert!(gap < 1e-9, "{n} wheels: gap {gap:e} m");
    }
}

#[test]
fn agrees_with_a_sensor_offset() {
    let runs: Vec<Run> = paper_size().into_iter().take(9).collect();
    let model = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("sensor_offset_yaw", 3).unwrap());
    let mut p = model.nominal();
    p[9..].copy_from_slice(&[0.03, -0.02, 0.1]);
    let (gap, count) = max_gap(&model, &p, &runs, Selection::Path(1));
    assert!(gap < 1e-9, "gap {gap:e}");
    assert!(count > 9 * 30, "{count} poses");
}

#[test]
fn agrees_with_wheel_stage_effects() {
    let runs: Vec<Run> = paper_size().into_iter().take(10).collect();
    for (id, values) in [
        ("wheel_asymmetry", vec![0.05, -0.03, 0.02]),
        ("speed_scale", vec![0.01, -0.02, 0.015]),
        ("accel_slip", vec![0.05, 0.02, -0.03]),
        ("backlash", vec![0.02, 0.01, 0.03]),
        ("wheel_eccentricity", vec![0.02, -0.01, 0.01, 0.015, 0.0, -0.02]),
        ("learned:wheel", (0..27).map(|i| 0.002 * ((i * 7 % 11) as f64 - 5.0)).collect()),
    ] {
        let model = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id(id, 3).unwrap());
        let mut p = model.nominal();
        p[9..].copy_from_slice(&values);
        for selection in [Selection::End, Selection::Path(1)] {
            let (gap, _) = max_gap(&model, &p, &runs, selection);
            assert!(gap < 1e-9, "{id} {selection:?}: gap {gap:e}");
        }
    }
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

#[test]
fn declines_what_it_cannot_do() {
    let runs: Vec<Run> = paper_size().into_iter().take(5).collect();
    let prepared = PreparedRuns::new(&runs, None, Selection::End);
    let lagged = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("time_offset", 3).unwrap());
    let mut p = lagged.nominal();
    assert!(prepared.errors(&lagged.resolve(&p).unwrap(), &runs).is_some(), "no lag at τ = 0");
    p[9] = 0.01;
    assert!(prepared.errors(&lagged.resolve(&p).unwrap(), &runs).is_some(), "a lag takes groups of its own");
    p[9] = f64::INFINITY;
    assert!(lagged.resolve(&p).is_err(), "a lag that is not finite is refused before");
    let twist = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("rotation_slip", 3).unwrap());
    assert!(prepared.errors(&twist.resolve(&twist.nominal()).unwrap(), &runs).is_some(), "a built-in twist");
    let user = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::Custom(std::sync::Arc::new(Spin)));
    assert!(prepared.errors(&user.resolve(&user.nominal()).unwrap(), &runs).is_none(), "a user's twist");
    let stamps = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("sample_timing", 3).unwrap());
    assert!(prepared.errors(&stamps.resolve(&stamps.nominal()).unwrap(), &runs).is_none(), "measured stamps");
    let paper_step = Model::ik(IkMatrix::paper_design()).with_integration(Integration::PAPER);
    assert!(prepared.errors(&paper_step.resolve(&paper_step.nominal()).unwrap(), &runs).is_none(), "other step");
    // A step angle beyond the polynomials' range.
    let fast = Model::ik(IkMatrix::new(3, vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 50.0, 50.0, 50.0]).unwrap());
    assert!(prepared.errors(&fast.resolve(&fast.nominal()).unwrap(), &runs).is_none());
    // Other runs than the prepared ones.
    assert!(prepared.errors(&fast.resolve(&fast.nominal()).unwrap(), &runs[..2]).is_none());
}

/// Every error's bits, in run order.
fn bits(e: &FastErrors) -> Vec<u64> {
    (e.at_queries.iter().chain(&e.ends)).flat_map(|e| [e.dx_m, e.dy_m, e.dtheta_rad].map(f64::to_bits)).collect()
}

/// The residuals and IK Jacobian of `kind`, the evaluator's blocks stacked.
fn stacked(ev: &Evaluator<'_>, res: &crate::model::Resolved<'_>, kind: CostKind) -> (Vec<f64>, DMatrix<f64>) {
    let mut blocks: Vec<(Vec<f64>, DMatrix<f64>)> = Vec::new();
    ev.ik_jacobian_blocks(res, kind, &mut |b: IkBlock<'_>| blocks.push((b.residuals.to_vec(), b.jacobian.clone())))
        .unwrap();
    let rows: usize = blocks.iter().map(|b| b.0.len()).sum();
    let mut jac = DMatrix::zeros(rows, blocks.first().map_or(0, |b| b.1.ncols()));
    let mut r = Vec::new();
    for (res, j) in blocks {
        jac.rows_mut(r.len(), res.len()).copy_from(&j);
        r.extend(res);
    }
    (r, jac)
}

#[test]
fn redone_increments_give_the_same_bits_as_kept_ones() {
    let runs: Vec<Run> = paper_size().into_iter().take(23).collect();
    for (effect, values) in [(None, vec![]), (Some("speed_scale"), vec![0.01, -0.02, 0.015])] {
        let mut model = Model::ik(IkMatrix::paper_design()).with_integration(Integration::DEFAULT);
        if let Some(id) = effect {
            model = model.with_effect(EffectKind::from_id(id, 3).unwrap());
        }
        let mut p = IkMatrix::paper_calibrated().entries().to_vec();
        p.extend(&values);
        let res = model.resolve(&p).unwrap();
        for sel in [Selection::End, Selection::Path(1)] {
            let kept = PreparedRuns::new(&runs, None, sel);
            let redone = PreparedRuns::with_increment_budget(&runs, None, sel, 0);
            assert!(kept.increments_kept() && !redone.increments_kept());
            assert_eq!(bits(&kept.errors(&res, &runs).unwrap()), bits(&redone.errors(&res, &runs).unwrap()));
            let ends = |p: &PreparedRuns| p.end_pose_errors(&res, &runs).unwrap();
            assert_eq!(ends(&kept), ends(&redone));
            if effect.is_none() {
                let rows = |p: &PreparedRuns| {
                    let mut out = Vec::new();
                    (p.ik_jacobian_rows(&res, &runs, &mut |r| {
                        out.push((r.run, r.errors.to_vec(), r.jacobian.clone()))
                    }))
                    .unwrap();
                    out
                };
                assert_eq!(rows(&kept), rows(&redone));
            }
        }
    }
}

#[test]
fn jacobian_blocks_come_in_run_order_across_batches() {
    let runs: Vec<Run> = paper_size().into_iter().cycle().take(BLOCK_RUNS + 2 * LANES + 1).collect();
    let model = Model::ik(IkMatrix::paper_design());
    let ev = Evaluator::new(&model, &runs, Selection::Path(1)).unwrap();
    let x = IkMatrix::paper_calibrated().entries().to_vec();
    let res = model.resolve(&x).unwrap();
    let full = ev.residual_vector(&res, CostKind::PATH);
    let (mut next, mut row) = (0, 0);
    ev.ik_jacobian_blocks(&res, CostKind::PATH, &mut |b| {
        assert_eq!(b.run, next);
        let rows = 3 * (runs[b.run].truth().len() - 1);
        assert_eq!((b.residuals.len(), b.jacobian.nrows(), b.jacobian.ncols()), (rows, rows, 9));
        for (a, f) in b.residuals.iter().zip(&full[row..row + rows]) {
            assert!((a - f).abs() < 1e-15, "run {}: {a} vs {f}", b.run);
        }
        next += 1;
        row += rows;
    })
    .unwrap();
    assert_eq!((next, row), (runs.len(), full.len()));
}

#[test]
fn ik_jacobian_matches_central_differences() {
    let runs: Vec<Run> = paper_size().into_iter().step_by(15).collect();
    for (integration, kind) in [
        (Integration::PAPER, CostKind::EndPose),
        (Integration::DEFAULT, CostKind::EndPose),
        (Integration::DEFAULT, CostKind::PATH),
        (Integration::PAPER, CostKind::Path { every: 3, heading_weight_m_per_rad: 0.5 }),
    ] {
        let model = Model::ik(IkMatrix::paper_design())
            .with_integration(integration)
            .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap());
        let ev = Evaluator::for_cost(&model, &runs, kind).unwrap();
        let mut x = IkMatrix::paper_calibrated().entries().to_vec();
        x.extend([0.02, -0.01]);
        let res = model.resolve(&x).unwrap();
        let (r, j) = stacked(&ev, &res, kind);
        let fast = ev.residual_vector(&res, kind);
        assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "residuals differ");
        assert_eq!(j.ncols(), 9);
        let mut worst = 0.0f64;
        for c in 0..9 {
            let h = 1e-6 * x[c].abs().max(0.05);
            let mut xp = x.clone();
            xp[c] += h;
            let mut xm = x.clone();
            xm[c] -= h;
            let rp = ev.residual_vector(&model.resolve(&xp).unwrap(), kind);
            let rm = ev.residual_vector(&model.resolve(&xm).unwrap(), kind);
            // Relative to the column's largest entry: tiny entries carry the differences' rounding noise.
            let col_max = (0..r.len()).map(|i| j[(i, c)].abs()).fold(0.0f64, f64::max);
            assert!(col_max > 1e-3, "column {c} is flat");
            for i in 0..r.len() {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                let err = (fd - j[(i, c)]).abs() / col_max;
                worst = worst.max(err);
            }
        }
        assert!(worst < 1e-6, "{integration:?} {kind:?}: worst relative gap {worst:e}");
    }
}

#[test]
fn ik_jacobian_serves_six_wheels() {
    let runs: Vec<Run> = (0..5).map(|s| synthetic_run(6, s)).collect();
    let model = Model::ik(spread_ik(6)).with_integration(Integration::DEFAULT);
    let ev = Evaluator::for_cost(&model, &runs, CostKind::PATH).unwrap();
    let x = model.nominal();
    let (r, j) = stacked(&ev, &model.resolve(&x).unwrap(), CostKind::PATH);
    assert_eq!(j.ncols(), 18);
    for c in [0, 7, 14, 17] {
        let h = 1e-6 * x[c].abs().max(0.01);
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[c] += h;
        xm[c] -= h;
        let rp = ev.residual_vector(&model.resolve(&xp).unwrap(), CostKind::PATH);
        let rm = ev.residual_vector(&model.resolve(&xm).unwrap(), CostKind::PATH);
        let col_max = (0..r.len()).map(|i| j[(i, c)].abs()).fold(0.0f64, f64::max);
        for i in 0..r.len() {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            assert!((fd - j[(i, c)]).abs() < 1e-6 * col_max, "column {c} row {i}: {fd} vs {}", j[(i, c)]);
        }
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

#[test]
fn serves_diff_and_mecanum_models_as_the_walk_does() {
    for (model, p) in robot_type_models() {
        let n = model.n_wheels();
        let runs: Vec<Run> = (0..5).map(|s| synthetic_run(n, s)).collect();
        for selection in [Selection::End, Selection::Path(1), Selection::Path(3)] {
            let (gap, count) = max_gap(&model, &p, &runs, selection);
            assert!(gap < 1e-9, "{} ({n} wheels) {selection:?}: gap {gap:e} m", model.kinematics.id());
            assert!(count >= 5);
        }
    }
}

/// The fast path's IK Jacobian chained through the model's `twist_from_wheels_jacobian` (what the LM
/// polish uses for parametric models) against central differences in the model's own parameters.
#[test]
fn chained_jacobian_of_diff_and_mecanum_models_matches_central_differences() {
    for (model, x) in robot_type_models() {
        let runs: Vec<Run> = (0..4).map(|s| synthetic_run(model.n_wheels(), s)).collect();
        let ev = Evaluator::for_cost(&model, &runs, CostKind::PATH).unwrap();
        let (r, j_ik) = stacked(&ev, &model.resolve(&x).unwrap(), CostKind::PATH);
        let j = j_ik * model.kinematics.twist_from_wheels_jacobian(&x).unwrap();
        assert_eq!(j.ncols(), x.len());
        for c in 0..x.len() {
            let h = 1e-6 * x[c].abs();
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[c] += h;
            xm[c] -= h;
            let rp = ev.residual_vector(&model.resolve(&xp).unwrap(), CostKind::PATH);
            let rm = ev.residual_vector(&model.resolve(&xm).unwrap(), CostKind::PATH);
            let col_max = (0..r.len()).map(|i| j[(i, c)].abs()).fold(0.0f64, f64::max);
            assert!(col_max > 1e-3, "{}: column {c} is flat", model.kinematics.id());
            for i in 0..r.len() {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                let gap = (fd - j[(i, c)]).abs() / col_max;
                assert!(gap < 1e-6, "{} column {c} row {i}: {fd} vs {}", model.kinematics.id(), j[(i, c)]);
            }
        }
    }
}

/// Largest difference between the general fast walk and the literal walk (every selected pose and end
/// pose), and the number of poses compared; panics when the general walk declines.
fn general_gap(model: &Model, params: &[f64], runs: &[Run], selection: Selection) -> (f64, usize) {
    let res = model.resolve(params).unwrap();
    let general = crate::evaluate::general_errors(&res, runs, selection).expect("the general walk serves");
    let walk = Evaluator::with_route(model, runs, selection, Route::Walk).unwrap().errors(&res);
    let fast = Evaluator::new(model, runs, selection).unwrap();
    let (mut gap, mut count) = (0.0f64, 0);
    let mut at = |a: &PoseError, b: &PoseError| {
        gap = gap.max((a.dx_m - b.dx_m).abs()).max((a.dy_m - b.dy_m).abs()).max((a.dtheta_rad - b.dtheta_rad).abs());
    };
    let (via_evaluator, ends) = (fast.errors(&res), fast.end_pose_errors(&res));
    for (i, end) in ends.iter().enumerate() {
        assert_eq!(general.run(i).len(), walk.run(i).len());
        for ((a, b), c) in general.run(i).iter().zip(walk.run(i)).zip(via_evaluator.run(i)) {
            at(a, b);
            at(c, b);
            count += 1;
        }
        at(&general.ends()[i], &walk.ends()[i]);
        at(end, &walk.ends()[i]);
    }
    (gap, count)
}

/// Runs with late samples (jittered stamps), so that measured stamps differ from the fixed step.
fn jittered_runs(n: usize) -> Vec<Run> {
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    let cfg = SimConfig { seed: 5, sample_jitter_s: 0.003, duration_s: 4.0, ..SimConfig::default() };
    simulate(&cfg, &truth, "j/").unwrap().into_iter().step_by(5).take(n).collect()
}

/// Every effect the lane kernel does not serve (a clock lag either way, each twist-stage effect, measured
/// stamps), alone and mixed with wheel- and measurement-stage effects: the general fast walk agrees with
/// the literal walk within 1e-9 m, Euler and exact arcs, end and path selections.
#[test]
fn general_walk_agrees_with_the_literal_walk_for_every_effect() {
    let runs = jittered_runs(7);
    let cases: Vec<(Vec<&str>, Vec<f64>)> = vec![
        (vec!["time_offset"], vec![0.037]),
        (vec!["time_offset"], vec![-0.052]),
        (vec!["rotation_slip"], vec![0.12]),
        (vec!["turn_scrub"], vec![-0.13]),
        (vec!["world_drift"], vec![0.004, -0.003]),
        (vec!["sample_timing"], vec![]),
        (vec!["learned:body"], vec![0.05, 0.02, 0.1, -0.05, 0.03, 0.02, -0.01, 0.015, 0.01]),
        (vec!["learned:world"], vec![0.003, -0.002, 0.01, -0.02]),
        (vec!["learned:time"], vec![0.001, -0.0005, 0.002, 0.003]),
        (
            vec!["time_offset", "rotation_slip", "wheel_eccentricity", "sensor_offset_yaw", "world_drift"],
            vec![0.02, -0.1, 0.02, -0.01, 0.01, 0.015, 0.0, -0.02, 0.03, -0.02, 0.05, 0.002, 0.001],
        ),
        (vec!["sample_timing", "time_offset", "learned:time"], vec![-0.01, 0.001, 0.0, -0.002, 0.001]),
    ];
    for (ids, values) in cases {
        for integration in [Integration::PAPER, Integration::DEFAULT] {
            let mut model = Model::ik(IkMatrix::paper_design()).with_integration(integration);
            for id in &ids {
                model = model.with_effect(EffectKind::from_id(id, 3).unwrap());
            }
            let mut p = IkMatrix::paper_calibrated().entries().to_vec();
            p.extend(&values);
            assert_eq!(p.len(), model.n_params(), "{ids:?}");
            for selection in [Selection::End, Selection::Path(1), Selection::Path(7)] {
                let (gap, count) = general_gap(&model, &p, &runs, selection);
                eprintln!("{ids:?} {:?} {selection:?}: largest gap {gap:.1e} m", integration.scheme);
                assert!(gap < 1e-9, "{ids:?} {integration:?} {selection:?}: gap {gap:e} m");
                assert!(count >= runs.len(), "{count} poses");
            }
        }
    }
}

/// A step angle beyond the polynomials' range: the general walk declines, and the evaluator's numbers
/// are the literal walk's.
#[test]
fn general_walk_declines_large_step_angles() {
    let runs = jittered_runs(3);
    let model = Model::ik(IkMatrix::new(3, vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 50.0, 50.0, 50.0]).unwrap())
        .with_effect(EffectKind::from_id("rotation_slip", 3).unwrap());
    let p = model.nominal();
    let res = model.resolve(&p).unwrap();
    assert!(crate::evaluate::general_errors(&res, &runs, Selection::Path(1)).is_none());
    let via = Evaluator::new(&model, &runs, Selection::Path(1)).unwrap().errors(&res);
    let walk = Evaluator::with_route(&model, &runs, Selection::Path(1), Route::Walk).unwrap().errors(&res);
    assert_eq!(via, walk);
}

/// A clock lag (either way, several in turn so that the lag cache fills and turns over): the lane kernel
/// agrees with the literal walk within 1e-9 m, with the sensor offset and a wheel-stage effect too.
#[test]
fn kernel_serves_a_clock_lag_as_the_walk_does() {
    let runs: Vec<Run> = paper_size().into_iter().step_by(20).collect();
    for integration in [Integration::PAPER, Integration::DEFAULT] {
        let model = Model::ik(IkMatrix::paper_design())
            .with_integration(integration)
            .with_effect(EffectKind::from_id("time_offset", 3).unwrap())
            .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap())
            .with_effect(EffectKind::from_id("wheel_asymmetry", 3).unwrap());
        for selection in [Selection::End, Selection::Path(1), Selection::Path(5)] {
            let ev = Evaluator::new(&model, &runs, selection).unwrap();
            for (round, lag) in [0.041, -0.023, 0.0105, 0.3, -0.11, 0.041, 0.0].into_iter().enumerate() {
                let mut p = IkMatrix::paper_calibrated().entries().to_vec();
                p.extend([lag, 0.02, -0.01]);
                p.extend(if round % 2 == 0 { [0.0; 3] } else { [0.03, -0.02, 0.01] });
                let res = model.resolve(&p).unwrap();
                assert!(ev.is_fast(&res));
                let (gap, count) = max_gap(&model, &p, &runs, selection);
                assert!(gap < 1e-9, "{integration:?} {selection:?} lag {lag}: gap {gap:e} m");
                assert!(count >= runs.len());
                // The same evaluator, its lag cache warm or turned over: the same bits as a fresh one.
                let fresh = Evaluator::new(&model, &runs, selection).unwrap();
                assert_eq!(ev.errors(&res), fresh.errors(&res), "lag {lag}");
            }
        }
    }
}

/// With a clock lag the IK Jacobian is still the kernel's forward-mode one (the lag's own column is the
/// caller's finite difference): it matches central differences.
#[test]
fn ik_jacobian_with_a_clock_lag_matches_central_differences() {
    let runs: Vec<Run> = paper_size().into_iter().step_by(15).collect();
    for kind in [CostKind::EndPose, CostKind::PATH] {
        let model = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("time_offset", 3).unwrap());
        let ev = Evaluator::for_cost(&model, &runs, kind).unwrap();
        let mut x = IkMatrix::paper_calibrated().entries().to_vec();
        x.push(0.037);
        let res = model.resolve(&x).unwrap();
        let (r, j) = stacked(&ev, &res, kind);
        let fast = ev.residual_vector(&res, kind);
        assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "residuals differ");
        for c in 0..9 {
            let h = 1e-6 * x[c].abs().max(0.05);
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[c] += h;
            xm[c] -= h;
            let rp = ev.residual_vector(&model.resolve(&xp).unwrap(), kind);
            let rm = ev.residual_vector(&model.resolve(&xm).unwrap(), kind);
            let col_max = (0..r.len()).map(|i| j[(i, c)].abs()).fold(0.0f64, f64::max);
            assert!(col_max > 1e-3, "column {c} is flat");
            for i in 0..r.len() {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                assert!((fd - j[(i, c)]).abs() < 1e-6 * col_max, "{kind:?} column {c} row {i}: {fd} vs {}", j[(i, c)]);
            }
        }
    }
}

/// The law the fast path relies on for every effect that claims it (`wheel_rates_affine`): the rewritten
/// speeds are the measured ones plus each parameter's part, `w + Σ_i p_i (wheel_rates(e_i) − w)`, to
/// rounding; and backlash (a play operator) does not claim it.
#[test]
fn affine_wheel_effects_are_affine() {
    use crate::effect::{Effect, WheelContext};
    let run = &jittered_runs(1)[0];
    let (s, h) = crate::plan::sample_times(run, 0.0, None, false);
    let ctx = WheelContext { n_wheels: 3, t_s: &s, dt_s: &h, start_angle_rad: &[0.3, -1.0, 2.0] };
    let w = run.wheel_rad_s();
    let mut claimed = Vec::new();
    for id in crate::effect::CATALOGUE.iter().copied().chain(["learned:wheel"]) {
        let e = EffectKind::from_id(id, 3).unwrap();
        if !e.wheel_rates_affine() {
            continue;
        }
        claimed.push(id);
        let n = e.params().len();
        let p: Vec<f64> = (0..n).map(|i| 0.01 * (1.0 + i as f64) * if i % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let mut whole = w.to_vec();
        e.wheel_rates(&p, &ctx, &mut whole);
        let mut sum = w.to_vec();
        for i in 0..n {
            let mut unit = vec![0.0; n];
            unit[i] = 1.0;
            let mut part = w.to_vec();
            e.wheel_rates(&unit, &ctx, &mut part);
            for k in 0..w.len() {
                sum[k] += p[i] * (part[k] - w[k]);
            }
        }
        let scale = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let gap = whole.iter().zip(&sum).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(gap < 1e-12 * scale, "{id}: gap {gap:e} rad/s");
        assert!(whole.iter().zip(w).any(|(a, b)| (a - b).abs() > 1e-6 * scale), "{id} changes nothing here");
    }
    let expected = ["wheel_asymmetry", "speed_scale", "accel_slip", "wheel_eccentricity", "learned:wheel"];
    assert_eq!(claimed, expected);
}

/// With wheel-stage effects (an affine one from its parts, and two effects rewritten on each evaluation)
/// the IK Jacobian is the kernel's forward-mode one along the rewritten speeds: it matches central
/// differences.
#[test]
fn ik_jacobian_with_wheel_stage_effects_matches_central_differences() {
    let runs: Vec<Run> = paper_size().into_iter().step_by(15).collect();
    let cases: [(&[&str], Vec<f64>); 2] = [
        (&["wheel_eccentricity"], vec![0.02, -0.01, 0.01, 0.015, 0.0, -0.02]),
        (&["backlash", "wheel_asymmetry"], vec![0.02, 0.01, 0.03, 0.05, -0.03, 0.02]),
    ];
    for (ids, values) in cases {
        let mut model = Model::ik(IkMatrix::paper_design());
        for id in ids {
            model = model.with_effect(EffectKind::from_id(id, 3).unwrap());
        }
        let ev = Evaluator::for_cost(&model, &runs, CostKind::PATH).unwrap();
        let mut x = IkMatrix::paper_calibrated().entries().to_vec();
        x.extend(&values);
        let (r, j) = stacked(&ev, &model.resolve(&x).unwrap(), CostKind::PATH);
        let fast = ev.residual_vector(&model.resolve(&x).unwrap(), CostKind::PATH);
        assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "{ids:?}: residuals differ");
        // The affine effect's parameters are columns too (its parts); two wheel-stage effects: none.
        let carried = if ids.len() == 1 { values.len() } else { 0 };
        assert_eq!(j.ncols(), 9 + carried, "{ids:?}");
        for c in 0..9 + carried {
            let h = 1e-6 * x[c].abs().max(0.05);
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[c] += h;
            xm[c] -= h;
            let rp = ev.residual_vector(&model.resolve(&xp).unwrap(), CostKind::PATH);
            let rm = ev.residual_vector(&model.resolve(&xm).unwrap(), CostKind::PATH);
            let col_max = (0..r.len()).map(|i| j[(i, c)].abs()).fold(0.0f64, f64::max);
            assert!(col_max > 1e-3, "column {c} is flat");
            for i in 0..r.len() {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                assert!((fd - j[(i, c)]).abs() < 1e-6 * col_max, "{ids:?} column {c} row {i}: {fd} vs {}", j[(i, c)]);
            }
        }
    }
}

/// The forward-mode walk's Jacobian (IK entries and the effect parameters it carries) against central
/// differences of the evaluator's residuals, for twist-stage effects alone and mixed with a sensor offset,
/// an affine wheel-stage effect, measured stamps and a clock lag (whose column is left to the caller).
#[test]
fn forward_jacobian_matches_central_differences() {
    use crate::evaluate::ModelBlock;
    let runs = jittered_runs(5);
    let cases: Vec<(Vec<&str>, Vec<f64>, usize)> = vec![
        (vec!["rotation_slip"], vec![0.12], 1),
        (vec!["turn_scrub"], vec![-0.13], 1),
        (vec!["world_drift"], vec![0.004, -0.003], 2),
        (vec!["learned:body"], vec![0.05, 0.02, 0.1, -0.05, 0.03, 0.02, -0.01, 0.015, 0.01], 9),
        (vec!["learned:world"], vec![0.003, -0.002, 0.01, -0.02], 4),
        (vec!["learned:time"], vec![0.001, -0.0005, 0.002, 0.003], 4),
        (vec!["sensor_offset_yaw", "rotation_slip"], vec![0.03, -0.02, 0.05, 0.1], 4),
        (vec!["wheel_eccentricity", "world_drift"], vec![0.02, -0.01, 0.01, 0.015, 0.0, -0.02, 0.004, 0.002], 8),
        (vec!["sample_timing", "learned:ground_truth", "rotation_slip"], vec![0.02, 0.01, -0.03, 0.08], 4),
        (vec!["time_offset", "rotation_slip"], vec![0.03, 0.1], 1),
        (
            vec!["rotation_slip", "learned:world", "learned:body"],
            [vec![-0.7, 0.003, -0.002, 0.01, -0.02], vec![0.01; 9]].concat(),
            14,
        ),
        // A user's twist-stage effect: its hook's slopes by differences.
        (vec!["spin", "world_drift"], vec![0.02, 0.004, 0.002], 3),
    ];
    for (ids, values, carried) in cases {
        for kind in [CostKind::EndPose, CostKind::PATH, CostKind::Path { every: 4, heading_weight_m_per_rad: 0.5 }] {
            let mut model = Model::ik(IkMatrix::paper_design());
            for id in &ids {
                let e = match *id {
                    "spin" => EffectKind::Custom(std::sync::Arc::new(Spin)),
                    id => EffectKind::from_id(id, 3).unwrap(),
                };
                model = model.with_effect(e);
            }
            let mut x = IkMatrix::paper_calibrated().entries().to_vec();
            x.extend(&values);
            let ev = Evaluator::for_cost(&model, &runs, kind).unwrap();
            let mut rows: Vec<(Vec<f64>, DMatrix<f64>, Vec<usize>)> = Vec::new();
            ev.forward_jacobian_blocks(&model, &x, kind, &mut |b: ModelBlock<'_>| {
                rows.push((b.residuals.to_vec(), b.jacobian.clone(), b.covered.to_vec()))
            })
            .unwrap();
            assert_eq!(rows.len(), runs.len());
            let covered = rows[0].2.clone();
            assert_eq!(covered.len(), carried, "{ids:?}");
            let r: Vec<f64> = rows.iter().flat_map(|b| b.0.clone()).collect();
            let fast = ev.residual_vector(&model.resolve(&x).unwrap(), kind);
            assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "{ids:?} {kind:?}: residuals differ");
            let columns: Vec<usize> = (0..9).chain(covered.iter().copied()).collect();
            for (c, &g) in columns.iter().enumerate() {
                let h = 1e-6 * x[g].abs().max(if g < 9 { 0.05 } else { 1e-2 });
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[g] += h;
                xm[g] -= h;
                let rp = ev.residual_vector(&model.resolve(&xp).unwrap(), kind);
                let rm = ev.residual_vector(&model.resolve(&xm).unwrap(), kind);
                let col: Vec<f64> =
                    rows.iter().flat_map(|b| b.1.column(c).iter().copied().collect::<Vec<_>>()).collect();
                let col_max = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!(col_max > 1e-6, "{ids:?} column {g} is flat");
                for i in 0..r.len() {
                    let fd = (rp[i] - rm[i]) / (2.0 * h);
                    let gap = (fd - col[i]).abs() / col_max;
                    assert!(gap < 1e-6, "{ids:?} {kind:?} column {g} row {i}: {fd} vs {} ({gap:e})", col[i]);
                }
            }
        }
    }
}

/// The built-in twist-stage effects in the lane kernel (a turn of `rotation_slip` beyond the polynomials'
/// range included), alone and with a clock lag, a sensor offset and an affine wheel-stage effect: within
/// 1e-9 m of the literal walk, Euler and exact arcs, end and path selections.
#[test]
fn kernel_serves_builtin_twist_effects_as_the_walk_does() {
    let runs = jittered_runs(6);
    let cases: Vec<(Vec<&str>, Vec<f64>)> = vec![
        (vec!["rotation_slip"], vec![0.12]),
        (vec!["rotation_slip"], vec![-2.5]),
        (vec!["world_drift"], vec![0.004, -0.003]),
        (vec!["learned:body"], vec![0.05, 0.02, 0.1, -0.05, 0.03, 0.02, -0.01, 0.015, 0.01]),
        (vec!["learned:world"], vec![0.003, -0.002, 0.01, -0.02]),
        (vec!["learned:time"], vec![0.001, -0.0005, 0.002, 0.003]),
        (
            vec!["time_offset", "rotation_slip", "wheel_eccentricity", "sensor_offset_yaw", "learned:time"],
            vec![0.02, -0.1, 0.02, -0.01, 0.01, 0.015, 0.0, -0.02, 0.03, -0.02, 0.05, 0.001, -0.0005, 0.002, 0.003],
        ),
    ];
    for (ids, values) in cases {
        for integration in [Integration::PAPER, Integration::DEFAULT] {
            let mut model = Model::ik(IkMatrix::paper_design()).with_integration(integration);
            for id in &ids {
                model = model.with_effect(EffectKind::from_id(id, 3).unwrap());
            }
            let mut p = IkMatrix::paper_calibrated().entries().to_vec();
            p.extend(&values);
            for selection in [Selection::End, Selection::Path(1), Selection::Path(7)] {
                let (gap, count) = max_gap(&model, &p, &runs, selection);
                assert!(gap < 1e-9, "{ids:?} {integration:?} {selection:?}: gap {gap:e} m");
                assert!(count >= runs.len());
            }
        }
    }
}

/// Runs of 3 wheels and 19 lengths (700 to 3,166 samples: some end before a re-anchoring of the heading
/// that a longer run of their group reaches), so the groups mix lengths.
fn mixed_length_runs() -> Vec<Run> {
    (0..19).map(|seed| synthetic_run_of(3, seed, 700 + 137 * seed)).collect()
}

/// Every lane-arithmetic path this CPU has (portable, AVX2, AVX-512) gives the same bits, at the queries
/// and the ends, for Euler and exact arcs, with a measurement-stage and an affine wheel-stage effect; and
/// those numbers are the literal walk's within 1e-9 m.
#[test]
fn every_simd_path_gives_the_same_bits() {
    let runs = mixed_length_runs();
    assert!(runs.iter().any(|r| r.n_samples() < RESYNC_STEPS) && runs.iter().any(|r| r.n_samples() > 3 * RESYNC_STEPS));
    let paths = SimdPath::available();
    assert_eq!(paths[0], SimdPath::Portable);
    assert_eq!(SimdPath::selected(), *paths.last().unwrap());
    eprintln!("paths compared: {paths:?}");
    for integration in [Integration::PAPER, Integration::DEFAULT] {
        let model = Model::ik(spread_ik(3))
            .with_integration(integration)
            .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap())
            .with_effect(EffectKind::from_id("wheel_asymmetry", 3).unwrap());
        let mut p = spread_ik(3).entries().to_vec();
        p.extend([0.02, -0.01, 0.03, -0.02, 0.01]);
        let res = model.resolve(&p).unwrap();
        for selection in [Selection::End, Selection::Path(1)] {
            let (gap, _) = max_gap(&model, &p, &runs, selection);
            assert!(gap < 1e-9, "{integration:?} {selection:?}: gap {gap:e} m");
            let prepared = PreparedRuns::new(&runs, res.fixed_dt_s, selection);
            let portable = prepared.errors_on(SimdPath::Portable, &res, &runs).unwrap();
            assert_eq!(portable.ends.len(), runs.len());
            for &path in &paths {
                let errors = prepared.errors_on(path, &res, &runs).unwrap();
                assert_eq!(bits(&errors), bits(&portable), "{path:?} {integration:?} {selection:?}");
            }
        }
    }
}

/// A run's errors and IK Jacobian rows are the same bits whether it shares a lane group with longer and
/// shorter runs or walks alone (the heading is not re-anchored past a lane's last step), with a sensor
/// offset (which reads the carried cosine and sine at the end).
#[test]
fn a_runs_numbers_do_not_depend_on_the_runs_in_its_group() {
    let runs = mixed_length_runs();
    // A sensor offset: the end pose reads the heading's cosine and sine.
    let model = Model::ik(spread_ik(3))
        .with_integration(Integration::DEFAULT)
        .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap());
    let mut p = spread_ik(3).entries().to_vec();
    p.extend([0.05, -0.03]);
    let res = model.resolve(&p).unwrap();
    let pose_bits = |e: &PoseError| [e.dx_m, e.dy_m, e.dtheta_rad].map(f64::to_bits);
    let rows = |p: &PreparedRuns, runs: &[Run]| {
        let mut out = Vec::new();
        p.ik_jacobian_rows(&res, runs, &mut |r| out.push((r.errors.to_vec(), r.jacobian.clone()))).unwrap();
        out
    };
    for selection in [Selection::End, Selection::Path(1)] {
        let prepared = PreparedRuns::new(&runs, None, selection);
        let (all, all_rows) = (prepared.errors(&res, &runs).unwrap(), rows(&prepared, &runs));
        let mut first_query = 0;
        for (i, run) in runs.iter().enumerate() {
            let one = std::slice::from_ref(run);
            let alone_prepared = PreparedRuns::new(one, None, selection);
            let alone = alone_prepared.errors(&res, one).unwrap();
            assert_eq!(pose_bits(&alone.ends[0]), pose_bits(&all.ends[i]), "run {i} {selection:?}");
            let queries = &all.at_queries[first_query..first_query + alone.at_queries.len()];
            assert!(queries.iter().zip(&alone.at_queries).all(|(a, b)| pose_bits(a) == pose_bits(b)), "run {i}");
            first_query += alone.at_queries.len();
            assert_eq!(rows(&alone_prepared, one)[0], all_rows[i], "run {i} {selection:?}");
        }
        assert_eq!(first_query, all.at_queries.len());
    }
}

/// The same on the twist-stage walk (a built-in twist-stage effect and a sensor offset): a run's end-pose
/// error is the same bits alone and in a group of longer and shorter runs.
#[test]
fn a_runs_numbers_on_the_twist_walk_do_not_depend_on_its_group() {
    let runs = mixed_length_runs();
    let model = Model::ik(spread_ik(3))
        .with_integration(Integration::DEFAULT)
        .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap())
        .with_effect(EffectKind::from_id("world_drift", 3).unwrap());
    let mut p = spread_ik(3).entries().to_vec();
    p.extend([0.05, -0.03, 0.004, -0.003]);
    let res = model.resolve(&p).unwrap();
    assert!(!res.twist_effects.is_empty());
    let pose_bits = |e: &PoseError| [e.dx_m, e.dy_m, e.dtheta_rad].map(f64::to_bits);
    let all = PreparedRuns::new(&runs, None, Selection::End).end_pose_errors(&res, &runs).unwrap();
    for (i, run) in runs.iter().enumerate() {
        let one = std::slice::from_ref(run);
        let alone = PreparedRuns::new(one, None, Selection::End).end_pose_errors(&res, one).unwrap();
        assert_eq!(pose_bits(&alone[0]), pose_bits(&all[i]), "run {i}");
    }
}
