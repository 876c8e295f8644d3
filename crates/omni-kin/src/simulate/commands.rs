//! The runs' motions: the paper's flower commands, a differential drive's benchmark, the check that a
//! base can perform its commands (the sideways speed a differential drive cannot produce), and runs of
//! several legs (a square, a figure-eight).

use crate::error::{KinError, Settings};
use crate::geometry::RobotGeometry;
use crate::run::Command;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The paper's 36 flower commands: v = 0.2 m/s, α = 0°, 30°, …, 330°, ω ∈ {−0.35, 0, +0.35} rad/s.
pub fn flower_commands() -> Vec<Command> {
    let mut v = Vec::with_capacity(36);
    for omega in [-0.35, 0.0, 0.35] {
        for a in 0..12 {
            v.push(Command { v_m_s: 0.2, alpha_rad: (30.0 * a as f64).to_radians(), omega_rad_s: omega });
        }
    }
    v
}

/// Forward speed of [`diff_commands`]. m/s.
pub const DIFF_SPEED_M_S: f64 = 0.2;
/// Turn rates of [`diff_commands`]' arcs. rad/s.
pub const DIFF_TURN_RATES_RAD_S: [f64; 5] = [-0.7, -0.35, 0.0, 0.35, 0.7];

/// A differential drive's benchmark: the commands it can perform (it cannot move sideways). Forward
/// (α = 0°) and backward (α = 180°) at [`DIFF_SPEED_M_S`] on arcs of each of [`DIFF_TURN_RATES_RAD_S`]
/// (straight, gentle and tight turns both ways: 10 commands), then turns on the spot at ±0.7 rad/s (2):
/// 12 commands, which excite both wheel radii (straight runs: their mean and difference) and the wheel
/// separation (turns).
pub fn diff_commands() -> Vec<Command> {
    let mut v = Vec::with_capacity(12);
    for alpha_deg in [0.0f64, 180.0] {
        for omega in DIFF_TURN_RATES_RAD_S {
            v.push(Command { v_m_s: DIFF_SPEED_M_S, alpha_rad: alpha_deg.to_radians(), omega_rad_s: omega });
        }
    }
    for omega in [0.7, -0.7] {
        v.push(Command { v_m_s: 0.0, alpha_rad: 0.0, omega_rad_s: omega });
    }
    v
}

/// The benchmark commands for a robot: the paper's 36 [`flower_commands`] for a base that drives every
/// planar twist (omni, mecanum, [`RobotGeometry::is_omnidirectional`]), [`diff_commands`] for a base that
/// cannot move sideways (a differential drive).
pub fn benchmark_commands(design: &RobotGeometry) -> Vec<Command> {
    if design.is_omnidirectional() { flower_commands() } else { diff_commands() }
}

/// The part of each command's twist that the base `design` cannot produce, as a twist error (vx m/s, vy
/// m/s, ω rad/s): the command turned into wheel speeds and back through the design's inverse, minus the
/// command. Zero (to rounding) for every command of an omnidirectional base; a differential drive's is
/// the sideways speed `vy = v sin α` it was asked for.
pub fn unreachable_twists(design: &RobotGeometry, commands: &[Command]) -> Result<Vec<[f64; 3]>, KinError> {
    let fwd = design.wheels_from_twist();
    let ik = design.twist_from_wheels()?;
    Ok(commands
        .iter()
        .map(|c| {
            let (s, co) = c.alpha_rad.sin_cos();
            let twist = [c.v_m_s * co, c.v_m_s * s, c.omega_rad_s];
            let wheels: Vec<f64> =
                (0..design.n_wheels()).map(|i| (0..3).map(|j| fwd[(i, j)] * twist[j]).sum()).collect();
            let back = ik.twist(&wheels);
            [back.vx_m_s - twist[0], back.vy_m_s - twist[1], back.omega_rad_s - twist[2]]
        })
        .collect())
}

