//! The CDR building blocks shared by the message types: `builtin_interfaces/Time`, `std_msgs/Header`, the
//! geometry primitives, strings that decode without trusting their length prefix, and the `ros2msg` schema
//! text that rosbag2 stores with each type.
//!
//! Structs list their fields in `.msg` order: CDR has no field names, so the order *is* the format.

use serde::{Deserialize, Serialize, de};
use std::fmt;

/// Nanoseconds per second.
pub(super) const NS_PER_S: i64 = 1_000_000_000;

/// `builtin_interfaces/msg/Time`: seconds and nanoseconds since the epoch (or since sim-time start).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub(super) struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, `0..1e9`.
    pub nanosec: u32,
}

impl Time {
    /// The instant in nanoseconds.
    pub fn ns(self) -> i64 {
        i64::from(self.sec) * NS_PER_S + i64::from(self.nanosec)
    }

    /// The stamp for an instant in nanoseconds, when `sec` fits in an `int32`.
    pub fn from_ns(ns: i64) -> Option<Self> {
        let sec = i32::try_from(ns.div_euclid(NS_PER_S)).ok()?;
        let nanosec = u32::try_from(ns.rem_euclid(NS_PER_S)).ok()?;
        Some(Self { sec, nanosec })
    }
}

/// An instant in nanoseconds shown as `sec.nanosec`, e.g. `1700000000.250000000`.
pub(super) struct Stamp(pub i64);

impl fmt::Display for Stamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{:09}", self.0.div_euclid(NS_PER_S), self.0.rem_euclid(NS_PER_S))
    }
}

/// Seconds from `origin_s` (whole seconds) to the instant `ns`. Exact to the float64 rounding of the
/// fractional part, whatever the epoch.
pub(super) fn seconds_since(ns: i64, origin_s: i64) -> f64 {
    (ns.div_euclid(NS_PER_S) - origin_s) as f64 + ns.rem_euclid(NS_PER_S) as f64 * 1e-9
}

/// A CDR `string`. It decodes as a byte sequence, so a corrupted length prefix fails at the end of the
/// message instead of allocating up to 4 GiB first (as `cdr`'s own `String` decoding would).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(super) struct RosString(pub String);

impl Serialize for RosString {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.0)
    }
}

impl<'de> Deserialize<'de> for RosString {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Bytes;
        impl<'de> de::Visitor<'de> for Bytes {
            type Value = RosString;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a CDR string")
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<RosString, A::Error> {
                let mut bytes = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(64));
                while let Some(b) = seq.next_element::<u8>()? {
                    bytes.push(b);
                }
                if bytes.last() == Some(&0) {
                    bytes.pop();
                }
                String::from_utf8(bytes).map(RosString).map_err(|_| de::Error::custom("a string is not valid UTF-8"))
            }
        }
        d.deserialize_seq(Bytes)
    }
}

