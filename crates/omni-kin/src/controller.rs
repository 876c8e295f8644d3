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
//!   speeds), the opposite of omnical's omni-wheel convention ([`crate::geometry`]).
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
//! (Levenberg–Marquardt on 2–3 parameters from a start read off the matrix). Directions the runs never
//! excite carry no weight and stay at that start. When the target is of the controller's form the fit
//! reproduces it to rounding.

use crate::choice::Choice;
use crate::error::KinError;
use crate::ik::IkMatrix;
use crate::pose::Twist2;
use crate::run::Run;
use nalgebra::{DMatrix, DVector};
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

    /// Whether the controller can drive a base with `n_wheels` wheels.
    pub fn accepts(self, n_wheels: usize) -> bool {
        match self {
            Self::DiffDrive => n_wheels == 2,
            Self::MecanumDrive => n_wheels == 4,
            Self::OmniWheelDrive => n_wheels >= 3,
        }
    }

    /// The controller that matches a base: two wheels → differential drive; four wheels whose rollers
    /// all sit at ±45° → mecanum; three or more wheels otherwise → omni. `roller_angles_rad` is `None`
    /// when only a matrix is known (then four wheels count as omni wheels).
    pub fn for_base(n_wheels: usize, roller_angles_rad: Option<&[f64]>) -> Option<Self> {
        let mecanum = roller_angles_rad
            .is_some_and(|a| a.len() == 4 && a.iter().all(|g| (g.abs() - std::f64::consts::FRAC_PI_4).abs() < 1e-6));
        match n_wheels {
            2 => Some(Self::DiffDrive),
            4 if mecanum => Some(Self::MecanumDrive),
            n if n >= 3 => Some(Self::OmniWheelDrive),
            _ => None,
        }
    }

    /// Names of the controller's wheel slots in its own order (omni: `0`, `1`, … anticlockwise).
    pub fn slot_names(self, n_wheels: usize) -> Vec<String> {
        match self {
            Self::DiffDrive => vec!["left".into(), "right".into()],
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
        <Self as Choice>::from_id(s).map_err(|_| KinError::Unknown {
            what: "controller",
            name: s.into(),
            known: "diff_drive_controller, mecanum_drive_controller, omni_wheel_drive_controller".into(),
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
                vec![[rl / 2.0, 0.0, -rl / s], [rr / 2.0, 0.0, rr / s]]
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

/// Fit a controller's parameters so that its odometry best reproduces `target`'s twists for wheel speeds
/// with second moment `second_moment` (see the module docs). Errors when the matrix's wheel count or
/// layout cannot be expressed by the controller (e.g. two wheels that turn the robot the same way).
pub fn fit(
    kind: ControllerKind,
    target: &IkMatrix,
    second_moment: &DMatrix<f64>,
    opts: &FitOptions,
) -> Result<ControllerFit, KinError> {
    let n = target.n_wheels();
    if !kind.accepts(n) {
        return Err(KinError::Invalid { what: format!("{kind}"), why: format!("cannot drive a base with {n} wheels") });
    }
    if second_moment.nrows() != n || second_moment.ncols() != n {
        return Err(KinError::Shape { what: "wheel second moment".into(), got: second_moment.nrows(), expected: n });
    }
    let start = initial_guess(kind, target)?;
    let problem = Problem::new(target, second_moment, opts.heading_weight_m_per_rad, start.layout.clone());
    let p = levenberg_marquardt(&problem, start.params)?;
    let model = ControllerModel { params: p, layout: start.layout };
    let twist_from_wheels = model.twist_from_wheels()?;
    let d = difference_rows(&twist_from_wheels, target);
    let rms = |j: usize| (&d[j] * second_moment * d[j].transpose())[(0, 0)].max(0.0).sqrt();
    Ok(ControllerFit {
        model,
        twist_from_wheels,
        twist_rms: Twist2 { vx_m_s: rms(0), vy_m_s: rms(1), omega_rad_s: rms(2) },
        slot_angles_rad: start.slot_angles_rad,
    })
}

struct Start {
    params: ControllerParams,
    layout: WheelLayout,
    slot_angles_rad: Vec<f64>,
}

fn layout_error(kind: ControllerKind, why: String) -> KinError {
    KinError::Invalid { what: format!("the matrix as a {kind}"), why }
}

/// The wheel-from-twist rows (N × 3, rad/s per unit twist): the pseudo-inverse of the matrix.
fn wheel_rows(target: &IkMatrix) -> Result<DMatrix<f64>, KinError> {
    let n = target.n_wheels();
    let m = DMatrix::from_row_slice(3, n, target.entries());
    m.pseudo_inverse(1e-12).map_err(|e| KinError::Invalid { what: "IK matrix".into(), why: e.to_string() })
}

/// Start values and layout, read off the target matrix.
fn initial_guess(kind: ControllerKind, target: &IkMatrix) -> Result<Start, KinError> {
    match kind {
        ControllerKind::DiffDrive => diff_start(target),
        ControllerKind::MecanumDrive => mecanum_start(target),
        ControllerKind::OmniWheelDrive => omni_start(target),
    }
}

fn diff_start(m: &IkMatrix) -> Result<Start, KinError> {
    let kind = ControllerKind::DiffDrive;
    let mut sides = [None, None];
    for c in 0..2 {
        let (vx, om) = (m.get(0, c), m.get(2, c));
        if vx == 0.0 || om == 0.0 {
            return Err(layout_error(kind, format!("wheel {} moves the robot neither forward nor round", c + 1)));
        }
        let reversed = vx < 0.0;
        // A left wheel turning forward turns the robot clockwise (ω < 0).
        let side = usize::from((if reversed { -om } else { om }) > 0.0);
        if sides[side].is_some() {
            return Err(layout_error(kind, "both wheels turn the robot the same way (no left and right wheel)".into()));
        }
        sides[side] = Some((c, reversed, 2.0 * vx.abs(), 2.0 * vx.abs() / om.abs()));
    }
    let (Some(l), Some(r)) = (sides[0], sides[1]) else {
        return Err(layout_error(kind, "no left and right wheel".into()));
    };
    Ok(Start {
        params: ControllerParams::DiffDrive {
            wheel_separation_m: (l.3 + r.3) / 2.0,
            left_wheel_radius_m: l.2,
            right_wheel_radius_m: r.2,
        },
        layout: WheelLayout { columns: vec![l.0, r.0], reversed: vec![l.1, r.1] },
        slot_angles_rad: Vec::new(),
    })
}

fn mecanum_start(m: &IkMatrix) -> Result<Start, KinError> {
    let kind = ControllerKind::MecanumDrive;
    let f = wheel_rows(m)?;
    let mut slots: [Option<(usize, bool)>; 4] = [None; 4];
    let (mut inv_r, mut k) = (0.0, 0.0);
    for i in 0..4 {
        let reversed = f[(i, 0)] < 0.0;
        let s = if reversed { -1.0 } else { 1.0 };
        let (g0, g1, g2) = (s * f[(i, 0)], s * f[(i, 1)], s * f[(i, 2)]);
        if g0 == 0.0 {
            return Err(layout_error(kind, format!("wheel {} does not drive forward", i + 1)));
        }
        // FL: vy −, ω −; FR: +, +; RL: +, −; RR: −, +.
        let slot = match (g1 < 0.0, g2 < 0.0) {
            (true, true) => 0,
            (false, false) => 1,
            (false, true) => 2,
            (true, false) => 3,
        };
        if slots[slot].is_some() {
            let name = &kind.slot_names(4)[slot];
            return Err(layout_error(kind, format!("two wheels sit at the {name} position")));
        }
        slots[slot] = Some((i, reversed));
        inv_r += g0 / 4.0;
        k += g2.abs() / g0 / 4.0;
    }
    let mut layout = WheelLayout { columns: Vec::new(), reversed: Vec::new() };
    for (c, rev) in slots.iter().flatten() {
        layout.columns.push(*c);
        layout.reversed.push(*rev);
    }
    Ok(Start {
        params: ControllerParams::MecanumDrive { wheels_radius_m: 1.0 / inv_r, lx_plus_ly_m: k },
        layout,
        slot_angles_rad: Vec::new(),
    })
}

fn omni_start(m: &IkMatrix) -> Result<Start, KinError> {
    let kind = ControllerKind::OmniWheelDrive;
    let f = wheel_rows(m)?;
    let n = m.n_wheels();
    let mut wheels = Vec::with_capacity(n);
    for i in 0..n {
        if f[(i, 2)] == 0.0 {
            return Err(layout_error(kind, format!("wheel {} does not turn the robot", i + 1)));
        }
        // Controller row: r ω_i = σ (sin θ vx − cos θ vy − R ω) with R > 0.
        let reversed = f[(i, 2)] > 0.0;
        let s = if reversed { -1.0 } else { 1.0 };
        let theta = (s * f[(i, 0)]).atan2(-s * f[(i, 1)]).rem_euclid(TAU);
        let r = 1.0 / f[(i, 0)].hypot(f[(i, 1)]);
        wheels.push((theta, i, reversed, r, f[(i, 2)].abs() * r));
    }
    wheels.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mean = |k: fn(&(f64, usize, bool, f64, f64)) -> f64| wheels.iter().map(k).sum::<f64>() / n as f64;
    Ok(Start {
        params: ControllerParams::OmniWheelDrive {
            wheel_radius_m: mean(|w| w.3),
            robot_radius_m: mean(|w| w.4),
            wheel_offset_rad: wheels[0].0,
        },
        layout: WheelLayout {
            columns: wheels.iter().map(|w| w.1).collect(),
            reversed: wheels.iter().map(|w| w.2).collect(),
        },
        slot_angles_rad: wheels.iter().map(|w| w.0).collect(),
    })
}

/// Rows of `a − b` as 1 × N matrices.
fn difference_rows(a: &IkMatrix, b: &IkMatrix) -> Vec<DMatrix<f64>> {
    let n = a.n_wheels();
    (0..3).map(|j| DMatrix::from_fn(1, n, |_, c| a.get(j, c) - b.get(j, c))).collect()
}

/// The weighted least-squares problem over one controller's parameters with a fixed layout.
struct Problem<'a> {
    target: &'a IkMatrix,
    /// `S^{1/2}` (symmetric square root).
    sqrt_s: DMatrix<f64>,
    row_weights: [f64; 3],
    layout: WheelLayout,
}

impl<'a> Problem<'a> {
    fn new(target: &'a IkMatrix, s: &DMatrix<f64>, heading_weight: f64, layout: WheelLayout) -> Self {
        let eig = nalgebra::SymmetricEigen::new(s.clone());
        let root = eig.eigenvalues.map(|v| v.max(0.0).sqrt());
        let sqrt_s = &eig.eigenvectors * DMatrix::from_diagonal(&root) * eig.eigenvectors.transpose();
        Self { target, sqrt_s, row_weights: [1.0, 1.0, heading_weight], layout }
    }

    /// Residuals (3N), or `None` where the parameters are not physical.
    fn residuals(&self, params: ControllerParams) -> Option<DVector<f64>> {
        if !params.is_physical() {
            return None;
        }
        let model = ControllerModel { params, layout: self.layout.clone() };
        let m = model.twist_from_wheels().ok()?;
        let n = m.n_wheels();
        let mut r = DVector::zeros(3 * n);
        for (j, d) in difference_rows(&m, self.target).iter().enumerate() {
            let row = d * &self.sqrt_s * self.row_weights[j];
            r.rows_mut(j * n, n).copy_from(&row.transpose());
        }
        Some(r)
    }
}

/// Levenberg–Marquardt with a central-difference Jacobian; 2–3 parameters, so nothing fancier is needed.
fn levenberg_marquardt(problem: &Problem<'_>, start: ControllerParams) -> Result<ControllerParams, KinError> {
    let kind = start.kind();
    let at = |p: &[f64]| problem.residuals(ControllerParams::from_vec(kind, p));
    let mut p = start.to_vec();
    let mut r = at(&p).ok_or_else(|| layout_error(kind, format!("start {start:?} is not physical")))?;
    let mut lambda = 1e-3;
    for _ in 0..200 {
        let jac = jacobian(&at, &p, &r);
        let jtj = jac.transpose() * &jac;
        let g = jac.transpose() * &r;
        let cost = r.norm_squared();
        let mut improved = false;
        while lambda < 1e16 {
            let mut a = jtj.clone();
            for i in 0..p.len() {
                a[(i, i)] += lambda * jtj[(i, i)].max(1e-30);
            }
            let Some(step) = a.lu().solve(&(-&g)) else { break };
            let trial: Vec<f64> = p.iter().zip(step.iter()).map(|(x, d)| x + d).collect();
            match at(&trial) {
                Some(rt) if rt.norm_squared() < cost => {
                    let small = p.iter().zip(&trial).all(|(a, b)| (a - b).abs() <= 1e-15 * a.abs().max(1e-12));
                    p = trial;
                    r = rt;
                    lambda = (lambda / 10.0).max(1e-12);
                    improved = !small;
                    break;
                }
                _ => lambda *= 10.0,
            }
        }
        if !improved {
            break;
        }
    }
    Ok(ControllerParams::from_vec(kind, &p))
}

fn jacobian(at: &dyn Fn(&[f64]) -> Option<DVector<f64>>, p: &[f64], r: &DVector<f64>) -> DMatrix<f64> {
    let mut jac = DMatrix::zeros(r.len(), p.len());
    for i in 0..p.len() {
        let h = 1e-6 * p[i].abs().max(1e-3);
        let (mut up, mut down) = (p.to_vec(), p.to_vec());
        up[i] += h;
        down[i] -= h;
        let column = match (at(&up), at(&down)) {
            (Some(a), Some(b)) => (a - b) / (2.0 * h),
            (Some(a), None) => (a - r) / h,
            (None, Some(b)) => (r - b) / h,
            (None, None) => DVector::zeros(r.len()),
        };
        jac.set_column(i, &column);
    }
    jac
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::RobotGeometry;

    fn moment(n: usize) -> DMatrix<f64> {
        // A generic positive-definite second moment.
        DMatrix::from_fn(n, n, |i, j| if i == j { 4.0 + i as f64 } else { 0.3 })
    }

    fn assert_matrix_eq(a: &IkMatrix, b: &IkMatrix, tol: f64) {
        for (x, y) in a.entries().iter().zip(b.entries()) {
            assert!((x - y).abs() <= tol, "{:?}\nvs\n{:?}", a.rows(), b.rows());
        }
    }

    #[test]
    fn omni_controller_reproduces_apr02_exactly_with_reversed_joints() {
        let m = RobotGeometry::apr02().twist_from_wheels().unwrap();
        let fit = fit(ControllerKind::OmniWheelDrive, &m, &moment(3), &FitOptions::default()).unwrap();
        let ControllerParams::OmniWheelDrive { wheel_radius_m, robot_radius_m, wheel_offset_rad } = fit.model.params
        else {
            panic!("omni")
        };
        assert!((wheel_radius_m - 0.148).abs() < 1e-12, "{wheel_radius_m}");
        assert!((robot_radius_m - 0.195).abs() < 1e-12, "{robot_radius_m}");
        assert!((wheel_offset_rad - 60f64.to_radians()).abs() < 1e-12, "{wheel_offset_rad}");
        // APR-02's wheels turn the robot anticlockwise: the controller needs all three reversed.
        assert_eq!(fit.model.layout, WheelLayout { columns: vec![0, 1, 2], reversed: vec![true; 3] });
        assert_matrix_eq(&fit.twist_from_wheels, &m, 1e-14);
        assert!(fit.twist_rms.omega_rad_s < 1e-13);
    }

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
    fn mecanum_controller_reproduces_textbook_mecanum_exactly() {
        // omnical's mecanum4 order is FL, FR, RL, RR with the controller's own signs.
        let m = RobotGeometry::mecanum4(0.05, 0.2, 0.15).twist_from_wheels().unwrap();
        let fit = fit(ControllerKind::MecanumDrive, &m, &moment(4), &FitOptions::default()).unwrap();
        let ControllerParams::MecanumDrive { wheels_radius_m, lx_plus_ly_m } = fit.model.params else { panic!() };
        assert!((wheels_radius_m - 0.05).abs() < 1e-13 && (lx_plus_ly_m - 0.35).abs() < 1e-13);
        assert_eq!(fit.model.layout, WheelLayout { columns: vec![0, 1, 2, 3], reversed: vec![false; 4] });
        assert_matrix_eq(&fit.twist_from_wheels, &m, 1e-14);
    }

    #[test]
    fn diff_controller_reproduces_a_differential_drive_with_swapped_reversed_columns() {
        // Columns: right wheel reversed, then left. s = 0.4 m, r_L = 0.05 m, r_R = 0.052 m.
        let (s, rl, rr) = (0.4, 0.05, 0.052);
        let m = IkMatrix::from_rows(&[vec![-rr / 2.0, rl / 2.0], vec![0.0, 0.0], vec![-rr / s, -rl / s]]).unwrap();
        let fit = fit(ControllerKind::DiffDrive, &m, &moment(2), &FitOptions::default()).unwrap();
        let ControllerParams::DiffDrive { wheel_separation_m, left_wheel_radius_m, right_wheel_radius_m } =
            fit.model.params
        else {
            panic!("diff")
        };
        assert!((wheel_separation_m - s).abs() < 1e-15, "{wheel_separation_m}");
        assert!((left_wheel_radius_m - rl).abs() < 1e-16 && (right_wheel_radius_m - rr).abs() < 1e-16);
        assert_eq!(fit.model.layout, WheelLayout { columns: vec![1, 0], reversed: vec![false, true] });
        assert_matrix_eq(&fit.twist_from_wheels, &m, 1e-15);
    }

    #[test]
    fn fit_minimises_the_weighted_twist_error() {
        // A perturbed APR-02 (the paper's Eq. 9) is not of the controller's form: the fit leaves a
        // residual, and moving any parameter away from the fit makes the weighted error larger.
        let m = IkMatrix::paper_calibrated();
        let s = moment(3);
        let f = fit(ControllerKind::OmniWheelDrive, &m, &s, &FitOptions::default()).unwrap();
        let problem = Problem::new(&m, &s, 1.0, f.model.layout.clone());
        let best = problem.residuals(f.model.params).unwrap().norm_squared();
        assert!(best > 1e-8, "{best}");
        let p = f.model.params.to_vec();
        for i in 0..3 {
            for h in [-1e-4, 1e-4] {
                let mut q = p.clone();
                q[i] += h;
                let c = problem.residuals(ControllerParams::from_vec(ControllerKind::OmniWheelDrive, &q)).unwrap();
                assert!(c.norm_squared() > best, "parameter {i} {h:+}: {} <= {best}", c.norm_squared());
            }
        }
    }

    #[test]
    fn refuses_layouts_the_controller_cannot_express() {
        let same_way = IkMatrix::from_rows(&[vec![0.025, 0.025], vec![0.0, 0.0], vec![0.1, 0.1]]).unwrap();
        let err = fit(ControllerKind::DiffDrive, &same_way, &moment(2), &FitOptions::default()).unwrap_err();
        assert!(err.to_string().contains("both wheels turn the robot the same way"), "{err}");
        let m = IkMatrix::paper_design();
        let err = fit(ControllerKind::MecanumDrive, &m, &moment(3), &FitOptions::default()).unwrap_err();
        assert!(err.to_string().contains("cannot drive a base with 3 wheels"), "{err}");
    }

    #[test]
    fn kind_for_base() {
        assert_eq!(ControllerKind::for_base(2, None), Some(ControllerKind::DiffDrive));
        assert_eq!(ControllerKind::for_base(3, None), Some(ControllerKind::OmniWheelDrive));
        assert_eq!(ControllerKind::for_base(4, None), Some(ControllerKind::OmniWheelDrive));
        let q = std::f64::consts::FRAC_PI_4;
        assert_eq!(ControllerKind::for_base(4, Some(&[-q, q, q, -q])), Some(ControllerKind::MecanumDrive));
        assert_eq!(ControllerKind::for_base(1, None), None);
        assert_eq!("mecanum".parse::<ControllerKind>().unwrap(), ControllerKind::MecanumDrive);
    }
}
