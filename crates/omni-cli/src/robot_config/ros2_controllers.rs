//! The controller file of a robot configuration ([`super::CONTROLLER_YAML`]: the ros2_controllers drive
//! controller's parameters, with the accuracy it gives up and warnings as comments), and what `omnical
//! export` prints about it.

use super::odometry::{COMMENT_WIDTH, num, quoted, wrap};
use super::{Accuracy, CONTROLLER_YAML, ODOMETRY_HEADER, ODOMETRY_YAML, RobotConfig};
use crate::controller::{ControllerKind, ControllerParams};
use std::fmt::Write as _;
use std::path::Path;

/// The controller's parameters in SI units as `(name, value)`, for messages.
pub fn params_text(p: &ControllerParams) -> String {
    match *p {
        ControllerParams::DiffDrive { wheel_separation_m, left_wheel_radius_m, right_wheel_radius_m } => format!(
            "separation {wheel_separation_m:.5} m, left radius {left_wheel_radius_m:.5} m, right radius {right_wheel_radius_m:.5} m"
        ),
        ControllerParams::MecanumDrive { wheels_radius_m, lx_plus_ly_m } => {
            format!("wheel radius {wheels_radius_m:.5} m, lx + ly {lx_plus_ly_m:.5} m")
        }
        ControllerParams::OmniWheelDrive { wheel_radius_m, robot_radius_m, wheel_offset_rad } => format!(
            "wheel radius {wheel_radius_m:.5} m, robot radius {robot_radius_m:.5} m, wheel offset {wheel_offset_rad:.5} rad ({:.2}°)",
            wheel_offset_rad.to_degrees()
        ),
    }
}

/// How the controller counts a positive wheel speed.
fn convention(kind: ControllerKind) -> &'static str {
    match kind {
        ControllerKind::DiffDrive | ControllerKind::MecanumDrive => "drives the robot forward",
        ControllerKind::OmniWheelDrive => "turns the robot clockwise seen from above",
    }
}

/// Where each ros2_controllers version has the controller, and the parameter file its names come from.
fn availability(kind: ControllerKind) -> &'static str {
    match kind {
        ControllerKind::DiffDrive => {
            "every ROS 2 distribution (Humble, Jazzy, Kilted, Rolling); names from \
             diff_drive_controller/src/diff_drive_controller_parameter.yaml"
        }
        ControllerKind::MecanumDrive => {
            "Humble from 2.43.0, Jazzy (4.x), Kilted and Rolling; names from \
             mecanum_drive_controller/src/mecanum_drive_controller.yaml (pre-release versions used \
             command_joint_names and kinematics.wheels_k)"
        }
        ControllerKind::OmniWheelDrive => {
            "Jazzy from 4.30.0, Kilted (5.x) and Rolling, not Humble; names from \
             omni_wheel_drive_controller/src/omni_wheel_drive_controller_parameters.yaml"
        }
    }
}

fn pct_text(c: f64, m: f64) -> String {
    if m > 0.0 {
        format!("{:+.1} %", 100.0 * (c - m) / m)
    } else if c == m {
        "+0.0 %".into()
    } else {
        "n/a".into()
    }
}

/// The accuracy table (model, matrix alone, controller, loss), one line per row.
pub fn accuracy_lines(c: &RobotConfig) -> Vec<String> {
    let row = |label: &str, a: &Accuracy| format!("  {label:<34} {:>10.5} {:>10.5}", a.end_pose, a.path_rms);
    let title = format!("accuracy on the {} runs given:", c.n_runs);
    let mut v = vec![format!("{title:<36} {:>10} {:>10}", "Eq. 6", "path RMS")];
    if c.against == super::Against::ModelOdometry {
        v.push("  (the runs have no ground truth: measured against the calibrated model's own odometry)".into());
    }
    v.push(row("design (uncalibrated)", &c.design_accuracy));
    v.push(row("calibrated model", &c.model_accuracy));
    if let Some(m) = &c.matrix_accuracy {
        v.push(row("its matrix alone (the header)", m));
    }
    v.push(row(c.kind().id(), &c.controller_accuracy));
    if c.against == super::Against::ModelOdometry {
        // The model's row is 0 by construction: the controller's row is already what it gives up.
        v.push("  (the controller's row is its distance from the calibrated model: what it gives up)".into());
        return v;
    }
    let (m, k) = (&c.model_accuracy, &c.controller_accuracy);
    v.push(format!(
        "  {:<34} {:>10} {:>10}",
        "given up by the controller",
        pct_text(k.end_pose, m.end_pose),
        pct_text(k.path_rms, m.path_rms)
    ));
    v
}

