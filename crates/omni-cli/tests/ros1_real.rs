//! ROS 1 bags as a real mecanum robot records them (issue 44): JointState `position` in wheel encoder counts
//! beside `velocity` in motor rpm, which gives 6.6 times the rate (a gear the driver does not undo); a stale
//! copy of a joint; a joint missing now and then; `init` without a URDF; folders as people leave them.
//! The bags are written here, byte by byte, as `rosbag record` lays out format 2.0 (uncompressed chunks):
//! no Python needed.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::Path;
use support::{omnical, refused, stderr};

/// A ROS 1 bag of format 2.0, written as `rosbag record` lays it out (`ros1_real/ros1.rs`).
#[path = "ros1_real/ros1.rs"]
mod ros1;

const JOINTS: [&str; 4] = ["front_left_wheel", "front_right_wheel", "rear_left_wheel", "rear_right_wheel"];
/// Wheel encoder counts per wheel turn, and the motor's turns per wheel turn that the rpm field holds but
/// the robot description does not say (the 6.6 of issue 44).
const COUNTS_PER_REV: f64 = 4096.0;
const HIDDEN_GEAR: f64 = 6.6;
const RADIUS_M: f64 = 0.05;
const T0_NS: u64 = 1_700_000_000_000_000_000;

/// The mecanum robot's description: counts and rpm declared on the wheel's shaft, `source` if given.
fn robot(source: Option<&str>) -> String {
    let mut s = String::from("kind = \"mecanum\"\n");
    for (j, (x, y, roller)) in
        JOINTS.iter().zip([(0.2, 0.17, -45.0), (0.2, -0.17, 45.0), (-0.2, 0.17, 45.0), (-0.2, -0.17, -45.0)])
    {
        s += &format!(
            "\n[[wheels]]\njoint = \"{j}\"\nx_m = {x}\ny_m = {y}\nradius_m = {RADIUS_M}\nroller_angle_deg = {roller}\n"
        );
    }
    s += "\n[topics]\njoint_states = \"/joint_states\"\nground_truth = \"/mocap/pose\"\n";
    s += &format!("\n[wheel_data]\nposition = \"counts\"\nvelocity = \"rpm\"\ncounts_per_rev = {COUNTS_PER_REV}\n");
    if let Some(f) = source {
        s += &format!("source = \"{f}\"\n");
    }
    s
}

/// A bag of the robot driving straight ahead at 0.3 m/s for 8 s (joints at 50 Hz, motion capture at
/// 100 Hz), barely turning: `position` in wheel counts, `velocity` in motor rpm. `edit` may change each
/// joint message's names, positions and velocities.
fn straight_bag(path: &Path, edit: impl Fn(usize, &mut Vec<&str>, &mut Vec<f64>, &mut Vec<f64>)) {
    let omega = 0.3 / RADIUS_M;
    let mut messages = Vec::new();
    for k in 0..=400u64 {
        let (t, ns) = (k as f64 * 0.02, T0_NS + k * 20_000_000);
        let counts = (omega * t / std::f64::consts::TAU * COUNTS_PER_REV).round();
        let rpm = omega * 60.0 / std::f64::consts::TAU * HIDDEN_GEAR;
        let (mut names, mut p, mut v) = (JOINTS.to_vec(), vec![counts; 4], vec![rpm; 4]);
        edit(k as usize, &mut names, &mut p, &mut v);
        messages.push((0, ns, ros1::joint_state(ns, &names, &p, &v)));
    }
    for k in 0..=800u64 {
        let (t, ns) = (k as f64 * 0.01, T0_NS + k * 10_000_000);
        messages.push((1, ns, ros1::pose_stamped(ns, 0.3 * t, 0.0, 0.001 * t)));
    }
    messages.sort_by_key(|m| m.1);
    let topics = [("/joint_states", "sensor_msgs/JointState"), ("/mocap/pose", "geometry_msgs/PoseStamped")];
    std::fs::write(path, ros1::bytes(&topics, &messages)).unwrap();
}

fn load(dir: &Path, bag: &str, robot_file: &str) -> Result<omni_cli::dataset::Dataset, String> {
    let robot_file = dir.join(robot_file).display().to_string();
    let data = omni_cli::api::load::DataOptions { robot: Some(robot_file), ..Default::default() };
    let request = omni_cli::api::load::LoadRequest::new(&[dir.join(bag)], &data);
    let robot = request.robot().map_err(|e| e.to_string())?;
    request.read_for_robot(robot).map_err(|e| format!("{e:#}"))
}

