//! ROS 2 base controllers as kinematic models, and the controller nearest to a fitted IK matrix.
//!
//! The drive controllers of ros2_controllers compute odometry from wheel speeds with a fixed parametric
//! model, each in its own wheel order and sign convention (read from their `odometry.cpp`):
//!
//! - **`diff_drive_controller`** (slots left, right; positive = forward):
//!   `vx = (r_L ω_L + r_R ω_R) / 2`, `vy = 0`, `ω = (r_R ω_R − r_L ω_L) / s`, with
//!   `s = wheel_separation · wheel_separation_multiplier` and
//!   `r_L = wheel_radius · left_wheel_radius_multiplier` (right likewise).
//! - **`mecanum_drive_controller`** (slots front left, front right, rear left, rear right; positive =
//!   forward): `vx = r/4 (FL + FR + RL + RR)`, `vy = r/4 (−FL + FR + RL − RR)`,
//!   `ω = r/(4k) (−FL + FR − RL + RR)` with `r = kinematics.wheels_radius` and
//!   `k = kinematics.sum_of_robot_center_projection_on_X_Y_axis` (lx + ly).
//! - **`omni_wheel_drive_controller`** (N ≥ 3 wheels equally spaced on a circle, anticlockwise from the
//!   first at `wheel_offset`): wheel `i` at `θ_i = wheel_offset + 2π i / N` obeys
//!   `r ω_i = sin θ_i vx − cos θ_i vy − R ω`, and the twist is the least-squares solution over the wheels.
//!   A positive wheel speed turns the robot **clockwise** (pure rotation ω > 0 gives negative wheel
//!   speeds), the opposite of omnical's omni-wheel convention ([`omni_kin::geometry`]).
//!
//! A robot's joints may count the other way round than the controller expects; [`WheelLayout`] records
//! which model column feeds each controller slot and whether its sign must be reversed (by the hardware
//! interface or a transmission) before the controller reads it.
//!
//! ## The nearest parametric fit
//! For wheel speeds `w` with second moment `S = E[w wᵀ]` (rad²/s², averaged over the runs' samples,
//! each run counting equally) the mean squared difference between the twists of two matrices is, row by
//! row, `ΔM_j S ΔM_jᵀ`. So the least-squares fit over every body twist of the runs is the same as a fit of
//! the matrix entries weighted by the runs' wheel-speed second moments; [`fit`] minimises
//! `Σ_j λ_j² ΔM_j S ΔM_jᵀ` with `λ = (1, 1, heading weight)` over the controller's own parameters
//! (the project's Levenberg–Marquardt, [`omni_ga::LevenbergMarquardt`], on 2–3 parameters from a start read
//! off the matrix). Directions the runs never excite carry no weight and stay near that start (a step
//! along the excited ones may move them a little: the minimum is a valley there). When the target is of
//! the controller's form the fit reproduces it to rounding.
//!
//! This is ROS knowledge used by `omnical export --robot-config` ([`crate::robot_config`]), so it lives in
//! the crate that writes the files, not in the kinematics core.

mod fit;

pub use fit::fit;

use nalgebra::{DMatrix, DVector};
use omni_kin::{Choice, IkMatrix, KinError, Run, Twist2};
use std::f64::consts::TAU;
use std::fmt;
use std::str::FromStr;

/// A drive controller of ros2_controllers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControllerKind {
    /// `diff_drive_controller`: two wheels (or two sides).
    DiffDrive,
    /// `mecanum_drive_controller`: four mecanum wheels, rollers at ±45°.
    MecanumDrive,
    /// `omni_wheel_drive_controller`: N ≥ 3 omni wheels equally spaced on a circle.
    OmniWheelDrive,
}

impl ControllerKind {
    /// Every controller.
    pub const ALL: [ControllerKind; 3] = [Self::DiffDrive, Self::MecanumDrive, Self::OmniWheelDrive];

