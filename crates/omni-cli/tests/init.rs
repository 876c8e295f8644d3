//! `omnical init` through the real binary: a recording plus a URDF (file or `/robot_description` topic)
//! give a robot.toml whose design matrix matches the URDF's geometry; a URDF without wheel cylinders and
//! joints absent from the recording are refused with exit 2, naming the file.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use omni_cli::robot_file;
use omni_kin::IkMatrix;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use support::{apr02_wheel_urdf, omnical, stderr};

/// A three-wheel omni base like APR-02: wheels at 60°, 180°, 300°, 0.195 m out, r = 0.148 m
/// ([`apr02_wheel_urdf`]). Listed c, a, b: the recording's order must win.
fn omni3_urdf() -> String {
    format!(
        r#"<?xml version="1.0"?>
<robot name="omni3">
<link name="base_footprint"/>
<link name="base_link"><visual><geometry><box size="0.5 0.5 0.1"/></geometry></visual></link>
<joint name="base_joint" type="fixed"><parent link="base_footprint"/><child link="base_link"/>
  <origin xyz="0 0 0.148"/></joint>
{}{}{}</robot>
"#,
        apr02_wheel_urdf("wheel_c", 300.0),
        apr02_wheel_urdf("wheel_a", 60.0),
        apr02_wheel_urdf("wheel_b", 180.0)
    )
}

/// A TurtleBot-style differential drive: wheel frames rolled by −90° about x, turning about their z.
const DIFF_URDF: &str = r#"<?xml version="1.0"?>
<robot name="rover">
<link name="base_link"/>
<link name="left_wheel"><visual><origin rpy="1.5707963267948966 0 0"/><geometry><cylinder radius="0.033" length="0.018"/></geometry></visual></link>
<link name="right_wheel"><collision><origin rpy="1.5707963267948966 0 0"/><geometry><cylinder radius="0.034" length="0.018"/></geometry></collision></link>
<link name="caster"><visual><geometry><sphere radius="0.01"/></geometry></visual></link>
<joint name="wheel_left_joint" type="continuous"><parent link="base_link"/><child link="left_wheel"/>
  <origin xyz="0.0 0.144 0.023" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/></joint>
<joint name="wheel_right_joint" type="continuous"><parent link="base_link"/><child link="right_wheel"/>
  <origin xyz="0.0 -0.144 0.023" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/></joint>
<joint name="caster_joint" type="continuous"><parent link="base_link"/><child link="caster"/>
  <origin xyz="-0.08 0 -0.004"/><axis xyz="0 1 0"/></joint>
</robot>
"#;

#[derive(Serialize)]
struct Time {
    sec: i32,
    nanosec: u32,
}
#[derive(Serialize)]
struct Header {
    stamp: Time,
    frame_id: String,
}
#[derive(Serialize)]
struct JointState {
    header: Header,
    name: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}
#[derive(Serialize)]
struct RosString {
    data: String,
}

