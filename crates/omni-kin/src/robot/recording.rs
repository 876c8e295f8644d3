//! Where a description's data is: the topics of a recording, the ground truth's TF frames, and a separate
//! ground-truth file.

use serde::{Deserialize, Serialize};

/// Topics of a recording (ROS 2 MCAP). Each replaces the automatic choice; command-line flags override.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Topics {
    /// The wheels' `sensor_msgs/JointState` topic (`--joints-topic`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_states: Option<String>,
    /// The ground-truth topic (`--gt-topic`): PoseStamped, Odometry, or TF.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth: Option<String>,
    /// The motion command topic (Twist or TwistStamped). Default `/cmd_vel`, else the only one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub command: Option<String>,
}

impl Topics {
    pub(super) fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// Frames of the ground truth in a TF topic.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frames {
    /// The ground truth's world frame, e.g. `map` (`--gt-parent-frame`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth_parent: Option<String>,
    /// The tracked frame on the robot, e.g. `base_link` (`--gt-child-frame`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth_child: Option<String>,
    /// The robot's base frame, the frame the wheels move (default `base_link`, else `base_footprint`): a
    /// lidar's mount (`--gt-scans`) and a tracked frame's offset are looked up from it in the static
    /// transforms.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<String>,
}

impl Frames {
    pub(super) fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// Ground truth from a separate file (`[ground_truth]`): a TUM or CSV trajectory, e.g. from motion capture.
/// Command-line flags (`--gt`, `--gt-time-offset`, `--gt-columns`, `--gt-units`) override each entry.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundTruthFile {
    /// The file (one recording) or a folder of files named after the recordings, relative to the robot
    /// description's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Forced clock offset, `t_wheel = t_truth + offset`. s. Default: estimated from the data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_offset_s: Option<f64>,
    /// CSV column names: keys `t`, `x`, `y`, `yaw`. Default: the columns named `t`, `x`, `y`, `yaw` (or a
    /// quaternion `qx`, `qy`, `qz`, `qw`).
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub columns: std::collections::BTreeMap<String, String>,
    /// CSV units: `time` (s, ms, us, ns), `length` (m, cm, mm), `angle` (rad, deg). Default s, m, rad.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub units: std::collections::BTreeMap<String, String>,
}
