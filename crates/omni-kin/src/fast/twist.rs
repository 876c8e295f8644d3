//! The built-in twist-stage effects in the lane kernel: `rotation_slip`, `world_drift` and the learned
//! `body`, `world` and `time` families, each the same formula as its [`crate::effect::Effect::twist_at`]
//! hook, a group's lanes at a time (plain arrays), with the heading's cosine and sine the kernel carries (no `sin_cos` per step
//! but `rotation_slip`'s turn beyond the polynomials' range). A model with any other twist-stage effect
//! (a user's) takes the general walk.
//!
//! A step's displacement is `d = H v` (`H = f h` the step's length); the kernel's `M u` is `H` times the
//! twist from the wheels, so the effects see `v = d / H` and the step moves by `H v'`.

use super::LANES;
use super::kernel::{LaneState, RESYNC_STEPS, arc_factors, measured_error, step_lane};
use super::lanes::{LaneOps, Portable};
use super::prepare::{Group, Increments};
use super::{Lanes, MAX_STEP_ANGLE_RAD};
use crate::effect::learned::{Family, Learned, grain_in_body};
use crate::effect::{EffectKind, MOVING_OMEGA_RAD_S, MOVING_SPEED_M_S, longer_than};
use crate::model::Resolved;
use crate::plan::interval;
use crate::pose::{Pose2, PoseError};
use crate::run::Run;

/// One built-in twist-stage effect with its parameters.
#[derive(Clone, Copy, Debug)]
pub(super) enum LaneTwist {
    RotationSlip(f64),
    WorldDrift([f64; 2]),
    Body([f64; 9]),
    World([f64; 6]),
    Time([f64; 4]),
}

/// The lane forms of `res`'s twist-stage effects, in order; `None` when one has none.
pub(super) fn lane_twists(res: &Resolved<'_>) -> Option<Vec<LaneTwist>> {
    res.twist_effects
        .iter()
        .map(|(e, p)| {
            Some(match e {
                EffectKind::RotationSlip(_) => LaneTwist::RotationSlip(*p.first()?),
                EffectKind::WorldDrift(_) => LaneTwist::WorldDrift((*p).try_into().ok()?),
                EffectKind::Learned(Learned { family: Family::Body, .. }) => LaneTwist::Body((*p).try_into().ok()?),
                EffectKind::Learned(Learned { family: Family::World, .. }) => LaneTwist::World((*p).try_into().ok()?),
                EffectKind::Learned(Learned { family: Family::Time, .. }) => LaneTwist::Time((*p).try_into().ok()?),
                _ => return None,
            })
        })
        .collect()
}

/// The body twist of each lane: `(vx, vy, ω)`. m/s, rad/s.
type LaneTwistState = [Lanes; 3];

/// [`crate::effect::moving`] of lane `l`.
#[inline(always)]
fn moving(v: &LaneTwistState, l: usize) -> bool {
    v[2][l].abs() > MOVING_OMEGA_RAD_S || longer_than(v[0][l], v[1][l], MOVING_SPEED_M_S)
}

