//! Learned corrections: one effect per family of physically meaningful features, each a linear
//! correction `Σ_k θ_k f_k(state)` with named terms, null at θ = 0. The explorer (omni-ga's
//! `science::explore`) fits θ on training runs and judges each family on held-out runs; a family that
//! passes becomes the effect `learned:<family>` that training, diagnosis, model files and Python treat like
//! any other.
//!
//! | family | stage | correction | terms (unit) |
//! |---|---|---|---|
//! | `wheel` | wheel | `ω_i += f(ω_i, φ_i)` per wheel | `speed_<w>` (s/rad) × ω\|ω\|, `sign_<w>` (1) × \|ω\|, `accel_<w>` (s) × dω/dt, `cos<n>_<w>`, `sin<n>_<w>` (1) × ω cos nφ, ω sin nφ for n = 1, 2, 3 |
//! | `body` | twist | on the body twist `(v, ω)`, `s = \|v\|`, α its direction | `omega_speed` (rad/m) δω = θ s; `omega_abs` (1) δω = θ \|ω\|; `scale_speed` (s/m) δv = θ s v; `scale_turn` (s/rad) δv = θ \|ω\| v; `turn_omega` (s) δv = θ ω (−vy, vx); `scale_cos<n>`, `scale_sin<n>` (1) δv = θ cos nα v, θ sin nα v for n = 1, 2 |
//! | `world` | twist (heading) | a world-frame velocity `d` while moving, turned into the body frame | `drift_x`, `drift_y` (m/s) d = (θx, θy); `omega_cos1`, `omega_sin1` (rad/s) δω = θc cos ψ + θs sin ψ (ψ the heading); `grain_cos2`, `grain_sin2` (1) δv_w = [[θc, θs], [θs, −θc]] v_w, the world-frame velocity faster along one direction than across it (a carpet's grain) |
//! | `time` | twist (time) | growing with the time `t` since the run's first ground-truth pose, while moving | `drift_x_per_s`, `drift_y_per_s` (m/s²) d = t (θx, θy); `omega_per_s` (rad/s²) δω = θ t; `scale_per_s` (1/s) δv = θ t v |
//! | `ground_truth` | measurement | the ground-truth sensor's lever arm and yaw | `lever_x_m`, `lever_y_m` (m), `yaw_rad` (rad) |
//!
//! "Moving": `|v| > 5 mm/s` or `|ω| > 0.02 rad/s` ([`moving`]). The ground-truth sensor's scale is not a
//! term: a scale of the measured path is a scale of the translation, which the IK matrix already fits.

use super::{Effect, ParamSpec, Stage, TwistAt, WheelContext};
use crate::error::KinError;
use crate::pose::{Pose2, Twist2};
use serde::{Deserialize, Serialize};

/// Prefix of every learned effect id: `learned:world`.
pub const PREFIX: &str = "learned:";
/// The one "moving" predicate of every effect (world and time terms act only then; shared with
/// `world_drift`).
pub use super::{MOVING_OMEGA_RAD_S, MOVING_SPEED_M_S, moving};

/// A family of features the explorer fits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// Per wheel: speed, sign, acceleration, harmonics of the wheel angle.
    Wheel,
    /// Products of the body twist and harmonics of the travel direction in the body frame.
    Body,
    /// A world-frame drift while moving, and terms of the world heading.
    World,
    /// Drift growing with the time since the run started.
    Time,
    /// Lever arm and yaw of the ground-truth sensor.
    GroundTruth,
}

crate::choice!(Family, {
    Wheel => "wheel": "Per wheel: speed, sign, acceleration, harmonics 1-3 of the wheel angle",
    Body => "body": "Products of the body twist (v·ω, ω², |v|), harmonics of the travel direction",
    World => "world": "A world-frame drift while moving, a turn rate and a speed grain by the world heading",
    Time => "time": "Drift growing with the time since the run started",
    GroundTruth => "ground_truth": "Lever arm and yaw of the ground-truth sensor",
});