/// The real robot's bags: the two fields disagree, which is refused naming both rates; declared, the
/// source is read, and `velocity` in motor rpm is then refused by the wheel-unit check, although the run
/// barely turns; `position` gives the motion capture's speed.
#[test]
fn counts_beside_motor_rpm_are_refused_until_the_source_is_declared() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    straight_bag(&d.join("straight.bag"), |_, _, _, _| {});
    for (file, source) in
        [("robot.toml", None), ("by_position.toml", Some("position")), ("by_velocity.toml", Some("velocity"))]
    {
        std::fs::write(d.join(file), robot(source)).unwrap();
    }
    let err = refused(&["eval", "straight.bag", "--robot", "robot.toml"], d);
    let last = err.lines().last().unwrap();
    assert!(
        last.starts_with(
            "error: straight.bag: topic \"/joint_states\", message 0: field velocity gives a wheel rate of 39.600 \
             rad/s and field position 6.0"
        ),
        "{err}"
    );
    assert!(
        last.contains(
            "windows: 6.60 times more by velocity; position read in counts and velocity in rpm, as [wheel_data] declares)"
        ),
        "{err}"
    );
    assert!(last.ends_with("[wheel_data] source = \"position\" or \"velocity\", with that field's unit and gear_ratio (docs/formats.md)"), "{err}");

    // velocity declared: the wheels go 6.6 times as far as the motion capture; refused though the run turns
    // 0.5°, too little for the turning to be judged.
    let err = refused(&["eval", "straight.bag", "--robot", "by_velocity.toml"], d);
    let last = err.lines().last().unwrap();
    assert!(
        last.starts_with("error: through the design of by_velocity.toml, the wheels of run straight travel 15.1 m"),
        "{err}"
    );
    assert!(last.contains("where their ground truth travels 2.4 m and turns 0.0 rad: 6.29 times"), "{err}");

    // position declared: the wheel speeds of the motion capture, 6 rad/s, to a count's quantum.
    let ds = load(d, "straight.bag", "by_position.toml").unwrap();
    let run = &ds.runs[0];
    let mean: f64 = run.wheel_rad_s().iter().sum::<f64>() / run.wheel_rad_s().len() as f64;
    assert!((mean - 6.0).abs() < 0.01, "{mean}");
    assert!(
        ds.notes
            .iter()
            .any(|n| n.text.contains("the wheel speeds come from field position ([wheel_data] source = \"position\")")),
        "{:?}",
        ds.notes
    );
}

/// A stale copy of a joint before the live one, and a wheel missing from one message in fifty: read right,
/// each noted; a wheel missing for a fifth of a second is refused naming the gap.
#[test]
fn stale_copies_and_missing_joints_of_a_ros1_bag() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("robot.toml"), robot(Some("position"))).unwrap();
    straight_bag(&d.join("dup.bag"), |_, n, p, v| {
        n.insert(0, "rear_left_wheel");
        p.insert(0, 0.0);
        v.insert(0, 0.0);
    });
    straight_bag(&d.join("gaps.bag"), |k, n, p, v| {
        if k % 50 == 25 {
            n.remove(2);
            p.remove(2);
            v.remove(2);
        }
    });
    for bag in ["dup.bag", "gaps.bag"] {
        let ds = load(d, bag, "robot.toml").unwrap_or_else(|e| panic!("{bag}: {e}"));
        let w = ds.runs[0].wheel_rad_s();
        let worst = w.iter().map(|x| (x - 6.0).abs()).fold(0.0, f64::max);
        assert!(worst < 0.2, "{bag}: {worst}");
        let notes: Vec<&str> = ds.notes.iter().map(|n| n.text.as_str()).collect();
        let want = match bag {
            "dup.bag" => "joint \"rear_left_wheel\" is named twice in 401 messages; its first entry never changes",
            _ => "wheel joint \"rear_left_wheel\" is missing from 8 of 401 messages (at most 1 in a row)",
        };
        assert!(notes.iter().any(|n| n.contains(want)), "{bag}: {notes:?}");
    }
    straight_bag(&d.join("long_gap.bag"), |k, n, p, v| {
        if (100..110).contains(&k) {
            n.remove(2);
            p.remove(2);
            v.remove(2);
        }
    });
    let err = refused(&["eval", "long_gap.bag", "--robot", "robot.toml"], d);
    assert!(
        err.contains(
            "long_gap.bag: topic \"/joint_states\", message 100: wheel joint \"rear_left_wheel\" is missing from 10 \
             messages in a row (samples 100 to 109, 0.220 s from the message before to the one after): too long a gap"
        ),
        "{err}"
    );
}

