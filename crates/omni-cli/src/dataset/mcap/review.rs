//! What omnical makes of each topic of a recording, for `omnical info`: the role it would play in a read
//! with the given options (wheels, ground truth, recorded odometry, command, static transforms; a lidar, an
//! IMU or the URDF for the commands that use them) or why it plays none. The verdicts come from the same
//! topic choice as the read ([`Bag::joints`], [`Bag::truth`], …), so `info` cannot say one thing and
//! `train` do another.

use super::recording::{Channel, Content, MsgType, Recording};
use super::selection::{self, Bag, Truth, WheelSource};
use super::{McapOptions, imu, inspect::ROBOT_DESCRIPTION_TOPIC, laser_scan, tf};
use crate::api::settings::{self, named_with};
use crate::dataset::DatasetError;
use std::path::Path;

/// The role of one topic in a read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// The wheels' JointState.
    Wheels,
    /// The ground truth (a pose topic, or a pair of a TF topic).
    GroundTruth,
    /// A ground-truth candidate among several: none is taken until one is named.
    Candidate,
    /// The robot's own wheel odometry, kept beside the runs.
    RecordedOdometry,
    /// The command (Twist, TwistStamped).
    Command,
    /// Static transforms the ground truth is moved along.
    StaticTransforms,
    /// A lidar's scans (`--gt-scans`, `scan-odometry`).
    Lidar,
    /// An IMU (`omnical imu`).
    Imu,
    /// The robot's URDF (`omnical init`).
    Urdf,
    /// Not read.
    Unused,
}

/// What omnical makes of one topic.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TopicReview {
    /// The topic.
    pub topic: String,
    /// Its role in a read with the options given.
    pub role: Role,
    /// Why, in one sentence: what it is used as, or why it is not.
    pub why: String,
}

/// The message of an error, without the file name the caller already shows.
fn message(e: &DatasetError) -> String {
    match e {
        DatasetError::At { location, message, .. } => format!("{location}: {message}"),
        DatasetError::File { message, .. } | DatasetError::Clock { message, .. } => message.clone(),
        DatasetError::Io { error, .. } => error.to_string(),
        DatasetError::Run { error, .. } => error.to_string(),
    }
}

/// The choices a read makes on a recording.
struct Choices {
    joints: Result<WheelSource, DatasetError>,
    /// `None`: the ground truth comes from elsewhere (a `--gt` file, another reference).
    truth: Option<Result<Truth, DatasetError>>,
    odometry: Option<usize>,
    command: Option<usize>,
}

/// Every topic of the recording `rec` (read whole, from `path`) with its role in a read with `opts`;
/// `truth_elsewhere` names where the ground truth comes from instead of a topic (`--gt FILE`), if it does.
/// Sorted by topic.
pub(crate) fn review(
    path: &Path,
    rec: Recording,
    opts: &McapOptions,
    truth_elsewhere: Option<&str>,
) -> Vec<TopicReview> {
    let bag = Bag { path, channels: rec.channels };
    let mut notes = Vec::new();
    let choices = Choices {
        joints: bag.joints(opts),
        truth: (truth_elsewhere.is_none() && !opts.wheels_only).then(|| bag.truth(opts)),
        odometry: bag.recorded_odometry(&mut notes),
        command: bag.commands(opts.command_topic.as_deref(), &mut notes),
    };
    let mut out: Vec<TopicReview> = (0..bag.channels.len())
        .filter(|&i| bag.channels[i].messages > 0)
        .map(|i| {
            let (role, why) = topic_role(&bag, i, &choices, opts, truth_elsewhere);
            let why = match (&bag.channels[i].problem, role) {
                (Some((k, what)), Role::Wheels | Role::GroundTruth) => {
                    let at = k.map_or_else(String::new, |k| format!("message {k}: "));
                    format!("{why}; but {at}{what}")
                }
                _ => why,
            };
            TopicReview { topic: bag.channels[i].topic.clone(), role, why }
        })
        .collect();
    out.sort_by(|a, b| a.topic.cmp(&b.topic));
    out
}

/// The role of channel `i` and why.
fn topic_role(
    bag: &Bag,
    i: usize,
    choices: &Choices,
    opts: &McapOptions,
    truth_elsewhere: Option<&str>,
) -> (Role, String) {
    let c = &bag.channels[i];
    match c.msg_type {
        MsgType::JointState => joints_role(bag, i, &choices.joints, opts),
        MsgType::PoseStamped
        | MsgType::PoseWithCovarianceStamped
        | MsgType::PointStamped
        | MsgType::NavSatFix
        | MsgType::Odometry => {
            if let (Some(Err(e)), Some(named)) = (&choices.truth, &opts.truth_topic)
                && *named == c.topic
            {
                let why =
                    format!("named as the ground truth ({}), refused: {}", settings::named("gt_topic"), message(e));
                return (Role::Unused, why);
            }
            if let Ok(WheelSource::Odometry(o)) = choices.joints
                && o == i
            {
                return (
                    Role::Wheels,
                    format!(
                        "the robot's own odometry stands in for the missing JointState: wheel speeds ({}) recovered \
                         from its poses through the design",
                        opts.wheel_joints.join(", ")
                    ),
                );
            }
            if choices.odometry == Some(i) {
                return (
                    Role::RecordedOdometry,
                    "the robot's own wheel odometry (frame \"odom\", REP-105): kept beside the runs for comparison, \
                     never ground truth"
                        .into(),
                );
            }
            pose_role(bag, i, choices, opts, truth_elsewhere)
        }
        MsgType::Tf => tf_role(bag, i, choices, truth_elsewhere),
        MsgType::Twist | MsgType::TwistStamped if choices.command == Some(i) => {
            (Role::Command, "each run's first non-zero twist is its command (--split cuts at standstills)".into())
        }
        MsgType::Twist | MsgType::TwistStamped => {
            (Role::Unused, "another topic is the command (robot.toml's [topics] command chooses)".into())
        }
        MsgType::Other => other_role(c),
    }
}

