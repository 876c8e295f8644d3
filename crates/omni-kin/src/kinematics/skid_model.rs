//! The parametric model of a skid-steer base (`skid`): the ICR-based extended differential drive of
//! Martínez et al. (2005) and Mandow et al. (2007), "Experimental kinematics for wheeled skid-steer mobile
//! robots" (IROS 2007).
//!
//! Four or six (any even number of) wheels on two sides drive along x and cannot steer: turning drags
//! them sideways over the ground, so the robot turns about points that are not where the wheels are. The
//! model places the instantaneous centres of rotation (ICRs) of the left and right treads at lateral
//! offsets `y_L > y_R` and the robot's own ICR at a longitudinal offset `x` from the base's origin. With
//! each side's rim speed `v_S = r_S · mean over the side's wheels of σ_i ω_i` (`σ_i = ±1`: which way
//! positive wheel speed pushes) and `Δ = y_L − y_R`:
//!
//! ```text
//! vx = (v_R y_L − v_L y_R) / Δ      vy = −x ω      ω = (v_R − v_L) / Δ
//! ```
//!
//! Parameters, in order: `r_right`, `r_left` (each side's effective wheel radius, m), `y_icr_left`,
//! `y_icr_right` (the treads' ICRs, m, left of the origin positive), `x_icr` (the robot's ICR, m, forward
//! of the origin positive). At `y_L = −y_R = b/2`, `x = 0` it is the differential drive of separation `b`;
//! a skid-steer robot's effective track `Δ` is typically 1.2–2 times its wheels' separation (the track
//! expansion factor χ = Δ/b), and an ICR forward of the origin (`x > 0`, a load towards the front) makes
//! the robot slip sideways while it turns.
//!
//! Every parameter is identifiable from wheel speeds and a ground-truth pose: the `vx` and `ω` rows give
//! `y_L = vx/ω` of a right wheel's column, `y_R` of a left one's, then the radii; `x` needs turning while
//! the ground truth sees the sideways slip (`vy = −x ω`). A model file stores the design wheels and the
//! parameters in a `[skid]` table ([`SkidRecord`]).

use super::{BaseKinematics, BaseRecord, KinematicsKind, RecordError};
use crate::effect::ParamSpec;
use crate::error::{Domain, KinError};
use crate::geometry::RobotGeometry;
use crate::ik::IkMatrix;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// The `skid` model around a design geometry (wheels driving along x on two sides).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkidKinematics {
    /// Design geometry: the wheels on both sides, driving along x.
    pub design: RobotGeometry,
}

/// A model file's `[skid]` table: the fitted parameters, by name and unit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkidRecord {
    /// Right side's effective wheel radius. m.
    pub r_right_m: f64,
    /// Left side's effective wheel radius. m.
    pub r_left_m: f64,
    /// Left tread's ICR, left of the origin. m.
    pub y_icr_left_m: f64,
    /// Right tread's ICR, left of the origin (negative: to the right). m.
    pub y_icr_right_m: f64,
    /// The robot's ICR, forward of the origin. m.
    pub x_icr_m: f64,
}

impl SkidRecord {
    fn params(&self) -> Vec<f64> {
        vec![self.r_right_m, self.r_left_m, self.y_icr_left_m, self.y_icr_right_m, self.x_icr_m]
    }
}

/// Parameter names, in order.
pub const SKID_PARAMS: [&str; 5] = ["r_right", "r_left", "y_icr_left", "y_icr_right", "x_icr"];

/// The sides of a skid-steer geometry, read from its wheels.
#[derive(Clone, Debug, PartialEq)]
struct Sides {
    /// Per wheel: on the left (y > 0).
    left: Vec<bool>,
    /// Per wheel: `σ / n_side`, the wheel's share of its side's rim speed per unit radius.
    share: Vec<f64>,
    /// Design values of the parameters: mean radius per side (right, left), mean y per side (left,
    /// right), mean x of every wheel.
    design: [f64; 5],
    /// Half the design track, or half the wheelbase when longer: the scale of the ICR offsets. m.
    half_span_m: f64,
}

fn not_skid(why: &'static str) -> KinError {
    KinError::Layout { model: KinematicsKind::Skid, why }
}

