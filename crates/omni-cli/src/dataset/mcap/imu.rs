//! `sensor_msgs/msg/Imu`: an IMU's angular velocity (`angular_velocity`, rad/s, in the IMU's frame
//! `header.frame_id`) and the IMU's mount on the base from the recording's static transforms (`/tf_static`,
//! or a pair repeated unchanged on `/tf`), read as a gyro reference ([`omni_kin::gyro`]: the base's yaw
//! rate is the base-z component of the angular velocity turned by the mount) and written by the simulator.

use super::common::{
    HEADER_DEF, Header, NS_PER_S, QUATERNION_DEF, Quaternion, TIME_DEF, VECTOR3_DEF, Vector3, decode, schema_text,
    seconds_since,
};
use super::recording::{MessageSink, payload};
use super::statics::{SeenPairs, StaticTree};
use super::tf::{self, TfMessage};
use crate::dataset::DatasetError;
use omni_kin::gyro::{GyroSample, ImuMount};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The schema name.
pub(super) const NAME: &str = "sensor_msgs/msg/Imu";

/// `sensor_msgs/msg/Imu`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct Imu {
    pub header: Header,
    pub orientation: Quaternion,
    pub orientation_covariance: [f64; 9],
    /// rad/s.
    pub angular_velocity: Vector3,
    pub angular_velocity_covariance: [f64; 9],
    /// m/s².
    pub linear_acceleration: Vector3,
    pub linear_acceleration_covariance: [f64; 9],
}

/// The schema text, as rosbag2 writes it.
pub(super) fn schema() -> String {
    schema_text(
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n\
         geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n\
         geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n",
        &[&HEADER_DEF, &TIME_DEF, &QUATERNION_DEF, &VECTOR3_DEF],
    )
}

/// The base frames an IMU's mount is looked up from, in order.
pub const BASE_FRAMES: [&str; 2] = ["base_link", "base_footprint"];

/// One IMU sample: its angular velocity in its own frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuRate {
    /// s, since [`GyroRead::origin_s`].
    pub t_s: f64,
    /// x, y, z in the IMU's frame. rad/s.
    pub imu_rad_s: [f64; 3],
}

/// The IMU's mount as the recording's static transforms state it.
#[derive(Clone, Debug, PartialEq)]
pub struct StatedMount {
    /// The base frame it hangs from (`base_link`, else `base_footprint`).
    pub base_frame: String,
    /// The IMU frame's rotation in it.
    pub mount: ImuMount,
}

/// An IMU's samples read from a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct GyroRead {
    /// The angular velocities in time order; their `t_s` are seconds since [`Self::origin_s`].
    pub rates: Vec<ImuRate>,
    /// The whole second of the first sample's `header.stamp`. s.
    pub origin_s: i64,
    /// The IMU's frame (the first message's `header.frame_id`).
    pub frame_id: String,
    /// Its mount from the static transforms, when they place it under a base frame (or it is one).
    pub stated_mount: Option<StatedMount>,
}

impl GyroRead {
    /// The samples on another time base: seconds since `origin_s` (a run's).
    pub fn rebase(&mut self, origin_s: i64) {
        let shift_s = (self.origin_s - origin_s) as f64;
        self.rates.iter_mut().for_each(|s| s.t_s += shift_s);
        self.origin_s = origin_s;
    }

    /// The base's yaw rates for the IMU on `mount`.
    pub fn yaw_rates(&self, mount: &ImuMount) -> Vec<GyroSample> {
        self.rates.iter().map(|r| GyroSample { t_s: r.t_s, z_rad_s: mount.yaw_rate(r.imu_rad_s) }).collect()
    }
}

/// Collects one Imu topic's angular velocities, and the static transforms, from any storage ([`MessageSink`]).
pub(crate) struct ImuSink {
    topic: String,
    zstd_messages: bool,
    /// Every channel: topic, schema, whether ROS 2's encoding, messages seen.
    channels: Vec<(String, String, bool, usize)>,
    samples: Vec<(i64, [f64; 3])>,
    frame_id: Option<String>,
    statics: StaticTree,
    tf_pairs: SeenPairs,
    problem: Option<(usize, String)>,
}

impl ImuSink {
    /// A sink for `topic`; `zstd_messages`: each message is zstd-compressed (rosbag2's per-message mode).
    pub(crate) fn new(topic: &str, zstd_messages: bool) -> Self {
        Self {
            topic: topic.into(),
            zstd_messages,
            channels: Vec::new(),
            samples: Vec::new(),
            frame_id: None,
            statics: StaticTree::default(),
            tf_pairs: SeenPairs::default(),
            problem: None,
        }
    }

