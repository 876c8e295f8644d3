//! The forward-mode Jacobian along the general fast walk ([`super::general`]): the errors at the selected
//! poses of one run and their derivatives with respect to the IK entries and to the effect parameters the
//! walk can carry — those of twist-stage effects, of measurement-stage effects, and of the one affine
//! wheel-stage effect ([`super::features`]). Other parameters (a clock lag, backlash) are left to the
//! caller's finite differences.
//!
//! The state `(x, y, θ)` carries one tangent column per parameter. A step holds the twist
//! `v' = E(M w, pose, t)` (the twist-stage hooks `E` in order) for `H` seconds:
//! `dv' = J_v dv + J_X dX + J_p dp`, where the hooks' own derivatives `J_v`, `J_X` (pose) and `J_p` come from
//! central differences of the hooks at that step (cheap: a few flops each, and exact for the built-ins'
//! linear parts), and the rest is analytic: the arc's displacement `B(H v')` and its turn by the heading.
//! The measured pose `X ∘ S` adds the sensor pose's derivatives (also by central differences of the
//! measurement hooks), at the start (`X₀ = truth₀ ∘ S⁻¹`) and at every selected pose.

use super::MAX_STEP_ANGLE_RAD;
use super::features::WheelFeatures;
use super::jacobian::arc_factor_slopes;
use super::kernel::{LaneState, RESYNC_STEPS, arc_factors, measured_error, step_lane};
use super::twist::{LaneTwist, lane_twists};
use crate::effect::{Effect, EffectKind, Stage, TwistAt};
use crate::model::{Model, Resolved, Scheme};
use crate::plan::{StepPlan, interval};
use crate::pose::{Pose2, PoseError, Twist2};
use crate::run::Run;
use nalgebra::DMatrix;
use std::ops::Range;

/// Relative step of the hooks' central differences.
const HOOK_STEP: f64 = 1e-6;

