//! Fitting the noise model on training runs.
//!
//! 1. **Windows.** Each run is cut into consecutive, disjoint windows of motion `s = d + L φ` (distance
//!    driven plus [`TURN_LEVER_M`] per radian turned) of each length in [`FitNoiseOptions::window_m`]; the
//!    errors of disjoint windows of a random walk are independent. Several lengths let the fit tell the
//!    floor (the same at any length) from the rates (growing with it).
//! 2. **Systematic part, kept apart.** What the calibrated model still gets wrong in the same way every time
//!    is not noise: the window errors are regressed on the odometry's own displacement over the window
//!    (`e ≈ A (Δx, Δy, Δθ)`, least squares), `A` is reported ([`Systematic`]) and taken out before the
//!    noise is fitted.
//! 3. **Maximum likelihood.** The windows' errors are taken as zero-mean Gaussian with covariance
//!    `Σ_w(θ) = Σ_m θ_m B_{w,m}` ([`super::window_basis`]); `θ ≥ 0` is found by Fisher scoring from a
//!    moment fit (`e eᵀ` against `Σ_w`, least squares), with steps halved until the likelihood rises and
//!    parameters at the bound held there.
//! 4. **Uncertainty.** Each parameter's standard error is the spread of the fit over runs drawn with
//!    replacement (a seeded bootstrap), which stays honest when windows of one run are not independent.

use super::{N_PARAMS, NoiseRates, OdometryNoise, RunPoses, covariance, window_basis, window_error};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Length counted per radian turned when cutting windows. m/rad.
pub const TURN_LEVER_M: f64 = 0.25;

/// Settings of the fit.
#[derive(Clone, Debug, PartialEq)]
pub struct FitNoiseOptions {
    /// Window lengths of motion (m, with `TURN_LEVER_M` per radian). Default 0.25, 0.5, 1 and 2 m: the
    /// short ones tell the rates from the floor and carry most windows (on the simulated check of
    /// `tests/noise.rs` the rates' standard errors fell from 4–10 % with 0.5 and 2 m to 3–7 %), the long
    /// ones see how a heading error grows into position.
    pub window_m: Vec<f64>,
    /// Bootstrap resamples for the standard errors. Default 100.
    pub bootstrap: usize,
    /// Seed of the bootstrap. Default 0.
    pub seed: u64,
}

impl Default for FitNoiseOptions {
    fn default() -> Self {
        Self { window_m: vec![0.25, 0.5, 1.0, 2.0, 4.0], bootstrap: 100, seed: 0 }
    }
}

/// Why no noise model could be fitted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NoiseFitError {
    /// Too few windows for the parameters.
    #[error(
        "the runs give {windows} windows of motion, too few to fit the {params} noise parameters (need {need}): \
         record longer runs"
    )]
    TooFewWindows {
        /// Windows found.
        windows: usize,
        /// Parameters fitted.
        params: usize,
        /// Windows needed.
        need: usize,
    },
}

/// The systematic error left after calibration: the window errors' least-squares response to the
/// odometry's own displacement (rows x, y, θ of the error; columns Δx m, Δy m, Δθ rad).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Systematic {
    /// `A`, row-major.
    pub per_displacement: [[f64; 3]; 3],
    /// RMS of the systematic part of the window errors (position, m) against the RMS of the whole error.
    pub position_share: f64,
}

/// One window: its error and basis.
#[derive(Clone, Debug)]
struct Window {
    run: usize,
    error: Vector3<f64>,
    displacement: Vector3<f64>,
    basis: [Matrix3<f64>; N_PARAMS],
}

/// Consecutive disjoint windows of `length_m` of motion along `run`: pose index pairs.
pub(super) fn windows_of(run: &RunPoses, length_m: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let (mut start, mut s) = (0, 0.0);
    for k in 1..run.odometry.len() {
        let u = super::between(&run.odometry[k - 1], &run.odometry[k]);
        s += u.x_m.hypot(u.y_m) + TURN_LEVER_M * u.theta_rad.abs();
        if s >= length_m {
            out.push((start, k));
            (start, s) = (k, 0.0);
        }
    }
    out
}

fn collect_windows(runs: &[RunPoses], lengths: &[f64], holonomic: bool) -> Vec<Window> {
    let mut out = Vec::new();
    for (r, run) in runs.iter().enumerate() {
        for &len in lengths {
            for (i, j) in windows_of(run, len) {
                let p = super::between(&run.odometry[i], &run.odometry[j]);
                out.push(Window {
                    run: r,
                    error: Vector3::from(window_error(run, i, j)),
                    displacement: Vector3::new(p.x_m, p.y_m, p.theta_rad),
                    basis: window_basis(run, i, j, holonomic),
                });
            }
        }
    }
    out
}

