//! Choosing a recording's topics: where the wheel speeds come from (JointState, or the robot's own
//! odometry through the design), the ground truth (a pose topic or a TF pair, never a localization unless
//! named, moved to the base frame along static transforms, and the clock its topic runs on), the recorded
//! odometry and the command; every error lists the candidates and the flag that chooses.

mod truth;

pub(crate) use truth::SAME_CLOCK_MAX_OFFSET_S;
pub(super) use truth::{Truth, is_localization, localization_note, topic_clock};

use super::joint_state;
use super::odometry::{self, ODOM_FRAME};
use super::recording::{Channel, Content, MsgType};
use super::statics::StaticTree;
use super::{McapOptions, Origin, tf, twist};
use crate::api::settings::{named, named_with};
use crate::dataset::{DatasetError, Note};
use std::path::Path;

/// Frames that are the robot's own (REP-105): a pose in them is not a ground truth.
pub(super) const ROBOT_FRAMES: [&str; 3] = [ODOM_FRAME, "base_link", "base_footprint"];
/// The types a ground truth can come from.
const TRUTH_TYPES: &str = "geometry_msgs/msg/PoseStamped, geometry_msgs/msg/PoseWithCovarianceStamped, \
                           nav_msgs/msg/Odometry, tf2_msgs/msg/TFMessage, geometry_msgs/msg/PointStamped and sensor_msgs/msg/NavSatFix \
                           (positions only)";

/// Where the wheel speeds come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum WheelSource {
    /// A JointState channel.
    Joints(usize),
    /// The robot's own odometry channel, through the design (see [`super::odom_wheels`]).
    Odometry(usize),
}

impl WheelSource {
    /// The channel.
    pub(super) fn channel(self) -> usize {
        match self {
            Self::Joints(i) | Self::Odometry(i) => i,
        }
    }
}

/// What an odometry topic needs to stand in for the wheels.
const NEED_DESIGN: &str = "wheel speeds can come from it only through the robot's design; describe the robot \
                           (omnical init RECORDING writes robot.toml from its URDF, or --robot FILE)";

/// The file being read and its channels, for choosing topics and building errors.
pub(super) struct Bag<'a> {
    pub(super) path: &'a Path,
    pub(super) channels: Vec<Channel>,
}

/// `topic "/x"`.
pub(super) fn topic_location(topic: &str) -> String {
    format!("topic {topic:?}")
}

