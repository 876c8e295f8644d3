//! The odometry noise model where the ROS stack reads it (issue 46), from the `[noise]` a model file holds
//! ([`omni_kin::noise`]): the covariance diagonals of the controller's odometry messages (in
//! [`super::CONTROLLER_YAML`]), Nav2 AMCL's motion model ([`AMCL_YAML`]) and robot_localization's use of the
//! odometry's twist ([`ROBOT_LOCALIZATION_YAML`]).
//!
//! ros2_controllers publishes fixed diagonals that never grow with the distance driven: the pose diagonal
//! written is the covariance after [`POSE_HORIZON_M`] driven straight (the noise model's along, across and
//! heading variances there), the twist diagonal the variance of one message's velocity at the runs' RMS
//! speed and turn rate, published at [`MESSAGE_RATE_HZ`]. Entries for z, roll and pitch, which a planar
//! base does not measure, are [`UNMEASURED`].

use super::RobotConfig;
use super::odometry::{COMMENT_WIDTH, num, wrap};
use crate::controller::ControllerKind;
use omni_kin::noise::{self, OdometryNoise};
use std::fmt::Write as _;

/// Nav2 AMCL's parameter file.
pub const AMCL_YAML: &str = "nav2_amcl.yaml";
/// robot_localization's parameter file.
pub const ROBOT_LOCALIZATION_YAML: &str = "robot_localization.yaml";
/// Driven distance at which the fixed pose diagonal is the noise model's covariance. m.
pub const POSE_HORIZON_M: f64 = 1.0;
/// The rate the controller's odometry messages are assumed published at (diff_drive_controller's default
/// `publish_rate`). Hz.
pub const MESSAGE_RATE_HZ: f64 = 50.0;
/// Variance written for dimensions a planar base does not measure (z, roll, pitch): large, so a filter that
/// fuses them by mistake gives them no weight.
pub const UNMEASURED: f64 = 1.0e6;

/// Where the diagonals come from: the runs' RMS speed (m/s) and turn rate (rad/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TypicalMotion {
    /// RMS speed. m/s.
    pub speed_m_s: f64,
    /// RMS turn rate. rad/s.
    pub turn_rad_s: f64,
}

/// The pose covariance diagonal (x, y, z, roll, pitch, yaw) after `POSE_HORIZON_M` (1 m) driven straight,
/// the per-run biases included (a straight drive does not renew the wandering heading error).
pub fn pose_diagonal(n: &OdometryNoise) -> [f64; 6] {
    let r = n.rates.without_floor();
    let d = POSE_HORIZON_M;
    let strafe = if n.holonomic { r.strafe_per_m * d } else { 0.0 };
    // Heading noise driven on grows the lateral variance by rot_per_m d³ / 3; a run's heading drift κ
    // moves it by κ d² / 2.
    let lateral = strafe + r.rot_per_m * d.powi(3) / 3.0 + r.run_drift_var * d.powi(4) / 4.0;
    let along = r.trans_per_m * d + r.run_scale_var * d * d;
    let heading = r.rot_per_m * d + r.run_drift_var * d * d;
    [along, lateral, UNMEASURED, UNMEASURED, UNMEASURED, heading]
}

/// The twist covariance diagonal (vx, vy, vz, ωx, ωy, ωz) of one message at `motion`.
pub fn twist_diagonal(n: &OdometryNoise, motion: TypicalMotion) -> [f64; 6] {
    let [vx, vy, w] = noise::twist_variances(
        &n.rates.without_floor(),
        n.holonomic,
        motion.speed_m_s,
        motion.turn_rad_s,
        MESSAGE_RATE_HZ,
    );
    [vx, vy, UNMEASURED, UNMEASURED, UNMEASURED, w]
}

fn list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| num(*x)).collect();
    format!("[{}]", items.join(", "))
}

/// The comment above the covariance diagonals in the controller file.
fn diagonal_comment(n: &OdometryNoise, motion: TypicalMotion) -> String {
    let text = format!(
        "Covariance diagonals from omnical's noise model (fitted on {} windows of {} training runs; \
         `omnical eval` checks it on held-out runs). They are per message and do not grow: the pose diagonal is \
         the covariance after {POSE_HORIZON_M} m driven straight (it is too small beyond, too large before: the \
         true one grows with the distance driven, see {AMCL_YAML}); the twist diagonal is one message's velocity \
         variance at the runs' RMS speed {:.3} m/s and turn rate {:.3} rad/s, published at {MESSAGE_RATE_HZ} Hz \
         (it scales with 1/dt: rescale for another rate). z, roll and pitch: {} (not measured).",
        n.windows,
        n.runs,
        motion.speed_m_s,
        motion.turn_rad_s,
        num(UNMEASURED)
    );
    wrap(&text, COMMENT_WIDTH).iter().map(|l| format!("    # {l}\n")).collect()
}

