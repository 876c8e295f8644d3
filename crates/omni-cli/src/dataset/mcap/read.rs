//! Reading a bag: one pass over the messages in file order, decoding every channel of a known type as it
//! comes; then choosing the topics, and building the runs.
//!
//! A channel's first problem (an undecodable message, NaN, stamps going backwards, an unsupported encoding)
//! is kept with the channel and reported only if that channel is used, so a broken topic nobody asked for
//! does not stop the read.

use super::common::{NS_PER_S, decode, seconds_since};
use super::joint_state::{self, JointSeries, JointState, Wheels};
use super::odometry::{self, ODOM_FRAME, Odometry};
use super::pose_stamped::{self, PoseStamped, PoseWithCovarianceStamped};
use super::poses::{PoseSeries, start_heading_in_half_turn};
use super::statics::StaticTree;
use super::tf::{self, TfMessage, TfPairs};
use super::twist::{self, Commands, TwistStamped};
use super::{McapOptions, McapRead, Origin, split};
use crate::dataset::DatasetError;
use crate::dataset::ground_truth::{ExternalTruth, GtClock, TruthSample};
use mcap::sans_io::LinearReaderOptions;
use omni_kin::clock::ClockAlignment;
use omni_kin::{KinError, Pose2, Run, RunData, StampedPose};
use std::path::{Path, PathBuf};

/// Schema encodings whose type names this reader knows. `ros2idl` names the same types with the same CDR
/// layout as `ros2msg` (rosbag2 writes it for types defined in `.idl` files).
const SCHEMA_ENCODINGS: [&str; 2] = ["ros2msg", "ros2idl"];
/// The only message encoding this reader decodes.
const MESSAGE_ENCODING: &str = "cdr";
/// Frames that are the robot's own (REP-105): a pose in them is not a ground truth.
pub(super) const ROBOT_FRAMES: [&str; 3] = [ODOM_FRAME, "base_link", "base_footprint"];
/// The smallest and largest cap on one record's length (the cap is 64 × the file size between them).
pub(super) const MIN_RECORD_LIMIT: usize = 64 << 20;
pub(super) const MAX_RECORD_LIMIT: usize = 4 << 30;
/// The types a ground truth can come from.
const TRUTH_TYPES: &str = "geometry_msgs/msg/PoseStamped, geometry_msgs/msg/PoseWithCovarianceStamped, \
                           nav_msgs/msg/Odometry, tf2_msgs/msg/TFMessage";

/// The message types this reader decodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum MsgType {
    JointState,
    PoseStamped,
    PoseWithCovarianceStamped,
    Odometry,
    Tf,
    Twist,
    TwistStamped,
    Other,
}

impl MsgType {
    fn of(schema: &str) -> Self {
        match schema {
            joint_state::NAME => Self::JointState,
            pose_stamped::NAME => Self::PoseStamped,
            pose_stamped::WITH_COVARIANCE_NAME => Self::PoseWithCovarianceStamped,
            odometry::NAME => Self::Odometry,
            tf::NAME => Self::Tf,
            twist::NAME => Self::Twist,
            twist::STAMPED_NAME => Self::TwistStamped,
            _ => Self::Other,
        }
    }
}

/// What a channel has gathered.
#[derive(Debug)]
pub(super) enum Content {
    Joints(JointSeries),
    Poses(PoseSeries),
    Tf(TfPairs),
    Commands(Commands),
    Nothing,
}

/// One topic of the file.
#[derive(Debug)]
pub(super) struct Channel {
    pub(super) topic: String,
    /// Schema name, `""` without a schema.
    pub(super) schema: String,
    pub(super) msg_type: MsgType,
    /// Messages seen.
    pub(super) messages: usize,
    pub(super) content: Content,
    /// The first problem: the message index (`None` for the channel as a whole) and what is wrong. The
    /// channel takes nothing after it.
    pub(super) problem: Option<(Option<usize>, String)>,
}

impl Channel {
    /// A topic as its storage declares it: schema (type) name, schema encoding, message encoding.
    fn new(topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> Self {
        let msg_type = MsgType::of(schema);
        let content = match msg_type {
            MsgType::JointState => Content::Joints(JointSeries::default()),
            MsgType::PoseStamped | MsgType::PoseWithCovarianceStamped | MsgType::Odometry => {
                Content::Poses(PoseSeries::default())
            }
            MsgType::Tf => Content::Tf(TfPairs::default()),
            MsgType::Twist | MsgType::TwistStamped => Content::Commands(Commands::default()),
            MsgType::Other => Content::Nothing,
        };
        let problem = (msg_type != MsgType::Other
            && !(SCHEMA_ENCODINGS.contains(&schema_encoding) && message_encoding == MESSAGE_ENCODING))
            .then(|| {
                (
                    None,
                    format!(
                        "schema encoding {schema_encoding:?} with message encoding {:?} is not supported \
                         (expected schema encoding \"ros2msg\" and message encoding \"cdr\", as rosbag2 records)",
                        message_encoding
                    ),
                )
            });
        Self { topic: topic.to_string(), schema: schema.to_string(), msg_type, messages: 0, content, problem }
    }

    /// Takes the next message.
    fn take(&mut self, data: &[u8], log_time_ns: u64, wheel_joints: &[String]) {
        let index = self.messages;
        self.messages += 1;
        if self.problem.is_some() {
            return;
        }
        let result = match &mut self.content {
            Content::Joints(s) => decode::<JointState>(data)
                .and_then(|m| s.push(m, wheel_joints, i64::try_from(log_time_ns).unwrap_or(i64::MAX))),
            Content::Poses(s) => match self.msg_type {
                MsgType::PoseStamped => decode::<PoseStamped>(data).and_then(|m| {
                    s.check_frame(m.header.frame_id.frame(), None)?;
                    let p = &m.pose;
                    s.push(m.header.stamp.ns(), &p.position, &p.orientation, &pose_stamped::FIELDS)
                }),
                MsgType::PoseWithCovarianceStamped => decode::<PoseWithCovarianceStamped>(data).and_then(|m| {
                    s.check_frame(m.header.frame_id.frame(), None)?;
                    let p = &m.pose.pose;
                    s.push(m.header.stamp.ns(), &p.position, &p.orientation, &pose_stamped::WITH_COVARIANCE_FIELDS)
                }),
                _ => decode::<Odometry>(data).and_then(|m| {
                    s.check_frame(m.header.frame_id.frame(), Some(m.child_frame_id.frame()))?;
                    let p = &m.pose.pose;
                    s.push(m.header.stamp.ns(), &p.position, &p.orientation, &pose_stamped::WITH_COVARIANCE_FIELDS)
                }),
            },
            Content::Tf(pairs) => decode::<TfMessage>(data).map(|m| pairs.push(index, &m)),
            Content::Commands(c) => match self.msg_type {
                MsgType::TwistStamped => {
                    decode::<TwistStamped>(data).and_then(|m| c.push(m.header.stamp.ns(), &m.twist))
                }
                _ => decode(data).and_then(|t| c.push(i64::try_from(log_time_ns).unwrap_or(i64::MAX), &t)),
            },
            Content::Nothing => Ok(()),
        };
        if let Err(e) = result {
            self.problem = Some((Some(index), e));
        }
    }

    /// The frame of the first pose, for pose channels.
    pub(super) fn frame(&self) -> Option<&str> {
        match &self.content {
            Content::Poses(s) => s.frame.as_deref(),
            _ => None,
        }
    }

    /// Whether this is the robot's own wheel odometry (REP-105: Odometry in frame `odom`).
    pub(super) fn is_wheel_odometry(&self) -> bool {
        self.msg_type == MsgType::Odometry && self.frame() == Some(ODOM_FRAME)
    }

    /// `/topic (type, N messages, frame "f")`.
    fn describe(&self) -> String {
        let schema = if self.schema.is_empty() { "no schema" } else { &self.schema };
        let plural = if self.messages == 1 { "" } else { "s" };
        let mut s = format!("{} ({schema}, {} message{plural}", self.topic, self.messages);
        if let Some(f) = self.frame() {
            s.push_str(&format!(", frame {f:?}"));
        }
        if self.is_wheel_odometry() {
            s.push_str(": the robot's own odometry");
        }
        s.push(')');
        s
    }

    /// `/topic (type, frame "f")`, for lists of candidates.
    fn candidate(&self) -> String {
        match self.frame() {
            Some(f) => format!("{} ({}, frame {f:?})", self.topic, self.schema),
            None => format!("{} ({})", self.topic, self.schema),
        }
    }
}

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

/// Where the ground truth comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Truth {
    /// A pose channel.
    Poses(usize),
    /// A channel's TF pair.
    Tf(usize, usize),
}