/// `init` on a ROS 1 bag (no /robot_description): refused naming --kind; with --kind, a skeleton of the
/// bag's joints whose values to measure are marked, which omnical refuses until they are written.
#[test]
fn init_on_a_ros1_bag_offers_a_skeleton_with_the_values_to_measure_marked() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    straight_bag(&d.join("rec.bag"), |_, _, _, _| {});
    let err = refused(&["init", "rec.bag"], d);
    assert!(err.contains("rec.bag: the recording has no /robot_description topic"), "{err}");
    assert!(err.contains("add --kind diff|omni|mecanum for a robot.toml skeleton"), "{err}");
    let out = omnical(&["init", "rec.bag", "--kind", "mecanum"], d);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(d.join("robot.toml")).unwrap();
    assert_eq!(text.matches("[[wheels]]").count(), 4, "{text}");
    assert_eq!(text.lines().filter(|l| !l.starts_with('#') && l.contains("FILL IN")).count(), 16, "{text}");
    assert!(text.contains("joint = \"rear_right_wheel\""), "{text}");
    let line = text.lines().position(|l| l.starts_with("x_m = 0.0")).unwrap() + 1;
    let err = refused(&["eval", "rec.bag"], d);
    assert!(
        err.contains(&format!(
            "robot.toml: line {line}: x_m: is still marked FILL IN (a skeleton from omnical init): measure it, write \
             its value and remove the mark"
        )),
        "{err}"
    );
}

/// A folder holding a symbolic link to itself is read once, and says so; `info` on an empty folder, or
/// one without recordings, says what it looked for.
#[test]
fn folders_as_people_leave_them() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let data = d.join("data");
    std::fs::create_dir(&data).unwrap();
    std::fs::write(d.join("robot.toml"), robot(Some("position"))).unwrap();
    straight_bag(&data.join("a.bag"), |_, _, _, _| {});
    #[cfg(unix)]
    std::os::unix::fs::symlink(&data, data.join("again")).unwrap();
    let ds = load(d, "data", &d.join("robot.toml").display().to_string()).unwrap();
    assert_eq!(ds.runs.len(), 1);
    #[cfg(unix)]
    assert!(
        ds.notes.iter().any(|n| n.text.starts_with(
            "1 path leads to files or folders already read (symbolic links, or a path given twice), first "
        )),
        "{:?}",
        ds.notes
    );
    std::fs::create_dir(d.join("empty")).unwrap();
    let err = refused(&["info", "empty"], d);
    assert_eq!(
        err.lines().last().unwrap(),
        "error: empty: no ROS recording here: looked for .mcap, .db3 and .bag files and rosbag2 recording folders \
         (metadata.yaml), CSV runs and OptiOdom sets, in the folder and its subfolders; the folder is empty"
    );
    std::fs::create_dir(d.join("notes")).unwrap();
    std::fs::write(d.join("notes/readme.txt"), "x").unwrap();
    let err = refused(&["info", "notes"], d);
    assert!(
        err.lines().last().unwrap().ends_with("in the folder and its subfolders; it holds only readme.txt"),
        "{err}"
    );
}

/// A differential drive (wheels 0.05 m, 0.3 m apart) on an arc at 0.3 m/s and 0.4 rad/s for 8 s: joints at
/// 50 Hz in rad and rad/s, motion capture at 100 Hz; its description.
fn arc_bag(path: &Path) -> String {
    let (v, w, r, b) = (0.3, 0.4, 0.05, 0.3);
    let (left, right) = ((v - w * b / 2.0) / r, (v + w * b / 2.0) / r);
    let mut messages = Vec::new();
    for k in 0..=400u64 {
        let (t, ns) = (k as f64 * 0.02, T0_NS + k * 20_000_000);
        let names = ["left_wheel", "right_wheel"];
        messages.push((0, ns, ros1::joint_state(ns, &names, &[left * t, right * t], &[left, right])));
    }
    for k in 0..=800u64 {
        let (t, ns) = (k as f64 * 0.01, T0_NS + k * 10_000_000);
        let th = w * t;
        messages.push((1, ns, ros1::pose_stamped(ns, v / w * th.sin(), v / w * (1.0 - th.cos()), th)));
    }
    messages.sort_by_key(|m| m.1);
    let topics = [("/joint_states", "sensor_msgs/JointState"), ("/mocap/pose", "geometry_msgs/PoseStamped")];
    std::fs::write(path, ros1::bytes(&topics, &messages)).unwrap();
    "kind = \"diff\"\n\n[diff]\nwheel_separation_m = 0.3\nleft_joint = \"left_wheel\"\nright_joint = \"right_wheel\"\n\
     left_radius_m = 0.05\nright_radius_m = 0.05\n\n[topics]\njoint_states = \"/joint_states\"\n"
        .to_string()
}

