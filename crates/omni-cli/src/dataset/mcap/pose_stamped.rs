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

/// The schema name of NavSatFix: a GNSS fix (latitude, longitude, altitude on WGS 84), read as a
/// position-only ground truth in a local east-north-up frame ([`NavSatFix::east_north_up`]).
pub(super) const NAV_SAT_FIX_NAME: &str = "sensor_msgs/msg/NavSatFix";

/// `sensor_msgs/msg/NavSatStatus`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct NavSatStatus {
    /// -1: no fix; 0: a fix; 1: satellite-based augmentation; 2: ground-based augmentation (RTK).
    pub status: i8,
    /// The constellations used (a bit mask).
    pub service: u16,
}

/// `sensor_msgs/msg/NavSatFix`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct NavSatFix {
    pub header: Header,
    pub status: NavSatStatus,
    /// Degrees, positive north.
    pub latitude: f64,
    /// Degrees, positive east.
    pub longitude: f64,
    /// Metres above the WGS 84 ellipsoid.
    pub altitude: f64,
    /// m², east-north-up, row-major.
    pub position_covariance: [f64; 9],
    pub position_covariance_type: u8,
}

/// Field names of NavSatFix, for messages.
pub(super) const NAV_SAT_FIX_FIELDS: Fields =
    Fields { stamp: "header.stamp", position: "latitude, longitude", orientation: "(none: positions only)" };

impl NavSatFix {
    /// Whether the receiver had a fix (`status.status` ≥ 0): a message without one carries no position.
    pub fn has_fix(&self) -> bool {
        self.status.status >= 0
    }

    /// The fix as latitude, longitude (degrees) and altitude (m), checked: a latitude beyond ±90°, a
    /// longitude beyond ±180° or a value that is not finite is an error naming the field.
    pub fn geodetic(&self) -> Result<[f64; 3], String> {
        let checks = [("latitude", self.latitude, 90.0), ("longitude", self.longitude, 180.0)];
        for (name, v, limit) in checks {
            if !v.is_finite() || v.abs() > limit {
                return Err(format!("{name} {v} is not a position in degrees (within ±{limit})"));
            }
        }
        if !self.altitude.is_finite() {
            return Err(format!("altitude {} is not finite", self.altitude));
        }
        Ok([self.latitude, self.longitude, self.altitude])
    }

    /// The fix's position east, north and up of `origin` (latitude, longitude in degrees, altitude in m),
    /// in metres, on the WGS 84 ellipsoid (REP 103's local ENU frame).
    pub fn east_north_up(fix: [f64; 3], origin: [f64; 3]) -> Vector3 {
        let (e, n, u) = map_3d::geodetic2enu(
            fix[0].to_radians(),
            fix[1].to_radians(),
            fix[2],
            origin[0].to_radians(),
            origin[1].to_radians(),
            origin[2],
            map_3d::Ellipsoid::WGS84,
        );
        Vector3 { x: e, y: n, z: u }
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::mcap::common::{RosString, Time};

    fn fix(status: i8, latitude: f64, longitude: f64) -> NavSatFix {
        NavSatFix {
            header: Header { stamp: Time::default(), frame_id: RosString("gps".into()) },
            status: NavSatStatus { status, service: 1 },
            latitude,
            longitude,
            altitude: 400.0,
            position_covariance: [0.0; 9],
            position_covariance_type: 0,
        }
    }

    #[test]
    fn a_fix_is_metres_east_and_north_of_the_first_and_a_bad_one_names_its_field() {
        let origin = fix(0, 47.0, 8.0).geodetic().unwrap();
        // At 47° N a degree of latitude is 111.2 km on WGS 84, one of longitude 76.0 km (cos 47° of the
        // prime vertical radius).
        let p = NavSatFix::east_north_up(fix(0, 47.0001, 8.0001).geodetic().unwrap(), origin);
        assert!((p.y - 11.120).abs() < 0.01 && (p.x - 7.602).abs() < 0.01, "{p:?}");
        assert!(!fix(-1, f64::NAN, 0.0).has_fix() && fix(2, 47.0, 8.0).has_fix());
        assert_eq!(fix(0, 95.0, 8.0).geodetic().unwrap_err(), "latitude 95 is not a position in degrees (within ±90)");
        assert!(fix(0, 47.0, f64::NAN).geodetic().unwrap_err().starts_with("longitude NaN"));
    }
}