/// What the forward-mode walk differentiates: the IK entries (the first `3 N` columns, row-major), then
/// the effect parameters in [`Self::covered`].
#[derive(Debug)]
pub(crate) struct ForwardModel<'m> {
    /// Twist-stage effects in model order, with their parameters' indices.
    twist: Vec<(&'m EffectKind, Range<usize>)>,
    /// Measurement-stage effects in model order, with their parameters' indices.
    measurement: Vec<(&'m EffectKind, Range<usize>)>,
    /// The affine wheel-stage effect's parameters and their parts, when carried.
    wheel: Option<(Range<usize>, &'m WheelFeatures)>,
    /// Indices (in the model's parameter vector) of the effect parameters carried, in column order.
    pub covered: Vec<usize>,
    /// Each twist-stage effect's parameters: (index in the parameter vector, column).
    twist_columns: Vec<Vec<(usize, usize)>>,
    n_wheels: usize,
}

impl<'m> ForwardModel<'m> {
    /// The columns of `model` the walk carries; `parts`: the parts of its affine wheel-stage effect, when
    /// it has exactly one wheel-stage effect and the parts serve it.
    pub fn new(model: &'m Model, parts: Option<&'m WheelFeatures>) -> Self {
        let (mut twist, mut measurement, mut wheel) = (Vec::new(), Vec::new(), None);
        let wheel_effects = model.effects.iter().filter(|e| e.stage() == Stage::Wheel).count();
        for (e, r) in model.effects.iter().zip(model.effect_ranges()) {
            match e.stage() {
                Stage::Twist => twist.push((e, r)),
                Stage::Measurement => measurement.push((e, r)),
                Stage::Wheel if wheel_effects == 1 => wheel = parts.map(|p| (r, p)),
                _ => {}
            }
        }
        let mut covered: Vec<usize> = twist.iter().chain(&measurement).flat_map(|(_, r)| r.clone()).collect();
        covered.extend(wheel.iter().flat_map(|(r, _)| r.clone()));
        covered.sort_unstable();
        let nik = 3 * model.n_wheels();
        let column = |g: usize| nik + covered.iter().position(|&c| c == g).unwrap_or(0);
        let twist_columns = twist.iter().map(|(_, r)| r.clone().map(|g| (g, column(g))).collect()).collect();
        Self { twist, measurement, wheel, covered, twist_columns, n_wheels: model.n_wheels() }
    }

    /// Number of columns: IK entries, then the covered parameters.
    pub fn n_columns(&self) -> usize {
        3 * self.n_wheels + self.covered.len()
    }

    /// The twist after every twist-stage hook, with parameters `x`.
    fn twist(&self, x: &[f64], v: Twist2, w: &[f64], at: &TwistAt) -> Twist2 {
        self.twist.iter().fold(v, |t, (e, r)| e.twist_at(&x[r.clone()], t, w, at))
    }

    /// The sensor pose of the measurement-stage hooks, with parameters `x`.
    fn sensor(&self, x: &[f64]) -> Pose2 {
        self.measurement.iter().fold(Pose2::IDENTITY, |s, (e, r)| s.compose(&e.sensor_from_body(&x[r.clone()])))
    }
}

/// Central difference of `f` in parameter `g` of `x` (restored after).
fn param_slope<T: Copy>(x: &mut [f64], g: usize, f: impl Fn(&[f64]) -> T, diff: impl Fn(T, T, f64) -> T) -> T {
    let v = x[g];
    let h = HOOK_STEP * v.abs().max(1e-3);
    x[g] = v + h;
    let up = f(x);
    x[g] = v - h;
    let down = f(x);
    x[g] = v;
    diff(up, down, 2.0 * h)
}

fn pose_diff(a: Pose2, b: Pose2, h: f64) -> Pose2 {
    Pose2 { x_m: (a.x_m - b.x_m) / h, y_m: (a.y_m - b.y_m) / h, theta_rad: (a.theta_rad - b.theta_rad) / h }
}

fn twist_diff(a: Twist2, b: Twist2, h: f64) -> Twist2 {
    Twist2 {
        vx_m_s: (a.vx_m_s - b.vx_m_s) / h,
        vy_m_s: (a.vy_m_s - b.vy_m_s) / h,
        omega_rad_s: (a.omega_rad_s - b.omega_rad_s) / h,
    }
}

/// Tangent columns of the state `(x, y, θ)`, one entry per column.
#[derive(Clone, Debug)]
struct Tangent {
    x: Vec<f64>,
    y: Vec<f64>,
    th: Vec<f64>,
}

/// One step's twist and the derivatives of the twist with respect to every column (`dv'`).
struct StepTwist {
    v: Twist2,
    dvx: Vec<f64>,
    dvy: Vec<f64>,
    dw: Vec<f64>,
}

/// The state and tangent after holding `tw` for `h` seconds; `None` when the step angle exceeds
/// [`MAX_STEP_ANGLE_RAD`].
fn advance(arc: bool, st: LaneState, t: &Tangent, tw: &StepTwist, h: f64, out: &mut Tangent) -> Option<LaneState> {
    let (dx, dy, a) = (h * tw.v.vx_m_s, h * tw.v.vy_m_s, h * tw.v.omega_rad_s);
    if a.is_nan() || a.abs() > MAX_STEP_ANGLE_RAD {
        return None;
    }
    let (sinc, cosc) = if arc { arc_factors(a) } else { (1.0, 0.0) };
    let (ds, dc) = if arc { arc_factor_slopes(a) } else { (0.0, 0.0) };
    let (bx, by) = (sinc * dx - cosc * dy, cosc * dx + sinc * dy);
    let (ex, ey) = (ds * dx - dc * dy, dc * dx + ds * dy);
    let (c, s) = (st.c, st.s);
    let (rx, ry) = (-s * bx - c * by, c * bx - s * by);
    for d in 0..t.x.len() {
        let (ddx, ddy, da) = (h * tw.dvx[d], h * tw.dvy[d], h * tw.dw[d]);
        let dbx = sinc * ddx - cosc * ddy + ex * da;
        let dby = cosc * ddx + sinc * ddy + ey * da;
        out.x[d] = t.x[d] + rx * t.th[d] + c * dbx - s * dby;
        out.y[d] = t.y[d] + ry * t.th[d] + s * dbx + c * dby;
        out.th[d] = t.th[d] + da;
    }
    Some(if arc { step_lane::<true>(st, dx, dy, a) } else { step_lane::<false>(st, dx, dy, a) })
}

/// The rows of one run: errors at `plan`'s poses (or, with `end_only`, at the last ground-truth pose) and
/// their Jacobian (3 rows per pose; columns of `fm`), unscaled.
pub(crate) struct RunRows {
    pub errors: Vec<PoseError>,
    pub jacobian: DMatrix<f64>,
}

/// Everything one run's forward walk reads.
pub(crate) struct RunInput<'a> {
    pub res: &'a Resolved<'a>,
    pub params: &'a [f64],
    pub run: &'a Run,
    /// Index of the run (for the wheel parts).
    pub index: usize,
    pub plan: &'a StepPlan,
    /// The wheel speeds integrated (the run's own or rewritten).
    pub wheels: &'a [f64],
    pub end_only: bool,
}

/// The sensor pose's derivatives with respect to every column (zero but for measurement parameters),
/// and the start state's tangent.
fn sensor_slopes(fm: &ForwardModel<'_>, x: &mut [f64], start: Pose2) -> (Vec<Pose2>, Tangent) {
    let p = fm.n_columns();
    let nik = 3 * fm.n_wheels;
    let mut ds = vec![Pose2::new(0.0, 0.0, 0.0); p];
    let mut t = Tangent { x: vec![0.0; p], y: vec![0.0; p], th: vec![0.0; p] };
    for (k, &g) in fm.covered.iter().enumerate() {
        if !fm.measurement.iter().any(|(_, r)| r.contains(&g)) {
            continue;
        }
        ds[nik + k] = param_slope(x, g, |x| fm.sensor(x), pose_diff);
        let d0 = param_slope(x, g, |x| start.compose(&fm.sensor(x).inverse()), pose_diff);
        (t.x[nik + k], t.y[nik + k], t.th[nik + k]) = (d0.x_m, d0.y_m, d0.theta_rad);
    }
    (ds, t)
}

/// Appends the error rows of the measured pose at state `st` (tangent `t`) against `truth`.
fn error_rows(st: LaneState, t: &Tangent, sensor: Pose2, ds: &[Pose2], truth: &Pose2, out: &mut RunRows, row: usize) {
    out.errors.push(measured_error(st, sensor, truth));
    let (c, s) = (st.c, st.s);
    let (kx, ky) = (-s * sensor.x_m - c * sensor.y_m, c * sensor.x_m - s * sensor.y_m);
    for (d, q) in ds.iter().enumerate() {
        out.jacobian[(row, d)] = t.x[d] + kx * t.th[d] + c * q.x_m - s * q.y_m;
        out.jacobian[(row + 1, d)] = t.y[d] + ky * t.th[d] + s * q.x_m + c * q.y_m;
        out.jacobian[(row + 2, d)] = t.th[d] + q.theta_rad;
    }
}

/// The twist of one step and its derivatives with respect to every column.
struct TwistSlopes<'a> {
    fm: &'a ForwardModel<'a>,
    res: &'a Resolved<'a>,
    /// The twist-stage effects' lane forms (all built-in: analytic slopes), else `None` (differences).
    lanes: Option<Vec<LaneTwist>>,
    /// The hooks' slopes in the covered parameters: (column, slope); a buffer.
    jp: Vec<(usize, Twist2)>,
}

