//! The recording's own topics that an exported bag carries over unchanged, so it replays beside the
//! original in Foxglove: transforms (`tf2_msgs/msg/TFMessage`: `/tf`, `/tf_static`), the URDF
//! (`std_msgs/msg/String`, `/robot_description`) and the commands (`geometry_msgs/msg/Twist`,
//! `TwistStamped`). Messages are copied as recorded (CDR bytes, header stamps untouched); topics of other
//! types are not (their schema text is not known here to declare them). Static topics (`/tf_static`,
//! `/robot_description`, latched, usually logged before the motion) are copied whole into every run of the
//! recording, logged at the run's start when they were logged before it; the others within the run's span.

use super::recording::{MessageSink, payload};
use super::{laser_scan, twist};

/// `std_msgs/msg/String`.
const STRING_NAME: &str = "std_msgs/msg/String";

/// The schema text of a type this copies, `None` for the others.
fn schema_of(name: &str) -> Option<String> {
    match name {
        super::tf::NAME => Some(laser_scan::tf_schema()),
        twist::NAME => Some(twist::schema()),
        twist::STAMPED_NAME => Some(twist::stamped_schema()),
        STRING_NAME => Some("string data\n".to_string()),
        _ => None,
    }
}

/// Whether a topic is published once and latched: copied whole into every run.
fn is_static(topic: &str) -> bool {
    super::qos::is_latched(topic)
}

/// One topic carried over: its type and schema text, and its messages (log time ns, CDR bytes) in log order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CopiedTopic {
    /// The topic, as recorded.
    pub topic: String,
    /// Schema (type) name, e.g. `tf2_msgs/msg/TFMessage`.
    pub schema_name: String,
    /// The `ros2msg` schema text.
    pub schema_text: String,
    /// Log time (ns since the epoch) and CDR bytes of each message, in log order.
    pub messages: Vec<(u64, Vec<u8>)>,
}

/// Collects the topics to carry over from a recording (any storage, see [`MessageSink`]).
#[derive(Debug, Default)]
pub(crate) struct CopySink {
    /// Per channel: its topic, and what is collected of it (`None` for channels not copied).
    channels: Vec<(String, Option<CopiedTopic>)>,
    /// Each message is zstd-compressed (rosbag2's per-message mode).
    zstd_messages: bool,
}

impl MessageSink for CopySink {
    fn channel(&mut self, topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> usize {
        // A topic declared again (in another split file) keeps its first channel, copied or not.
        if let Some(i) = self.channels.iter().position(|(t, _)| t == topic) {
            return i;
        }
        let ros2 = matches!(schema_encoding, "ros2msg" | "ros2idl") && message_encoding == "cdr";
        let copied = schema_of(schema).filter(|_| ros2).map(|text| CopiedTopic {
            topic: topic.to_string(),
            schema_name: schema.to_string(),
            schema_text: text,
            messages: Vec::new(),
        });
        self.channels.push((topic.to_string(), copied));
        self.channels.len() - 1
    }

    fn message(&mut self, i: usize, data: &[u8], log_time_ns: u64) {
        let Some((_, Some(c))) = self.channels.get_mut(i) else { return };
        // A message that does not decompress is left out: the copy is for viewing, not for the fit.
        let Ok(bytes) = payload(self.zstd_messages, data) else { return };
        c.messages.push((log_time_ns, bytes.into_owned()));
    }
}

impl CopySink {
    /// A sink; `zstd_messages`: each message is zstd-compressed (rosbag2's per-message mode).
    pub(crate) fn new(zstd_messages: bool) -> Self {
        Self { channels: Vec::new(), zstd_messages }
    }

    /// The topics collected, with at least one message each.
    pub(crate) fn finish(self) -> Vec<CopiedTopic> {
        let mut out: Vec<CopiedTopic> =
            self.channels.into_iter().filter_map(|(_, c)| c).filter(|c| !c.messages.is_empty()).collect();
        for c in &mut out {
            c.messages.sort_by_key(|&(t, _)| t);
        }
        out
    }
}

/// The part of `topics` a run spanning `[from_ns, to_ns]` (log time) carries: static topics whole (logged at
/// `from_ns` when logged before it), the others within the span. Topics left empty are dropped.
pub fn within(topics: &[CopiedTopic], from_ns: u64, to_ns: u64) -> Vec<CopiedTopic> {
    topics
        .iter()
        .map(|c| {
            let messages = if is_static(&c.topic) {
                c.messages.iter().map(|(t, m)| ((*t).max(from_ns), m.clone())).collect()
            } else {
                c.messages.iter().filter(|(t, _)| (from_ns..=to_ns).contains(t)).cloned().collect()
            };
            CopiedTopic {
                topic: c.topic.clone(),
                schema_name: c.schema_name.clone(),
                schema_text: c.schema_text.clone(),
                messages,
            }
        })
        .filter(|c| !c.messages.is_empty())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_known_ros2_types_and_cuts_dynamic_topics_to_the_span() {
        let mut sink = CopySink::default();
        let tf = sink.channel("/tf", super::super::tf::NAME, "ros2msg", "cdr");
        let st = sink.channel("/tf_static", super::super::tf::NAME, "ros2msg", "cdr");
        let js = sink.channel("/joint_states", "sensor_msgs/msg/JointState", "ros2msg", "cdr");
        let ros1 = sink.channel("/cmd_vel", "geometry_msgs/Twist", "ros2msg", "cdr");
        // Declared again by another split file: the same channels, copied or not.
        assert_eq!(
            (sink.channel("/tf", super::super::tf::NAME, "ros2msg", "cdr"), sink.channel("/joint_states", "x", "", "")),
            (tf, js)
        );
        for (i, t) in [(st, 5), (tf, 10), (tf, 20), (tf, 30), (js, 20), (ros1, 20)] {
            sink.message(i, &[t as u8], t);
        }
        let topics = sink.finish();
        assert_eq!(topics.iter().map(|c| c.topic.as_str()).collect::<Vec<_>>(), ["/tf", "/tf_static"]);
        let cut = within(&topics, 15, 25);
        assert_eq!(cut[0].messages, vec![(20, vec![20])]);
        assert_eq!(cut[1].messages, vec![(15, vec![5])], "a static topic is logged at the run's start");
        assert!(within(&topics, 40, 50).iter().all(|c| c.topic == "/tf_static"));
    }
}
