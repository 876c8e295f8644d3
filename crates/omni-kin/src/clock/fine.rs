//! Step 2 and 3 of the estimate (see the module docs of [`super`]): the offset refined as a continuous
//! parameter on the truth's own sample blocks, and its Gauss–Newton standard error.

use super::{FINE_BLOCK_S, MIN_BLOCK_SAMPLES, Poses, STILL_CHANNEL_SHARE, WheelAngles};
use nalgebra::DMatrix;

/// The fine objective over the ground truth's own sample intervals whose shifted copies stay inside the wheel
/// data for every offset in the search bracket (so the set is the same for all of them). The targets (the
/// truth's body velocities, with its noise) stay fixed; the offset moves the wheel side, whose angle is
/// piecewise linear between samples *exactly* (speeds are interval means), so the truth's noise adds the
/// same amount to the residual at every offset instead of one that varies with where the interpolation
/// falls between its samples.
pub(super) struct Fine<'a> {
    wheels: &'a WheelAngles<'a>,
    /// Truth intervals `[start, end]` on the truth's clock. s.
    intervals: Vec<(f64, f64)>,
    /// Targets, one row per interval: mean body velocity `(v_x, v_y, ω)`.
    y: DMatrix<f64>,
    /// `1 / TSS_c` per channel (0 for a channel without motion).
    weights: [f64; 3],
}

/// One least-squares fit at an offset.
pub(super) struct Fit {
    /// `Σ_c RSS_c / TSS_c`.
    pub normalised_rss: f64,
    /// The fitted map, n × 3 (wheel speeds → body velocity, one column per channel).
    pub beta: DMatrix<f64>,
    /// Channels with motion.
    pub channels: usize,
}

impl<'a> Fine<'a> {
    pub(super) fn new(wheels: &'a WheelAngles<'a>, poses: &Poses<'_>, lo: f64, hi: f64) -> Option<Self> {
        let t = wheels.t_s;
        let (w0, w1) = (t[0], t[t.len() - 1]);
        let p = poses.poses;
        // Blocks of consecutive truth samples spanning about FINE_BLOCK_S: the truth's noise, differenced,
        // shrinks with the block's length while the motion stays resolved. None across a gap.
        // At least MIN_BLOCK_SAMPLES intervals per block, unless that leaves too few blocks to fit (a sparse,
        // short reference keeps its single intervals).
        let m = ((FINE_BLOCK_S / poses.median_dt_s).round() as usize).max(1);
        let blocks = |m: usize| -> Vec<(f64, f64)> {
            (0..(p.len() - 1) / m)
                .map(|j| (p[j * m].t_s, p[(j + 1) * m].t_s))
                .filter(|&(a, b)| a + lo >= w0 && b + hi <= w1 && poses.measured(a, b))
                .collect()
        };
        let enough = |v: &Vec<(f64, f64)>| v.len() > 3 * wheels.n;
        let intervals = Some(blocks(m.max(MIN_BLOCK_SAMPLES))).filter(enough).or_else(|| Some(blocks(m)))?;
        if !enough(&intervals) {
            return None;
        }
        let mut y = DMatrix::zeros(intervals.len(), 3);
        for (r, &(a, b)) in intervals.iter().enumerate() {
            let v = poses.mean_twist(a, b);
            for c in 0..3 {
                y[(r, c)] = v[c];
            }
        }
        let tss: [f64; 3] = std::array::from_fn(|c| y.column(c).norm_squared());
        let mut weights = [0.0; 3];
        for (c, w) in weights.iter_mut().enumerate() {
            // A direction the base does not move in (a differential drive's v_y: the truth's noise, or
            // far less than its motion the other way) has nothing an offset could explain; scoring it
            // would cap the explained share of a diff robot at two thirds.
            let still = c < 2 && tss[c] < STILL_CHANNEL_SHARE * tss[1 - c];
            if tss[c] > 0.0 && !still {
                *w = 1.0 / tss[c];
            }
        }
        weights.iter().any(|&w| w > 0.0).then_some(Self { wheels, intervals, y, weights })
    }

    pub(super) fn overlap_s(&self) -> f64 {
        match (self.intervals.first(), self.intervals.last()) {
            (Some(a), Some(b)) => b.1 - a.0,
            _ => 0.0,
        }
    }

    /// The regressors at `offset`: the mean wheel speeds over each truth interval moved onto the wheel clock.
    fn regressors(&self, offset: f64) -> DMatrix<f64> {
        let n = self.wheels.n;
        let mut u = DMatrix::zeros(self.intervals.len(), n);
        let mut row = vec![0.0; n];
        for (r, &(a, b)) in self.intervals.iter().enumerate() {
            self.wheels.mean_rates(a + offset, b + offset, &mut row);
            for (w, v) in row.iter().enumerate() {
                u[(r, w)] = *v;
            }
        }
        u
    }

    pub(super) fn fit(&self, offset: f64) -> Option<Fit> {
        let u = self.regressors(offset);
        // Normal equations: n is a handful of wheels and the speeds are well scaled.
        let beta = (u.transpose() * &u).cholesky()?.solve(&(u.transpose() * &self.y));
        let res = &self.y - &u * &beta;
        let mut normalised_rss = 0.0;
        for c in 0..3 {
            normalised_rss += self.weights[c] * res.column(c).norm_squared();
        }
        let channels = self.weights.iter().filter(|&&w| w > 0.0).count();
        Some(Fit { normalised_rss, beta, channels })
    }

    /// Golden-section search of the normalised residual on `[lo, hi]`.
    pub(super) fn minimise(&self, mut lo: f64, mut hi: f64) -> f64 {
        const INV_PHI: f64 = 0.618_033_988_749_895;
        let f = |x: f64| self.fit(x).map_or(f64::INFINITY, |fit| fit.normalised_rss);
        let (mut a, mut b) = (hi - INV_PHI * (hi - lo), lo + INV_PHI * (hi - lo));
        let (mut fa, mut fb) = (f(a), f(b));
        while hi - lo > 1e-6 {
            if fa < fb {
                hi = b;
                (b, fb) = (a, fa);
                a = hi - INV_PHI * (hi - lo);
                fa = f(a);
            } else {
                lo = a;
                (a, fa) = (b, fb);
                b = lo + INV_PHI * (hi - lo);
                fb = f(b);
            }
        }
        0.5 * (lo + hi)
    }

    /// Gauss–Newton standard error of the offset at `offset`: the prediction's derivative `(∂U/∂offset) β`,
    /// projected off the regressors' span, against the residual variance.
    pub(super) fn std_error(&self, offset: f64, fit: &Fit) -> f64 {
        const DELTA_S: f64 = 1e-4;
        let u = self.regressors(offset);
        let du = (self.regressors(offset + DELTA_S) - self.regressors(offset - DELTA_S)) / (2.0 * DELTA_S);
        let d = &du * &fit.beta;
        let q = u.qr().q();
        let d_perp = &d - &q * (q.transpose() * &d);
        let curvature: f64 = (0..3).map(|c| self.weights[c] * d_perp.column(c).norm_squared()).sum();
        let dof = (3 * self.intervals.len()).saturating_sub(3 * self.wheels.n + 1).max(1) as f64;
        (fit.normalised_rss / dof / curvature).sqrt()
    }
}
