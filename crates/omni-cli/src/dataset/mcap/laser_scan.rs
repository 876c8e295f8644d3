//! `sensor_msgs/msg/LaserScan`: a planar lidar's ranges (REP-117: +inf nothing in range, NaN an erroneous
//! reading), read into [`omni_kin::lidar::Scan`]s and written by the simulator; and the `/tf_static`
//! message that places the lidar on the robot.

use super::common::{
    HEADER_DEF, Header, MsgDef, NS_PER_S, QUATERNION_DEF, RosString, TIME_DEF, VECTOR3_DEF, decode, schema_text,
    seconds_since,
};
use super::recording::{MessageSink, payload};
use super::statics::StaticTree;
use super::tf::{self, TfMessage, Transform, TransformStamped};
use crate::dataset::DatasetError;
use omni_kin::Pose2;
use omni_kin::lidar::Scan;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The schema name.
pub(super) const NAME: &str = "sensor_msgs/msg/LaserScan";

/// `sensor_msgs/msg/LaserScan`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct LaserScan {
    pub header: Header,
    /// rad.
    pub angle_min: f32,
    /// rad.
    pub angle_max: f32,
    /// rad.
    pub angle_increment: f32,
    /// Time between beams. s.
    pub time_increment: f32,
    /// Time between scans. s.
    pub scan_time: f32,
    /// m.
    pub range_min: f32,
    /// m.
    pub range_max: f32,
    /// m.
    pub ranges: Vec<f32>,
    pub intensities: Vec<f32>,
}

/// The schema text, as rosbag2 writes it.
pub(super) fn schema() -> String {
    schema_text(
        "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n\
         float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\nfloat32[] ranges\n\
         float32[] intensities\n",
        &[&HEADER_DEF, &TIME_DEF],
    )
}

/// The `tf2_msgs/msg/TFMessage` schema text, as rosbag2 writes it.
pub(super) fn tf_schema() -> String {
    const TRANSFORM_STAMPED: MsgDef = MsgDef {
        name: "geometry_msgs/TransformStamped",
        text: "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
    };
    const TRANSFORM: MsgDef = MsgDef {
        name: "geometry_msgs/Transform",
        text: "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
    };
    schema_text(
        "geometry_msgs/TransformStamped[] transforms\n",
        &[&TRANSFORM_STAMPED, &HEADER_DEF, &TIME_DEF, &TRANSFORM, &VECTOR3_DEF, &QUATERNION_DEF],
    )
}

/// One static transform: `child` at `pose` in `parent`, stamped `header.stamp`.
pub(super) fn static_transform(header: Header, child: &str, pose: &omni_kin::Pose2) -> TfMessage {
    let p = super::common::Pose::planar(pose.x_m, pose.y_m, pose.theta_rad);
    TfMessage {
        transforms: vec![TransformStamped {
            header,
            child_frame_id: RosString(child.to_string()),
            transform: Transform { translation: p.position, rotation: p.orientation },
        }],
    }
}

/// The base frame the lidar's mount is looked up from in `/tf_static`.
const BASE_FRAME: &str = "base_link";

/// A lidar's scans read from a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanRead {
    /// The scans in time order; their `t_s` are seconds since [`Self::origin_s`].
    pub scans: Vec<Scan>,
    /// The whole second (`header.stamp.sec`) of the first scan. s since the epoch (or sim-time start).
    pub origin_s: i64,
    /// The scans' `header.frame_id` (of the first scan).
    pub frame_id: String,
    /// The lidar's pose in `base_link` from the recording's static transforms, when they hold it (m, rad).
    pub base_from_sensor: Option<Pose2>,
    /// The static transforms mount the lidar upside down: the scans' beam angles were mirrored (negated), so
    /// that they sweep counter-clockwise seen from above as the base's frame does.
    pub mirrored: bool,
}

impl ScanRead {
    /// Puts the scans' times on another time base: seconds since `origin_s` (e.g. the runs'
    /// [`super::McapRead::origin_s`], so scans and wheel samples share one clock). Exact: only whole seconds
    /// move.
    pub fn rebase(&mut self, origin_s: i64) {
        let shift_s = (self.origin_s - origin_s) as f64;
        for s in &mut self.scans {
            s.t_s += shift_s;
        }
        self.origin_s = origin_s;
    }
}

