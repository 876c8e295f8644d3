//! A skid-steer base (issue 47 item 5): `kind = "skid"` in robot.toml, the ICR-based extended differential
//! drive as its default model, `simulate --effect icr_shift=…` for a hidden shift of its centres of
//! rotation, and `diff_drive_controller` with both wheels of each side as its export.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use serde_json::Value;
use support::{json, param_se, refused, succeeded, test_data};
use yaml_rust2::{Yaml, YamlLoader};

/// The hidden truth: each tread's centre of rotation 0.2 m further out (effective track 0.955 m against
/// the wheels' 0.555 m), the robot's 0.05 m ahead of the origin.
const TRUE_ICR: [(&str, f64); 3] = [("y_icr_left", 0.4775), ("y_icr_right", -0.4775), ("x_icr", 0.05)];

fn path_cost(model: &str, data: &str, dir: &std::path::Path) -> f64 {
    json(&["eval", "--model", model, data, "--json"], dir)["path_cost"].as_f64().unwrap()
}

#[test]
fn a_hidden_icr_shift_is_calibrated_diagnosed_and_exported() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let robot = test_data("skid_robot.toml");
    succeeded(
        &["simulate", "--robot", robot.to_str().unwrap(), "--effect", "icr_shift=0.2,-0.2,0.05", "--out", "sim", "-q"],
        d,
    );
    let truth = std::fs::read_to_string(d.join("sim/truth_model.toml")).unwrap();
    assert!(truth.contains("kinematics = \"skid\"") && truth.contains("x_icr_m = 0.05"), "{truth}");

    // train picks the skid model from robot.toml and finds the hidden ICRs within 2 mm (3 standard
    // errors), the radii within 0.1 %.
    let fit: Value = json(&["train", "sim/train", "--out", "m.toml", "--json"], d);
    assert_eq!(fit["params"].as_array().unwrap().len(), 5, "the skid model's five parameters: {fit}");
    for (name, truth) in TRUE_ICR {
        let (v, se) = param_se(&fit, name);
        eprintln!("{name}: {v:.5} ± {se:.1e} (true {truth})");
        assert!((v - truth).abs() < 2e-3 && (v - truth).abs() < 3.0 * se.max(3e-4), "{name}: {v} ± {se} vs {truth}");
    }
    for name in ["r_left", "r_right"] {
        let (v, _) = param_se(&fit, name);
        assert!((v - 0.165).abs() < 1.65e-4, "{name}: {v}");
    }

    // Held out: within 1.2 times the true model's path error, where the design is 200 times off.
    let fitted = path_cost("m.toml", "sim/validation", d);
    let oracle = path_cost("sim/truth_model.toml", "sim/validation", d);
    let design = path_cost("design", "sim/validation", d);
    eprintln!("held-out path RMS: fitted {fitted:.5} m, true model {oracle:.5} m, design {design:.4} m");
    assert!(fitted <= 1.2 * oracle, "fitted {fitted} vs true {oracle}");
    assert!(design > 100.0 * oracle, "design {design} vs true {oracle}");

    // diagnose: nothing is left to name (the model holds the truth).
    let diag = json(&["diagnose", "--model", "m.toml", "sim/train", "--validate", "sim/validation", "--json"], d);
    let verdict = diag["verdict_text"].as_str().unwrap();
    assert!(verdict.contains("no systematic error remains"), "{verdict}");

    // export: diff_drive_controller with both wheels of each side and the effective track; AMCL's
    // differential motion model; the ICR the controller cannot express is said.
    let out = succeeded(&["export", "--model", "m.toml", "--robot-config", "rc", "sim/validation"], d);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(text.contains("diff_drive_controller: separation 0.95"), "{text}");
    assert!(text.contains("effective track is y_icr_left − y_icr_right = 0.95"), "{text}");
    assert!(text.contains("cannot express the robot's centre of rotation at x = 0.04"), "{text}");
    let text = std::fs::read_to_string(d.join("rc/ros2_controllers.yaml")).unwrap();
    let y: Yaml = YamlLoader::load_from_str(&text).unwrap().remove(0);
    let p = &y["diff_drive_controller"]["ros__parameters"];
    let names = |k: &str| p[k].as_vec().unwrap().iter().map(|v| v.as_str().unwrap().to_string()).collect::<Vec<_>>();
    assert_eq!(names("left_wheel_names"), ["front_left_wheel", "rear_left_wheel"]);
    assert_eq!(names("right_wheel_names"), ["front_right_wheel", "rear_right_wheel"]);
    let separation = p["wheel_separation"].as_f64().unwrap() * p["wheel_separation_multiplier"].as_f64().unwrap();
    assert!((separation - 0.955).abs() < 0.005, "separation {separation}");
    let amcl = std::fs::read_to_string(d.join("rc/nav2_amcl.yaml")).unwrap();
    assert!(amcl.contains("nav2_amcl::DifferentialMotionModel"), "{amcl}");

    // The report draws how far to trust the odometry (issue 46): the noise model `train` fitted covers
    // 90-98 % of the held-out poses with its 95 % ellipses (the simulator's wheel and ground-truth noise).
    // Measured 94.8 % before the per-run biases and the wandering heading, 97.7 % with them: on runs
    // without such errors their variances, held non-negative, come out a little above zero.
    let args = ["report", "--model", "m.toml", "sim/train", "--validate", "sim/validation", "--no-diagnose"];
    succeeded(&[&args[..], &["--out", "r.html", "-q"]].concat(), d);
    let html = std::fs::read_to_string(d.join("r.html")).unwrap();
    assert!(html.contains("data-figure=\"trust-ellipses\"") && html.contains("data-figure=\"trust-growth\""));
    let inside: f64 = html
        .split(" % of the poses lie inside their ellipse")
        .next()
        .and_then(|head| head.rsplit(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no coverage in the report"));
    eprintln!("held-out poses inside their 95 % ellipse: {inside} %");
    assert!((90.0..=98.0).contains(&inside), "{inside} %");
}

#[test]
fn a_skid_steer_description_is_checked() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let text = std::fs::read_to_string(test_data("skid_robot.toml")).unwrap();
    let wheels: Vec<&str> = text.split("[[wheels]]").collect();
    // Three wheels: an even number is needed.
    std::fs::write(d.join("odd.toml"), wheels[..4].join("[[wheels]]")).unwrap();
    let err = refused(&["simulate", "--robot", "odd.toml", "--out", "o"], d);
    assert!(err.contains("an even number, at least 4"), "{err}");
    // Every wheel on the left.
    std::fs::write(d.join("left.toml"), text.replace("y_m = -0.2775", "y_m = 0.2775")).unwrap();
    let err = refused(&["simulate", "--robot", "left.toml", "--out", "o"], d);
    assert!(err.contains("as many wheels left (y_m > 0) as right (y_m < 0)"), "{err}");
    // Rollers.
    let rollers = text.replacen("radius_m = 0.165", "radius_m = 0.165\nroller_angle_deg = 45.0", 1);
    std::fs::write(d.join("rollers.toml"), rollers).unwrap();
    let err = refused(&["simulate", "--robot", "rollers.toml", "--out", "o"], d);
    assert!(err.contains("wheels[0].roller_angle_deg") && err.contains("no rollers"), "{err}");
    // icr_shift on a base that is not skid-steer (the paper's omni robot).
    let err = refused(&["simulate", "--effect", "icr_shift=0.1,-0.1,0", "--out", "o"], d);
    assert!(
        err.contains("icr_shift is a skid-steer base's") && err.contains("every wheel must drive along x"),
        "{err}"
    );
}