/// Every learned effect id, in family order: `learned:wheel`, ….
pub fn ids() -> Vec<String> {
    Family::ALL.iter().map(|f| format!("{PREFIX}{}", f.id())).collect()
}

/// A learned correction over one family's features (see the module table).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Learned {
    /// Which features.
    pub family: Family,
    /// Number of wheels (the `wheel` family has terms per wheel).
    pub n_wheels: usize,
}

fn letter(i: usize) -> char {
    char::from(b'a' + (i % 26) as u8)
}

/// Wheel-family term kinds, in parameter order (each then per wheel).
const WHEEL_TERMS: [(&str, &str); 9] = [
    ("speed", "s/rad"),
    ("sign", "1"),
    ("accel", "s"),
    ("cos1", "1"),
    ("sin1", "1"),
    ("cos2", "1"),
    ("sin2", "1"),
    ("cos3", "1"),
    ("sin3", "1"),
];

const BODY_TERMS: [(&str, &str); 9] = [
    ("omega_speed", "rad/m"),
    ("omega_abs", "1"),
    ("scale_speed", "s/m"),
    ("scale_turn", "s/rad"),
    ("turn_omega", "s"),
    ("scale_cos1", "1"),
    ("scale_sin1", "1"),
    ("scale_cos2", "1"),
    ("scale_sin2", "1"),
];

const WORLD_TERMS: [(&str, &str); 6] = [
    ("drift_x", "m/s"),
    ("drift_y", "m/s"),
    ("omega_cos1", "rad/s"),
    ("omega_sin1", "rad/s"),
    ("grain_cos2", "1"),
    ("grain_sin2", "1"),
];

const TIME_TERMS: [(&str, &str); 4] =
    [("drift_x_per_s", "m/s²"), ("drift_y_per_s", "m/s²"), ("omega_per_s", "rad/s²"), ("scale_per_s", "1/s")];

const GROUND_TRUTH_TERMS: [(&str, &str); 3] = [("lever_x_m", "m"), ("lever_y_m", "m"), ("yaw_rad", "rad")];

/// Search bound of a term by its unit: what training's box (the GA's search space) allows. A box much
/// wider than any physical value lets the GA settle in a far local minimum.
fn bound(unit: &str) -> f64 {
    match unit {
        "m/s" | "rad/s" => 0.05,
        "m/s²" | "rad/s²" | "1/s" => 0.01,
        "m" | "rad" | "s/m" => 0.5,
        _ => 0.2,
    }
}

impl Learned {
    /// `learned:<family>` for a robot with `n_wheels` wheels.
    pub fn from_id(id: &str, n_wheels: usize) -> Result<Self, KinError> {
        let name = id.strip_prefix(PREFIX).unwrap_or(id);
        let family = Family::ALL
            .iter()
            .copied()
            .find(|f| f.id() == name)
            .ok_or_else(|| KinError::unknown("effect", id, &ids()))?;
        Ok(Self { family, n_wheels })
    }

