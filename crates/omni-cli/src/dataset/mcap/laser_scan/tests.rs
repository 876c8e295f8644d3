//! The LaserScan reader's unit tests: decoding, bad messages, and the static transforms that place the lidar
//! as real recordings hold them.

use super::super::common::{Time, decode, encode};
use super::*;

/// A scan of frame `laser` stamped `stamp`: `ranges` from −3 rad every `angle_increment` rad, 0.05 to 12 m.
fn message(stamp: Time, angle_increment: f32, ranges: Vec<f32>) -> LaserScan {
    LaserScan {
        header: Header { stamp, frame_id: RosString("laser".into()) },
        angle_min: -3.0,
        angle_max: 3.0,
        angle_increment,
        time_increment: 0.0,
        scan_time: 0.1,
        range_min: 0.05,
        range_max: 12.0,
        ranges,
        intensities: vec![],
    }
}

#[test]
fn laser_scan_round_trips_with_inf_and_nan() {
    let m = message(Time { sec: 5, nanosec: 7 }, 0.0087, vec![1.5, f32::INFINITY, f32::NAN]);
    let back: LaserScan = decode(&encode(&m).unwrap()).unwrap();
    assert_eq!(back.header, m.header);
    assert_eq!(back.ranges[..2], m.ranges[..2]);
    assert!(back.ranges[2].is_nan());
    assert_eq!((back.angle_increment, back.range_max), (0.0087, 12.0));
}