fn joints_role(bag: &Bag, i: usize, joints: &Result<WheelSource, DatasetError>, opts: &McapOptions) -> (Role, String) {
    let units = &opts.wheel_data;
    match joints {
        Ok(WheelSource::Joints(j)) if *j == i => (
            Role::Wheels,
            format!(
                "joints {} in wheel order (position in {}, velocity in {})",
                opts.wheel_joints.join(", "),
                units.position.name(),
                units.velocity.name()
            ),
        ),
        Ok(source) => (Role::Unused, format!("the wheels come from {}", bag.channels[source.channel()].topic)),
        Err(e) => (Role::Unused, format!("no wheels read: {}", message(e))),
    }
}

/// A pose topic (PoseStamped, PoseWithCovarianceStamped, Odometry) that is not the recorded odometry.
fn pose_role(
    bag: &Bag,
    i: usize,
    choices: &Choices,
    opts: &McapOptions,
    truth_elsewhere: Option<&str>,
) -> (Role, String) {
    let c = &bag.channels[i];
    let robot_frame = c.frame().filter(|f| selection::ROBOT_FRAMES.contains(f));
    match &choices.truth {
        Some(Ok(Truth::Poses(t))) if *t == i => {
            let mut why = format!("{} poses{}", c.messages, frame_words(c));
            if selection::is_localization(&c.topic) {
                why.push_str(", as named: it looks like a localization, which may fuse the wheel odometry");
            }
            return (Role::GroundTruth, why);
        }
        _ if c.is_wheel_odometry() => {
            return (Role::Unused, "wheel odometry (frame \"odom\", REP-105): never ground truth".into());
        }
        _ if robot_frame.is_some() => {
            return (
                Role::Unused,
                format!("in the robot's own frame {:?}: not a ground truth", robot_frame.unwrap_or("")),
            );
        }
        _ if selection::is_localization(&c.topic) => {
            return (
                Role::Unused,
                format!(
                    "a localization: it may fuse the wheel odometry being calibrated, so it is ground truth only when \
                     named ({})",
                    settings::named("gt_topic")
                ),
            );
        }
        _ => {}
    }
    if let Some(why) = bag.truth_mismatch(i, opts) {
        return (Role::Unused, format!("not a ground truth: it {why}"));
    }
    match (&choices.truth, truth_elsewhere) {
        (_, Some(source)) => (Role::Unused, format!("a ground-truth candidate, but the ground truth is {source}")),
        (None, None) => (Role::Unused, "a ground-truth candidate; this read takes the wheels only".into()),
        (Some(Ok(_)), None) => (Role::Unused, "a ground-truth candidate; another source was chosen".into()),
        (Some(Err(e)), None) => (Role::Candidate, message(e)),
    }
}

/// ` (frame "map")`, or nothing.
fn frame_words(c: &Channel) -> String {
    c.frame().map_or_else(String::new, |f| format!(" (frame {f:?})"))
}

/// A TF topic: its pairs, and which one (if any) is the ground truth.
fn tf_role(bag: &Bag, i: usize, choices: &Choices, truth_elsewhere: Option<&str>) -> (Role, String) {
    let c = &bag.channels[i];
    let Content::Tf(pairs) = &c.content else { return (Role::Unused, "no transforms read".into()) };
    let list: Vec<String> = pairs.pairs.iter().map(|p| format!("{} → {}", p.parent, p.child)).collect();
    let list = if list.is_empty() { "none".to_string() } else { list.join(", ") };
    if tf::is_static_topic(&c.topic) {
        return (
            Role::StaticTransforms,
            format!("{list}: a ground truth of a tracked frame is moved along them to the base"),
        );
    }
    match (&choices.truth, truth_elsewhere) {
        (Some(Ok(Truth::Tf(t, k))), _) if *t == i => {
            let p = &pairs.pairs[*k];
            (Role::GroundTruth, format!("the pair {} → {} (transforms: {list})", p.parent, p.child))
        }
        (Some(Err(e)), None) if !pairs.candidates(None, None, &bag.statics()).is_empty() => {
            (Role::Candidate, format!("transforms {list}: {}", message(e)))
        }
        (_, Some(source)) => (Role::Unused, format!("transforms {list}; the ground truth is {source}")),
        _ => (Role::Unused, format!("transforms {list}: none is taken as ground truth")),
    }
}

/// A topic of a type the runs are not read from.
fn other_role(c: &Channel) -> (Role, String) {
    let t = &c.topic;
    match c.schema.as_str() {
        laser_scan::NAME => (
            Role::Lidar,
            format!(
                "a relative reference with {}; its path: omnical scan-odometry --topic {t}",
                named_with("gt_scans", t)
            ),
        ),
        imu::NAME => (Role::Imu, format!("omnical imu --topic {t} fits the wheel matrix's rotation row")),
        "std_msgs/msg/String" if t.ends_with(ROBOT_DESCRIPTION_TOPIC) => {
            (Role::Urdf, "omnical init drafts robot.toml from it".into())
        }
        _ => (Role::Unused, "not read by omnical".into()),
    }
}
