//! The nearest parametric fit ([`fit`]): a start and the wheel layout read off the target matrix, then the
//! weighted least-squares problem over the controller's parameters ([`ControllerProblem`], omni-ga's
//! [`Problem`] and [`LeastSquares`]) solved by the project's Levenberg–Marquardt ([`LevenbergMarquardt`]).

use super::{ControllerFit, ControllerKind, ControllerModel, ControllerParams, FitOptions, WheelLayout};
use nalgebra::{DMatrix, DVector};
use omni_ga::problem::{Bounds, LeastSquares, Problem};
use omni_ga::{LevenbergMarquardt, LmConfig, NoopObserver, Optimizer};
use omni_kin::{IkMatrix, KinError, Twist2};
use std::f64::consts::TAU;

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
    let problem =
        ControllerProblem::new(target, second_moment, opts.heading_weight_m_per_rad, kind, start.layout.clone());
    let p = problem.minimise(start.params)?;
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

/// A differential controller's start: each wheel's side from its column (a left wheel turning forward
/// turns the robot clockwise), the side's radius and the separation from the columns' `vx` and `ω`. With
/// more than one wheel per side (a skid-steer base) the controller averages each side's wheels, so a
/// column carries `1/k` of its side.
fn diff_start(m: &IkMatrix) -> Result<Start, KinError> {
    let kind = ControllerKind::DiffDrive;
    let n = m.n_wheels();
    let k = n / 2;
    // Per side (left 0, right 1): (column, reversed, radius, separation).
    let mut sides: [Vec<(usize, bool, f64, f64)>; 2] = [Vec::new(), Vec::new()];
    for c in 0..n {
        let (vx, om) = (m.get(0, c), m.get(2, c));
        if vx == 0.0 || om == 0.0 {
            return Err(layout_error(kind, format!("wheel {} moves the robot neither forward nor round", c + 1)));
        }
        let reversed = vx < 0.0;
        let side = usize::from((if reversed { -om } else { om }) > 0.0);
        sides[side].push((c, reversed, 2.0 * k as f64 * vx.abs(), 2.0 * vx.abs() / om.abs()));
    }
    if sides.iter().any(|s| s.len() != k) {
        let why = if n == 2 {
            "both wheels turn the robot the same way (no left and right wheel)".to_string()
        } else {
            format!(
                "{} wheels turn the robot as left wheels and {} as right ones; the controller needs as many on each side",
                sides[0].len(),
                sides[1].len()
            )
        };
        return Err(layout_error(kind, why));
    }
    let mean = |v: &[(usize, bool, f64, f64)], f: fn(&(usize, bool, f64, f64)) -> f64| {
        v.iter().map(f).sum::<f64>() / v.len() as f64
    };
    let all: Vec<_> = sides.iter().flatten().copied().collect();
    Ok(Start {
        params: ControllerParams::DiffDrive {
            wheel_separation_m: mean(&all, |w| w.3),
            left_wheel_radius_m: mean(&sides[0], |w| w.2),
            right_wheel_radius_m: mean(&sides[1], |w| w.2),
        },
        layout: WheelLayout { columns: all.iter().map(|w| w.0).collect(), reversed: all.iter().map(|w| w.1).collect() },
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

/// The weighted least-squares problem over one controller's parameters with a fixed layout: residuals
/// `λ_j ΔM_j S^{1/2}` (3N), the parameters in [`ControllerParams`]' order. Unbounded; a point where a
/// radius or length is not positive and finite has infinite cost (non-finite residuals), which the solver
/// never accepts. The Jacobian is the trait's default: central differences
/// ([`omni_ga::problem::finite_difference_jacobian`]).
struct ControllerProblem<'a> {
    target: &'a IkMatrix,
    /// `S^{1/2}` (symmetric square root).
    sqrt_s: DMatrix<f64>,
    row_weights: [f64; 3],
    kind: ControllerKind,
    layout: WheelLayout,
    bounds: Bounds,
}

impl<'a> ControllerProblem<'a> {
    fn new(
        target: &'a IkMatrix,
        s: &DMatrix<f64>,
        heading_weight: f64,
        kind: ControllerKind,
        layout: WheelLayout,
    ) -> Self {
        let eig = nalgebra::SymmetricEigen::new(s.clone());
        let root = eig.eigenvalues.map(|v| v.max(0.0).sqrt());
        let sqrt_s = &eig.eigenvectors * DMatrix::from_diagonal(&root) * eig.eigenvectors.transpose();
        // As many as `ControllerParams::to_vec` gives: the mecanum controller has two.
        let n_params = if kind == ControllerKind::MecanumDrive { 2 } else { 3 };
        let bounds = Bounds::unbounded(n_params);
        Self { target, sqrt_s, row_weights: [1.0, 1.0, heading_weight], kind, layout, bounds }
    }

    /// Residuals (3N), or `None` where the parameters are not physical.
    fn twist_residuals(&self, params: ControllerParams) -> Option<DVector<f64>> {
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

    /// The solver's settings. The default budget and tolerances suit a calibration's polish; this
    /// problem is tiny (2–3 parameters, 3N residuals) and its answer is written out to every digit, so
    /// the fit runs to rounding (as a target of the controller's form must be reproduced exactly).
    fn lm_config(&self) -> LmConfig {
        LmConfig {
            max_evaluations: 200 * (self.bounds.len() + 1),
            ftol: LM_TOLERANCE,
            xtol: LM_TOLERANCE,
            gtol: LM_TOLERANCE,
            ..LmConfig::default()
        }
    }

    /// The parameters from `start` that minimise the weighted twist difference (never a higher cost than
    /// `start`'s: the solver returns its start when it finds nothing better).
    fn minimise(&self, start: ControllerParams) -> Result<ControllerParams, KinError> {
        if self.twist_residuals(start).is_none() {
            return Err(layout_error(self.kind, format!("start {start:?} is not physical")));
        }
        let mut lm = LevenbergMarquardt { config: self.lm_config() };
        let solution = lm
            .minimize(self, &start.to_vec(), &mut NoopObserver)
            .map_err(|e| KinError::Invalid { what: format!("the {} fit", self.kind), why: e.to_string() })?;
        Ok(ControllerParams::from_vec(self.kind, &solution.params))
    }
}

/// Relative tolerance of the solver's convergence tests (`ftol`, `xtol`, `gtol`): a few units of rounding.
const LM_TOLERANCE: f64 = 30.0 * f64::EPSILON;

impl Problem for ControllerProblem<'_> {
    fn bounds(&self) -> &Bounds {
        &self.bounds
    }

    fn cost(&self, x: &[f64]) -> f64 {
        self.twist_residuals(ControllerParams::from_vec(self.kind, x)).map_or(f64::INFINITY, |r| r.norm_squared())
    }
}

impl LeastSquares for ControllerProblem<'_> {
    fn residuals(&self, x: &[f64]) -> Vec<f64> {
        match self.twist_residuals(ControllerParams::from_vec(self.kind, x)) {
            Some(r) => r.iter().copied().collect(),
            None => vec![f64::NAN; 3 * self.layout.columns.len()],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use omni_kin::RobotGeometry;

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
        let problem = ControllerProblem::new(&m, &s, 1.0, ControllerKind::OmniWheelDrive, f.model.layout.clone());
        let best = problem.twist_residuals(f.model.params).unwrap().norm_squared();
        assert!(best > 1e-8, "{best}");
        let p = f.model.params.to_vec();
        for i in 0..3 {
            for h in [-1e-4, 1e-4] {
                let mut q = p.clone();
                q[i] += h;
                let c =
                    problem.twist_residuals(ControllerParams::from_vec(ControllerKind::OmniWheelDrive, &q)).unwrap();
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
}