/// A small bag: `/robot_description` (once) and `/joint_states` at 50 Hz for 1 s with `joints`.
fn write_bag(path: &Path, urdf: Option<&str>, joints: &[&str]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::WriteOptions::new().profile("ros2").create(file).unwrap();
    let js = w.add_schema("sensor_msgs/msg/JointState", "ros2msg", b"").unwrap();
    let js = w.add_channel(js, "/joint_states", "cdr", &BTreeMap::new()).unwrap();
    let t0 = 1_700_000_000_000_000_000u64;
    if let Some(text) = urdf {
        let s = w.add_schema("std_msgs/msg/String", "ros2msg", b"string data\n").unwrap();
        let ch = w.add_channel(s, "/robot_description", "cdr", &BTreeMap::new()).unwrap();
        let bytes = cdr::serialize::<_, _, cdr::CdrLe>(&RosString { data: text.into() }, cdr::Infinite).unwrap();
        let header = mcap::records::MessageHeader { channel_id: ch, sequence: 0, log_time: t0, publish_time: t0 };
        w.write_to_known_channel(&header, &bytes).unwrap();
    }
    for k in 0..50u64 {
        let t = t0 + k * 20_000_000;
        let msg = JointState {
            header: Header {
                stamp: Time { sec: (t / 1_000_000_000) as i32, nanosec: (t % 1_000_000_000) as u32 },
                frame_id: String::new(),
            },
            name: joints.iter().map(|s| s.to_string()).collect(),
            position: vec![0.01 * k as f64; joints.len()],
            velocity: vec![0.5; joints.len()],
            effort: vec![],
        };
        let bytes = cdr::serialize::<_, _, cdr::CdrLe>(&msg, cdr::Infinite).unwrap();
        let header = mcap::records::MessageHeader { channel_id: js, sequence: k as u32, log_time: t, publish_time: t };
        w.write_to_known_channel(&header, &bytes).unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn omni3_urdf_gives_the_papers_design() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("omni3.urdf"), omni3_urdf()).unwrap();
    write_bag(&d.join("rec.mcap"), None, &["wheel_a", "wheel_b", "wheel_c"]);
    let out = omnical(&["init", "rec.mcap", "--urdf", "omni3.urdf"], d);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains(
            "/joint_states (sensor_msgs/msg/JointState): 50 messages, 50.0 Hz, joints wheel_a, wheel_b, wheel_c"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("kind omni: guessed from the 3 wheels"), "{stdout}");
    let text = std::fs::read_to_string(d.join("robot.toml")).unwrap();
    assert!(text.starts_with("# robot.toml drafted by `omnical init rec.mcap`"), "{text}");
    assert!(text.contains("# joint wheel_a: origin (0.0975, 0.168874954"), "{text}");
    let r = robot_file::read(&d.join("robot.toml")).unwrap();
    assert_eq!(r.joints(), ["wheel_a", "wheel_b", "wheel_c"], "the recording's order");
    assert_eq!(r.topics.joint_states.as_deref(), Some("/joint_states"));
    // Positions in base_link; the design matrix is the paper's Eq. 7 to the file's 1e-9 m.
    let ik = r.design_ik().unwrap();
    for (a, b) in ik.entries().iter().zip(IkMatrix::paper_design().entries()) {
        assert!((a - b).abs() < 1e-8, "{a} vs {b}\n{text}");
    }
    // base_link off base_footprint in the plane (10 cm forward, 2 cm left, turned 0.3 rad): the wheels are
    // still where they are on base_link, so the design is still Eq. 7, and the file says which frame.
    let urdf = std::fs::read_to_string(d.join("omni3.urdf")).unwrap();
    let shifted = urdf.replace(r#"<origin xyz="0 0 0.148"/>"#, r#"<origin xyz="0.1 0.02 0.148" rpy="0 0 0.3"/>"#);
    assert_ne!(shifted, urdf);
    std::fs::write(d.join("shifted.urdf"), shifted).unwrap();
    let out = omnical(&["init", "rec.mcap", "--urdf", "shifted.urdf", "--out", "shifted.toml"], d);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(d.join("shifted.toml")).unwrap();
    assert!(text.contains("positions and axles are in base_link (at (0.1, 0.02, 0.148) m in base_footprint"), "{text}");
    let ik = robot_file::read(&d.join("shifted.toml")).unwrap().design_ik().unwrap();
    for (a, b) in ik.entries().iter().zip(IkMatrix::paper_design().entries()) {
        assert!((a - b).abs() < 1e-8, "{a} vs {b}\n{text}");
    }
    // A second run does not overwrite without --force.
    let again = omnical(&["init", "rec.mcap", "--urdf", "omni3.urdf"], d);
    assert_eq!(again.status.code(), Some(2));
    assert!(stderr(&again).contains("robot.toml exists; pass --force"), "{}", stderr(&again));
    assert!(omnical(&["init", "rec.mcap", "--urdf", "omni3.urdf", "--force"], d).status.success());
}

#[test]
fn diff_drive_from_the_recordings_robot_description() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write_bag(&d.join("rec.mcap"), Some(DIFF_URDF), &["wheel_right_joint", "wheel_left_joint"]);
    let out = omnical(&["init", "rec.mcap", "--out", "rover.toml"], d);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("Read from the URDF (topic /robot_description of rec.mcap)"), "{stdout}");
    assert!(stdout.contains("kind diff: guessed from the 2 wheels"), "{stdout}");
    let r = robot_file::read(&d.join("rover.toml")).unwrap();
    let diff = r.diff.clone().unwrap();
    assert_eq!(diff.left_joint, "wheel_left_joint");
    assert_eq!(diff.wheel_separation_m, 0.288);
    assert_eq!((diff.left_radius_m, diff.right_radius_m), (0.033, 0.034));
    let ik = r.design_ik().unwrap();
    assert_eq!(ik.rows(), vec![vec![0.0165, 0.017], vec![0.0, 0.0], vec![-0.033 / 0.288, 0.034 / 0.288]]);
    // The caster (a sphere) is not a wheel, and the file says so.
    let text = std::fs::read_to_string(d.join("rover.toml")).unwrap();
    assert!(text.contains("Not wheels (no cylinder on the child link): caster_joint."), "{text}");
}

