//! Unit tests of the relative pose error: window parsing, pairs, drift on straight and turning runs, the estimate at
//! the ground-truth stamps.

use super::*;
use approx::assert_relative_eq;

fn stamped(t_s: f64, x_m: f64, y_m: f64, theta_rad: f64) -> StampedPose {
    StampedPose { t_s, pose: Pose2::new(x_m, y_m, theta_rad) }
}

/// A straight line along x at `v` m/s sampled every 0.25 s (exact binary steps), heading `heading`.
fn line(n: usize, v: f64, heading: f64) -> Vec<StampedPose> {
    (0..n).map(|k| stamped(0.25 * k as f64, v * 0.25 * k as f64, 0.0, heading)).collect()
}

#[test]
fn windows_parse_and_bad_ones_say_why() {
    assert_eq!("1m".parse(), Ok(RpeDelta::DistanceM(1.0)));
    assert_eq!(" 0.5 m".parse(), Ok(RpeDelta::DistanceM(0.5)));
    assert_eq!("2s".parse(), Ok(RpeDelta::TimeS(2.0)));
    assert_eq!("1e-1s".parse(), Ok(RpeDelta::TimeS(0.1)));
    assert_eq!(RpeDelta::TimeS(2.5).to_string(), "2.5s");
    assert_eq!(RpeDelta::default().to_string(), "1m");
    let err = |s: &str| s.parse::<RpeDelta>().unwrap_err().to_string();
    assert_eq!(err("1km"), "expected a distance in metres or a time in seconds, as 1m or 2s");
    assert_eq!(err("1"), "expected a distance in metres or a time in seconds, as 1m or 2s");
    assert_eq!(err("m"), "expected a distance in metres or a time in seconds, as 1m or 2s");
    assert_eq!(err("-1m"), "the window must be longer than 0 (got -1m)");
    assert_eq!(err("0s"), "the window must be longer than 0 (got 0s)");
    assert_eq!(
        err("infm"),
        "`inf` is not a finite number (expected a distance in metres or a time in seconds, as 1m or 2s)"
    );
    assert_eq!(
        err("1.2.3s"),
        "`1.2.3` is not a finite number (expected a distance in metres or a time in seconds, as 1m or 2s)"
    );
}

/// evo's rule: the step lengths accumulate until they reach Δ, the overshoot dropped.
#[test]
fn pairs_chain_as_evos_consecutive_pairs() {
    let steps = [0.0, 0.6, 0.6, 0.3, 0.5, 0.6, 0.2];
    let mut x = 0.0;
    let path: Vec<StampedPose> = steps
        .iter()
        .enumerate()
        .map(|(k, s)| {
            x += s;
            stamped(k as f64, x, 0.0, 0.0)
        })
        .collect();
    // 0.6 + 0.6 = 1.2 ≥ 1 ends at 2; then 0.3 + 0.5 + 0.6 = 1.4 ends at 5; 0.2 is left over.
    assert_eq!(pairs(&path, RpeDelta::DistanceM(1.0)), [(0, 2), (2, 5)]);
    // Time: 3 s windows from 0, then from 3.
    assert_eq!(pairs(&path, RpeDelta::TimeS(3.0)), [(0, 3), (3, 6)]);
    assert_eq!(pairs(&path, RpeDelta::DistanceM(5.0)), []);
    assert_eq!(pairs(&[], RpeDelta::DistanceM(1.0)), []);
    // Exactly Δ counts (0.25 m steps add up exactly).
    assert_eq!(pairs(&line(9, 1.0, 0.0), RpeDelta::DistanceM(1.0)), [(0, 4), (4, 8)]);
}

#[test]
fn identical_trajectories_have_no_error() {
    let q: Vec<StampedPose> =
        (0..40).map(|k| k as f64 * 0.1).map(|t| stamped(t, t.sin(), 2.0 * t.cos(), 0.3 * t)).collect();
    let p: Vec<Pose2> = q.iter().map(|s| s.pose).collect();
    let e = pair_errors(&q, &p, RpeDelta::DistanceM(0.5)).unwrap();
    assert!(e.len() >= 5, "{} pairs", e.len());
    let s = RpeSummary::of(&e, RpeDelta::DistanceM(0.5));
    // Zero but for the rounding of the compositions.
    assert!(s.translation_m.max < 1e-15 && s.rotation_rad.max < 1e-15 && s.drift_pct.max < 1e-13, "{s:?}");
}

/// A 2 % scale error along a straight line (driven sideways, heading 90°): 2 % drift, exactly.
#[test]
fn a_two_percent_scale_error_is_two_percent_drift() {
    let q = line(41, 0.5, std::f64::consts::FRAC_PI_2);
    let p: Vec<Pose2> = q.iter().map(|s| Pose2::new(1.02 * s.pose.x_m, s.pose.y_m, s.pose.theta_rad)).collect();
    let e = pair_errors(&q, &p, RpeDelta::DistanceM(1.0)).unwrap();
    // 0.125 m steps: eight of them make a pair of 1 m exactly, 5 m in 5 pairs.
    assert_eq!(e.len(), 5);
    let s = RpeSummary::of(&e, RpeDelta::DistanceM(1.0));
    assert_relative_eq!(s.drift_pct.mean, 2.0, epsilon = 1e-12);
    assert_relative_eq!(s.drift_pct.max, 2.0, epsilon = 1e-12);
    assert_relative_eq!(s.translation_m.rmse, 0.02, epsilon = 1e-12);
    assert_eq!(s.rotation_rad.max, 0.0);
    assert_eq!(s.drift_pairs, 5);
}