/// One step's inputs besides the parameters.
struct StepInput<'a> {
    w: &'a [f64],
    /// (column, wheel, part) of the affine wheel-stage effect's parameters at this sample.
    parts: &'a [(usize, usize, f64)],
    at: &'a TwistAt,
    /// Cosine and sine of the heading the state carries.
    cs: (f64, f64),
}

impl TwistSlopes<'_> {
    /// The twist of a step and `dv'` of every column (`out`), from the tangent `t` at its start.
    fn at(&mut self, x: &mut [f64], input: &StepInput<'_>, t: &Tangent, out: &mut StepTwist) {
        let (fm, m) = (self.fm, self.res.ik.entries());
        let n = fm.n_wheels;
        let raw = self.res.ik.twist(input.w);
        // dv (before the hooks): the IK entries and the wheel parts.
        out.dvx.iter_mut().chain(out.dvy.iter_mut()).chain(out.dw.iter_mut()).for_each(|v| *v = 0.0);
        for (j, &wj) in input.w.iter().enumerate().take(n) {
            (out.dvx[j], out.dvy[n + j], out.dw[2 * n + j]) = (wj, wj, wj);
        }
        for &(col, wheel, value) in input.parts {
            out.dvx[col] += m[wheel] * value;
            out.dvy[col] += m[n + wheel] * value;
            out.dw[col] += m[2 * n + wheel] * value;
        }
        if fm.twist.is_empty() {
            out.v = raw;
            return;
        }
        self.jp.clear();
        let (v, jv, jx) = match &self.lanes {
            Some(lanes) => lane_slopes(lanes, &fm.twist_columns, raw, input, &mut self.jp),
            None => self.differences(x, raw, input),
        };
        out.v = v;
        let pose_free = jx.iter().all(|j| j.vx_m_s == 0.0 && j.vy_m_s == 0.0 && j.omega_rad_s == 0.0);
        for d in 0..out.dvx.len() {
            let (a, b, c) = (out.dvx[d], out.dvy[d], out.dw[d]);
            let mut g = Twist2 {
                vx_m_s: jv[0].vx_m_s * a + jv[1].vx_m_s * b + jv[2].vx_m_s * c,
                vy_m_s: jv[0].vy_m_s * a + jv[1].vy_m_s * b + jv[2].vy_m_s * c,
                omega_rad_s: jv[0].omega_rad_s * a + jv[1].omega_rad_s * b + jv[2].omega_rad_s * c,
            };
            if !pose_free {
                let (tx, ty, tt) = (t.x[d], t.y[d], t.th[d]);
                g.vx_m_s += jx[0].vx_m_s * tx + jx[1].vx_m_s * ty + jx[2].vx_m_s * tt;
                g.vy_m_s += jx[0].vy_m_s * tx + jx[1].vy_m_s * ty + jx[2].vy_m_s * tt;
                g.omega_rad_s += jx[0].omega_rad_s * tx + jx[1].omega_rad_s * ty + jx[2].omega_rad_s * tt;
            }
            (out.dvx[d], out.dvy[d], out.dw[d]) = (g.vx_m_s, g.vy_m_s, g.omega_rad_s);
        }
        for &(col, jp) in &self.jp {
            out.dvx[col] += jp.vx_m_s;
            out.dvy[col] += jp.vy_m_s;
            out.dw[col] += jp.omega_rad_s;
        }
    }

    /// The twist after the hooks and their slopes by central differences (in the twist, in the pose
    /// `x, y, θ`; the parameters' into `self.jp`).
    fn differences(&mut self, x: &mut [f64], raw: Twist2, input: &StepInput<'_>) -> (Twist2, [Twist2; 3], [Twist2; 3]) {
        let (fm, w, at) = (self.fm, input.w, input.at);
        let v = fm.twist(x, raw, w, at);
        let hv = HOOK_STEP * raw.vx_m_s.abs().max(raw.vy_m_s.abs()).max(raw.omega_rad_s.abs()).max(1e-3);
        let shifted = |i: usize, d: f64| {
            let mut v = raw;
            match i {
                0 => v.vx_m_s += d,
                1 => v.vy_m_s += d,
                _ => v.omega_rad_s += d,
            }
            v
        };
        let jv: [Twist2; 3] = std::array::from_fn(|i| {
            twist_diff(fm.twist(x, shifted(i, hv), w, at), fm.twist(x, shifted(i, -hv), w, at), 2.0 * hv)
        });
        let p = at.pose;
        let hxy = HOOK_STEP * p.x_m.abs().max(p.y_m.abs()).max(1.0);
        let hp = [hxy, hxy, HOOK_STEP];
        let moved = |i: usize, d: f64| {
            let mut a = *at;
            match i {
                0 => a.pose.x_m += d,
                1 => a.pose.y_m += d,
                _ => a.pose.theta_rad += d,
            }
            a
        };
        let jx: [Twist2; 3] = std::array::from_fn(|i| {
            twist_diff(fm.twist(x, raw, w, &moved(i, hp[i])), fm.twist(x, raw, w, &moved(i, -hp[i])), 2.0 * hp[i])
        });
        for cols in &fm.twist_columns {
            for &(g, col) in cols {
                self.jp.push((col, param_slope(x, g, |x| fm.twist(x, raw, w, at), twist_diff)));
            }
        }
        (v, jv, jx)
    }
}

