//! `sensor_msgs/msg/JointState`: the wheel speeds.
//!
//! Joints are matched **by name** to the wheel order (the arrays are parallel to `name`, each either as long
//! or empty). Velocity is rad/s; when a message has no velocity, the speeds come from position (rad)
//! differentiated over `header.stamp`: sample `k` covers `(t_{k−1}, t_k]` (omni-kin's convention), so
//! `v_k = (p_k − p_{k−1}) / (t_k − t_{k−1})`, and the first sample takes the second's speed.

use super::common::{HEADER_DEF, Header, RosString, Stamp, TIME_DEF, schema_text};
use serde::{Deserialize, Serialize};

/// The schema name.
pub(super) const NAME: &str = "sensor_msgs/msg/JointState";

/// `sensor_msgs/msg/JointState`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(super) struct JointState {
    pub header: Header,
    pub name: Vec<RosString>,
    /// rad.
    pub position: Vec<f64>,
    /// rad/s.
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// The schema text, as rosbag2 writes it.
pub(super) fn schema() -> String {
    schema_text(
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
        &[&HEADER_DEF, &TIME_DEF],
    )
}

/// The wheel joints of one topic, gathered message by message.
#[derive(Debug, Default)]
pub(super) struct JointSeries {
    /// `header.stamp` of each message. ns.
    pub t_ns: Vec<i64>,
    /// Wheel speeds, `messages × wheels` in wheel order (NaN where a message has no velocity). rad/s.
    velocity: Vec<f64>,
    /// Wheel angles, the same shape (NaN where a message has no position). rad.
    position: Vec<f64>,
    /// The first message without velocity, and the first without position.
    first_without_velocity: Option<usize>,
    first_without_position: Option<usize>,
    /// Messages without velocity.
    without_velocity: usize,
    /// The joint names of the last message and where each wheel joint is among them, reused while the
    /// names stay the same (they almost always do).
    names: Vec<RosString>,
    index: Vec<usize>,
}

/// Wheel data ready to build runs from.
#[derive(Debug)]
pub(super) struct Wheels {
    /// Stamps. ns.
    pub t_ns: Vec<i64>,
    /// Speeds, `samples × wheels`. rad/s.
    pub rad_s: Vec<f64>,
    /// Angles, `samples × wheels`, when every message has them. rad.
    pub position: Option<Vec<f64>>,
    /// Messages without velocity, when the speeds were differentiated from position.
    pub differentiated: Option<usize>,
}

impl JointSeries {
    /// Messages taken so far.
    pub fn len(&self) -> usize {
        self.t_ns.len()
    }

    /// Takes message number `self.len()`, or says what is wrong with it.
    pub fn push(&mut self, msg: JointState, wheel_joints: &[String]) -> Result<(), String> {
        let n = msg.name.len();
        for (field, len) in [("position", msg.position.len()), ("velocity", msg.velocity.len())] {
            if len != 0 && len != n {
                return Err(format!("field {field} has {len} entries, expected {n} (one per name) or none"));
            }
        }
        if msg.velocity.is_empty() && msg.position.is_empty() {
            return Err("fields velocity and position are both empty".into());
        }
        if msg.name != self.names {
            self.index.clear();
            for joint in wheel_joints {
                match msg.name.iter().position(|name| name.0 == *joint) {
                    Some(i) => self.index.push(i),
                    None => {
                        let names: Vec<&str> = msg.name.iter().map(|s| s.0.as_str()).collect();
                        return Err(format!("wheel joint {joint:?} is missing (names: {})", names.join(", ")));
                    }
                }
            }
            self.names = msg.name;
        }
        let t = msg.header.stamp.ns();
        if let Some(&prev) = self.t_ns.last()
            && t <= prev
        {
            return Err(format!(
                "header.stamp {} is not after the previous message's {} (stamps must increase)",
                Stamp(t),
                Stamp(prev)
            ));
        }
        let k = self.t_ns.len();
        self.t_ns.push(t);
        for (values, out, first_without) in [
            (&msg.velocity, &mut self.velocity, &mut self.first_without_velocity),
            (&msg.position, &mut self.position, &mut self.first_without_position),
        ] {
            if values.is_empty() {
                out.extend(self.index.iter().map(|_| f64::NAN));
                first_without.get_or_insert(k);
            } else {
                out.extend(self.index.iter().map(|&i| values[i]));
            }
        }
        if msg.velocity.is_empty() {
            self.without_velocity += 1;
        }
        Ok(())
    }

