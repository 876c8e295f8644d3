//! `omnical init REC --kind KIND` on a recording without a URDF (a ROS 1 bag has no `/robot_description`;
//! many ROS 2 recordings leave it out): a robot.toml skeleton from the recording's joint names and the
//! kind given, each value to measure marked [`FILL_IN`]. The robot description reader refuses a file while a
//! mark is left (`robot_file::parse`), naming the line.

use crate::dataset::mcap::{Inventory, TopicSummary};
use omni_kin::robot::BaseKind;
use std::fmt::Write as _;

/// The mark on a value still to measure.
pub const FILL_IN: &str = "FILL IN";

/// The JointState topic whose joints the skeleton names: `/joint_states` if it is one, else the one with the
/// most joints.
fn joint_topic(inv: &Inventory) -> Option<&TopicSummary> {
    let topics = inv.topics.iter().filter(|t| !t.joint_names.is_empty());
    let all: Vec<&TopicSummary> = topics.collect();
    all.iter().find(|t| t.topic == "/joint_states").or_else(|| all.iter().max_by_key(|t| t.joint_names.len())).copied()
}

/// The skeleton's text, its joints and the topic they come from; an error when the recording names no joint.
pub fn skeleton(inv: &Inventory, recording: &str, kind: BaseKind) -> Result<(String, Vec<String>, String), String> {
    let Some(topic) = joint_topic(inv) else {
        return Err("the recording has no JointState topic with joint names, which a skeleton names the wheels \
                    after; write robot.toml by hand (docs/formats.md)"
            .to_string());
    };
    let joints = topic.joint_names.clone();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# robot.toml skeleton drafted by `omnical init {recording} --kind {kind}`: the recording has no URDF, so the\n\
         # geometry is yours to measure. Write each value marked {FILL_IN} and remove the mark: omnical refuses\n\
         # the file while a mark is left. Lengths in metres, angles in degrees (docs/formats.md).\n\
         #\n\
         # The joints of {} ({}), in the order the wheel columns take.",
        topic.topic, topic.msg_type
    );
    let _ = writeln!(s, "kind = \"{}\"", kind.name());
    let mark = |what: &str| format!("  # {FILL_IN}: {what}");
    match kind {
        BaseKind::Diff => {
            let named = |side: &str| joints.iter().find(|j| j.to_lowercase().contains(side));
            let (left, right) = match (named("left"), named("right"), &joints[..]) {
                (Some(l), Some(r), _) => (l.clone(), r.clone()),
                (_, _, [a, b]) => (a.clone(), b.clone()),
                _ => (joints[0].clone(), joints.get(1).cloned().unwrap_or_default()),
            };
            let checked = named("left").is_some() && named("right").is_some();
            let side = |j: &str, which: &str| {
                if checked {
                    format!("\"{j}\"")
                } else {
                    format!("\"{j}\"{}", mark(&format!("the {which} wheel's joint, one of {}", joints.join(", "))))
                }
            };
            let _ = writeln!(s, "\n[diff]");
            let _ = writeln!(s, "left_joint = {}", side(&left, "left"));
            let _ = writeln!(s, "right_joint = {}", side(&right, "right"));
            let _ = writeln!(s, "wheel_separation_m = 0.0{}", mark("between the two wheels' contact points, m"));
            let _ = writeln!(s, "left_radius_m = 0.0{}", mark("the left wheel's radius, m"));
            let _ = writeln!(s, "right_radius_m = 0.0{}", mark("the right wheel's radius, m"));
        }
        BaseKind::Omni | BaseKind::Mecanum | BaseKind::Skid => {
            if joints.len() > if kind == BaseKind::Mecanum { 4 } else { 8 } {
                let _ = writeln!(
                    s,
                    "# The topic names {} joints: delete the [[wheels]] of those that are no wheels.",
                    joints.len()
                );
            }
            for j in &joints {
                let _ = writeln!(s, "\n[[wheels]]\njoint = \"{j}\"");
                let _ = writeln!(s, "x_m = 0.0{}", mark("the wheel's contact point ahead of the base's centre, m"));
                let _ = writeln!(s, "y_m = 0.0{}", mark("the wheel's contact point left of the base's centre, m"));
                let _ = writeln!(s, "radius_m = 0.0{}", mark("m"));
                if kind == BaseKind::Mecanum {
                    let _ = writeln!(
                        s,
                        "roller_angle_deg = 45.0{}",
                        mark("+45 or −45: the rollers' angle to the axle, seen from above")
                    );
                } else if kind == BaseKind::Skid {
                    let _ = writeln!(
                        s,
                        "drive_deg = 0.0{}",
                        mark("0 if positive speed drives the base forward, 180 if backward")
                    );
                } else {
                    let _ = writeln!(
                        s,
                        "drive_deg = 0.0{}",
                        mark("where the rim pushes the base at positive speed, degrees from x (forward) to y (left)")
                    );
                }
            }
        }
    }
    let _ = writeln!(s, "\n[topics]\njoint_states = \"{}\"", topic.topic);
    Ok((s, joints, topic.topic.clone()))
}

/// The first line of `text` still marked [`FILL_IN`] (1-based), and its key.
pub fn first_mark(text: &str) -> Option<(usize, String)> {
    text.lines().enumerate().find_map(|(i, line)| {
        let (value, comment) = line.split_once('#')?;
        let key = value.split('=').next()?.trim();
        (comment.contains(FILL_IN) && !key.is_empty()).then(|| (i + 1, key.to_string()))
    })
}
