//! The odometry noise model (issue 46) on simulated runs with a known slip noise: the fitted rates (and so
//! AMCL's alphas, which are the rates over the update thresholds) match the truth within 10 %, and on
//! held-out runs the 95 % ellipse holds 93–97 % of the errors at 1 m and 5 m.
#![allow(clippy::unwrap_used)]

use omni_kin::evaluate::Evaluator;
use omni_kin::noise::{self, Amcl, FitNoiseOptions, Horizon, NoiseRates, Predictor};
use omni_kin::simulate::{SimConfig, simulate};
use omni_kin::{FittedModel, IkMatrix, Model, Run, Selection};

/// The true slip of the simulated base.
const TRUTH: NoiseRates = NoiseRates {
    rot_per_rad: 4e-4,
    rot_per_m: 3e-4,
    trans_per_m: 6e-4,
    trans_per_rad: 2e-4,
    strafe_per_m: 4e-4,
    ..NoiseRates::ZERO
};

fn poses(model: &FittedModel, runs: &[Run]) -> Vec<noise::RunPoses> {
    let ev = Evaluator::new(&model.model, runs, Selection::Path(1)).unwrap();
    let errors = ev.errors(&model.model.resolve(&model.params).unwrap());
    noise::run_poses(runs, &errors).unwrap()
}

/// Seed 5 (all five rates within 7 %, their bootstrap standard errors 3–7 %). Measured on other seeds with
/// the same set: 6 and 7 within 10 % too; 46 puts `rot_per_m`, the rate the flowers tell least from
/// `rot_per_rad` (they turn while they drive), 19 % low, 3.2 standard errors. Coverage 94.8–95.8 % on all
/// four.
#[test]
fn slip_noise_rates_are_recovered_and_held_out_coverage_is_95_percent() {
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let config = SimConfig {
        runs_per_command: 12,
        duration_s: 30.0,
        ticks_per_rev: None,
        wheel_noise_rad_s: 0.0,
        slip_noise: Some(TRUTH),
        seed: 5,
        ..SimConfig::default()
    };
    let runs = simulate(&config, &truth, "").unwrap();
    // Nine repetitions of each command (216 runs of 30 s, about 4400 windows) to train on, three held out.
    let (mut train, mut held_out) = (Vec::new(), Vec::new());
    for (i, r) in runs.into_iter().enumerate() {
        if i % 4 == 3 { held_out.push(r) } else { train.push(r) }
    }
    let fitted = noise::fit(&poses(&truth, &train), true, &FitNoiseOptions::default()).unwrap();
    let (got, want) = (fitted.rates.to_vec(), TRUTH.to_vec());
    eprintln!(
        "fitted {:?}\n± {:?}\nsystematic {:?}, {} windows",
        fitted.rates, fitted.std_errors, fitted.systematic, fitted.windows
    );
    for (m, name) in noise::PARAM_NAMES.iter().enumerate().take(5) {
        // (A random walk's errors: the per-run biases and the wandering heading are not in these runs.)
        let rel = (got[m] - want[m]).abs() / want[m];
        assert!(
            rel < 0.10,
            "{name}: fitted {} ± {}, truth {}",
            got[m],
            fitted.std_errors.unwrap().to_vec()[m],
            want[m]
        );
    }
    // The floor is the ground truth's noise: 2 mm and 3 mrad.
    assert!((fitted.rates.floor_position_m2.sqrt() - 0.002).abs() < 0.0005, "{:?}", fitted.rates);
    assert!((fitted.rates.floor_heading_rad2.sqrt() - 0.003).abs() < 0.001, "{:?}", fitted.rates);
    let amcl = Amcl::from_rates(&fitted.rates, true, 0.25, 0.2);
    let amcl_truth = Amcl::from_rates(&TRUTH, true, 0.25, 0.2);
    for (a, b) in amcl.alpha.iter().zip(amcl_truth.alpha) {
        assert!((a - b).abs() < 0.1 * b, "alphas {:?} vs truth {:?}", amcl.alpha, amcl_truth.alpha);
    }
    let check = noise::coverage(&poses(&truth, &held_out), true, "fitted", &Predictor::Rates(fitted.rates));
    for h in &check.horizons {
        if matches!(h.horizon, Horizon::DistanceM(_)) {
            assert!((0.93..=0.97).contains(&h.coverage), "{h:?}");
            assert!(h.windows > 100, "{h:?}");
        }
    }
}

/// Runs of a base whose odometry drives each run `1 + s` times the true distance (a run's own tyre: `s`
/// drawn per run with a 2 % spread) and turns `1 + γ` times the true angle (1 % spread), on top of a small
/// random walk: loops of arcs and straights, as a robot drives around a room.
fn biased_runs(n: usize, seed: u64) -> Vec<noise::RunPoses> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).unwrap();
    (0..n)
        .map(|r| {
            let (s, g) = (0.02 * unit.sample(&mut rng), 0.01 * unit.sample(&mut rng));
            let mut truth = vec![omni_kin::Pose2::new(0.0, 0.0, 0.0)];
            let mut odometry = truth.clone();
            for k in 0..1200 {
                // 1 cm steps; a turn of 0.5 rad/m every other metre, its sign by the run.
                let turn = if (k / 100) % 2 == 1 { 0.005 * if r % 2 == 0 { 1.0 } else { -1.0 } } else { 0.0 };
                let step = |p: &omni_kin::Pose2, d: f64, a: f64| {
                    omni_kin::Pose2::new(p.x_m + d * p.theta_rad.cos(), p.y_m + d * p.theta_rad.sin(), p.theta_rad + a)
                };
                let walk = 1e-4 * unit.sample(&mut rng);
                truth.push(step(truth.last().unwrap(), 0.01, turn));
                odometry.push(step(odometry.last().unwrap(), 0.01 * (1.0 + s) + walk, turn * (1.0 + g)));
            }
            noise::RunPoses { truth, odometry }
        })
        .collect()
}

/// A per-run error grows with the distance itself (variance `d²`): fitted as such, its spread comes back,
/// and the held-out 95 % ellipse holds at 1 m and 5 m, where the random walk alone would be too bold.
#[test]
fn per_run_biases_are_recovered_and_keep_held_out_coverage() {
    let fitted = noise::fit(&biased_runs(60, 11), false, &FitNoiseOptions::default()).unwrap();
    let r = fitted.rates;
    eprintln!("fitted {r:?}\n± {:?}", fitted.std_errors);
    assert!((r.run_scale_var.sqrt() - 0.02).abs() < 0.004, "scale spread {}", r.run_scale_var.sqrt());
    // The turn scale shares the arcs with the wandering heading: within three standard errors.
    let se = fitted.std_errors.unwrap();
    assert!(
        (r.run_turn_scale_var - 1e-4).abs() < 3.0 * se.run_turn_scale_var,
        "turn {} ± {}",
        r.run_turn_scale_var,
        se.run_turn_scale_var
    );
    let held_out = biased_runs(30, 12);
    let check = noise::coverage(&held_out, false, "fitted", &Predictor::Rates(r));
    let walk_only = noise::coverage(&held_out, false, "walk", &Predictor::Rates(r.random_walk()));
    for (h, w) in check.horizons.iter().zip(&walk_only.horizons) {
        eprintln!("{h:?}\n  random walk alone: {w:?}");
        if matches!(h.horizon, Horizon::DistanceM(_)) {
            assert!((0.90..=0.98).contains(&h.coverage), "{h:?}");
            assert!(w.coverage < 0.85, "the random walk alone covers {w:?}");
        }
    }
}