/// One topic as the storage declares it.
struct Declared {
    topic: String,
    schema: String,
    /// The encodings are ROS 2's (`ros2msg`/`ros2idl` schemas, `cdr` messages).
    cdr: bool,
    messages: usize,
}

/// Gathers the LaserScan messages of one topic (and the static transforms) from any storage reader.
pub(crate) struct ScanSink {
    topic: String,
    zstd_messages: bool,
    channels: Vec<Declared>,
    /// Stamp (ns) and scan (its `t_s` not yet set).
    scans: Vec<(i64, Scan)>,
    frame_id: Option<String>,
    statics: StaticTree,
    /// The first problem on the topic: message index and what.
    problem: Option<(usize, String)>,
}

impl ScanSink {
    /// A sink for the LaserScan messages on `topic`; `zstd_messages`: each payload is zstd-compressed.
    pub(crate) fn new(topic: &str, zstd_messages: bool) -> Self {
        Self {
            topic: topic.to_string(),
            zstd_messages,
            channels: Vec::new(),
            scans: Vec::new(),
            frame_id: None,
            statics: StaticTree::default(),
            problem: None,
        }
    }

    /// Takes the next message of the scan topic (index `k` within it).
    fn take_scan(&mut self, k: usize, data: &[u8]) -> Result<(), String> {
        let m: LaserScan = decode(data)?;
        for (field, v) in [
            ("angle_min", m.angle_min),
            ("angle_increment", m.angle_increment),
            ("range_min", m.range_min),
            ("range_max", m.range_max),
        ] {
            if !v.is_finite() {
                return Err(format!("field {field} is {v}"));
            }
        }
        if m.angle_increment == 0.0 {
            return Err("field angle_increment is 0: the beams have no directions".into());
        }
        if !(m.range_min >= 0.0 && m.range_max > m.range_min) {
            return Err(format!("fields range_min {} and range_max {} do not make a range", m.range_min, m.range_max));
        }
        let ns = m.header.stamp.ns();
        if let Some(&(prev, _)) = self.scans.last()
            && ns <= prev
        {
            let stamp = super::common::Stamp;
            return Err(format!(
                "field header.stamp {} is not after the previous scan's {} (message {})",
                stamp(ns),
                stamp(prev),
                k - 1
            ));
        }
        self.frame_id.get_or_insert_with(|| m.header.frame_id.frame().to_string());
        // The time between beams; a value that is not finite says nothing (beams taken at once).
        let time_increment_s = Some(f64::from(m.time_increment)).filter(|t| t.is_finite()).unwrap_or(0.0);
        let scan = Scan {
            t_s: 0.0,
            time_increment_s,
            angle_min_rad: f64::from(m.angle_min),
            angle_increment_rad: f64::from(m.angle_increment),
            range_min_m: f64::from(m.range_min),
            range_max_m: f64::from(m.range_max),
            ranges_m: m.ranges,
        };
        self.scans.push((ns, scan));
        Ok(())
    }

