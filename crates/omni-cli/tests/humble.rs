//! Issue 27's acceptance: a Humble differential-drive robot's recordings as its stack writes them
//! (tests/rosbag2/make_humble.py: joint_state_broadcaster with a caster joint, the URDF on
//! /robot_description, /tf_static, diff_drive_controller's /odom, a header-less /cmd_vel, and motion capture
//! stamped by its own clock 0.8 s behind the wheels'), calibrated with the README's recipe for one's own
//! robot (`init`, then `train`): the right wheel's 2 % larger radius within 0.2 %, and the clock offset
//! within 5 ms, with the motion capture in the bag or in TUM files beside it.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use support::{copy_dir, made_by_python, ok_with_stderr, param, refused};

fn recordings() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| made_by_python("rosbag2/make_humble.py", Path::new(env!("CARGO_TARGET_TMPDIR")).join("humble")))
}

/// Runs omnical in `dir`; stdout, stderr, after checking it succeeded.
fn omnical(dir: &Path, args: &[&str]) -> (String, String) {
    ok_with_stderr(args, dir)
}

/// `init` on the first session, then `train` on all three; the fitted radii and the clocks found. Returns
/// train's stderr.
fn recipe(variant: &str, extra: &[&str]) -> String {
    let rec = recordings();
    let expected: Value = serde_json::from_str(&std::fs::read_to_string(rec.join("expected.json")).unwrap()).unwrap();
    let dir = rec.join(variant);
    let _ = std::fs::remove_file(dir.join("robot.toml"));
    omnical(&dir, &["init", "session_01", "--out", "robot.toml"]);
    let robot = std::fs::read_to_string(dir.join("robot.toml")).unwrap();
    assert!(robot.contains("kind = \"diff\"") && robot.contains("left_joint = \"left_wheel_joint\""), "{robot}");
    let mut args = vec!["train", "session_01", "session_02", "session_03", "--out", "mine.toml", "--json"];
    args.extend_from_slice(extra);
    let (out, err) = omnical(&dir, &args);
    let v: Value = serde_json::from_str(&out).unwrap();
    let (r_left, r_right) = (param(&v, "r_left"), param(&v, "r_right"));
    let truth = |k: &str| expected[k].as_f64().unwrap();
    let ratio = r_right / r_left;
    let true_ratio = truth("r_right_m") / truth("r_left_m");
    assert!((ratio / true_ratio - 1.0).abs() < 0.002, "{variant}: r_right / r_left {ratio} against {true_ratio}");
    for (got, want) in
        [(r_left, truth("r_left_m")), (r_right, truth("r_right_m")), (param(&v, "b"), truth("separation_m"))]
    {
        assert!((got / want - 1.0).abs() < 0.002, "{variant}: {got} against {want}");
    }
    let clocks = v["ground_truth_clock"].as_array().unwrap();
    assert_eq!(clocks.len(), 3, "{variant}: {err}");
    for c in clocks {
        let offset = c["offset_s"].as_f64().unwrap();
        assert!((offset - truth("mocap_offset_s")).abs() < 0.005, "{variant}: {c}");
    }
    // The joint state broadcaster's caster joint and the controller's /odom are not wheels or truth.
    assert!(!err.contains("caster"), "{err}");
    err
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn readme_recipe_on_humble_recordings_with_mocap_in_the_bag() {
    recipe("bag", &[]);
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn readme_recipe_on_humble_recordings_with_mocap_in_files() {
    recipe("file", &["--gt", "mocap"]);
}

/// Runs omnical in `dir` expecting it to succeed, and parses its JSON.
fn omnical_json(dir: &Path, args: &[&str]) -> Value {
    serde_json::from_str(&omnical(dir, args).0).unwrap()
}

/// The role `info --json` gives `topic`, and why.
fn role<'a>(v: &'a Value, topic: &str) -> (&'a str, &'a str) {
    let t = v["recordings"][0]["topics"].as_array().unwrap().iter().find(|t| t["topic"] == topic).unwrap();
    (t["role"].as_str().unwrap(), t["why"].as_str().unwrap())
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn info_names_each_topics_role_the_runs_and_the_mocap_clock() {
    let dir = recordings().join("bag");
    let robot = dir.join("info-robot.toml");
    omnical(&dir, &["init", "session_01", "--out", "info-robot.toml", "--force"]);
    let robot = robot.to_str().unwrap();
    let v = omnical_json(&dir, &["info", "session_01", "--robot", robot, "--json"]);
    let rec = &v["recordings"][0];
    assert_eq!(rec["topics"].as_array().unwrap().len(), 6, "{rec}");
    for (topic, want) in [
        ("/joint_states", "wheels"),
        ("/mocap/pose", "ground_truth"),
        ("/odom", "recorded_odometry"),
        ("/cmd_vel", "command"),
        ("/tf_static", "static_transforms"),
        ("/robot_description", "urdf"),
    ] {
        assert_eq!(role(&v, topic).0, want, "{topic}: {v}");
    }
    assert!(role(&v, "/joint_states").1.contains("left_wheel_joint, right_wheel_joint in wheel order"), "{v}");
    let joints = &rec["topics"].as_array().unwrap().iter().find(|t| t["topic"] == "/joint_states").unwrap();
    assert_eq!(joints["joint_names"][0], "caster_swivel_joint");
    assert_eq!(joints["messages"], 1251);
    let read = &rec["read"];
    assert_eq!(read["ok"], true, "{read}");
    let run = &read["runs"][0];
    assert_eq!(run["wheel_samples"], 1251);
    assert!((run["wheel_rate_hz"].as_f64().unwrap() - 50.0).abs() < 1e-6, "{run}");
    assert!((run["truth_rate_hz"].as_f64().unwrap() - 120.0).abs() < 0.5, "{run}");
    let offset = read["clocks"][0]["offset_s"].as_f64().unwrap();
    assert!((offset - 0.8).abs() < 0.005, "mocap clock {offset}");

    // Naming the robot's own odometry as the ground truth: the topic says why it is refused, and the read
    // fails with the loader's own message (info itself succeeds: it reports).
    let v = omnical_json(&dir, &["info", "session_01", "--robot", robot, "--gt-topic", "/odom", "--json"]);
    let (r, why) = role(&v, "/odom");
    assert_eq!(r, "unused");
    assert!(why.starts_with("named as the ground truth (--gt-topic), refused:") && why.contains("REP-105"), "{why}");
    assert_eq!(v["recordings"][0]["read"]["ok"], false);
    assert!(v["recordings"][0]["read"]["error"].as_str().unwrap().contains("the model under test, never ground truth"));
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn one_mocap_take_with_gaps_serves_every_recording_it_covers() {
    // One motion-capture take across the three sessions (on the mocap PC's clock, 0.8 s behind), the
    // marker lost for 1.5 s of every 5 s: each recording finds its stretch of the take, on one clock.
    let rec = recordings();
    let dir = rec.join("take");
    let _ = std::fs::remove_dir_all(&dir);
    for s in ["session_01", "session_02", "session_03"] {
        copy_dir(&rec.join("file").join(s), &dir.join(s));
    }
    let mut take = String::new();
    for s in ["session_01", "session_02", "session_03"] {
        let text = std::fs::read_to_string(rec.join("file/mocap").join(format!("{s}.tum"))).unwrap();
        for line in text.lines().enumerate().filter(|(i, _)| i % 600 < 420).map(|(_, l)| l) {
            take.push_str(line);
            take.push('\n');
        }
    }
    std::fs::write(dir.join("take.tum"), take).unwrap();
    recipe("take", &["--gt", "take.tum"]);
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn odometry_only_recordings_calibrate_the_controllers_parameters() {
    // The same sessions without /joint_states: diff_drive_controller's /odom (25 Hz, integrated through the
    // design radii) is the only wheel record. The wheel speeds recovered through the design give the true
    // radii and separation within 0.2 % (the recipe's assertions), with a note that says where they came from.
    let err = recipe("odom", &[]);
    assert!(
        err.contains(
            "session_01: no sensor_msgs/msg/JointState topic: the wheel speeds are recovered from topic \"/odom\" \
             (the robot's own odometry, 626 poses) through the design"
        ) && err.contains("every parameter of the model is within a fit's reach"),
        "{err}"
    );
    let v = omnical_json(&recordings().join("odom"), &["info", "session_01", "--json"]);
    let (r, why) = role(&v, "/odom");
    assert_eq!(r, "wheels", "{v}");
    assert!(why.starts_with("the robot's own odometry stands in for the missing JointState"), "{why}");

    // Without the robot's design there is no way from the odometry to the wheels: refused, with the way on.
    let bare = recordings().join("odom-bare");
    let _ = std::fs::remove_dir_all(&bare);
    copy_dir(&recordings().join("odom/session_01"), &bare.join("session_01"));
    let err = refused(&["train", "session_01"], &bare);
    assert!(
        err.contains(
            "session_01: no sensor_msgs/msg/JointState topic for the wheel speeds; /odom is the robot's own odometry: \
             wheel speeds can come from it only through the robot's design; describe the robot (omnical init \
             RECORDING writes robot.toml from its URDF, or --robot FILE)"
        ),
        "{err}"
    );

    // With the JointState there, the odometry is taken when named: the same radii within 0.2 %.
    let named = recordings().join("bag-odom");
    let _ = std::fs::remove_dir_all(&named);
    for s in ["session_01", "session_02", "session_03"] {
        copy_dir(&recordings().join("bag").join(s), &named.join(s));
    }
    let err = recipe("bag-odom", &["--joints-topic", "/odom"]);
    assert!(err.contains("the wheel speeds are recovered from topic \"/odom\""), "{err}");
    // A JointState topic without the described wheels points at the odometry.
    let robot = std::fs::read_to_string(named.join("robot.toml")).unwrap().replace("left_wheel_joint", "lw");
    std::fs::write(named.join("renamed.toml"), robot).unwrap();
    let err = refused(&["train", "session_01", "--robot", "renamed.toml"], &named);
    assert!(
        err.contains(
            "wheel joint \"lw\" is missing (names: caster_swivel_joint, left_wheel_joint, right_wheel_joint); if no \
             JointState topic carries the wheels, the robot's own odometry /odom can stand in through the robot's \
             design: --joints-topic /odom ([topics] joint_states in robot.toml)"
        ),
        "{err}"
    );
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn exported_bags_carry_the_recordings_transforms_urdf_and_commands() {
    // `export --mcap` of a Humble session: the recording's /tf_static, /robot_description and /cmd_vel come
    // along as recorded (the command as its Twist, replacing the written one), stamped in the recording's
    // Unix time, and the bag reads back with its ground truth named.
    let dir = recordings().join("bag");
    omnical(&dir, &["init", "session_01", "--out", "export-robot.toml", "--force"]);
    let out = dir.join("exported");
    let _ = std::fs::remove_dir_all(&out);
    let out_s = out.to_str().unwrap();
    omnical(&dir, &["export", "session_01", "--robot", "export-robot.toml", "--model", "design", "--mcap", out_s]);
    let bag = out.join("session_01.mcap");
    let args = ["info", bag.to_str().unwrap(), "--robot", "export-robot.toml", "--gt-topic", "/ground_truth/pose"];
    let v = omnical_json(&dir, &[&args[..], &["--json"]].concat());
    let rec = &v["recordings"][0];
    assert_eq!(rec["start_unix_s"].as_f64().unwrap(), 1_717_000_100.0, "{rec}");
    let topic = |name: &str| rec["topics"].as_array().unwrap().iter().find(|t| t["topic"] == name).unwrap().clone();
    for (name, role, kind) in [
        ("/tf_static", "static_transforms", "tf2_msgs/msg/TFMessage"),
        ("/robot_description", "urdf", "std_msgs/msg/String"),
        ("/cmd_vel", "command", "geometry_msgs/msg/Twist"),
    ] {
        let t = topic(name);
        assert_eq!((t["role"].as_str(), t["type"].as_str(), t["messages"].as_u64()), (Some(role), Some(kind), Some(1)));
    }
    assert!(role(&v, "/tf_static").1.contains("base_footprint → base_link, base_link → laser"), "{v}");
    assert_eq!(rec["read"]["ok"], true, "{rec}");
}