/// Measured end poses as people type them: decimal commas in a `;` table read as in a `,` one; a decimal
/// comma in a `,` table, millimetres under x_m, degrees under yaw_rad and radians under yaw_deg are refused
/// against what the wheels say, naming the line, the column and the unit the value fits.
#[test]
fn end_pose_tables_are_checked_against_the_wheels() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("robot.toml"), arc_bag(&d.join("arc.bag"))).unwrap();
    // The arc's end in its start's frame: 3.2 rad round a 0.75 m radius.
    let (x, y, yaw) = (0.75 * 3.2f64.sin(), 0.75 * (1.0 - 3.2f64.cos()), 3.2f64);
    let tables = [
        ("ok.csv", format!("run;x_m;y_m;yaw_deg\narc;{};{};{}\n", x, y, yaw.to_degrees()).replace('.', ",")),
        ("comma.csv", format!("run,x_m,y_m,yaw_deg\narc,{},{},{}\n", x, y, yaw.to_degrees()).replacen("0.", "0,", 1)),
        ("mm.csv", format!("run,x_m,y_m,yaw_rad\narc,{:.1},{:.1},{yaw}\n", x * 1e3, y * 1e3)),
        ("deg.csv", format!("run,x_m,y_m,yaw_rad\narc,{x},{y},{:.1}\n", yaw.to_degrees())),
        ("rad.csv", format!("run,x_m,y_m,yaw_deg\narc,{x},{y},{yaw}\n")),
    ];
    for (name, text) in &tables {
        std::fs::write(d.join(name), text).unwrap();
    }
    let data = omni_cli::api::load::DataOptions {
        gt_kind: omni_kin::reference::ReferenceKind::EndPose,
        gt: Some(d.join("ok.csv")),
        robot: Some(d.join("robot.toml").display().to_string()),
        ..Default::default()
    };
    let request = omni_cli::api::load::LoadRequest::new(&[d.join("arc.bag")], &data);
    let ds = request.read_for_robot(request.robot().unwrap()).unwrap();
    let end = ds.runs[0].truth().last().unwrap().pose;
    assert!((end.x_m - x).abs() < 1e-9 && (end.y_m - y).abs() < 1e-9 && (end.theta_rad - yaw).abs() < 1e-9, "{end:?}");
    let refusal = |table: &str| {
        let err = refused(&["eval", "arc.bag", "--gt-kind", "end-pose", "--gt", table], d);
        err.lines().last().unwrap().to_string()
    };
    let e = refusal("comma.csv");
    assert!(e.starts_with("error: comma.csv: line 2: \"arc,-0,0"), "{e}");
    assert!(e.contains("has 5 cells but the header names 4 columns: a decimal comma (1,5)?"), "{e}");
    let e = refusal("mm.csv");
    assert!(e.starts_with("error: mm.csv: line 2, column x_m: run arc: the end is 1499."), "{e}");
    assert!(e.contains("but the wheels, through the design, put it 1.499 m from it along a 2.400 m path"), "{e}");
    assert!(e.ends_with("The values fit mm: name the columns x_mm and y_mm."), "{e}");
    let e = refusal("deg.csv");
    assert!(e.starts_with("error: deg.csv: line 2, column yaw_rad: run arc: the heading turned 183.3 rad"), "{e}");
    assert!(e.ends_with("As yaw_deg, 183.3 would fit: name the column yaw_deg."), "{e}");
    let e = refusal("rad.csv");
    assert!(
        e.starts_with(
            "error: rad.csv: line 2, column yaw_deg: run arc: the heading turned 3.2°, but the wheels, through \
             the design, turned it 183.3°"
        ),
        "{e}"
    );
    assert!(e.ends_with("As yaw_rad, 3.2 would fit: name the column yaw_rad."), "{e}");
}

