//! The MCAP reader's refusals on real ROS 2 and ROS 1 bags (written by Python `rosbags`,
//! `tests/mcap/make_bags.py`): a bad piece collected with `skip_invalid`, unindexed or truncated bags, and
//! errors that name the file, topic, message and field. The interpreter and the ignored-without-tools rule
//! are `mcap_rosbags`'s.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a failed unwrap is a failed test

#[macro_use]
#[path = "mcap/fixtures.rs"]
mod fixtures;
#[path = "mcap/helpers.rs"]
mod helpers;
mod support;

use fixtures::{error, fixtures, read};
use helpers::check_run;
use omni_cli::dataset::mcap::McapOptions;

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn skip_invalid_collects_a_bad_piece() {
    let (dir, expected) = fixtures_or_skip!();
    let path = dir.join("split_gap.mcap");
    let reason =
        format!("{}: run split_gap#2: ground-truth poses has 1 entries, at least 2 are needed", path.display());
    let opts = McapOptions { split: Some(1.0), ..Default::default() };
    assert_eq!(read(dir, "split_gap", &opts).unwrap_err(), reason);
    let r = read(dir, "split_gap", &McapOptions { skip_invalid: true, ..opts }).unwrap();
    assert_eq!(r.runs.len(), 1);
    check_run(&r.runs[0], &expected["split_gap"]["runs"][0]);
    assert_eq!(r.skipped, [("split_gap#2".to_string(), reason)]);
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn unindexed_and_truncated_ros1_bags_say_to_reindex() {
    let (dir, _) = fixtures_or_skip!();
    let bytes = std::fs::read(dir.join("ros1_bz2.bag")).unwrap();
    let read_err = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = omni_cli::dataset::ros1::read_bag(&path, &McapOptions::default(), None).unwrap_err();
        (e.to_string(), path.display().to_string())
    };
    // An interrupted `rosbag record` leaves index_pos 0 in the bag header.
    let at = bytes.windows(10).position(|w| w == b"index_pos=").unwrap() + 10;
    let mut unindexed = bytes.clone();
    unindexed[at..at + 8].fill(0);
    let (e, path) = read_err("unindexed.bag", &unindexed);
    assert_eq!(
        e,
        format!(
            "{path}: the bag has no index (was its recording interrupted?): run `rosbag reindex {path}` (ROS 1) and \
             read the reindexed bag"
        )
    );
    let (e, path) = read_err("cut.bag", &bytes[..bytes.len() / 2]);
    assert!(e.starts_with(&format!("{path}: the file is truncated: its index should start at byte ")), "{e}");
    assert!(e.ends_with(&format!("run `rosbag reindex {path}` (ROS 1) and read the reindexed bag")), "{e}");
    let (e, path) = read_err("text.bag", b"not a bag");
    assert_eq!(e, format!("{path}: not a ROS 1 bag: it does not start with \"#ROSBAG V2.0\""));
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn errors_name_file_topic_message_and_field() {
    let (dir, _) = fixtures_or_skip!();
    let d = McapOptions::default();
    let cases: [(&str, McapOptions, &str); 12] = [
        ("not_mcap", d.clone(), "not an MCAP file (it does not start with the MCAP magic bytes)"),
        (
            "no_truth",
            d.clone(),
            "no ground truth: no geometry_msgs/msg/PoseStamped, geometry_msgs/msg/PoseWithCovarianceStamped, \
             nav_msgs/msg/Odometry, tf2_msgs/msg/TFMessage, geometry_msgs/msg/PointStamped and sensor_msgs/msg/NavSatFix (positions only) \
             source outside the robot's frames (odom, base_link, base_footprint); topics: /chatter (std_msgs/msg/String, 1 message), /joint_states \
             (sensor_msgs/msg/JointState, 101 messages), /odom (nav_msgs/msg/Odometry, 1 message, frame \"odom\": \
             the robot's own odometry). Without motion capture: a lidar's scans (--gt-scans TOPIC); a sensor's or a \
             localization's own path (--gt-kind relative with --gt-topic or --gt); tape-measured end poses (--gt-kind end-pose --gt TABLE; \
             omnical plan --umbmark)",
        ),
        (
            "no_truth",
            McapOptions { truth_topic: Some("/chatter".into()), ..d.clone() },
            "topic \"/chatter\": type std_msgs/msg/String cannot be ground truth (supported: \
             geometry_msgs/msg/PoseStamped, geometry_msgs/msg/PoseWithCovarianceStamped, nav_msgs/msg/Odometry, \
             tf2_msgs/msg/TFMessage, geometry_msgs/msg/PointStamped and sensor_msgs/msg/NavSatFix (positions only))",
        ),
        (
            "no_truth",
            McapOptions { truth_topic: Some("/odom".into()), ..d.clone() },
            "topic \"/odom\": is the robot's own wheel odometry (frame \"odom\", REP-105): the model under test, \
             never ground truth; choose a map, world or motion-capture source",
        ),
        (
            "no_truth",
            McapOptions { joints_topic: Some("/chatter".into()), ..d.clone() },
            "topic \"/chatter\": type std_msgs/msg/String is not sensor_msgs/msg/JointState (wheel speeds) or \
             nav_msgs/msg/Odometry (the robot's own odometry)",
        ),
        (
            "no_truth",
            McapOptions { joints_topic: Some("/odom".into()), ..d.clone() },
            "topic \"/odom\": is nav_msgs/msg/Odometry: wheel speeds can come from it only through the robot's \
             design; describe the robot (omnical init RECORDING writes robot.toml from its URDF, or --robot FILE)",
        ),
        (
            "no_truth",
            McapOptions { truth_topic: Some("/mocap".into()), ..d.clone() },
            "--gt-topic /mocap: no such topic; topics: /chatter (std_msgs/msg/String, 1 message), /joint_states \
             (sensor_msgs/msg/JointState, 101 messages), /odom (nav_msgs/msg/Odometry, 1 message, frame \"odom\": \
             the robot's own odometry)",
        ),
        ("nan_velocity", d.clone(), "topic \"/joint_states\", message 7: field velocity[1] (joint \"wheel_b\") is NaN"),
        ("nan_pose", d.clone(), "topic \"/mocap/pose\", message 3: field pose.position.x is NaN"),
        (
            "backwards",
            d.clone(),
            "topic \"/joint_states\", message 10: header.stamp 1700000000.325000000 is not after the previous \
             message's 1700000000.340000000 (stamps must increase)",
        ),
        ("empty", d.clone(), "topic \"/joint_states\": has no messages (empty run)"),
        (
            "json_encoding",
            d.clone(),
            "topic \"/joint_states\": schema encoding \"ros2msg\" with message encoding \"json\" is not supported \
             (expected schema encoding \"ros2msg\" and message encoding \"cdr\", as rosbag2 records)",
        ),
    ];
    for (name, opts, want) in cases {
        assert_eq!(error(dir, name, &opts), want, "{name}");
    }
    // A wheel missing from one message (5) is mended from its neighbours, with a note that counts it
    // (issue 44); a long gap is refused (joint_state::repair's own tests).
    let mended = read(dir, "missing_joint", &d).unwrap();
    let notes: Vec<String> = mended.notes.iter().map(|n| n.text.clone()).collect();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("wheel joint \"wheel_c\" is missing from 1 of 101 messages (at most 1 in a row)")),
        "{notes:?}"
    );
    assert_eq!(
        error(dir, "ambiguous", &d),
        "several ground-truth sources: /mocap/pose (geometry_msgs/msg/PoseStamped, frame \"map\"), /vicon/pose \
         (geometry_msgs/msg/PoseStamped, frame \"map\"); choose one with --gt-topic (for a TF topic, also \
         --gt-parent-frame and --gt-child-frame)"
    );
    let r = read(dir, "ambiguous", &McapOptions { truth_topic: Some("/mocap/pose".into()), ..d.clone() }).unwrap();
    assert_eq!(r.runs[0].truth().len(), 21);
    // The arm's JointState topic has no wheel joints; it fails only when chosen, and points at the robot's
    // own odometry the bag also holds.
    assert_eq!(
        error(dir, "normal", &McapOptions { joints_topic: Some("/arm/joint_states".into()), ..d.clone() }),
        "topic \"/arm/joint_states\", message 0: wheel joint \"wheel_a\" is missing (names: shoulder, elbow); if no \
         JointState topic carries the wheels, the robot's own odometry /odom can stand in through the robot's \
         design: --joints-topic /odom ([topics] joint_states in robot.toml)"
    );
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn truncated_bag_is_an_error() {
    let (dir, _) = fixtures_or_skip!();
    let bytes = std::fs::read(dir.join("zstd.mcap")).unwrap();
    let cut = dir.join("truncated.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 3 / 5]).unwrap();
    assert_eq!(
        error(dir, "truncated", &McapOptions::default()),
        "the file is truncated: it ends in the middle of a record, before the MCAP end marker (was the recording \
         interrupted?)"
    );
}