impl LaneTwist {
    /// Applies the effect to every lane's twist `v`; `c`, `s`: the heading's cosine and sine, `t`: the time
    /// since each run's first ground-truth pose (middle of the step). The formulas of the effects' hooks.
    #[inline(always)]
    fn apply(&self, v: &mut LaneTwistState, c: &Lanes, s: &Lanes, t: &Lanes) {
        match *self {
            LaneTwist::RotationSlip(k) if k != 0.0 => {
                let [vx, vy, w] = v;
                for ((x, y), w) in vx.iter_mut().zip(vy.iter_mut()).zip(w.iter()) {
                    let (sn, cs) = turn(k * w);
                    (*x, *y) = (cs * *x - sn * *y, sn * *x + cs * *y);
                }
            }
            LaneTwist::WorldDrift(p) if p != [0.0; 2] => {
                for l in 0..LANES {
                    if moving(v, l) {
                        v[0][l] += c[l] * p[0] + s[l] * p[1];
                        v[1][l] += -s[l] * p[0] + c[l] * p[1];
                    }
                }
            }
            LaneTwist::Body(p) if p != [0.0; 9] => (0..LANES).for_each(|l| body(&p, v, l)),
            LaneTwist::World(p) if p != [0.0; 6] => {
                for l in 0..LANES {
                    if moving(v, l) {
                        let (vx, vy) = (v[0][l], v[1][l]);
                        let (gc, gs) = grain_in_body(p[4], p[5], c[l], s[l]);
                        v[0][l] += c[l] * p[0] + s[l] * p[1] + gc * vx + gs * vy;
                        v[1][l] += -s[l] * p[0] + c[l] * p[1] + gs * vx - gc * vy;
                        v[2][l] += p[2] * c[l] + p[3] * s[l];
                    }
                }
            }
            LaneTwist::Time(p) if p != [0.0; 4] => {
                for l in 0..LANES {
                    if moving(v, l) {
                        let k = t[l];
                        let (vx, vy) = (v[0][l], v[1][l]);
                        v[0][l] += p[3] * k * vx;
                        v[1][l] += p[3] * k * vy;
                        let d = [p[0] * k, p[1] * k];
                        v[0][l] += c[l] * d[0] + s[l] * d[1];
                        v[1][l] += -s[l] * d[0] + c[l] * d[1];
                        v[2][l] += p[2] * k;
                    }
                }
            }
            _ => {}
        }
    }
}

/// `sin x`, `cos x`: the arc factors' polynomials for small angles, the library beyond.
#[inline(always)]
fn turn(x: f64) -> (f64, f64) {
    if x.abs() <= MAX_STEP_ANGLE_RAD {
        let (sinc, cosc) = arc_factors(x);
        (x * sinc, 1.0 - x * cosc)
    } else {
        x.sin_cos()
    }
}

/// The `body` family's correction of lane `l` (`learned::body`).
#[inline(always)]
fn body(p: &[f64; 9], v: &mut LaneTwistState, l: usize) {
    let (vx, vy, w) = (v[0][l], v[1][l], v[2][l]);
    let s = (vx * vx + vy * vy).sqrt();
    let (ca, sa) = if s > 0.0 { (vx / s, vy / s) } else { (0.0, 0.0) };
    let (c2, s2) = (ca * ca - sa * sa, 2.0 * ca * sa);
    let scale = p[2] * s + p[3] * w.abs() + p[5] * ca + p[6] * sa + p[7] * c2 + p[8] * s2;
    v[0][l] = vx + scale * vx - p[4] * w * vy;
    v[1][l] = vy + scale * vy + p[4] * w * vx;
    v[2][l] = w + p[0] * s + p[1] * w.abs();
}

/// What the twist-stage effects read of a group's steps besides the increments.
#[derive(Clone, Debug, Default)]
pub(super) struct StepTimes {
    /// Each step's length `f h` (0 past a lane's last step). s.
    step_s: Vec<Lanes>,
    /// Time since each lane's first ground-truth pose at the middle of the step's interval. s.
    since_start_s: Vec<Lanes>,
    /// Each query's partial step `f h` (0 at rest), in the group's query order. s.
    query_s: Vec<f64>,
}

impl StepTimes {
    /// The step times of group `g` (its runs `chunk`), as the walk takes them.
    pub fn new(g: &Group, chunk: &[Run]) -> Self {
        let mut out = StepTimes {
            step_s: vec![[0.0; LANES]; g.steps],
            since_start_s: vec![[0.0; LANES]; g.steps],
            query_s: Vec::with_capacity(g.queries.len()),
        };
        for (lane, (run, plan)) in chunk.iter().zip(g.plans()).enumerate() {
            let (t, median, h) = (run.wheel_t_s(), run.median_dt_s(), g.h()[lane]);
            let t0 = run.truth()[0].t_s;
            for (i, f) in plan.fractions().enumerate() {
                let (a_k, s_k) = interval(t, plan.clock_lag_s, median, plan.first_sample + i);
                out.step_s[i][lane] = f * h;
                out.since_start_s[i][lane] = (0.5 * (a_k + s_k) - t0).max(0.0);
            }
        }
        for q in &g.queries {
            let at = &g.plans()[q.lane].queries[q.source()];
            out.query_s.push(at.fraction.map_or(0.0, |f| f * g.h()[q.lane]));
        }
        out
    }
}