    /// The package and default controller name, e.g. `diff_drive_controller`.
    pub fn id(self) -> &'static str {
        match self {
            Self::DiffDrive => "diff_drive_controller",
            Self::MecanumDrive => "mecanum_drive_controller",
            Self::OmniWheelDrive => "omni_wheel_drive_controller",
        }
    }

    /// The pluginlib class the controller manager loads (`type:`).
    pub fn plugin(self) -> &'static str {
        match self {
            Self::DiffDrive => "diff_drive_controller/DiffDriveController",
            Self::MecanumDrive => "mecanum_drive_controller/MecanumDriveController",
            Self::OmniWheelDrive => "omni_wheel_drive_controller/OmniWheelDriveController",
        }
    }

    /// Whether the controller can drive a base with `n_wheels` wheels (a differential controller: as many
    /// on each side, `left_wheel_names` and `right_wheel_names` of equal length).
    pub fn accepts(self, n_wheels: usize) -> bool {
        match self {
            Self::DiffDrive => n_wheels >= 2 && n_wheels.is_multiple_of(2),
            Self::MecanumDrive => n_wheels == 4,
            Self::OmniWheelDrive => n_wheels >= 3,
        }
    }

    /// The controller that matches a base: a base that drives only forward and turning
    /// (`twist_dof` 2: a differential drive, a skid-steer base) → differential drive; four wheels whose
    /// rollers all sit at ±45° → mecanum; three or more wheels otherwise → omni. `design` is the base's
    /// design geometry, `None` when only a matrix is known (then two wheels count as an axle and more as
    /// omni wheels).
    pub fn for_base(n_wheels: usize, design: Option<&omni_kin::RobotGeometry>) -> Option<Self> {
        let roller_angles: Option<Vec<f64>> = design.map(|g| g.wheels.iter().map(|w| w.roller_angle_rad).collect());
        let mecanum = roller_angles
            .is_some_and(|a| a.len() == 4 && a.iter().all(|g| (g.abs() - std::f64::consts::FRAC_PI_4).abs() < 1e-6));
        let two_sided = design.is_some_and(|g| g.twist_dof() == 2 && Self::DiffDrive.accepts(g.n_wheels()));
        match n_wheels {
            2 => Some(Self::DiffDrive),
            _ if two_sided => Some(Self::DiffDrive),
            4 if mecanum => Some(Self::MecanumDrive),
            n if n >= 3 => Some(Self::OmniWheelDrive),
            _ => None,
        }
    }

    /// Names of the controller's wheel slots in its own order (omni: `0`, `1`, … anticlockwise).
    pub fn slot_names(self, n_wheels: usize) -> Vec<String> {
        match self {
            Self::DiffDrive if n_wheels <= 2 => vec!["left".into(), "right".into()],
            Self::DiffDrive => {
                let k = n_wheels / 2;
                ["left", "right"].iter().flat_map(|side| (0..k).map(move |i| format!("{side}_{i}"))).collect()
            }
            Self::MecanumDrive => {
                ["front_left", "front_right", "rear_left", "rear_right"].iter().map(|s| s.to_string()).collect()
            }
            Self::OmniWheelDrive => (0..n_wheels).map(|i| i.to_string()).collect(),
        }
    }
}

/// The choice table (command-line values and their help): the package names, which are also the ids
/// written into ros2_controllers.yaml, so the command line takes them as they are (snake_case; the
/// kebab-case and short forms `diff`, `diff_drive`, … as aliases).
impl Choice for ControllerKind {
    const ALL: &'static [Self] = &ControllerKind::ALL;
    const DEFAULT: Option<Self> = None;

    fn id(self) -> &'static str {
        ControllerKind::id(self)
    }

    fn describe(self) -> &'static str {
        match self {
            Self::DiffDrive => "Two wheels (or two sides of wheels): wheel separation and left/right radii",
            Self::MecanumDrive => "Four mecanum wheels, rollers at ±45°: wheel radius and lx + ly",
            Self::OmniWheelDrive => {
                "Three or more omni wheels equally spaced on a circle: wheel radius, robot radius, first wheel's angle"
            }
        }
    }

    fn flag_value(self) -> String {
        self.id().to_string()
    }

    fn aliases(self) -> &'static [&'static str] {
        match self {
            Self::DiffDrive => &["diff", "diff_drive", "diff-drive-controller"],
            Self::MecanumDrive => &["mecanum", "mecanum_drive", "mecanum-drive-controller"],
            Self::OmniWheelDrive => &["omni", "omni_wheel_drive", "omni-wheel-drive-controller"],
        }
    }
}

