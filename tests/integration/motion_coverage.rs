//! Issue 25 item 8: a rotation gain that depends on the translation (`turn_scrub`, ω ← ω (1 + k |v|)),
//! the way OptiOdom's omni4 over-rotates on circles after a fit on squares. Squares (sides, then quarter
//! turns on the spot) never translate and rotate at once, so no fit on them can see it: diagnose must say
//! which motions the training runs lack and what to record. With arcs among the training runs the effect
//! is found, and one model serves squares and circles.
use crate::common::path_cost;
use omnical::ga::calibrate::{Calibration, Plan, Preset, calibrate};
use omnical::ga::coverage::MotionKind;
use omnical::ga::diagnose::{DiagnoseOptions, Finding, diagnose};
use omnical::ga::observe::NoopObserver;
use omnical::kin::simulate::{SimConfig, simulate, simulate_legs, square_legs};
use omnical::kin::{Command, EffectKind, FittedModel, Model, RobotGeometry, Run};

/// The true turn-rate gain per m/s of translation: at 0.2 m/s the robot turns 2.6 % less than its wheels
/// say (odometry heading / true heading 1.026, as OptiOdom's omni4 on circles).
const K_S_M: f64 = -0.13;

fn robot() -> RobotGeometry {
    RobotGeometry::omni_regular(4, 0.05, 0.2, 45f64.to_radians())
}

fn design() -> FittedModel {
    FittedModel::nominal(Model::ik(robot().twist_from_wheels().unwrap()))
}

/// The design with `turn_scrub` at [`K_S_M`].
fn truth() -> FittedModel {
    let mut t = design().with_effect(EffectKind::from_id("turn_scrub", 4).unwrap());
    t.set("turn_scrub.k_s_m", K_S_M).unwrap();
    t
}

fn config(seed: u64) -> SimConfig {
    SimConfig { design: robot(), seed, ..SimConfig::default() }
}

/// Squares of 1 m at 0.2 m/s with quarter turns at ±0.5 rad/s, `n` runs (both senses).
fn squares(seed: u64, n: usize, prefix: &str) -> Vec<Run> {
    (0..n)
        .map(|i| {
            let omega = if i % 2 == 0 { 0.5 } else { -0.5 };
            simulate_legs(&config(seed), &truth(), &square_legs(1.0, 0.2, omega), i as u64, format!("{prefix}{i}"))
                .unwrap()
        })
        .collect()
}

/// Arcs (circles) at 0.2 m/s and ±0.35 rad/s, `reps` each, 10 s.
fn circles(seed: u64, reps: usize, prefix: &str) -> Vec<Run> {
    let commands = [0.35, -0.35].map(|w| Command { v_m_s: 0.2, alpha_rad: 0.0, omega_rad_s: w }).to_vec();
    let cfg = SimConfig { commands, runs_per_command: reps, ..config(seed) };
    simulate(&cfg, &truth(), prefix).unwrap()
}

/// The default preset's fit of the design matrix plus `effects`.
fn fit(train: &[Run], effects: &[&str]) -> Calibration {
    let mut start = design();
    for id in effects {
        start = start.with_effect(EffectKind::from_id(id, 4).unwrap());
    }
    let plan = Plan::preset(Preset::Default, start.params.len());
    calibrate(&start, train, &plan, &mut NoopObserver).unwrap()
}