    fn take(&mut self, k: usize, data: &[u8]) -> Result<(), String> {
        let m: Imu = decode(data)?;
        let w = m.angular_velocity;
        for (axis, v) in [("x", w.x), ("y", w.y), ("z", w.z)] {
            if !v.is_finite() {
                return Err(format!("field angular_velocity.{axis} is {v}"));
            }
        }
        let ns = m.header.stamp.ns();
        if let Some(&(prev, _)) = self.samples.last()
            && ns <= prev
        {
            let stamp = super::common::Stamp;
            return Err(format!(
                "field header.stamp {} is not after the previous message's {} (message {})",
                stamp(ns),
                stamp(prev),
                k - 1
            ));
        }
        self.frame_id.get_or_insert_with(|| m.header.frame_id.frame().to_string());
        self.samples.push((ns, [w.x, w.y, w.z]));
        Ok(())
    }

    /// The IMU's mount on the first base frame that the static transforms (`/tf_static`, then the pairs
    /// that never moved on `/tf`) place it under; the identity when its frame is a base frame.
    fn stated_mount(mut self, frame_id: &str) -> Option<StatedMount> {
        self.tf_pairs.add_statics(false, &mut self.statics);
        BASE_FRAMES.iter().find_map(|base| {
            let rotation = match *base == frame_id {
                true => nalgebra::UnitQuaternion::identity(),
                false => self.statics.rotation(base, frame_id)?,
            };
            Some(StatedMount { base_frame: base.to_string(), mount: ImuMount { base_from_imu: rotation } })
        })
    }

    /// The samples, or an error naming the file, the topic and, for a bad message, its index and field.
    pub(crate) fn finish(mut self, path: &Path) -> Result<GyroRead, DatasetError> {
        let here = format!("topic {:?}", self.topic);
        let Some((_, schema, cdr, _)) = self.channels.iter().find(|c| c.0 == self.topic) else {
            let imus: Vec<&str> = self.channels.iter().filter(|c| c.1 == NAME).map(|c| c.0.as_str()).collect();
            let hint = match imus.is_empty() {
                true => "no topic holds sensor_msgs/msg/Imu: record the IMU".to_string(),
                false => format!("the Imu topics are {}: name one (--topic)", imus.join(", ")),
            };
            return Err(DatasetError::file(path, format!("no topic {:?} in the recording; {hint}", self.topic)));
        };
        if schema != NAME {
            return Err(DatasetError::at(path, here, format!("is a {schema}, not a {NAME}")));
        }
        if !cdr {
            return Err(DatasetError::at(path, here, "its encoding is not ROS 2's (ros2msg schema, cdr messages)"));
        }
        if let Some((k, what)) = self.problem.take() {
            return Err(DatasetError::at(path, format!("{here}, message {k}"), what));
        }
        let Some(&(first_ns, _)) = self.samples.first() else {
            return Err(DatasetError::at(path, here, "holds no messages: record the IMU while the robot turns"));
        };
        let origin_s = first_ns.div_euclid(NS_PER_S);
        let rates = std::mem::take(&mut self.samples)
            .into_iter()
            .map(|(ns, w)| ImuRate { t_s: seconds_since(ns, origin_s), imu_rad_s: w })
            .collect();
        let frame_id = self.frame_id.take().unwrap_or_default();
        let stated_mount = self.stated_mount(&frame_id);
        Ok(GyroRead { rates, origin_s, frame_id, stated_mount })
    }

    /// Takes one transform message: every transform of a static topic, and `/tf`'s pairs while they repeat.
    fn take_transforms(&mut self, is_static: bool, data: &[u8]) {
        let Ok(m) = decode::<TfMessage>(data) else { return };
        if is_static {
            m.transforms.iter().for_each(|t| {
                self.statics.add_transform(t);
            });
        } else {
            self.tf_pairs.push(&m);
        }
    }
}

