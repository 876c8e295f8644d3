//! `sensor_msgs/msg/JointState`: the wheel speeds.
//!
//! Joints are matched **by name** to the wheel order (the arrays are parallel to `name`, each either as long
//! or empty). Velocity is rad/s; when a message has no velocity, the speeds come from position (rad)
//! differentiated over `header.stamp`: sample `k` covers `(t_{k−1}, t_k]` (omni-kin's convention), so
//! `v_k = (p_k − p_{k−1}) / (t_k − t_{k−1})`, and the first sample takes the second's speed.
//!
//! Topics as real systems publish them (each case counted and named in a note, never silent):
//! - several publishers on one topic (an arm's and the base's `joint_state_broadcaster`): a message that
//!   names none of the wheel joints belongs to another publisher and is passed over;
//! - a message repeated exactly (same stamp, same values: a relay or a recorder subscribed twice) is
//!   dropped;
//! - `header.stamp` 0 on the first two messages (a driver that never fills it): the whole topic is
//!   stamped by its log time instead;
//! - a wheel velocity that is NaN in a message that has the wheel positions (ros2_control on
//!   position-only wheels): the speeds come from the positions, as for an empty velocity;
//! - positions that wrap (an encoder angle reported modulo 2π, in [−π, π] or [0, 2π]): unwrapped before
//!   they are differentiated;
//! - a wheel joint named twice in a message (a stale copy beside the live one): the copy that changes is
//!   read ([`repair::resolve_copies`]);
//! - a wheel joint missing from a message now and then: filled from the neighbouring messages, a long gap
//!   refused ([`repair::fill_gaps`]);
//! - `position` and `velocity` that give different wheel rates (motor rpm beside wheel encoder counts):
//!   refused unless `[wheel_data] source` names the field to read ([`fields`]).

mod fields;
mod repair;

use super::common::{HEADER_DEF, Header, RosString, Stamp, TIME_DEF, schema_text};
use omni_kin::robot::{WheelData, WheelField};
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
    index: Vec<Option<usize>>,
    /// Wheel joints named twice or missing (boxed: a topic's content stays small).
    entries: Box<Entries>,
    /// Messages passed over: naming no wheel joint (another publisher), and exact repeats.
    other_publisher: usize,
    /// Messages pushed, and the first passed over for naming no wheel joint (its index, and which joint is
    /// missing): the error when no message names one.
    seen: usize,
    first_other: Option<(usize, String)>,
    duplicates: usize,
    /// Messages stamped by log time (`header.stamp` 0 on the first two messages), and the first message's
    /// log time. ns.
    by_log_time: bool,
    first_log_ns: i64,
    /// Messages whose wheel velocity was NaN and whose speeds come from positions.
    nan_velocity: usize,
}

/// Wheel joints named twice in a message, or missing from one.
#[derive(Debug, Default)]
struct Entries {
    /// Where a wheel joint named twice in the last names has its other entry (the first; `index` holds the
    /// last).
    other_entry: Vec<Option<usize>>,
    /// The other entries' values of wheel joints named twice, message by message.
    copies: Vec<repair::Copy>,
    /// Samples `(message, wheel)` where a wheel joint was missing, and per wheel the first such message's
    /// problem (`wheel joint "x" is missing (names: …)`).
    missing: Vec<(usize, usize)>,
    missing_text: Vec<Option<(usize, String)>>,
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
    /// What was done to the topic on the way (see the module docs), one sentence each.
    pub notes: Vec<String>,
}

impl JointSeries {
    /// Messages taken so far.
    pub fn len(&self) -> usize {
        self.t_ns.len()
    }