    /// Term names and units, in parameter order.
    pub fn terms(&self) -> Vec<(String, &'static str)> {
        let fixed = |t: &[(&str, &'static str)]| t.iter().map(|(n, u)| (n.to_string(), *u)).collect();
        match self.family {
            Family::Wheel => WHEEL_TERMS
                .iter()
                .flat_map(|(n, u)| (0..self.n_wheels).map(move |i| (format!("{n}_{}", letter(i)), *u)))
                .collect(),
            Family::Body => fixed(&BODY_TERMS),
            Family::World => fixed(&WORLD_TERMS),
            Family::Time => fixed(&TIME_TERMS),
            Family::GroundTruth => fixed(&GROUND_TRUTH_TERMS),
        }
    }
}

/// Adds the world-frame velocity `d` (m/s) to the body twist of a robot at heading `psi`.
fn add_world(t: &mut Twist2, d: [f64; 2], psi: f64) {
    let (s, c) = psi.sin_cos();
    t.vx_m_s += c * d[0] + s * d[1];
    t.vy_m_s += -s * d[0] + c * d[1];
}

/// A floor whose grain makes the world-frame velocity `v_w` of the twist `t` (at heading `psi`) faster
/// along one world direction than across it: `δv_w = G v_w`, `G = [[gc, gs], [gs, −gc]]` (traceless: the
/// common speed scale is the kinematics'), the speed along the direction `atan2(gs, gc) / 2` scaled by
/// `1 + hypot(gc, gs)` and across it by `1 − hypot(gc, gs)`; added to `out`'s body velocity.
fn grain(out: &mut Twist2, t: Twist2, [gc, gs]: [f64; 2], psi: f64) {
    if gc == 0.0 && gs == 0.0 {
        return;
    }
    let (sn, cs) = psi.sin_cos();
    let (c, s) = grain_in_body(gc, gs, cs, sn);
    out.vx_m_s += c * t.vx_m_s + s * t.vy_m_s;
    out.vy_m_s += s * t.vx_m_s - c * t.vy_m_s;
}

/// The grain `(gc, gs)` seen in the body frame at heading cosine and sine `(c, s)`: the same gain turned by
/// −2ψ. Shared with the lane kernel, which carries the heading's cosine and sine.
#[inline(always)]
pub(crate) fn grain_in_body(gc: f64, gs: f64, c: f64, s: f64) -> (f64, f64) {
    let (c2, s2) = (c * c - s * s, 2.0 * c * s);
    (gc * c2 + gs * s2, gs * c2 - gc * s2)
}

/// The `body` family's correction of one twist.
fn body(p: &[f64], t: Twist2) -> Twist2 {
    let (vx, vy, w) = (t.vx_m_s, t.vy_m_s, t.omega_rad_s);
    let s = (vx * vx + vy * vy).sqrt();
    let (ca, sa) = if s > 0.0 { (vx / s, vy / s) } else { (0.0, 0.0) };
    let (c2, s2) = (ca * ca - sa * sa, 2.0 * ca * sa);
    let scale = p[2] * s + p[3] * w.abs() + p[5] * ca + p[6] * sa + p[7] * c2 + p[8] * s2;
    Twist2 {
        vx_m_s: vx + scale * vx - p[4] * w * vy,
        vy_m_s: vy + scale * vy + p[4] * w * vx,
        omega_rad_s: w + p[0] * s + p[1] * w.abs(),
    }
}

impl Effect for Learned {
    fn id(&self) -> &str {
        match self.family {
            Family::Wheel => "learned:wheel",
            Family::Body => "learned:body",
            Family::World => "learned:world",
            Family::Time => "learned:time",
            Family::GroundTruth => "learned:ground_truth",
        }
    }
    fn describe(&self) -> String {
        format!("a learned correction over the {} features", self.family.id())
    }
    fn stage(&self) -> Stage {
        match self.family {
            Family::Wheel => Stage::Wheel,
            Family::Body | Family::World | Family::Time => Stage::Twist,
            Family::GroundTruth => Stage::Measurement,
        }
    }
    fn params(&self) -> Vec<ParamSpec> {
        self.terms()
            .into_iter()
            .map(|(name, unit)| {
                let b = bound(unit);
                ParamSpec::new(name, unit, 0.0, -b, b)
            })
            .collect()
    }
    fn wheel_rates_affine(&self) -> bool {
        self.family == Family::Wheel
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        if self.family == Family::Wheel {
            wheel_rates(p, ctx, w);
        }
    }
    fn twist(&self, p: &[f64], t: Twist2, _w: &[f64]) -> Twist2 {
        self.twist_at(p, t, _w, &TwistAt::default())
    }
    fn twist_at(&self, p: &[f64], t: Twist2, _w: &[f64], at: &TwistAt) -> Twist2 {
        if p.iter().all(|v| *v == 0.0) {
            return t;
        }
        match self.family {
            Family::Body => body(p, t),
            Family::World if moving(&t) => {
                let psi = at.pose.theta_rad;
                let mut out = t;
                add_world(&mut out, [p[0], p[1]], psi);
                out.omega_rad_s += p[2] * psi.cos() + p[3] * psi.sin();
                grain(&mut out, t, [p[4], p[5]], psi);
                out
            }
            Family::Time if moving(&t) => {
                let k = at.since_start_s;
                let mut out = t;
                out.vx_m_s += p[3] * k * t.vx_m_s;
                out.vy_m_s += p[3] * k * t.vy_m_s;
                add_world(&mut out, [p[0] * k, p[1] * k], at.pose.theta_rad);
                out.omega_rad_s += p[2] * k;
                out
            }
            _ => t,
        }
    }
    fn sensor_from_body(&self, p: &[f64]) -> Pose2 {
        match self.family {
            Family::GroundTruth => Pose2::new(p[0], p[1], p[2]),
            _ => Pose2::IDENTITY,
        }
    }
}

/// The `wheel` family's correction of a run's wheel speeds (every term from the measured speeds).
fn wheel_rates(p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
    let n = ctx.n_wheels;
    let term = |k: usize, i: usize| p[k * n + i];
    for i in 0..n {
        if (0..WHEEL_TERMS.len()).all(|k| term(k, i) == 0.0) {
            continue;
        }
        let mut phi = ctx.start_angle_rad.get(i).copied().unwrap_or(0.0);
        let mut prev = None;
        for s in 0..ctx.t_s.len() {
            let v = w[s * n + i];
            let h = ctx.dt_s[s];
            // Angle at the middle of the step; acceleration by a backward difference.
            let mid = phi + 0.5 * v * h;
            let accel = match prev {
                Some(u) if h > 0.0 => (v - u) / h,
                _ => 0.0,
            };
            let mut harmonics = 0.0;
            for m in 1..=3 {
                let (a, b) = (term(1 + 2 * m, i), term(2 + 2 * m, i));
                // A harmonic without terms adds nothing (skipping its sine and cosine changes no bit).
                if a != 0.0 || b != 0.0 {
                    let (sn, cs) = (m as f64 * mid).sin_cos();
                    harmonics += a * cs + b * sn;
                }
            }
            w[s * n + i] = v + term(0, i) * v * v.abs() + term(1, i) * v.abs() + term(2, i) * accel + harmonics * v;
            phi += v * h;
            prev = Some(v);
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_and_terms_are_named() {
        for id in ids() {
            let e = Learned::from_id(&id, 3).unwrap();
            assert_eq!(e.id(), id);
        }
        let w = Learned::from_id("learned:wheel", 3).unwrap();
        assert_eq!(w.params().len(), 27);
        assert_eq!(w.params()[4].name, "sign_b");
        let world = Learned::from_id("learned:world", 3).unwrap();
        assert_eq!(world.params()[0].name, "drift_x");
        assert_eq!(world.params()[1].name, "drift_y");
        let err = Learned::from_id("learned:floor", 3).unwrap_err().to_string();
        assert!(err.contains("learned:floor") && err.contains("learned:ground_truth"), "{err}");
    }

    #[test]
    fn world_drift_is_turned_into_the_body_frame() {
        let e = Learned::from_id("learned:world", 3).unwrap();
        let p = [0.01, 0.0, 0.0, 0.0, 0.0, 0.0];
        let at = TwistAt { pose: Pose2::new(0.0, 0.0, std::f64::consts::FRAC_PI_2), since_start_s: 0.0 };
        let t = e.twist_at(&p, Twist2 { vx_m_s: 0.2, vy_m_s: 0.0, omega_rad_s: 0.0 }, &[], &at);
        // Heading +90°: world +x is the body's −y.
        assert!((t.vx_m_s - 0.2).abs() < 1e-15 && (t.vy_m_s + 0.01).abs() < 1e-15, "{t:?}");
        let rest = e.twist_at(&p, Twist2::default(), &[], &at);
        assert_eq!(rest, Twist2::default());
    }

    /// A grain along the world's x axis (`grain_cos2` 0.02): driving along it is 2 % faster, across it 2 %
    /// slower, whatever way the body points; at 45° the speed keeps its size and turns towards the grain.
    #[test]
    fn a_floor_grain_scales_the_world_velocity_along_its_axis() {
        let e = Learned::from_id("learned:world", 3).unwrap();
        let p = [0.0, 0.0, 0.0, 0.0, 0.02, 0.0];
        let forward = Twist2 { vx_m_s: 0.2, vy_m_s: 0.0, omega_rad_s: 0.0 };
        let sideways = Twist2 { vx_m_s: 0.0, vy_m_s: 0.2, omega_rad_s: 0.0 };
        let at = |deg: f64| TwistAt { pose: Pose2::new(0.0, 0.0, deg.to_radians()), since_start_s: 0.0 };
        let along = e.twist_at(&p, forward, &[], &at(0.0));
        assert!((along.vx_m_s - 0.204).abs() < 1e-15 && along.vy_m_s.abs() < 1e-15, "{along:?}");
        let across = e.twist_at(&p, forward, &[], &at(90.0));
        assert!((across.vx_m_s - 0.196).abs() < 1e-15 && across.vy_m_s.abs() < 1e-15, "{across:?}");
        // Heading −90°, driving to the body's left: world +x again, along the grain.
        let left = e.twist_at(&p, sideways, &[], &at(-90.0));
        assert!(left.vx_m_s.abs() < 1e-15 && (left.vy_m_s - 0.204).abs() < 1e-15, "{left:?}");
        let diagonal = e.twist_at(&p, forward, &[], &at(45.0));
        assert!((diagonal.vx_m_s - 0.2).abs() < 1e-15 && (diagonal.vy_m_s + 0.004).abs() < 1e-15, "{diagonal:?}");
    }

    /// The squared test `moving` uses decides as `hypot` does, on and around the threshold.
    #[test]
    fn longer_than_decides_as_hypot_does() {
        let r = MOVING_SPEED_M_S;
        let mut checked = 0;
        for i in 0..2000 {
            let angle = 0.0031 * i as f64;
            for rel in [-1e-6, -1e-12, -1e-15, 0.0, 1e-16, 1e-15, 1e-12, 1e-6, 0.5, -0.5] {
                let len = r * (1.0 + rel);
                let (x, y) = (len * angle.cos(), len * angle.sin());
                assert_eq!(super::super::longer_than(x, y, r), x.hypot(y) > r, "{x:e} {y:e}");
                checked += 1;
            }
        }
        assert_eq!(checked, 20_000);
    }

    /// `world_drift` and `learned:world` act on exactly the same steps: the body twist above 5 mm/s or
    /// 0.02 rad/s, whatever the wheels do (wheels fighting each other at 1 rad/s move the robot nowhere).
    #[test]
    fn world_drift_and_learned_world_share_one_moving_predicate() {
        let learned = Learned::from_id("learned:world", 3).unwrap();
        let catalogue = super::super::EffectKind::from_id("world_drift", 3).unwrap();
        let at = TwistAt { pose: Pose2::new(0.0, 0.0, 0.0), since_start_s: 1.0 };
        let fighting = [1.0, -1.0, 1.0];
        let cases = [
            (Twist2 { vx_m_s: 0.004, vy_m_s: 0.0, omega_rad_s: 0.0 }, false),
            (Twist2 { vx_m_s: 0.0, vy_m_s: 0.006, omega_rad_s: 0.0 }, true),
            (Twist2 { vx_m_s: 0.0, vy_m_s: 0.0, omega_rad_s: 0.019 }, false),
            (Twist2 { vx_m_s: 0.0, vy_m_s: 0.0, omega_rad_s: -0.021 }, true),
            (Twist2::default(), false),
        ];
        for (t, moves) in cases {
            assert_eq!(moving(&t), moves, "{t:?}");
            let a = learned.twist_at(&[0.01, 0.0, 0.0, 0.0, 0.0, 0.0], t, &fighting, &at);
            let b = catalogue.twist_at(&[0.01, 0.0], t, &fighting, &at);
            assert_eq!(a, b, "{t:?}");
            assert_eq!(a.vx_m_s == t.vx_m_s + 0.01, moves, "{t:?}: {a:?}");
        }
    }
}
