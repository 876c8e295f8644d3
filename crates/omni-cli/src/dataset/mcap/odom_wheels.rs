//! Wheel speeds recovered from the robot's own odometry, for a recording that has no JointState: only the
//! base controller's `nav_msgs/msg/Odometry` (frame `odom`), as many robots log it.
//!
//! The controller integrated its wheel increments through its declared parameters (the design). Between
//! two odometry poses the body twist is the one that, held constant, moves the first pose onto the second:
//! `ω = Δθ/Δt` and `v = R(−(θ₀ + Δθ/2)) Δp / (Δt · sinc(Δθ/2))` (exact for a constant twist, as a
//! controller's exact-arc or midpoint integration makes it). The design's forward kinematics turn that twist
//! back into the wheel speeds the controller saw (rad/s). The twist fields of the messages are not used:
//! controllers smooth them (`diff_drive_controller` reports a rolling mean), the poses they do not.
//!
//! What a fit can reach from these speeds: with as many independent wheel speeds as the twist has degrees
//! of freedom (two wheels of a differential drive, three omni wheels) the recovered speeds are the measured
//! ones, and every parameter (both radii and the separation; every entry of a 3 × 3 matrix) is within
//! reach. With more wheels than that (four mecanum or omni wheels), the speeds are the measured ones
//! projected onto what the design can produce: a fit reaches a 3 × 3 correction of the design, never one
//! wheel's own radius. The first sample takes the second's speeds (as speeds from positions do).

use super::joint_state::Wheels;
use super::poses::PoseSeries;
use omni_kin::pose::wrap_angle;

/// Wheel speeds (`samples × wheels`, rad/s) at the odometry's stamps, from its poses through the design's
/// forward kinematics `wheels_from_twist` (a row per wheel: rad/s per vx, vy m/s and ω rad/s in the body
/// frame). Errors name the message: fewer than two poses.
pub(super) fn wheels_from_odometry(
    odometry: &PoseSeries,
    wheels_from_twist: &[[f64; 3]],
) -> Result<Wheels, (usize, String)> {
    let n = odometry.t_ns.len();
    if n < 2 {
        return Err((0, format!("has {n} pose(s): wheel speeds need two or more")));
    }
    let w = wheels_from_twist.len();
    let mut rad_s = vec![0.0; n * w];
    for k in 1..n {
        let dt_s = (odometry.t_ns[k] - odometry.t_ns[k - 1]) as f64 * 1e-9;
        let twist = body_twist(odometry.xy_yaw[k - 1], odometry.xy_yaw[k], dt_s);
        for (speed, row) in rad_s[k * w..(k + 1) * w].iter_mut().zip(wheels_from_twist) {
            *speed = row[0] * twist[0] + row[1] * twist[1] + row[2] * twist[2];
        }
    }
    rad_s.copy_within(w..2 * w, 0);
    Ok(Wheels { t_ns: odometry.t_ns.clone(), rad_s, position: None, differentiated: None, notes: Vec::new() })
}

/// The constant body twist (vx, vy m/s, ω rad/s) that moves pose `a` onto pose `b` (`[x_m, y_m, yaw_rad]`)
/// in `dt_s` seconds.
fn body_twist(a: [f64; 3], b: [f64; 3], dt_s: f64) -> [f64; 3] {
    let d_theta = wrap_angle(b[2] - a[2]);
    let half = d_theta / 2.0;
    let sinc = if half.abs() < 1e-9 { 1.0 } else { half.sin() / half };
    let (s, c) = (a[2] + half).sin_cos();
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let scale = 1.0 / (dt_s * sinc);
    [(c * dx + s * dy) * scale, (-s * dx + c * dy) * scale, d_theta / dt_s]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_twist_is_recovered_exactly_from_its_arc() {
        // vx 0.4, vy −0.1 m/s, ω 1.5 rad/s held for 0.2 s from heading 2.9 rad (the arc crosses ±π).
        let (vx, vy, w, dt, th0) = (0.4, -0.1, 1.5, 0.2, 2.9_f64);
        let arc = |t: f64| {
            // ∫ R(th0 + w τ) (vx, vy) dτ from 0 to t.
            let (s0, c0, s1, c1) = (th0.sin(), th0.cos(), (th0 + w * t).sin(), (th0 + w * t).cos());
            let x = (vx * (s1 - s0) + vy * (c1 - c0)) / w;
            let y = (vx * (c0 - c1) + vy * (s1 - s0)) / w;
            [x, y, wrap_angle(th0 + w * t)]
        };
        let got = body_twist(arc(0.0), arc(dt), dt);
        for (g, want) in got.iter().zip([vx, vy, w]) {
            assert!((g - want).abs() < 1e-12, "{got:?}");
        }
    }

    #[test]
    fn wheel_speeds_are_the_design_forward_kinematics_of_the_twist() {
        // A differential drive (r 0.05 m, separation 0.3 m) turning on the spot at 1 rad/s, then moving
        // 0.05 m along the world's y at heading 0.1 rad (a slide, for the numbers: the vy column is zero).
        let fwd = [[20.0, 0.0, -3.0], [20.0, 0.0, 3.0]];
        let odom = PoseSeries {
            t_ns: vec![0, 100_000_000, 200_000_000],
            xy_yaw: vec![[1.0, 2.0, 0.0], [1.0, 2.0, 0.1], [1.0, 2.05, 0.1]],
            ..Default::default()
        };
        let wheels = wheels_from_odometry(&odom, &fwd).unwrap();
        let vx = 0.05 * 0.1_f64.sin() / 0.1;
        let expected = [-3.0, 3.0, -3.0, 3.0, 20.0 * vx, 20.0 * vx];
        for (g, e) in wheels.rad_s.iter().zip(expected) {
            assert!((g - e).abs() < 1e-9, "{:?}", wheels.rad_s);
        }
        let one = PoseSeries { t_ns: vec![0], xy_yaw: vec![[0.0; 3]], ..Default::default() };
        assert_eq!(
            wheels_from_odometry(&one, &fwd).unwrap_err(),
            (0, "has 1 pose(s): wheel speeds need two or more".into())
        );
    }
}
