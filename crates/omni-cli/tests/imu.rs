//! An IMU's yaw rate as a rotation reference (issue 28, `omnical imu`, `simulate --imu`) through the real
//! binary: on simulated runs of the paper's robot the rotation row comes back as motion capture gives it,
//! at any gyro rate, with the gyro's bias; the command says the translation is not reached; bad inputs are
//! refused naming the file and topic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use serde_json::Value;
use std::path::Path;
use support::{json, ok, omnical};

/// Simulated MCAP runs with an IMU at `rate` Hz, bias 0.005 rad/s.
fn simulate(dir: &Path, out: &str, rate: &str) {
    ok(
        &[
            "simulate",
            "--out",
            out,
            "--imu",
            "--imu-rate",
            rate,
            "--imu-bias",
            "0.005",
            "--runs-per-command",
            "1",
            "--duration",
            "6",
            "-q",
        ],
        dir,
    );
}

#[test]
fn the_rotation_row_comes_back_at_any_gyro_rate_and_the_translation_is_not_reached() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "sim", "100");
    let fit: Value = json(&["train", "sim/train", "--json"], d);
    let mocap: Vec<f64> = fit["matrix"][2].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let imu: Value = json(&["imu", "sim/train", "--json"], d);
    let row: Vec<f64> = imu["fit"]["row"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    for (i, (r, m)) in row.iter().zip(&mocap).enumerate() {
        eprintln!("wheel {i}: IMU {r:.6}, motion capture {m:.6} ({:+.3} %)", 100.0 * (r / m - 1.0));
        assert!((r / m - 1.0).abs() < 0.003, "wheel {i}: IMU {r} vs motion capture {m}");
    }
    let (bias, se) = (imu["fit"]["bias_rad_s"].as_f64().unwrap(), imu["fit"]["bias_std_rad_s"].as_f64().unwrap());
    assert!((bias - 0.005).abs() < (4.0 * se).max(2e-4), "bias {bias} ± {se}");
    // Another gyro rate (37 Hz, not a multiple of the wheels' 100 Hz) gives the same row.
    simulate(d, "slow", "37");
    let slow: Value = json(&["imu", "slow/train", "--json"], d);
    for (a, b) in slow["fit"]["row"].as_array().unwrap().iter().zip(&row) {
        assert!((a.as_f64().unwrap() / b - 1.0).abs() < 0.003, "37 Hz {a} vs 100 Hz {b}");
    }
    let text = ok(&["imu", "sim/train", "--out", "imu.toml"], d);
    assert!(text.contains("an IMU senses no translation: the translation rows are not reached"), "{text}");
    assert!(d.join("imu.toml").exists());
}

#[test]
fn bad_imu_inputs_are_refused_naming_the_file_and_topic() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "sim", "100");
    ok(&["simulate", "--out", "plain", "--runs-per-command", "1", "--duration", "2", "-q"], d);
    let cases: [(&[&str], &str); 4] = [
        (
            &["imu", "sim/train", "--gt-scans", "/scan"],
            "error: --gt-scans changes nothing for `omnical imu`: the IMU is the reference, and each recording one run",
        ),
        (
            &["imu", "sim/train/00-r0.mcap", "--topic", "/imu2"],
            "error: sim/train/00-r0.mcap: no topic \"/imu2\" in the recording; the Imu topics are /imu: name one (--topic)",
        ),
        (
            &["imu", "plain/train/00-r0.mcap"],
            "error: plain/train/00-r0.mcap: no topic \"/imu\" in the recording; no topic holds sensor_msgs/msg/Imu: record the IMU",
        ),
        (
            &["simulate", "--out", "csv", "--imu", "--format", "csv"],
            "error: --imu writes Imu messages into ROS 2 bags: use --format mcap (the default)",
        ),
    ];
    for (args, want) in cases {
        let out = omnical(args, d);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        let error = err.lines().find(|l| l.starts_with("error:")).unwrap_or_default();
        assert_eq!(error, want, "{args:?}: {err}");
    }
}

#[test]
fn info_points_the_imu_to_omnical_imu_and_refuses_what_is_no_recording() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "sim", "50");
    let v: Value = json(&["info", "sim/train/00-r0.mcap", "--json"], d);
    let topics = v["recordings"][0]["topics"].as_array().unwrap();
    let imu = topics.iter().find(|t| t["topic"] == "/imu").unwrap();
    assert_eq!(imu["role"], "imu");
    assert_eq!(imu["why"], "omnical imu --topic /imu fits the wheel matrix's rotation row");
    assert!((imu["rate_hz"].as_f64().unwrap() - 50.0).abs() < 0.1, "{imu}");
    let run = &v["recordings"][0]["read"]["runs"][0];
    assert_eq!(run["name"], "00-r0");
    // 6 s of motion between rests, sampled at 100 Hz: the duration is the samples' span.
    let samples = run["wheel_samples"].as_u64().unwrap();
    assert!(samples > 600, "{run}");
    assert!((run["duration_s"].as_f64().unwrap() - (samples - 1) as f64 * 0.01).abs() < 1e-9, "{run}");
    assert!((run["wheel_rate_hz"].as_f64().unwrap() - 100.0).abs() < 1e-6, "{run}");
    // Text: the same verdicts, one topic per line.
    let text = ok(&["info", "sim/train/00-r0.mcap"], d);
    assert!(text.contains("    /imu (sensor_msgs/msg/Imu, "), "{text}");
    assert!(text.contains("      IMU: omnical imu --topic /imu fits the wheel matrix's rotation row"), "{text}");
    assert!(text.contains("  omnical reads 1 run:\n    00-r0: "), "{text}");
    ok(&["simulate", "--out", "csv", "--format", "csv", "--runs-per-command", "1", "--duration", "2", "-q"], d);
    let out = omnical(&["info", "csv/train/00-r0.csv"], d);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim(), "error: csv/train/00-r0.csv: not a ROS recording (.mcap, .db3, .bag or a rosbag2 folder)");
}
