//! The QoS a written bag says each topic was offered with: the `offered_qos_profiles` channel metadata
//! that rosbag2 writes and `ros2 bag play` reads to publish each topic as it was published (MCAP's `ros2`
//! profile requires the key). Latched topics (`/tf_static`, `/robot_description`) are transient local, so a
//! node that starts after playback began still receives them; every other topic is volatile. All are
//! reliable, keep-last.
//!
//! The profile is written as rosbag2 up to metadata version 8 writes it (Humble: policies as integers, the
//! `rmw_qos_*_policy_t` values), and the file carries a `rosbag2` metadata record without
//! `serialized_metadata`, from which newer readers (Jazzy, Kilted, Rolling: `rosbag2_storage_mcap`) take
//! version 8 and so read integers too. Durations `{sec: 0, nsec: 0}` are RMW's "unspecified" (the
//! middleware's default: no deadline, no lifespan, no lease).

use std::collections::BTreeMap;

/// Name of the MCAP metadata record rosbag2 keeps its bag metadata in.
pub(super) const ROSBAG2_METADATA: &str = "rosbag2";

/// Channel metadata key of the QoS profiles.
pub(super) const OFFERED_QOS_PROFILES: &str = "offered_qos_profiles";

/// `RMW_QOS_POLICY_DURABILITY_TRANSIENT_LOCAL`.
const TRANSIENT_LOCAL: u8 = 1;
/// `RMW_QOS_POLICY_DURABILITY_VOLATILE`.
const VOLATILE: u8 = 2;

/// Whether a topic is latched: published once, kept for late subscribers (transient local).
pub(super) fn is_latched(topic: &str) -> bool {
    super::tf::is_static_topic(topic) || topic.trim_end_matches('/').ends_with("/robot_description")
}

/// The `offered_qos_profiles` YAML of one publisher on `topic` (version-8 encoding, see the module docs).
pub(super) fn offered_qos_profiles(topic: &str) -> String {
    let (durability, depth) = if is_latched(topic) { (TRANSIENT_LOCAL, 1) } else { (VOLATILE, 10) };
    let unspecified = "\n    sec: 0\n    nsec: 0";
    format!(
        "- history: 1\n  depth: {depth}\n  reliability: 1\n  durability: {durability}\n  deadline:{unspecified}\n  \
         lifespan:{unspecified}\n  liveliness: 1\n  liveliness_lease_duration:{unspecified}\n  \
         avoid_ros_namespace_conventions: false\n"
    )
}

/// The channel metadata of `topic`.
pub(super) fn channel_metadata(topic: &str) -> BTreeMap<String, String> {
    BTreeMap::from([(OFFERED_QOS_PROFILES.to_string(), offered_qos_profiles(topic))])
}

/// The `rosbag2` metadata record: the distribution the QoS encoding follows, no `serialized_metadata`.
pub(super) fn rosbag2_metadata() -> mcap::records::Metadata {
    mcap::records::Metadata {
        name: ROSBAG2_METADATA.to_string(),
        metadata: BTreeMap::from([("ROS_DISTRO".to_string(), "humble".to_string())]),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn latched_topics_are_transient_local_and_the_others_volatile() {
        let latched = offered_qos_profiles("/tf_static");
        assert!(latched.contains("durability: 1\n") && latched.contains("depth: 1\n"), "{latched}");
        assert!(offered_qos_profiles("/robot_description").contains("durability: 1\n"));
        let odom = offered_qos_profiles("/omnical/odometry");
        assert!(odom.contains("durability: 2\n") && odom.contains("reliability: 1\n"), "{odom}");
        // One profile, a YAML list of one mapping with the nine keys rosbag2 reads.
        let docs = yaml_rust2::YamlLoader::load_from_str(&latched).unwrap();
        let list = docs[0].as_vec().unwrap();
        assert_eq!(list.len(), 1);
        let keys: Vec<&str> = list[0].as_hash().unwrap().keys().map(|k| k.as_str().unwrap()).collect();
        assert_eq!(
            keys,
            [
                "history",
                "depth",
                "reliability",
                "durability",
                "deadline",
                "lifespan",
                "liveliness",
                "liveliness_lease_duration",
                "avoid_ros_namespace_conventions"
            ]
        );
    }
}
