//! References that measure positions only: UWB, GNSS, a tracker without a heading
//! ([`crate::Run::truth_position_only`]).
//!
//! Such a run has no heading to start the odometry from and none to compare with. Its errors are therefore
//! taken after the one rotation about the run's start position that best lays the predicted positions on
//! the measured ones (the start heading, fitted per run in closed form: the 2-D Procrustes rotation), and
//! its heading errors are 0. For a model at `p` the aligned errors are `e'ⱼ = R(δ) aⱼ − bⱼ`, with
//! `aⱼ = predictedⱼ − start` and `bⱼ = measuredⱼ − start` at the selected poses, and
//! `δ = atan2(Σ aⱼ × bⱼ, Σ aⱼ · bⱼ)`.
//!
//! Jacobians follow variable projection (Golub and Pereyra, with Kaufman's simplification): the position
//! rows are rotated by `δ` and the direction in which `δ` itself moves the residuals, `gⱼ = R(δ + π/2) aⱼ`,
//! is projected out of every column. The cost's gradient from it is exact everywhere, and the Jacobian is
//! exact where the aligned residuals vanish, so Levenberg–Marquardt steps, standard errors and
//! identifiability all account for the free start heading (a rotation in place, which moves no position,
//! shows as undetermined).

use crate::pose::{PoseError, StampedPose};
use nalgebra::DMatrix;

/// Poses a reference must have, at least, before a heading that never changes says it measures none.
pub const MIN_POSES_FOR_CONSTANT_HEADING: usize = 10;
/// Distance a reference must span, at least, before a heading that never changes says it measures none. m.
pub const MIN_SPAN_FOR_CONSTANT_HEADING_M: f64 = 0.1;

/// Whether a reference's headings (rad) are all exactly the first while its positions (m) span more than
/// [`MIN_SPAN_FOR_CONSTANT_HEADING_M`] over at least [`MIN_POSES_FOR_CONSTANT_HEADING`] poses: a tracker, UWB
/// or GNSS that writes a fixed orientation (an identity quaternion) beside its positions. A measured heading
/// is never bit-for-bit constant while the robot moves (its noise alone changes it).
pub fn heading_never_changes(poses: impl Iterator<Item = (f64, f64, f64)> + Clone) -> bool {
    let mut first = None;
    let (mut n, mut span) = (0usize, 0.0f64);
    for (x, y, theta) in poses {
        let (x0, y0, t0) = *first.get_or_insert((x, y, theta));
        if theta != t0 {
            return false;
        }
        span = span.max((x - x0).hypot(y - y0));
        n += 1;
    }
    n >= MIN_POSES_FOR_CONSTANT_HEADING && span > MIN_SPAN_FOR_CONSTANT_HEADING_M
}

/// The start rotation that best lays `errors` (at the ground-truth poses `idx` of `truth`) on the measured
/// positions, and the vectors `a` (predicted positions less the start) it rotates. rad.
fn rotation(truth: &[StampedPose], idx: &[usize], errors: &[PoseError]) -> (f64, Vec<[f64; 2]>) {
    let start = truth[0].pose;
    let (mut cross, mut dot) = (0.0, 0.0);
    let a: Vec<[f64; 2]> = idx
        .iter()
        .zip(errors)
        .map(|(&i, e)| {
            let t = truth[i].pose;
            let b = [t.x_m - start.x_m, t.y_m - start.y_m];
            let a = [b[0] + e.dx_m, b[1] + e.dy_m];
            cross += a[0] * b[1] - a[1] * b[0];
            dot += a[0] * b[0] + a[1] * b[1];
            a
        })
        .collect();
    let delta = if cross == 0.0 && dot == 0.0 { 0.0 } else { cross.atan2(dot) };
    (delta, a)
}

