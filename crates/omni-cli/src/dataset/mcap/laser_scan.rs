//! `sensor_msgs/msg/LaserScan`: a planar lidar's ranges (REP-117: +inf nothing in range, NaN an erroneous
//! reading), read into [`omni_kin::lidar::Scan`]s and written by the simulator; and the static transforms
//! that place the lidar on the robot (`…tf_static` topics, and fixed pairs republished on `/tf`, as ROS 1
//! bags hold them: [`super::statics`]), from `base_link`, else `base_footprint`, down to the scans' frame.

use super::common::{
    HEADER_DEF, Header, MsgDef, NS_PER_S, QUATERNION_DEF, RosString, TIME_DEF, VECTOR3_DEF, decode, schema_text,
    seconds_since,
};
use super::recording::{MessageSink, payload};
use super::statics::{SeenPairs, StaticTree, base_frames};
use super::tf::{self, TfMessage, Transform, TransformStamped};
use crate::api::settings::named_with;
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

/// A lidar's scans read from a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanRead {
    /// The scans in time order; their `t_s` are seconds since [`Self::origin_s`].
    pub scans: Vec<Scan>,
    /// The whole second (`header.stamp.sec`) of the first scan. s since the epoch (or sim-time start).
    pub origin_s: i64,
    /// The scans' `header.frame_id` (of the first scan, without a leading `/`); empty when the driver left
    /// it empty.
    pub frame_id: String,
    /// The lidar's pose in the base frame from the recording's static transforms, when they hold it (m, rad).
    pub base_from_sensor: Option<Pose2>,
    /// The frames the mount was composed along, from the base to [`Self::frame_id`]
    /// (`["base_footprint", "base_link", "base_scan"]`); empty without a mount.
    pub chain: Vec<String>,
    /// The static transforms mount the lidar upside down: the scans' beam angles were mirrored (negated), so
    /// that they sweep counter-clockwise seen from above as the base's frame does.
    pub mirrored: bool,
    /// The scans' `header.stamp` was 0 on the first two (never filled): they are timed by their log time.
    pub by_log_time: bool,
    /// Scans whose `angle_max` disagrees with their beams (`angle_min + (n − 1)·angle_increment`), when any
    /// do: the beams' angles are taken from `angle_min` and `angle_increment`, `angle_max` is not used.
    pub angle_max_mismatch: Option<AngleMaxMismatch>,
}

/// Scans whose `angle_max` is not where their beams end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngleMaxMismatch {
    /// How many scans disagree.
    pub scans: usize,
    /// The first one's `angle_max`. rad.
    pub angle_max_rad: f64,
    /// Where its beams end: `angle_min + (n − 1)·angle_increment`. rad.
    pub beams_end_rad: f64,
    /// Its beam count.
    pub beams: usize,
}

impl AngleMaxMismatch {
    /// The note on `topic`: which field is used.
    pub fn describe(&self, topic: &str) -> String {
        format!(
            "lidar {topic:?}: {} scans have an angle_max ({:.2}°) that disagrees with their {} beams, which end at \
             {:.2}° (angle_min + (n − 1)·angle_increment): the beams' directions are taken from angle_min and \
             angle_increment, as ROS's laser_geometry takes them; angle_max is not used",
            self.scans,
            self.angle_max_rad.to_degrees(),
            self.beams,
            self.beams_end_rad.to_degrees()
        )
    }
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

    /// The mount's chain as `base_link → laser`.
    pub fn chain_text(&self) -> String {
        self.chain.join(" → ")
    }
}

/// One topic as the storage declares it.
struct Declared {
    topic: String,
    schema: String,
    /// The encodings are ROS 2's (`ros2msg`/`ros2idl` schemas, `cdr` messages).
    cdr: bool,
    messages: usize,
    /// A TF topic's pairs, for its static transforms.
    tf: SeenPairs,
}

impl Declared {
    fn is_tf(&self) -> bool {
        self.schema == tf::NAME && self.cdr
    }
}

/// One scan as read: `header.stamp` and log time (ns), and the scan (its `t_s` not yet set).
struct Taken {
    stamp_ns: i64,
    log_ns: i64,
    scan: Scan,
}