    /// The scans read, or the error naming the file `path`, the topic, the message and the field.
    pub(crate) fn finish(self, path: &Path) -> Result<ScanRead, DatasetError> {
        let here = format!("topic {:?}", self.topic);
        let Some(c) = self.channels.iter().find(|c| c.topic == self.topic) else {
            let mut list: Vec<String> = self.channels.iter().map(|c| format!("{} ({})", c.topic, c.schema)).collect();
            list.sort();
            let scans: Vec<&str> =
                self.channels.iter().filter(|c| c.schema == NAME).map(|c| c.topic.as_str()).collect();
            let hint = if scans.is_empty() {
                "no topic holds sensor_msgs/msg/LaserScan: record the lidar's scans".to_string()
            } else {
                format!(
                    "the LaserScan topics are {}: name one (--gt-scans TOPIC, scan-odometry --topic TOPIC)",
                    scans.join(", ")
                )
            };
            return Err(DatasetError::file(
                path,
                format!("no topic {:?} in the recording (its topics: {}); {hint}", self.topic, list.join(", ")),
            ));
        };
        if c.schema != NAME {
            return Err(DatasetError::at(path, here, format!("is a {}, not a {NAME}", c.schema)));
        }
        if !c.cdr {
            return Err(DatasetError::at(path, here, "its encoding is not ROS 2's (ros2msg schema, cdr messages)"));
        }
        if let Some((k, what)) = self.problem {
            return Err(DatasetError::at(path, format!("{here}, message {k}"), what));
        }
        let Some(&(first_ns, _)) = self.scans.first() else {
            return Err(DatasetError::at(path, here, "holds no scans: record the lidar while the robot moves"));
        };
        let origin_s = first_ns.div_euclid(NS_PER_S);
        let frame_id = self.frame_id.unwrap_or_default();
        let base_from_sensor = self.statics.offset(BASE_FRAME, &frame_id).map(|(p, _)| p);
        // A lidar mounted upside down sweeps clockwise seen from above: its beams' angles are mirrored.
        let mirrored = self.statics.mirrored(BASE_FRAME, &frame_id) == Some(true);
        let scans = self
            .scans
            .into_iter()
            .map(|(ns, s)| {
                let t_s = seconds_since(ns, origin_s);
                match mirrored {
                    true => {
                        Scan { t_s, angle_min_rad: -s.angle_min_rad, angle_increment_rad: -s.angle_increment_rad, ..s }
                    }
                    false => Scan { t_s, ..s },
                }
            })
            .collect();
        Ok(ScanRead { scans, origin_s, frame_id, base_from_sensor, mirrored })
    }
}

impl MessageSink for ScanSink {
    fn channel(&mut self, topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> usize {
        if let Some(i) = self.channels.iter().position(|c| c.topic == topic) {
            return i;
        }
        let cdr = matches!(schema_encoding, "ros2msg" | "ros2idl") && message_encoding == "cdr";
        self.channels.push(Declared { topic: topic.into(), schema: schema.into(), cdr, messages: 0 });
        self.channels.len() - 1
    }

    fn message(&mut self, i: usize, data: &[u8], _log_time_ns: u64) {
        let c = &mut self.channels[i];
        let k = c.messages;
        c.messages += 1;
        let is_scan = c.topic == self.topic && c.schema == NAME && c.cdr;
        let is_static = tf::is_static_topic(&c.topic) && c.schema == tf::NAME && c.cdr;
        if !(is_scan && self.problem.is_none() || is_static) {
            return;
        }
        let data = match payload(self.zstd_messages, data) {
            Ok(plain) => plain,
            Err(e) if is_scan => {
                self.problem = Some((k, e));
                return;
            }
            Err(_) => return,
        };
        if is_scan {
            if let Err(e) = self.take_scan(k, &data) {
                self.problem = Some((k, e));
            }
        } else if let Ok(m) = decode::<TfMessage>(&data) {
            for t in &m.transforms {
                let (p, q) = (&t.transform.translation, &t.transform.rotation);
                if p.x.is_finite() && p.y.is_finite() && q.yaw_rad().is_finite() {
                    let pose = Pose2::new(p.x, p.y, q.yaw_rad());
                    self.statics.add(t.header.frame_id.frame(), t.child_frame_id.frame(), pose);
                    // The child's z axis in the parent: R₂₂ = w² − x² − y² + z² (over the norm).
                    if q.w * q.w - q.x * q.x - q.y * q.y + q.z * q.z < 0.0 {
                        self.statics.mark_flipped(t.child_frame_id.frame());
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
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
            let mut tf =
                static_transform(Header::default(), "laser", &Pose2::new(0.1, 0.0, std::f64::consts::FRAC_PI_2));
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
        assert_eq!(
            err,
            "rec.mcap: topic \"/scan\", message 1: field angle_increment is 0: the beams have no directions"
        );
        let err = run(&[scan(1, 0.1), scan(2, f32::NAN)]).unwrap_err().to_string();
        assert_eq!(err, "rec.mcap: topic \"/scan\", message 1: field angle_increment is NaN");
        let err = run(&[scan(2, 0.1), scan(1, 0.1)]).unwrap_err().to_string();
        assert_eq!(
            err,
            "rec.mcap: topic \"/scan\", message 1: field header.stamp 1.000000000 is not after the previous scan's \
             2.000000000 (message 0)"
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
}
