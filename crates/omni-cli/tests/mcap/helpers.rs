//! Helpers shared by the `mcap_*` tests (included with `#[path]`).
#![allow(dead_code)]

use omni_kin::{Command, Pose2, Run, RunData, StampedPose};
use serde_json::Value;

/// A JSON array of numbers.
pub fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// Element-wise `|got - want| <= tol`.
pub fn close(got: &[f64], want: &[f64], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: lengths differ");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((g - w).abs() <= tol, "{what}[{i}]: got {g}, expected {w}");
    }
}

/// Poses against `[[t, x, y, theta], ...]`.
pub fn close_poses(got: &[StampedPose], want: &Value, what: &str) {
    let want: Vec<Vec<f64>> = want.as_array().unwrap().iter().map(floats).collect();
    assert_eq!(got.len(), want.len(), "{what}: lengths differ");
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        let g = [g.t_s, g.pose.x_m, g.pose.y_m, g.pose.theta_rad];
        close(&g, w, 1e-12, &format!("{what}[{i}] (t, x, y, theta)"));
    }
}

/// Checks a run against one expected entry of make_bags.py's JSON (absent keys are not checked).
pub fn check_run(run: &Run, want: &Value) {
    close(run.wheel_t_s(), &floats(&want["wheel_t_s"]), 1e-12, "wheel_t_s");
    close(run.wheel_rad_s(), &floats(&want["wheel_rad_s"]), 1e-12, "wheel_rad_s");
    close_poses(run.truth(), &want["truth"], "truth");
    if let Some(s) = want.get("wheel_start_rad") {
        close(run.wheel_start_rad(), &floats(s), 1e-15, "wheel_start_rad");
    }
    if let Some(c) = want.get("command") {
        let got = run.command().unwrap();
        close(&[got.v_m_s, got.alpha_rad, got.omega_rad_s], &floats(c), 1e-12, "command (v, alpha, omega)");
    }
    if let Some(o) = want.get("recorded_odometry") {
        close_poses(run.recorded_odometry(), o, "recorded_odometry");
    }
}

/// A run like `omnical simulate` makes: 3 wheels at 100 Hz from t = 0 for `duration_s`, ground truth at
/// 25 Hz turning at 2 rad/s (so the heading crosses ±π), a command and wheel start angles.
pub fn simulated_run(name: &str, duration_s: f64) -> Run {
    let n = (duration_s * 100.0).round() as usize + 1;
    let wheel_t_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
    let wheel_rad_s = wheel_t_s.iter().flat_map(|t| [1.0 + t, -0.5 * t, 2.0 * (3.0 * t).sin()]).collect();
    let m = (duration_s * 25.0).floor() as usize + 1;
    let truth = (0..m)
        .map(|k| k as f64 * 0.04)
        .map(|t| StampedPose { t_s: t, pose: Pose2::new(t.sin(), 0.1 * t, -3.0 + 2.0 * t) });
    Run::new(RunData {
        name: name.into(),
        wheel_t_s,
        wheel_rad_s,
        n_wheels: 3,
        truth: truth.collect(),
        command: Some(Command { v_m_s: 0.25, alpha_rad: 0.5, omega_rad_s: -0.75 }),
        wheel_start_rad: vec![0.5, -0.25, 3.0],
        ..Default::default()
    })
    .unwrap()
}

/// The design odometry of a run: its truth stretched in x.
pub fn design_odometry(run: &Run) -> Vec<StampedPose> {
    run.truth()
        .iter()
        .map(|p| StampedPose { t_s: p.t_s, pose: Pose2::new(1.1 * p.pose.x_m, p.pose.y_m, p.pose.theta_rad) })
        .collect()
}