    /// The wheel data, given the stamps in seconds (`t_s[k]` for message `k`); `Err((message, problem))`.
    pub fn finish(self, wheel_joints: &[String], t_s: &[f64]) -> Result<Wheels, (usize, String)> {
        let w = wheel_joints.len();
        let position = self.first_without_position.is_none().then_some(self.position);
        let (rad_s, differentiated) = match (self.first_without_velocity, position.as_ref()) {
            (None, _) => (self.velocity, None),
            (Some(_), Some(p)) => (differentiate(t_s, p, w), Some(self.without_velocity)),
            (Some(j), None) => {
                let k = self.first_without_position.unwrap_or_default();
                return Err((
                    k,
                    format!(
                        "field position is empty, but message {j} has no velocity, so wheel speeds must come \
                         from positions"
                    ),
                ));
            }
        };
        let used =
            if differentiated.is_some() { ("position", position.as_deref()) } else { ("velocity", Some(&rad_s[..])) };
        if let (field, Some(values)) = used
            && let Some(i) = values.iter().position(|v| !v.is_finite())
        {
            let (k, j) = (i / w, i % w);
            return Err((k, format!("field {field}[{}] (joint {:?}) is {}", j, wheel_joints[j], values[i])));
        }
        Ok(Wheels { t_ns: self.t_ns, rad_s, position, differentiated })
    }
}

/// Backward differences of `position` (`samples × w`) over `t_s`; the first sample takes the second's.
fn differentiate(t_s: &[f64], position: &[f64], w: usize) -> Vec<f64> {
    let n = t_s.len();
    let mut v = vec![0.0; n * w];
    for k in 1..n {
        let dt = t_s[k] - t_s[k - 1];
        for j in 0..w {
            v[k * w + j] = (position[k * w + j] - position[(k - 1) * w + j]) / dt;
        }
    }
    if n > 1 {
        v.copy_within(w..2 * w, 0);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::mcap::common::Time;

    fn wheels() -> Vec<String> {
        ["wheel_a", "wheel_b", "wheel_c"].map(String::from).to_vec()
    }

    fn msg(ns: i64, names: &[&str], position: &[f64], velocity: &[f64]) -> JointState {
        JointState {
            header: Header { stamp: Time::from_ns(ns).unwrap(), frame_id: RosString::default() },
            name: names.iter().map(|s| RosString(s.to_string())).collect(),
            position: position.to_vec(),
            velocity: velocity.to_vec(),
            effort: vec![],
        }
    }

    #[test]
    fn maps_joints_by_name() {
        let mut s = JointSeries::default();
        s.push(msg(0, &["x", "wheel_c", "wheel_a", "wheel_b"], &[], &[9.0, 3.0, 1.0, 2.0]), &wheels()).unwrap();
        s.push(msg(10, &["wheel_b", "wheel_a", "wheel_c"], &[], &[5.0, 4.0, 6.0]), &wheels()).unwrap();
        let w = s.finish(&wheels(), &[0.0, 1e-8]).unwrap();
        assert_eq!(w.rad_s, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(w.differentiated, None);
        assert_eq!(w.position, None);
    }

    #[test]
    fn differentiates_position_when_velocity_is_empty() {
        let mut s = JointSeries::default();
        let names = ["wheel_a", "wheel_b", "wheel_c"];
        s.push(msg(0, &names, &[0.0, 0.0, 0.0], &[]), &wheels()).unwrap();
        s.push(msg(500_000_000, &names, &[1.0, -2.0, 0.5], &[]), &wheels()).unwrap();
        s.push(msg(1_000_000_000, &names, &[2.0, -4.0, 0.5], &[]), &wheels()).unwrap();
        let w = s.finish(&wheels(), &[0.0, 0.5, 1.0]).unwrap();
        assert_eq!(w.rad_s, [2.0, -4.0, 1.0, 2.0, -4.0, 1.0, 2.0, -4.0, 0.0]);
        assert_eq!(w.differentiated, Some(3));
    }

    #[test]
    fn problems_name_the_field() {
        let mut s = JointSeries::default();
        let e = s.push(msg(0, &["wheel_a", "wheel_b"], &[], &[1.0, 2.0]), &wheels()).unwrap_err();
        assert_eq!(e, "wheel joint \"wheel_c\" is missing (names: wheel_a, wheel_b)");
        let e = s.push(msg(0, &["wheel_a", "wheel_b", "wheel_c"], &[], &[1.0, 2.0]), &wheels()).unwrap_err();
        assert_eq!(e, "field velocity has 2 entries, expected 3 (one per name) or none");
        let names = ["wheel_a", "wheel_b", "wheel_c"];
        s.push(msg(5, &names, &[], &[1.0, f64::NAN, 2.0]), &wheels()).unwrap();
        let e = s.push(msg(5, &names, &[], &[1.0, 1.0, 2.0]), &wheels()).unwrap_err();
        assert_eq!(
            e,
            "header.stamp 0.000000005 is not after the previous message's 0.000000005 (stamps must increase)"
        );
        s.push(msg(6, &names, &[], &[1.0, 1.0, 2.0]), &wheels()).unwrap();
        let e = s.finish(&wheels(), &[0.0, 1e-9]).unwrap_err();
        assert_eq!(e, (0, "field velocity[1] (joint \"wheel_b\") is NaN".to_string()));
    }
}
