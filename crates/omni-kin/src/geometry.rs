//! Robot descriptions: where the wheels are, how big they are and which way they push.
//!
//! Wheel `i` sits at distance `R_i` (m) from the rotation centre, at angle `δ_i` (rad) in the robot frame
//! (x forward, y left). It drives along the tangent direction `β_i = δ_i + π/2 + drive_offset_i`; an omni
//! wheel has free rollers across that direction, a mecanum wheel has rollers at `γ_i` (±π/4). The wheel's
//! rim speed then relates to the body twist by (forward kinematics, one row per wheel):
//!
//! ```text
//! r_i ω_i = [cos(β_i+γ_i), sin(β_i+γ_i), x_i sin(β_i+γ_i) − y_i cos(β_i+γ_i)] · (vx, vy, ω) / cos γ_i
//! ```
//!
//! with `(x_i, y_i) = R_i (cos δ_i, sin δ_i)`. For the paper's three omni wheels this is
//! `r_i ω_i = −sin δ_i vx + cos δ_i vy + R_i ω`, whose inverse is the paper's Eq. 3; the APR-02 design
//! values give Eq. 7. With more than three wheels the IK matrix is the least-squares (pseudo-)inverse.

use crate::error::KinError;
use crate::ik::IkMatrix;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// Dimensions of a planar twist (vx, vy, ω): the rank an omnidirectional base's forward kinematics needs.
pub const PLANAR_TWIST_DIMENSIONS: usize = 3;

/// Singular values of the forward kinematics at or below this count as zero in [`RobotGeometry::rank`].
const RANK_TOLERANCE: f64 = 1e-9;

/// One wheel of the robot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wheel {
    /// Wheel radius. m.
    pub radius_m: f64,
    /// Distance from the rotation centre to the wheel contact point. m.
    pub distance_m: f64,
    /// Angle of the wheel position in the robot frame, from x towards y. rad.
    pub angle_rad: f64,
    /// Drive direction relative to the tangent `angle_rad + π/2`. rad. Default 0 (omni wheels on a circle).
    #[serde(default)]
    pub drive_offset_rad: f64,
    /// Roller angle: 0 for omni wheels, ±π/4 for mecanum wheels. rad. Default 0.
    #[serde(default)]
    pub roller_angle_rad: f64,
}

/// Largest |sin| of a wheel's drive direction (and |roller angle|, rad) that still counts as driving along x.
const ALONG_X: f64 = 1e-9;

impl Wheel {
    /// An omni wheel on the circle of radius `distance_m`, driving along the tangent.
    pub fn omni(radius_m: f64, distance_m: f64, angle_rad: f64) -> Self {
        Self { radius_m, distance_m, angle_rad, drive_offset_rad: 0.0, roller_angle_rad: 0.0 }
    }

    /// A wheel at `(x_m, y_m)` driving forward (along +x) at positive speed, with rollers at `roller_angle_rad`
    /// (0: none, or an omni wheel's across the drive).
    pub fn forward_at(radius_m: f64, x_m: f64, y_m: f64, roller_angle_rad: f64) -> Self {
        let angle_rad = y_m.atan2(x_m);
        Self {
            radius_m,
            distance_m: x_m.hypot(y_m),
            angle_rad,
            drive_offset_rad: -angle_rad - FRAC_PI_2,
            roller_angle_rad,
        }
    }

    /// Whether the wheel drives along the x axis (forward or backward) without rollers: it cannot push the
    /// base sideways (a differential drive's or a skid-steer base's wheel). Within 1e-9 (|sin|, rad).
    pub fn drives_along_x(&self) -> bool {
        let beta = self.angle_rad + FRAC_PI_2 + self.drive_offset_rad;
        beta.sin().abs() <= ALONG_X && self.roller_angle_rad.abs() <= ALONG_X
    }

    /// The forward-kinematics row: wheel speed (rad/s) per unit (vx m/s, vy m/s, ω rad/s).
    pub fn wheel_from_twist_row(&self) -> [f64; 3] {
        let beta = self.angle_rad + FRAC_PI_2 + self.drive_offset_rad + self.roller_angle_rad;
        let (sb, cb) = beta.sin_cos();
        let (sd, cd) = self.angle_rad.sin_cos();
        let (x, y) = (self.distance_m * cd, self.distance_m * sd);
        let k = 1.0 / (self.roller_angle_rad.cos() * self.radius_m);
        [cb * k, sb * k, (x * sb - y * cb) * k]
    }

