//! Step 1 of the estimate (see the module docs of [`super`]): the best lag on a uniform grid, every lag
//! of the whole recording scored at once.
//!
//! For a lag `L` (wheel interval `i` paired with truth interval `j = i − L`) the score is the mean share of
//! each truth channel's sum of squares that a least-squares fit on the wheel speeds explains,
//! `Σ_c b_cᵀ G⁻¹ b_c / TSS_c` with `G = Σ u uᵀ` and `b_c = Σ u y_c` over the pairs where the truth is
//! measured. Each of these sums, as a function of `L`, is a cross-correlation of two sequences on the grid
//! (`b`: a wheel speed with a truth channel; `G`: a product of two wheel speeds with the truth's
//! "measured" mask; `TSS`: the mask of the wheel side with a squared channel; the pair count: that mask with
//! the truth's). So all lags cost a handful of FFTs (`rustfft`), `O(N log N)`, instead of a sum over the
//! overlap per lag, `O(N²)`: this ran on every recording read, and was three quarters of loading
//! (issue 44).

use super::COARSE_INTERVALS;
use super::{ClockError, MIN_COARSE_STEP_S, MIN_OVERLAP_S, Poses, WheelAngles};
use nalgebra::{DMatrix, DVector};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

pub(super) struct Coarse {
    pub offset_s: f64,
    pub step_s: f64,
}

/// The cross-correlations `c(L) = Σ_i a[i] b[i − L]` of sequences `a` (length `nw`) with `b` (length
/// `ng`) for every lag `L ∈ [−(ng − 1), nw − 1]`, by FFT.
struct Correlator {
    n_fft: usize,
    nw: usize,
    ng: usize,
    forward: std::sync::Arc<dyn rustfft::Fft<f64>>,
    inverse: std::sync::Arc<dyn rustfft::Fft<f64>>,
}

impl Correlator {
    fn new(nw: usize, ng: usize) -> Self {
        // A size with small prime factors only (rustfft is fastest there), at least nw + ng − 1 so that the
        // circular correlation holds the linear one.
        let mut n_fft = (nw + ng).next_power_of_two();
        for k in [3 * n_fft / 4, 5 * n_fft / 8] {
            if k >= nw + ng {
                n_fft = k;
            }
        }
        let mut planner = FftPlanner::new();
        Self { n_fft, nw, ng, forward: planner.plan_fft_forward(n_fft), inverse: planner.plan_fft_inverse(n_fft) }
    }

    /// The spectrum of a sequence, zero-padded.
    fn spectrum(&self, x: impl Iterator<Item = f64>) -> Vec<Complex<f64>> {
        let mut buf = vec![Complex::new(0.0, 0.0); self.n_fft];
        for (b, v) in buf.iter_mut().zip(x) {
            b.re = v;
        }
        self.forward.process(&mut buf);
        buf
    }

    /// `c(L)` for every lag from the spectra of `a` and `b`, indexed by `L + ng − 1`.
    fn correlate(&self, a: &[Complex<f64>], b: &[Complex<f64>]) -> Vec<f64> {
        let mut buf: Vec<Complex<f64>> = a.iter().zip(b).map(|(x, y)| x * y.conj()).collect();
        self.inverse.process(&mut buf);
        let scale = 1.0 / self.n_fft as f64;
        // Lag L ≥ 0 sits at index L, lag L < 0 at n_fft + L.
        (-(self.ng as i64 - 1)..self.nw as i64)
            .map(|lag| buf[lag.rem_euclid(self.n_fft as i64) as usize].re * scale)
            .collect()
    }
}

