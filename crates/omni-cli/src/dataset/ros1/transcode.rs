//! ROS 1 serialization → ROS 2 CDR, for the message types omnical reads, so that a ROS 1 bag feeds the same
//! decoders as MCAP and rosbag2.
//!
//! ROS 1 is little-endian without alignment; strings and variable arrays carry a u32 length (strings
//! without a terminating NUL); `std_msgs/Header` starts with a `seq` u32 that ROS 2 dropped, and `time` is
//! two u32 (ROS 2: i32 seconds, u32 nanoseconds). CDR (little-endian, encapsulation `00 01 00 00`) aligns
//! each primitive to its size from the end of the encapsulation header and ends strings with a NUL.

/// A field of a message, as both serializations lay it out.
#[derive(Clone, Copy)]
pub(super) enum Field {
    /// `std_msgs/Header`.
    Header,
    /// `string`.
    Str,
    /// `float64[N]` (N = 1 for a plain float64).
    F64(usize),
    /// `float64[]`.
    F64Seq,
    /// `float32[N]` (N = 1 for a plain float32).
    F32(usize),
    /// `float32[]`.
    F32Seq,
    /// `uint8` or `int8`.
    U8,
    /// `uint16`.
    U16,
    /// `string[]`.
    StrSeq,
    /// `geometry_msgs/TransformStamped[]`.
    TransformSeq,
}

use Field::*;

/// `geometry_msgs/TransformStamped`: header, child_frame_id, translation (3), rotation (4).
const TRANSFORM_STAMPED: &[Field] = &[Header, Str, F64(3), F64(4)];

/// The layout of a ROS 1 message type (`sensor_msgs/JointState`), and its ROS 2 name; `None` for a type
/// omnical does not read.
pub(super) fn layout(ros1_type: &str) -> Option<(&'static str, &'static [Field])> {
    Some(match ros1_type {
        "sensor_msgs/JointState" => ("sensor_msgs/msg/JointState", &[Header, StrSeq, F64Seq, F64Seq, F64Seq]),
        "geometry_msgs/PoseStamped" => ("geometry_msgs/msg/PoseStamped", &[Header, F64(3), F64(4)]),
        "geometry_msgs/PointStamped" => ("geometry_msgs/msg/PointStamped", &[Header, F64(3)]),
        "sensor_msgs/NavSatFix" => ("sensor_msgs/msg/NavSatFix", &[Header, U8, U16, F64(3), F64(9), U8]),
        "geometry_msgs/PoseWithCovarianceStamped" => {
            ("geometry_msgs/msg/PoseWithCovarianceStamped", &[Header, F64(3), F64(4), F64(36)])
        }
        "nav_msgs/Odometry" => ("nav_msgs/msg/Odometry", &[Header, Str, F64(3), F64(4), F64(36), F64(6), F64(36)]),
        "tf2_msgs/TFMessage" | "tf/tfMessage" => ("tf2_msgs/msg/TFMessage", &[TransformSeq]),
        "geometry_msgs/Twist" => ("geometry_msgs/msg/Twist", &[F64(6)]),
        "geometry_msgs/TwistStamped" => ("geometry_msgs/msg/TwistStamped", &[Header, F64(6)]),
        "sensor_msgs/Imu" => ("sensor_msgs/msg/Imu", &[Header, F64(4), F64(9), F64(3), F64(9), F64(3), F64(9)]),
        "sensor_msgs/LaserScan" => ("sensor_msgs/msg/LaserScan", &[Header, F32(7), F32Seq, F32Seq]),
        _ => return None,
    })
}

/// Reads ROS 1 bytes.
struct Ros1<'a> {
    data: &'a [u8],
    at: usize,
}