/// `--split 3s` cuts an 8 s recording of a robot that never stops into runs of 3 s (the last 2 s, more than
/// half a length, its own); a bare number still cuts at standstills (none here: one run).
#[test]
fn split_with_a_unit_cuts_fixed_lengths() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("robot.toml"), robot(Some("position"))).unwrap();
    straight_bag(&d.join("long.bag"), |_, _, _, _| {});
    let runs = |split: &str| {
        let v: serde_json::Value = support::json(&["info", "long.bag", "--split", split, "--json"], d);
        let runs = v["recordings"][0]["read"]["runs"].as_array().unwrap().clone();
        runs.iter()
            .map(|r| (r["name"].as_str().unwrap().to_string(), r["duration_s"].as_f64().unwrap()))
            .collect::<Vec<_>>()
    };
    let cut = runs("3s");
    assert_eq!(cut.iter().map(|r| r.0.as_str()).collect::<Vec<_>>(), ["long#1", "long#2", "long#3"]);
    assert!((cut[0].1 - 3.0).abs() < 1e-9 && (cut[2].1 - 2.0).abs() < 1e-9, "{cut:?}");
    assert_eq!(runs("0.05min").len(), 3);
    assert_eq!(runs("2").len(), 1);
    let err = refused(&["info", "long.bag", "--split", "3 m/s"], d);
    assert!(err.contains("a length with its unit (20s, 2min)"), "{err}");
}

/// A motion-capture marker that the URDF places below base_link, base_link under base_footprint: the
/// ground truth (world → marker) is moved to base_link through the static transform followed upwards; a
/// marker the static transforms name but do not join to the base is said so.
#[test]
fn a_marker_below_base_link_is_followed_up_the_tree() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let marker = (0.1, 0.05, 0.3);
    let write = |path: &Path, statics: &[(&str, &str, f64, f64, f64)]| {
        let mut messages = Vec::new();
        let omega = 0.3 / RADIUS_M;
        for k in 0..=400u64 {
            let (t, ns) = (k as f64 * 0.02, T0_NS + k * 20_000_000);
            let p = [omega * t; 4];
            messages.push((0, ns, ros1::joint_state(ns, &JOINTS, &p, &[omega; 4])));
        }
        messages.push((2, T0_NS, ros1::tf(T0_NS, statics)));
        for k in 0..=800u64 {
            let (t, ns) = (k as f64 * 0.01, T0_NS + k * 10_000_000);
            // The base at (0.3 t, 0), heading 0; the marker on it at `marker`.
            let (bx, by) = (0.3 * t, 0.0);
            messages.push((1, ns, ros1::tf(ns, &[("world", "marker", bx + marker.0, by + marker.1, marker.2)])));
        }
        messages.sort_by_key(|m| m.1);
        let topics = [
            ("/joint_states", "sensor_msgs/JointState"),
            ("/tf", "tf2_msgs/TFMessage"),
            ("/tf_static", "tf2_msgs/TFMessage"),
        ];
        std::fs::write(path, ros1::bytes(&topics, &messages)).unwrap();
    };
    let robot_text = robot(None).replace("ground_truth = \"/mocap/pose\"", "ground_truth = \"/tf\"").replace(
        &format!("\n[wheel_data]\nposition = \"counts\"\nvelocity = \"rpm\"\ncounts_per_rev = {COUNTS_PER_REV}\n"),
        "",
    );
    std::fs::write(d.join("robot.toml"), robot_text).unwrap();
    write(
        &d.join("below.bag"),
        &[("base_footprint", "base_link", 0.0, 0.0, 0.0), ("base_link", "marker", marker.0, marker.1, marker.2)],
    );
    let ds = load(d, "below.bag", &d.join("robot.toml").display().to_string()).unwrap();
    for p in ds.runs[0].truth() {
        assert!(
            (p.pose.x_m - 0.3 * p.t_s).abs() < 1e-6 && p.pose.y_m.abs() < 1e-6 && p.pose.theta_rad.abs() < 1e-9,
            "{p:?}"
        );
    }
    let notes: Vec<&str> = ds.notes.iter().map(|n| n.text.as_str()).collect();
    assert!(
        notes.iter().any(|n| n.contains("the ground truth tracks \"marker\"; it is moved to \"base_link\" through static transforms (marker → base_link")),
        "{notes:?}"
    );
    write(
        &d.join("apart.bag"),
        &[("base_footprint", "base_link", 0.0, 0.0, 0.0), ("marker", "marker_led", 0.0, 0.01, 0.0)],
    );
    let ds = load(d, "apart.bag", &d.join("robot.toml").display().to_string()).unwrap();
    let notes: Vec<&str> = ds.notes.iter().map(|n| n.text.as_str()).collect();
    assert!(
        notes.iter().any(|n| n.contains(
            "the ground truth tracks \"marker\", which the static transforms name, but they do not join it to base_link \
             or base_footprint"
        )),
        "{notes:?}"
    );
}

