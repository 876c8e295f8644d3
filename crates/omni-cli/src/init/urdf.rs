//! The wheels of a URDF (parsed with `urdf-rs`): every `continuous` joint whose child link has a cylinder
//! (collision geometry first, else visual), with its position and axle in the root link's frame and the
//! cylinder's radius.
//!
//! Joint origins compose from the root link down (`xyz`, then fixed-axis `rpy`: R = Rz(yaw)·Ry(pitch)·
//! Rx(roll)); joints are taken at zero position. A wheel turning at positive speed about its axle `a`
//! (right-hand rule) pushes the robot along `a × z`, i.e. `a` turned by −90° in the plane.

/// A 3 × 3 rotation, rows.
type Mat3 = [[f64; 3]; 3];

/// A wheel found in a URDF.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfWheel {
    /// The joint name.
    pub joint: String,
    /// The wheel's link.
    pub link: String,
    /// The joint origin in the root link's frame. m.
    pub position_m: [f64; 3],
    /// The joint axis (unit) in the root link's frame.
    pub axle: [f64; 3],
    /// The cylinder's radius. m.
    pub radius_m: f64,
    /// `collision` or `visual`: where the radius comes from.
    pub radius_from: &'static str,
}

impl UrdfWheel {
    /// The direction the rim pushes the robot at positive wheel speed, from x towards y, in (−180, 180].
    /// deg.
    pub fn drive_deg(&self) -> f64 {
        let [ax, ay, _] = self.axle;
        let d = (-ax).atan2(ay).to_degrees();
        if d <= -180.0 { d + 360.0 } else { d }
    }

    /// Whether the axle lies (nearly) in the ground plane, as a driving wheel's does.
    pub fn axle_is_horizontal(&self) -> bool {
        self.axle[2].abs() < 0.1
    }
}

/// The wheels of a URDF, and what else was noticed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UrdfWheels {
    /// The robot's name in the URDF.
    pub robot: String,
    /// The frame positions and axles are in: `base_link` when the URDF has one (the robot's base, which a
    /// ground truth tracks by default), else the root link.
    pub root: String,
    /// When `root` is `base_link` below the URDF's root link: that link, and `base_link`'s origin in it. m.
    pub base_in_root: Option<(String, [f64; 3])>,
    /// The wheels, in URDF order.
    pub wheels: Vec<UrdfWheel>,
    /// Continuous joints whose child link has no cylinder (not taken as wheels).
    pub without_cylinder: Vec<String>,
    /// Passive casters, not taken as wheels: continuous joints with a cylinder below a joint that swivels
    /// about a vertical axis, or named `caster`.
    pub casters: Vec<String>,
}

