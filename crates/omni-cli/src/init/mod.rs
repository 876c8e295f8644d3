//! `omnical init`: a first robot description drafted from a recording and the robot's URDF.
//!
//! The recording gives the topics (types, counts, rates) and the joint names of its JointState topics; the
//! URDF (a file, or the recording's `/robot_description`) gives the wheels: continuous joints whose child
//! link has a cylinder (origin → position, axis → drive direction, cylinder → radius). The kind is guessed
//! from the wheels (2 → `diff`; 4 with "mecanum" in a joint or link name → `mecanum`, rollers guessed by
//! quadrant; otherwise `omni`), and every guess is written as a comment beside the value.

pub mod skeleton;
pub mod urdf;

use crate::dataset::mcap::{Inventory, TopicSummary};
use crate::robot_file::Comments;
use omni_kin::robot::{BaseKind, DiffSpec, Frames, RobotDescription, Topics, WheelSpec};
use urdf::{UrdfWheel, UrdfWheels};

/// Where the URDF came from, for comments and messages.
#[derive(Clone, Debug)]
pub struct UrdfSource {
    /// `robot.urdf` or `topic /robot_description of rec.mcap`.
    pub label: String,
}

/// A drafted robot description with the comments that say what was read and guessed.
#[derive(Clone, Debug)]
pub struct Draft {
    /// The description (valid).
    pub description: RobotDescription,
    /// Header and per-wheel comments.
    pub comments: Comments,
    /// Things the user must check, also printed on stderr.
    pub warnings: Vec<String>,
}

/// Why no description could be drafted (the caller names the URDF's source).
#[derive(Clone, Debug, PartialEq)]
pub enum DraftError {
    /// No wheel: no continuous joint with a cylinder on its child link.
    NoWheels {
        /// Continuous joints whose child has no cylinder.
        without_cylinder: Vec<String>,
    },
    /// The URDF's wheels are not in the recording's JointState topics.
    JointsNotRecorded {
        /// The URDF's wheel joints.
        urdf: Vec<String>,
        /// The joint names in the recording.
        recorded: Vec<String>,
    },
    /// One wheel, or a kind that does not fit the wheel count.
    Kind(String),
    /// The drafted description does not validate (e.g. wheels on one line).
    Invalid(String),
}

impl std::fmt::Display for DraftError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoWheels { without_cylinder } if without_cylinder.is_empty() => {
                f.write_str("no wheel found: the URDF has no continuous joint (wheels turn on continuous joints)")
            }
            Self::NoWheels { without_cylinder } => write!(
                f,
                "no wheel found: the continuous joints {} have child links without a cylinder geometry (collision \
                 or visual), which gives a wheel's radius; add one, or write robot.toml by hand (docs/formats.md)",
                without_cylinder.join(", ")
            ),
            Self::JointsNotRecorded { urdf, recorded } => write!(
                f,
                "its wheel joints ({}) are not in the recording's JointState topics (joints there: {})",
                urdf.join(", "),
                if recorded.is_empty() { "none".to_string() } else { recorded.join(", ") }
            ),
            Self::Kind(why) | Self::Invalid(why) => f.write_str(why),
        }
    }
}

/// Rounds to `decimals` places (lengths to 1 nm, angles to 1 µdeg), so the file shows `0.195`, not
/// `0.19500000000000003`; no negative zero.
fn round(v: f64, decimals: i32) -> f64 {
    let k = 10f64.powi(decimals);
    (v * k).round() / k + 0.0
}

