//! The robot description through the real binary: `--robot FILE|apr02`, a `robot.toml` found beside the
//! data or in the working directory (and said so on stderr), joint names and topics from it, refusals
//! without one, and bad files (exit 2, naming the file, line and field).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::Path;
use support::{omnical, stderr, succeeded};

fn simulate(dir: &Path, out: &str, extra: &[&str]) {
    let base = ["simulate", "--out", out, "--runs-per-command", "1", "--duration", "2", "--seed", "4", "-q"];
    succeeded(&[&base[..], extra].concat(), dir);
}

const OMNI4: &str = r#"kind = "omni"
[[wheels]]
joint = "fl"
distance_m = 0.21
angle_deg = 45.0
radius_m = 0.05
[[wheels]]
joint = "rl"
distance_m = 0.21
angle_deg = 135.0
radius_m = 0.05
[[wheels]]
joint = "rr"
distance_m = 0.21
angle_deg = 225.0
radius_m = 0.05
[[wheels]]
joint = "fr"
distance_m = 0.21
angle_deg = 315.0
radius_m = 0.05
"#;

#[test]
fn simulated_runs_carry_their_robot_and_it_is_announced() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "sim", &[]);
    let text = std::fs::read_to_string(d.join("sim/validation/robot.toml")).unwrap();
    assert!(text.starts_with("# The robot these simulated runs were made with"), "{text}");
    assert!(text.contains("angle_deg = 300.0"), "{text}");
    let found = succeeded(&["eval", "sim/validation", "--json"], d);
    assert!(stderr(&found).contains("robot: sim/validation/robot.toml (found beside the data)"), "{}", stderr(&found));
    // The same numbers as naming the paper's robot.
    let named = succeeded(&["eval", "sim/validation", "--json", "--robot", "apr02"], d);
    assert_eq!(found.stdout, named.stdout);
    assert!(!stderr(&named).contains("robot: "), "a named robot is not announced: {}", stderr(&named));
    // A file given by path.
    let given = succeeded(&["eval", "sim/validation", "--json", "--robot", "sim/train/robot.toml"], d);
    assert_eq!(found.stdout, given.stdout);
}

#[test]
fn no_robot_no_design() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "sim", &["--format", "csv"]);
    std::fs::remove_file(d.join("sim/train/robot.toml")).unwrap();
    for cmd in [
        &["eval", "sim/train"][..],
        &["train", "sim/train", "-q"],
        &["plan"],
        &["diagnose", "--model", "design", "sim/train"],
    ] {
        let out = omnical(cmd, d);
        let e = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{cmd:?}: {e}");
        assert!(e.starts_with("error: "), "{e}");
        assert!(e.contains("needs the robot's design") && e.contains("--robot apr02"), "{cmd:?}: {e}");
        assert!(e.contains("robot.toml") && e.contains("omnical init"), "{e}");
    }
    // A model file carries its design: no robot needed.
    succeeded(&["train", "sim/train", "-q", "--robot", "apr02", "--out", "fit.toml"], d);
    succeeded(&["eval", "--model", "fit.toml", "sim/train"], d);
    // A robot.toml in the working directory is found.
    std::fs::copy(d.join("sim/validation/robot.toml"), d.join("robot.toml")).unwrap();
    let out = succeeded(&["eval", "sim/train"], d);
    assert!(stderr(&out).contains("robot: robot.toml (found beside the data)"), "{}", stderr(&out));
}

#[test]
fn joint_names_and_a_four_wheel_design_come_from_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("omni4.toml"), OMNI4).unwrap();
    simulate(d, "sim4", &["--robot", "omni4.toml", "--truth", "design", "--noise-free"]);
    // The runs were written with the file's joints; eval reads them through the robot.toml beside them and
    // the design (a 3 × 4 matrix from the file) reproduces the noise-free motion.
    let out = succeeded(&["eval", "sim4/validation", "--json"], d);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let cost = v["cost"].as_f64().unwrap();
    assert!(cost < 2e-3, "Eq. 6 of the design on its own noise-free runs: {cost}");
    assert_eq!(v["runs"].as_array().unwrap().len(), 36);
    // --joints still wins: the bag's names are listed.
    let out = omnical(&["eval", "sim4/validation/00-r0.mcap", "--joints", "wheel_a,wheel_b,wheel_c,wheel_d"], d);
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(e.contains("wheel_a") && e.contains("fl"), "{e}");
    // The paper's Eq. 9 is not this robot.
    let out = omnical(&["simulate", "--out", "x", "--robot", "omni4.toml", "--truth", "paper"], d);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--truth paper is the paper's Eq. 9"), "{}", stderr(&out));
}