impl Sides {
    fn of(g: &RobotGeometry) -> Result<Self, KinError> {
        let n = g.n_wheels();
        if n < 2 || g.wheel_names.len() != n {
            return Err(not_skid("a skid-steer base has wheels on both sides (and one name per wheel)"));
        }
        let (mut left, mut sign, mut xs) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
        let (mut sum_r, mut sum_y, mut count) = ([0.0; 2], [0.0; 2], [0usize; 2]);
        for (i, w) in g.wheels.iter().enumerate() {
            if !(w.radius_m > 0.0 && w.radius_m.is_finite()) {
                return Err(KinError::BadWheel { wheel: i, field: "radius_m", value: w.radius_m, why: "must be > 0" });
            }
            let beta = w.angle_rad + FRAC_PI_2 + w.drive_offset_rad;
            if !w.drives_along_x() {
                return Err(not_skid("every wheel must drive along x, without rollers (no steering)"));
            }
            let (x, y) = (w.distance_m * w.angle_rad.cos(), w.distance_m * w.angle_rad.sin());
            if y == 0.0 || !y.is_finite() {
                return Err(not_skid("every wheel must sit on one side of the centre (y < 0 or y > 0)"));
            }
            let side = usize::from(y > 0.0);
            left.push(y > 0.0);
            sign.push(beta.cos().signum());
            xs.push(x);
            sum_r[side] += w.radius_m;
            sum_y[side] += y;
            count[side] += 1;
        }
        if count.contains(&0) {
            return Err(not_skid("a skid-steer base needs wheels on both sides (y < 0 and y > 0)"));
        }
        let share = (0..n).map(|i| sign[i] / count[usize::from(left[i])] as f64).collect();
        let (y_left, y_right) = (sum_y[1] / count[1] as f64, sum_y[0] / count[0] as f64);
        let x_mean = xs.iter().sum::<f64>() / n as f64;
        let wheelbase =
            xs.iter().copied().fold(f64::NEG_INFINITY, f64::max) - xs.iter().copied().fold(f64::INFINITY, f64::min);
        Ok(Self {
            left,
            share,
            design: [sum_r[0] / count[0] as f64, sum_r[1] / count[1] as f64, y_left, y_right, x_mean],
            half_span_m: 0.5 * (y_left - y_right).max(wheelbase),
        })
    }
}

impl SkidKinematics {
    /// The model around a design geometry, checked: wheels driving along x, on both sides.
    pub fn new(design: RobotGeometry) -> Result<Self, KinError> {
        Sides::of(&design)?;
        Ok(Self { design })
    }

    fn sides(&self) -> Result<Sides, KinError> {
        Sides::of(&self.design)
    }

    /// `(r_R, r_L, y_L, y_R, x)` from `p`, checked: radii > 0, `y_L > y_R`, all finite.
    fn unpack(&self, p: &[f64]) -> Result<[f64; 5], KinError> {
        if p.len() != 5 {
            return Err(KinError::ParamCount { got: p.len(), expected: 5 });
        }
        for (name, v) in SKID_PARAMS.iter().zip(p).take(2) {
            if !(v.is_finite() && *v > 0.0) {
                return Err(KinError::BadParam { name: name.to_string(), value: *v, must: Domain::Positive });
            }
        }
        for (name, v) in SKID_PARAMS.iter().zip(p).skip(2) {
            if !v.is_finite() {
                return Err(KinError::BadParam { name: name.to_string(), value: *v, must: Domain::Finite });
            }
        }
        if p[2] <= p[3] {
            return Err(KinError::BadParam {
                name: "y_icr_left - y_icr_right".into(),
                value: p[2] - p[3],
                must: Domain::Positive,
            });
        }
        Ok([p[0], p[1], p[2], p[3], p[4]])
    }

    /// The design values of the parameters.
    pub fn design_params(&self) -> Result<Vec<f64>, KinError> {
        Ok(self.sides()?.design.to_vec())
    }

    /// The effective track `y_L − y_R` at `p` (what a differential controller calls the wheel separation).
    /// m.
    pub fn effective_track_m(p: &[f64]) -> Option<f64> {
        (p.len() == 5).then(|| p[2] - p[3])
    }
}

impl BaseKinematics for SkidKinematics {
    fn kind(&self) -> KinematicsKind {
        KinematicsKind::Skid
    }

    fn n_wheels(&self) -> usize {
        self.design.n_wheels()
    }

    fn wheel_names(&self) -> Vec<String> {
        self.design.wheel_names.clone()
    }

    fn n_params(&self) -> usize {
        5
    }

    /// The radii ±10 %; the treads' ICRs from half their design value inwards to 1.5 times the design
    /// track's half outwards (skid-steer robots turn as if their track were up to twice as wide); the
    /// robot's ICR within the wheelbase's half (the track's, when wider) of the wheels' centre.
    fn params(&self) -> Vec<ParamSpec> {
        let Ok(s) = self.sides() else {
            return SKID_PARAMS.iter().map(|n| ParamSpec::new(*n, "m", f64::NAN, f64::NAN, f64::NAN)).collect();
        };
        let [rr, rl, yl, yr, x] = s.design;
        let half_track = 0.5 * (yl - yr);
        vec![
            ParamSpec::new("r_right", "m", rr, 0.9 * rr, 1.1 * rr),
            ParamSpec::new("r_left", "m", rl, 0.9 * rl, 1.1 * rl),
            ParamSpec::new("y_icr_left", "m", yl, yl - 0.5 * half_track, yl + 1.5 * half_track),
            ParamSpec::new("y_icr_right", "m", yr, yr - 1.5 * half_track, yr + 0.5 * half_track),
            ParamSpec::new("x_icr", "m", x, x - s.half_span_m, x + s.half_span_m),
        ]
    }

