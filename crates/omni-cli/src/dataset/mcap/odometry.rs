//! `nav_msgs/msg/Odometry`: either the robot's own wheel odometry (REP-105: `header.frame_id` `odom`, child
//! `base_link`, typically on `/odom`), which is the model under test and never ground truth, or a ground
//! truth from a simulator or tracker in a world frame (`map`, `world`, …).
//!
//! The pose is in `header.frame_id`; the twist is in `child_frame_id` (body frame).

use super::common::{
    Covariance, HEADER_DEF, Header, MsgDef, POINT_DEF, POSE_DEF, QUATERNION_DEF, RosString, TIME_DEF, TWIST_DEF, Twist,
    VECTOR3_DEF, schema_text,
};
use super::pose_stamped::PoseWithCovariance;
use serde::{Deserialize, Serialize};

/// The schema name.
pub(super) const NAME: &str = "nav_msgs/msg/Odometry";

/// The frame of wheel odometry (REP-105).
pub(super) const ODOM_FRAME: &str = "odom";
/// The robot's body frame (REP-105).
pub(super) const BASE_FRAME: &str = "base_link";

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct TwistWithCovariance {
    pub twist: Twist,
    pub covariance: Covariance,
}

/// `nav_msgs/msg/Odometry`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct Odometry {
    pub header: Header,
    pub child_frame_id: RosString,
    pub pose: PoseWithCovariance,
    pub twist: TwistWithCovariance,
}

/// The schema text, as rosbag2 writes it.
pub(super) fn schema() -> String {
    const POSE_WITH_COVARIANCE: MsgDef =
        MsgDef { name: "geometry_msgs/PoseWithCovariance", text: "geometry_msgs/Pose pose\nfloat64[36] covariance\n" };
    const TWIST_WITH_COVARIANCE: MsgDef = MsgDef {
        name: "geometry_msgs/TwistWithCovariance",
        text: "geometry_msgs/Twist twist\nfloat64[36] covariance\n",
    };
    schema_text(
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n\
         geometry_msgs/TwistWithCovariance twist\n",
        &[
            &HEADER_DEF,
            &TIME_DEF,
            &POSE_WITH_COVARIANCE,
            &POSE_DEF,
            &POINT_DEF,
            &QUATERNION_DEF,
            &TWIST_WITH_COVARIANCE,
            &TWIST_DEF,
            &VECTOR3_DEF,
        ],
    )
}