    fn validate(&self, index: usize) -> Result<(), KinError> {
        let checks: [(&'static str, f64); 5] = [
            ("radius_m", self.radius_m),
            ("distance_m", self.distance_m),
            ("angle_rad", self.angle_rad),
            ("drive_offset_rad", self.drive_offset_rad),
            ("roller_angle_rad", self.roller_angle_rad),
        ];
        for (field, value) in checks {
            if !value.is_finite() {
                return Err(KinError::BadWheel { wheel: index, field, value, why: "not finite" });
            }
        }
        if self.radius_m <= 0.0 {
            return Err(KinError::BadWheel {
                wheel: index,
                field: "radius_m",
                value: self.radius_m,
                why: "must be > 0",
            });
        }
        if self.distance_m < 0.0 {
            return Err(KinError::BadWheel {
                wheel: index,
                field: "distance_m",
                value: self.distance_m,
                why: "must be ≥ 0",
            });
        }
        if self.roller_angle_rad.abs() >= 1.4 {
            return Err(KinError::BadWheel {
                wheel: index,
                field: "roller_angle_rad",
                value: self.roller_angle_rad,
                why: "must be within ±1.4 rad (rollers parallel to the drive give no traction)",
            });
        }
        Ok(())
    }
}

/// A robot description: its wheels, in the order the wheel-speed columns come in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobotGeometry {
    /// Wheel names, one per wheel (joint names in ROS logs). Default `wheel_a`, `wheel_b`, …
    pub wheel_names: Vec<String>,
    /// The wheels.
    pub wheels: Vec<Wheel>,
}

/// Default wheel names `wheel_a`, `wheel_b`, … for `n` wheels.
pub fn default_wheel_names(n: usize) -> Vec<String> {
    (0..n)
        .map(|i| {
            let letter = char::from(b'a' + (i % 26) as u8);
            format!("wheel_{letter}")
        })
        .collect()
}

impl RobotGeometry {
    /// A description from wheels, with default names. Validates every wheel and the rank.
    pub fn new(wheels: Vec<Wheel>) -> Result<Self, KinError> {
        let g = Self { wheel_names: default_wheel_names(wheels.len()), wheels };
        g.validate()?;
        Ok(g)
    }

    /// The paper's APR-02 design: r = 0.148 m, R = 0.195 m, δ = 60°, 180°, 300°.
    pub fn apr02() -> Self {
        Self::omni_regular(3, 0.148, 0.195, 60f64.to_radians())
    }

    /// `n` identical omni wheels evenly spaced on a circle, the first at `first_angle_rad`.
    pub fn omni_regular(n: usize, radius_m: f64, distance_m: f64, first_angle_rad: f64) -> Self {
        let step = 2.0 * std::f64::consts::PI / n as f64;
        let wheels = (0..n).map(|i| Wheel::omni(radius_m, distance_m, first_angle_rad + step * i as f64)).collect();
        Self { wheel_names: default_wheel_names(n), wheels }
    }

    /// A four-wheel mecanum base: wheels at (±lx, ±ly) in the order front-left, front-right, rear-left,
    /// rear-right, driving forward, rollers at ∓45° (X configuration seen from above).
    pub fn mecanum4(radius_m: f64, lx_m: f64, ly_m: f64) -> Self {
        let q = std::f64::consts::FRAC_PI_4;
        let corners = [(lx_m, ly_m, -q), (lx_m, -ly_m, q), (-lx_m, ly_m, q), (-lx_m, -ly_m, -q)];
        let wheels = corners.iter().map(|&(x, y, roller)| Wheel::forward_at(radius_m, x, y, roller)).collect();
        Self { wheel_names: default_wheel_names(4), wheels }
    }

    /// A four-wheel skid-steer base: wheels at (±lx, ±ly) in the order front-left, rear-left, front-right,
    /// rear-right (each side together), driving forward, without rollers (the layout of a `kind = "skid"`
    /// robot description; Husky: r 0.165 m, lx 0.256 m, ly 0.2775 m).
    pub fn skid4(radius_m: f64, lx_m: f64, ly_m: f64) -> Self {
        let corners = [(lx_m, ly_m), (-lx_m, ly_m), (lx_m, -ly_m), (-lx_m, -ly_m)];
        let wheels = corners.iter().map(|&(x, y)| Wheel::forward_at(radius_m, x, y, 0.0)).collect();
        Self { wheel_names: default_wheel_names(4), wheels }
    }