/// The controller's covariance parameters (appended under its `ros__parameters`).
pub fn controller_lines(c: &RobotConfig, n: &OdometryNoise) -> String {
    let (pose, twist) = (list(&pose_diagonal(n)), list(&twist_diagonal(n, c.motion)));
    let mut s = diagonal_comment(n, c.motion);
    match c.kind() {
        ControllerKind::OmniWheelDrive => {
            let _ = writeln!(s, "    diagonal_covariance:\n      pose: {pose}\n      twist: {twist}");
        }
        ControllerKind::DiffDrive | ControllerKind::MecanumDrive => {
            let _ = writeln!(s, "    pose_covariance_diagonal: {pose}\n    twist_covariance_diagonal: {twist}");
        }
    }
    s
}

/// A comment block of wrapped lines.
fn comment(lines: &[String]) -> String {
    lines.iter().flat_map(|l| wrap(l, COMMENT_WIDTH)).map(|l| format!("# {l}\n")).collect()
}

/// The parameter uncertainty in words: each alpha with its standard error.
fn alpha_lines(n: &OdometryNoise) -> Vec<String> {
    let a = crate::api::noise::amcl(n);
    let se = n.std_errors.map(|e| noise::Amcl::from_rates(&e, n.holonomic, a.update_min_d_m, a.update_min_a_rad).alpha);
    (0..5)
        .map(|k| match se {
            Some(e) => format!("    alpha{}: {}  # ± {:.2e} (one standard error)", k + 1, num(a.alpha[k]), e[k]),
            None => format!("    alpha{}: {}", k + 1, num(a.alpha[k])),
        })
        .collect()
}

/// Nav2 AMCL's motion-model parameters for the base.
pub fn amcl_yaml(c: &RobotConfig, n: &OdometryNoise) -> String {
    let a = crate::api::noise::amcl(n);
    let model = if n.holonomic { "nav2_amcl::OmniMotionModel" } else { "nav2_amcl::DifferentialMotionModel" };
    let r = &n.rates;
    let mut s = comment(&[
        format!(
            "Nav2 AMCL motion model for {}, generated by omnical {} from {}.",
            c.spec,
            env!("CARGO_PKG_VERSION"),
            c.spec
        ),
        "For Nav2 on Humble, Jazzy, Kilted and Rolling (robot_model_type takes the plugin names since Galactic); \
         names from nav2_amcl/src/amcl_node.cpp."
            .into(),
        format!(
            "AMCL adds variances alpha · δ² per filter update, so the alphas hold for updates every update_min_d \
             and update_min_a (below): they are the noise model's rates over those thresholds (heading {} rad²/rad \
             and {} rad²/m, along {} m²/m and {} m²/rad, across {} m²/m). Change the thresholds and the alphas \
             must change with them.",
            num(r.rot_per_rad),
            num(r.rot_per_m),
            num(r.trans_per_m),
            num(r.trans_per_rad),
            num(r.strafe_per_m)
        ),
    ]);
    let _ = writeln!(s, "amcl:\n  ros__parameters:\n    robot_model_type: \"{model}\"");
    for l in alpha_lines(n) {
        let _ = writeln!(s, "{l}");
    }
    let _ = writeln!(s, "    update_min_d: {}\n    update_min_a: {}", num(a.update_min_d_m), num(a.update_min_a_rad));
    s
}

/// robot_localization's EKF fusing the controller's odometry twist.
pub fn robot_localization_yaml(c: &RobotConfig, n: &OdometryNoise) -> String {
    let twist = twist_diagonal(n, c.motion);
    let mut s = comment(&[
        format!(
            "robot_localization (ekf_node) fusing the wheel odometry's twist, generated by omnical {} from {}.",
            env!("CARGO_PKG_VERSION"),
            c.spec
        ),
        "For robot_localization's ros2 branch: Humble, Jazzy, Kilted and Rolling; names from \
         robot_localization/params/ekf.yaml."
            .into(),
        format!(
            "robot_localization reads the covariance from each odometry message: {} publishes the twist \
             covariance diagonal of {} (vx {} m²/s², vy {} m²/s², ωz {} rad²/s²; in {}). The twist is fused, not \
             the pose: the pose covariance of the controller does not grow, so fusing its pose would trust the \
             odometry more the farther the robot drives.",
            c.kind(),
            super::CONTROLLER_YAML,
            num(twist[0]),
            num(twist[1]),
            num(twist[5]),
            super::CONTROLLER_YAML
        ),
    ]);
    // The controllers' odometry topics: `~/odometry` for mecanum_drive_controller, `~/odom` for the others.
    let topic = if c.kind() == ControllerKind::MecanumDrive { "odometry" } else { "odom" };
    let _ = writeln!(
        s,
        "ekf_filter_node:\n  ros__parameters:\n    two_d_mode: true\n    odom0: /{}/{topic}\n    # x, y, z, roll, pitch, yaw, vx, vy, vz, vroll, vpitch, vyaw, ax, ay, az\n    odom0_config: [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]\n    odom0_differential: false\n    odom0_relative: false",
        c.kind().id()
    );
    s
}