#[test]
fn squares_lack_arcs_and_arcs_find_the_turn_gain() {
    let train_squares = squares(1, 6, "train/square-");
    let held_circles = circles(2, 3, "held/circle-");
    let held_squares = squares(3, 4, "held/square-");
    let oracle = path_cost(&truth(), &held_circles);

    // Trained on squares: fine on squares, 9× the oracle on circles, and diagnose says why.
    let on_squares = fit(&train_squares, &[]).fitted;
    assert!(path_cost(&on_squares, &held_circles) > 5.0 * oracle);
    let d = diagnose(&on_squares, &design(), &train_squares, Some(&held_circles), &DiagnoseOptions::default()).unwrap();
    let c = d.coverage.as_ref().unwrap();
    assert!(matches!(d.facts.first(), Some(Finding::MissingMotions(_))), "{:?}", d.findings);
    // The squares: sides (translating) and quarter turns (rotating); the corners blend the two briefly.
    assert!(c.train.translating > 0.5 && c.train.rotating > 0.3, "{:?}", c.train);
    assert!(c.train.translating_while_rotating < 0.05, "{:?}", c.train);
    assert!(c.held_out.translating_while_rotating > 0.95, "{:?}", c.held_out);
    assert_eq!(c.gaps.len(), 1, "{:?}", c.gaps);
    let gap = &c.gaps[0];
    assert_eq!(gap.kind, MotionKind::TranslatingWhileRotating);
    assert!(gap.held_out_share > 0.95 && gap.train_share < 0.05, "{gap:?}");
    assert!((gap.speed_m_s - 0.2).abs() < 0.01 && (gap.turn_rate_rad_s - 0.35).abs() < 0.02, "{gap:?}");
    // What to record: the circles' arcs, both ways.
    let mut turns: Vec<f64> = gap.record.iter().map(|r| r.omega_rad_s).collect();
    turns.sort_by(f64::total_cmp);
    assert_eq!(turns.len(), 2, "{:?}", gap.record);
    assert!((turns[0] + 0.35).abs() < 0.02 && (turns[1] - 0.35).abs() < 0.02, "{:?}", gap.record);
    assert!(gap.record.iter().all(|r| (r.v_m_s - 0.2).abs() < 0.01 && r.alpha_rad == 0.0), "{:?}", gap.record);
    assert_eq!(c.unseen_effects, ["rotation_slip", "turn_scrub"]);
    let said = &d.findings[0];
    for words in [
        "translating while rotating (arcs): 99 % of the held-out motion",
        "no fit on these runs can see \
                   rotation_slip, turn_scrub",
        "`omnical plan --effect rotation_slip --effect turn_scrub`",
    ] {
        assert!(said.contains(words), "{said}");
    }

    // With arcs (two speeds, two turn rates) among the training runs: diagnose names turn_scrub, and one
    // model with it serves circles and squares as well as the true robot does.
    let mut train = train_squares;
    train.extend(circles(4, 2, "train/circle-"));
    let slow = [0.5, -0.5].map(|w| Command { v_m_s: 0.1, alpha_rad: 0.0, omega_rad_s: w }).to_vec();
    train.extend(
        simulate(&SimConfig { commands: slow, runs_per_command: 2, ..config(5) }, &truth(), "t/slow-").unwrap(),
    );
    let plain = fit(&train, &[]).fitted;
    let d = diagnose(&plain, &design(), &train, Some(&held_circles), &DiagnoseOptions::default()).unwrap();
    assert_eq!(d.verdict.as_deref(), Some("turn_scrub"), "{}", d.verdict_text);
    assert!(d.coverage.as_ref().is_some_and(|c| !c.lacking()), "{:?}", d.coverage);
    let with = fit(&train, &["turn_scrub"]);
    let k = with.identifiability.params.last().unwrap();
    let se = k.std_error.unwrap();
    assert!((k.value - K_S_M).abs() <= 3.0 * se && se < 0.01, "k_s_m = {} ± {se}, truth {K_S_M}", k.value);
    let (circles_plain, circles_with) = (path_cost(&plain, &held_circles), path_cost(&with.fitted, &held_circles));
    let (squares_with, squares_oracle) = (path_cost(&with.fitted, &held_squares), path_cost(&truth(), &held_squares));
    assert!(circles_plain > 3.0 * oracle, "circles without the effect {circles_plain} m, oracle {oracle} m");
    assert!(circles_with <= 1.5 * oracle, "circles {circles_with} m, oracle {oracle} m");
    assert!(squares_with <= 1.5 * squares_oracle, "squares {squares_with} m, oracle {squares_oracle} m");
}
