//! An IMU's yaw rate as a rotation reference (issue 28, `omnical imu`, `simulate --imu`) through the real
//! binary: on simulated runs of the paper's robot the rotation row comes back as motion capture gives it,
//! at any gyro rate, with the gyro's bias; the command says the translation is not reached; bad inputs are
//! refused naming the file and topic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use serde_json::Value;
use std::path::Path;
use support::{json, ok, omnical};

/// Simulated MCAP runs with an IMU at `rate` Hz, bias 0.005 rad/s, and `more` simulate options.
fn simulate_with(dir: &Path, out: &str, rate: &str, more: &[&str]) {
    let mut args =
        vec!["simulate", "--out", out, "--imu", "--imu-rate", rate, "--imu-bias", "0.005", "--runs-per-command", "1"];
    args.extend(["--duration", "6", "-q"]);
    args.extend(more);
    ok(&args, dir);
}

/// Simulated MCAP runs with an upright IMU at `rate` Hz, bias 0.005 rad/s.
fn simulate(dir: &Path, out: &str, rate: &str) {
    simulate_with(dir, out, rate, &[]);
}

/// The fitted rotation row of `omnical imu ARGS --json`, and the document.
fn imu_row(args: &[&str], dir: &Path) -> (Vec<f64>, Value) {
    let mut args = args.to_vec();
    args.push("--json");
    let doc: Value = json(&args, dir);
    (doc["fit"]["row"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect(), doc)
}

/// The first `error:` line of `omnical ARGS`, which must exit with status 2.
fn refusal(args: &[&str], dir: &Path) -> String {
    let out = omnical(args, dir);
    assert_eq!(out.status.code(), Some(2), "{args:?}");
    let err = String::from_utf8(out.stderr).unwrap();
    err.lines().find(|l| l.starts_with("error:")).unwrap_or_default().to_string()
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
            "error: --gt-scans changes nothing for `omnical imu`: it reads no ground truth (the IMU is the reference)",
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
        assert_eq!(refusal(args, d), want, "{args:?}");
    }
}

/// Every data option `omnical imu` does not read is refused, naming the option and why (issue 28).
#[test]
fn every_data_option_that_changes_nothing_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    const GT: &str = "it reads no ground truth (the IMU is the reference)";
    let cases: [(&[&str], &str, &str); 13] = [
        (&["--gt", "x.tum"], "--gt", GT),
        (&["--gt-topic", "/mocap"], "--gt-topic", GT),
        (&["--gt-parent-frame", "map"], "--gt-parent-frame", GT),
        (&["--gt-child-frame", "base_link"], "--gt-child-frame", GT),
        (&["--gt-columns", "t=stamp"], "--gt-columns", GT),
        (&["--gt-units", "length=mm"], "--gt-units", GT),
        (&["--gt-scans", "/scan"], "--gt-scans", GT),
        (&["--gt-kind", "relative"], "--gt-kind", GT),
        (&["--gt-window", "2"], "--gt-window", GT),
        (&["--gt-mount", "0,0,0"], "--gt-mount", GT),
        (&["--gt-time-offset", "0.1"], "--gt-time-offset", GT),
        (&["--split", "1"], "--split", "each recording is one run"),
        (
            &["--ticks-per-rev", "4096"],
            "--ticks-per-rev",
            "it reads ROS recordings, whose JointState gives the wheel speeds (ticks per revolution convert CSV tick \
             columns)",
        ),
    ];
    for (option, flag, why) in cases {
        let mut args = vec!["imu", "missing.mcap"];
        args.extend(option);
        assert_eq!(refusal(&args, d), format!("error: {flag} changes nothing for `omnical imu`: {why}"));
    }
    // A project's ground truth for training (project-wide keys) leaves `omnical imu` alone; set for `imu`
    // itself, it is refused.
    simulate(d, "sim", "100");
    std::fs::write(d.join("omnical.toml"), "gt_topic = \"/mocap\"\nsplit = 2\nticks_per_rev = 4096\n").unwrap();
    let (row, _) = imu_row(&["imu", "sim/train/00-r0.mcap"], d);
    assert_eq!(row.len(), 3);
    std::fs::write(d.join("omnical.toml"), "[imu]\ngt_topic = \"/mocap\"\n").unwrap();
    assert_eq!(
        refusal(&["imu", "sim/train/00-r0.mcap"], d),
        format!("error: --gt-topic changes nothing for `omnical imu`: {GT}")
    );
}