/// The parameters a base fits: all but `strafe_per_m` for a differential drive.
fn free(holonomic: bool) -> Vec<usize> {
    (0..N_PARAMS).filter(|&m| holonomic || m != 4).collect()
}

/// Fits the noise model of an odometry on training runs (their ground truth and odometry at the same
/// stamps). `holonomic`: the base moves sideways.
pub fn fit(runs: &[RunPoses], holonomic: bool, opts: &FitNoiseOptions) -> Result<OdometryNoise, NoiseFitError> {
    let mut windows = collect_windows(runs, &opts.window_m, holonomic);
    let params = free(holonomic).len();
    let need = 3 * params;
    if windows.len() < need {
        return Err(NoiseFitError::TooFewWindows { windows: windows.len(), params, need });
    }
    let systematic = remove_systematic(&mut windows);
    let all: Vec<usize> = (0..windows.len()).collect();
    let rates = maximum_likelihood(&windows, &all, holonomic);
    let std_errors = bootstrap(&windows, runs.len(), holonomic, opts);
    Ok(OdometryNoise { holonomic, rates, std_errors, systematic, runs: runs.len(), windows: windows.len() })
}

/// Fits `A` (error against displacement), takes it out of the windows' errors and says how large it was.
fn remove_systematic(windows: &mut [Window]) -> Systematic {
    let n = windows.len();
    let x = DMatrix::from_fn(n, 3, |r, c| windows[r].displacement[c]);
    let xtx = x.transpose() * &x;
    let mut a = [[0.0; 3]; 3];
    if let Some(inv) = xtx.try_inverse() {
        for (row, out) in a.iter_mut().enumerate() {
            let y = DVector::from_fn(n, |r, _| windows[r].error[row]);
            let coef = &inv * x.transpose() * y;
            out.copy_from_slice(coef.as_slice());
        }
    }
    let am = Matrix3::from_fn(|r, c| a[r][c]);
    let (mut sys, mut whole) = (0.0, 0.0);
    for w in windows.iter_mut() {
        let part = am * w.displacement;
        sys += part[0].powi(2) + part[1].powi(2);
        whole += w.error[0].powi(2) + w.error[1].powi(2);
        w.error -= part;
    }
    let position_share = if whole > 0.0 { (sys / whole).sqrt() } else { 0.0 };
    Systematic { per_displacement: a, position_share }
}

/// Negative log-likelihood (up to a constant) of the windows `idx` under `theta`; `None` when a window's
/// covariance is not positive definite.
fn neg_log_likelihood(windows: &[Window], idx: &[usize], theta: &NoiseRates) -> Option<f64> {
    let mut total = 0.0;
    for &k in idx {
        let w = &windows[k];
        let s = covariance(&w.basis, theta);
        let chol = s.cholesky()?;
        let det = chol.l().diagonal().iter().map(|d| d.ln()).sum::<f64>() * 2.0;
        total += 0.5 * (det + w.error.dot(&chol.solve(&w.error)));
    }
    Some(total)
}

/// The moment fit: least squares of `e eᵀ` (six distinct entries) against `Σ_w`, clipped to a small
/// positive value.
fn moments(windows: &[Window], idx: &[usize], free: &[usize]) -> [f64; N_PARAMS] {
    let entries = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    let rows = idx.len() * entries.len();
    let a = DMatrix::from_fn(rows, free.len(), |r, c| {
        let (w, (i, j)) = (&windows[idx[r / entries.len()]], entries[r % entries.len()]);
        w.basis[free[c]][(i, j)]
    });
    let b = DVector::from_fn(rows, |r, _| {
        let (w, (i, j)) = (&windows[idx[r / entries.len()]], entries[r % entries.len()]);
        w.error[i] * w.error[j]
    });
    let mut theta = [0.0; N_PARAMS];
    if let Ok(sol) = a.clone().svd(true, true).solve(&b, 1e-12) {
        for (c, &m) in free.iter().enumerate() {
            theta[m] = sol[c];
        }
    }
    // A positive start: a tenth of the mean of the positive ones where the moment fit went negative.
    let pos: Vec<f64> = free.iter().map(|&m| theta[m]).filter(|v| *v > 0.0).collect();
    let fallback = if pos.is_empty() { 1e-6 } else { 0.1 * pos.iter().sum::<f64>() / pos.len() as f64 };
    for &m in free {
        if theta[m] <= 0.0 {
            theta[m] = fallback;
        }
    }
    theta
}

