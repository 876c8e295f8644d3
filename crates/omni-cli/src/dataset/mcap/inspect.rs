//! What a recording holds, for `omnical init`: every topic with its message type, count and rate, the
//! joint names of each `sensor_msgs/msg/JointState` topic, and the robot's URDF if a `std_msgs/msg/String`
//! topic `/robot_description` carries it.

use super::common::{RosString, decode};
use super::joint_state::{self, JointState};
use super::read::{MAX_RECORD_LIMIT, MIN_RECORD_LIMIT};
use crate::dataset::DatasetError;
use mcap::sans_io::LinearReaderOptions;
use std::path::Path;

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
            format!("the file is {len} bytes, above the limit of {max_bytes} bytes (--max-file-mb)"),
        ));
    }
    let buf = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    inspect_bytes(path, &buf)
}

/// [`inspect`] on a file held in memory; `path` names it in errors.
pub fn inspect_bytes(path: &Path, buf: &[u8]) -> Result<Inventory, DatasetError> {
    // The mcap crate can panic on some damaged files (see the reader): an error, never a crash.
    std::panic::catch_unwind(|| scan(path, buf))
        .unwrap_or_else(|_| Err(DatasetError::file(path, "the file is damaged: the MCAP reader panicked on it")))
}

fn scan(path: &Path, buf: &[u8]) -> Result<Inventory, DatasetError> {
    if !buf.starts_with(mcap::MAGIC) {
        return Err(DatasetError::file(path, "not an MCAP file (it does not start with the MCAP magic bytes)"));
    }
    let mut inv = Inventory::default();
    let mut index: Vec<(u16, usize)> = Vec::new();
    // Damaged files fail cleanly (as in the reader): a cap on record lengths, and a panic is an error.
    let limit = buf.len().saturating_mul(64).clamp(MIN_RECORD_LIMIT, MAX_RECORD_LIMIT);
    let options = LinearReaderOptions::default().with_validate_chunk_crcs(true).with_record_length_limit(limit);
    let reader = mcap::io::MessageReader::new_with_options(std::io::Cursor::new(buf), options);
    for (n, m) in reader.enumerate() {
        let m = m.map_err(|e| DatasetError::file(path, format!("cannot read the MCAP file: {e}")))?;
        let i = match index.iter().find(|(id, _)| *id == m.channel.id) {
            Some(&(_, i)) => i,
            None => {
                let msg_type = m.channel.schema.as_ref().map(|s| s.name.clone()).unwrap_or_default();
                inv.topics.push(TopicSummary {
                    topic: m.channel.topic.clone(),
                    msg_type,
                    count: 0,
                    first_ns: m.log_time,
                    last_ns: m.log_time,
                    joint_names: Vec::new(),
                });
                index.push((m.channel.id, inv.topics.len() - 1));
                inv.topics.len() - 1
            }
        };
        let t = &mut inv.topics[i];
        t.count += 1;
        t.first_ns = t.first_ns.min(m.log_time);
        t.last_ns = t.last_ns.max(m.log_time);
        let at = |e: String| DatasetError::at(path, format!("topic {:?}, message {n}", t.topic), e);
        if t.msg_type == joint_state::NAME {
            let js: JointState = decode(&m.data).map_err(at)?;
            for name in js.name {
                if !t.joint_names.contains(&name.0) {
                    t.joint_names.push(name.0);
                }
            }
        } else if t.topic == ROBOT_DESCRIPTION_TOPIC && t.msg_type == "std_msgs/msg/String" {
            let text: RosString = decode(&m.data).map_err(at)?;
            inv.robot_description = Some(text.0);
        }
    }
    inv.topics.sort_by(|a, b| a.topic.cmp(&b.topic));
    Ok(inv)
}