/// An IMU upside down (roll 180°) or on its side (roll 90°) with its mount on /tf_static gives the upright
/// IMU's row (the same seed: the same gyro samples, turned into the IMU's frame and back); without the
/// transform it is refused, naming the files and topic and what to do, and `--mount` reads it right.
#[test]
fn a_mounted_imu_gives_the_upright_row_with_its_mount_and_is_refused_without() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "up", "100");
    simulate_with(d, "down", "100", &["--imu-mount", "180,0,0"]);
    simulate_with(d, "side", "100", &["--imu-mount", "90,0,0"]);
    simulate_with(d, "bare", "100", &["--imu-mount", "180,0,0", "--imu-tf", "none"]);
    simulate_with(d, "flat", "100", &["--imu-mount", "0,-90,30", "--imu-tf", "none"]);
    let (up, doc) = imu_row(&["imu", "up/train"], d);
    assert_eq!(doc["mounts"][0]["source"], "transforms");
    for (dir, roll) in [("down", 180.0), ("side", 90.0)] {
        let (row, doc) = imu_row(&["imu", &format!("{dir}/train")], d);
        let m = &doc["mounts"][0];
        assert_eq!(
            (m["source"].as_str(), m["base_frame"].as_str(), m["recordings"].as_u64()),
            (Some("transforms"), Some("base_link"), Some(36))
        );
        assert!((m["roll_deg"].as_f64().unwrap() - roll).abs() < 1e-9, "{m}");
        for (a, b) in row.iter().zip(&up) {
            assert!((a / b - 1.0).abs() < 1e-9, "{dir}: {a} vs upright {b}");
        }
    }
    let text = ok(&["imu", "down/train"], d);
    assert!(text.contains("IMU mount from the static transforms (base_link → imu_link): roll 180.0°, pitch 0.0°, yaw 0.0° (z down), 36 recordings"), "{text}");
    assert_eq!(
        refusal(&["imu", "bare/train"], d),
        "error: bare/train/00-r0.mcap, bare/train/01-r0.mcap, bare/train/02-r0.mcap, and 33 more recordings: topic \
         \"/imu\" (frame \"imu_link\"): the rotation row fitted with the IMU upright points against the design's \
         (their dot product is -1.784e-1 < 0): the IMU's z axis seems to point down. Publish its mount on /tf_static \
         (base_link → imu_link, as robot_state_publisher does from the URDF) or give it: --mount 180,0,0 \
         (ROLL,PITCH,YAW_DEG in degrees; Python: mount=(180, 0, 0))"
    );
    let (given, doc) = imu_row(&["imu", "bare/train", "--mount", "180,0,0"], d);
    assert_eq!(doc["mounts"][0]["source"], "given");
    assert!(given.iter().zip(&up).all(|(a, b)| (a / b - 1.0).abs() < 1e-9), "{given:?} vs {up:?}");
    // Pitch −90°: the IMU's x axis points up; unstated, it is refused as on its side, and the hint reads it.
    let err = refusal(&["imu", "flat/train/00-r0.mcap"], d);
    assert!(err.starts_with("error: flat/train/00-r0.mcap: topic \"/imu\" (frame \"imu_link\"): the IMU's x axis turns with the base more than its z axis"), "{err}");
    assert!(err.contains("give it: --mount 0,-90,0 if its x axis points up (0,90,0 if down"), "{err}");
    let (flat, _) = imu_row(&["imu", "flat/train", "--mount", "0,-90,30"], d);
    assert!(flat.iter().zip(&up).all(|(a, b)| (a / b - 1.0).abs() < 1e-9), "{flat:?} vs {up:?}");
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
    // A CSV run is an input the loader reads, so info describes it (issue 48); a file that is none is refused
    // naming what is read.
    let csv = ok(&["info", "csv/train/00-r0.csv"], d);
    assert!(csv.contains("  an omnical CSV run (t_s, wheel speeds, ground-truth pose per row"), "{csv}");
    assert!(csv.contains("  omnical reads 1 run:\n    train/00-r0: "), "{csv}");
    std::fs::write(d.join("notes.txt"), "not a recording").unwrap();
    let out = omnical(&["info", "notes.txt"], d);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.starts_with("error: notes.txt: unsupported input (expected .csv (omnical run), .mcap (ROS 2 bag)"),
        "{err}"
    );
}