/// Fisher scoring iterations of the Gaussian likelihood from the moment fit.
fn maximum_likelihood(windows: &[Window], idx: &[usize], holonomic: bool) -> NoiseRates {
    let free = free(holonomic);
    let mut theta = moments(windows, idx, &free);
    let Some(mut best) = neg_log_likelihood(windows, idx, &NoiseRates::from_slice(&theta)) else {
        return NoiseRates::from_slice(&theta);
    };
    for _ in 0..50 {
        let current = NoiseRates::from_slice(&theta);
        let (score, info) = score_and_information(windows, idx, &current, &free);
        let Some(step) = info.clone().try_inverse().map(|inv| inv * &score) else { break };
        let mut t = 1.0;
        let mut moved = false;
        for _ in 0..30 {
            let mut trial = theta;
            for (c, &m) in free.iter().enumerate() {
                trial[m] = (theta[m] + t * step[c]).max(0.0);
            }
            if let Some(v) = neg_log_likelihood(windows, idx, &NoiseRates::from_slice(&trial))
                && v < best
            {
                moved = best - v > 1e-10 * best.abs().max(1.0);
                (theta, best) = (trial, v);
                break;
            }
            t *= 0.5;
        }
        if !moved {
            break;
        }
    }
    NoiseRates::from_slice(&theta)
}

/// The score `∂ℓ/∂θ_m = ½ Σ (eᵀ Σ⁻¹ B_m Σ⁻¹ e − tr Σ⁻¹ B_m)` and Fisher information
/// `½ Σ tr(Σ⁻¹ B_m Σ⁻¹ B_n)` over the free parameters.
fn score_and_information(
    windows: &[Window],
    idx: &[usize],
    theta: &NoiseRates,
    free: &[usize],
) -> (DVector<f64>, DMatrix<f64>) {
    let p = free.len();
    let (mut score, mut info) = (DVector::zeros(p), DMatrix::zeros(p, p));
    for &k in idx {
        let w = &windows[k];
        let Some(inv) = covariance(&w.basis, theta).try_inverse() else { continue };
        let se = inv * w.error;
        let sb: Vec<Matrix3<f64>> = free.iter().map(|&m| inv * w.basis[m]).collect();
        for a in 0..p {
            score[a] += 0.5 * (se.dot(&(w.basis[free[a]] * se)) - sb[a].trace());
            for b in a..p {
                // tr(X Y) = Σ X_ij Y_ji.
                let t = sb[a].component_mul(&sb[b].transpose()).sum();
                info[(a, b)] += 0.5 * t;
                if b != a {
                    info[(b, a)] += 0.5 * t;
                }
            }
        }
    }
    (score, info)
}

/// Standard errors by resampling runs with replacement.
fn bootstrap(windows: &[Window], n_runs: usize, holonomic: bool, opts: &FitNoiseOptions) -> Option<NoiseRates> {
    if opts.bootstrap < 2 || n_runs < 2 {
        return None;
    }
    let by_run: Vec<Vec<usize>> =
        (0..n_runs).map(|r| windows.iter().enumerate().filter(|(_, w)| w.run == r).map(|(k, _)| k).collect()).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let draws: Vec<Vec<usize>> = (0..opts.bootstrap)
        .map(|_| (0..n_runs).flat_map(|_| by_run[rng.random_range(0..n_runs)].iter().copied()).collect())
        .collect();
    // In parallel, collected in draw order: the same seed gives the same numbers on any thread count.
    let fits: Vec<[f64; N_PARAMS]> = draws
        .par_iter()
        .filter(|idx| idx.len() >= 3 * free(holonomic).len())
        .map(|idx| maximum_likelihood(windows, idx, holonomic).to_vec())
        .collect();
    if fits.len() < 2 {
        return None;
    }
    let mut sd = [0.0; N_PARAMS];
    for (m, out) in sd.iter_mut().enumerate() {
        let mean = fits.iter().map(|f| f[m]).sum::<f64>() / fits.len() as f64;
        let var = fits.iter().map(|f| (f[m] - mean).powi(2)).sum::<f64>() / (fits.len() - 1) as f64;
        *out = var.sqrt();
    }
    Some(NoiseRates::from_slice(&sd))
}
