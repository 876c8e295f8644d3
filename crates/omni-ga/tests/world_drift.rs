//! The catalogue's `world_drift` (a constant world-frame velocity while moving: a tilted floor, a moving
//! ground-truth frame) found by diagnose on simulated data that has it, with its parameters recovered.
#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use omni_ga::diagnose::{DiagnoseOptions, diagnose};
use omni_kin::simulate::{SimConfig, flower_commands, simulate};
use omni_kin::{CostKind, EffectKind, FittedModel, IkMatrix, Model, cost};

/// True drift while moving: (+3.9, −2.1) mm/s in the world frame.
const DRIFT_M_S: [f64; 2] = [0.0039, -0.0021];

fn base() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))
}

#[test]
fn diagnose_finds_a_world_frame_drift_and_recovers_it() {
    let mut truth = base().with_effect(EffectKind::from_id("world_drift", 3).unwrap());
    let n = truth.params.len();
    truth.params[n - 2..].copy_from_slice(&DRIFT_M_S);
    let commands = flower_commands().into_iter().step_by(3).collect();
    let cfg = SimConfig { commands, runs_per_command: 4, duration_s: 4.0, seed: 21, ..SimConfig::default() };
    let runs = simulate(&cfg, &truth, "w/").unwrap();
    let d = diagnose(&base(), &base(), &runs, None, &DiagnoseOptions::default()).unwrap();
    eprintln!("{}\n{:?}", d.verdict_text, d.ranking.first().map(|c| (&c.effect, c.held_out_gain, &c.params)));
    assert_eq!(d.verdict.as_deref(), Some("world_drift"), "{}", d.verdict_text);
    let top = &d.ranking[0];
    assert!(top.held_out_gain > 0.3, "held-out gain {}", top.held_out_gain);
    for (p, truth) in top.params.iter().zip(DRIFT_M_S) {
        let se = p.std_error.unwrap();
        assert!((p.value - truth).abs() < 2e-4, "{} = {} vs {truth}", p.name, p.value);
        assert!((p.value - truth).abs() < 5.0 * se.max(2e-5), "{} = {} ± {se} vs {truth}", p.name, p.value);
    }
    assert_eq!((top.params[0].name.as_str(), top.params[0].unit.as_str()), ("drift_x_m_s", "m/s"));
    // Nothing is left once it is added.
    assert!(!d.unexplained, "{}", d.verdict_text);
}

#[test]
fn the_drift_acts_only_while_the_wheels_turn() {
    // At rest (before and after the motion) the odometry with the drift equals the odometry without it.
    let mut truth = base().with_effect(EffectKind::from_id("world_drift", 3).unwrap());
    let n = truth.params.len();
    truth.params[n - 2..].copy_from_slice(&DRIFT_M_S);
    let cfg = SimConfig {
        commands: flower_commands()[..1].to_vec(),
        runs_per_command: 1,
        duration_s: 2.0,
        ..SimConfig::default()
    }
    .noise_free();
    let runs = simulate(&cfg, &truth, "r/").unwrap();
    // The true model reproduces the data (to the fine-step integration), the base model does not.
    let with = cost::cost(&truth.model, &truth.params, &runs, CostKind::EndPose).unwrap();
    let without = cost::cost(&base().model, &base().params, &runs, CostKind::EndPose).unwrap();
    assert!(with < 2e-4, "with the drift: {with}");
    // 2 s of motion (plus the controller's ramp) at |drift| = 4.43 mm/s: about 9 mm.
    assert!((0.008..0.011).contains(&without), "without the drift: {without}");
}