impl RosString {
    /// A frame id without the leading `/` that ROS 1 style publishers add (`/world` is `world`).
    pub fn frame(&self) -> &str {
        self.0.trim_start_matches('/')
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(super) struct Header {
    /// When the data was sampled.
    pub stamp: Time,
    /// The frame the data is expressed in.
    pub frame_id: RosString,
}

/// `geometry_msgs/msg/Vector3`, and `geometry_msgs/msg/Point` (the same layout).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(super) struct Vector3 {
    /// m or m/s or rad/s.
    pub x: f64,
    /// m or m/s or rad/s.
    pub y: f64,
    /// m or m/s or rad/s.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Quaternion {
    /// The rotation by `yaw_rad` about z.
    pub fn from_yaw(yaw_rad: f64) -> Self {
        let (s, c) = (0.5 * yaw_rad).sin_cos();
        Self { x: 0.0, y: 0.0, z: s, w: c }
    }

    /// Yaw (rotation about z, counter-clockwise) in (−π, π]: `atan2(2(wz + xy), w² + x² − y² − z²)`, which
    /// does not need a unit quaternion.
    pub fn yaw_rad(&self) -> f64 {
        let Self { x, y, z, w } = *self;
        (2.0 * (w * z + x * y)).atan2(w * w + x * x - y * y - z * z)
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct Pose {
    /// `geometry_msgs/Point`. m.
    pub position: Vector3,
    pub orientation: Quaternion,
}

impl Pose {
    /// A planar pose.
    pub fn planar(x_m: f64, y_m: f64, yaw_rad: f64) -> Self {
        Self { position: Vector3 { x: x_m, y: y_m, z: 0.0 }, orientation: Quaternion::from_yaw(yaw_rad) }
    }
}

/// `geometry_msgs/msg/Twist`: linear (m/s) and angular (rad/s) velocity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(super) struct Twist {
    pub linear: Vector3,
    pub angular: Vector3,
}

/// A row-major 6×6 covariance, `float64[36]` (nested arrays: serde derives arrays up to 32; the CDR layout is
/// the same).
pub(super) type Covariance = [[f64; 6]; 6];

/// What is wrong with a pose, if anything: the first non-finite component or a zero quaternion.
pub(super) fn pose_problem(
    position_field: &str,
    position: &Vector3,
    orientation_field: &str,
    q: &Quaternion,
) -> Option<String> {
    for (axis, v) in [("x", position.x), ("y", position.y)] {
        if !v.is_finite() {
            return Some(format!("field {position_field}.{axis} is {v}"));
        }
    }
    for (axis, v) in [("x", q.x), ("y", q.y), ("z", q.z), ("w", q.w)] {
        if !v.is_finite() {
            return Some(format!("field {orientation_field}.{axis} is {v}"));
        }
    }
    if q.x == 0.0 && q.y == 0.0 && q.z == 0.0 && q.w == 0.0 {
        return Some(format!("field {orientation_field} is not a rotation (x = y = z = w = 0)"));
    }
    None
}

/// Decodes one CDR message (4-byte encapsulation header, then the body; little- or big-endian).
pub(super) fn decode<'de, T: Deserialize<'de>>(data: &[u8]) -> Result<T, String> {
    cdr::deserialize_from(data, cdr::Bounded(data.len() as u64)).map_err(|e| match e {
        cdr::Error::SizeLimit => format!(
            "cannot decode CDR: the {}-byte message ends before its last field (cut short, or a length inside it \
             is corrupted); is the message type right?",
            data.len()
        ),
        e => format!("cannot decode CDR ({e}); is the message type right?"),
    })
}

/// Encodes one message as little-endian CDR with its encapsulation header, as ROS 2 publishes it.
pub(super) fn encode<T: Serialize>(msg: &T) -> Result<Vec<u8>, String> {
    cdr::serialize::<_, _, cdr::CdrLe>(msg, cdr::Infinite).map_err(|e| format!("cannot encode CDR: {e}"))
}

/// One `.msg` definition, by its short name (`std_msgs/Header`) as dependencies are named in schema text.
pub(super) struct MsgDef {
    /// `package/Type`.
    pub name: &'static str,
    /// The fields, one per line.
    pub text: &'static str,
}

/// `builtin_interfaces/Time`.
pub(super) const TIME_DEF: MsgDef = MsgDef { name: "builtin_interfaces/Time", text: "int32 sec\nuint32 nanosec\n" };
/// `std_msgs/Header`.
pub(super) const HEADER_DEF: MsgDef =
    MsgDef { name: "std_msgs/Header", text: "builtin_interfaces/Time stamp\nstring frame_id\n" };
/// `geometry_msgs/Vector3`.
pub(super) const VECTOR3_DEF: MsgDef =
    MsgDef { name: "geometry_msgs/Vector3", text: "float64 x\nfloat64 y\nfloat64 z\n" };
/// `geometry_msgs/Point`.
pub(super) const POINT_DEF: MsgDef = MsgDef { name: "geometry_msgs/Point", text: "float64 x\nfloat64 y\nfloat64 z\n" };
/// `geometry_msgs/Quaternion`.
pub(super) const QUATERNION_DEF: MsgDef =
    MsgDef { name: "geometry_msgs/Quaternion", text: "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n" };
/// `geometry_msgs/Pose`.
pub(super) const POSE_DEF: MsgDef =
    MsgDef { name: "geometry_msgs/Pose", text: "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n" };
/// `geometry_msgs/Twist`.
pub(super) const TWIST_DEF: MsgDef =
    MsgDef { name: "geometry_msgs/Twist", text: "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n" };

/// Schema text as rosbag2 stores it (`ros2msg`): the type's own fields, then each type it uses, depth first
/// and once, after a line of 80 `=` and a `MSG: package/Type` line.
pub(super) fn schema_text(fields: &str, deps: &[&MsgDef]) -> String {
    let mut s = String::from(fields);
    for d in deps {
        s.push_str(&"=".repeat(80));
        s.push_str("\nMSG: ");
        s.push_str(d.name);
        s.push('\n');
        s.push_str(d.text);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_round_trips_and_ignores_scale() {
        for yaw in [-3.0, -1.0, 0.0, 0.5, 3.1] {
            let q = Quaternion::from_yaw(yaw);
            assert!((q.yaw_rad() - yaw).abs() < 1e-15);
            let s = Quaternion { x: 3.0 * q.x, y: 3.0 * q.y, z: 3.0 * q.z, w: 3.0 * q.w };
            assert!((s.yaw_rad() - yaw).abs() < 1e-15);
        }
    }

    #[test]
    fn stamps_convert_exactly() {
        let t = Time { sec: 1_700_000_000, nanosec: 250_000_001 };
        assert_eq!(Time::from_ns(t.ns()), Some(t));
        assert_eq!(Stamp(t.ns()).to_string(), "1700000000.250000001");
        assert_eq!(seconds_since(t.ns(), 1_700_000_000), 0.250000001);
        assert_eq!(Time::from_ns(-1), Some(Time { sec: -1, nanosec: 999_999_999 }));
    }

    #[test]
    fn strings_round_trip_and_a_huge_length_fails_cleanly() {
        let h = Header { stamp: Time { sec: 1, nanosec: 2 }, frame_id: RosString("map".into()) };
        let bytes = encode(&h).unwrap();
        assert_eq!(bytes, [0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 4, 0, 0, 0, b'm', b'a', b'p', 0]);
        assert_eq!(decode::<Header>(&bytes).unwrap(), h);
        let mut bad = bytes.clone();
        bad[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode::<Header>(&bad).is_err());
    }
}