/// The wheels to describe, in the recording's joint order when it has them.
fn recorded_wheels(found: &UrdfWheels, inv: &Inventory) -> Result<(Vec<UrdfWheel>, Option<String>), DraftError> {
    let joint_topics: Vec<&TopicSummary> = inv.topics.iter().filter(|t| !t.joint_names.is_empty()).collect();
    if joint_topics.is_empty() {
        return Ok((found.wheels.clone(), None));
    }
    // The JointState topic naming the most URDF wheels; its order is the column order.
    let best = joint_topics
        .iter()
        .max_by_key(|t| found.wheels.iter().filter(|w| t.joint_names.contains(&w.joint)).count())
        .copied();
    let ordered: Vec<UrdfWheel> = best.map_or_else(Vec::new, |t| {
        t.joint_names.iter().filter_map(|n| found.wheels.iter().find(|w| &w.joint == n).cloned()).collect()
    });
    if ordered.is_empty() {
        let mut recorded: Vec<String> = joint_topics.iter().flat_map(|t| t.joint_names.clone()).collect();
        recorded.dedup();
        return Err(DraftError::JointsNotRecorded {
            urdf: found.wheels.iter().map(|w| w.joint.clone()).collect(),
            recorded,
        });
    }
    Ok((ordered, best.map(|t| t.topic.clone())))
}

fn guess_kind(wheels: &[UrdfWheel], forced: Option<BaseKind>) -> Result<(BaseKind, String), DraftError> {
    let mecanum_named = wheels.iter().any(|w| (w.joint.clone() + &w.link).to_lowercase().contains("mecanum"));
    match (forced, wheels.len()) {
        (Some(k), _) => Ok((k, format!("kind {k}: given with --kind"))),
        (None, 0 | 1) => Err(DraftError::Kind(format!(
            "{} wheel found; a base needs 2 (diff) or at least 3 (omni, mecanum)",
            wheels.len()
        ))),
        (None, 2) => Ok((BaseKind::Diff, "kind diff: guessed from the 2 wheels".into())),
        (None, 4) if mecanum_named => {
            Ok((BaseKind::Mecanum, "kind mecanum: guessed from 4 wheels with \"mecanum\" in their names".into()))
        }
        (None, n)
            if n >= 4
                && n.is_multiple_of(2)
                && wheels.iter().all(|w| w.drive_deg().to_radians().sin().abs() < 1e-3) =>
        {
            Ok((
                BaseKind::Skid,
                format!(
                    "kind skid: guessed from {n} wheels whose axles all point sideways. If they are mecanum wheels, \
                     set kind = \"mecanum\" and roller_angle_deg = ±45 per wheel (docs/formats.md): a URDF does \
                     not model rollers"
                ),
            ))
        }
        (None, 4) => Ok((
            BaseKind::Omni,
            "kind omni: guessed from 4 wheels. If they are mecanum wheels, set kind = \"mecanum\" and \
             roller_angle_deg = ±45 per wheel (docs/formats.md): a URDF does not model rollers"
                .into(),
        )),
        (None, n) => Ok((BaseKind::Omni, format!("kind omni: guessed from the {n} wheels"))),
    }
}

fn wheel_note(w: &UrdfWheel, root: &str) -> String {
    let p = w.position_m.map(|v| round(v, 9));
    let a = w.axle.map(|v| round(v, 9));
    format!(
        "joint {}: origin ({}, {}, {}) m in {root}, axle ({}, {}, {}); radius from link {}'s {} cylinder",
        w.joint, p[0], p[1], p[2], a[0], a[1], a[2], w.link, w.radius_from
    )
}

fn omni_wheels(wheels: &[UrdfWheel], kind: BaseKind, root: &str) -> (Vec<WheelSpec>, Vec<Vec<String>>) {
    let mut specs = Vec::new();
    let mut notes = Vec::new();
    for w in wheels {
        let mut note = vec![wheel_note(w, root)];
        let roller_angle_deg = (kind == BaseKind::Mecanum).then(|| {
            // The usual layout: front-left and rear-right −45°, the others +45°.
            let r = if w.position_m[0] * w.position_m[1] > 0.0 { -45.0 } else { 45.0 };
            note.push(format!("roller_angle_deg {r}: GUESSED from the wheel's corner (a URDF has no rollers)"));
            r
        });
        specs.push(WheelSpec {
            joint: w.joint.clone(),
            x_m: Some(round(w.position_m[0], 9)),
            y_m: Some(round(w.position_m[1], 9)),
            drive_deg: Some(round(w.drive_deg(), 6)),
            radius_m: round(w.radius_m, 9),
            roller_angle_deg,
            ..WheelSpec::default()
        });
        notes.push(note);
    }
    (specs, notes)
}

