//! The lane kernel against the literal walk: any wheel count, the robot-type models, sensor offsets, clock
//! lags, wheel- and twist-stage effects (and the affine law it relies on), and what it declines.

use super::*;

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
        (vec!["learned:world"], vec![0.003, -0.002, 0.01, -0.02, 0.015, -0.01]),
        (vec!["learned:time"], vec![0.001, -0.0005, 0.002, 0.003]),
        (
            vec!["time_offset", "rotation_slip", "wheel_eccentricity", "sensor_offset_yaw", "learned:time"],
            vec![0.02, -0.1, 0.02, -0.01, 0.01, 0.015, 0.0, -0.02, 0.03, -0.02, 0.05, 0.001, -0.0005, 0.002, 0.003],
        ),
    ];
    for (ids, values) in cases {
        for integration in [Integration::PAPER, Integration::DEFAULT] {
            let (model, p) = paper_with(&ids, &values, integration);
            for selection in [Selection::End, Selection::Path(1), Selection::Path(7)] {
                let (gap, count) = max_gap(&model, &p, &runs, selection);
                assert!(gap < 1e-9, "{ids:?} {integration:?} {selection:?}: gap {gap:e} m");
                assert!(count >= runs.len());
            }
        }
    }
}
