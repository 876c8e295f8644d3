//! Read speed of a 180-run dataset (one bag per run, 1050 JointState at 100 Hz + 40 PoseStamped each).
//! Speed is measured, not asserted (STYLE B6); run it in release mode:
//!
//! ```text
//! cargo test --release -p omni-cli --test mcap_speed -- --ignored --nocapture
//! ```
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a failed unwrap is a failed test

use omni_cli::dataset::mcap::{McapOptions, WriteOptions, read_file, write_run};
use omni_kin::{Command, Pose2, Run, RunData, StampedPose};
use std::time::Instant;

fn run(i: usize) -> Run {
    let n = 1050;
    let wheel_t_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
    let w = 1.0 + i as f64 * 0.01;
    let wheel_rad_s = wheel_t_s.iter().flat_map(|t| [w, -0.5 * w, (w * t).sin()]).collect();
    let end = wheel_t_s[n - 1];
    let truth =
        (0..40).map(|k| end * k as f64 / 39.0).map(|t| StampedPose { t_s: t, pose: Pose2::new(0.2 * t, 0.0, t) });
    Run::new(RunData {
        name: format!("run-{i:03}"),
        wheel_t_s,
        wheel_rad_s,
        n_wheels: 3,
        truth: truth.collect(),
        command: Some(Command { v_m_s: 0.2, alpha_rad: 0.0, omega_rad_s: 1.0 }),
        ..Default::default()
    })
    .unwrap()
}

#[test]
#[ignore = "timing; run in release with --ignored --nocapture"]
fn read_180_bags() {
    let dir = tempfile::tempdir().unwrap();
    let paths: Vec<_> = (0..180)
        .map(|i| {
            let path = dir.path().join(format!("run-{i:03}.mcap"));
            write_run(&path, &run(i), &WriteOptions::default()).unwrap();
            path
        })
        .collect();
    let bytes: u64 = paths.iter().map(|p| std::fs::metadata(p).unwrap().len()).sum();
    let opts = McapOptions::default();
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        let mut samples = 0;
        for p in &paths {
            let r = read_file(p, &opts).unwrap();
            samples += r.runs[0].n_samples();
        }
        assert_eq!(samples, 180 * 1050);
        best = best.min(start.elapsed().as_secs_f64());
    }
    eprintln!(
        "read 180 bags ({:.1} MB, 189000 JointState + 7200 PoseStamped messages) in {:.3} s (best of 3, one thread)",
        bytes as f64 / 1e6,
        best
    );
}