/// `model`'s matrix with its rotation row scaled by `factor`, as a model file `out` (the TOML's third
/// `matrix` row).
fn with_rotation_row_scaled(dir: &Path, model: &str, factor: f64, out: &str) {
    let text = std::fs::read_to_string(dir.join(model)).unwrap();
    let mut file: toml::Table = text.parse().unwrap();
    let matrix = file["matrix"].as_array_mut().unwrap();
    let row: Vec<toml::Value> =
        matrix[2].as_array().unwrap().iter().map(|v| toml::Value::Float(v.as_float().unwrap() * factor)).collect();
    matrix[2] = toml::Value::Array(row);
    file.remove("fit");
    std::fs::write(dir.join(out), toml::to_string(&file).unwrap()).unwrap();
}

#[test]
fn a_model_of_the_turning_gives_the_gyros_scale_that_the_imu_alone_cannot() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "sim", "100");
    // The true robot's row: the simulated gyro has no scale error (its central differences of the true
    // heading read about 0.1 % high, as the free row does against motion capture), and its bias 0.005 rad/s.
    let doc: Value = json(&["imu", "sim/train", "--model", "sim/truth_model.toml", "--json"], d);
    let a = &doc["against_model"];
    let (scale, se) = (a["gyro_scale"].as_f64().unwrap(), a["gyro_scale_std"].as_f64().unwrap());
    let bias = a["bias_rad_s"].as_f64().unwrap();
    eprintln!("against the truth: scale {scale:.5} ± {se:.5}, bias {bias:.5}, {}", a["difference_sigmas"]);
    assert!((scale - 1.0).abs() < 2e-3 && se < 1e-3, "scale {scale} ± {se}");
    assert!((bias - 0.005).abs() < 3e-4, "bias {bias}");
    assert!(a["difference_sigmas"].as_array().unwrap().iter().all(|s| s.as_f64().unwrap().abs() < 4.0), "{a}");
    // Against a row 2 % low (a model whose turning is off, or a gyro reading 2 % high) the scale is 1/0.98.
    with_rotation_row_scaled(d, "sim/truth_model.toml", 0.98, "low.toml");
    let doc: Value = json(&["imu", "sim/train", "--model", "low.toml", "--json"], d);
    let low = doc["against_model"]["gyro_scale"].as_f64().unwrap();
    assert!((low - scale / 0.98).abs() < 1e-6, "scale {low} against {scale} / 0.98");
    let text = ok(&["imu", "sim/train", "--model", "low.toml"], d);
    assert!(text.contains("against low.toml's rotation row: gyro scale 1.02"), "{text}");
    assert!(text.contains("they disagree beyond the gyro's scale"), "{text}");
    // A model of another robot is refused naming the option.
    let err = refusal(&["imu", "sim/train", "--model", "nowhere.toml"], d);
    assert!(err.starts_with("error: --model"), "{err}");
}

