//! The step kernel: a group's eight runs at once in SIMD lanes (one AVX-512 vector, two passes of one
//! AVX2 vector, or plain arrays: [`SimdPath`], the same bits on each). Each step's body displacement is `M u` (3 × N
//! multiply-adds on the wheel-angle increments), the arc factors and the heading's rotation come from
//! short polynomials in the step angle (exact to < 1e-16 for `|a| ≤ 0.1` rad), and the heading's cosine
//! and sine are re-taken from the summed heading every [`RESYNC_STEPS`] steps of a lane's own steps (not
//! past its last one, so a run's numbers do not depend on the runs it shares a group with).

use super::LANES;
use super::lanes::{Fused, LaneOps, SimdPath};
use super::prepare::{Group, Increments};
use crate::pose::{Pose2, PoseError, wrap_angle};

/// Steps between re-taking the heading's cosine and sine from the summed heading.
pub(super) const RESYNC_STEPS: usize = 1024;

// Series of sin(a)/a and (1 − cos a)/a: truncation error below 3e-18 for |a| ≤ 0.1.
pub(super) const S1: f64 = -1.0 / 6.0;
pub(super) const S2: f64 = 1.0 / 120.0;
pub(super) const S3: f64 = -1.0 / 5040.0;
pub(super) const S4: f64 = 1.0 / 362_880.0;
pub(super) const C0: f64 = 0.5;
pub(super) const C1: f64 = -1.0 / 24.0;
pub(super) const C2: f64 = 1.0 / 720.0;
pub(super) const C3: f64 = -1.0 / 40_320.0;
pub(super) const C4: f64 = 1.0 / 3_628_800.0;

/// `sin(a)/a` and `(1 − cos a)/a` for small `a`.
#[inline(always)]
pub(super) fn arc_factors(a: f64) -> (f64, f64) {
    let a2 = a * a;
    let sinc = 1.0 + a2 * (S1 + a2 * (S2 + a2 * (S3 + a2 * S4)));
    let cosc = a * (C0 + a2 * (C1 + a2 * (C2 + a2 * (C3 + a2 * C4))));
    (sinc, cosc)
}

/// One lane's state: body pose and the heading's cosine and sine.
#[derive(Clone, Copy, Debug)]
pub(super) struct LaneState {
    pub x: f64,
    pub y: f64,
    pub th: f64,
    pub c: f64,
    pub s: f64,
}

/// One step of one lane by the body displacement `(dx, dy)` and turn `a` (scalar; for queries).
#[inline(always)]
pub(super) fn step_lane<const ARC: bool>(st: LaneState, dx: f64, dy: f64, a: f64) -> LaneState {
    let (sinc, cosc) = arc_factors(a);
    let (bx, by) = if ARC { (sinc * dx - cosc * dy, cosc * dx + sinc * dy) } else { (dx, dy) };
    let (sa, cm1) = (a * sinc, -a * cosc); // sin a, cos a − 1
    LaneState {
        x: st.x + st.c * bx - st.s * by,
        y: st.y + st.s * bx + st.c * by,
        th: st.th + a,
        c: st.c + st.c * cm1 - st.s * sa,
        s: st.s + st.s * cm1 + st.c * sa,
    }
}

/// The body displacement `M u` of a step (scalar).
#[inline(always)]
pub(super) fn displacement<const N: usize>(m: &[f64], u: &[f64]) -> (f64, f64, f64) {
    let (mut dx, mut dy, mut a) = (0.0, 0.0, 0.0);
    for j in 0..N {
        dx += m[j] * u[j];
        dy += m[N + j] * u[j];
        a += m[2 * N + j] * u[j];
    }
    (dx, dy, a)
}

/// `wrap_angle`, with the common case (already within (−π, π]) first.
#[inline(always)]
fn wrap(d: f64) -> f64 {
    if d > -std::f64::consts::PI && d <= std::f64::consts::PI { d } else { wrap_angle(d) }
}

/// The measured pose of a lane (body ∘ sensor) and its error to `truth`.
#[inline(always)]
pub(super) fn measured_error(st: LaneState, sensor: Pose2, truth: &Pose2) -> PoseError {
    PoseError {
        dx_m: st.x + st.c * sensor.x_m - st.s * sensor.y_m - truth.x_m,
        dy_m: st.y + st.s * sensor.x_m + st.c * sensor.y_m - truth.y_m,
        dtheta_rad: wrap(st.th + sensor.theta_rad - truth.theta_rad),
    }
}