/// A model whose wheels are another robot's (or the same in another column order) is refused naming both
/// lists; a plan at 200 m/s or 90 rad/s (km/h, deg/s taken for m/s, rad/s) is refused naming the flag.
#[test]
fn another_robots_model_and_an_impossible_plan_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("robot.toml"), robot(Some("position"))).unwrap();
    straight_bag(&d.join("straight.bag"), |_, _, _, _| {});
    let model = |names: &[&str]| {
        let quoted: Vec<String> = names.iter().map(|n| format!("{n:?}")).collect();
        let m = "[[0.0125, 0.0125, 0.0125, 0.0125], [-0.0125, 0.0125, 0.0125, -0.0125], [-0.0337, 0.0337, -0.0337, 0.0337]]";
        format!(
            "format = \"omnical-model/1\"\nkinematics = \"ik\"\nwheel_names = [{}]\nmatrix = {m}\ndesign_matrix = {m}\n\n\
             [integration]\nstep = \"fixed\"\nscheme = \"exact_arc\"\n",
            quoted.join(", ")
        )
    };
    std::fs::write(d.join("other.toml"), model(&["fl", "fr", "rl", "rr"])).unwrap();
    let mut swapped = JOINTS;
    swapped.swap(0, 1);
    std::fs::write(d.join("swapped.toml"), model(&swapped)).unwrap();
    std::fs::write(d.join("same.toml"), model(&JOINTS)).unwrap();
    let err = refused(&["eval", "straight.bag", "--robot", "robot.toml", "--model", "other.toml"], d);
    assert_eq!(
        err.lines().last().unwrap(),
        "error: other.toml: the model's wheels are fl, fr, rl, rr, but robot.toml names the robot's wheel joints \
         front_left_wheel, front_right_wheel, rear_left_wheel, rear_right_wheel: a model of another robot; use the \
         model trained for this robot (or give --robot the description it was trained with)"
    );
    let err = refused(&["eval", "straight.bag", "--robot", "robot.toml", "--model", "swapped.toml"], d);
    assert!(err.contains(": the same wheels in another column order; use the model trained"), "{err}");
    let out = omnical(&["eval", "straight.bag", "--robot", "robot.toml", "--model", "same.toml"], d);
    assert!(out.status.success(), "{}", stderr(&out));

    let err = refused(&["plan", "--robot", "robot.toml", "--speed", "200"], d);
    assert_eq!(
        err.lines().last().unwrap(),
        "error: --speed 200 m/s: faster than the calibration runs of a wheeled robot are driven (at most 5 m/s; the \
         default is 0.2 m/s); give the runs' translation speed in m/s (not km/h or mm/s)"
    );
    let err = refused(&["plan", "--robot", "robot.toml", "--omega", "90"], d);
    assert!(err.contains("error: --omega 90 rad/s: 5157°/s, faster than the calibration runs"), "{err}");
}

/// `--max-file-mb` reaches every reader of a ROS 1 bag (`info` reviews it through the message feed, which
/// once read any size), and the lidar reader takes the cap it is given (`--gt-scans`).
#[test]
fn the_size_cap_reaches_every_reader() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    straight_bag(&d.join("rec.bag"), |_, _, _, _| {});
    let err = refused(&["info", "rec.bag", "--max-file-mb", "0"], d);
    assert!(err.contains("rec.bag: the file is "), "{err}");
    assert!(err.contains("raise the limit with --max-file-mb"), "{err}");
    let e = omni_cli::lidar::read_scans_within(&d.join("rec.bag"), "/scan", None, 1000).unwrap_err().to_string();
    let e = omni_cli::api::settings::as_flags(&e);
    assert!(e.contains("raise the limit with --max-file-mb"), "{e}");
    let e = omni_cli::lidar::read_scans_within(&d.join("rec.bag"), "/scan", None, 1 << 30).unwrap_err().to_string();
    assert!(e.contains("no topic \"/scan\" in the recording"), "{e}");
}