    /// A differential drive: two wheels on one axle across y, `separation_m` apart, the left (at +y,
    /// the first column) and the right (at −y), both driving forward at positive speed (the layout of a
    /// `kind = "diff"` robot description). Names `wheel_a` (left), `wheel_b` (right).
    pub fn diff_drive(left_radius_m: f64, right_radius_m: f64, separation_m: f64) -> Self {
        let half = 0.5 * separation_m;
        let wheel = |radius_m, angle_rad, drive_offset_rad| Wheel {
            radius_m,
            distance_m: half,
            angle_rad,
            drive_offset_rad,
            roller_angle_rad: 0.0,
        };
        Self {
            wheel_names: default_wheel_names(2),
            wheels: vec![
                // Left: δ = 90°, tangent 180°, turned by 180° to drive forward. Right: δ = −90°, tangent 0°.
                wheel(left_radius_m, FRAC_PI_2, std::f64::consts::PI),
                wheel(right_radius_m, -FRAC_PI_2, 0.0),
            ],
        }
    }

    /// Number of wheels.
    pub fn n_wheels(&self) -> usize {
        self.wheels.len()
    }

    /// Checks every wheel, the names and that the wheels span every planar twist (rank
    /// [`PLANAR_TWIST_DIMENSIONS`]): what an omnidirectional base needs.
    pub fn validate(&self) -> Result<(), KinError> {
        self.validate_for(PLANAR_TWIST_DIMENSIONS)
    }

    /// Numerical rank of the forward kinematics [`Self::wheels_from_twist`] (singular values above
    /// `1e-9`): how many independent twist directions the wheels drive (3 for an omnidirectional base, 2
    /// for a differential drive).
    pub fn rank(&self) -> usize {
        self.wheels_from_twist().rank(RANK_TOLERANCE)
    }

    /// Whether the wheels drive every planar twist ([`Self::rank`] 3: omni, mecanum); a base that is not
    /// (a differential drive, two wheels on one axle) cannot move sideways. The kinematics decide, not the
    /// number of wheels.
    pub fn is_omnidirectional(&self) -> bool {
        self.rank() == PLANAR_TWIST_DIMENSIONS
    }

    /// The planar twist directions the base is built to drive: 2 when every wheel drives along x without
    /// rollers (a differential drive's axle, a skid-steer base's sides: they cannot push sideways, and the
    /// vehicle moves forward and turns), else 3 (omni, mecanum: every planar twist). The wheels' kinds
    /// decide, not their number.
    pub fn twist_dof(&self) -> usize {
        if !self.wheels.is_empty() && self.wheels.iter().all(Wheel::drives_along_x) {
            2
        } else {
            PLANAR_TWIST_DIMENSIONS
        }
    }

    /// Checks every wheel, the names and that the wheels drive at least `needed` independent twist
    /// directions ([`Self::rank`]); a base type states what it needs (3: every planar twist).
    pub fn validate_for(&self, needed: usize) -> Result<(), KinError> {
        if self.wheel_names.len() != self.wheels.len() {
            return Err(KinError::Shape {
                what: "wheel_names".into(),
                got: self.wheel_names.len(),
                expected: self.wheels.len(),
            });
        }
        for (i, w) in self.wheels.iter().enumerate() {
            w.validate(i)?;
        }
        let rank = self.rank();
        if rank < needed {
            return Err(KinError::Singular { wheels: self.wheels.len(), rank, needed });
        }
        Ok(())
    }

    /// Forward kinematics (N × 3): wheel speeds (rad/s) from a body twist (vx, vy in m/s, ω in rad/s).
    /// Used to turn motion commands into wheel-speed targets.
    pub fn wheels_from_twist(&self) -> DMatrix<f64> {
        let n = self.wheels.len();
        DMatrix::from_fn(n, 3, |i, j| self.wheels[i].wheel_from_twist_row()[j])
    }