/// The twist each lane holds over step `k`, from its displacement `d` (`M u`).
#[inline(always)]
fn twist_of_step(
    d: &LaneTwistState,
    times: &StepTimes,
    k: usize,
    twists: &[LaneTwist],
    st: (&Lanes, &Lanes),
) -> LaneTwistState {
    let h = &times.step_s[k];
    let mut v: LaneTwistState = [[0.0; LANES]; 3];
    for l in 0..LANES {
        let inv = if h[l] > 0.0 { 1.0 / h[l] } else { 0.0 };
        for r in 0..3 {
            v[r][l] = d[r][l] * inv;
        }
    }
    for e in twists {
        e.apply(&mut v, st.0, st.1, &times.since_start_s[k]);
    }
    v
}

/// Walks group `g` with increments `inc` and the twist-stage effects `twists` (N wheels, exact arcs or
/// Euler): calls `on_query(slot, error)` for each query, returns the end-pose errors; `None` when a step
/// angle after the effects exceeds [`MAX_STEP_ANGLE_RAD`].
/// long: the kernel's step loop with the twist stage between the displacement and the step, one loop for
/// the same reason as the kernel's.
pub(super) fn walk<const N: usize, const ARC: bool>(
    g: &Group,
    inc: &Increments<'_>,
    times: &StepTimes,
    (m, sensor): (&[f64], Pose2),
    twists: &[LaneTwist],
    on_query: &mut dyn FnMut(usize, PoseError),
) -> Option<[PoseError; LANES]> {
    let o = Portable;
    let inv = sensor.inverse();
    let mut lanes: [LaneState; LANES] = std::array::from_fn(|l| {
        let body = g.start[l].compose(&inv);
        let (s, c) = body.theta_rad.sin_cos();
        LaneState { x: body.x_m, y: body.y_m, th: body.theta_rad, c, s }
    });
    let mut qi = 0;
    for (k, uk) in inc.u[..g.steps * N].chunks_exact(N).enumerate() {
        let mut d: LaneTwistState = [[0.0; LANES]; 3];
        for j in 0..N {
            let u = o.load(&uk[j]);
            d[0] = o.mul_add(o.splat(m[j]), u, d[0]);
            d[1] = o.mul_add(o.splat(m[N + j]), u, d[1]);
            d[2] = o.mul_add(o.splat(m[2 * N + j]), u, d[2]);
        }
        let (c, s): (Lanes, Lanes) = (std::array::from_fn(|l| lanes[l].c), std::array::from_fn(|l| lanes[l].s));
        let v = twist_of_step(&d, times, k, twists, (&c, &s));
        while qi < g.queries.len() && g.queries[qi].step == k {
            let q = &g.queries[qi];
            let hq = times.query_s[qi];
            let (dx, dy, a) = (hq * v[0][q.lane], hq * v[1][q.lane], hq * v[2][q.lane]);
            if a.is_nan() || a.abs() > MAX_STEP_ANGLE_RAD {
                return None;
            }
            on_query(q.slot, measured_error(step_lane::<ARC>(lanes[q.lane], dx, dy, a), sensor, &q.truth));
            qi += 1;
        }
        for (l, st) in lanes.iter_mut().enumerate() {
            let h = times.step_s[k][l];
            let (dx, dy, a) = (h * v[0][l], h * v[1][l], h * v[2][l]);
            if a.is_nan() || a.abs() > MAX_STEP_ANGLE_RAD {
                return None;
            }
            *st = step_lane::<ARC>(*st, dx, dy, a);
            // Not past the lane's last step (the same numbers whatever runs share the group).
            if k % RESYNC_STEPS == RESYNC_STEPS - 1 && g.plans().get(l).is_some_and(|p| k < p.steps) {
                (st.s, st.c) = st.th.sin_cos();
            }
        }
    }
    // After the last step: at rest.
    for q in &g.queries[qi..] {
        on_query(q.slot, measured_error(lanes[q.lane], sensor, &q.truth));
    }
    Some(std::array::from_fn(|l| measured_error(lanes[l], sensor, &g.end[l])))
}