    /// Takes the next message, logged at `log_time_ns`, or says what is wrong with it.
    pub fn push(&mut self, msg: JointState, wheel_joints: &[String], log_time_ns: i64) -> Result<(), String> {
        let n = msg.name.len();
        for (field, len) in [("position", msg.position.len()), ("velocity", msg.velocity.len())] {
            if len != 0 && len != n {
                return Err(format!("field {field} has {len} entries, expected {n} (one per name) or none"));
            }
        }
        if msg.velocity.is_empty() && msg.position.is_empty() {
            return Err("fields velocity and position are both empty".into());
        }
        let index = self.seen;
        self.seen += 1;
        if !msg.name.iter().any(|name| wheel_joints.contains(&name.0)) {
            self.other_publisher += 1;
            if self.first_other.is_none()
                && let Some(missing) = missing_wheel(&msg.name, wheel_joints)
            {
                self.first_other = Some((index, missing));
            }
            return Ok(());
        }
        if msg.name != self.names {
            (self.index, self.entries.other_entry) = wheel_entries(&msg.name, wheel_joints);
            self.names = msg.name;
        }
        // Never filled: the first two messages both stamped 0 (a real clock is not 0 twice).
        if self.t_ns.len() == 1 && self.t_ns[0] == 0 && msg.header.stamp.ns() == 0 && !self.by_log_time {
            self.by_log_time = true;
            self.t_ns[0] = self.first_log_ns;
        }
        if self.t_ns.is_empty() {
            self.first_log_ns = log_time_ns;
        }
        let t = if self.by_log_time { log_time_ns } else { msg.header.stamp.ns() };
        let wheel = |values: &[f64]| -> Vec<f64> {
            if values.is_empty() {
                vec![f64::NAN; self.index.len()]
            } else {
                self.index.iter().map(|i| i.map_or(f64::NAN, |i| values[i])).collect()
            }
        };
        let (mut velocity, position) = (wheel(&msg.velocity), wheel(&msg.position));
        if let Some(&prev) = self.t_ns.last() {
            if t == prev && self.repeats_last(&velocity, &position) {
                self.duplicates += 1;
                return Ok(());
            }
            if t <= prev {
                let what = if self.by_log_time { "log time" } else { "header.stamp" };
                return Err(format!(
                    "{what} {} is not after the previous message's {} (stamps must increase)",
                    Stamp(t),
                    Stamp(prev)
                ));
            }
        }
        let nan_velocity = !msg.velocity.is_empty()
            && velocity.iter().any(|v| v.is_nan())
            && !msg.position.is_empty()
            && position.iter().all(|p| p.is_finite());
        if nan_velocity {
            velocity.iter_mut().for_each(|v| *v = f64::NAN);
            self.nan_velocity += 1;
        }
        let k = self.t_ns.len();
        self.note_entries(k, index, &msg.velocity, &msg.position, wheel_joints);
        self.t_ns.push(t);
        if msg.velocity.is_empty() || nan_velocity {
            self.first_without_velocity.get_or_insert(k);
            self.without_velocity += 1;
        }
        if msg.position.is_empty() {
            self.first_without_position.get_or_insert(k);
        }
        self.velocity.extend(velocity);
        self.position.extend(position);
        Ok(())
    }

    /// Records sample `k` (message `index`)'s missing wheel joints and the other entries of joints named
    /// twice.
    fn note_entries(&mut self, k: usize, index: usize, velocity: &[f64], position: &[f64], wheel_joints: &[String]) {
        self.entries.missing_text.resize(wheel_joints.len(), None);
        for (j, at) in self.index.iter().enumerate() {
            if at.is_none() {
                self.entries.missing.push((k, j));
                if self.entries.missing_text[j].is_none() {
                    let names: Vec<&str> = self.names.iter().map(|s| s.0.as_str()).collect();
                    let what = format!("{MISSING_WHEEL}{:?} is missing (names: {})", wheel_joints[j], names.join(", "));
                    self.entries.missing_text[j] = Some((index, what));
                }
            }
        }
        for (j, other) in self.entries.other_entry.iter().enumerate() {
            if let Some(i) = *other {
                let value = |v: &[f64]| v.get(i).copied().unwrap_or(f64::NAN);
                self.entries.copies.push(repair::Copy { k, j, velocity: value(velocity), position: value(position) });
            }
        }
    }

    /// When no message names a wheel joint: the first message's index and which joint it lacks.
    pub fn no_wheel_message(&self) -> Option<&(usize, String)> {
        self.first_other.as_ref().filter(|_| self.t_ns.is_empty())
    }