/// Walks group `g` with increments `inc` (N wheels, exact arcs or Euler) on `path` (or the widest
/// narrower one this CPU has).
pub(super) fn walk<const N: usize, const ARC: bool>(
    path: SimdPath,
    g: &Group,
    inc: &Increments<'_>,
    m: &[f64],
    sensor: Pose2,
    on_query: &mut dyn FnMut(usize, PoseError),
) -> [PoseError; LANES] {
    let mut ends = [PoseError::default(); LANES];
    let out = &mut ends;
    #[cfg(target_arch = "x86_64")]
    if path == SimdPath::Avx512
        && let Some(simd) = pulp::x86::V4::try_new()
    {
        simd.vectorize(|| kernel::<_, N, ARC, 0>(simd, g, inc, (m, sensor), on_query, out));
        return ends;
    }
    #[cfg(target_arch = "x86_64")]
    if path >= SimdPath::Avx2
        && let Some(simd) = pulp::x86::V3::try_new()
    {
        // Two passes of four lanes, one `vectorize` each (a closure holding both kernels is not inlined
        // into the AVX2 context: 50x slower).
        simd.vectorize(|| kernel::<_, N, ARC, 0>(simd, g, inc, (m, sensor), on_query, &mut *out));
        simd.vectorize(|| kernel::<_, N, ARC, 4>(simd, g, inc, (m, sensor), on_query, out));
        return ends;
    }
    let _ = path;
    kernel::<_, N, ARC, 0>(Fused, g, inc, (m, sensor), on_query, out);
    ends
}

// The AVX2 path's two passes of four lanes and the AVX-512 path's one of eight cover a group.
const _: () = assert!(LANES == 8);

/// The heading's cosine and sine `(c, s)` after step `k`, re-taken from the summed heading `th` in the
/// lanes that walked step `k` (`k < lane_steps[lane]`), kept in the others (past their last step); the
/// values hold lanes `BASE..BASE + O::WIDTH`.
#[inline(never)]
fn resync<O: LaneOps, const BASE: usize>(o: O, k: usize, lane_steps: &[usize; LANES], v: [O::V; 3]) -> (O::V, O::V) {
    let [t, mut c, mut s] = v.map(|v| {
        let mut lanes = [0.0; LANES];
        o.store(v, &mut lanes[BASE..]);
        lanes
    });
    for l in BASE..BASE + O::WIDTH {
        if k < lane_steps[l] {
            (s[l], c[l]) = t[l].sin_cos();
        }
    }
    (o.load(&c[BASE..]), o.load(&s[BASE..]))
}

/// The lane states of a group, unpacked (lanes `BASE..BASE + O::WIDTH`; the others zero).
#[inline(always)]
fn unpack<O: LaneOps, const BASE: usize>(o: O, v: &[O::V; 5]) -> [LaneState; LANES] {
    let [x, y, th, c, s] = v.map(|v| {
        let mut lanes = [0.0; LANES];
        o.store(v, &mut lanes[BASE..]);
        lanes
    });
    std::array::from_fn(|l| LaneState { x: x[l], y: y[l], th: th[l], c: c[l], s: s[l] })
}