/// `omnical imu` on a differential drive (issue 43: it panicked, exit 101, on every one): the two-wheel
/// rotation row comes back as motion capture fits it, and the model file keeps the design's structural zeros.
#[test]
fn a_differential_drives_rotation_row_comes_back_as_motion_capture_fits_it() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let robot = support::test_data("diff_robot.toml");
    simulate_with(d, "sim", "100", &["--robot", robot.to_str().unwrap(), "--effect", "wheel_radius:a=0.02"]);
    let fit: Value = json(&["train", "sim/train", "--model", "ik", "--json"], d);
    let mocap: Vec<f64> = fit["matrix"][2].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let (row, doc) = imu_row(&["imu", "sim/train", "--out", "imu.toml"], d);
    assert_eq!(doc["wheel_names"], serde_json::json!(["wheel_left_joint", "wheel_right_joint"]));
    for (i, (r, m)) in row.iter().zip(&mocap).enumerate() {
        eprintln!("diff wheel {i}: IMU {r:.6}, motion capture {m:.6} ({:+.3} %)", 100.0 * (r / m - 1.0));
        assert!((r / m - 1.0).abs() < 0.003, "wheel {i}: IMU {r} vs motion capture {m}");
    }
    // The left wheel 2 % large turns the base 2 % more per radian: its entry is 2 % above the design's.
    let design = doc["design_row"][0].as_f64().unwrap();
    assert!((row[0] / design - 1.02).abs() < 0.004, "left {} vs design {design}", row[0]);
    let model: toml::Table = std::fs::read_to_string(d.join("imu.toml")).unwrap().parse().unwrap();
    let matrix = model["matrix"].as_array().unwrap();
    assert_eq!(matrix[1], toml::Value::Array(vec![toml::Value::Float(0.0), toml::Value::Float(0.0)]));
    assert!((matrix[2].as_array().unwrap()[1].as_float().unwrap() - row[1]).abs() < 1e-12);
    // The written model reads back.
    ok(&["eval", "--model", "imu.toml", "sim/validation/00-r0.mcap"], d);
}

/// A gyro that reports deg/s (the same simulated runs, every yaw rate × 180/π) is refused naming the files,
/// the topic, the factor and the fix; nothing is written.
#[test]
fn a_gyro_in_degrees_per_second_is_refused_naming_the_topic_and_the_fix() {
    use omni_cli::api::simulate::{Format, Imu, simulate_split, write_split};
    use omni_kin::simulate::{SimConfig, flower_commands};
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let commands = flower_commands().into_iter().step_by(6).collect();
    let config = SimConfig { commands, runs_per_command: 1, duration_s: 4.0, seed: 5, ..SimConfig::default() };
    let truth = omni_kin::FittedModel::nominal(omni_kin::Model::ik(omni_kin::IkMatrix::paper_calibrated()));
    let (runs, mut sensors) = simulate_split(&config, &truth, "", None, Some(&Imu::default())).unwrap();
    for track in sensors.imu.as_mut().unwrap() {
        track.samples.iter_mut().for_each(|s| s.z_rad_s = s.z_rad_s.to_degrees());
    }
    let names: Vec<String> = ["wheel_a", "wheel_b", "wheel_c"].map(String::from).to_vec();
    write_split(&d.join("deg"), &runs, Format::Mcap, &names, sensors.as_sensors()).unwrap();
    let err = refusal(&["imu", "deg", "--robot", "apr02", "--out", "imu.toml"], d);
    assert!(
        err.starts_with(
            "error: deg/00-r0.mcap, deg/01-r0.mcap, deg/02-r0.mcap, and 3 more recordings: topic \"/imu\": \
                         the rotation row the gyro fits is 5"
        ),
        "{err}"
    );
    assert!(
        err.ends_with(
            "57.296 is the factor when the gyro reports deg/s (sensor_msgs/msg/Imu's angular_velocity is rad/s): \
             convert it in the driver (× π/180)"
        ),
        "{err}"
    );
    assert!(!d.join("imu.toml").exists());
}