/// A yaw-rate bias `b` on a straight run at `v`: the estimate drives arcs of rate `b`. Every 2 s pair
/// turns `2b` too far, and its end lands on the arc's chord instead of the line.
#[test]
fn a_yaw_rate_bias_gives_its_rotation_per_window() {
    let (v, b, window) = (0.5, 0.05, 2.0);
    let q = line(33, v, 0.0); // 8 s
    let arc = |t: f64| Pose2::new(v / b * (b * t).sin(), v / b * (1.0 - (b * t).cos()), b * t);
    let p: Vec<Pose2> = q.iter().map(|s| arc(s.t_s)).collect();
    let e = pair_errors(&q, &p, RpeDelta::TimeS(window)).unwrap();
    assert_eq!(e.iter().map(|e| (e.from, e.to)).collect::<Vec<_>>(), [(0, 8), (8, 16), (16, 24), (24, 32)]);
    let s = RpeSummary::of(&e, RpeDelta::TimeS(window));
    assert_relative_eq!(s.rotation_rad.rmse, b * window, epsilon = 1e-12);
    assert_relative_eq!(s.rotation_rad.max, b * window, epsilon = 1e-12);
    let a = b * window;
    let t = (v / b * a.sin() - v * window).hypot(v / b * (1.0 - a.cos()));
    assert_relative_eq!(s.translation_m.rmse, t, epsilon = 1e-12);
    assert_relative_eq!(s.drift_pct.mean, 100.0 * t / (v * window), epsilon = 1e-9);
}

/// A time window's pair standing still stays out of the drift (its creep would be divided by 0 m); it
/// counts in the translation error.
#[test]
fn standing_pairs_stay_out_of_the_drift() {
    let q: Vec<StampedPose> = (0..9).map(|k| stamped(k as f64, if k > 4 { 1.0 } else { 0.0 }, 0.0, 0.0)).collect();
    // 10 % too far and 1 mm of creep per second.
    let p: Vec<Pose2> = q.iter().map(|s| Pose2::new(1.1 * s.pose.x_m + 0.001 * s.t_s, 0.0, 0.0)).collect();
    let e = pair_errors(&q, &p, RpeDelta::TimeS(4.0)).unwrap();
    assert_eq!(e.iter().map(|e| (e.from, e.to, e.distance_m)).collect::<Vec<_>>(), [(0, 4, 0.0), (4, 8, 1.0)]);
    let s = RpeSummary::of(&e, RpeDelta::TimeS(4.0));
    assert_eq!((s.pairs, s.drift_pairs), (2, 1));
    assert_relative_eq!(s.translation_m.max, 0.104, epsilon = 1e-12);
    assert_relative_eq!(s.translation_m.mean, 0.054, epsilon = 1e-12);
    assert_relative_eq!(s.drift_pct.mean, 10.4, epsilon = 1e-9);
    let short = pair_errors(&q, &p[1..], RpeDelta::TimeS(4.0)).unwrap_err().to_string();
    assert_eq!(short, "estimated poses (one per reference pose) has 8 entries, expected 9");
}
/// The estimate read off the evaluator's errors is the walk's odometry at the ground-truth stamps;
/// errors at other poses than every one are refused, naming the run.
#[test]
fn the_estimate_is_the_odometry_at_the_ground_truth_stamps() {
    use crate::odometry::{Selection, residuals};
    use crate::simulate::{SimConfig, flower_commands, simulate};
    use crate::{FittedModel, IkMatrix, Model, RunModels};
    let config = SimConfig {
        commands: flower_commands().into_iter().step_by(9).collect(),
        runs_per_command: 1,
        duration_s: 3.0,
        seed: 3,
        ..SimConfig::default()
    };
    let runs = simulate(&config, &FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated())), "").unwrap();
    let design = FittedModel::paper_design();
    let errors = RunModels::from(&design).errors(&runs, Selection::Path(1)).unwrap();
    let rel = RelativeErrors::new(&runs, &errors, RpeDelta::DistanceM(0.5)).unwrap();
    let res = design.model.resolve(&design.params).unwrap();
    for (i, run) in runs.iter().enumerate() {
        let walk = residuals(&res, run, Selection::Path(1));
        let ours = estimate_at_truth(run.truth(), errors.run(i));
        assert_eq!(ours[0], run.truth()[0].pose);
        for (w, o) in walk.iter().zip(&ours[1..]) {
            let e = w.predicted.error_to(o);
            assert!(e.position_m() < 1e-9 && e.dtheta_rad.abs() < 1e-9, "run {i}: {e:?}");
        }
    }
    let all = rel.summary();
    assert_eq!(all.pairs, (0..runs.len()).map(|i| rel.run(i).len()).sum::<usize>());
    assert!(all.pairs >= runs.len() && all.drift_pct.mean > 0.1, "{all:?}");
    let ends = RunModels::from(&design).errors(&runs, Selection::End).unwrap();
    let e = RelativeErrors::new(&runs, &ends, RpeDelta::DEFAULT).unwrap_err().to_string();
    let n = runs[0].truth().len() - 1;
    assert_eq!(
        e,
        format!("run {}: errors at the ground-truth poses after the first has 1 entries, expected {n}", runs[0].name())
    );
}
