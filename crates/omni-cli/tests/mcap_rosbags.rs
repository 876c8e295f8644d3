//! The MCAP reader and writer against a real ROS 2 bag client: Python `rosbags` writes the fixture bags
//! (`tests/mcap/make_bags.py`, with the values it wrote in `expected.json`), and reads back what we write.
//!
//! The interpreter is `$OMNICAL_PYTHON` (default `python3`). Without `rosbags`, `mcap`, `mcap-ros2-support`
//! and `numpy` there, these tests are reported as ignored with the reason (build.rs); `bash scripts/test.sh`
//! installs them from requirements-dev.txt.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a failed unwrap is a failed test

#[macro_use]
#[path = "mcap/fixtures.rs"]
mod fixtures;
#[path = "mcap/helpers.rs"]
mod helpers;
mod support;

use fixtures::{error, fixtures, read, read_ok};
use helpers::{check_run, close, design_odometry, floats, simulated_run};
use omni_cli::dataset::mcap::{McapOptions, WriteOptions, write_run};
use omni_kin::Command as RunCommand;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use support::python;

/// The script that writes the fixture bags and checks ours.
fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mcap/make_bags.py")
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn normal_and_zstd_bags_give_the_values_written() {
    let (dir, expected) = fixtures_or_skip!();
    for name in ["normal", "zstd"] {
        let r = read_ok(dir, name);
        assert_eq!(r.origin_s, 1_700_000_000);
        assert_eq!(r.runs.len(), 1);
        assert_eq!(r.runs[0].name(), name);
        check_run(&r.runs[0], &expected[name]);
        // The heading crosses ±π and is unwrapped: it ends near -2.5 + 2 * 3 = 3.5 rad.
        assert!((r.runs[0].end().pose.theta_rad - 3.5).abs() < 1e-9);
        let path = dir.join(format!("{name}.mcap"));
        assert_eq!(
            r.notes.iter().map(ToString::to_string).collect::<Vec<_>>(),
            [
                format!(
                    "{}: topic \"/cmd_vel\" (geometry_msgs/msg/Twist) has no header: command times are log times",
                    path.display()
                ),
                format!(
                    "{}: topic \"/mocap/pose\": dropped 4 ground-truth poses outside the wheel data's time span \
                     (0.25..3.25 s)",
                    path.display()
                ),
            ]
        );
        assert_eq!(expected[name]["truth_dropped"], 4);
    }
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn split_cuts_at_the_standstill() {
    let (dir, expected) = fixtures_or_skip!();
    let want = &expected["split"];
    let r = read(dir, "split", &McapOptions { split: Some(1.0), ..Default::default() }).unwrap();
    let names: Vec<&str> = r.runs.iter().map(|r| r.name()).collect();
    assert_eq!(names, ["split#1", "split#2"]);
    for (run, w) in r.runs.iter().zip(want["runs"].as_array().unwrap()) {
        check_run(run, w);
    }
    let still = floats(&want["standstill_s"]);
    let cut = r.runs[0].wheel_t_s().last().unwrap();
    assert!(still[0] < *cut && *cut < still[1]);
    assert_eq!(r.runs[1].wheel_t_s()[0], *cut);
    // A standstill shorter than asked for is no cut; without `split` the file is one run.
    let r = read(dir, "split", &McapOptions { split: Some(2.5), ..Default::default() }).unwrap();
    assert_eq!(r.runs.iter().map(|r| r.name()).collect::<Vec<_>>(), ["split#1"]);
    let r = read_ok(dir, "split");
    assert_eq!(r.runs.iter().map(|r| r.name()).collect::<Vec<_>>(), ["split"]);
    assert_eq!(r.runs[0].command(), Some(RunCommand { v_m_s: 0.2, alpha_rad: 0.0, omega_rad_s: 0.5 }));
    assert!(r.notes.is_empty(), "{:?}", r.notes);
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn position_only_joint_states_are_differentiated() {
    let (dir, expected) = fixtures_or_skip!();
    let want = &expected["position_only"];
    let r = read_ok(dir, "position_only");
    let run = &r.runs[0];
    close(run.wheel_rad_s(), &floats(&want["wheel_rad_s"]), 1e-12, "wheel_rad_s");
    // And they are the speeds the positions were integrated from (after the first sample).
    close(&run.wheel_rad_s()[3..], &floats(&want["wheel_rad_s_true"])[3..], 1e-9, "true speeds");
    close(run.wheel_start_rad(), &floats(&want["wheel_start_rad"]), 0.0, "wheel_start_rad");
    assert_eq!(
        r.notes.iter().map(ToString::to_string).collect::<Vec<_>>(),
        [format!(
            "{}: topic \"/joint_states\": 201 of 201 messages have no velocity: wheel speeds are differences of \
             position over header.stamp",
            dir.join("position_only.mcap").display()
        )]
    );
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn joint_states_as_real_systems_publish_them_are_read_with_notes() {
    let (dir, expected) = fixtures_or_skip!();
    for name in ["ros2_control", "unstamped"] {
        let want = &expected[name];
        let r = read_ok(dir, name);
        let run = &r.runs[0];
        close(run.wheel_t_s(), &floats(&want["wheel_t_s"]), 1e-9, "wheel_t_s");
        // The speeds the positions were integrated from (after the first sample, which takes the second's).
        close(&run.wheel_rad_s()[3..], &floats(&want["wheel_rad_s_true"])[3..], 1e-9, name);
        let path = dir.join(format!("{name}.mcap")).display().to_string();
        let notes: Vec<String> = r.notes.iter().map(|n| n.to_string().replace(&path, "BAG")).collect();
        let expected_notes: &[&str] = if name == "ros2_control" {
            &[
                "BAG: topic \"/joint_states\": 51 messages name none of the wheel joints (another publisher on the \
                 topic): passed over",
                "BAG: topic \"/joint_states\": 20 messages repeat the one before exactly (stamp and values): dropped",
                "BAG: topic \"/joint_states\": 201 messages have a NaN wheel velocity beside finite positions: their \
                 speeds come from the positions",
                "BAG: topic \"/joint_states\": the position of joint \"wheel_a\" wraps around (an angle modulo 2π): \
                 unwrapped at 3 jumps before it is differentiated",
                "BAG: topic \"/joint_states\": the position of joint \"wheel_b\" wraps around (an angle modulo 2π): \
                 unwrapped at 1 jumps before it is differentiated",
                "BAG: topic \"/joint_states\": the position of joint \"wheel_c\" wraps around (an angle modulo 2π): \
                 unwrapped at 1 jumps before it is differentiated",
                "BAG: topic \"/joint_states\": 201 of 201 messages have no velocity: wheel speeds are differences of \
                 position over header.stamp",
            ]
        } else {
            &["BAG: topic \"/joint_states\": header.stamp is 0: the messages are stamped by their log time instead"]
        };
        assert_eq!(notes, expected_notes, "{name}");
    }
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn a_mocap_topic_on_another_clock_is_aligned_and_a_lag_is_left_to_diagnose() {
    let (dir, expected) = fixtures_or_skip!();
    // +0.8 s: another clock, beyond what the time_offset effect models: aligned, within 5 ms.
    let r = read_ok(dir, "mocap_clock");
    let clock = r.ground_truth_clock.as_ref().expect("the topic's clock is aligned");
    assert!((clock.offset_s - 0.8).abs() < 0.005, "{clock:?}");
    let want = &expected["mocap_clock"]["truth"];
    let truth = r.runs[0].truth();
    // The truth as written on the wheel clock: the first pose within the wheel data.
    let first = want.as_array().unwrap().iter().find(|p| (p[0].as_f64().unwrap() - truth[0].t_s).abs() < 0.01).unwrap();
    assert!((truth[0].pose.x_m - first[1].as_f64().unwrap()).abs() < 1e-9, "{:?} vs {first}", truth[0]);
    // Forced (--gt-time-offset without --gt): applied as given, not estimated.
    let forced = McapOptions { truth_time_offset_s: Some(0.75), ..Default::default() };
    let r = read(dir, "mocap_clock", &forced).unwrap();
    let clock = r.ground_truth_clock.as_ref().unwrap();
    assert!(clock.offset_s == 0.75 && clock.estimate.is_none(), "{clock:?}");
    // 60 ms: a lag the time_offset effect models (diagnose names it): the stamps stay as recorded.
    let r = read_ok(dir, "mocap_lag");
    assert!(r.ground_truth_clock.is_none(), "{:?}", r.ground_truth_clock);
    // Poses every 40 ms from 0.25 s − 60 ms: the first within the wheel data (from 0.25 s) is at 0.27 s.
    assert!((r.runs[0].truth()[0].t_s - (0.25 - 0.06 + 0.08)).abs() < 1e-9, "{:?}", r.runs[0].truth()[0]);
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn ros1_bags_give_the_runs_of_the_same_messages_in_mcap() {
    let (dir, _) = fixtures_or_skip!();
    let want = read_ok(dir, "ros1_pair");
    for name in ["ros1_bz2", "ros1_lz4"] {
        let got = omni_cli::dataset::ros1::read_bag(&dir.join(format!("{name}.bag")), &McapOptions::default(), None)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(got.runs.len(), 1, "{name}");
        let (a, b) = (&got.runs[0], &want.runs[0]);
        assert_eq!(a.wheel_t_s(), b.wheel_t_s(), "{name}");
        assert_eq!(a.wheel_rad_s(), b.wheel_rad_s(), "{name}");
        assert_eq!(a.truth(), b.truth(), "{name}");
        assert_eq!(got.origin_s, want.origin_s, "{name}");
        assert_eq!(got.notes.len(), want.notes.len(), "{name}: {:?} vs {:?}", got.notes, want.notes);
    }
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn encoder_counts_and_motor_rpm_are_read_with_the_declared_units() {
    use omni_kin::robot::{PositionUnit, VelocityUnit, WheelData};
    let (dir, _) = fixtures_or_skip!();
    let want = read_ok(dir, "ros1_pair");
    let units = WheelData {
        position: PositionUnit::Counts,
        velocity: VelocityUnit::Rpm,
        counts_per_rev: Some(1024.0),
        gear_ratio: Some(30.0),
        source: None,
    };
    let opts = McapOptions { wheel_data: units, ..Default::default() };
    let read = |name: &str, opts: &McapOptions| {
        omni_cli::dataset::ros1::read_bag(&dir.join(format!("{name}.bag")), opts, None)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    // Motor rpm: the wheel speeds written, to rounding.
    let rpm = read("ros1_counts_rpm", &opts);
    let (a, b) = (&rpm.runs[0], &want.runs[0]);
    assert_eq!(a.wheel_t_s(), b.wheel_t_s());
    let worst = a.wheel_rad_s().iter().zip(b.wheel_rad_s()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-12, "rpm: {worst}");
    assert!(
        rpm.notes.iter().any(|n| n.text.ends_with(
            "joint positions in counts and velocities in rpm (1024 counts per revolution) behind a 30:1 gear are \
         converted to the wheel's rad and rad/s ([wheel_data] in the robot description)"
        )),
        "{:?}",
        rpm.notes
    );
    // Counts only: speeds are differences of counts, each count 2π / 30720 rad, over 10 ms steps.
    let counts = read("ros1_counts", &opts);
    let quantum_rad_s = std::f64::consts::TAU / (30.0 * 1024.0) / 0.01;
    let a = &counts.runs[0];
    let worst = a.wheel_rad_s().iter().zip(b.wheel_rad_s()).skip(3).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    assert!(worst <= quantum_rad_s * 1.0001, "counts: {worst} vs one count per step {quantum_rad_s}");
    // Read as radians, the counts turn the wheels 4889 times too fast: refused, saying what to declare.
    let e = omni_cli::dataset::ros1::read_bag(&dir.join("ros1_counts.bag"), &McapOptions::default(), None)
        .unwrap_err()
        .to_string();
    assert!(
        e.ends_with(
            "topic \"/joint_states\", message 0: run ros1_counts: wheel sample 0 has wheel_rad_s[2] = \
             12199.999999999989, beyond the plausible limit ±10000: are the joints in encoder counts, rpm or \
             degrees? Declare their units in robot.toml's [wheel_data] (docs/formats.md)"
        ),
        "{e}"
    );
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn ground_truth_from_tf_pose_with_covariance_and_odometry() {
    let (dir, expected) = fixtures_or_skip!();
    for name in ["tf", "pose_cov", "odom_truth"] {
        let r = read_ok(dir, name);
        check_run(&r.runs[0], &expected[name]);
    }
    // A marker's TF, moved to base_link through /tf_static (marker → mount → base_link), with a note.
    let r = read_ok(dir, "tf_marker");
    check_run(&r.runs[0], &expected["tf_marker"]);
    assert!(
        r.notes.iter().any(|n| n.text.ends_with(
            "topic \"/tf\": the ground truth tracks \"marker\"; it is moved to \"base_link\" through static \
             transforms (marker → mount → base_link: x -0.1000 m, y 0.0500 m, yaw 30.00°)"
        )),
        "{:?}",
        r.notes
    );
    // Named, the child frame may be any frame the statics reach; the marker itself is the marker's poses.
    let laser = read(dir, "tf_marker", &McapOptions { truth_child_frame: Some("laser".into()), ..Default::default() });
    let (at_laser, at_base) = (laser.unwrap().runs[0].truth()[5], r.runs[0].truth()[5]);
    let th = at_base.pose.theta_rad;
    assert!((at_laser.pose.x_m - at_base.pose.x_m - 0.2 * th.cos()).abs() < 1e-9, "{at_laser:?} {at_base:?}");
    assert!((at_laser.pose.y_m - at_base.pose.y_m - 0.2 * th.sin()).abs() < 1e-9, "{at_laser:?} {at_base:?}");
    let marker =
        read(dir, "tf_marker", &McapOptions { truth_child_frame: Some("marker".into()), ..Default::default() });
    let at_marker = marker.unwrap().runs[0].truth()[5];
    assert!((at_marker.pose.theta_rad - (th - 30f64.to_radians())).abs() < 1e-9, "{at_marker:?}");
    // The world-frame Odometry is the truth; the odom-frame one is the recorded odometry (x twice the truth's).
    let r = read_ok(dir, "odom_truth");
    let (odom, truth) = (r.runs[0].recorded_odometry(), r.runs[0].truth());
    assert_eq!(odom.len(), 21);
    assert!((odom[20].pose.x_m - 2.0 * truth[20].pose.x_m).abs() < 1e-12 && truth[20].pose.x_m > 0.25);
    // TF frames chosen explicitly (a leading `/` in a frame id is ignored).
    let opts = McapOptions {
        truth_topic: Some("/tf".into()),
        truth_parent_frame: Some("world".into()),
        truth_child_frame: Some("robot_mocap".into()),
        ..Default::default()
    };
    check_run(&read(dir, "tf", &opts).unwrap().runs[0], &expected["tf"]);
    let opts = McapOptions { truth_child_frame: Some("base_link".into()), ..opts };
    assert_eq!(
        error(dir, "tf", &opts),
        "topic \"/tf\": no transform could be the ground truth (transforms: map → odom (51 poses), odom → base_link \
         (51 poses), world → robot_mocap (20 poses)); choose one with --gt-parent-frame and --gt-child-frame"
    );
    let opts = McapOptions { truth_parent_frame: Some("world".into()), ..Default::default() };
    assert_eq!(
        error(dir, "pose_cov", &opts),
        "no ground truth: no geometry_msgs/msg/PoseStamped, geometry_msgs/msg/PoseWithCovarianceStamped, \
         nav_msgs/msg/Odometry, tf2_msgs/msg/TFMessage, geometry_msgs/msg/PointStamped and sensor_msgs/msg/NavSatFix (positions only) source \
         outside the robot's frames (odom, base_link, base_footprint) matching --gt-parent-frame \"world\" --gt-child-frame \"(any)\"; topics: /joint_states \
         (sensor_msgs/msg/JointState, 101 messages), /mocap/pose_cov (geometry_msgs/msg/PoseWithCovarianceStamped, \
         21 messages, frame \"mocap\"). Without motion capture: a lidar's scans (--gt-scans TOPIC); a sensor's or a \
         localization's own path (--gt-kind relative with --gt-topic or --gt); tape-measured end poses (--gt-kind end-pose --gt TABLE; \
         omnical plan --umbmark)"
    );
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn rosbags_and_mcap_read_what_we_write() {
    let (dir, _) = fixtures_or_skip!();
    let run = simulated_run("sim", 2.0);
    let path = dir.join("ours.mcap");
    let w =
        WriteOptions { design_odometry: Some(design_odometry(&run)), origin_s: 1_700_000_000, ..Default::default() };
    write_run(&path, &run, &w).unwrap();
    let out = Command::new(python()).arg(script()).arg("--check").arg(&path).output().unwrap();
    assert!(out.status.success(), "make_bags.py --check failed: {}", String::from_utf8_lossy(&out.stderr));
    let seen: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(seen["profile"], "ros2");
    assert_eq!(seen["chunk_compression"], serde_json::json!(["zstd"]));
    let topics = &seen["topics"];
    for (topic, schema, count) in [
        ("/joint_states", "sensor_msgs/msg/JointState", 201),
        ("/ground_truth/pose", "geometry_msgs/msg/PoseStamped", 51),
        ("/cmd_vel", "geometry_msgs/msg/TwistStamped", 2),
        ("/odom", "nav_msgs/msg/Odometry", 51),
    ] {
        assert_eq!(topics[topic]["schema"], schema, "{topic}");
        assert_eq!(topics[topic]["schema_encoding"], "ros2msg", "{topic}");
        assert_eq!(topics[topic]["message_encoding"], "cdr", "{topic}");
        assert_eq!(topics[topic]["count"], count, "{topic}");
        assert_eq!(seen["schemas_match_rosbags"][schema], true, "{schema}: schema text differs from rosbags'");
    }
    assert_eq!(topics.as_object().unwrap().len(), 4);
    // With mcap-ros2-support installed: every message decodes through our schema text, as in Foxglove.
    assert_eq!(seen["decoded_from_schema_text"], 201 + 51 + 2 + 51, "mcap-ros2-support decodes every message");
    // Values as rosbags decodes them.
    let js = &seen["messages"]["/joint_states"];
    let last = &js[200];
    assert_eq!((last[0].as_i64(), last[1].as_i64()), (Some(1_700_000_002), Some(0)));
    assert_eq!(last[2], serde_json::json!(["wheel_a", "wheel_b", "wheel_c"]));
    close(&floats(&last[3]), run.wheel_sample(200), 0.0, "velocity");
    let start = floats(&js[0][4]);
    close(&start, run.wheel_start_rad(), 0.0, "position at the first sample");
    let gt = &seen["messages"]["/ground_truth/pose"][50];
    assert_eq!(gt[2], "map");
    close(&[gt[3].as_f64().unwrap(), gt[4].as_f64().unwrap()], &[2f64.sin(), 0.2], 1e-15, "truth x, y");
    // The quaternion of yaw 1 rad: (z, w) = (sin 0.5, cos 0.5).
    let yaw = 2.0 * gt[5].as_f64().unwrap().atan2(gt[6].as_f64().unwrap());
    assert!((yaw - 1.0).abs() < 1e-12, "yaw {yaw}");
    // The command is stamped (TwistStamped, body frame): at the first and the last wheel sample.
    let cmd = &seen["messages"]["/cmd_vel"];
    assert_eq!(
        (cmd[0][0].as_i64(), cmd[0][1].as_i64(), cmd[0][2].as_str()),
        (Some(1_700_000_000), Some(0), Some("base_link"))
    );
    assert_eq!((cmd[1][0].as_i64(), cmd[1][1].as_i64()), (Some(1_700_000_002), Some(0)));
    assert_eq!(cmd[0][3].as_i64(), Some(1_700_000_000_000_000_000), "log time = stamp");
    let twist = |row: &Value| floats(&Value::from(row.as_array().unwrap()[4..].to_vec()));
    close(&twist(&cmd[0]), &[0.25 * 0.5f64.cos(), 0.25 * 0.5f64.sin(), -0.75], 1e-15, "command");
    close(&twist(&cmd[1]), &[0.0, 0.0, 0.0], 0.0, "final zero command");
    let od = &seen["messages"]["/odom"][0];
    assert_eq!((od[2].as_str(), od[3].as_str()), (Some("odom"), Some("base_link")));
}