impl Bag<'_> {
    /// Every topic, sorted, with type and count.
    fn listing(&self) -> String {
        let mut all: Vec<&Channel> = self.channels.iter().collect();
        all.sort_by(|a, b| a.topic.cmp(&b.topic));
        let list: Vec<String> = all.iter().map(|c| c.describe()).collect();
        if list.is_empty() { "none".into() } else { list.join(", ") }
    }

    /// The channel of an explicitly chosen topic, set at `origin`.
    fn find(&self, topic: &str, origin: &Origin) -> Result<usize, DatasetError> {
        self.channels.iter().position(|c| c.topic == topic).ok_or_else(|| {
            let named = origin.naming(topic);
            DatasetError::file(self.path, format!("{named}: no such topic; topics: {}", self.listing()))
        })
    }

    /// The channel's problem as an error, if it has one.
    pub(super) fn check(&self, i: usize) -> Result<(), DatasetError> {
        match self.problem(i) {
            None => Ok(()),
            Some((location, what)) => Err(DatasetError::at(self.path, location, what)),
        }
    }

    /// The channel's problem, if it has one: where (topic, and message when one is to blame) and what.
    fn problem(&self, i: usize) -> Option<(String, String)> {
        let c = &self.channels[i];
        let (message, what) = c.problem.as_ref()?;
        let location = match message {
            None => topic_location(&c.topic),
            Some(k) => format!("topic {:?}, message {k}", c.topic),
        };
        Some((location, what.clone()))
    }

    /// Where the wheel speeds come from: the JointState topic named (`--joints-topic`, robot.toml) or the
    /// only one (else the only one carrying the wheel joints); without JointState, the robot's own odometry
    /// through the design ([`McapOptions::wheels_from_twist`]).
    pub(super) fn joints(&self, opts: &McapOptions) -> Result<WheelSource, DatasetError> {
        if let Some(topic) = &opts.joints_topic {
            let i = self.find(topic, &opts.origins.joints_topic)?;
            let c = &self.channels[i];
            return match (c.msg_type, &opts.wheels_from_twist) {
                (MsgType::JointState, _) => Ok(WheelSource::Joints(i)),
                (MsgType::Odometry, Some(_)) => Ok(WheelSource::Odometry(i)),
                (MsgType::Odometry, None) => Err(DatasetError::at(
                    self.path,
                    topic_location(topic),
                    format!("is {}: {NEED_DESIGN}", odometry::NAME),
                )),
                _ => Err(DatasetError::at(
                    self.path,
                    topic_location(topic),
                    format!(
                        "type {} is not {} (wheel speeds) or {} (the robot's own odometry)",
                        schema_or_none(&c.schema),
                        joint_state::NAME,
                        odometry::NAME
                    ),
                )),
            };
        }
        let candidates: Vec<usize> =
            (0..self.channels.len()).filter(|&i| self.channels[i].msg_type == MsgType::JointState).collect();
        if let [i] = candidates[..] {
            return Ok(WheelSource::Joints(i));
        }
        if candidates.is_empty() {
            let odometry = self.recorded_odometry(&mut Vec::new());
            return match (odometry, &opts.wheels_from_twist) {
                (Some(i), Some(_)) => Ok(WheelSource::Odometry(i)),
                (Some(i), None) => Err(DatasetError::file(
                    self.path,
                    format!(
                        "no {} topic for the wheel speeds; {topic} is the robot's own odometry: {NEED_DESIGN}; with \
                         it, {topic} stands in for the wheels ({})",
                        joint_state::NAME,
                        named_with("joints_topic", &self.channels[i].topic),
                        topic = self.channels[i].topic
                    ),
                )),
                (None, _) => Err(DatasetError::file(
                    self.path,
                    format!(
                        "no {} topic for the wheel speeds; topics: {}{}",
                        joint_state::NAME,
                        self.listing(),
                        self.any_odometry_hint()
                    ),
                )),
            };
        }
        let with_wheels: Vec<usize> = candidates
            .iter()
            .copied()
            .filter(|&i| matches!(&self.channels[i].content, Content::Joints(s) if s.len() > 0))
            .collect();
        if let [i] = with_wheels[..] {
            return Ok(WheelSource::Joints(i));
        }
        let list: Vec<String> = candidates.iter().map(|&i| self.channels[i].describe()).collect();
        Err(DatasetError::file(
            self.path,
            format!(
                "cannot tell which {} topic has the wheel joints ({}): {}; choose one with {}",
                joint_state::NAME,
                opts.wheel_joints.join(", "),
                list.join(", "),
                named("joints_topic")
            ),
        ))
    }

    /// [`Self::check`] for the wheels' channel `i`: a JointState message without a wheel joint also says
    /// what else could give the wheels ([`Self::odometry_hint`]).
    pub(super) fn check_wheels(&self, i: usize) -> Result<(), DatasetError> {
        match (&self.channels[i].problem, self.odometry_hint()) {
            (Some((Some(k), what)), Some(hint)) if joint_state::is_missing_wheel(what) => Err(DatasetError::at(
                self.path,
                format!("topic {:?}, message {k}", self.channels[i].topic),
                format!("{what}; {hint}"),
            )),
            _ => self.check(i),
        }
    }

    /// Without JointState and without an odometry in frame `odom` (REP-105): an odometry in another frame
    /// may still be the wheels', named with the way to read it (`; if … --joints-topic …`), or nothing.
    fn any_odometry_hint(&self) -> String {
        let odometry = self.channels.iter().find(|c| c.msg_type == MsgType::Odometry);
        odometry.map_or_else(String::new, |c| {
            format!(
                "; if {topic} is the robot's own wheel odometry, it can stand in for the wheels through the robot's \
                 design: {}, with a robot description (omnical init RECORDING writes robot.toml from its URDF, or \
                 --robot FILE)",
                named_with("joints_topic", &c.topic),
                topic = c.topic
            )
        })
    }

    /// What to try when the JointState topic does not carry the wheels and the robot's own odometry is
    /// recorded: name it as the wheel source.
    pub(super) fn odometry_hint(&self) -> Option<String> {
        let i = self.recorded_odometry(&mut Vec::new())?;
        let topic = &self.channels[i].topic;
        Some(format!(
            "if no JointState topic carries the wheels, the robot's own odometry {topic} can stand in through the \
             robot's design: {} ([topics] joint_states in robot.toml)",
            named_with("joints_topic", topic)
        ))
    }

    /// The robot's recorded wheel odometry: `/odom` if it is one, else the only one.
    pub(super) fn recorded_odometry(&self, notes: &mut Vec<Note>) -> Option<usize> {
        self.optional(Channel::is_wheel_odometry, "/odom", "recorded odometry", notes)
    }

    /// The command topic: `preferred` (default `/cmd_vel`) if it is one, else the only one.
    pub(super) fn commands(&self, preferred: Option<&str>, notes: &mut Vec<Note>) -> Option<usize> {
        let is_cmd = |c: &Channel| matches!(c.msg_type, MsgType::Twist | MsgType::TwistStamped);
        let chosen = self.optional(is_cmd, preferred.unwrap_or("/cmd_vel"), "the command", notes)?;
        if self.channels[chosen].msg_type == MsgType::Twist {
            notes.push(Note::about(
                self.path,
                format!(
                    "topic {:?} ({}) has no header: command times are log times",
                    self.channels[chosen].topic,
                    twist::NAME
                ),
            ));
        }
        Some(chosen)
    }

    /// An optional source (`what`) among the channels that are `wanted`: the one named `preferred`, else the
    /// only one. Several without the preferred one, or a problem on the chosen one, leave it out with a note.
    fn optional(
        &self,
        wanted: impl Fn(&Channel) -> bool,
        preferred: &str,
        what: &str,
        notes: &mut Vec<Note>,
    ) -> Option<usize> {
        let all: Vec<usize> = (0..self.channels.len()).filter(|&i| wanted(&self.channels[i])).collect();
        let chosen = match all[..] {
            [] => return None,
            [i] => i,
            _ => match all.iter().find(|&&i| self.channels[i].topic == preferred) {
                Some(&i) => i,
                None => {
                    let list: Vec<&str> = all.iter().map(|&i| self.channels[i].topic.as_str()).collect();
                    notes.push(Note::about(
                        self.path,
                        format!(
                            "{what} could come from several topics ({}), none of them {preferred}: {what} is left out",
                            list.join(", ")
                        ),
                    ));
                    return None;
                }
            },
        };
        self.usable(chosen, what, notes)
    }

    /// `Some(i)` if channel `i` has no problem; otherwise a note that `what` is left out.
    fn usable(&self, i: usize, what: &str, notes: &mut Vec<Note>) -> Option<usize> {
        match self.problem(i) {
            None => Some(i),
            Some((location, problem)) => {
                notes.push(Note::about(self.path, format!("{location}: {problem} ({what} is left out)")));
                None
            }
        }
    }

    /// The static transforms of every TF topic.
    pub(super) fn statics(&self) -> StaticTree {
        let mut tree = StaticTree::default();
        for c in &self.channels {
            if let Content::Tf(pairs) = &c.content {
                pairs.add_statics(tf::is_static_topic(&c.topic), &mut tree);
            }
        }
        tree
    }

    /// Moves a channel's content out.
    pub(super) fn take(&mut self, i: usize) -> Content {
        std::mem::replace(&mut self.channels[i].content, Content::Nothing)
    }
}

fn schema_or_none(schema: &str) -> &str {
    if schema.is_empty() { "(no schema)" } else { schema }
}

#[cfg(test)]
mod tests;