impl fmt::Display for ControllerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

impl FromStr for ControllerKind {
    type Err = KinError;

    /// Accepts the package names and their aliases ([`Choice::aliases`]: `diff`, `mecanum`, `omni`, …).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as Choice>::from_id(s).map_err(|_| {
            KinError::unknown(
                "controller",
                s,
                &["diff_drive_controller", "mecanum_drive_controller", "omni_wheel_drive_controller"],
            )
        })
    }
}

/// The kinematic parameters a controller reads, in SI units (the parameter names are in the docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ControllerParams {
    /// `diff_drive_controller`: the effective separation and radii (parameter × multiplier).
    DiffDrive {
        /// `wheel_separation × wheel_separation_multiplier`. m.
        wheel_separation_m: f64,
        /// `wheel_radius × left_wheel_radius_multiplier`. m.
        left_wheel_radius_m: f64,
        /// `wheel_radius × right_wheel_radius_multiplier`. m.
        right_wheel_radius_m: f64,
    },
    /// `mecanum_drive_controller`.
    MecanumDrive {
        /// `kinematics.wheels_radius`. m.
        wheels_radius_m: f64,
        /// `kinematics.sum_of_robot_center_projection_on_X_Y_axis`: lx + ly. m.
        lx_plus_ly_m: f64,
    },
    /// `omni_wheel_drive_controller`.
    OmniWheelDrive {
        /// `wheel_radius`. m.
        wheel_radius_m: f64,
        /// `robot_radius`: centre to wheels. m.
        robot_radius_m: f64,
        /// `wheel_offset`: angle of the first wheel from the x axis, anticlockwise. rad.
        wheel_offset_rad: f64,
    },
}

impl ControllerParams {
    /// The controller these parameters belong to.
    pub fn kind(&self) -> ControllerKind {
        match self {
            Self::DiffDrive { .. } => ControllerKind::DiffDrive,
            Self::MecanumDrive { .. } => ControllerKind::MecanumDrive,
            Self::OmniWheelDrive { .. } => ControllerKind::OmniWheelDrive,
        }
    }

    fn to_vec(self) -> Vec<f64> {
        match self {
            Self::DiffDrive { wheel_separation_m, left_wheel_radius_m, right_wheel_radius_m } => {
                vec![wheel_separation_m, left_wheel_radius_m, right_wheel_radius_m]
            }
            Self::MecanumDrive { wheels_radius_m, lx_plus_ly_m } => vec![wheels_radius_m, lx_plus_ly_m],
            Self::OmniWheelDrive { wheel_radius_m, robot_radius_m, wheel_offset_rad } => {
                vec![wheel_radius_m, robot_radius_m, wheel_offset_rad]
            }
        }
    }

    fn from_vec(kind: ControllerKind, p: &[f64]) -> Self {
        match kind {
            ControllerKind::DiffDrive => {
                Self::DiffDrive { wheel_separation_m: p[0], left_wheel_radius_m: p[1], right_wheel_radius_m: p[2] }
            }
            ControllerKind::MecanumDrive => Self::MecanumDrive { wheels_radius_m: p[0], lx_plus_ly_m: p[1] },
            ControllerKind::OmniWheelDrive => {
                Self::OmniWheelDrive { wheel_radius_m: p[0], robot_radius_m: p[1], wheel_offset_rad: p[2] }
            }
        }
    }

    /// Radii and lengths are positive and finite (every parameter but the omni wheel offset).
    fn is_physical(self) -> bool {
        let v = self.to_vec();
        let lengths = if matches!(self, Self::OmniWheelDrive { .. }) { &v[..2] } else { &v[..] };
        v.iter().all(|x| x.is_finite()) && lengths.iter().all(|&x| x > 0.0)
    }