    /// Whether `velocity` and `position` (wheel order) are bit for bit the last message's.
    fn repeats_last(&self, velocity: &[f64], position: &[f64]) -> bool {
        let w = velocity.len();
        let same =
            |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits() || x.is_nan() && y.is_nan());
        same(&self.velocity[self.velocity.len() - w..], velocity)
            && same(&self.position[self.position.len() - w..], position)
    }

    /// One sentence per thing done to the topic on the way (see the module docs).
    fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if self.other_publisher > 0 {
            notes.push(format!(
                "{} messages name none of the wheel joints (another publisher on the topic): passed over",
                self.other_publisher
            ));
        }
        if self.duplicates > 0 {
            notes.push(format!(
                "{} messages repeat the one before exactly (stamp and values): dropped",
                self.duplicates
            ));
        }
        if self.by_log_time {
            notes.push("header.stamp is 0: the messages are stamped by their log time instead".to_string());
        }
        if self.nan_velocity > 0 {
            notes.push(format!(
                "{} messages have a NaN wheel velocity beside finite positions: their speeds come from the positions",
                self.nan_velocity
            ));
        }
        notes
    }

    /// The wheel data, given the stamps in seconds (`t_s[k]` for message `k`) and the units the joints are
    /// published in (`[wheel_data]`: turned into the wheel's rad and rad/s; its `source`: the field read);
    /// `Err((message, problem))`.
    pub fn finish(self, wheel_joints: &[String], t_s: &[f64], units: &WheelData) -> Result<Wheels, (usize, String)> {
        let w = wheel_joints.len();
        let mut notes = self.notes();
        let (mut velocity, mut position) = (self.velocity, self.position);
        notes.extend(repair::resolve_copies(&self.entries.copies, &mut velocity, &mut position, wheel_joints)?);
        let gaps = repair::Gaps { missing: &self.entries.missing, first: &self.entries.missing_text };
        notes.extend(repair::fill_gaps(&gaps, t_s, &mut velocity, &mut position, wheel_joints)?);
        if !units.is_identity() {
            let (p, v) = (units.position_rad_per_unit(), units.velocity_rad_s_per_unit());
            velocity.iter_mut().for_each(|x| *x *= v);
            position.iter_mut().for_each(|x| *x *= p);
            notes.push(format!("{} ([wheel_data] in the robot description)", describe_units(units)));
        }
        let position = self.first_without_position.is_none().then_some(position);
        // An encoder behind a gearbox wraps on its own shaft, not on the wheel's: left as it is.
        let geared = units.gear_ratio.is_some_and(|g| g != 1.0);
        let unwrapped = |p: &[f64]| if geared { (p.to_vec(), vec![0; w]) } else { unwrap(p, w) };
        if self.first_without_velocity.is_none()
            && let Some(p) = position.as_ref()
        {
            notes.extend(fields::compare(t_s, &velocity, &unwrapped(p).0, w, units)?);
        }
        let from_position = match (self.first_without_velocity, position.as_ref(), units.source) {
            (Some(j), _, Some(WheelField::Velocity)) => {
                return Err((
                    j,
                    "field velocity is empty (or NaN), but [wheel_data] source = \"velocity\" reads the \
                                wheel speeds from it: remove source, or record the joints' velocities"
                        .to_string(),
                ));
            }
            (None, None, Some(WheelField::Position)) => {
                let k = self.first_without_position.unwrap_or_default();
                return Err((
                    k,
                    "field position is empty, but [wheel_data] source = \"position\" reads the wheel \
                                speeds from it: remove source, or record the joints' positions"
                        .to_string(),
                ));
            }
            (Some(_), Some(_), _) | (None, Some(_), Some(WheelField::Position)) => true,
            (None, _, _) => false,
            (Some(j), None, _) => {
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
        let (rad_s, differentiated) = match (from_position, position.as_ref()) {
            (true, Some(p)) => {
                let (unwrapped, wrapped) = unwrapped(p);
                for (j, wraps) in wrapped.iter().enumerate().filter(|(_, n)| **n > 0) {
                    notes.push(format!(
                        "the position of joint {:?} wraps around (an angle modulo 2π): unwrapped at {wraps} jumps \
                         before it is differentiated",
                        wheel_joints[j]
                    ));
                }
                let without = if self.first_without_velocity.is_some() { self.without_velocity } else { t_s.len() };
                (differentiate(t_s, &unwrapped, w), Some(without))
            }
            _ => (velocity, None),
        };
        let used =
            if differentiated.is_some() { ("position", position.as_deref()) } else { ("velocity", Some(&rad_s[..])) };
        if let (field, Some(values)) = used
            && let Some(i) = values.iter().position(|v| !v.is_finite())
        {
            let (k, j) = (i / w, i % w);
            return Err((k, format!("field {field}[{}] (joint {:?}) is {}", j, wheel_joints[j], values[i])));
        }
        Ok(Wheels { t_ns: self.t_ns, rad_s, position, differentiated, notes })
    }
}

/// One sentence: what the joint values were converted from.
fn describe_units(units: &WheelData) -> String {
    let mut s = format!("joint positions in {} and velocities in {}", units.position.name(), units.velocity.name());
    if let Some(c) = units.counts_per_rev {
        s.push_str(&format!(" ({c} counts per revolution)"));
    }
    if let Some(g) = units.gear_ratio.filter(|&g| g != 1.0) {
        s.push_str(&format!(" behind a {g}:1 gear"));
    }
    s.push_str(" are converted to the wheel's rad and rad/s");
    s
}

/// How the problem of a message without one of the wheel joints begins.
const MISSING_WHEEL: &str = "wheel joint ";

/// Whether a JointState topic's problem `what` is a message without one of the wheel joints.
pub(super) fn is_missing_wheel(what: &str) -> bool {
    what.starts_with(MISSING_WHEEL)
}

/// Where each of `wheel_joints` is in `names` (its last entry; `None`: missing), and where a joint named
/// twice has its first entry.
fn wheel_entries(names: &[RosString], wheel_joints: &[String]) -> (Vec<Option<usize>>, Vec<Option<usize>>) {
    let at = |joint: &String| -> Vec<usize> {
        names.iter().enumerate().filter(|(_, n)| n.0 == *joint).map(|(i, _)| i).collect()
    };
    let entries: Vec<Vec<usize>> = wheel_joints.iter().map(at).collect();
    let last = entries.iter().map(|e| e.last().copied()).collect();
    let first = entries.iter().map(|e| if e.len() > 1 { e.first().copied() } else { None }).collect();
    (last, first)
}

/// Which of `wheel_joints` `names` lacks (the first), as a problem.
fn missing_wheel(names: &[RosString], wheel_joints: &[String]) -> Option<String> {
    let joint = wheel_joints.iter().find(|j| !names.iter().any(|n| n.0 == **j))?;
    let names: Vec<&str> = names.iter().map(|s| s.0.as_str()).collect();
    Some(format!("{MISSING_WHEEL}{joint:?} is missing (names: {})", names.join(", ")))
}

/// `position` (`samples × w`) with each joint's wrap-arounds undone, and the jumps undone per joint. A
/// joint wraps when every position lies in [−π, π] or in [0, 2π] and a step between samples exceeds π
/// (half a turn): each such step is taken the short way round. A joint that leaves both ranges is
/// counting turns itself and is left as it is.
fn unwrap(position: &[f64], w: usize) -> (Vec<f64>, Vec<usize>) {
    use std::f64::consts::{PI, TAU};
    const SLACK: f64 = 1e-6;
    let mut out = position.to_vec();
    let mut wraps = vec![0; w];
    for j in 0..w {
        let column = || position.iter().skip(j).step_by(w).copied();
        let within = |lo: f64, hi: f64| column().all(|p| (lo - SLACK..=hi + SLACK).contains(&p));
        if !(within(-PI, PI) || within(0.0, TAU)) {
            continue;
        }
        let mut offset = 0.0;
        for k in 1..position.len() / w {
            let step = position[k * w + j] - position[(k - 1) * w + j];
            if step.abs() > PI {
                offset -= TAU * (step / TAU).round();
                wraps[j] += 1;
            }
            out[k * w + j] = position[k * w + j] + offset;
        }
    }
    (out, wraps)
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
mod tests;