/// Aligns one run's `errors` at the ground-truth poses `idx` of `truth` (and its `end` error, at the last
/// pose) by the best start rotation; heading errors become 0. Returns the rotation (rad) and the rotated
/// vectors `R(δ) a` (for [`project_jacobian`]).
pub fn align(
    truth: &[StampedPose],
    idx: &[usize],
    errors: &mut [PoseError],
    end: Option<&mut PoseError>,
) -> (f64, Vec<[f64; 2]>) {
    let (delta, a) = rotation(truth, idx, errors);
    let (s, c) = delta.sin_cos();
    let start = truth[0].pose;
    let rotate = |v: [f64; 2]| [c * v[0] - s * v[1], s * v[0] + c * v[1]];
    let mut ra = Vec::with_capacity(a.len());
    for ((&i, e), a) in idx.iter().zip(errors.iter_mut()).zip(&a) {
        let t = truth[i].pose;
        let r = rotate(*a);
        *e = PoseError { dx_m: r[0] - (t.x_m - start.x_m), dy_m: r[1] - (t.y_m - start.y_m), dtheta_rad: 0.0 };
        ra.push(r);
    }
    if let Some(end) = end {
        let t = truth[truth.len() - 1].pose;
        let b = [t.x_m - start.x_m, t.y_m - start.y_m];
        let r = rotate([b[0] + end.dx_m, b[1] + end.dy_m]);
        *end = PoseError { dx_m: r[0] - b[0], dy_m: r[1] - b[1], dtheta_rad: 0.0 };
    }
    (delta, ra)
}

