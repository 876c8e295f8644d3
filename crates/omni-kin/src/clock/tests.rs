//! Tests of the clock estimate on a simulated omni base.

use super::*;
use crate::Pose2;

/// A three-wheel omni base driving a smooth twist: wheel samples as interval means at 100 Hz, truth at
/// 125 Hz on a clock `offset` behind.
fn recording(offset: f64) -> (Vec<f64>, Vec<f64>, Vec<StampedPose>) {
    let twist = |t: f64| [0.25 * (0.7 * t).sin(), 0.18 * (1.1 * t + 1.0).sin(), 0.9 * (0.45 * t + 0.3).sin()];
    let angles = [90f64, 210.0, 330.0].map(f64::to_radians);
    let dt = 1e-4;
    let (mut t, mut pose, mut wheel) = (-0.1, [0.0f64, 0.0, 0.3], [0.0f64; 3]);
    let (mut wheel_t, mut rates, mut truth) = (Vec::new(), Vec::new(), Vec::new());
    let mut last_wheel = [0.0; 3];
    let mut step = 0usize;
    while t < 30.0 {
        let [vx, vy, wz] = twist(t + 0.5 * dt);
        let (s, c) = pose[2].sin_cos();
        pose = [pose[0] + (c * vx - s * vy) * dt, pose[1] + (s * vx + c * vy) * dt, pose[2] + wz * dt];
        for (w, b) in angles.iter().enumerate() {
            wheel[w] += (-b.sin() * vx + b.cos() * vy + 0.2 * wz) / 0.05 * dt;
        }
        t += dt;
        step += 1;
        if step.is_multiple_of(100) && t > 0.0 {
            wheel_t.push(t);
            rates.extend((0..3).map(|w| (wheel[w] - last_wheel[w]) / 0.01));
        }
        if step.is_multiple_of(100) {
            last_wheel = wheel;
        }
        if step.is_multiple_of(80) {
            truth.push(StampedPose { t_s: t - offset, pose: Pose2 { x_m: pose[0], y_m: pose[1], theta_rad: pose[2] } });
        }
    }
    (wheel_t, rates, truth)
}

#[test]
fn recovers_offsets_of_seconds_and_of_milliseconds() {
    for offset in [3.217, 0.05, -1.3] {
        let (t, rates, truth) = recording(offset);
        let a = align_clocks(&t, &rates, 3, &truth).unwrap();
        assert!((a.offset_s - offset).abs() < 2e-4, "{offset}: {a:?}");
        assert!(a.std_error_s > 0.0 && a.std_error_s < 1e-3, "{a:?}");
        assert!(a.r_squared > 0.999, "{a:?}");
    }
}

#[test]
fn gaps_in_the_truth_are_left_out() {
    // The marker lost for 1.5 s of every 5 s, and a stretch 100 s later that no wheel data covers (a
    // take spanning several recordings): before gaps were left out, the interpolation across the long
    // one matched the wheels better than the motion did, and the estimate failed.
    let offset = 0.8;
    let (t, rates, truth) = recording(offset);
    let mut gappy: Vec<StampedPose> = truth.iter().copied().filter(|p| (p.t_s + offset) % 5.0 < 3.5).collect();
    // Later, the robot parked where it stopped (the next recording not yet started).
    let last = truth[truth.len() - 1];
    let later = (0..3000).map(|k| StampedPose { t_s: last.t_s + 100.0 + k as f64 * 0.008, pose: last.pose });
    gappy.extend(later);
    let a = align_clocks(&t, &rates, 3, &gappy).unwrap();
    assert!((a.offset_s - offset).abs() < 2e-4, "{a:?}");
    assert!(a.r_squared > 0.999, "{a:?}");
    let poses = Poses::new(&gappy);
    assert!(poses.gaps.len() >= 6, "{:?}", poses.gaps);
    assert!(!poses.measured(40.0, 40.1) && poses.measured(0.5, 0.6));
}

#[test]
fn refuses_a_truth_of_another_motion() {
    let (t, rates, _) = recording(0.0);
    let still: Vec<StampedPose> = (0..3000)
        .map(|k| StampedPose {
            t_s: k as f64 * 0.01,
            pose: Pose2 { x_m: (k as f64 * 0.37).sin(), y_m: 0.0, theta_rad: 0.0 },
        })
        .collect();
    assert!(matches!(align_clocks(&t, &rates, 3, &still), Err(ClockError::NoMatch { .. })));
    let short = &still[..100];
    assert!(matches!(align_clocks(&t, &rates, 3, short), Err(ClockError::NoOverlap { .. })));
}