/// long: the hot step loop stays one function so that the lanes' state lives in registers across the
/// loop (inlined, const generics per wheel count); splitting it measurably slows every evaluation. Walks
/// lanes `BASE..BASE + O::WIDTH` of the group and writes their end-pose errors to `ends`.
#[inline(always)]
fn kernel<O: LaneOps, const N: usize, const ARC: bool, const BASE: usize>(
    o: O,
    g: &Group,
    inc: &Increments<'_>,
    (m, sensor): (&[f64], Pose2),
    on_query: &mut dyn FnMut(usize, PoseError),
    ends: &mut [PoseError; LANES],
) {
    let pass = BASE..BASE + O::WIDTH;
    let (u, query_u) = (inc.u, inc.query_u);
    let inv = sensor.inverse();
    let mut init = [[0.0; LANES]; 5];
    for l in 0..LANES {
        let body = g.start[l].compose(&inv);
        let (s, c) = body.theta_rad.sin_cos();
        for (v, value) in init.iter_mut().zip([body.x_m, body.y_m, body.theta_rad, c, s]) {
            v[l] = value;
        }
    }
    let [mut x, mut y, mut th, mut c, mut s] = init.map(|v| o.load(&v[BASE..]));
    let mx: [O::V; N] = std::array::from_fn(|j| o.splat(m[j]));
    let my: [O::V; N] = std::array::from_fn(|j| o.splat(m[N + j]));
    let ma: [O::V; N] = std::array::from_fn(|j| o.splat(m[2 * N + j]));
    let (s1, s2, s3, s4) = (o.splat(S1), o.splat(S2), o.splat(S3), o.splat(S4));
    let (c0, c1, c2, c3, c4) = (o.splat(C0), o.splat(C1), o.splat(C2), o.splat(C3), o.splat(C4));
    let one = o.splat(1.0);
    let lane_steps: [usize; LANES] = std::array::from_fn(|l| g.plans().get(l).map_or(0, |p| p.steps));
    let mut qi = 0;
    let mut next_query = g.queries.first().map_or(usize::MAX, |q| q.step);
    let mut answer = |qi: &mut usize, next_query: &mut usize, v: &[O::V; 5]| {
        let lanes = unpack::<O, BASE>(o, v);
        while *qi < g.queries.len() && g.queries[*qi].step == *next_query {
            let q = &g.queries[*qi];
            if pass.contains(&q.lane) {
                let (dx, dy, a) = displacement::<N>(m, &query_u[*qi * N..(*qi + 1) * N]);
                on_query(q.slot, measured_error(step_lane::<ARC>(lanes[q.lane], dx, dy, a), sensor, &q.truth));
            }
            *qi += 1;
        }
        *next_query = g.queries.get(*qi).map_or(usize::MAX, |q| q.step);
    };
    for (k, uk) in u[..g.steps * N].chunks_exact(N).enumerate() {
        if k == next_query {
            answer(&mut qi, &mut next_query, &[x, y, th, c, s]);
        }
        let u: [O::V; N] = std::array::from_fn(|j| o.load(&uk[j][BASE..]));
        let mut dx = o.mul(mx[0], u[0]);
        let mut dy = o.mul(my[0], u[0]);
        let mut a = o.mul(ma[0], u[0]);
        for j in 1..N {
            dx = o.mul_add(mx[j], u[j], dx);
            dy = o.mul_add(my[j], u[j], dy);
            a = o.mul_add(ma[j], u[j], a);
        }
        let a2 = o.mul(a, a);
        let p = o.mul_add(a2, s4, s3);
        let p = o.mul_add(a2, p, s2);
        let p = o.mul_add(a2, p, s1);
        let sinc = o.mul_add(a2, p, one);
        let q = o.mul_add(a2, c4, c3);
        let q = o.mul_add(a2, q, c2);
        let q = o.mul_add(a2, q, c1);
        let cosc = o.mul(a, o.mul_add(a2, q, c0));
        let (bx, by) = if ARC {
            (o.neg_mul_add(cosc, dy, o.mul(sinc, dx)), o.mul_add(cosc, dx, o.mul(sinc, dy)))
        } else {
            (dx, dy)
        };
        x = o.mul_add(c, bx, o.neg_mul_add(s, by, x));
        y = o.mul_add(s, bx, o.mul_add(c, by, y));
        let sa = o.mul(a, sinc);
        let ac = o.mul(a, cosc); // 1 − cos a
        let c_next = o.neg_mul_add(c, ac, o.neg_mul_add(s, sa, c));
        s = o.neg_mul_add(s, ac, o.mul_add(c, sa, s));
        c = c_next;
        th = o.add(th, a);
        if k % RESYNC_STEPS == RESYNC_STEPS - 1 {
            (c, s) = resync::<O, BASE>(o, k, &lane_steps, [th, c, s]);
        }
    }
    let v = [x, y, th, c, s];
    if qi < g.queries.len() {
        answer(&mut qi, &mut next_query, &v);
    }
    let lanes = unpack::<O, BASE>(o, &v);
    for l in pass {
        ends[l] = measured_error(lanes[l], sensor, &g.end[l]);
    }
}
