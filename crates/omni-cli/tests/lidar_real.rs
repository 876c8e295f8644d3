//! The lidar reference (`--gt-scans`) on recordings shaped as real robots write them, through the real
//! binary: a 270° lidar at 40 Hz (a Hokuyo's field of view, `--lidar-fov 270`), its mount not on
//! `/tf_static` but republished on `/tf` with every message as ROS 1's static_transform_publisher and
//! robot_state_publisher do, ROS 1 frame names with a leading `/`, the laser hanging from `base_footprint`
//! (beside a `base_footprint → base_link` pair and the moving `odom → base_footprint`), and the scans' ranges
//! of 0 where a driver means "no return". The wheels and the mount come out as from motion capture.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;
use support::{ok_with_stderr, param_se as param, succeeded, test_data};

/// `omnical ARGS --json` in `dir`, which must succeed: the document, and stderr.
fn json(args: &[&str], dir: &Path) -> (Value, String) {
    let (stdout, stderr) = ok_with_stderr(&[args, &["--json"]].concat(), dir);
    (serde_json::from_str(&stdout).unwrap(), stderr)
}

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Serialize, Deserialize)]
struct Time {
    sec: i32,
    nanosec: u32,
}

/// `std_msgs/msg/Header`.
#[derive(Serialize, Deserialize)]
struct Header {
    stamp: Time,
    frame_id: String,
}

/// `sensor_msgs/msg/LaserScan`.
#[derive(Serialize, Deserialize)]
struct LaserScan {
    header: Header,
    angles_times_ranges: [f32; 7],
    ranges: Vec<f32>,
    intensities: Vec<f32>,
}

/// `geometry_msgs/msg/TransformStamped`, planar: translation x, y, z and rotation x, y, z, w.
#[derive(Serialize)]
struct TransformStamped {
    header: Header,
    child_frame_id: String,
    transform: [f64; 7],
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Serialize)]
struct TfMessage {
    transforms: Vec<TransformStamped>,
}

fn cdr_bytes<T: Serialize>(m: &T) -> Vec<u8> {
    cdr::serialize::<_, _, cdr::CdrLe>(m, cdr::Infinite).unwrap()
}

/// `/tf` at `stamp` as a ROS 1 robot publishes it: the moving `odom → base_footprint` (driving along x at
/// 0.1 m/s from `t_s`), the fixed `base_footprint → base_link` (0.1 m up, planar identity) and the
/// fixed `base_footprint → laser` (0.2 m, 0, 5°), frames with a leading `/`.
fn ros1_tf(stamp: Time, t_s: f64) -> Vec<u8> {
    let planar = |x: f64, y: f64, z: f64, yaw_deg: f64| {
        let (s, c) = (0.5 * yaw_deg.to_radians()).sin_cos();
        [x, y, z, 0.0, 0.0, s, c]
    };
    let pair = |parent: &str, child: &str, transform: [f64; 7]| TransformStamped {
        header: Header { stamp, frame_id: parent.into() },
        child_frame_id: child.into(),
        transform,
    };
    cdr_bytes(&TfMessage {
        transforms: vec![
            pair("/odom", "/base_footprint", planar(0.1 * t_s, 0.0, 0.0, 2.0 * t_s)),
            pair("/base_footprint", "/base_link", planar(0.0, 0.0, 0.1, 0.0)),
            pair("/base_footprint", "/laser", planar(0.2, 0.0, 0.3, 5.0)),
        ],
    })
}

/// A scan rewritten as a ROS 1 driver leaves it: frame `/laser`, `range_min` 0, and the beams that saw
/// nothing (+inf, NaN) as 0.
fn ros1_scan(data: &[u8]) -> Vec<u8> {
    let mut m: LaserScan = cdr::deserialize_from(data, cdr::Infinite).unwrap();
    m.header.frame_id = "/laser".into();
    m.angles_times_ranges[5] = 0.0;
    for r in &mut m.ranges {
        if !r.is_finite() {
            *r = 0.0;
        }
    }
    cdr_bytes(&m)
}

/// Writes one message on channel `id`.
fn write<W: std::io::Write + std::io::Seek>(out: &mut mcap::Writer<W>, id: u16, log_time: u64, data: &[u8]) {
    let header = mcap::records::MessageHeader { channel_id: id, sequence: 0, log_time, publish_time: log_time };
    out.write_to_known_channel(&header, data).unwrap();
}