/// The Jacobian of a run's aligned residuals from that of its raw ones (rows `3j, 3j+1, 3j+2` for pose `j`'s
/// x, y and heading, any columns): the position rows rotated by `delta`, the heading rows 0, then the
/// start rotation's direction `g` (from the rotated vectors `ra` of [`align`]) projected out of every
/// column.
pub fn project_jacobian(jacobian: &mut DMatrix<f64>, delta: f64, ra: &[[f64; 2]]) {
    let (s, c) = delta.sin_cos();
    // d(R(δ) a)/dδ = R(δ + π/2) a = (−(R a)_y, (R a)_x).
    let g: Vec<[f64; 2]> = ra.iter().map(|v| [-v[1], v[0]]).collect();
    let gg: f64 = g.iter().map(|v| v[0] * v[0] + v[1] * v[1]).sum();
    for mut column in jacobian.column_iter_mut() {
        let mut dot = 0.0;
        for (j, gj) in g.iter().enumerate() {
            let (x, y) = (column[3 * j], column[3 * j + 1]);
            let (rx, ry) = (c * x - s * y, s * x + c * y);
            column[3 * j] = rx;
            column[3 * j + 1] = ry;
            column[3 * j + 2] = 0.0;
            dot += gj[0] * rx + gj[1] * ry;
        }
        if gg > 0.0 {
            let f = dot / gg;
            for (j, gj) in g.iter().enumerate() {
                column[3 * j] -= f * gj[0];
                column[3 * j + 1] -= f * gj[1];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::Pose2;

    fn truth(points: &[[f64; 2]]) -> Vec<StampedPose> {
        points
            .iter()
            .enumerate()
            .map(|(k, p)| StampedPose { t_s: k as f64, pose: Pose2::new(p[0], p[1], 0.0) })
            .collect()
    }

    #[test]
    fn a_heading_that_never_changes_while_the_robot_moves_is_none() {
        let line = |theta: fn(usize) -> f64| (0..20).map(move |k| (0.05 * k as f64, 0.0, theta(k)));
        assert!(heading_never_changes(line(|_| 0.0)));
        assert!(!heading_never_changes(line(|k| if k == 7 { 1e-12 } else { 0.0 })), "noise is a measurement");
        assert!(!heading_never_changes((0..20).map(|_| (0.0, 0.0, 0.3))), "standing still says nothing");
        assert!(!heading_never_changes(line(|_| 0.0).take(5)), "too few poses");
    }

    /// A predicted path that is the measured one turned by 0.3 rad about the start aligns to zero error.
    #[test]
    fn a_path_turned_about_its_start_aligns_exactly() {
        let pts = [[1.0, 2.0], [2.0, 2.5], [3.0, 1.0], [2.5, -1.0]];
        let t = truth(&pts);
        let (s, c) = 0.3f64.sin_cos();
        let idx = [1, 2, 3];
        let mut e: Vec<PoseError> = idx
            .iter()
            .map(|&i| {
                let b = [pts[i][0] - 1.0, pts[i][1] - 2.0];
                let a = [c * b[0] - s * b[1], s * b[0] + c * b[1]];
                PoseError { dx_m: a[0] - b[0], dy_m: a[1] - b[1], dtheta_rad: 0.7 }
            })
            .collect();
        let mut end = e[2];
        let (delta, _) = align(&t, &idx, &mut e, Some(&mut end));
        assert!((delta + 0.3).abs() < 1e-12, "{delta}");
        for e in e.iter().chain([&end]) {
            assert!(e.dx_m.abs() < 1e-12 && e.dy_m.abs() < 1e-12 && e.dtheta_rad == 0.0, "{e:?}");
        }
    }

    /// Predicted errors at poses 1..=3 of `PTS` for parameters `p`: the measured path scaled by `1 + p0`,
    /// its y shifted by `p1 j²`, turned by 0.2 rad about the start.
    const PTS: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.2], [1.8, 0.9], [2.1, 2.0]];
    const IDX: [usize; 3] = [1, 2, 3];

    fn predict(p: [f64; 2]) -> Vec<PoseError> {
        let (s, c) = 0.2f64.sin_cos();
        IDX.iter()
            .map(|&i| {
                let q = [PTS[i][0] * (1.0 + p[0]), PTS[i][1] * (1.0 + p[0]) + p[1] * (i * i) as f64];
                let r = [c * q[0] - s * q[1], s * q[0] + c * q[1]];
                PoseError { dx_m: r[0] - PTS[i][0], dy_m: r[1] - PTS[i][1], dtheta_rad: 0.1 }
            })
            .collect()
    }

    /// The raw residuals' Jacobian by finite differences (rows x, y, heading per pose), and the aligned
    /// residuals at `p` and at each `p + h eₖ`.
    fn raw_jacobian_and_aligned(p: [f64; 2], h: f64) -> (DMatrix<f64>, Vec<PoseError>, Vec<Vec<PoseError>>) {
        let t = truth(&PTS);
        let raw = predict(p);
        let mut jac = DMatrix::zeros(9, 2);
        let mut moved_aligned = Vec::new();
        for k in 0..2 {
            let mut q = p;
            q[k] += h;
            let moved = predict(q);
            for (j, (a, b)) in moved.iter().zip(&raw).enumerate() {
                jac[(3 * j, k)] = (a.dx_m - b.dx_m) / h;
                jac[(3 * j + 1, k)] = (a.dy_m - b.dy_m) / h;
                jac[(3 * j + 2, k)] = (a.dtheta_rad - b.dtheta_rad) / h;
            }
            let mut m = moved;
            align(&t, &IDX, &mut m, None);
            moved_aligned.push(m);
        }
        let mut e = raw;
        let (delta, ra) = align(&t, &IDX, &mut e, None);
        project_jacobian(&mut jac, delta, &ra);
        (jac, e, moved_aligned)
    }

    /// Where the aligned residuals vanish, the projected Jacobian is the finite-difference Jacobian of the
    /// aligned residuals (δ re-fitted at each step).
    #[test]
    fn the_projected_jacobian_is_that_of_the_aligned_residuals_at_a_fit() {
        let h = 1e-7;
        let (jac, e, moved) = raw_jacobian_and_aligned([0.0, 0.0], h);
        for k in 0..2 {
            for j in 0..3 {
                let fd = [(moved[k][j].dx_m - e[j].dx_m) / h, (moved[k][j].dy_m - e[j].dy_m) / h];
                assert!((fd[0] - jac[(3 * j, k)]).abs() < 1e-5, "{k} {j}: {fd:?} vs {}", jac[(3 * j, k)]);
                assert!((fd[1] - jac[(3 * j + 1, k)]).abs() < 1e-5, "{k} {j}: {fd:?} vs {}", jac[(3 * j + 1, k)]);
                assert_eq!(jac[(3 * j + 2, k)], 0.0);
            }
        }
    }

    /// Away from a fit, the cost's gradient from the projected Jacobian is the finite-difference gradient of
    /// the aligned cost.
    #[test]
    fn the_projected_jacobian_gives_the_aligned_costs_gradient() {
        let h = 1e-7;
        let (jac, e, moved) = raw_jacobian_and_aligned([0.05, 0.03], h);
        let half_sq = |e: &[PoseError]| 0.5 * e.iter().map(|e| e.dx_m * e.dx_m + e.dy_m * e.dy_m).sum::<f64>();
        let r: Vec<f64> = e.iter().flat_map(|e| [e.dx_m, e.dy_m, e.dtheta_rad]).collect();
        for k in 0..2 {
            let analytic: f64 = (0..9).map(|i| jac[(i, k)] * r[i]).sum();
            let fd = (half_sq(&moved[k]) - half_sq(&e)) / h;
            assert!((analytic - fd).abs() < 1e-5 * (1.0 + fd.abs()), "{k}: {analytic} vs {fd}");
            assert!(fd.abs() > 1e-3, "the test point must be away from a fit: {fd}");
        }
    }
}