/// Largest distance of the omni wheels' angles (read off the matrix) from the equal spacing the
/// controller assumes. rad.
fn spacing_error_rad(c: &RobotConfig) -> Option<f64> {
    let ControllerParams::OmniWheelDrive { wheel_offset_rad, .. } = c.fit.model.params else { return None };
    let n = c.fit.slot_angles_rad.len();
    c.fit
        .slot_angles_rad
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let d = a - wheel_offset_rad - std::f64::consts::TAU * i as f64 / n as f64;
            omni_kin::pose::wrap_angle(d).abs()
        })
        .reduce(f64::max)
}

/// Warnings about using the controller, one sentence each.
pub fn warning_lines(c: &RobotConfig) -> Vec<String> {
    let kind = c.kind();
    let mut v = Vec::new();
    let reversed = c.reversed_joints();
    if !reversed.is_empty() {
        v.push(format!(
            "{kind} counts a wheel speed positive when it {}; these joints count the other way: {}. Negate their \
             position and velocity in the hardware interface (or a transmission with a negative reduction) before \
             loading these parameters; the accuracy above assumes you do.",
            convention(kind),
            reversed.join(", ")
        ));
    }
    if let Some(e) = spacing_error_rad(c).filter(|e| e.to_degrees() > 1.0) {
        v.push(format!(
            "the wheels sit up to {:.1}° from the equal spacing {kind} assumes; its odometry cannot follow that.",
            e.to_degrees()
        ));
    }
    if kind == ControllerKind::DiffDrive && c.design_fit.is_none() {
        v.push("no design to scale: wheel_separation and wheel_radius are the fitted values, multipliers 1.0.".into());
    }
    if !c.effects.is_empty() {
        let ids: Vec<&str> = c.effects.iter().map(|e| e.id.as_str()).collect();
        v.push(format!("the controller cannot carry the model's effects ({}).", ids.join(", ")));
    }
    v
}

fn comment_block(c: &RobotConfig) -> String {
    let kind = c.kind();
    let t = c.fit.twist_rms;
    let lines = [
        format!("ros2_control parameters for {kind} ({}),", kind.plugin()),
        format!("generated by omnical {} from {}.", env!("CARGO_PKG_VERSION"), c.spec),
        format!("Available in {}.", availability(kind)),
        format!(
            "Nearest parametric fit: the controller's parameters whose odometry best reproduces the calibrated \
             matrix's body twists over the wheel speeds of the {} runs given (least squares weighted by their \
             second moments, ω weighted 1 m/rad). Twist RMS difference: vx {:.2e} m/s, vy {:.2e} m/s, ω {:.2e} rad/s.",
            c.n_runs, t.vx_m_s, t.vy_m_s, t.omega_rad_s
        ),
    ];
    let mut lines: Vec<String> = lines.iter().flat_map(|l| wrap(l, COMMENT_WIDTH)).collect();
    lines.extend(accuracy_lines(c));
    for n in &c.base_notes {
        lines.extend(wrap(&format!("NOTE: {n}"), COMMENT_WIDTH));
    }
    for w in warning_lines(c) {
        lines.extend(wrap(&format!("WARNING: {w}"), COMMENT_WIDTH));
    }
    lines.iter().map(|l| format!("# {l}\n")).collect()
}

