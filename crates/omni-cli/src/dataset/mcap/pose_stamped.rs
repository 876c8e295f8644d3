//! `geometry_msgs/msg/PoseStamped` and `geometry_msgs/msg/PoseWithCovarianceStamped`: ground truth from a
//! motion-capture system or a simulator, expressed in `header.frame_id` (e.g. `map`, `world`, `mocap`).

use super::common::{
    Covariance, HEADER_DEF, Header, POINT_DEF, POSE_DEF, Pose, QUATERNION_DEF, Quaternion, TIME_DEF, Vector3,
    schema_text,
};
use super::poses::Fields;
use serde::{Deserialize, Serialize};

/// The schema name of PoseStamped.
pub(super) const NAME: &str = "geometry_msgs/msg/PoseStamped";
/// The schema name of PoseWithCovarianceStamped.
pub(super) const WITH_COVARIANCE_NAME: &str = "geometry_msgs/msg/PoseWithCovarianceStamped";

/// The schema name of PointStamped: a position without a heading (a tracker, a UWB or total-station
/// reference), read as a position-only ground truth.
pub(super) const POINT_NAME: &str = "geometry_msgs/msg/PointStamped";

/// `geometry_msgs/msg/PointStamped`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct PointStamped {
    pub header: Header,
    pub point: Vector3,
}

/// The heading a PointStamped's poses carry: none changes, so the run is position-only (the heading is a
/// placeholder, never compared).
pub(super) const NO_HEADING: Quaternion = Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 };

/// Field names of PointStamped, for messages.
pub(super) const POINT_FIELDS: Fields =
    Fields { stamp: "header.stamp", position: "point", orientation: "(none: positions only)" };

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