impl Truth {
    /// The channel.
    pub(super) fn channel(self) -> usize {
        match self {
            Self::Poses(i) | Self::Tf(i, _) => i,
        }
    }
}

/// The file being read and its channels, for choosing topics and building errors.
pub(super) struct Bag<'a> {
    pub(super) path: &'a Path,
    pub(super) channels: Vec<Channel>,
}

/// `topic "/x"`.
fn topic_location(topic: &str) -> String {
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
    fn check(&self, i: usize) -> Result<(), DatasetError> {
        let c = &self.channels[i];
        match &c.problem {
            None => Ok(()),
            Some((None, what)) => Err(DatasetError::at(self.path, topic_location(&c.topic), what.clone())),
            Some((Some(k), what)) => {
                Err(DatasetError::at(self.path, format!("topic {:?}, message {k}", c.topic), what.clone()))
            }
        }
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
                        "no {} topic for the wheel speeds; {} is the robot's own odometry: {NEED_DESIGN}",
                        joint_state::NAME,
                        self.channels[i].topic
                    ),
                )),
                (None, _) => Err(DatasetError::file(
                    self.path,
                    format!("no {} topic for the wheel speeds; topics: {}", joint_state::NAME, self.listing()),
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
                "cannot tell which {} topic has the wheel joints ({}): {}; choose one with --joints-topic",
                joint_state::NAME,
                opts.wheel_joints.join(", "),
                list.join(", ")
            ),
        ))
    }

    /// Why channel `i` cannot be the ground truth under `opts`, if it cannot.
    pub(super) fn truth_mismatch(&self, i: usize, opts: &McapOptions) -> Option<String> {
        let c = &self.channels[i];
        let Content::Poses(s) = &c.content else { return None };
        let frame = s.frame.as_deref()?;
        if c.is_wheel_odometry() {
            return Some(format!(
                "is the robot's own wheel odometry (frame {ODOM_FRAME:?}, REP-105): the model under test, never \
                 ground truth; choose a map, world or motion-capture source"
            ));
        }
        if let Some(p) = &opts.truth_parent_frame
            && p != frame
        {
            return Some(format!("has frame {frame:?}, but {}", opts.origins.truth_parent_frame.naming(p)));
        }
        if let (Some(want), Some(child)) = (&opts.truth_child_frame, &s.child)
            && want != child
        {
            return Some(format!("has child frame {child:?}, but {}", opts.origins.truth_child_frame.naming(want)));
        }
        None
    }

    /// long: the ground-truth channel, named (`--gt-topic`) or found, with errors that list every
    /// transform or pose topic seen; kept together so the messages can name them.
    pub(super) fn truth(&self, opts: &McapOptions) -> Result<Truth, DatasetError> {
        let (parent, child) = (opts.truth_parent_frame.as_deref(), opts.truth_child_frame.as_deref());
        let statics = self.statics();
        if let Some(topic) = &opts.truth_topic {
            let i = self.find(topic, &opts.origins.truth_topic)?;
            let c = &self.channels[i];
            return match (&c.content, c.msg_type) {
                (Content::Tf(pairs), _) => {
                    self.check(i)?;
                    let found = pairs.candidates(parent, child, &statics);
                    match found[..] {
                        [k] => Ok(Truth::Tf(i, k)),
                        _ => {
                            let all: Vec<String> = pairs
                                .pairs
                                .iter()
                                .map(|p| format!("{} → {} ({} poses)", p.parent, p.child, p.poses.t_ns.len()))
                                .collect();
                            let what = if found.is_empty() { "no transform" } else { "several transforms" };
                            Err(DatasetError::at(
                                self.path,
                                topic_location(topic),
                                format!(
                                    "{what} could be the ground truth (transforms: {}); choose one with \
                                     --gt-parent-frame and --gt-child-frame",
                                    if all.is_empty() { "none".into() } else { all.join(", ") }
                                ),
                            ))
                        }
                    }
                }
                (Content::Poses(_), _) => match self.truth_mismatch(i, opts) {
                    Some(why) => Err(DatasetError::at(self.path, topic_location(topic), why)),
                    None => Ok(Truth::Poses(i)),
                },
                _ => Err(DatasetError::at(
                    self.path,
                    topic_location(topic),
                    format!("type {} cannot be ground truth (supported: {TRUTH_TYPES})", schema_or_none(&c.schema)),
                )),
            };
        }
        let mut found: Vec<(Truth, String)> = Vec::new();
        let mut localizations: Vec<&str> = Vec::new();
        for (i, c) in self.channels.iter().enumerate() {
            if c.messages == 0 {
                continue;
            }
            match &c.content {
                Content::Poses(_) if is_localization(&c.topic) => localizations.push(&c.topic),
                Content::Poses(_) => {
                    let robot_frame = c.frame().is_some_and(|f| ROBOT_FRAMES.contains(&f));
                    if !robot_frame && self.truth_mismatch(i, opts).is_none() {
                        found.push((Truth::Poses(i), c.candidate()));
                    }
                }
                Content::Tf(_) if tf::is_static_topic(&c.topic) => {}
                Content::Tf(pairs) => {
                    for k in pairs.candidates(parent, child, &statics) {
                        let p = &pairs.pairs[k];
                        found.push((Truth::Tf(i, k), format!("{} ({} → {})", c.topic, p.parent, p.child)));
                    }
                }
                _ => {}
            }
        }
        match &found[..] {
            [(t, _)] => Ok(*t),
            [] => Err(DatasetError::file(
                self.path,
                format!(
                    "no ground truth: no {TRUTH_TYPES} source outside the robot's frames ({}){}; topics: {}",
                    ROBOT_FRAMES.join(", "),
                    match (parent, child) {
                        (None, None) => String::new(),
                        _ => format!(
                            " matching --gt-parent-frame {:?} --gt-child-frame {:?}",
                            parent.unwrap_or("(any)"),
                            child.unwrap_or("(any)")
                        ),
                    },
                    self.listing()
                ) + &localization_hint(&localizations),
            )),
            _ => {
                let list: Vec<&str> = found.iter().map(|(_, d)| d.as_str()).collect();
                Err(DatasetError::file(
                    self.path,
                    format!(
                        "several ground-truth sources: {}; choose one with --gt-topic (for a TF topic, also \
                         --gt-parent-frame and --gt-child-frame)",
                        list.join(", ")
                    ),
                ))
            }
        }
    }

    /// The ground truth `src` on channel `ch` (taken out of the bag): its topic and its poses in seconds
    /// since `origin_s`; a TF pair's problem is an error naming the message.
    fn truth_poses(
        &mut self,
        src: Truth,
        ch: usize,
        origin_s: i64,
        opts: &McapOptions,
        notes: &mut Vec<String>,
    ) -> Result<(String, Vec<StampedPose>), DatasetError> {
        let topic = self.channels[ch].topic.clone();
        let statics = self.statics();
        let poses = match (src, self.take(ch)) {
            (Truth::Tf(_, k), Content::Tf(mut pairs)) => {
                let mut pair = pairs.pairs.swap_remove(k);
                if let Some((m, what)) = pair.problem {
                    return Err(DatasetError::at(self.path, format!("topic {topic:?}, message {m}"), what));
                }
                if let Some(note) = to_base_frame(&mut pair, &statics, opts.truth_child_frame.as_deref()) {
                    notes.push(format!("{}: topic {topic:?}: {note}", self.path.display()));
                }
                pair.poses
            }
            (_, Content::Poses(p)) => p,
            _ => unreachable!("truth() returns pose channels or TF pairs"),
        };
        Ok((topic, poses.stamped(origin_s)))
    }

    /// [`Self::check`] for the wheels' channel `i`: a JointState message without a wheel joint also says
    /// what else could give the wheels ([`Self::odometry_hint`]).
    fn check_wheels(&self, i: usize) -> Result<(), DatasetError> {
        match (&self.channels[i].problem, self.odometry_hint()) {
            (Some((Some(k), what)), Some(hint)) if joint_state::is_missing_wheel(what) => Err(DatasetError::at(
                self.path,
                format!("topic {:?}, message {k}", self.channels[i].topic),
                format!("{what}; {hint}"),
            )),
            _ => self.check(i),
        }
    }

    /// What to try when the JointState topic does not carry the wheels and the robot's own odometry is
    /// recorded: name it as the wheel source.
    fn odometry_hint(&self) -> Option<String> {
        let i = self.recorded_odometry(&mut Vec::new())?;
        let topic = &self.channels[i].topic;
        Some(format!(
            "if no JointState topic carries the wheels, the robot's own odometry {topic} can stand in through the \
             robot's design: --joints-topic {topic} ([topics] joint_states in robot.toml)"
        ))
    }

    /// The robot's recorded wheel odometry: `/odom` if it is one, else the only one.
    pub(super) fn recorded_odometry(&self, notes: &mut Vec<String>) -> Option<usize> {
        self.optional(Channel::is_wheel_odometry, "/odom", "recorded odometry", notes)
    }

    /// The command topic: `preferred` (default `/cmd_vel`) if it is one, else the only one.
    pub(super) fn commands(&self, preferred: Option<&str>, notes: &mut Vec<String>) -> Option<usize> {
        let is_cmd = |c: &Channel| matches!(c.msg_type, MsgType::Twist | MsgType::TwistStamped);
        let chosen = self.optional(is_cmd, preferred.unwrap_or("/cmd_vel"), "the command", notes)?;
        if self.channels[chosen].msg_type == MsgType::Twist {
            notes.push(format!(
                "{}: topic {:?} ({}) has no header: command times are log times",
                self.path.display(),
                self.channels[chosen].topic,
                twist::NAME
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
        notes: &mut Vec<String>,
    ) -> Option<usize> {
        let all: Vec<usize> = (0..self.channels.len()).filter(|&i| wanted(&self.channels[i])).collect();
        let chosen = match all[..] {
            [] => return None,
            [i] => i,
            _ => match all.iter().find(|&&i| self.channels[i].topic == preferred) {
                Some(&i) => i,
                None => {
                    let list: Vec<&str> = all.iter().map(|&i| self.channels[i].topic.as_str()).collect();
                    notes.push(format!(
                        "{}: {what} could come from several topics ({}), none of them {preferred}: {what} is left out",
                        self.path.display(),
                        list.join(", ")
                    ));
                    return None;
                }
            },
        };
        self.usable(chosen, what, notes)
    }

    /// `Some(i)` if channel `i` has no problem; otherwise a note that `what` is left out.
    fn usable(&self, i: usize, what: &str, notes: &mut Vec<String>) -> Option<usize> {
        match self.check(i) {
            Ok(()) => Some(i),
            Err(e) => {
                notes.push(format!("{e} ({what} is left out)"));
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
    fn take(&mut self, i: usize) -> Content {
        std::mem::replace(&mut self.channels[i].content, Content::Nothing)
    }
}

/// The robot frames a tracked frame is moved to by default, the first that static transforms reach.
const BASE_FRAMES: [&str; 2] = ["base_link", "base_footprint"];

/// Moves a TF pair's poses from its child frame (a motion-capture marker) along static transforms to
/// `target` (`--gt-child-frame`), or by default to the first of [`BASE_FRAMES`] they reach; says so.
fn to_base_frame(pair: &mut tf::Pair, statics: &StaticTree, target: Option<&str>) -> Option<String> {
    let (to, (offset, frames)) = match target {
        Some(t) => (t, statics.offset(&pair.child, t)?),
        None if BASE_FRAMES.contains(&pair.child.as_str()) => return None,
        None => BASE_FRAMES.iter().find_map(|&t| statics.offset(&pair.child, t).map(|o| (t, o)))?,
    };
    for p in &mut pair.poses.xy_yaw {
        let moved = Pose2::new(p[0], p[1], p[2]).compose(&offset);
        *p = [moved.x_m, moved.y_m, omni_kin::pose::wrap_angle(moved.theta_rad)];
    }
    Some(format!(
        "the ground truth tracks {:?}; it is moved to {to:?} through static transforms ({} → {}: x {:.4} m, \
         y {:.4} m, yaw {:.2}°)",
        pair.child,
        pair.child,
        frames.join(" → "),
        offset.x_m,
        offset.y_m,
        offset.theta_rad.to_degrees()
    ))
}

fn schema_or_none(schema: &str) -> &str {
    if schema.is_empty() { "(no schema)" } else { schema }
}

/// The name of an MCAP record opcode (MCAP specification, "Records").
fn record_kind(opcode: u8) -> &'static str {
    match opcode {
        0x01 => "Header",
        0x02 => "Footer",
        0x03 => "Schema",
        0x04 => "Channel",
        0x05 => "Message",
        0x06 => "Chunk",
        0x07 => "Message Index",
        0x08 => "Chunk Index",
        0x09 => "Attachment",
        0x0a => "Attachment Index",
        0x0b => "Statistics",
        0x0c => "Metadata",
        0x0d => "Metadata Index",
        0x0e => "Summary Offset",
        0x0f => "Data End",
        _ => "unknown",
    }
}

/// An MCAP reading error, in words.
fn mcap_error(path: &Path, e: mcap::McapError) -> DatasetError {
    use mcap::McapError as E;
    let what = match e {
        E::UnexpectedEof | E::BadMagic | E::BadFooter => {
            "the file is truncated: it ends in the middle of a record, before the MCAP end marker (was the \
             recording interrupted?)"
                .to_string()
        }
        E::BadChunkCrc { saved, calculated } => {
            format!("the file is corrupted: a chunk's CRC is {calculated:08x}, but {saved:08x} was recorded")
        }
        E::RecordTooLarge { opcode, len } => format!(
            "the file is corrupted: a {} record (opcode 0x{opcode:02x}) claims {len} bytes, more than the file \
             holds",
            record_kind(opcode)
        ),
        E::ChunkTooLarge(len) => {
            format!("the file is corrupted: a chunk claims {len} bytes of records, more than the file holds")
        }
        E::Parse(_) => "the file is corrupted: the fields inside a record do not parse (a length or string in \
                        it is damaged)"
            .to_string(),
        e => format!("the file is damaged: {e}"),
    };
    DatasetError::file(path, what)
}

/// The top-level record at `pos`: opcode, body (cut at the end of the file: the mcap reader streams a
/// chunk's records before it has the whole chunk) and whether the body is whole.
fn record_at(buf: &[u8], pos: usize) -> Option<(u8, &[u8], bool)> {
    let op = *buf.get(pos)?;
    let len = u64::from_le_bytes(buf.get(pos + 1..pos + 9)?.try_into().ok()?);
    let start = pos + 9;
    let end = usize::try_from(len).ok().and_then(|n| start.checked_add(n)).filter(|&e| e <= buf.len());
    Some((op, &buf[start.min(buf.len())..end.unwrap_or(buf.len())], end.is_some()))
}

/// Checks that the records inside each uncompressed chunk fit in it. mcap 0.26 subtracts an inner record's
/// length from the chunk's remaining bytes unchecked (`sans_io/linear_reader.rs`): a corrupted length
/// panics with overflow checks and reads past the chunk without them. Found by fuzzing
/// (`tests/data/bad/fuzz/chunk_record_overrun.mcap`). Other damage is left to the mcap reader.
fn check_chunks(buf: &[u8]) -> Result<(), String> {
    const CHUNK: u8 = 0x06;
    const FOOTER: u8 = 0x02;
    let u64_at = |b: &[u8], at: usize| -> Option<u64> { Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?)) };
    let mut pos = mcap::MAGIC.len();
    while let Some((op, body, whole)) = record_at(buf, pos) {
        if op == FOOTER {
            break;
        }
        if op == CHUNK {
            // start time, end time, uncompressed size (u64 each), uncompressed CRC (u32), compression (string),
            // records (u64 length + bytes).
            let Some(name_len) = body.get(28..32).and_then(|b| b.try_into().ok()).map(u32::from_le_bytes) else {
                return Ok(());
            };
            let name_end = 32 + name_len as usize;
            if name_len == 0
                && let Some(records_len) = u64_at(body, name_end)
            {
                // Checked against the declared length, which the mcap reader counts down; bytes missing at
                // the end of a cut file are left to it (it reports the truncation).
                let records = body.get(name_end + 8..).unwrap_or_default();
                if whole && records_len > records.len() as u64 {
                    return Err(format!(
                        "the chunk at byte {pos} claims {records_len} bytes of records but holds {}",
                        records.len()
                    ));
                }
                let mut at: u64 = 0;
                while at < records_len {
                    let left = records_len - at;
                    if left < 9 {
                        return Err(format!(
                            "the chunk at byte {pos} ends inside the header of a record ({left} bytes left)"
                        ));
                    }
                    let Some(len) = usize::try_from(at).ok().and_then(|a| u64_at(records, a + 1)) else {
                        break;
                    };
                    if len > left - 9 {
                        return Err(format!(
                            "a record in the chunk at byte {pos} claims {len} bytes but the chunk has {} left",
                            left - 9
                        ));
                    }
                    at += 9 + len;
                }
            }
        }
        if !whole {
            break;
        }
        pos += 9 + body.len();
    }
    Ok(())
}

/// Where the storage readers (MCAP files, rosbag2 sqlite3 files) put a recording's topics and messages:
/// [`Recording`] (the runs) or an inventory of the topics (`omnical init`, [`super::inspect`]).
pub(crate) trait MessageSink {
    /// The channel of `topic`, declared on its first sight (a later declaration of the same topic, in another
    /// split file, keeps the first one's type).
    fn channel(&mut self, topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> usize;
    /// Takes the next message of channel `i` (an index from [`Self::channel`]), logged at `log_time_ns` (ns
    /// since the epoch).
    fn message(&mut self, i: usize, data: &[u8], log_time_ns: u64);
}

/// The channels of one recording, filled message by message from any storage (MCAP files, rosbag2 sqlite3
/// files, several split files of one recording): the one message pipeline behind every reader. Topics are
/// matched by name, so the split files of a recording feed the same channels.
pub(crate) struct Recording {
    wheel_joints: Vec<String>,
    pub(super) channels: Vec<Channel>,
    /// Every message payload is zstd-compressed on its own (rosbag2's `compression_mode: MESSAGE`).
    pub(crate) zstd_messages: bool,
}

impl Recording {
    /// An empty recording whose JointState topics are read for these wheel joints (in wheel order).
    pub(crate) fn new(wheel_joints: &[String]) -> Self {
        Self { wheel_joints: wheel_joints.to_vec(), channels: Vec::new(), zstd_messages: false }
    }

    /// Messages taken on `topic` (`None`: no such topic).
    pub(crate) fn messages_on(&self, topic: &str) -> Option<usize> {
        self.channels.iter().find(|c| c.topic == topic).map(|c| c.messages)
    }
}

impl MessageSink for Recording {
    fn channel(&mut self, topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> usize {
        match self.channels.iter().position(|c| c.topic == topic) {
            Some(i) => i,
            None => {
                self.channels.push(Channel::new(topic, schema, schema_encoding, message_encoding));
                self.channels.len() - 1
            }
        }
    }

    fn message(&mut self, i: usize, data: &[u8], log_time_ns: u64) {
        let c = &mut self.channels[i];
        if self.zstd_messages && c.msg_type != MsgType::Other && c.problem.is_none() {
            match zstd::stream::decode_all(data) {
                Ok(plain) => return c.take(&plain, log_time_ns, &self.wheel_joints),
                Err(e) => {
                    c.problem =
                        Some((Some(c.messages), format!("the zstd-compressed message does not decompress: {e}")));
                    c.messages += 1;
                    return;
                }
            }
        }
        c.take(data, log_time_ns, &self.wheel_joints);
    }
}

/// Feeds every message of an MCAP file, in file order, into `rec`.
pub(crate) fn feed_mcap(path: &Path, buf: &[u8], rec: &mut impl MessageSink) -> Result<(), DatasetError> {
    // mcap 0.26 can still panic on some damaged files (an integer overflow on a record longer than its
    // uncompressed chunk, in builds with overflow checks): a damaged file is an error, never a crash.
    let mut rec = std::panic::AssertUnwindSafe(rec);
    std::panic::catch_unwind(move || scan(path, buf, &mut **rec))
        .unwrap_or_else(|_| Err(DatasetError::file(path, "the file is damaged: the MCAP reader panicked on it")))
}

fn scan<S: MessageSink>(path: &Path, buf: &[u8], rec: &mut S) -> Result<(), DatasetError> {
    if !buf.starts_with(mcap::MAGIC) {
        return Err(DatasetError::file(path, "not an MCAP file (it does not start with the MCAP magic bytes)"));
    }
    check_chunks(buf).map_err(|what| DatasetError::file(path, format!("the file is corrupted: {what}")))?;
    // This file's channel ids and the recording's channels they feed.
    let mut ids: Vec<(u16, usize)> = Vec::new();
    let declare = |rec: &mut S, ids: &mut Vec<(u16, usize)>, ch: &mcap::Channel<'_>| {
        let (schema, encoding) = ch.schema.as_ref().map_or(("", ""), |s| (s.name.as_str(), s.encoding.as_str()));
        let i = rec.channel(&ch.topic, schema, encoding, &ch.message_encoding);
        ids.push((ch.id, i));
        i
    };
    // The summary lists every channel, also those without messages. A damaged summary is ignored here: the
    // pass over the messages below reports what is wrong with the file.
    if let Ok(Some(summary)) = mcap::Summary::read(buf) {
        let mut all: Vec<_> = summary.channels.values().collect();
        all.sort_by_key(|c| c.id);
        for c in all {
            declare(rec, &mut ids, c);
        }
    }
    // A cap on record lengths: a corrupted length then fails cleanly instead of overflowing inside the
    // mcap crate (its default is no limit).
    let limit = buf.len().saturating_mul(64).clamp(MIN_RECORD_LIMIT, MAX_RECORD_LIMIT);
    let options = LinearReaderOptions::default().with_validate_chunk_crcs(true).with_record_length_limit(limit);
    for m in mcap::io::MessageReader::new_with_options(std::io::Cursor::new(buf), options) {
        let m = m.map_err(|e| mcap_error(path, e))?;
        let i = match ids.iter().find(|(id, _)| *id == m.channel.id) {
            Some(&(_, i)) => i,
            None => declare(rec, &mut ids, &m.channel),
        };
        rec.message(i, &m.data, m.log_time);
    }
    Ok(())
}

/// Reads one bag. See the module docs of [`super`].
pub(super) fn read_file(
    path: &Path,
    opts: &McapOptions,
    external: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    let buf = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    read_bytes(path, &buf, opts, external)
}

/// Reads one bag from its bytes; `path` only names it in messages and runs.
pub(super) fn read_bytes(
    path: &Path,
    buf: &[u8],
    opts: &McapOptions,
    external: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    let mut rec = Recording::new(&opts.wheel_joints);
    feed_mcap(path, buf, &mut rec)?;
    let stem = path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned());
    runs(path, &stem, rec, opts, external)
}

/// The poses of a ground-truth file on the wheel clock (seconds since `origin_s`), with the clock offset:
/// the forced one, or one estimated from the wheel data (`omni_kin::clock`). Errors name the file.
/// A `--gt` file's poses for a run on the wheel clock, its place for messages (`in FILE (+0.1 s clock
/// offset)`), its label (`ground truth FILE`) and its clock.
fn external_file(
    ext: &ExternalTruth,
    stem: &str,
    origin_s: i64,
    t_s: &[f64],
    rad_s: &[f64],
    n_wheels: usize,
) -> Result<(Vec<StampedPose>, String, String, Option<GtClock>), DatasetError> {
    let (poses, clock) = external_truth(ext, stem, origin_s, t_s, rad_s, n_wheels)?;
    let file = ext.path.display();
    Ok((
        poses,
        format!("in {file} ({:+.4} s clock offset)", clock.offset_s),
        format!("ground truth {file}"),
        Some(clock),
    ))
}

fn external_truth(
    ext: &ExternalTruth,
    recording: &str,
    origin_s: i64,
    t_s: &[f64],
    rad_s: &[f64],
    n_wheels: usize,
) -> Result<(Vec<StampedPose>, GtClock), DatasetError> {
    let pose =
        |s: &TruthSample, t_s: f64| StampedPose { t_s, pose: Pose2 { x_m: s.x_m, y_m: s.y_m, theta_rad: s.yaw_rad } };
    let clock = |offset_s: f64, estimate: Option<ClockAlignment>| GtClock {
        recording: recording.to_string(),
        file: ext.path.clone(),
        offset_s,
        estimate,
    };
    if let Some(offset_s) = ext.time_offset_s {
        let poses = ext.samples.iter().map(|s| pose(s, seconds_since(s.t_ns, origin_s) + offset_s)).collect();
        return Ok((poses, clock(offset_s, None)));
    }
    // The truth's times relative to its own first whole second (small numbers for the estimate).
    let truth_origin_s = ext.samples.first().map_or(0, |s| s.t_ns.div_euclid(NS_PER_S));
    let own: Vec<StampedPose> = ext.samples.iter().map(|s| pose(s, seconds_since(s.t_ns, truth_origin_s))).collect();
    let a = omni_kin::clock::align_clocks(t_s, rad_s, n_wheels, &own).map_err(|e| DatasetError::Clock {
        path: ext.path.clone(),
        message: format!("cannot align its clock with recording {recording:?}: {e}"),
    })?;
    // own + a.offset_s is on the wheel clock since origin_s.
    let poses = own.iter().map(|p| StampedPose { t_s: p.t_s + a.offset_s, ..*p }).collect();
    // t_wheel = t_truth + offset in absolute time: the relative offset less the origins' difference.
    let origins_s = (origin_s - truth_origin_s) as f64;
    let offset_s = a.offset_s + origins_s;
    let estimate = ClockAlignment { offset_s, coarse_offset_s: a.coarse_offset_s + origins_s, ..a };
    Ok((poses, clock(offset_s, Some(estimate))))
}

/// Words in a topic's name that mark a localization (AMCL, slam_toolbox, cartographer, robot_localization's
/// EKF/UKF `odometry/filtered`, …): its poses may fuse the very wheel odometry being calibrated, so it is
/// never taken as ground truth unless named.
const LOCALIZATION_WORDS: [&str; 8] = ["amcl", "locali", "slam", "cartographer", "ekf", "ukf", "filtered", "fused"];

/// Whether `topic` names a localization ([`LOCALIZATION_WORDS`], case-insensitive).
pub(super) fn is_localization(topic: &str) -> bool {
    let t = topic.to_ascii_lowercase();
    LOCALIZATION_WORDS.iter().any(|w| t.contains(w))
}

/// The note for a ground-truth topic named although it looks like a localization.
fn localization_note(path: &Path, topic: &str) -> Option<String> {
    is_localization(topic).then(|| {
        format!(
            "{}: topic {topic:?} is taken as ground truth as named, but it looks like a localization: if it fuses \
             the wheel odometry being calibrated, the fit measures the wheels against themselves",
            path.display()
        )
    })
}

/// The end of the "no ground truth" message when localizations were passed over.
fn localization_hint(localizations: &[&str]) -> String {
    if localizations.is_empty() {
        return String::new();
    }
    format!(
        "; {} looks like a localization, which may fuse the wheel odometry being calibrated, so it is not taken \
         as ground truth unless named with --gt-topic",
        localizations.join(", ")
    )
}

/// Largest clock offset between the wheel data and a ground-truth topic of the same recording taken as
/// recorded: a lag up to this is physics the `time_offset` effect models (its range) and diagnose names;
/// beyond it the topic runs on another clock (a motion-capture bridge stamping with its own). s.
pub const SAME_CLOCK_MAX_OFFSET_S: f64 = 0.5;

/// How clear an estimate must be for a topic's stamps to be moved: its standard error (s) and the share
/// of the ground truth's motion the wheels explain at it. A topic whose motion hardly follows the wheels
/// keeps its stamps (whatever is wrong with it, moving it would hide it).
pub const TOPIC_CLOCK_MAX_STD_ERROR_S: f64 = 0.02;
pub const TOPIC_CLOCK_MIN_R_SQUARED: f64 = 0.9;
/// The share of the ground truth's motion the wheels must explain at offset 0 for its clock to be taken as
/// the wheels' without a search.
pub const TOPIC_CLOCK_SEARCH_BELOW_R2: f64 = 0.98;

/// The clock of a ground-truth topic: `forced_s` when given (`--gt-time-offset`), else checked against the
/// wheels' ([`omni_kin::clock::align_clocks`]): when the
/// estimated offset is clear and beyond [`SAME_CLOCK_MAX_OFFSET_S`] and three standard errors, the poses
/// are moved onto the wheel clock and the offset returned (a note); otherwise, or when no estimate is
/// possible (too little motion), the stamps stay as recorded.
#[allow(clippy::too_many_arguments)] // the topic's names, its poses and the wheel data they are checked against
fn topic_clock(
    path: &Path,
    recording: &str,
    topic: &str,
    forced_s: Option<f64>,
    poses: &mut [StampedPose],
    t_s: &[f64],
    rad_s: &[f64],
    n_wheels: usize,
) -> Option<GtClock> {
    let clock = |offset_s: f64, estimate| GtClock {
        recording: recording.to_string(),
        file: PathBuf::from(format!("{}, topic {topic:?}", path.display())),
        offset_s,
        estimate,
    };
    if let Some(offset_s) = forced_s {
        poses.iter_mut().for_each(|p| p.t_s += offset_s);
        return Some(clock(offset_s, None));
    }
    // On the wheels' clock, or off it by a small lag (nearly always): the wheels explain nearly all the
    // truth's motion at offset 0, and no search is needed. (Half of it is not enough: slow, smooth motion
    // 0.8 s off is still 60 % explained.)
    if omni_kin::clock::explained_at(t_s, rad_s, n_wheels, poses, 0.0)
        .is_none_or(|r2| r2 >= TOPIC_CLOCK_SEARCH_BELOW_R2)
    {
        return None;
    }
    let a = omni_kin::clock::align_clocks(t_s, rad_s, n_wheels, poses).ok()?;
    let clear = a.std_error_s <= TOPIC_CLOCK_MAX_STD_ERROR_S && a.r_squared >= TOPIC_CLOCK_MIN_R_SQUARED;
    if !clear || a.offset_s.abs() <= SAME_CLOCK_MAX_OFFSET_S.max(3.0 * a.std_error_s) {
        return None;
    }
    poses.iter_mut().for_each(|p| p.t_s += a.offset_s);
    Some(clock(a.offset_s, Some(a)))
}

/// The wheels of `bag`'s JointState channel `j` (its content taken), with notes on what was done to them;
/// a topic without the wheel joints says what else could give them ([`Bag::odometry_hint`]).
fn joint_wheels(bag: &mut Bag, j: usize, opts: &McapOptions, notes: &mut Vec<String>) -> Result<Wheels, DatasetError> {
    let (path, topic, hint) = (bag.path, bag.channels[j].topic.clone(), bag.odometry_hint());
    let Content::Joints(series) = bag.take(j) else { unreachable!("joints() returns JointState channels") };
    if let Some((k, missing)) = series.no_wheel_message() {
        let message = hint.map_or_else(|| missing.clone(), |h| format!("{missing}; {h}"));
        return Err(DatasetError::at(path, format!("topic {topic:?}, message {k}"), message));
    }
    let Some(&first_ns) = series.t_ns.first() else {
        return Err(DatasetError::at(path, topic_location(&topic), "has no messages (empty run)"));
    };
    let origin_s = first_ns.div_euclid(NS_PER_S);
    let t_s: Vec<f64> = series.t_ns.iter().map(|&t| seconds_since(t, origin_s)).collect();
    let wheels = series
        .finish(&opts.wheel_joints, &t_s, &opts.wheel_data)
        .map_err(|(k, what)| DatasetError::at(path, format!("topic {topic:?}, message {k}"), what))?;
    notes.extend(wheels.notes.iter().map(|n| format!("{}: topic {topic:?}: {n}", path.display())));
    if let Some(without) = wheels.differentiated {
        notes.push(format!(
            "{}: topic {topic:?}: {without} of {} messages have no velocity: wheel speeds are differences \
             of position over header.stamp",
            path.display(),
            t_s.len()
        ));
    }
    Ok(wheels)
}

/// The wheels recovered from the robot's own odometry `odometry` on `topic` through the design
/// ([`super::odom_wheels`]), with a note saying so and what a fit can reach from them.
fn odometry_wheels(
    path: &Path,
    odometry: &Content,
    topic: &str,
    opts: &McapOptions,
    notes: &mut Vec<String>,
) -> Result<Wheels, DatasetError> {
    let (Content::Poses(series), Some(rows)) = (odometry, &opts.wheels_from_twist) else {
        unreachable!("joints() returns an odometry channel only with the design's forward kinematics")
    };
    let wheels = super::odom_wheels::wheels_from_odometry(series, rows)
        .map_err(|(k, what)| DatasetError::at(path, format!("topic {topic:?}, message {k}"), what))?;
    let reach = if rows.len() <= 3 {
        "every parameter of the model is within a fit's reach (as many wheels as the motion has degrees of freedom)"
            .to_string()
    } else {
        format!(
            "with {} wheels and 3 degrees of freedom a fit reaches a 3 × 3 correction of the design, not one \
             wheel's own radius",
            rows.len()
        )
    };
    notes.push(format!(
        "{}: no {} topic: the wheel speeds are recovered from topic {topic:?} (the robot's own odometry, {} \
         poses) through the design, as its controller computed them; {reach}",
        path.display(),
        joint_state::NAME,
        series.t_ns.len()
    ));
    Ok(wheels)
}

/// The ground-truth poses `all` within the wheel data's span `t_s` (a note counts those dropped); none is an
/// error naming the wheels' topic and where the ground truth came from (`names`: the wheels' topic, the
/// ground truth's place and label).
fn within_wheels(
    path: &Path,
    all: &[StampedPose],
    t_s: &[f64],
    names: (&str, &str, &str),
    notes: &mut Vec<String>,
) -> Result<Vec<StampedPose>, DatasetError> {
    let (joints_topic, truth_where, truth_label) = names;
    let (w0, w1) = (t_s[0], t_s[t_s.len() - 1]);
    let truth: Vec<StampedPose> = all.iter().copied().filter(|p| (w0..=w1).contains(&p.t_s)).collect();
    if truth.is_empty() {
        let span = match (all.first(), all.last()) {
            (Some(a), Some(b)) => format!("spans {}..{} s", a.t_s, b.t_s),
            _ => "has no poses".to_string(),
        };
        return Err(DatasetError::file(
            path,
            format!(
                "wheel data on {joints_topic:?} spans {w0}..{w1} s but the ground truth {truth_where} {span}: \
                 no ground-truth pose lies within the wheel data"
            ),
        ));
    }
    let dropped = all.len() - truth.len();
    if dropped > 0 {
        notes.push(format!(
            "{}: {truth_label}: dropped {dropped} ground-truth poses outside the wheel data's time span \
             ({w0}..{w1} s)",
            path.display()
        ));
    }
    Ok(truth)
}

/// A recording's streams on one time line (s since its origin), ready to be cut into runs.
struct Streams {
    t_s: Vec<f64>,
    wheels: Wheels,
    truth: Vec<StampedPose>,
    odometry: Vec<StampedPose>,
    commands: Option<Commands>,
    joints_topic: String,
}

impl Streams {
    /// The runs: the whole recording as one named `stem`, or with [`McapOptions::split`] its pieces between
    /// standstills named `stem#1`, `stem#2`, …; each with its name, or the error that refuses it.
    fn runs(&self, path: &Path, stem: &str, opts: &McapOptions) -> Vec<(String, Result<Run, DatasetError>)> {
        let (t_s, n_wheels) = (&self.t_s, opts.wheel_joints.len());
        let pieces = match opts.split {
            Some(min_s) => split::pieces(t_s, &self.wheels.rad_s, n_wheels, &self.truth, min_s),
            None => vec![(0, t_s.len() - 1)],
        };
        let last_piece = pieces.len() - 1;
        let mut out = Vec::with_capacity(pieces.len());
        for (p, &(lo, hi)) in pieces.iter().enumerate() {
            let name = if opts.split.is_some() { format!("{stem}#{}", p + 1) } else { stem.to_string() };
            let span = t_s[lo]..=t_s[hi];
            let within = |poses: &[StampedPose]| {
                let mut v: Vec<StampedPose> = poses.iter().copied().filter(|q| span.contains(&q.t_s)).collect();
                start_heading_in_half_turn(&mut v);
                v
            };
            // Commands tile the whole time line: the first run also takes those before it, the last those after.
            let from_ns = if p == 0 { i64::MIN } else { self.wheels.t_ns[lo] };
            let to_ns = if p == last_piece { i64::MAX } else { self.wheels.t_ns[hi] };
            let data = RunData {
                name: name.clone(),
                wheel_t_s: t_s[lo..=hi].to_vec(),
                wheel_rad_s: self.wheels.rad_s[lo * n_wheels..(hi + 1) * n_wheels].to_vec(),
                n_wheels,
                truth: within(&self.truth),
                command: self.commands.as_ref().and_then(|c| c.first_in(from_ns, to_ns)),
                repetition: None,
                recorded_odometry: within(&self.odometry),
                wheel_start_rad: self
                    .wheels
                    .position
                    .as_ref()
                    .map(|pos| pos[lo * n_wheels..(lo + 1) * n_wheels].to_vec())
                    .unwrap_or_default(),
            };
            out.push((name, Run::new(data).map_err(|e| self.run_error(path, lo, e))));
        }
        out
    }

    /// A run's validation error, for the run starting at wheel sample `lo`: a bad wheel sample is named as
    /// the wheel topic's message of the same index.
    fn run_error(&self, path: &Path, lo: usize, source: KinError) -> DatasetError {
        let joints_topic = &self.joints_topic;
        match &source {
            KinError::NonFinite { what: "wheel sample", index, .. }
            | KinError::NotIncreasing { what: "wheel sample", index, .. } => {
                DatasetError::at(path, format!("topic {joints_topic:?}, message {}", lo + index), source.to_string())
            }
            // No wheel turns at 10⁴ rad/s: the joints are in another unit.
            KinError::Implausible { what: "wheel sample", index, .. } => DatasetError::at(
                path,
                format!("topic {joints_topic:?}, message {}", lo + index),
                format!(
                    "{source}: are the joints in encoder counts, rpm or degrees? Declare their units in \
                     robot.toml's [wheel_data] (docs/formats.md)"
                ),
            ),
            _ => DatasetError::Run { path: path.to_path_buf(), error: source },
        }
    }
}

/// The file of a `--gt` folder that covers most of the wheel data's span `t_s` (s since `origin_s`), for a
/// recording no file is named after, with a note saying which and how much it covers.
fn overlapping_file(
    path: &Path,
    folder: &ExternalTruth,
    origin_s: i64,
    t_s: &[f64],
    notes: &mut Vec<String>,
) -> Result<ExternalTruth, DatasetError> {
    let at = |t: f64| origin_s * NS_PER_S + (t * 1e9).round() as i64;
    let (ext, share) = folder
        .overlapping(at(t_s[0]), at(t_s[t_s.len() - 1]))
        .map_err(|e| DatasetError::file(path, format!("--gt folder {}: {e}", folder.path.display())))?;
    notes.push(format!(
        "{}: no file of the --gt folder is named after it: {} covers {:.0} % of its span and is its ground truth",
        path.display(),
        ext.path.display(),
        100.0 * share
    ));
    Ok(ext)
}

/// The runs of a recording whose messages are all in `rec`; `path` names it in messages, `stem` names its
/// runs (`stem`, or `stem#1`, `stem#2`, … when split). See the module docs of [`super`].
///
/// With `external`, the ground truth comes from that file (its clock aligned to the wheels', see
/// [`external_truth`]) and the recording needs no ground-truth topic.
pub(crate) fn runs(
    path: &Path,
    stem: &str,
    rec: Recording,
    opts: &McapOptions,
    external: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    let mut bag = Bag { path, channels: rec.channels };
    let mut notes = Vec::new();

    let source = bag.joints(opts)?;
    let j = source.channel();
    bag.check_wheels(j)?;
    let truth_src = match external {
        Some(_) => None,
        None if opts.wheels_only => None,
        None => Some(bag.truth(opts)?),
    };
    let truth_ch = truth_src.map(Truth::channel);
    if let Some(i) = truth_ch {
        bag.check(i)?;
        notes.extend(localization_note(path, &bag.channels[i].topic));
    }
    let odom = if opts.recorded_odometry { bag.recorded_odometry(&mut notes) } else { None };
    let odom = odom.filter(|&i| Some(i) != truth_ch);
    let cmd = bag.commands(opts.command_topic.as_deref(), &mut notes);

    // Wheels.
    let joints_topic = bag.channels[j].topic.clone();
    let wheels = match source {
        WheelSource::Joints(_) => joint_wheels(&mut bag, j, opts, &mut notes)?,
        WheelSource::Odometry(_) => odometry_wheels(path, &bag.channels[j].content, &joints_topic, opts, &mut notes)?,
    };
    let origin_s = wheels.t_ns[0].div_euclid(NS_PER_S);
    let t_s: Vec<f64> = wheels.t_ns.iter().map(|&t| seconds_since(t, origin_s)).collect();

    // Ground truth, trimmed to the wheel data's span.
    let n_wheels = opts.wheel_joints.len();
    let (all_truth, truth_where, truth_label, clock) = match (truth_src, truth_ch, external) {
        (Some(src), Some(ch), _) => {
            let (truth_topic, mut poses) = bag.truth_poses(src, ch, origin_s, opts, &mut notes)?;
            let forced = opts.truth_time_offset_s;
            let clock = topic_clock(path, stem, &truth_topic, forced, &mut poses, &t_s, &wheels.rad_s, n_wheels);
            (poses, format!("on {truth_topic:?}"), format!("topic {truth_topic:?}"), clock)
        }
        (_, _, Some(ext)) if !ext.by_time.is_empty() => {
            let ext = overlapping_file(path, ext, origin_s, &t_s, &mut notes)?;
            external_file(&ext, stem, origin_s, &t_s, &wheels.rad_s, n_wheels)?
        }
        (_, _, Some(ext)) => external_file(ext, stem, origin_s, &t_s, &wheels.rad_s, n_wheels)?,
        _ if opts.wheels_only => {
            let at = |t_s: f64| StampedPose { t_s, pose: omni_kin::Pose2::IDENTITY };
            let placeholder = vec![at(t_s[0]), at(t_s[t_s.len() - 1])];
            (placeholder, "measured at the end".to_string(), "the measured end pose".to_string(), None)
        }
        _ => unreachable!("the ground truth comes from a topic or a file"),
    };
    let truth = within_wheels(path, &all_truth, &t_s, (&joints_topic, &truth_where, &truth_label), &mut notes)?;
    let odometry: Vec<StampedPose> = match odom.map(|i| bag.take(i)) {
        Some(Content::Poses(p)) => p.stamped(origin_s),
        _ => Vec::new(),
    };
    let commands = match cmd.map(|i| bag.take(i)) {
        Some(Content::Commands(c)) => Some(c),
        _ => None,
    };

    // Runs.
    let streams = Streams { t_s, wheels, truth, odometry, commands, joints_topic };
    let mut out = McapRead { runs: Vec::new(), notes, skipped: Vec::new(), origin_s, ground_truth_clock: clock };
    for (name, run) in streams.runs(path, stem, opts) {
        match run {
            Ok(run) => out.runs.push(run),
            Err(e) if opts.skip_invalid => out.skipped.push((name, e.to_string())),
            Err(e) => return Err(e),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(topic: &str, msg_type: MsgType, frame: Option<&str>, problem: Option<&str>) -> Channel {
        let content = match msg_type {
            MsgType::Odometry => Content::Poses(PoseSeries { frame: frame.map(String::from), ..Default::default() }),
            _ => Content::Commands(Commands::default()),
        };
        Channel {
            topic: topic.into(),
            schema: String::new(),
            msg_type,
            messages: 3,
            content,
            problem: problem.map(|p| (Some(2), p.to_string())),
        }
    }

    #[test]
    fn optional_sources_are_left_out_with_a_note() {
        let path = Path::new("a.mcap");
        let odom = |t: &str| channel(t, MsgType::Odometry, Some(ODOM_FRAME), None);
        let bag = Bag { path, channels: vec![odom("/robot1/odom"), odom("/robot2/odom")] };
        let mut notes = Vec::new();
        assert_eq!(bag.recorded_odometry(&mut notes), None);
        assert_eq!(
            notes,
            ["a.mcap: recorded odometry could come from several topics (/robot1/odom, /robot2/odom), none of them \
              /odom: recorded odometry is left out"]
        );
        let bag = Bag { path, channels: vec![odom("/robot1/odom"), odom("/odom")] };
        assert_eq!(bag.recorded_odometry(&mut Vec::new()), Some(1));

        let bag = Bag {
            path,
            channels: vec![channel("/cmd_vel", MsgType::TwistStamped, None, Some("field linear.x is NaN"))],
        };
        let mut notes = Vec::new();
        assert_eq!(bag.commands(None, &mut notes), None);
        assert_eq!(notes, ["a.mcap: topic \"/cmd_vel\", message 2: field linear.x is NaN (the command is left out)"]);
    }

    #[test]
    fn a_localization_is_never_taken_as_ground_truth_unless_named() {
        let path = Path::new("a.mcap");
        let bag = Bag { path, channels: vec![channel("/amcl_pose", MsgType::Odometry, Some("map"), None)] };
        let e = bag.truth(&McapOptions::default()).err().unwrap().to_string();
        assert!(
            e.ends_with(
                "; /amcl_pose looks like a localization, which may fuse the wheel odometry being calibrated, so it is \
                 not taken as ground truth unless named with --gt-topic"
            ),
            "{e}"
        );
        let named = McapOptions { truth_topic: Some("/amcl_pose".into()), ..Default::default() };
        assert!(matches!(bag.truth(&named), Ok(Truth::Poses(0))));
        let bag = Bag {
            path,
            channels: vec![
                channel("/amcl_pose", MsgType::Odometry, Some("map"), None),
                channel("/mocap/pose", MsgType::Odometry, Some("world"), None),
            ],
        };
        assert!(matches!(bag.truth(&McapOptions::default()), Ok(Truth::Poses(1))));
    }
}
