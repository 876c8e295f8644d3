//! `sensor_msgs/msg/Imu`: an IMU's yaw rate (`angular_velocity.z`, rad/s, about the IMU frame's z axis),
//! read as a gyro reference ([`omni_kin::gyro`]) and written by the simulator.

use super::common::{
    HEADER_DEF, Header, NS_PER_S, QUATERNION_DEF, Quaternion, TIME_DEF, VECTOR3_DEF, Vector3, decode, schema_text,
    seconds_since,
};
use super::recording::{MessageSink, payload};
use crate::dataset::DatasetError;
use omni_kin::gyro::GyroSample;
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

/// A gyro's samples read from a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct GyroRead {
    /// The yaw rates in time order; their `t_s` are seconds since [`Self::origin_s`].
    pub samples: Vec<GyroSample>,
    /// The whole second of the first sample's `header.stamp`. s.
    pub origin_s: i64,
}

impl GyroRead {
    /// The samples on another time base: seconds since `origin_s` (a run's).
    pub fn rebase(&mut self, origin_s: i64) {
        let shift_s = (self.origin_s - origin_s) as f64;
        self.samples.iter_mut().for_each(|s| s.t_s += shift_s);
        self.origin_s = origin_s;
    }
}

/// Collects one Imu topic's yaw rates from any storage ([`MessageSink`]).
pub(crate) struct ImuSink {
    topic: String,
    zstd_messages: bool,
    /// Every channel: topic, schema, whether ROS 2's encoding, messages seen.
    channels: Vec<(String, String, bool, usize)>,
    samples: Vec<(i64, f64)>,
    problem: Option<(usize, String)>,
}

impl ImuSink {
    /// A sink for `topic`; `zstd_messages`: each message is zstd-compressed (rosbag2's per-message mode).
    pub(crate) fn new(topic: &str, zstd_messages: bool) -> Self {
        Self { topic: topic.into(), zstd_messages, channels: Vec::new(), samples: Vec::new(), problem: None }
    }

    fn take(&mut self, k: usize, data: &[u8]) -> Result<(), String> {
        let m: Imu = decode(data)?;
        let z = m.angular_velocity.z;
        if !z.is_finite() {
            return Err(format!("field angular_velocity.z is {z}"));
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
        self.samples.push((ns, z));
        Ok(())
    }

    /// The samples, or an error naming the file, the topic and, for a bad message, its index and field.
    pub(crate) fn finish(self, path: &Path) -> Result<GyroRead, DatasetError> {
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
        if let Some((k, what)) = self.problem {
            return Err(DatasetError::at(path, format!("{here}, message {k}"), what));
        }
        let Some(&(first_ns, _)) = self.samples.first() else {
            return Err(DatasetError::at(path, here, "holds no messages: record the IMU while the robot turns"));
        };
        let origin_s = first_ns.div_euclid(NS_PER_S);
        let samples = self
            .samples
            .into_iter()
            .map(|(ns, z)| GyroSample { t_s: seconds_since(ns, origin_s), z_rad_s: z })
            .collect();
        Ok(GyroRead { samples, origin_s })
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
        if !(c.0 == self.topic && c.1 == NAME && c.2) || self.problem.is_some() {
            return;
        }
        let plain = match payload(self.zstd_messages, data) {
            Ok(p) => p,
            Err(e) => {
                self.problem = Some((k, e));
                return;
            }
        };
        if let Err(e) = self.take(k, &plain) {
            self.problem = Some((k, e));
        }
    }
}
