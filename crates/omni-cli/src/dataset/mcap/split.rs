//! Cutting one recording into several runs at standstills.
//!
//! A standstill is a stretch of consecutive wheel samples whose speeds are all at most
//! [`STILL_WHEEL_RAD_S`], lasting at least the requested time (first to last sample), with motion on both
//! sides (a still start or end of the file is not a cut), while the ground truth stays still: every pose
//! stamped inside the stretch is within [`STILL_TRUTH_M`] and [`STILL_TRUTH_RAD`] of the first one there.
//! The cut is at the middle sample of the standstill, which both neighbouring runs share, so each run starts
//! and ends at rest.

use omni_kin::StampedPose;

/// A wheel is still at or below this speed. rad/s. (0.01 rad/s moves a 5 cm wheel 0.5 mm/s.)
pub const STILL_WHEEL_RAD_S: f64 = 0.01;
/// The ground truth is still while it stays this close to where the standstill began. m.
pub const STILL_TRUTH_M: f64 = 0.005;
/// The ground truth is still while its heading stays this close to where the standstill began. rad.
pub const STILL_TRUTH_RAD: f64 = 0.01;

/// The pieces, as inclusive sample ranges `(first, last)` that tile `0..t_s.len()` (neighbours share the
/// cut sample). One piece when there is no standstill to cut at.
pub(super) fn pieces(
    t_s: &[f64],
    rad_s: &[f64],
    n_wheels: usize,
    truth: &[StampedPose],
    min_standstill_s: f64,
) -> Vec<(usize, usize)> {
    let n = t_s.len();
    let still = |k: usize| rad_s[k * n_wheels..(k + 1) * n_wheels].iter().all(|v| v.abs() <= STILL_WHEEL_RAD_S);
    let mut cuts = Vec::new();
    let mut k = 0;
    while k < n {
        if !still(k) {
            k += 1;
            continue;
        }
        let a = k;
        while k + 1 < n && still(k + 1) {
            k += 1;
        }
        let b = k;
        k += 1;
        if a > 0 && b + 1 < n && t_s[b] - t_s[a] >= min_standstill_s && truth_still(truth, t_s[a], t_s[b]) {
            cuts.push((a + b) / 2);
        }
    }
    let mut out = Vec::with_capacity(cuts.len() + 1);
    let mut first = 0;
    for c in cuts {
        out.push((first, c));
        first = c;
    }
    if n > 0 {
        out.push((first, n - 1));
    }
    out
}

/// The pieces of `--split LENGTH` (`20s`): inclusive sample ranges tiling `0..t_s.len()` (neighbours share
/// the cut sample), each from its first sample to the first at least `length_s` later; what is left at the
/// end joins the last piece when it is shorter than half a length (no stub of a run), else is a piece of its
/// own.
pub(super) fn fixed_pieces(t_s: &[f64], length_s: f64) -> Vec<(usize, usize)> {
    let n = t_s.len();
    let mut out = Vec::new();
    let mut first = 0;
    for k in 1..n {
        if t_s[k] - t_s[first] >= length_s {
            out.push((first, k));
            first = k;
        }
    }
    let tail_s = t_s[n - 1] - t_s[first];
    let (stub, left) = (tail_s < 0.5 * length_s, first < n - 1);
    match out.last_mut() {
        Some(last) if left && stub => last.1 = n - 1,
        Some(_) if !left => {}
        _ => out.push((first, n - 1)),
    }
    out
}

/// Whether the poses stamped in `[from_s, to_s]` stay where the first of them is.
fn truth_still(truth: &[StampedPose], from_s: f64, to_s: f64) -> bool {
    let lo = truth.partition_point(|p| p.t_s < from_s);
    let hi = truth.partition_point(|p| p.t_s <= to_s);
    let inside = &truth[lo..hi.max(lo)];
    let Some(first) = inside.first() else { return true };
    inside.iter().all(|p| {
        (p.pose.x_m - first.pose.x_m).hypot(p.pose.y_m - first.pose.y_m) <= STILL_TRUTH_M
            && (p.pose.theta_rad - first.pose.theta_rad).abs() <= STILL_TRUTH_RAD
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use omni_kin::Pose2;

    #[test]
    fn fixed_pieces_tile_the_recording_without_a_stub() {
        let t: Vec<f64> = (0..=100).map(|k| 0.5 * k as f64).collect(); // 50 s at 2 Hz
        assert_eq!(fixed_pieces(&t, 20.0), [(0, 40), (40, 80), (80, 100)], "10 s left: half a length, its own run");
        assert_eq!(fixed_pieces(&t, 15.0), [(0, 30), (30, 60), (60, 100)], "5 s left: less than half, joined");
        assert_eq!(fixed_pieces(&t, 60.0), [(0, 100)]);
        assert_eq!(fixed_pieces(&t, 50.0), [(0, 100)]);
    }

    fn pose(t_s: f64, x_m: f64) -> StampedPose {
        StampedPose { t_s, pose: Pose2::new(x_m, 0.0, 0.0) }
    }

    #[test]
    fn cuts_in_the_middle_of_long_interior_standstills_only() {
        // 0..=9 still (start: no cut), 10..=19 moving, 20..=49 still (3 s), 50..=59 moving, 60..=64 still (0.4 s),
        // 65..=79 moving, 80..=99 still (end: no cut).
        let moving = |k: usize| (10..20).contains(&k) || (50..60).contains(&k) || (65..80).contains(&k);
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.1).collect();
        let v: Vec<f64> = (0..100).flat_map(|k| [if moving(k) { 1.0 } else { 0.001 }, 0.0]).collect();
        let truth = vec![pose(0.0, 0.0), pose(4.0, 1.0), pose(9.9, 2.0)];
        assert_eq!(pieces(&t, &v, 2, &truth, 1.0), [(0, 34), (34, 99)]);
        assert_eq!(pieces(&t, &v, 2, &truth, 0.3), [(0, 34), (34, 62), (62, 99)]);
        assert_eq!(pieces(&t, &v, 2, &truth, 5.0), [(0, 99)]);
        // Wheels still but the robot moves (pushed, or slipping): no cut.
        let pushed = vec![pose(2.5, 1.0), pose(3.0, 1.1)];
        assert_eq!(pieces(&t, &v, 2, &pushed, 1.0), [(0, 99)]);
    }
}