/// Largest twist error (m/s or rad/s) [`unreachable_twists`] tolerates: rounding, not a command.
pub const UNREACHABLE_TOL: f64 = 1e-9;

/// Checks that the base `design` can perform every command; the error names the first that it cannot
/// (`commands[i]`) and the speed it cannot produce.
pub fn check_commands(design: &RobotGeometry, commands: &[Command]) -> Result<(), KinError> {
    for (i, c) in commands.iter().enumerate() {
        for (f, v) in [("v_m_s", c.v_m_s), ("alpha_rad", c.alpha_rad), ("omega_rad_s", c.omega_rad_s)] {
            if !v.is_finite() {
                return Err(KinError::Setting {
                    of: Settings::Simulator,
                    field: format!("commands[{i}].{f}"),
                    why: format!("{v} is not finite"),
                });
            }
        }
    }
    let misses = unreachable_twists(design, commands)?;
    match misses.iter().position(|m| m.iter().any(|x| x.abs() > UNREACHABLE_TOL)) {
        None => Ok(()),
        Some(i) => Err(KinError::Setting {
            of: Settings::Simulator,
            field: format!("commands[{i}].alpha_rad"),
            why: unreachable_message(design.n_wheels(), &commands[i], &misses[i]),
        }),
    }
}

/// Why a command `c` that misses the twist `miss` (from [`unreachable_twists`]) cannot be driven by a
/// base of `n_wheels` wheels: the command's twist and the components the base cannot produce.
pub fn unreachable_message(n_wheels: usize, c: &Command, miss: &[f64; 3]) -> String {
    let (s, co) = c.alpha_rad.sin_cos();
    let missing: Vec<String> = [("vx", "m/s"), ("vy", "m/s"), ("ω", "rad/s")]
        .iter()
        .zip(miss)
        .filter(|(_, m)| m.abs() > UNREACHABLE_TOL)
        .map(|((name, unit), m)| format!("{name} {:.4} {unit}", -m))
        .collect();
    format!(
        "α = {:.1}° asks for vx {:.4} m/s, vy {:.4} m/s, ω {:.4} rad/s, and a base with {n_wheels} wheels cannot \
         produce {} of it; a differential drive moves forward or backward (α = 0° or 180°) and turns, never \
         sideways",
        c.alpha_rad.to_degrees(),
        c.v_m_s * co,
        c.v_m_s * s,
        c.omega_rad_s,
        missing.join(", "),
    )
}

/// One leg of a run with several motions: a command held for a while.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Leg {
    /// The command.
    pub command: Command,
    /// How long it is held. s.
    pub duration_s: f64,
}

/// A square of side `side_m` driven the way a differential drive (or UMBmark) drives it: forward along a
/// side at `speed_m_s`, then a quarter turn on the spot at `omega_rad_s` (its sign: which way), four times.
/// It never translates and rotates at once.
pub fn square_legs(side_m: f64, speed_m_s: f64, omega_rad_s: f64) -> Vec<Leg> {
    let side =
        Leg { command: Command { v_m_s: speed_m_s, alpha_rad: 0.0, omega_rad_s: 0.0 }, duration_s: side_m / speed_m_s };
    let turn =
        Leg { command: Command { v_m_s: 0.0, alpha_rad: 0.0, omega_rad_s }, duration_s: 0.5 * PI / omega_rad_s.abs() };
    [side, turn].repeat(4)
}

/// A figure-eight: a full circle to the left at `speed_m_s` and `omega_rad_s`, then one to the right.
pub fn figure_eight_legs(speed_m_s: f64, omega_rad_s: f64) -> Vec<Leg> {
    let circle = 2.0 * PI / omega_rad_s.abs();
    let left = Command { v_m_s: speed_m_s, alpha_rad: 0.0, omega_rad_s: omega_rad_s.abs() };
    let right = Command { omega_rad_s: -omega_rad_s.abs(), ..left };
    vec![Leg { command: left, duration_s: circle }, Leg { command: right, duration_s: circle }]
}
