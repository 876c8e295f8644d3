//! `geometry_msgs/msg/Twist` and `geometry_msgs/msg/TwistStamped` on `/cmd_vel`: the motion command, a
//! body-frame twist (x forward, y left, yaw counter-clockwise; m/s and rad/s).
//!
//! A run keeps the **first non-zero command** as its [`Command`]: `v = hypot(vx, vy)`, `α = atan2(vy, vx)`,
//! `ω = wz` (the paper's (v, α, ω)). Twist has no header, so its time is the log time.

use super::common::{HEADER_DEF, Header, TIME_DEF, TWIST_DEF, Twist, VECTOR3_DEF, schema_text};
use omni_kin::Command;
use serde::{Deserialize, Serialize};

/// The schema name of Twist.
pub(super) const NAME: &str = "geometry_msgs/msg/Twist";
/// The schema name of TwistStamped.
pub(super) const STAMPED_NAME: &str = "geometry_msgs/msg/TwistStamped";

/// Components at or below this are zero. m/s, rad/s.
const ZERO: f64 = 1e-9;

/// `geometry_msgs/msg/TwistStamped`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct TwistStamped {
    pub header: Header,
    pub twist: Twist,
}

/// The Twist schema text, as rosbag2 writes it.
pub(super) fn schema() -> String {
    schema_text("geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n", &[&VECTOR3_DEF])
}

/// The TwistStamped schema text, as rosbag2 writes it.
pub(super) fn stamped_schema() -> String {
    schema_text(
        "std_msgs/Header header\ngeometry_msgs/Twist twist\n",
        &[&HEADER_DEF, &TIME_DEF, &TWIST_DEF, &VECTOR3_DEF],
    )
}

/// The non-zero commands of one topic.
#[derive(Debug, Default)]
pub(super) struct Commands {
    /// Time (header stamp, or log time for Twist) and command, in message order.
    pub nonzero: Vec<(i64, Command)>,
}

impl Commands {
    /// Takes one command, or says what is wrong with it.
    pub fn push(&mut self, t_ns: i64, twist: &Twist) -> Result<(), String> {
        let (vx, vy, wz) = (twist.linear.x, twist.linear.y, twist.angular.z);
        for (field, v) in [("linear.x", vx), ("linear.y", vy), ("angular.z", wz)] {
            if !v.is_finite() {
                return Err(format!("field {field} is {v}"));
            }
        }
        if vx.abs() > ZERO || vy.abs() > ZERO || wz.abs() > ZERO {
            self.nonzero.push((t_ns, Command { v_m_s: vx.hypot(vy), alpha_rad: vy.atan2(vx), omega_rad_s: wz }));
        }
        Ok(())
    }

    /// The first non-zero command in `[from_ns, to_ns]`.
    pub fn first_in(&self, from_ns: i64, to_ns: i64) -> Option<Command> {
        self.nonzero.iter().find(|(t, _)| (from_ns..=to_ns).contains(t)).map(|&(_, c)| c)
    }
}

/// The twist of a command: the inverse of what [`Commands::push`] keeps.
pub(super) fn twist_of(c: &Command) -> Twist {
    let (s, co) = c.alpha_rad.sin_cos();
    let mut t = Twist::default();
    t.linear.x = c.v_m_s * co;
    t.linear.y = c.v_m_s * s;
    t.angular.z = c.omega_rad_s;
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_first_nonzero_command_as_v_alpha_omega() {
        let mut c = Commands::default();
        c.push(0, &Twist::default()).unwrap();
        let mut t = Twist::default();
        (t.linear.x, t.linear.y, t.angular.z) = (0.3, 0.3, -1.0);
        c.push(5, &t).unwrap();
        let first = c.first_in(0, 10).unwrap();
        assert!((first.v_m_s - 0.3 * 2f64.sqrt()).abs() < 1e-15);
        assert!((first.alpha_rad - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
        assert_eq!(first.omega_rad_s, -1.0);
        assert_eq!(c.first_in(6, 10), None);
        let back = twist_of(&first);
        assert!((back.linear.x - 0.3).abs() < 1e-15 && (back.linear.y - 0.3).abs() < 1e-15);
        t.linear.y = f64::NAN;
        assert_eq!(c.push(6, &t).unwrap_err(), "field linear.y is NaN");
    }
}