    /// The twist (vx m/s, vy m/s, ω rad/s) per unit speed (rad/s) of each controller slot, in the
    /// controller's own order and sign convention.
    pub fn slot_columns(&self, n_wheels: usize) -> Vec<[f64; 3]> {
        match *self {
            Self::DiffDrive { wheel_separation_m: s, left_wheel_radius_m: rl, right_wheel_radius_m: rr } => {
                // The left slots first, then the right: the controller averages each side's wheels.
                let k = (n_wheels / 2).max(1) as f64;
                let left = [rl / (2.0 * k), 0.0, -rl / (s * k)];
                let right = [rr / (2.0 * k), 0.0, rr / (s * k)];
                let per_side = (n_wheels / 2).max(1);
                std::iter::repeat_n(left, per_side).chain(std::iter::repeat_n(right, per_side)).collect()
            }
            Self::MecanumDrive { wheels_radius_m: r, lx_plus_ly_m: k } => {
                let q = r / 4.0;
                // Slots FL, FR, RL, RR.
                vec![[q, -q, -q / k], [q, q, q / k], [q, q, -q / k], [q, -q, q / k]]
            }
            Self::OmniWheelDrive { wheel_radius_m: r, robot_radius_m: big_r, wheel_offset_rad: offset } => {
                omni_columns(r, big_r, offset, n_wheels)
            }
        }
    }
}

/// `r (AᵀA)⁻¹ Aᵀ` of the omni controller, column by column (the least-squares solution it computes by SVD).
fn omni_columns(r: f64, big_r: f64, offset_rad: f64, n: usize) -> Vec<[f64; 3]> {
    let a = DMatrix::from_fn(n, 3, |i, j| {
        let theta = offset_rad + TAU * i as f64 / n as f64;
        [theta.sin(), -theta.cos(), -big_r][j]
    });
    let at = a.transpose();
    match (&at * &a).try_inverse() {
        Some(inv) => {
            let p = inv * at * r;
            (0..n).map(|i| [p[(0, i)], p[(1, i)], p[(2, i)]]).collect()
        }
        None => vec![[f64::NAN; 3]; n],
    }
}

/// Which model column (wheel) feeds each controller slot, and with which sign.
#[derive(Clone, Debug, PartialEq)]
pub struct WheelLayout {
    /// Model column of each slot, in the controller's slot order.
    pub columns: Vec<usize>,
    /// Per slot: the joint turns the other way from the controller's convention, so its speed must be
    /// negated before the controller reads it.
    pub reversed: Vec<bool>,
}

/// A controller with its parameters and the wheel layout that connects it to a model's columns.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerModel {
    /// Parameters.
    pub params: ControllerParams,
    /// Slots → model columns.
    pub layout: WheelLayout,
}

impl ControllerModel {
    /// The controller's odometry as an IK matrix in the model's column order (reversed joints negated):
    /// the twist the controller computes from the model's wheel speeds.
    pub fn twist_from_wheels(&self) -> Result<IkMatrix, KinError> {
        let n = self.layout.columns.len();
        let mut entries = vec![0.0; 3 * n];
        for (slot, col) in self.params.slot_columns(n).iter().enumerate() {
            let c = self.layout.columns[slot];
            let sign = if self.layout.reversed[slot] { -1.0 } else { 1.0 };
            for (row, v) in col.iter().enumerate() {
                entries[row * n + c] = sign * v;
            }
        }
        IkMatrix::new(n, entries)
    }
}

/// Options of [`fit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// Weight of yaw-rate differences against velocity differences. m/rad. Default 1 (as Eq. 6 and the
    /// path cost mix metres and radians).
    pub heading_weight_m_per_rad: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self { heading_weight_m_per_rad: 1.0 }
    }
}