/// One twist-stage effect at one step with its derivatives: the twist it gives, and its derivatives with
/// respect to the incoming twist (`jv[out][in]`, components vx, vy, ω), to the heading, and to its own
/// parameters (the first `n_params` of `jp`). Exact but at `moving`'s threshold and at rest, where the
/// hooks are not differentiable (there: the slopes of the side the step is on).
#[derive(Clone, Copy, Debug)]
pub(super) struct Slopes {
    pub v: [f64; 3],
    pub jv: [[f64; 3]; 3],
    pub jth: [f64; 3],
    pub jp: [[f64; 3]; 9],
    pub n_params: usize,
}

impl LaneTwist {
    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        match self {
            LaneTwist::RotationSlip(_) => 1,
            LaneTwist::WorldDrift(_) => 2,
            LaneTwist::Body(_) => 9,
            LaneTwist::World(_) => 6,
            LaneTwist::Time(_) => 4,
        }
    }

    /// The effect on twist `v` at heading cosine and sine `(c, s)` and time `t` since the start, with its
    /// derivatives ([`Slopes`]); the same formulas as [`Self::apply`].
    pub fn slopes(&self, v: [f64; 3], (c, s): (f64, f64), t: f64) -> Slopes {
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let mut out = Slopes { v, jv: id, jth: [0.0; 3], jp: [[0.0; 3]; 9], n_params: self.n_params() };
        let [vx, vy, w] = v;
        let moves = || crate::effect::moving(&crate::pose::Twist2 { vx_m_s: vx, vy_m_s: vy, omega_rad_s: w });
        match *self {
            LaneTwist::RotationSlip(k) => {
                let (sn, cs) = if k != 0.0 { turn(k * w) } else { (0.0, 1.0) };
                let (rx, ry) = (-sn * vx - cs * vy, cs * vx - sn * vy);
                out.v = [cs * vx - sn * vy, sn * vx + cs * vy, w];
                out.jv = [[cs, -sn, k * rx], [sn, cs, k * ry], [0.0, 0.0, 1.0]];
                out.jp[0] = [w * rx, w * ry, 0.0];
            }
            LaneTwist::WorldDrift(p) => {
                if moves() {
                    out.v = [vx + c * p[0] + s * p[1], vy - s * p[0] + c * p[1], w];
                    out.jth = [-s * p[0] + c * p[1], -c * p[0] - s * p[1], 0.0];
                    out.jp[0] = [c, -s, 0.0];
                    out.jp[1] = [s, c, 0.0];
                }
            }
            LaneTwist::Body(p) => body_slopes(&p, &mut out),
            LaneTwist::World(p) => {
                if moves() {
                    let (gc, gs) = grain_in_body(p[4], p[5], c, s);
                    let (c2, s2) = (c * c - s * s, 2.0 * c * s);
                    out.v = [
                        vx + c * p[0] + s * p[1] + gc * vx + gs * vy,
                        vy - s * p[0] + c * p[1] + gs * vx - gc * vy,
                        w + p[2] * c + p[3] * s,
                    ];
                    out.jv = [[1.0 + gc, gs, 0.0], [gs, 1.0 - gc, 0.0], [0.0, 0.0, 1.0]];
                    // d(gc)/dψ = 2 gs, d(gs)/dψ = −2 gc (the body-frame grain turns by −2ψ).
                    out.jth = [
                        -s * p[0] + c * p[1] + 2.0 * (gs * vx - gc * vy),
                        -c * p[0] - s * p[1] - 2.0 * (gc * vx + gs * vy),
                        -p[2] * s + p[3] * c,
                    ];
                    out.jp[..6].copy_from_slice(&[
                        [c, -s, 0.0],
                        [s, c, 0.0],
                        [0.0, 0.0, c],
                        [0.0, 0.0, s],
                        [c2 * vx - s2 * vy, -s2 * vx - c2 * vy, 0.0],
                        [s2 * vx + c2 * vy, c2 * vx - s2 * vy, 0.0],
                    ]);
                }
            }
            LaneTwist::Time(p) => {
                if moves() {
                    let (dx, dy) = (p[0] * t, p[1] * t);
                    let g = 1.0 + p[3] * t;
                    out.v = [vx + p[3] * t * vx + c * dx + s * dy, vy + p[3] * t * vy - s * dx + c * dy, w + p[2] * t];
                    out.jv = [[g, 0.0, 0.0], [0.0, g, 0.0], [0.0, 0.0, 1.0]];
                    out.jth = [-s * dx + c * dy, -c * dx - s * dy, 0.0];
                    let jp = [[c * t, -s * t, 0.0], [s * t, c * t, 0.0], [0.0, 0.0, t], [t * vx, t * vy, 0.0]];
                    out.jp[..4].copy_from_slice(&jp);
                }
            }
        }
        out
    }
}

