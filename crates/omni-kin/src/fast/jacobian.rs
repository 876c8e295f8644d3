//! The forward-mode Jacobian of the errors at the selected poses with respect to the IK matrix entries,
//! one run at a time along the same steps as the kernel (scalar, closed forms, no finite differences).

use super::Lanes;
use super::kernel::{
    C0, C1, C2, C3, C4, LaneState, RESYNC_STEPS, S1, S2, S3, S4, arc_factors, displacement, measured_error, step_lane,
};
use super::prepare::{Group, Increments};
use crate::odometry::Selection;
use crate::pose::{Pose2, PoseError};
use nalgebra::DMatrix;

/// One run's errors at its selected poses and their Jacobian with respect to the IK entries (3 rows per
/// pose: dx, dy, dθ; columns `m11 … m3N`), unscaled.
pub(super) struct LaneRows {
    pub errors: Vec<PoseError>,
    pub jacobian: DMatrix<f64>,
}

/// Forward-mode sums along a walk, per wheel `j` (see [`jacobian_lane`]).
#[derive(Clone, Copy, Debug)]
struct Tangents<const N: usize> {
    /// Σ u_j (p_x, p_y): world displacement per unit body-x displacement, weighted by the increment.
    d: [[f64; 2]; N],
    /// Σ u_j R B'(a) b: the change of the arc's shape with its angle.
    g: [[f64; 2]; N],
    /// Σ u_j (= ∂θ/∂m3j).
    u: [f64; N],
    /// Σ u_j x_after, Σ u_j y_after.
    p: [[f64; 2]; N],
}

/// Derivatives of `sin(a)/a` and `(1 − cos a)/a`.
#[inline(always)]
pub(super) fn arc_factor_slopes(a: f64) -> (f64, f64) {
    let a2 = a * a;
    let ds = a * (2.0 * S1 + a2 * (4.0 * S2 + a2 * (6.0 * S3 + a2 * 8.0 * S4)));
    let dc = C0 + a2 * (3.0 * C1 + a2 * (5.0 * C2 + a2 * (7.0 * C3 + a2 * 9.0 * C4)));
    (ds, dc)
}

/// One step of a lane with its tangents.
#[inline(always)]
fn step_with_tangents<const N: usize, const ARC: bool>(
    st: LaneState,
    t: &mut Tangents<N>,
    m: &[f64],
    u: &[f64],
) -> LaneState {
    let (dx, dy, a) = displacement::<N>(m, u);
    let (sinc, cosc) = arc_factors(a);
    let (sb, cb) = if ARC { (sinc, cosc) } else { (1.0, 0.0) };
    let (px, py) = (st.c * sb - st.s * cb, st.s * sb + st.c * cb);
    let (gx, gy) = if ARC {
        let (ds, dc) = arc_factor_slopes(a);
        let (bx, by) = (ds * dx - dc * dy, dc * dx + ds * dy);
        (st.c * bx - st.s * by, st.s * bx + st.c * by)
    } else {
        (0.0, 0.0)
    };
    let next = step_lane::<ARC>(st, dx, dy, a);
    for (j, &uj) in u.iter().enumerate().take(N) {
        t.d[j][0] += uj * px;
        t.d[j][1] += uj * py;
        t.g[j][0] += uj * gx;
        t.g[j][1] += uj * gy;
        t.u[j] += uj;
        t.p[j][0] += uj * next.x;
        t.p[j][1] += uj * next.y;
    }
    next
}

/// The measured pose's error and derivatives at lane state `st` with tangents `t`.
///
/// With `Θ_j = Σ u_j` the heading's derivative, a step's world displacement `Δ = R(θ) B(a) b` moves by
/// `Θ_j J Δ` through the heading, so `∂x/∂m3j = −Σ_k Θ_jk Δy_k + g_jx = −(y Θ_j − Σ u_j y_after) + g_jx` (and
/// likewise for y); the first two rows act on `b` only: `∂(x, y)/∂m1j = d_j`, `∂(x, y)/∂m2j = J d_j`.
fn tangent_row<const N: usize>(
    st: LaneState,
    t: &Tangents<N>,
    sensor: Pose2,
    truth: &Pose2,
    jac: &mut DMatrix<f64>,
    row: usize,
) -> PoseError {
    // The sensor's lever arm turns with the heading.
    let (lx, ly) = (-st.s * sensor.x_m - st.c * sensor.y_m, st.c * sensor.x_m - st.s * sensor.y_m);
    for j in 0..N {
        jac[(row, j)] = t.d[j][0];
        jac[(row + 1, j)] = t.d[j][1];
        jac[(row, N + j)] = -t.d[j][1];
        jac[(row + 1, N + j)] = t.d[j][0];
        let th = t.u[j];
        jac[(row, 2 * N + j)] = -(st.y * th - t.p[j][1]) + t.g[j][0] + th * lx;
        jac[(row + 1, 2 * N + j)] = (st.x * th - t.p[j][0]) + t.g[j][1] + th * ly;
        jac[(row + 2, 2 * N + j)] = th;
    }
    measured_error(st, sensor, truth)
}

/// The rows of one lane (one run): its queries in slot order, or its end pose.
pub(super) fn lane_rows<const N: usize, const ARC: bool>(
    g: &Group,
    inc: &Increments<'_>,
    lane: usize,
    m: &[f64],
    sensor: Pose2,
    selection: Selection,
) -> LaneRows {
    let body = g.start[lane].compose(&sensor.inverse());
    let (s, c) = body.theta_rad.sin_cos();
    let mut st = LaneState { x: body.x_m, y: body.y_m, th: body.theta_rad, c, s };
    let mut t = Tangents::<N> { d: [[0.0; 2]; N], g: [[0.0; 2]; N], u: [0.0; N], p: [[0.0; 2]; N] };
    let mine: Vec<(usize, usize, usize)> =
        (g.queries.iter().enumerate()).filter(|(_, q)| q.lane == lane).map(|(qi, q)| (qi, q.step, q.slot)).collect();
    let first_slot = mine.iter().map(|&(_, _, slot)| slot).min().unwrap_or(0);
    let poses = if selection == Selection::End { 1 } else { mine.len() };
    let mut out = LaneRows { errors: vec![PoseError::default(); poses], jacobian: DMatrix::zeros(3 * poses, 3 * N) };
    let mut next = 0;
    let mut u = [0.0; N];
    let increments: &[Lanes] = inc.u;
    for k in 0..=g.steps {
        while next < mine.len() && mine[next].1 == k {
            let (qi, _, slot) = mine[next];
            let mut tq = t;
            let sq = step_with_tangents::<N, ARC>(st, &mut tq, m, &inc.query_u[qi * N..(qi + 1) * N]);
            let r = slot - first_slot;
            out.errors[r] = tangent_row(sq, &tq, sensor, &g.queries[qi].truth, &mut out.jacobian, 3 * r);
            next += 1;
        }
        if k == g.steps {
            break;
        }
        for (j, v) in u.iter_mut().enumerate() {
            *v = increments[k * N + j][lane];
        }
        st = step_with_tangents::<N, ARC>(st, &mut t, m, &u);
        if k % RESYNC_STEPS == RESYNC_STEPS - 1 {
            (st.s, st.c) = st.th.sin_cos();
        }
    }
    if selection == Selection::End {
        out.errors[0] = tangent_row(st, &t, sensor, &g.end[lane], &mut out.jacobian, 0);
    }
    out
}