fn rpy_matrix([roll, pitch, yaw]: [f64; 3]) -> Mat3 {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

fn apply(a: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Pose (rotation, translation) of `link` in the root's frame, walking the parents up; `None` for a loop.
fn pose_in_root(robot: &urdf_rs::Robot, link: &str) -> Option<(Mat3, [f64; 3])> {
    let mut chain = Vec::new();
    let mut at = link;
    while let Some(j) = robot.joints.iter().find(|j| j.child.link == at) {
        if chain.len() > robot.joints.len() {
            return None;
        }
        chain.push(j);
        at = &j.parent.link;
    }
    let (mut r, mut t) = (IDENTITY, [0.0; 3]);
    for j in chain.iter().rev() {
        let o = apply(&r, *j.origin.xyz);
        t = [t[0] + o[0], t[1] + o[1], t[2] + o[2]];
        r = mul(&r, &rpy_matrix(*j.origin.rpy));
    }
    Some((r, t))
}

/// Whether the wheel on `joint` is a passive caster: named so (joint or link), or hanging below a
/// non-fixed joint whose axis is vertical in the root's frame (the caster's swivel).
fn is_caster(robot: &urdf_rs::Robot, joint: &urdf_rs::Joint) -> bool {
    let named = |s: &str| s.to_lowercase().contains("caster");
    if named(&joint.name) || named(&joint.child.link) {
        return true;
    }
    let mut at = joint.parent.link.as_str();
    for _ in 0..robot.joints.len() {
        let Some(up) = robot.joints.iter().find(|j| j.child.link == at) else { return false };
        if up.joint_type != urdf_rs::JointType::Fixed {
            let r = pose_in_root(robot, &up.parent.link).map_or(IDENTITY, |(r, _)| r);
            let a = apply(&mul(&r, &rpy_matrix(*up.origin.rpy)), *up.axis.xyz);
            let norm = a.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > 0.0 && (a[2] / norm).abs() > 0.9 {
                return true;
            }
        }
        at = &up.parent.link;
    }
    false
}

/// The radius of a link's cylinder: collision geometry first, else visual.
fn cylinder(link: &urdf_rs::Link) -> Option<(f64, &'static str)> {
    let of = |g: &urdf_rs::Geometry| match g {
        urdf_rs::Geometry::Cylinder { radius, .. } => Some(*radius),
        _ => None,
    };
    link.collision
        .iter()
        .find_map(|c| of(&c.geometry).map(|r| (r, "collision")))
        .or_else(|| link.visual.iter().find_map(|v| of(&v.geometry).map(|r| (r, "visual"))))
}

/// The wheels of a URDF document. Errors are the parser's message.
pub fn wheels(text: &str) -> Result<UrdfWheels, String> {
    let robot = urdf_rs::read_from_string(text).map_err(|e| format!("not a URDF this reader understands: {e}"))?;
    let roots: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !robot.joints.iter().any(|j| j.child.link == *n))
        .collect();
    let root = match roots[..] {
        [r] => r.to_string(),
        [] => return Err("the URDF has no root link (every link is some joint's child)".into()),
        _ => return Err(format!("the URDF has several root links ({}); it must be one tree", roots.join(", "))),
    };
    // Positions in base_link, not in a base_footprint above it that sits elsewhere in the plane.
    const BASE: &str = "base_link";
    let base =
        (root != BASE && robot.links.iter().any(|l| l.name == BASE)).then(|| pose_in_root(&robot, BASE)).flatten();
    let to_base = |v: [f64; 3], t: [f64; 3]| match &base {
        // Rᵀ (v − t): a root-frame vector in base_link's frame.
        Some((r, _)) => [0, 1, 2].map(|i| (0..3).map(|k| r[k][i] * (v[k] - t[k])).sum()),
        None => v,
    };
    let base_origin = base.as_ref().map_or([0.0; 3], |(_, t)| *t);
    let mut out = UrdfWheels {
        robot: robot.name.clone(),
        root: if base.is_some() { BASE.to_string() } else { root.clone() },
        base_in_root: base.as_ref().map(|(_, t)| (root.clone(), *t)),
        ..UrdfWheels::default()
    };
    for j in robot.joints.iter().filter(|j| j.joint_type == urdf_rs::JointType::Continuous) {
        let Some(link) = robot.links.iter().find(|l| l.name == j.child.link) else {
            return Err(format!("joint {:?}: its child link {:?} is not defined", j.name, j.child.link));
        };
        let Some((radius_m, radius_from)) = cylinder(link) else {
            out.without_cylinder.push(j.name.clone());
            continue;
        };
        if is_caster(&robot, j) {
            out.casters.push(j.name.clone());
            continue;
        }
        let (r, _) = pose_in_root(&robot, &j.parent.link)
            .ok_or_else(|| format!("joint {:?}: the links above it form a loop", j.name))?;
        let (_, position_m) = pose_in_root(&robot, &j.child.link)
            .ok_or_else(|| format!("joint {:?}: the links above it form a loop", j.name))?;
        let a = apply(&mul(&r, &rpy_matrix(*j.origin.rpy)), *j.axis.xyz);
        let norm = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(format!("joint {:?}: axis {:?} has no direction", j.name, *j.axis.xyz));
        }
        out.wheels.push(UrdfWheel {
            joint: j.name.clone(),
            link: link.name.clone(),
            position_m: to_base(position_m, base_origin),
            axle: to_base(a.map(|v| v / norm), [0.0; 3]),
            radius_m,
            radius_from,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn rpy_turns_the_axis_as_ros_does() {
        // TurtleBot-style wheel: axis z in a frame rolled by −90° about x → the axle points along +y.
        let a = apply(&rpy_matrix([-std::f64::consts::FRAC_PI_2, 0.0, 0.0]), [0.0, 0.0, 1.0]);
        assert!((a[0]).abs() < 1e-15 && (a[1] - 1.0).abs() < 1e-15 && a[2].abs() < 1e-15, "{a:?}");
        // Yaw 90° turns x into y.
        let b = apply(&rpy_matrix([0.0, 0.0, std::f64::consts::FRAC_PI_2]), [1.0, 0.0, 0.0]);
        assert!(b[0].abs() < 1e-15 && (b[1] - 1.0).abs() < 1e-15, "{b:?}");
        let w = UrdfWheel {
            joint: "l".into(),
            link: "l".into(),
            position_m: [0.0; 3],
            axle: [0.0, 1.0, 0.0],
            radius_m: 0.1,
            radius_from: "visual",
        };
        assert_eq!(w.drive_deg(), 0.0);
        assert_eq!(UrdfWheel { axle: [0.0, -1.0, 0.0], ..w.clone() }.drive_deg(), 180.0);
        assert_eq!(UrdfWheel { axle: [1.0, 0.0, 0.0], ..w }.drive_deg(), -90.0);
    }
}