/// A lidar whose /tf_static turns it upside down (roll π, yaw 90°) is read mirrored: the beams sweep
/// clockwise seen from above, and its mount keeps the yaw of its x axis.
#[test]
fn an_upside_down_lidar_is_read_mirrored() {
    let scan = message(Time { sec: 1, nanosec: 0 }, 0.5, vec![1.0; 13]);
    let read = |roll_pi: bool| {
        let mut tf = static_transform(Header::default(), "laser", &Pose2::new(0.1, 0.0, std::f64::consts::FRAC_PI_2));
        if roll_pi {
            // Rz(90°)·Rx(180°): the rotation by π about the axis (cos 45°, sin 45°, 0).
            let h = std::f64::consts::FRAC_1_SQRT_2;
            tf.transforms[0].transform.rotation = super::super::common::Quaternion { x: h, y: h, z: 0.0, w: 0.0 };
        }
        tf.transforms[0].header.frame_id = RosString("base_link".into());
        let mut sink = ScanSink::new("/scan", false);
        let t = sink.channel("/tf_static", tf::NAME, "ros2msg", "cdr");
        let i = sink.channel("/scan", NAME, "ros2msg", "cdr");
        sink.message(t, &encode(&tf).unwrap(), 0);
        sink.message(i, &encode(&scan).unwrap(), 0);
        sink.finish(Path::new("rec.mcap")).unwrap()
    };
    let upright = read(false);
    assert!(!upright.mirrored && upright.scans[0].angle_min_rad == -3.0);
    let flipped = read(true);
    assert!(flipped.mirrored);
    assert_eq!((flipped.scans[0].angle_min_rad, flipped.scans[0].angle_increment_rad), (3.0, -0.5));
    let m = flipped.base_from_sensor.unwrap();
    assert!((m.x_m - 0.1).abs() < 1e-12 && (m.theta_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12, "{m:?}");
}

#[test]
fn a_bad_scan_names_the_message_and_the_field() {
    let path = Path::new("rec.mcap");
    let scan = |sec: i32, inc: f32| message(Time { sec, nanosec: 0 }, inc, vec![1.0; 4]);
    let run = |msgs: &[LaserScan]| {
        let mut sink = ScanSink::new("/scan", false);
        let i = sink.channel("/scan", NAME, "ros2msg", "cdr");
        for m in msgs {
            sink.message(i, &encode(m).unwrap(), 0);
        }
        sink.finish(path)
    };
    let err = run(&[scan(1, 0.1), scan(2, 0.0)]).unwrap_err().to_string();
    assert_eq!(err, "rec.mcap: topic \"/scan\", message 1: field angle_increment is 0: the beams have no directions");
    let err = run(&[scan(1, 0.1), scan(2, f32::NAN)]).unwrap_err().to_string();
    assert_eq!(err, "rec.mcap: topic \"/scan\", message 1: field angle_increment is NaN");
    let err = run(&[scan(2, 0.1), scan(1, 0.1)]).unwrap_err().to_string();
    assert_eq!(
        err,
        "rec.mcap: topic \"/scan\", message 1: field header.stamp 1.000000000 is not after the previous scan's \
         2.000000000 (message 0): a scan topic's stamps must increase; record the lidar driver's topic as it \
         publishes it (one driver, its own clock)"
    );
    assert_eq!(
        run(&[]).unwrap_err().to_string(),
        "rec.mcap: topic \"/scan\": holds no scans: record the lidar while the robot moves"
    );
    let mut ok = run(&[scan(2, 0.1), scan(3, 0.1)]).unwrap();
    assert_eq!((ok.origin_s, ok.scans[1].t_s, ok.base_from_sensor), (2, 1.0, None));
    ok.rebase(-1);
    assert_eq!((ok.origin_s, ok.scans[0].t_s, ok.scans[1].t_s), (-1, 3.0, 4.0));
}

/// One TF message: each `(parent, child, x, y, yaw_deg)` a transform stamped `sec`.
fn tf_message(sec: i32, pairs: &[(&str, &str, f64, f64, f64)]) -> TfMessage {
    let transforms = pairs
        .iter()
        .flat_map(|&(parent, child, x, y, yaw_deg)| {
            let header = Header { stamp: Time { sec, nanosec: 0 }, frame_id: RosString(parent.into()) };
            static_transform(header, child, &Pose2::new(x, y, yaw_deg.to_radians())).transforms
        })
        .collect();
    TfMessage { transforms }
}

/// The scans of frame `frame` read beside `tf` (one message per second on `topic`), the mount looked up
/// from `base` (default: base_link, else base_footprint).
fn read_with_tf(frame: &str, topic: &str, tf: &[TfMessage], base: Option<&str>) -> ScanRead {
    let mut sink = ScanSink::new("/scan", false).with_base_frame(base);
    let t = sink.channel(topic, tf::NAME, "ros2msg", "cdr");
    let i = sink.channel("/scan", NAME, "ros2msg", "cdr");
    for (k, m) in tf.iter().enumerate() {
        sink.message(t, &encode(m).unwrap(), 0);
        let mut scan = message(Time { sec: k as i32 + 1, nanosec: 0 }, 0.5, vec![1.0; 13]);
        scan.header.frame_id = RosString(frame.into());
        sink.message(i, &encode(&scan).unwrap(), 0);
    }
    sink.finish(Path::new("rec.bag")).unwrap()
}

/// A ROS 1 bag's `/tf` as robot_state_publisher (Indigo) and tf's static_transform_publisher leave it:
/// frames with a leading `/`, the fixed joints republished with every message beside the moving odom pair.
/// The fixed pairs are the mount (the chain from base_link; from base_footprint when the laser hangs there),
/// the moving one never is, nor a pair whose value changes once by a micrometre.
#[test]
fn fixed_pairs_republished_on_tf_place_the_lidar_and_moving_ones_do_not() {
    let ros1 = |k: i32, laser_parent: &str, jitter_m: f64| {
        tf_message(
            k,
            &[
                ("/odom", "/base_footprint", 0.1 * f64::from(k), 0.0, 3.0 * f64::from(k)),
                ("/base_footprint", "/base_link", 0.0, 0.0, 0.0),
                (laser_parent, "/laser", 0.2 + if k == 3 { jitter_m } else { 0.0 }, 0.01, 5.0),
            ],
        )
    };
    let tf: Vec<TfMessage> = (1..=5).map(|k| ros1(k, "/base_link", 0.0)).collect();
    let read = read_with_tf("/laser", "/tf", &tf, None);
    assert_eq!((read.frame_id.as_str(), read.chain_text().as_str()), ("laser", "base_link → laser"));
    let m = read.base_from_sensor.unwrap();
    assert!((m.x_m - 0.2).abs() < 1e-12 && (m.y_m - 0.01).abs() < 1e-12, "{m:?}");
    assert!((m.theta_rad.to_degrees() - 5.0).abs() < 1e-9, "{m:?}");
    // The laser straight under base_footprint (no base_link above it).
    let tf: Vec<TfMessage> = (1..=5).map(|k| ros1(k, "/base_footprint", 0.0)).collect();
    let read = read_with_tf("laser", "/tf", &tf, None);
    assert_eq!(read.chain_text(), "base_footprint → laser");
    // A robot description naming the base: odom moves, so nothing hangs from it by fixed transforms.
    assert_eq!(read_with_tf("laser", "/tf", &tf, Some("/odom")).base_from_sensor, None);
    assert_eq!(read_with_tf("laser", "/tf", &tf, Some("/base_footprint")).chain_text(), "base_footprint → laser");
    // One message a micrometre off: the pair moves, it is no mount.
    let tf: Vec<TfMessage> = (1..=5).map(|k| ros1(k, "/base_link", 1e-6)).collect();
    let read = read_with_tf("laser", "/tf", &tf, None);
    assert_eq!((read.base_from_sensor, read.chain.len()), (None, 0));
    // On /tf_static every pair is static (the first value), the moving one too, as latched topics hold it.
    let read = read_with_tf("laser", "/tf_static", &tf[..1], Some("odom"));
    assert_eq!(read.chain_text(), "odom → base_footprint → base_link → laser");
}

/// TurtleBot's tree, base_footprint → base_link → base_scan on /tf_static: the mount is the chain from
/// base_link (the first base frame found); the empty frame_id of a driver that leaves it so is no mount.
#[test]
fn the_mount_is_read_through_the_chain_and_an_empty_frame_id_has_none() {
    let tf = [tf_message(
        0,
        &[("base_footprint", "base_link", 0.0, 0.0, 0.0), ("base_link", "base_scan", -0.064, 0.0, 180.0)],
    )];
    let read = read_with_tf("base_scan", "/tf_static", &tf, None);
    assert_eq!(read.chain_text(), "base_link → base_scan");
    assert!((read.base_from_sensor.unwrap().x_m + 0.064).abs() < 1e-12);
    let tf = [tf_message(0, &[("base_link", "", 0.1, 0.0, 0.0)])];
    let read = read_with_tf("", "/tf_static", &tf, None);
    assert_eq!((read.frame_id.as_str(), read.base_from_sensor), ("", None));
}

/// Stamps a driver never filled (0 on the first two scans) time the scans by their log time, and say so.
#[test]
fn scans_stamped_0_are_timed_by_their_log_time() {
    let mut sink = ScanSink::new("/scan", false);
    let i = sink.channel("/scan", NAME, "ros2msg", "cdr");
    for k in 0..3u64 {
        let scan = message(Time { sec: 0, nanosec: 0 }, 0.5, vec![1.0; 13]);
        sink.message(i, &encode(&scan).unwrap(), 1_700_000_000_000_000_000 + k * 25_000_000);
    }
    let read = sink.finish(Path::new("rec.mcap")).unwrap();
    assert!(read.by_log_time);
    assert_eq!(read.origin_s, 1_700_000_000);
    let t: Vec<f64> = read.scans.iter().map(|s| s.t_s).collect();
    assert!((t[1] - 0.025).abs() < 1e-12 && (t[2] - 0.05).abs() < 1e-12, "{t:?}");
}

/// A scan whose angle_max is not where its beams end (13 beams of 0.25 rad from −3 rad end at 0 rad, not at
/// the 3 rad it says) is read by angle_min and angle_increment, and the read says so; a driver's
/// angle_max one increment past the last beam is no disagreement.
#[test]
fn an_angle_max_that_disagrees_with_the_beams_is_named_and_not_used() {
    let read = |inc: f32, beams: usize| {
        let mut sink = ScanSink::new("/scan", false);
        let i = sink.channel("/scan", NAME, "ros2msg", "cdr");
        for sec in 1..=3 {
            sink.message(i, &encode(&message(Time { sec, nanosec: 0 }, inc, vec![1.0; beams])).unwrap(), 0);
        }
        sink.finish(Path::new("rec.mcap")).unwrap()
    };
    let off = read(0.25, 13);
    assert_eq!((off.scans[0].angle_min_rad, off.scans[0].angle_increment_rad), (-3.0, 0.25));
    let m = off.angle_max_mismatch.unwrap();
    assert_eq!(
        m.describe("/scan"),
        "lidar \"/scan\": 3 scans have an angle_max (171.89°) that disagrees with their 13 beams, which end at \
         0.00° (angle_min + (n − 1)·angle_increment): the beams' directions are taken from angle_min and \
         angle_increment, as ROS's laser_geometry takes them; angle_max is not used"
    );
    assert_eq!(read(0.5, 13).angle_max_mismatch, None);
    assert_eq!(read(0.5, 12).angle_max_mismatch, None, "angle_max one increment past the last beam");
}
