//! What a recording holds, for `omnical init`: every topic with its message type, count and rate, the
//! joint names of each `sensor_msgs/msg/JointState` topic, and the robot's URDF if a `std_msgs/msg/String`
//! topic `/robot_description` carries it.
//!
//! Gathered by [`InventorySink`] from the same storage readers as the runs ([`MessageSink`]), so whatever
//! `train` reads can be inspected: a bare `.mcap` here, a `.db3` or a rosbag2 folder in
//! [`crate::dataset::rosbag2`], any of them under a folder in [`crate::dataset::inspect`].

use super::common::{RosString, decode};
use super::framing;
use super::joint_state::{self, JointState};
use super::recording::{MessageSink, payload};
use crate::api::settings::named;
use crate::dataset::DatasetError;
use std::path::{Path, PathBuf};
/// The topic `robot_state_publisher` publishes the URDF on.
pub const ROBOT_DESCRIPTION_TOPIC: &str = "/robot_description";

/// One topic of a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicSummary {
    /// The topic name.
    pub topic: String,
    /// The message type (schema name), e.g. `sensor_msgs/msg/JointState`; empty if the channel has none.
    pub msg_type: String,
    /// Messages in the file.
    pub count: u64,
    /// Log time of the first and of the last message. ns.
    pub first_ns: u64,
    /// See `first_ns`. ns.
    pub last_ns: u64,
    /// JointState topics: the joint names, in order of first appearance over all messages.
    pub joint_names: Vec<String>,
}

impl TopicSummary {
    /// Mean message rate over the topic's span (`None` for fewer than two messages or a zero span). Hz.
    pub fn rate_hz(&self) -> Option<f64> {
        let span_s = (self.last_ns.saturating_sub(self.first_ns)) as f64 * 1e-9;
        (self.count >= 2 && span_s > 0.0).then(|| (self.count - 1) as f64 / span_s)
    }
}

/// What a recording holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Inventory {
    /// Every topic with at least one message or a channel record, sorted by name.
    pub topics: Vec<TopicSummary>,
    /// The last message on `/robot_description` (`std_msgs/msg/String`), if any: the URDF.
    pub robot_description: Option<String>,
}

/// Lists what the MCAP file at `path` holds (read whole into memory; `max_bytes` caps its size).
pub fn inspect(path: &Path, max_bytes: u64) -> Result<Inventory, DatasetError> {
    let len = std::fs::metadata(path).map_err(|e| DatasetError::io(path, e))?.len();
    if len > max_bytes {
        return Err(DatasetError::file(
            path,
            format!("the file is {len} bytes, above the limit of {max_bytes} bytes ({})", named("max_file_mb")),
        ));
    }
    let buf = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    inspect_bytes(path, &buf)
}

/// [`inspect`] on a file held in memory; `path` names it in errors.
pub fn inspect_bytes(path: &Path, buf: &[u8]) -> Result<Inventory, DatasetError> {
    let mut inv = InventorySink::new(path);
    framing::feed_mcap(path, buf, &mut inv)?;
    inv.finish()
}

/// Gathers an [`Inventory`] message by message. JointState topics and `/robot_description` are decoded; the
/// first message that does not decode is the error (naming the recording, topic and message index, 0-based
/// within its topic).
pub(crate) struct InventorySink {
    /// The recording, for errors.
    path: PathBuf,
    inv: Inventory,
    /// Every message payload is zstd-compressed on its own (rosbag2's `compression_mode: MESSAGE`).
    pub(crate) zstd_messages: bool,
    error: Option<DatasetError>,
}

impl InventorySink {
    /// An empty inventory of the recording at `path`.
    pub(crate) fn new(path: &Path) -> Self {
        Self { path: path.to_path_buf(), inv: Inventory::default(), zstd_messages: false, error: None }
    }

    /// The inventory: topics with at least one message, sorted by name; or the first decoding error.
    pub(crate) fn finish(mut self) -> Result<Inventory, DatasetError> {
        if let Some(e) = self.error {
            return Err(e);
        }
        self.inv.topics.retain(|t| t.count > 0);
        self.inv.topics.sort_by(|a, b| a.topic.cmp(&b.topic));
        Ok(self.inv)
    }

    /// Decodes what the inventory keeps of a message of topic `i`.
    fn decode(&mut self, i: usize, data: &[u8]) -> Result<(), String> {
        let t = &mut self.inv.topics[i];
        // A namespaced robot publishes it as `/robot1/robot_description`.
        let is_urdf = (t.topic == ROBOT_DESCRIPTION_TOPIC || t.topic.ends_with(ROBOT_DESCRIPTION_TOPIC))
            && t.msg_type == "std_msgs/msg/String";
        if t.msg_type != joint_state::NAME && !is_urdf {
            return Ok(());
        }
        let data = &payload(self.zstd_messages, data)?[..];
        if is_urdf {
            let text: RosString = decode(data)?;
            self.inv.robot_description = Some(text.0);
        } else {
            let js: JointState = decode(data)?;
            for name in js.name {
                if !t.joint_names.contains(&name.0) {
                    t.joint_names.push(name.0);
                }
            }
        }
        Ok(())
    }
}

impl MessageSink for InventorySink {
    fn channel(&mut self, topic: &str, schema: &str, _schema_encoding: &str, _message_encoding: &str) -> usize {
        match self.inv.topics.iter().position(|t| t.topic == topic) {
            Some(i) => i,
            None => {
                self.inv.topics.push(TopicSummary {
                    topic: topic.to_string(),
                    msg_type: schema.to_string(),
                    count: 0,
                    first_ns: 0,
                    last_ns: 0,
                    joint_names: Vec::new(),
                });
                self.inv.topics.len() - 1
            }
        }
    }

    fn message(&mut self, i: usize, data: &[u8], log_time_ns: u64) {
        if self.error.is_some() {
            return;
        }
        let t = &mut self.inv.topics[i];
        let index = t.count;
        if index == 0 {
            (t.first_ns, t.last_ns) = (log_time_ns, log_time_ns);
        }
        t.count += 1;
        t.first_ns = t.first_ns.min(log_time_ns);
        t.last_ns = t.last_ns.max(log_time_ns);
        if let Err(e) = self.decode(i, data) {
            let topic = &self.inv.topics[i].topic;
            self.error = Some(DatasetError::at(&self.path, format!("topic {topic:?}, message {index}"), e));
        }
    }
}