/// The controller nearest to a matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerFit {
    /// The fitted controller.
    pub model: ControllerModel,
    /// Its odometry in the model's column order.
    pub twist_from_wheels: IkMatrix,
    /// RMS difference between the controller's twist and the target matrix's over the weighting wheel
    /// speeds, per component.
    pub twist_rms: Twist2,
    /// Omni only: each slot's wheel angle read off the target matrix (controller convention, rad in
    /// [0, 2π)); compare with `wheel_offset + 2π i / N` to see how far from equal spacing the wheels are.
    pub slot_angles_rad: Vec<f64>,
}

/// The mean second moment `E[w wᵀ]` of the runs' wheel speeds (N × N, rad²/s²): per run the mean over its
/// samples, then the mean over runs (each run counts equally, as in the path cost).
pub fn wheel_second_moment(runs: &[Run]) -> Result<DMatrix<f64>, KinError> {
    let n = runs.first().map_or(0, Run::n_wheels);
    if n == 0 {
        return Err(KinError::Invalid { what: "controller fit".into(), why: "no runs to weight the fit with".into() });
    }
    let mut s = DMatrix::zeros(n, n);
    for run in runs {
        if run.n_wheels() != n {
            return Err(KinError::Shape {
                what: format!("run {} wheel columns", run.name()),
                got: run.n_wheels(),
                expected: n,
            });
        }
        let mut per = DMatrix::zeros(n, n);
        for k in 0..run.n_samples() {
            let w = DVector::from_column_slice(run.wheel_sample(k));
            per += &w * w.transpose();
        }
        s += per / run.n_samples().max(1) as f64;
    }
    Ok(s / runs.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn omni_controller_matches_its_own_unit_test() {
        // ros2_controllers test_odometry.cpp: R = 1 m, r = 0.1 m, offset 0, 4 wheels; wheel speeds
        // (0, 10, 0, −10) rad/s give vx = 1 m/s; (−20, −20, −20, −20) give ω = 2 rad/s.
        let p = ControllerParams::OmniWheelDrive { wheel_radius_m: 0.1, robot_radius_m: 1.0, wheel_offset_rad: 0.0 };
        let m =
            ControllerModel { params: p, layout: WheelLayout { columns: vec![0, 1, 2, 3], reversed: vec![false; 4] } }
                .twist_from_wheels()
                .unwrap();
        let t = m.twist(&[0.0, 10.0, 0.0, -10.0]);
        assert!((t.vx_m_s - 1.0).abs() < 1e-12 && t.vy_m_s.abs() < 1e-12 && t.omega_rad_s.abs() < 1e-12);
        let t = m.twist(&[-20.0; 4]);
        assert!((t.omega_rad_s - 2.0).abs() < 1e-12 && t.vx_m_s.abs() < 1e-12);
        let t = m.twist(&[-15.0, 5.0, -5.0, -25.0]);
        assert!(
            (t.vx_m_s - 1.5).abs() < 1e-12 && (t.vy_m_s - 0.5).abs() < 1e-12 && (t.omega_rad_s - 1.0).abs() < 1e-12
        );
    }

    #[test]
    fn kind_for_base() {
        assert_eq!(ControllerKind::for_base(2, None), Some(ControllerKind::DiffDrive));
        assert_eq!(ControllerKind::for_base(3, None), Some(ControllerKind::OmniWheelDrive));
        assert_eq!(ControllerKind::for_base(4, None), Some(ControllerKind::OmniWheelDrive));
        let q = std::f64::consts::FRAC_PI_4;
        let mut mecanum = omni_kin::RobotGeometry::apr02();
        mecanum.wheels.push(mecanum.wheels[0].clone());
        mecanum.wheel_names.push("d".into());
        for (w, a) in mecanum.wheels.iter_mut().zip([-q, q, q, -q]) {
            w.roller_angle_rad = a;
        }
        assert_eq!(ControllerKind::for_base(4, Some(&mecanum)), Some(ControllerKind::MecanumDrive));
        assert_eq!(ControllerKind::for_base(1, None), None);
        assert_eq!("mecanum".parse::<ControllerKind>().unwrap(), ControllerKind::MecanumDrive);
    }
}