/// The twist after the built-in hooks `lanes` (in order; `columns`: each one's (parameter, column)) and
/// their exact slopes ([`LaneTwist::slopes`], chained): in the twist, in the pose (the heading only), and
/// the parameters' (pushed to `jp`).
fn lane_slopes(
    lanes: &[LaneTwist],
    columns: &[Vec<(usize, usize)>],
    raw: Twist2,
    input: &StepInput<'_>,
    jp: &mut Vec<(usize, Twist2)>,
) -> (Twist2, [Twist2; 3], [Twist2; 3]) {
    let apply = |m: &[[f64; 3]; 3], v: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
    };
    let mut v = [raw.vx_m_s, raw.vy_m_s, raw.omega_rad_s];
    // d v / d raw (columns: the raw twist's components), d v / d θ.
    let mut jv = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut jth = [0.0; 3];
    let mut own: Vec<(usize, [f64; 3])> = Vec::new();
    for (e, cols) in lanes.iter().zip(columns) {
        let sl = e.slopes(v, input.cs, input.at.since_start_s);
        jv = std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| sl.jv[r][k] * jv[k][c]).sum()));
        let moved = apply(&sl.jv, jth);
        jth = std::array::from_fn(|r| moved[r] + sl.jth[r]);
        for (_, j) in own.iter_mut() {
            *j = apply(&sl.jv, *j);
        }
        own.extend(cols.iter().zip(&sl.jp[..sl.n_params]).map(|(&(_, col), j)| (col, *j)));
        v = sl.v;
    }
    let t = |a: [f64; 3]| Twist2 { vx_m_s: a[0], vy_m_s: a[1], omega_rad_s: a[2] };
    jp.extend(own.into_iter().map(|(col, j)| (col, t(j))));
    let column = |c: usize| t([jv[0][c], jv[1][c], jv[2][c]]);
    (t(v), [column(0), column(1), column(2)], [Twist2::default(), Twist2::default(), t(jth)])
}