    /// The IK matrix (3 × N, Eq. 3): body twist from wheel speeds. The exact inverse for three wheels; for
    /// more, the least-squares inverse in rim speeds (`G = diag(r) F`, rim speed m/s per twist:
    /// `M = (GᵀG)⁻¹ Gᵀ diag(r)`), which weighs every wheel's arc length alike whatever its radius, as
    /// OptiOdom's and the textbook mecanum models do (with equal radii it is `F`'s own least-squares
    /// inverse). Two wheels (a differential drive) drive two twist directions (rank 2 is enough): the
    /// minimum-norm inverse `M = Gᵀ (G Gᵀ)⁻¹ diag(r)`, which on an axle along y has a zero `vy` row.
    pub fn twist_from_wheels(&self) -> Result<IkMatrix, KinError> {
        let n = self.wheels.len();
        let needed = if n == 2 { 2 } else { self.twist_dof() };
        self.validate_for(needed)?;
        let m = self.wheels_from_twist();
        // The (pseudo-)inverse exists once the rank is enough; were it lost to rounding, say so as a rank
        // one short.
        let lost = KinError::Singular { wheels: n, rank: needed - 1, needed };
        let inv = if n == 3 {
            m.try_inverse().ok_or(lost)?
        } else {
            let radii =
                DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(n, self.wheels.iter().map(|w| w.radius_m)));
            let rim = &radii * &m;
            let rt = rim.transpose();
            if needed == 2 && n > 2 {
                // Wheels on two sides (skid-steer): the pseudo-inverse in rim speeds, each side's wheels
                // sharing its rim speed alike; no wheel pushes sideways, so the vy row is zero.
                let mut inv = rim.clone().pseudo_inverse(1e-12).map_err(|_| lost)? * radii;
                inv.row_mut(1).fill(0.0);
                inv
            } else if n == 2 {
                let gram_inv = (&rim * &rt).try_inverse().ok_or(lost)?;
                let mut inv = rt * gram_inv * radii;
                // An axle along y cannot push sideways: its vy row is zero, exactly (not sin π's rounding),
                // so that models see a structural zero.
                if m.column(1).amax() <= 1e-12 * m.amax() {
                    inv.row_mut(1).fill(0.0);
                }
                inv
            } else {
                let normal_inv = (&rt * &rim).try_inverse().ok_or(lost)?;
                normal_inv * rt * radii
            }
        };
        let n = self.wheels.len();
        let mut entries = Vec::with_capacity(3 * n);
        for r in 0..3 {
            for c in 0..n {
                entries.push(inv[(r, c)]);
            }
        }
        IkMatrix::new(n, entries)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ik::IkMatrix;
    use approx::assert_relative_eq;

    #[test]
    fn eq3_reproduces_eq7() {
        let ik = RobotGeometry::apr02().twist_from_wheels().unwrap();
        let eq7 = IkMatrix::paper_design();
        for r in 0..3 {
            for c in 0..3 {
                assert!(
                    (ik.get(r, c) - eq7.get(r, c)).abs() < 1e-12,
                    "m{}{}: {} vs {}",
                    r + 1,
                    c + 1,
                    ik.get(r, c),
                    eq7.get(r, c)
                );
            }
        }
    }

    #[test]
    fn forward_row_of_apr02_wheel_b() {
        // δ = 180°: r ω = −vy + R ω.
        let g = RobotGeometry::apr02();
        let row = g.wheels[1].wheel_from_twist_row();
        assert_relative_eq!(row[0], 0.0, epsilon = 1e-12);
        assert_relative_eq!(row[1], -1.0 / 0.148, epsilon = 1e-12);
        assert_relative_eq!(row[2], 0.195 / 0.148, epsilon = 1e-12);
    }

    #[test]
    fn mecanum_matches_textbook() {
        let (r, lx, ly) = (0.05, 0.2, 0.15);
        let m = RobotGeometry::mecanum4(r, lx, ly).wheels_from_twist();
        let expect = [[1.0, -1.0, -(lx + ly)], [1.0, 1.0, lx + ly], [1.0, 1.0, -(lx + ly)], [1.0, -1.0, lx + ly]];
        for (i, row) in expect.iter().enumerate() {
            for j in 0..3 {
                assert_relative_eq!(m[(i, j)], row[j] / r, epsilon = 1e-9);
            }
        }
        let ik = RobotGeometry::mecanum4(r, lx, ly).twist_from_wheels().unwrap();
        // Pseudo-inverse recovers a twist from consistent wheel speeds.
        let twist = [0.3, -0.1, 0.5];
        let w: Vec<f64> = (0..4).map(|i| (0..3).map(|j| m[(i, j)] * twist[j]).sum()).collect();
        let t = ik.twist(&w);
        assert_relative_eq!(t.vx_m_s, 0.3, epsilon = 1e-12);
        assert_relative_eq!(t.vy_m_s, -0.1, epsilon = 1e-12);
        assert_relative_eq!(t.omega_rad_s, 0.5, epsilon = 1e-12);
    }

    #[test]
    fn rejects_bad_wheels() {
        let mut g = RobotGeometry::apr02();
        g.wheels[2].radius_m = -0.1;
        assert_eq!(
            g.twist_from_wheels().unwrap_err().to_string(),
            "wheel 2: radius_m = -0.1 is not valid (must be > 0)"
        );
        let collinear = RobotGeometry::new(vec![
            Wheel::omni(0.1, 0.2, 0.0),
            Wheel::omni(0.1, 0.2, 0.0),
            Wheel::omni(0.1, 0.2, 0.0),
        ]);
        assert!(matches!(collinear, Err(KinError::Singular { .. })));
    }
}