impl MessageSink for ImuSink {
    fn channel(&mut self, topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> usize {
        if let Some(i) = self.channels.iter().position(|c| c.0 == topic) {
            return i;
        }
        let cdr = matches!(schema_encoding, "ros2msg" | "ros2idl") && message_encoding == "cdr";
        self.channels.push((topic.into(), schema.into(), cdr, 0));
        self.channels.len() - 1
    }

    fn message(&mut self, i: usize, data: &[u8], _log_time_ns: u64) {
        let c = &mut self.channels[i];
        let k = c.3;
        c.3 += 1;
        let is_imu = c.0 == self.topic && c.1 == NAME && c.2;
        let is_tf = c.1 == tf::NAME && c.2;
        let is_static = is_tf && tf::is_static_topic(&c.0);
        if !(is_imu && self.problem.is_none() || is_tf) {
            return;
        }
        let plain = match payload(self.zstd_messages, data) {
            Ok(p) => p,
            Err(e) if is_imu => {
                self.problem = Some((k, e));
                return;
            }
            Err(_) => return,
        };
        if is_imu {
            if let Err(e) = self.take(k, &plain) {
                self.problem = Some((k, e));
            }
        } else {
            self.take_transforms(is_static, &plain);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::common::{RosString, Time, encode};
    use super::super::tf::{Transform, TransformStamped};
    use super::*;

    /// An Imu message of frame `/imu_link` at `sec` s turning at (x, y, z) rad/s.
    fn message(sec: i32, w: [f64; 3]) -> Vec<u8> {
        let m = Imu {
            header: Header { stamp: Time { sec, nanosec: 0 }, frame_id: RosString("/imu_link".into()) },
            orientation: Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 },
            orientation_covariance: [0.0; 9],
            angular_velocity: Vector3 { x: w[0], y: w[1], z: w[2] },
            angular_velocity_covariance: [0.0; 9],
            linear_acceleration: Vector3::default(),
            linear_acceleration_covariance: [0.0; 9],
        };
        encode(&m).unwrap()
    }

    /// A TF message: `child` in `parent` turned by the quaternion (x, y, z, w).
    fn tf(parent: &str, child: &str, q: [f64; 4]) -> Vec<u8> {
        let t = TransformStamped {
            header: Header { stamp: Time::default(), frame_id: RosString(parent.into()) },
            child_frame_id: RosString(child.into()),
            transform: Transform {
                translation: Vector3::default(),
                rotation: Quaternion { x: q[0], y: q[1], z: q[2], w: q[3] },
            },
        };
        encode(&TfMessage { transforms: vec![t] }).unwrap()
    }

    /// An IMU upside down whose mount a ROS 1 bag publishes on /tf, repeated unchanged from base_footprint
    /// (no base_link), beside odom → base_footprint that moves: the mount is found, the yaw rate is −z.
    #[test]
    fn a_mount_repeated_on_tf_from_base_footprint_is_read() {
        let mut sink = ImuSink::new("/imu", false);
        let (t, i) = (sink.channel("/tf", tf::NAME, "ros2msg", "cdr"), sink.channel("/imu", NAME, "ros2msg", "cdr"));
        for k in 0..4 {
            sink.message(t, &tf("base_footprint", "imu_link", [1.0, 0.0, 0.0, 0.0]), 0);
            sink.message(t, &tf("odom", "base_footprint", [0.0, 0.0, (0.1 * k as f64).sin(), 1.0]), 0);
            sink.message(i, &message(10 + k, [0.0, 0.0, -0.5]), 0);
        }
        let read = sink.finish(Path::new("rec.bag")).unwrap();
        assert_eq!((read.frame_id.as_str(), read.origin_s, read.rates.len()), ("imu_link", 10, 4));
        let stated = read.stated_mount.clone().unwrap();
        assert_eq!(stated.base_frame, "base_footprint");
        assert!((stated.mount.z_up() + 1.0).abs() < 1e-12, "{stated:?}");
        assert!(read.yaw_rates(&stated.mount).iter().all(|g| (g.z_rad_s - 0.5).abs() < 1e-12));
        assert_eq!(read.yaw_rates(&ImuMount::UPRIGHT)[3], GyroSample { t_s: 3.0, z_rad_s: -0.5 });
    }

    /// A pair that moves on /tf is no mount; /tf_static's wins over /tf; a bad axis is named.
    #[test]
    fn a_moving_pair_is_no_mount_and_a_bad_axis_is_named() {
        let run = |moving: bool, statics: bool, w: [f64; 3]| {
            let mut sink = ImuSink::new("/imu", false);
            let t = sink.channel("/tf", tf::NAME, "ros2msg", "cdr");
            let s = sink.channel("/tf_static", tf::NAME, "ros2msg", "cdr");
            let i = sink.channel("/imu", NAME, "ros2msg", "cdr");
            if statics {
                sink.message(s, &tf("base_link", "imu_link", [0.0, 0.0, 0.0, 1.0]), 0);
            }
            for k in 0..3 {
                let z = if moving { 0.1 * k as f64 } else { 0.0 };
                sink.message(t, &tf("base_link", "imu_link", [1.0, 0.0, z, 0.0]), 0);
                sink.message(i, &message(k, w), 0);
            }
            sink.finish(Path::new("rec.mcap"))
        };
        assert_eq!(run(true, false, [0.0; 3]).unwrap().stated_mount, None);
        let upright = run(false, true, [0.0; 3]).unwrap().stated_mount.unwrap();
        assert_eq!((upright.base_frame.as_str(), upright.mount.z_up()), ("base_link", 1.0));
        assert_eq!(
            run(false, false, [f64::NAN, 0.0, 0.1]).unwrap_err().to_string(),
            "rec.mcap: topic \"/imu\", message 0: field angular_velocity.x is NaN"
        );
    }
}