#[test]
fn joint_names_go_into_the_model_file_and_the_exported_config() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("omni4.toml"), OMNI4).unwrap();
    simulate(d, "sim4", &["--robot", "omni4.toml", "--truth", "design", "--format", "csv"]);
    let names = r#"wheel_names = ["fl", "rl", "rr", "fr"]"#;
    // Trained around the robot found beside the runs: the matrix model and the geometry model both name
    // their columns after the robot's joints.
    for (kind, file) in [("ik", "fit.toml"), ("geometry", "geo.toml")] {
        succeeded(&["train", "sim4/train", "-q", "--model", kind, "--out", file], d);
        let text = std::fs::read_to_string(d.join(file)).unwrap();
        assert!(text.contains(names), "{kind}: {text}");
    }
    // Exported without the robot description (CSV runs, no robot.toml): the wheel order is the model's.
    std::fs::remove_file(d.join("sim4/validation/robot.toml")).unwrap();
    succeeded(&["export", "--model", "fit.toml", "--robot-config", "rc", "sim4/validation", "-q"], d);
    let yaml = std::fs::read_to_string(d.join("rc/omnical_odometry.yaml")).unwrap();
    assert!(yaml.contains(r#"wheel_names: ["fl", "rl", "rr", "fr"]"#), "{yaml}");
    let header = std::fs::read_to_string(d.join("rc/omnical_odometry.h")).unwrap();
    assert!(header.contains(r#"OMNICAL_WHEEL_NAMES[OMNICAL_N_WHEELS] = {"fl", "rl", "rr", "fr"};"#), "{header}");
}

#[test]
fn csv_wheel_columns_follow_the_robots_joints() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("omni4.toml"), OMNI4).unwrap();
    simulate(d, "sim4", &["--robot", "omni4.toml", "--truth", "design", "--format", "csv"]);
    let cost = |robot: &str| {
        let out = succeeded(&["eval", "sim4/validation", "--json", "--robot", robot], d);
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()["path_cost"].as_f64().unwrap()
    };
    let as_written = cost("omni4.toml");
    // The same robot with its wheels listed in another order: the CSV columns are read in that order too,
    // so the design's columns still meet their wheels' data.
    let blocks: Vec<&str> = OMNI4.split("[[wheels]]\n").collect();
    let reordered = [blocks[0], blocks[4], blocks[1], blocks[2], blocks[3]].join("[[wheels]]\n");
    std::fs::write(d.join("reordered.toml"), &reordered).unwrap();
    let again = cost("reordered.toml");
    assert!((again - as_written).abs() <= 1e-12 * as_written, "{again} vs {as_written}");
    // A joint the files do not have: exit 2, naming the file, the missing column and both lists.
    std::fs::write(d.join("renamed.toml"), OMNI4.replace(r#""fl""#, r#""front_left""#)).unwrap();
    let out = omnical(&["eval", "sim4/validation", "--robot", "renamed.toml"], d);
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(e.contains("00-r0.csv: line "), "{e}");
    assert!(
        e.contains(
            ": no column front_left_rad_s (the robot's joints: front_left, rl, rr, fr; the file's wheel columns: \
             fl, rl, rr, fr)"
        ),
        "{e}"
    );
}

/// A differential drive (r 33 mm, axle 0.287 m), one file for robot.rs and robot_types.rs.
const DIFF: &str = include_str!("data/diff_robot.toml");

#[test]
fn priors_bound_the_parametric_search_and_are_reported() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // The true robot's left wheel is 1 mm (3 %) larger than its description says.
    std::fs::write(d.join("true.toml"), DIFF.replace("left_radius_m = 0.033", "left_radius_m = 0.034")).unwrap();
    simulate(d, "sim", &["--robot", "true.toml", "--truth", "design", "--noise-free", "--format", "csv"]);
    let priors = "[priors]\nradius_std_m = 0.0001\nseparation_std_m = 0.003\n";
    std::fs::write(d.join("sim/train/robot.toml"), format!("{DIFF}{priors}")).unwrap();
    let fit = |extra: &[&str]| {
        let out = succeeded(&[&["train", "sim/train", "-q", "--json"][..], extra].concat(), d);
        (serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap(), stderr(&out))
    };
    let (v, _) = fit(&["--model", "diff"]);
    let p = v["priors"].as_array().unwrap();
    let names: Vec<&str> = p.iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["r_right", "r_left", "b"]);
    let left = &p[1];
    assert_eq!((left["design"].as_f64(), left["std"].as_f64()), (Some(0.033), Some(0.0001)));
    // The GA stays within design ± 3 σ (0.3 mm); the polish finds the true radius beyond it, 10 σ from the
    // design, and says it left the box.
    let fitted = left["fitted"].as_f64().unwrap();
    assert!((fitted - 0.034).abs() < 2e-5, "fitted r_left {fitted}");
    assert!((left["sigmas"].as_f64().unwrap() - 10.0).abs() < 0.2, "{left}");
    assert_eq!(v["outside_box"], serde_json::json!(["r_left"]));
    let text = succeeded(&["train", "sim/train", "-q", "--model", "diff"], d);
    let line =
        String::from_utf8_lossy(&text.stdout).lines().find(|l| l.starts_with("prior r_left")).unwrap().to_string();
    assert!(line.starts_with("prior r_left: design 0.033 ± 0.0001 m (GA box ±3 σ), fitted 0.0340"), "{line}");
    assert!(line.ends_with(" σ)") && line.contains("(+"), "{line}");
    // Without priors: the ±10 % box holds the true radius, nothing is reported.
    std::fs::write(d.join("sim/train/robot.toml"), DIFF).unwrap();
    let (v, _) = fit(&["--model", "diff"]);
    assert!(v.get("priors").is_none() && v["outside_box"] == serde_json::json!([]), "{v}");
    // The ik matrix's entries are not geometry: the priors are unused, and that is said (a warning: shown
    // with -q).
    std::fs::write(d.join("sim/train/robot.toml"), format!("{DIFF}{priors}")).unwrap();
    // train's default on a differential drive is its diff model, which the priors bound.
    let (v, _) = fit(&[]);
    assert_eq!(v["priors"].as_array().map(Vec::len), Some(3), "{v}");
    let (v, e) = fit(&["--model", "ik"]);
    assert!(v.get("priors").is_none(), "{v}");
    assert!(
        e.contains(
            "warning: the [priors] of sim/train/robot.toml (found beside the data) bound the parametric models' search"
        ),
        "{e}"
    );
}

#[test]
fn bad_robot_files_name_the_file_line_and_field() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "sim", &["--format", "csv"]);
    let good = std::fs::read_to_string(d.join("sim/train/robot.toml")).unwrap();
    let cut_last_wheel = good.rsplit_once("\n[[wheels]]").unwrap().0.to_string() + "\n";
    let cases: [(&str, String, &str); 8] = [
        (
            "mm.toml",
            good.replacen("radius_m = 0.148", "radius_m = 148.0", 1),
            "wheels[0].radius_m: 148 m is not a plausible wheel radius (at most 2 m): is it in millimetres?",
        ),
        (
            "radians.toml",
            good.replace("angle_deg = 60.0", "angle_deg = 1.0471975511965976")
                .replace("angle_deg = 180.0", "angle_deg = 3.141592653589793")
                .replace("angle_deg = 300.0", "angle_deg = 5.235987755982989"),
            "wheels: the wheel angles (1.0471975511965976, 3.141592653589793, 5.235987755982989) all lie within ±2π",
        ),
        ("joints.toml", cut_last_wheel, "wheels: a omni base needs at least 3"),
        (
            "dup.toml",
            good.replace("joint = \"wheel_c\"", "joint = \"wheel_b\""),
            "wheels[2].joint: joint \"wheel_b\" is also",
        ),
        ("radius.toml", good.replacen("radius_m = 0.148", "radius_m = 0.0", 1), "wheels[0].radius_m: 0 must be > 0"),
        (
            "collinear.toml",
            good.replace("angle_deg = 180.0", "angle_deg = 60.0").replace("angle_deg = 300.0", "angle_deg = 60.0"),
            "wheels: the wheels can produce only 1 of the 3",
        ),
        ("kind.toml", good.replace("kind = \"omni\"", "kind = \"hexapod\""), "kind: unknown variant `hexapod`"),
        (
            "key.toml",
            good.replace("radius_m = 0.148", "radius_m = 0.148\ntyre = \"soft\""),
            "wheels[0].tyre: unknown field",
        ),
    ];
    for (name, text, want) in cases {
        std::fs::write(d.join(name), text).unwrap();
        let out = omnical(&["eval", "sim/train", "--robot", name], d);
        let e = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{name}: {e}");
        assert!(
            e.starts_with(&format!("error: --robot: {name}: line ")) || e.starts_with(&format!("error: {name}: line ")),
            "{name}: {e}"
        );
        assert!(e.contains(want), "{name}: {e}");
        assert!(!e.contains("panicked"), "{e}");
    }
    // A bad robot.toml found beside the data is refused the same way.
    std::fs::write(d.join("sim/train/robot.toml"), good.replace("kind = \"omni\"", "kind = \"tank\"")).unwrap();
    let out = omnical(&["eval", "sim/train"], d);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).starts_with("error: sim/train/robot.toml: line 3: kind: unknown variant `tank`"),
        "{}",
        stderr(&out)
    );
    // A syntax error outside any field, in a robot file and in a model file: line and column.
    let syntax = good.replacen("[[wheels]]", "[[wheels]\n", 1);
    let line = good.lines().position(|l| l == "[[wheels]]").unwrap() + 1;
    std::fs::write(d.join("sim/train/robot.toml"), syntax).unwrap();
    let out = omnical(&["eval", "sim/train"], d);
    let want =
        format!("error: sim/train/robot.toml: not TOML: line {line}, column 10: unclosed array table, expected `]`");
    assert!(stderr(&out).starts_with(&want), "{}", stderr(&out));
    std::fs::write(d.join("sim/train/robot.toml"), &good).unwrap();
    std::fs::write(d.join("model.toml"), "schema = 1\nparams = [1.0,\n").unwrap();
    let out = omnical(&["eval", "sim/train", "--model", "model.toml"], d);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("model.toml: line 2, column 15: unclosed array"), "{}", stderr(&out));
}