/// The forward walk of one run (see the module docs); `None` when a step angle exceeds
/// [`MAX_STEP_ANGLE_RAD`].
/// long: the walk of [`super::general::run_errors`] with its tangents, one loop like it.
pub(crate) fn run_rows(fm: &ForwardModel<'_>, input: &RunInput<'_>) -> Option<RunRows> {
    let RunInput { res, params, run, index, plan, wheels, end_only } = *input;
    let (n_w, p) = (run.n_wheels(), fm.n_columns());
    let nik = 3 * n_w;
    let t_s = run.wheel_t_s();
    let (lag, median) = (plan.clock_lag_s, run.median_dt_s());
    let fixed = res.fixed_dt_s.unwrap_or(median);
    let truth = run.truth();
    let (sensor, arc) = (res.sensor_from_body, res.scheme == Scheme::ExactArc);
    let mut x = params.to_vec();
    let (ds, mut t) = sensor_slopes(fm, &mut x, truth[0].pose);
    let body = truth[0].pose.compose(&sensor.inverse());
    let (s, c) = body.theta_rad.sin_cos();
    let mut st = LaneState { x: body.x_m, y: body.y_m, th: body.theta_rad, c, s };
    let rows = if end_only { 1 } else { plan.queries.len() };
    let mut out = RunRows { errors: Vec::with_capacity(rows), jacobian: DMatrix::zeros(3 * rows, p) };
    let mut tw = StepTwist { v: Twist2::default(), dvx: vec![0.0; p], dvy: vec![0.0; p], dw: vec![0.0; p] };
    let (mut next_t, mut query_t) = (t.clone(), t.clone());
    let mut slopes = TwistSlopes { fm, res, lanes: lane_twists(res), jp: Vec::new() };
    // The wheel parameters' columns and their parts' runs.
    let wheel_parts: Vec<(usize, usize, &[f64])> = match &fm.wheel {
        Some((r, f)) => f
            .run_parts(index)
            .map(|(param, wheel, column)| {
                let col = nik + fm.covered.iter().position(|&g| g == r.start + param).unwrap_or(0);
                (col, wheel, column)
            })
            .collect(),
        None => Vec::new(),
    };
    let mut parts = Vec::with_capacity(wheel_parts.len());
    let mut queries = plan.queries.iter().peekable();
    for (i, f) in plan.fractions().enumerate() {
        let k = plan.first_sample + i;
        let (a_k, s_k) = interval(t_s, lag, median, k);
        let h = if res.stamps { s_k - a_k } else { fixed };
        let at =
            TwistAt { pose: Pose2::new(st.x, st.y, st.th), since_start_s: (0.5 * (a_k + s_k) - truth[0].t_s).max(0.0) };
        parts.clear();
        parts.extend(wheel_parts.iter().map(|&(col, wheel, column)| (col, wheel, column[k])));
        let input = StepInput { w: &wheels[k * n_w..(k + 1) * n_w], parts: &parts, at: &at, cs: (st.c, st.s) };
        slopes.at(&mut x, &input, &t, &mut tw);
        while let Some(q) = queries.next_if(|q| q.step == i) {
            if end_only {
                continue;
            }
            let sq = match q.fraction {
                Some(fq) => advance(arc, st, &t, &tw, fq * h, &mut query_t)?,
                None => {
                    query_t.clone_from(&t);
                    st
                }
            };
            let row = 3 * out.errors.len();
            error_rows(sq, &query_t, sensor, &ds, &truth[q.truth_index].pose, &mut out, row);
        }
        st = advance(arc, st, &t, &tw, f * h, &mut next_t)?;
        std::mem::swap(&mut t, &mut next_t);
        if i % RESYNC_STEPS == RESYNC_STEPS - 1 {
            (st.s, st.c) = st.th.sin_cos();
        }
    }
    if end_only {
        error_rows(st, &t, sensor, &ds, &truth[truth.len() - 1].pose, &mut out, 0);
    } else {
        // After the last sample: at rest.
        for q in queries {
            let row = 3 * out.errors.len();
            error_rows(st, &t, sensor, &ds, &truth[q.truth_index].pose, &mut out, row);
        }
    }
    Some(out)
}