/// The best lag on the coarse grid (step 1 of the module docs).
pub(super) fn coarse(wheels: &WheelAngles<'_>, poses: &Poses<'_>) -> Result<Coarse, ClockError> {
    let (w0, w1) = (wheels.t_s[0], wheels.t_s[wheels.t_s.len() - 1]);
    let (g0, g1) = poses.span();
    let no_overlap = ClockError::NoOverlap { wheel_s: w1 - w0, truth_s: g1 - g0 };
    let h = MIN_COARSE_STEP_S.max((w1 - w0).max(g1 - g0) / COARSE_INTERVALS as f64);
    let nw = ((w1 - w0) / h).floor() as usize;
    let ng = ((g1 - g0) / h).floor() as usize;
    let n = wheels.n;
    if nw == 0 || ng == 0 {
        return Err(no_overlap);
    }
    let mut u = vec![0.0; nw * n];
    for i in 0..nw {
        let a = w0 + i as f64 * h;
        wheels.mean_rates(a, a + h, &mut u[i * n..(i + 1) * n]);
    }
    // Truth intervals inside a gap are no measurement: mask 0, left out of every lag's sums.
    let y: Vec<Option<[f64; 3]>> = (0..ng)
        .map(|j| {
            let (a, b) = (g0 + j as f64 * h, g0 + (j + 1) as f64 * h);
            poses.measured(a, b).then(|| poses.mean_twist(a, b))
        })
        .collect();
    let measured = y.iter().filter(|v| v.is_some()).count();
    let min_pairs = ((nw.min(measured)) / 2).max((MIN_OVERLAP_S / h).ceil() as usize).max(n + 1);
    if nw.min(measured) < min_pairs {
        return Err(no_overlap);
    }
    let fft = Correlator::new(nw, ng);
    let channel = |c: usize, power: i32| fft.spectrum(y.iter().map(|v| v.map_or(0.0, |v| v[c].powi(power))));
    let mask = fft.spectrum(y.iter().map(|v| if v.is_some() { 1.0 } else { 0.0 }));
    let ones = fft.spectrum(std::iter::repeat_n(1.0, nw));
    let wheel: Vec<Vec<Complex<f64>>> = (0..n).map(|r| fft.spectrum((0..nw).map(|i| u[i * n + r]))).collect();
    let pairs = fft.correlate(&ones, &mask);
    let tss: Vec<Vec<f64>> = (0..3).map(|c| fft.correlate(&ones, &channel(c, 2))).collect();
    let b: Vec<Vec<Vec<f64>>> =
        (0..3).map(|c| (0..n).map(|r| fft.correlate(&wheel[r], &channel(c, 1))).collect()).collect();
    let mut gram = vec![Vec::new(); n * n];
    for r in 0..n {
        for s in r..n {
            let product = fft.spectrum((0..nw).map(|i| u[i * n + r] * u[i * n + s]));
            gram[r * n + s] = fft.correlate(&product, &mask);
        }
    }
    // A channel's sum of squares below this is rounding (the FFT's sums are exact only to ~1e-15 of
    // the largest term), not motion.
    let tss_floor = 1e-12 * tss.iter().flatten().fold(0.0f64, |m, &v| m.max(v));
    let mut best: Option<(f64, usize)> = None;
    for (k, count) in pairs.iter().enumerate() {
        if count.round() < min_pairs as f64 {
            continue;
        }
        let g = DMatrix::from_fn(n, n, |r, s| gram[r.min(s) * n + r.max(s)][k]);
        let Some(chol) = g.cholesky() else { continue };
        let mut score = 0.0;
        for (tss_c, b_c) in tss.iter().zip(&b) {
            if tss_c[k] > tss_floor {
                let bc = DVector::from_fn(n, |r, _| b_c[r][k]);
                score += bc.dot(&chol.solve(&bc)) / tss_c[k];
            }
        }
        if best.is_none_or(|(s, _)| score > s) {
            best = Some((score, k));
        }
    }
    let Some((score, k)) = best else { return Err(no_overlap) };
    if score <= 0.0 {
        return Err(ClockError::NoMotion);
    }
    let lag = k as i64 - (ng as i64 - 1);
    Ok(Coarse { offset_s: (w0 - g0) + lag as f64 * h, step_s: h })
}