/// Rewrites a simulated bag as a ROS 1 robot records it: no `/tf_static`; `/tf` at 20 Hz ([`ros1_tf`]);
/// the scans as [`ros1_scan`].
fn as_ros1(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    let mut out = mcap::WriteOptions::new().profile("ros2").create(std::io::Cursor::new(Vec::new())).unwrap();
    let mut ids = BTreeMap::new();
    let mut tf_schema = None;
    let (mut first_ns, mut last_ns) = (u64::MAX, 0);
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m.channel.schema.as_ref().unwrap();
        if m.channel.topic == "/tf_static" {
            tf_schema = Some((schema.name.clone(), schema.data.clone()));
            continue;
        }
        let id = *ids.entry(m.channel.topic.clone()).or_insert_with(|| {
            let s = out.add_schema(&schema.name, &schema.encoding, &schema.data).unwrap();
            out.add_channel(s, &m.channel.topic, "cdr", &BTreeMap::new()).unwrap()
        });
        let data: Cow<[u8]> = if m.channel.topic == "/scan" { ros1_scan(&m.data).into() } else { m.data };
        (first_ns, last_ns) = (first_ns.min(m.log_time), last_ns.max(m.log_time));
        write(&mut out, id, m.log_time, &data);
    }
    let (name, text) = tf_schema.expect("the simulated bag has /tf_static");
    let s = out.add_schema(&name, "ros2msg", &text).unwrap();
    let tf = out.add_channel(s, "/tf", "cdr", &BTreeMap::new()).unwrap();
    for ns in (first_ns..=last_ns).step_by(50_000_000) {
        let stamp = Time { sec: (ns / 1_000_000_000) as i32, nanosec: (ns % 1_000_000_000) as u32 };
        write(&mut out, tf, ns, &ros1_tf(stamp, (ns - first_ns) as f64 * 1e-9));
    }
    out.finish().unwrap();
    std::fs::write(path, out.into_inner().into_inner()).unwrap();
}

/// A 270° lidar of 1081 beams at 40 Hz: a Hokuyo UTM-30LX's scans (0.25° apart). Matching them all takes
/// about 3 s here in release, so the test keeps the real count.
const BEAMS: &str = "1081";

/// The diff drive (left wheel 2 % large) with the 270° lidar at 0.2 m, 0, 5°, its bags rewritten as a ROS 1
/// robot records them: the motion-capture fit and the lidar's on the same runs agree, and the mount comes
/// through `/tf` under `base_footprint` (the fit's correction of it stays within 1 cm and 0.5°; had the mount
/// been missed, it would be the whole 0.2 m and 5°).
#[test]
fn a_270_degree_lidar_mounted_on_tf_under_base_footprint_calibrates_as_motion_capture_does() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let robot = test_data("diff_robot.toml");
    let args = [
        "simulate",
        "--robot",
        robot.to_str().unwrap(),
        "--out",
        "sim",
        "--lidar",
        "room",
        "--lidar-mount",
        "0.2,0,5",
        "--lidar-fov",
        "270",
        "--lidar-rate",
        "40",
        "--lidar-beams",
        BEAMS,
        "--effect",
        "wheel_radius:a=0.02",
        "--runs-per-command",
        "2",
        "--duration",
        "6",
        "-q",
    ];
    succeeded(&args, d);
    let mut bags = 0;
    for e in std::fs::read_dir(d.join("sim/train")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "mcap") {
            as_ros1(&p);
            bags += 1;
        }
    }
    assert!(bags >= 12, "{bags} bags");
    let (mocap, _) = json(&["train", "sim/train"], d);
    let (lidar, stderr) = json(&["train", "sim/train", "--gt-scans", "/scan"], d);
    let said = "its path moved to the base by the static transforms base_footprint → laser (x 0.200 m, y 0.000 m, \
                yaw 5.00°)";
    assert!(stderr.contains(said), "{stderr}");
    support::assert_wheels_as_motion_capture(&lidar, &mocap, "lidar");
    // The fit's correction of the mount read from /tf.
    let (dx, _) = param(&lidar, "sensor_offset_yaw.dx_m");
    let (dy, _) = param(&lidar, "sensor_offset_yaw.dy_m");
    let (dyaw, dyaw_se) = param(&lidar, "sensor_offset_yaw.dyaw_rad");
    eprintln!("mount correction: {dx:.5} m, {dy:.5} m, {:.4}° ± {:.4}°", dyaw.to_degrees(), dyaw_se.to_degrees());
    assert!(dx.abs() < 0.01 && dy.abs() < 0.01, "mount correction {dx} m, {dy} m");
    assert!(dyaw.to_degrees().abs() < 0.5, "mount yaw correction {}°", dyaw.to_degrees());
}