fn diff_axle(wheels: &[UrdfWheel], root: &str, warnings: &mut Vec<String>) -> (DiffSpec, Vec<String>) {
    let (l, r) = if wheels[0].position_m[1] >= wheels[1].position_m[1] {
        (&wheels[0], &wheels[1])
    } else {
        (&wheels[1], &wheels[0])
    };
    for w in [l, r] {
        let d = w.drive_deg();
        if d.abs() > 1.0 {
            warnings.push(format!(
                "joint {} pushes along {d:.1}° at positive speed (URDF axle {:?}); a diff base assumes forward (0°): \
                 check the sign of its JointState velocity",
                w.joint, w.axle
            ));
        }
    }
    let dx = l.position_m[0] - r.position_m[0];
    let dy = l.position_m[1] - r.position_m[1];
    let spec = DiffSpec {
        wheel_separation_m: round(dx.hypot(dy), 9),
        left_joint: l.joint.clone(),
        right_joint: r.joint.clone(),
        left_radius_m: round(l.radius_m, 9),
        right_radius_m: round(r.radius_m, 9),
    };
    let notes = vec![
        wheel_note(l, root),
        wheel_note(r, root),
        "left: the wheel with the larger y; wheel_separation_m: the distance between the two joint origins".into(),
    ];
    (spec, notes)
}

/// The topics to name: the wheels' JointState topic, a single pose topic as ground truth, `/cmd_vel` or a
/// single Twist topic as the command. Returns the topics and comment lines listing the candidates.
fn guess_topics(inv: &Inventory, joints_topic: Option<String>) -> (Topics, Vec<String>) {
    let of_types = |types: &[&str]| -> Vec<&TopicSummary> {
        inv.topics.iter().filter(|t| types.contains(&t.msg_type.as_str())).collect()
    };
    let poses = of_types(&[
        "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/PoseWithCovarianceStamped",
        "geometry_msgs/msg/PointStamped",
        "sensor_msgs/msg/NavSatFix",
    ]);
    let other_truth = of_types(&["nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage"]);
    let commands = of_types(&["geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"]);
    let mut notes = Vec::new();
    let ground_truth = match poses[..] {
        [one] => Some(one.topic.clone()),
        _ => {
            let all: Vec<&str> = poses.iter().chain(&other_truth).map(|t| t.topic.as_str()).collect();
            notes.push(format!(
                "ground truth not chosen (candidates: {}); set [topics] ground_truth, and for a TF topic [frames]",
                if all.is_empty() { "none".to_string() } else { all.join(", ") }
            ));
            None
        }
    };
    let command = commands
        .iter()
        .find(|t| t.topic == "/cmd_vel")
        .or(if commands.len() == 1 { commands.first() } else { None })
        .map(|t| t.topic.clone());
    (Topics { joint_states: joints_topic, ground_truth, command }, notes)
}

fn inventory_lines(inv: &Inventory, recording: &str) -> Vec<String> {
    let mut lines = vec![format!("Read from the recording {recording}:")];
    for t in &inv.topics {
        let rate = t.rate_hz().map_or_else(|| "-".to_string(), |r| format!("{r:.1} Hz"));
        let joints =
            if t.joint_names.is_empty() { String::new() } else { format!(", joints {}", t.joint_names.join(", ")) };
        lines.push(format!("  {} ({}): {} messages, {rate}{joints}", t.topic, t.msg_type, t.count));
    }
    lines
}