#[test]
fn refusals_name_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write_bag(&d.join("rec.mcap"), None, &["wheel_a", "wheel_b", "wheel_c"]);
    // Mesh wheels: no cylinder gives the radius.
    std::fs::write(
        d.join("mesh.urdf"),
        omni3_urdf().replace(r#"<cylinder radius="0.148" length="0.04"/>"#, r#"<mesh filename="wheel.stl"/>"#),
    )
    .unwrap();
    let out = omnical(&["init", "rec.mcap", "--urdf", "mesh.urdf"], d);
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(e.starts_with("error: mesh.urdf: no wheel found: the continuous joints wheel_c, wheel_a, wheel_b have child links without a cylinder"), "{e}");
    assert!(!d.join("robot.toml").exists());
    // No URDF anywhere.
    let out = omnical(&["init", "rec.mcap"], d);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).starts_with("error: rec.mcap: the recording has no /robot_description topic"),
        "{}",
        stderr(&out)
    );
    // The URDF's wheels are not the recording's joints.
    write_bag(&d.join("other.mcap"), None, &["m1", "m2", "m3"]);
    std::fs::write(d.join("omni3.urdf"), omni3_urdf()).unwrap();
    let out = omnical(&["init", "other.mcap", "--urdf", "omni3.urdf"], d);
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(e.contains("omni3.urdf: its wheel joints (wheel_c, wheel_a, wheel_b) are not in the recording's JointState topics (joints there: m1, m2, m3)"), "{e}");
    // Not XML.
    std::fs::write(d.join("bad.urdf"), "robot { wheels: 3 }").unwrap();
    let out = omnical(&["init", "rec.mcap", "--urdf", "bad.urdf"], d);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).starts_with("error: bad.urdf: not a URDF"), "{}", stderr(&out));
}

/// A differential drive with a passive caster wheel (a cylinder on a continuous joint below a vertical
/// swivel, named neither caster nor wheel), whose joints the recording publishes too: the caster is not
/// driven, so the base is the two wheels.
#[test]
fn a_passive_caster_wheel_is_not_taken_as_driven() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let urdf = DIFF_URDF.replace(
        "</robot>",
        r#"<link name="fork"/>
<link name="roller"><collision><origin rpy="1.5707963267948966 0 0"/><geometry><cylinder radius="0.02" length="0.01"/></geometry></collision></link>
<joint name="swivel_joint" type="continuous"><parent link="base_link"/><child link="fork"/>
  <origin xyz="-0.1 0 0.0"/><axis xyz="0 0 1"/></joint>
<joint name="roller_joint" type="continuous"><parent link="fork"/><child link="roller"/>
  <origin xyz="-0.02 0 -0.01" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/></joint>
</robot>"#,
    );
    write_bag(
        &d.join("rec.mcap"),
        Some(&urdf),
        &["wheel_right_joint", "wheel_left_joint", "swivel_joint", "roller_joint"],
    );
    let out = omnical(&["init", "rec.mcap", "--out", "rover.toml"], d);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("kind diff: guessed from the 2 wheels"), "{stdout}");
    assert!(
        stdout.contains("Not driven (passive casters: below a swivel joint, or named caster): roller_joint."),
        "{stdout}"
    );
    let r = robot_file::read(&d.join("rover.toml")).unwrap();
    assert_eq!(r.joints(), ["wheel_left_joint", "wheel_right_joint"]);
}