    /// The radii's own magnitudes; half the effective track at `p` for the three ICR offsets.
    fn param_scales(&self, p: &[f64]) -> Vec<f64> {
        let half = if p.len() == 5 { 0.5 * (p[2] - p[3]).abs() } else { f64::NAN };
        let half = if half > 0.0 { half } else { self.sides().map_or(f64::NAN, |s| s.half_span_m) };
        let radius = |i: usize| p.get(i).map_or(f64::NAN, |v| v.abs());
        vec![radius(0), radius(1), half, half, half]
    }

    fn twist_from_wheels(&self, p: &[f64]) -> Result<IkMatrix, KinError> {
        let s = self.sides()?;
        let [rr, rl, yl, yr, x] = self.unpack(p)?;
        let n = s.left.len();
        let d = yl - yr;
        let mut m = vec![0.0; 3 * n];
        for c in 0..n {
            // The side's rim speed per unit of this wheel's speed, then its share of vx and ω.
            let (vx, om) = if s.left[c] { (-yr / d, -1.0 / d) } else { (yl / d, 1.0 / d) };
            let k = s.share[c] * if s.left[c] { rl } else { rr };
            m[c] = k * vx;
            m[n + c] = -x * k * om;
            m[2 * n + c] = k * om;
        }
        IkMatrix::new(n, m)
    }

    /// Exact (see the module's formulas).
    fn twist_from_wheels_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, KinError> {
        let s = self.sides()?;
        let [rr, rl, yl, yr, x] = self.unpack(p)?;
        let n = s.left.len();
        let d = yl - yr;
        let d2 = d * d;
        let mut j = DMatrix::zeros(3 * n, 5);
        for c in 0..n {
            let a = s.share[c];
            let (vx, vy, om) = (c, n + c, 2 * n + c);
            if s.left[c] {
                // vx = −a r_L y_R/Δ, ω = −a r_L/Δ, vy = a r_L x/Δ.
                j[(vx, 1)] = -a * yr / d;
                j[(om, 1)] = -a / d;
                j[(vy, 1)] = a * x / d;
                j[(vx, 2)] = a * rl * yr / d2;
                j[(om, 2)] = a * rl / d2;
                j[(vy, 2)] = -a * rl * x / d2;
                j[(vx, 3)] = -a * rl * yl / d2;
                j[(om, 3)] = -a * rl / d2;
                j[(vy, 3)] = a * rl * x / d2;
                j[(vy, 4)] = a * rl / d;
            } else {
                // vx = a r_R y_L/Δ, ω = a r_R/Δ, vy = −a r_R x/Δ.
                j[(vx, 0)] = a * yl / d;
                j[(om, 0)] = a / d;
                j[(vy, 0)] = -a * x / d;
                j[(vx, 2)] = -a * rr * yr / d2;
                j[(om, 2)] = -a * rr / d2;
                j[(vy, 2)] = a * rr * x / d2;
                j[(vx, 3)] = a * rr * yl / d2;
                j[(om, 3)] = a * rr / d2;
                j[(vy, 3)] = -a * rr * x / d2;
                j[(vy, 4)] = -a * rr / d;
            }
        }
        Ok(j)
    }

    /// Half the design's effective track.
    fn lever_arm_m(&self) -> f64 {
        self.sides().map_or(super::DEFAULT_LEVER_ARM_M, |s| 0.5 * (s.design[2] - s.design[3]))
    }