/// The header lines on continuous joints not taken as wheels: without a cylinder, or passive casters.
fn not_wheels(found: &UrdfWheels) -> Vec<String> {
    let mut lines = Vec::new();
    if !found.without_cylinder.is_empty() {
        lines.push(format!("Not wheels (no cylinder on the child link): {}.", found.without_cylinder.join(", ")));
    }
    if !found.casters.is_empty() {
        lines.push(format!(
            "Not driven (passive casters: below a swivel joint, or named caster): {}.",
            found.casters.join(", ")
        ));
    }
    lines
}

/// Drafts a robot description from what a recording and a URDF hold.
pub fn draft(
    inv: &Inventory,
    recording: &str,
    found: &UrdfWheels,
    urdf: &UrdfSource,
    forced: Option<BaseKind>,
) -> Result<Draft, DraftError> {
    let horizontal: Vec<UrdfWheel> = found.wheels.iter().filter(|w| w.axle_is_horizontal()).cloned().collect();
    if horizontal.is_empty() {
        return Err(DraftError::NoWheels { without_cylinder: found.without_cylinder.clone() });
    }
    let (wheels, joints_topic) = recorded_wheels(&UrdfWheels { wheels: horizontal, ..found.clone() }, inv)?;
    let (kind, kind_note) = guess_kind(&wheels, forced)?;
    let mut warnings = Vec::new();
    let mut header = vec![
        format!("robot.toml drafted by `omnical init {recording}`: check every value before calibrating."),
        String::new(),
    ];
    header.extend(inventory_lines(inv, recording));
    header.push(String::new());
    header.push(match &found.base_in_root {
        None => format!(
            "Read from the URDF ({}): robot {:?}, root link {} (positions and axles are in its frame); wheels \
             are continuous joints whose child link has a cylinder.",
            urdf.label, found.robot, found.root
        ),
        Some((root, t)) => format!(
            "Read from the URDF ({}): robot {:?}, root link {root}; positions and axles are in {} (at ({}, {}, \
             {}) m in {root}: the frame a ground truth is moved to by default); wheels are continuous joints \
             whose child link has a cylinder.",
            urdf.label,
            found.robot,
            found.root,
            round(t[0], 9),
            round(t[1], 9),
            round(t[2], 9)
        ),
    });
    header.extend(not_wheels(found));
    header.push(String::new());
    header.push("Guessed:".into());
    header.push(format!("  {kind_note}"));
    header.push(match &joints_topic {
        Some(t) => format!("  column order: as the joints appear in {t}"),
        None => "  column order: as in the URDF (the recording has no JointState joint names)".into(),
    });
    let (topics, topic_notes) = guess_topics(inv, joints_topic);
    header.extend(topic_notes.into_iter().map(|n| format!("  {n}")));
    let mut description = RobotDescription {
        name: (!found.robot.is_empty()).then(|| found.robot.clone()),
        kind,
        wheels: Vec::new(),
        diff: None,
        topics,
        frames: Frames::default(),
        ground_truth: None,
        priors: None,
        wheel_data: Default::default(),
    };
    let wheel_notes = match kind {
        BaseKind::Diff if wheels.len() == 2 => {
            let (spec, notes) = diff_axle(&wheels, &found.root, &mut warnings);
            description.diff = Some(spec);
            vec![notes]
        }
        BaseKind::Diff => {
            return Err(DraftError::Kind(format!("kind diff needs 2 wheels, the URDF has {}", wheels.len())));
        }
        _ => {
            let (specs, notes) = omni_wheels(&wheels, kind, &found.root);
            description.wheels = specs;
            notes
        }
    };
    description.validate().map_err(|e| DraftError::Invalid(format!("the drafted description is not valid: {e}")))?;
    header.extend(warnings.iter().map(|w| format!("  CHECK: {w}")));
    Ok(Draft { description, comments: Comments { header, wheels: wheel_notes }, warnings })
}