/// Gathers the LaserScan messages of one topic (and the static transforms) from any storage reader.
pub(crate) struct ScanSink {
    topic: String,
    /// Every payload is zstd-compressed on its own (set by a [`super::recording::Recording`] that feeds it).
    pub(super) zstd_messages: bool,
    /// The frame the lidar's mount is looked up from; `None`: `base_link`, else `base_footprint`.
    base_frame: Option<String>,
    channels: Vec<Declared>,
    scans: Vec<Taken>,
    /// Scans whose angle_max disagrees with their beams.
    angle_max_mismatch: Option<AngleMaxMismatch>,
    frame_id: Option<String>,
    /// The first problem on the topic: message index and what.
    problem: Option<(usize, String)>,
}

impl ScanSink {
    /// A sink for the LaserScan messages on `topic`; `zstd_messages`: each payload is zstd-compressed.
    pub(crate) fn new(topic: &str, zstd_messages: bool) -> Self {
        Self {
            topic: topic.to_string(),
            zstd_messages,
            base_frame: None,
            channels: Vec::new(),
            scans: Vec::new(),
            angle_max_mismatch: None,
            frame_id: None,
            problem: None,
        }
    }

    /// Looks the lidar's mount up from `base_frame` (`[frames] base` of a robot description) instead of the
    /// first of `base_link` and `base_footprint` that holds it.
    pub(crate) fn with_base_frame(mut self, base_frame: Option<&str>) -> Self {
        self.base_frame = base_frame.map(str::to_string);
        self
    }

    /// Takes the next message of the scan topic, logged at `log_ns`.
    fn take_scan(&mut self, data: &[u8], log_ns: i64) -> Result<(), String> {
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
        self.check_angle_max(&m);
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
        self.scans.push(Taken { stamp_ns: m.header.stamp.ns(), log_ns, scan });
        Ok(())
    }

    /// Counts `m` among the scans whose `angle_max` is not where their beams end: beyond one increment
    /// (drivers differ on whether angle_max is the last beam's or one increment past it) and float32's
    /// rounding.
    fn check_angle_max(&mut self, m: &LaserScan) {
        let beams = m.ranges.len();
        if beams < 2 || !m.angle_max.is_finite() {
            return;
        }
        let (min, inc, max) = (f64::from(m.angle_min), f64::from(m.angle_increment), f64::from(m.angle_max));
        let end = min + (beams - 1) as f64 * inc;
        if (max - end).abs() <= inc.abs() * 1.01 + 1e-5 {
            return;
        }
        let first = AngleMaxMismatch { scans: 0, angle_max_rad: max, beams_end_rad: end, beams };
        self.angle_max_mismatch.get_or_insert(first).scans += 1;
    }

    /// The error when the scan topic is missing or not a ROS 2 LaserScan (naming the file `path`).
    fn check_topic(&self, path: &Path) -> Result<(), DatasetError> {
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
                    "the LaserScan topics are {}: name one ({}, scan-odometry --topic TOPIC)",
                    scans.join(", "),
                    named_with("gt_scans", "TOPIC")
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
        Ok(())
    }

    /// Each scan's time (ns): `header.stamp`, or the log time when the first two stamps are 0 (a driver
    /// that never fills them); an error naming the message when they do not increase.
    fn times_ns(&self) -> Result<(Vec<i64>, bool), (usize, String)> {
        let by_log_time = self.scans.len() >= 2 && self.scans[..2].iter().all(|s| s.stamp_ns == 0);
        let times: Vec<i64> = self.scans.iter().map(|s| if by_log_time { s.log_ns } else { s.stamp_ns }).collect();
        let field = if by_log_time { "log time" } else { "field header.stamp" };
        for (k, w) in times.windows(2).enumerate() {
            if w[1] <= w[0] {
                let stamp = super::common::Stamp;
                return Err((
                    k + 1,
                    format!(
                        "{field} {} is not after the previous scan's {} (message {k}): a scan topic's stamps must \
                         increase; record the lidar driver's topic as it publishes it (one driver, its own clock)",
                        stamp(w[1]),
                        stamp(w[0]),
                    ),
                ));
            }
        }
        Ok((times, by_log_time))
    }