/// [`LaneTwist::slopes`] of the `body` family (`learned::body`).
fn body_slopes(p: &[f64; 9], out: &mut Slopes) {
    let [vx, vy, w] = out.v;
    let s = (vx * vx + vy * vy).sqrt();
    let (ca, sa) = if s > 0.0 { (vx / s, vy / s) } else { (0.0, 0.0) };
    let (c2, s2) = (ca * ca - sa * sa, 2.0 * ca * sa);
    let scale = p[2] * s + p[3] * w.abs() + p[5] * ca + p[6] * sa + p[7] * c2 + p[8] * s2;
    let sw = if w > 0.0 {
        1.0
    } else if w < 0.0 {
        -1.0
    } else {
        0.0
    };
    // Slopes of s, ca, sa in (vx, vy) (none at rest).
    let inv = if s > 0.0 { 1.0 / s } else { 0.0 };
    let ds = [ca, sa];
    let dca = [sa * sa * inv, -ca * sa * inv];
    let dsa = [-ca * sa * inv, ca * ca * inv];
    let dscale: [f64; 2] = std::array::from_fn(|i| {
        let dc2 = 2.0 * ca * dca[i] - 2.0 * sa * dsa[i];
        let ds2 = 2.0 * (dca[i] * sa + ca * dsa[i]);
        p[2] * ds[i] + p[5] * dca[i] + p[6] * dsa[i] + p[7] * dc2 + p[8] * ds2
    });
    let dscale_w = p[3] * sw;
    out.v = [vx + scale * vx - p[4] * w * vy, vy + scale * vy + p[4] * w * vx, w + p[0] * s + p[1] * w.abs()];
    out.jv = [
        [1.0 + scale + vx * dscale[0], vx * dscale[1] - p[4] * w, vx * dscale_w - p[4] * vy],
        [vy * dscale[0] + p[4] * w, 1.0 + scale + vy * dscale[1], vy * dscale_w + p[4] * vx],
        [p[0] * ds[0], p[0] * ds[1], 1.0 + p[1] * sw],
    ];
    out.jp = [
        [0.0, 0.0, s],
        [0.0, 0.0, w.abs()],
        [vx * s, vy * s, 0.0],
        [vx * w.abs(), vy * w.abs(), 0.0],
        [-w * vy, w * vx, 0.0],
        [vx * ca, vy * ca, 0.0],
        [vx * sa, vy * sa, 0.0],
        [vx * c2, vy * c2, 0.0],
        [vx * s2, vy * s2, 0.0],
    ];
}
