//! Measured end poses against what the wheels say. A table typed by hand can hold millimetres under `x_m`,
//! degrees under `yaw_rad` or radians under `yaw_deg`; the wheels, through the robot description's design,
//! tell the distance within a factor of 2 (a calibration corrects per cents) and the turn, so a row far
//! from them is refused, naming the line, the column and the unit its value fits.

use crate::dataset::end_poses::EndPose;
use omni_kin::pose::wrap_angle;
use omni_kin::{IkMatrix, Run};

/// The wheels tell the distance from start to end within this factor.
const DISTANCE_FACTOR: f64 = 2.0;
/// … when the end is at least this far from the start by the wheels, and the run is no loop (the end at
/// least this fraction of the path from the start). m, and a fraction.
const MIN_DISTANCE_M: f64 = 0.2;
const MIN_STRAIGHTNESS: f64 = 0.25;
/// The wheels tell the turn within this much, plus [`TURN_SLACK`] of the turning done. rad.
const TURN_TOLERANCE_RAD: f64 = 0.35;
const TURN_SLACK: f64 = 0.15;

/// Where the wheels take a run through a design: the end pose, and the path and turning on the way.
#[derive(Clone, Copy, Debug)]
struct DeadReckoning {
    x_m: f64,
    y_m: f64,
    /// The heading at the end, unwrapped. rad.
    theta_rad: f64,
    path_m: f64,
    turning_rad: f64,
}

fn dead_reckon(run: &Run, ik: &IkMatrix) -> DeadReckoning {
    let t = run.wheel_t_s();
    let mut d = DeadReckoning { x_m: 0.0, y_m: 0.0, theta_rad: 0.0, path_m: 0.0, turning_rad: 0.0 };
    for k in 1..t.len() {
        let dt = t[k] - t[k - 1];
        let v = ik.twist(run.wheel_sample(k));
        let (s, c) = d.theta_rad.sin_cos();
        d.x_m += (v.vx_m_s * c - v.vy_m_s * s) * dt;
        d.y_m += (v.vx_m_s * s + v.vy_m_s * c) * dt;
        d.theta_rad += v.omega_rad_s * dt;
        d.path_m += v.vx_m_s.hypot(v.vy_m_s) * dt;
        d.turning_rad += v.omega_rad_s.abs() * dt;
    }
    d
}

/// What is wrong with `measured`'s row for `run` against its wheels through `ik`, if anything: the text
/// after `file: line N, column C: `, and the column.
pub(super) fn check(run: &Run, measured: &EndPose, ik: &IkMatrix) -> Option<(String, String)> {
    if run.n_wheels() != ik.n_wheels() {
        return None;
    }
    let w = dead_reckon(run, ik);
    let p = &measured.pose;
    let c = &measured.columns;
    let (wheels_m, measured_m) = (w.x_m.hypot(w.y_m), p.x_m.hypot(p.y_m));
    let as_unit = |m: f64| m / c.metres_per_unit;
    let told = wheels_m >= MIN_DISTANCE_M && wheels_m >= MIN_STRAIGHTNESS * w.path_m;
    let beyond_path = measured_m > DISTANCE_FACTOR * w.path_m + 0.1;
    let ratio = measured_m / wheels_m;
    if beyond_path || (told && !(1.0 / DISTANCE_FACTOR..=DISTANCE_FACTOR).contains(&ratio)) {
        let fits = ["m", "cm", "mm"]
            .into_iter()
            .zip([1.0, 0.01, 0.001])
            .find(|(_, f)| {
                let m = as_unit(measured_m) * f;
                (m - wheels_m).abs() <= 0.5 * wheels_m.max(0.05)
            })
            .map_or_else(String::new, |(u, _)| format!(" The values fit {u}: name the columns x_{u} and y_{u}."));
        return Some((
            c.length.clone(),
            format!(
                "run {}: the end is {} {} ({measured_m:.3} m) from the start, but the wheels, through the design, \
                 put it {wheels_m:.3} m from it along a {:.3} m path: beyond the factor of {DISTANCE_FACTOR} the \
                 wheels tell it within. Are the lengths in another unit than the column's?{fits}",
                measured.run,
                fmt(as_unit(measured_m)),
                unit_of(&c.length),
                w.path_m
            ),
        ));
    }
    let tolerance = TURN_TOLERANCE_RAD + TURN_SLACK * w.turning_rad;
    let off = wrap_angle(p.theta_rad - w.theta_rad).abs();
    let too_much = p.theta_rad.abs() > w.theta_rad.abs().max(w.turning_rad) + std::f64::consts::PI;
    if off > tolerance || too_much {
        let degrees = c.yaw.ends_with("_deg");
        let typed = if degrees { p.theta_rad.to_degrees() } else { p.theta_rad };
        // The value as typed, read in the other unit.
        let (other_name, other_rad) = if degrees { ("yaw_rad", typed) } else { ("yaw_deg", typed.to_radians()) };
        let other_fits = wrap_angle(other_rad - w.theta_rad).abs() <= tolerance
            && other_rad.abs() <= w.theta_rad.abs().max(w.turning_rad) + std::f64::consts::PI;
        let fits = if other_fits {
            format!(" As {other_name}, {} would fit: name the column {other_name}.", fmt(typed))
        } else {
            String::new()
        };
        return Some((
            c.yaw.clone(),
            format!(
                "run {}: the heading turned {}, but the wheels, through the design, turned it {:.1}° (they tell it \
                 within {:.0}°).{fits}",
                measured.run,
                if degrees {
                    format!("{}°", fmt(typed))
                } else {
                    format!("{} rad ({:.1}°)", fmt(typed), p.theta_rad.to_degrees())
                },
                w.theta_rad.to_degrees(),
                tolerance.to_degrees()
            ),
        ));
    }
    None
}

/// The unit of a length column (`x_mm` → `mm`).
fn unit_of(column: &str) -> &str {
    column.rsplit('_').next().unwrap_or(column)
}

/// A value as typed: up to 4 decimals, no trailing zeros.
fn fmt(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}