impl Ros1<'_> {
    fn bytes(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len()).ok_or_else(|| {
            format!("the message is cut short: {} bytes, field at byte {} needs {n} more", self.data.len(), self.at)
        })?;
        let b = &self.data[self.at..end];
        self.at = end;
        Ok(b)
    }
    fn u32(&mut self) -> Result<u32, String> {
        let b = self.bytes(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

/// Writes CDR bytes.
struct Cdr(Vec<u8>);

impl Cdr {
    /// Pads to a multiple of `n` from the end of the 4-byte encapsulation header.
    fn align(&mut self, n: usize) {
        while !(self.0.len() - 4).is_multiple_of(n) {
            self.0.push(0);
        }
    }
    fn u32(&mut self, v: u32) {
        self.align(4);
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn str(&mut self, s: &[u8]) {
        self.u32(s.len() as u32 + 1);
        self.0.extend_from_slice(s);
        self.0.push(0);
    }
    /// float32 values.
    fn f32s(&mut self, b: &[u8]) {
        if !b.is_empty() {
            self.align(4);
            self.0.extend_from_slice(b);
        }
    }
    /// float64 values (none: no padding either, as CDR writers do for an empty sequence).
    fn f64s(&mut self, b: &[u8]) {
        if !b.is_empty() {
            self.align(8);
            self.0.extend_from_slice(b);
        }
    }
}

/// The CDR bytes of the ROS 1 message `data` laid out as `fields`, or what is wrong with it.
pub(super) fn to_cdr(data: &[u8], fields: &[Field]) -> Result<Vec<u8>, String> {
    let mut r = Ros1 { data, at: 0 };
    let mut w = Cdr(vec![0, 1, 0, 0]);
    fields_to_cdr(&mut r, &mut w, fields)?;
    if r.at != data.len() {
        return Err(format!("{} bytes are left after the message's last field", data.len() - r.at));
    }
    Ok(w.0)
}

fn fields_to_cdr(r: &mut Ros1<'_>, w: &mut Cdr, fields: &[Field]) -> Result<(), String> {
    for f in fields {
        match *f {
            Header => {
                r.u32()?; // seq
                let (sec, nsec) = (r.u32()?, r.u32()?);
                w.u32(sec);
                w.u32(nsec);
                let n = r.u32()? as usize;
                w.str(r.bytes(n)?);
            }
            Str => {
                let n = r.u32()? as usize;
                w.str(r.bytes(n)?);
            }
            F64(n) => w.f64s(r.bytes(8 * n)?),
            F64Seq => {
                let n = r.u32()?;
                w.u32(n);
                w.f64s(r.bytes(8 * n as usize)?);
            }
            F32(n) => w.f32s(r.bytes(4 * n)?),
            U8 => w.0.extend_from_slice(r.bytes(1)?),
            U16 => {
                let b = r.bytes(2)?;
                w.align(2);
                w.0.extend_from_slice(b);
            }
            F32Seq => {
                let n = r.u32()?;
                w.u32(n);
                w.f32s(r.bytes(4 * n as usize)?);
            }
            StrSeq => {
                let n = r.u32()?;
                w.u32(n);
                for _ in 0..n {
                    let len = r.u32()? as usize;
                    w.str(r.bytes(len)?);
                }
            }
            TransformSeq => {
                let n = r.u32()?;
                w.u32(n);
                for _ in 0..n {
                    fields_to_cdr(r, w, TRANSFORM_STAMPED)?;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn laser_scan_becomes_cdr_with_float32_alignment() {
        let Some((name, fields)) = layout("sensor_msgs/LaserScan") else { panic!("no LaserScan layout") };
        assert_eq!(name, "sensor_msgs/msg/LaserScan");
        // ROS 1: seq, stamp (sec, nsec), frame "laser", 7 float32, ranges [1.5, inf], intensities [].
        let mut ros1 = Vec::new();
        for v in [9u32, 5, 7, 5] {
            ros1.extend_from_slice(&v.to_le_bytes());
        }
        ros1.extend_from_slice(b"laser");
        for v in [-3.0f32, 3.0, 0.5, 0.0, 0.1, 0.05, 12.0] {
            ros1.extend_from_slice(&v.to_le_bytes());
        }
        ros1.extend_from_slice(&2u32.to_le_bytes());
        ros1.extend_from_slice(&1.5f32.to_le_bytes());
        ros1.extend_from_slice(&f32::INFINITY.to_le_bytes());
        ros1.extend_from_slice(&0u32.to_le_bytes());
        // CDR: encapsulation, stamp, frame with its NUL (6 bytes, then 2 of padding to the float32s), the
        // float32s, the sequences with their lengths.
        let mut cdr = vec![0u8, 1, 0, 0];
        for v in [5u32, 7, 6] {
            cdr.extend_from_slice(&v.to_le_bytes());
        }
        cdr.extend_from_slice(b"laser\0\0\0");
        for v in [-3.0f32, 3.0, 0.5, 0.0, 0.1, 0.05, 12.0] {
            cdr.extend_from_slice(&v.to_le_bytes());
        }
        cdr.extend_from_slice(&2u32.to_le_bytes());
        cdr.extend_from_slice(&1.5f32.to_le_bytes());
        cdr.extend_from_slice(&f32::INFINITY.to_le_bytes());
        cdr.extend_from_slice(&0u32.to_le_bytes());
        assert_eq!(to_cdr(&ros1, fields).unwrap(), cdr);
        assert_eq!(
            to_cdr(&ros1[..ros1.len() - 6], fields).unwrap_err(),
            "the message is cut short: 59 bytes, field at byte 53 needs 8 more"
        );
    }

    #[test]
    fn nav_sat_fix_becomes_cdr_with_its_status_bytes_aligned() {
        let Some((name, fields)) = layout("sensor_msgs/NavSatFix") else { panic!("no NavSatFix layout") };
        assert_eq!(name, "sensor_msgs/msg/NavSatFix");
        // ROS 1: seq, stamp, frame "gps", status −1 (int8), service 1 (uint16), latitude, longitude, altitude,
        // 9 covariances, covariance type 2 (uint8).
        let mut ros1 = Vec::new();
        for v in [9u32, 5, 7, 3] {
            ros1.extend_from_slice(&v.to_le_bytes());
        }
        ros1.extend_from_slice(b"gps");
        ros1.push(0xff);
        ros1.extend_from_slice(&1u16.to_le_bytes());
        let doubles: Vec<f64> = (0..12).map(f64::from).collect();
        doubles.iter().for_each(|v| ros1.extend_from_slice(&v.to_le_bytes()));
        ros1.push(2);
        // CDR: encapsulation, stamp, "gps" with its NUL (ends at byte 16 from the encapsulation), the status
        // byte, one of padding, the service, 4 of padding to the float64s, the covariance type.
        let mut cdr = vec![0u8, 1, 0, 0];
        for v in [5u32, 7, 4] {
            cdr.extend_from_slice(&v.to_le_bytes());
        }
        cdr.extend_from_slice(b"gps\0");
        cdr.extend_from_slice(&[0xff, 0, 1, 0, 0, 0, 0, 0]);
        doubles.iter().for_each(|v| cdr.extend_from_slice(&v.to_le_bytes()));
        cdr.push(2);
        assert_eq!(to_cdr(&ros1, fields).unwrap(), cdr);
    }
}
