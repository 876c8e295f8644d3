//! `geometry_msgs/msg/PoseStamped` and `geometry_msgs/msg/PoseWithCovarianceStamped`: ground truth from a
//! motion-capture system or a simulator, expressed in `header.frame_id` (e.g. `map`, `world`, `mocap`).

use super::common::{Covariance, HEADER_DEF, Header, POINT_DEF, POSE_DEF, Pose, QUATERNION_DEF, TIME_DEF, schema_text};
use super::poses::Fields;
use serde::{Deserialize, Serialize};

/// The schema name of PoseStamped.
pub(super) const NAME: &str = "geometry_msgs/msg/PoseStamped";
/// The schema name of PoseWithCovarianceStamped.
pub(super) const WITH_COVARIANCE_NAME: &str = "geometry_msgs/msg/PoseWithCovarianceStamped";

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct PoseStamped {
    pub header: Header,
    pub pose: Pose,
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct PoseWithCovariance {
    pub pose: Pose,
    pub covariance: Covariance,
}

/// `geometry_msgs/msg/PoseWithCovarianceStamped`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct PoseWithCovarianceStamped {
    pub header: Header,
    pub pose: PoseWithCovariance,
}

/// Field names of PoseStamped, for messages.
pub(super) const FIELDS: Fields =
    Fields { stamp: "header.stamp", position: "pose.position", orientation: "pose.orientation" };
/// Field names of PoseWithCovarianceStamped (and Odometry), for messages.
pub(super) const WITH_COVARIANCE_FIELDS: Fields =
    Fields { stamp: "header.stamp", position: "pose.pose.position", orientation: "pose.pose.orientation" };

/// The PoseStamped schema text, as rosbag2 writes it.
pub(super) fn schema() -> String {
    schema_text(
        "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
        &[&HEADER_DEF, &TIME_DEF, &POSE_DEF, &POINT_DEF, &QUATERNION_DEF],
    )
}