    /// The recording's static transforms: those of the `…tf_static` topics first, then the fixed pairs of
    /// the other TF topics.
    fn statics(&self) -> StaticTree {
        let mut tree = StaticTree::default();
        for on_static_topic in [true, false] {
            for c in self.channels.iter().filter(|c| c.is_tf() && tf::is_static_topic(&c.topic) == on_static_topic) {
                c.tf.add_statics(on_static_topic, &mut tree);
            }
        }
        tree
    }

    /// The lidar's mount (pose in the base, the frames from the base to `frame`, mirrored), from the named
    /// base frame or the first of `base_link` and `base_footprint` that `frame` hangs from.
    fn mount(&self, frame: &str) -> Option<(Pose2, Vec<String>, bool)> {
        let tree = self.statics();
        base_frames(self.base_frame.as_deref()).into_iter().find_map(|base| {
            let (pose, frames) = tree.offset(base, frame)?;
            let mirrored = tree.mirrored(base, frame) == Some(true);
            Some((pose, std::iter::once(base.to_string()).chain(frames).collect(), mirrored))
        })
    }

    /// The scans read, or the error naming the file `path`, the topic, the message and the field.
    pub(crate) fn finish(self, path: &Path) -> Result<ScanRead, DatasetError> {
        self.check_topic(path)?;
        let here = format!("topic {:?}", self.topic);
        if let Some((k, what)) = &self.problem {
            return Err(DatasetError::at(path, format!("{here}, message {k}"), what.clone()));
        }
        if self.scans.is_empty() {
            return Err(DatasetError::at(path, here, "holds no scans: record the lidar while the robot moves"));
        }
        let (times, by_log_time) =
            self.times_ns().map_err(|(k, what)| DatasetError::at(path, format!("{here}, message {k}"), what))?;
        let origin_s = times[0].div_euclid(NS_PER_S);
        let frame_id = self.frame_id.clone().unwrap_or_default();
        let mount = if frame_id.is_empty() { None } else { self.mount(&frame_id) };
        // A lidar mounted upside down sweeps clockwise seen from above: its beams' angles are mirrored.
        let mirrored = mount.as_ref().is_some_and(|m| m.2);
        let scans = self
            .scans
            .into_iter()
            .zip(times)
            .map(|(Taken { scan: s, .. }, ns)| {
                let t_s = seconds_since(ns, origin_s);
                match mirrored {
                    true => {
                        Scan { t_s, angle_min_rad: -s.angle_min_rad, angle_increment_rad: -s.angle_increment_rad, ..s }
                    }
                    false => Scan { t_s, ..s },
                }
            })
            .collect();
        let (base_from_sensor, chain) = mount.map_or((None, Vec::new()), |(p, c, _)| (Some(p), c));
        let angle_max_mismatch = self.angle_max_mismatch;
        Ok(ScanRead { scans, origin_s, frame_id, base_from_sensor, chain, mirrored, by_log_time, angle_max_mismatch })
    }
}

impl MessageSink for ScanSink {
    fn channel(&mut self, topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> usize {
        if let Some(i) = self.channels.iter().position(|c| c.topic == topic) {
            return i;
        }
        let cdr = matches!(schema_encoding, "ros2msg" | "ros2idl") && message_encoding == "cdr";
        let tf = SeenPairs::default();
        self.channels.push(Declared { topic: topic.into(), schema: schema.into(), cdr, messages: 0, tf });
        self.channels.len() - 1
    }

    fn message(&mut self, i: usize, data: &[u8], log_time_ns: u64) {
        let c = &mut self.channels[i];
        let k = c.messages;
        c.messages += 1;
        let is_scan = c.topic == self.topic && c.schema == NAME && c.cdr;
        if !(is_scan && self.problem.is_none() || c.is_tf()) {
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
            let log_ns = i64::try_from(log_time_ns).unwrap_or(i64::MAX);
            if let Err(e) = self.take_scan(&data, log_ns) {
                self.problem = Some((k, e));
            }
        } else if let Ok(m) = decode::<TfMessage>(&data) {
            c.tf.push(&m);
        }
    }
}

#[cfg(test)]
mod tests;
