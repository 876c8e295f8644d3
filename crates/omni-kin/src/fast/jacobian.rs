//! The forward-mode Jacobian of the errors at the selected poses with respect to the IK matrix entries,
//! one run at a time along the same steps as the kernel (scalar, closed forms, no finite differences).

use super::Lanes;
use super::kernel::{
    C0, C1, C2, C3, C4, LaneState, RESYNC_STEPS, S1, S2, S3, S4, arc_factors, displacement, measured_error, step_lane,
};
use super::prepare::{Group, GroupParts, Increments};
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

/// What one step adds to the tangent sums per unit of an increment's weight: `p`, `g` and the position
/// after the step (see [`Tangents`]).
#[derive(Clone, Copy, Debug, Default)]
struct StepWeights {
    p: [f64; 2],
    g: [f64; 2],
    next: [f64; 2],
}

/// The tangent sums of increment directions other than the wheels' own: the parts of an affine wheel-stage
/// effect (one per part, each weighted by the part's increments instead of a wheel's).
#[derive(Clone, Debug, Default)]
struct PartTangents {
    d: Vec<[f64; 2]>,
    g: Vec<[f64; 2]>,
    u: Vec<f64>,
    p: Vec<[f64; 2]>,
}

impl PartTangents {
    fn new(n: usize) -> Self {
        Self { d: vec![[0.0; 2]; n], g: vec![[0.0; 2]; n], u: vec![0.0; n], p: vec![[0.0; 2]; n] }
    }

    /// Adds one step (`w`) with part increments `du` (one per part).
    #[inline(always)]
    fn add(&mut self, w: &StepWeights, du: impl Iterator<Item = f64>) {
        for (i, v) in du.enumerate() {
            self.d[i][0] += v * w.p[0];
            self.d[i][1] += v * w.p[1];
            self.g[i][0] += v * w.g[0];
            self.g[i][1] += v * w.g[1];
            self.u[i] += v;
            self.p[i][0] += v * w.next[0];
            self.p[i][1] += v * w.next[1];
        }
    }
}

/// One step of a lane with its tangents.
#[inline(always)]
fn step_with_tangents<const N: usize, const ARC: bool>(
    st: LaneState,
    t: &mut Tangents<N>,
    m: &[f64],
    u: &[f64],
) -> (LaneState, StepWeights) {
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
    (next, StepWeights { p: [px, py], g: [gx, gy], next: [next.x, next.y] })
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

/// Adds the columns of the affine wheel-stage effect's parameters (after the IK entries) to the rows at
/// `row`: each part is an increment direction on one wheel, `∂/∂θ = Σ_r m_rj ∂/∂m_rj` with the part's sums.
fn part_rows<const N: usize>(
    st: LaneState,
    t: &PartTangents,
    keys: &[(usize, usize)],
    m: &[f64],
    sensor: Pose2,
    jac: &mut DMatrix<f64>,
    row: usize,
) {
    let (lx, ly) = (-st.s * sensor.x_m - st.c * sensor.y_m, st.c * sensor.x_m - st.s * sensor.y_m);
    for (i, &(param, j)) in keys.iter().enumerate() {
        let (d, g, u, p) = (t.d[i], t.g[i], t.u[i], t.p[i]);
        let (m1, m2, m3) = (m[j], m[N + j], m[2 * N + j]);
        let col = 3 * N + param;
        jac[(row, col)] += m1 * d[0] - m2 * d[1] + m3 * (-(st.y * u - p[1]) + g[0] + u * lx);
        jac[(row + 1, col)] += m1 * d[1] + m2 * d[0] + m3 * ((st.x * u - p[0]) + g[1] + u * ly);
        jac[(row + 2, col)] += m3 * u;
    }
}

/// The parts of an affine wheel-stage effect a lane's rows also differentiate: the group's parts and the
/// effect's parameter count.
pub(super) type PartColumns<'a> = Option<(&'a GroupParts, usize)>;

/// The rows of one lane (one run): its queries in slot order, or its end pose.
pub(super) fn lane_rows<const N: usize, const ARC: bool>(
    g: &Group,
    inc: &Increments<'_>,
    lane: usize,
    m: &[f64],
    sensor: Pose2,
    selection: Selection,
    parts: PartColumns<'_>,
) -> LaneRows {
    let body = g.start[lane].compose(&sensor.inverse());
    let (s, c) = body.theta_rad.sin_cos();
    let mut st = LaneState { x: body.x_m, y: body.y_m, th: body.theta_rad, c, s };
    let mut t = Tangents::<N> { d: [[0.0; 2]; N], g: [[0.0; 2]; N], u: [0.0; N], p: [[0.0; 2]; N] };
    let mine: Vec<(usize, usize, usize)> =
        (g.queries.iter().enumerate()).filter(|(_, q)| q.lane == lane).map(|(qi, q)| (qi, q.step, q.slot)).collect();
    let first_slot = mine.iter().map(|&(_, _, slot)| slot).min().unwrap_or(0);
    let poses = if selection == Selection::End { 1 } else { mine.len() };
    let (keys, np, n_params) = parts.map_or((&[][..], 0, 0), |(p, n)| (p.keys.as_slice(), p.keys.len(), n));
    let mut pt = PartTangents::new(np);
    let mut pq = PartTangents::new(np);
    let cols = 3 * N + n_params;
    let mut out = LaneRows { errors: vec![PoseError::default(); poses], jacobian: DMatrix::zeros(3 * poses, cols) };
    let mut next = 0;
    let mut u = [0.0; N];
    let increments: &[Lanes] = inc.u;
    // The kernel's re-anchoring: not past the lane's last step.
    let lane_steps = g.plans()[lane].steps;
    for k in 0..=g.steps {
        while next < mine.len() && mine[next].1 == k {
            let (qi, _, slot) = mine[next];
            let mut tq = t;
            let (sq, w) = step_with_tangents::<N, ARC>(st, &mut tq, m, &inc.query_u[qi * N..(qi + 1) * N]);
            let r = slot - first_slot;
            out.errors[r] = tangent_row(sq, &tq, sensor, &g.queries[qi].truth, &mut out.jacobian, 3 * r);
            if let Some((p, _)) = parts {
                pq.clone_from(&pt);
                pq.add(&w, p.query_u[qi * np..(qi + 1) * np].iter().copied());
                part_rows::<N>(sq, &pq, keys, m, sensor, &mut out.jacobian, 3 * r);
            }
            next += 1;
        }
        if k == g.steps {
            break;
        }
        for (j, v) in u.iter_mut().enumerate() {
            *v = increments[k * N + j][lane];
        }
        let w;
        (st, w) = step_with_tangents::<N, ARC>(st, &mut t, m, &u);
        if let Some((p, _)) = parts {
            pt.add(&w, p.u[k * np..(k + 1) * np].iter().map(|v| v[lane]));
        }
        if k % RESYNC_STEPS == RESYNC_STEPS - 1 && k < lane_steps {
            (st.s, st.c) = st.th.sin_cos();
        }
    }
    if selection == Selection::End {
        out.errors[0] = tangent_row(st, &t, sensor, &g.end[lane], &mut out.jacobian, 0);
        part_rows::<N>(st, &pt, keys, m, sensor, &mut out.jacobian, 0);
    }
    out
}