/// The controller's parameters in controller_manager style.
pub fn controller_yaml(c: &RobotConfig) -> String {
    let kind = c.kind();
    let mut s = comment_block(c);
    let _ = writeln!(s, "controller_manager:\n  ros__parameters:\n    {}:\n      type: {}\n", kind.id(), kind.plugin());
    let _ = writeln!(s, "{}:\n  ros__parameters:", kind.id());
    let name = |slot: usize| quoted(&c.wheel_names[c.fit.model.layout.columns[slot]]);
    match c.fit.model.params {
        ControllerParams::DiffDrive { wheel_separation_m, left_wheel_radius_m, right_wheel_radius_m } => {
            let (s0, r0) = match c.design_fit.as_ref().map(|d| d.model.params) {
                Some(ControllerParams::DiffDrive {
                    wheel_separation_m: s,
                    left_wheel_radius_m: l,
                    right_wheel_radius_m: r,
                }) => (s, (l + r) / 2.0),
                _ => (wheel_separation_m, (left_wheel_radius_m + right_wheel_radius_m) / 2.0),
            };
            let k = c.wheel_names.len() / 2;
            let names = |slots: std::ops::Range<usize>| slots.map(name).collect::<Vec<_>>().join(", ");
            let _ =
                writeln!(s, "    left_wheel_names: [{}]\n    right_wheel_names: [{}]", names(0..k), names(k..2 * k));
            let _ = writeln!(
                s,
                "    wheel_separation: {}  # design, m\n    wheel_radius: {}  # design, m",
                num(s0),
                num(r0)
            );
            let _ = writeln!(
                s,
                "    wheel_separation_multiplier: {}  # fitted {} m",
                num(wheel_separation_m / s0),
                num(wheel_separation_m)
            );
            let _ = writeln!(
                s,
                "    left_wheel_radius_multiplier: {}  # fitted {} m",
                num(left_wheel_radius_m / r0),
                num(left_wheel_radius_m)
            );
            let _ = writeln!(
                s,
                "    right_wheel_radius_multiplier: {}  # fitted {} m",
                num(right_wheel_radius_m / r0),
                num(right_wheel_radius_m)
            );
        }
        ControllerParams::MecanumDrive { wheels_radius_m, lx_plus_ly_m } => {
            for (slot, key) in ["front_left", "front_right", "rear_left", "rear_right"].iter().enumerate() {
                let _ = writeln!(s, "    {key}_wheel_command_joint_name: {}", name(slot));
            }
            let _ = writeln!(s, "    kinematics:\n      wheels_radius: {}  # m", num(wheels_radius_m));
            let _ =
                writeln!(s, "      sum_of_robot_center_projection_on_X_Y_axis: {}  # lx + ly, m", num(lx_plus_ly_m));
        }
        ControllerParams::OmniWheelDrive { wheel_radius_m, robot_radius_m, wheel_offset_rad } => {
            let names: Vec<String> = (0..c.wheel_names.len()).map(name).collect();
            let _ = writeln!(s, "    wheel_names: [{}]  # anticlockwise from wheel_offset", names.join(", "));
            let offset = omni_kin::pose::wrap_angle(wheel_offset_rad);
            let _ = writeln!(s, "    wheel_offset: {}  # rad ({:.3}°)", num(offset), offset.to_degrees());
            let _ = writeln!(
                s,
                "    robot_radius: {}  # m\n    wheel_radius: {}  # m",
                num(robot_radius_m),
                num(wheel_radius_m)
            );
        }
    }
    if let Some(n) = &c.noise {
        s.push_str(&super::noise::controller_lines(c, n));
    }
    s
}

/// What `omnical export` prints about the robot configuration (on stdout; [`warning_lines`] go to stderr).
pub fn summary(c: &RobotConfig, dir: &Path) -> String {
    let t = c.fit.twist_rms;
    let noise_files = if c.noise.is_some() {
        format!(", {} and {}", super::AMCL_YAML, super::ROBOT_LOCALIZATION_YAML)
    } else {
        String::new()
    };
    let mut s = format!(
        "wrote {ODOMETRY_YAML}, {ODOMETRY_HEADER}, {CONTROLLER_YAML}{noise_files} to {}\n{}: {} (nearest fit; twist RMS \
         difference vx {:.2e} m/s, vy {:.2e} m/s, ω {:.2e} rad/s)\n",
        dir.display(),
        c.kind(),
        params_text(&c.fit.model.params),
        t.vx_m_s,
        t.vy_m_s,
        t.omega_rad_s
    );
    for l in accuracy_lines(c) {
        let _ = writeln!(s, "{l}");
    }
    for n in &c.base_notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}