    fn noun(&self) -> &'static str {
        "skid-steer base"
    }

    /// `[[design_wheels]]` and the parameters as `[skid]`.
    fn record(&self, p: &[f64]) -> Result<BaseRecord, KinError> {
        let [rr, rl, yl, yr, x] = self.unpack(p)?;
        Ok(BaseRecord {
            wheel_names: self.design.wheel_names.clone(),
            design_wheels: Some(self.design.wheels.clone()),
            skid: Some(SkidRecord { r_right_m: rr, r_left_m: rl, y_icr_left_m: yl, y_icr_right_m: yr, x_icr_m: x }),
            ..BaseRecord::default()
        })
    }

    /// The design from `[[design_wheels]]`, the parameters from `[skid]`.
    fn from_record(record: &BaseRecord) -> Result<(Self, Vec<f64>), RecordError> {
        let d = record.design_wheels.clone().ok_or(RecordError::Missing { kind: "skid", key: "[[design_wheels]]" })?;
        let skid = record.skid.ok_or(RecordError::Missing { kind: "skid", key: "[skid]" })?;
        let design = RobotGeometry { wheel_names: record.wheel_names.clone(), wheels: d };
        let model = Self::new(design).map_err(|error| RecordError::Invalid { key: "design_wheels", error })?;
        let p = skid.params();
        model.unpack(&p).map_err(|error| RecordError::Invalid { key: "skid", error })?;
        Ok((model, p))
    }

    /// The robot's geometry, which must be a skid-steer base; there is no default robot.
    fn design_for(robot: Option<&RobotGeometry>) -> Result<Self, KinError> {
        let g = robot.ok_or_else(|| not_skid("the skid model needs the robot's geometry (a robot description)"))?;
        Self::new(g.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Husky-like base: 4 wheels, track 0.555 m, wheelbase 0.512 m, r = 0.165 m, joints FL, RL, FR, RR.
    fn husky() -> RobotGeometry {
        let mut g = RobotGeometry::skid4(0.165, 0.256, 0.2775);
        g.wheel_names = ["fl", "rl", "fr", "rr"].iter().map(|s| s.to_string()).collect();
        g
    }

    #[test]
    fn the_design_is_the_differential_drive_of_the_wheels_separation() {
        let k = SkidKinematics::new(husky()).unwrap();
        let p = k.design_params().unwrap();
        assert_eq!(p.len(), 5);
        assert!((p[2] - 0.2775).abs() < 1e-12 && (p[3] + 0.2775).abs() < 1e-12 && p[4].abs() < 1e-12);
        let m = k.twist_from_wheels(&p).unwrap();
        // All four wheels at 1 rad/s: vx = r; left side forward only: ω = −r/b (each left wheel half of it).
        let t = m.twist(&[1.0; 4]);
        assert!((t.vx_m_s - 0.165).abs() < 1e-12 && t.vy_m_s.abs() < 1e-12 && t.omega_rad_s.abs() < 1e-12);
        let t = m.twist(&[1.0, 1.0, 0.0, 0.0]);
        assert!((t.omega_rad_s + 0.165 / 0.555).abs() < 1e-12);
        // The geometry's own (pseudo-)inverse agrees.
        let g = husky().twist_from_wheels().unwrap();
        for (a, b) in m.entries().iter().zip(g.entries()) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
    }

    #[test]
    fn an_icr_shift_widens_the_turn_and_slips_sideways() {
        let k = SkidKinematics::new(husky()).unwrap();
        let p = [0.165, 0.165, 0.45, -0.45, 0.05];
        let m = k.twist_from_wheels(&p).unwrap();
        // Turning on the spot (right forward, left back): ω = 2 v/Δ, vy = −x ω, vx = 0 (symmetric ICRs).
        let t = m.twist(&[-1.0, -1.0, 1.0, 1.0]);
        assert!((t.omega_rad_s - 2.0 * 0.165 / 0.9).abs() < 1e-12);
        assert!((t.vy_m_s + 0.05 * t.omega_rad_s).abs() < 1e-12 && t.vx_m_s.abs() < 1e-12);
        assert_eq!(SkidKinematics::effective_track_m(&p), Some(0.9));
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let k = SkidKinematics::new(husky()).unwrap();
        let p = [0.16, 0.17, 0.41, -0.38, 0.03];
        let j = k.twist_from_wheels_jacobian(&p).unwrap();
        for col in 0..5 {
            let h = 1e-6;
            let mut up = p;
            let mut down = p;
            up[col] += h;
            down[col] -= h;
            let (a, b) = (k.twist_from_wheels(&up).unwrap(), k.twist_from_wheels(&down).unwrap());
            for (row, (x, y)) in a.entries().iter().zip(b.entries()).enumerate() {
                let fd = (x - y) / (2.0 * h);
                assert!((fd - j[(row, col)]).abs() < 1e-6, "entry {row}, param {col}: {fd} vs {}", j[(row, col)]);
            }
        }
    }

    #[test]
    fn a_record_round_trips_and_bad_values_are_named() {
        let k = SkidKinematics::new(husky()).unwrap();
        let p = vec![0.16, 0.17, 0.41, -0.38, 0.03];
        let rec = k.record(&p).unwrap();
        let (back, q) = SkidKinematics::from_record(&rec).unwrap();
        assert_eq!((back, q), (k.clone(), p));
        let err = k.twist_from_wheels(&[0.16, 0.17, -0.4, -0.38, 0.0]).unwrap_err().to_string();
        assert!(err.contains("y_icr_left - y_icr_right"), "{err}");
        let mut one_side = husky();
        for w in &mut one_side.wheels {
            w.angle_rad = w.angle_rad.abs();
            w.drive_offset_rad = -w.angle_rad - FRAC_PI_2;
        }
        let err = SkidKinematics::new(one_side).unwrap_err().to_string();
        assert!(err.contains("both sides"), "{err}");
    }
}
