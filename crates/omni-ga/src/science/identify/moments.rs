//! The residuals' moments, from which the covariance is made: `JᵀJ` and each cluster's score `J_gᵀ r_g`,
//! the clusters being runs or, when the runs are too few, segments of them cut by time (at least
//! [`MIN_SEGMENT_S`] each); and the standard errors of a free subset of columns from them.

use super::CovarianceKind;
use super::analysis;
use nalgebra::{DMatrix, DVector};

/// Shortest segment a run is cut into for the per-run standard errors when the runs are too few. s.
/// 5 s: several ground-truth poses at any rate, and long enough that most of a segment's error is its own.
pub const MIN_SEGMENT_S: f64 = 5.0;

/// How to cut each run's ground-truth poses into clusters for the per-run standard errors of `n_params`
/// parameters: one cluster per run when there are at least `n_params + 2` runs; otherwise each run (its
/// poses' times `pose_times_s`, one slice per run) is cut into as many consecutive pieces of at least
/// [`MIN_SEGMENT_S`] as it holds (at least one, each at least two poses). Returns each run's pose count per
/// segment, in order.
pub fn segment_poses(pose_times_s: &[Vec<f64>], n_params: usize) -> Vec<Vec<usize>> {
    let whole = |t: &Vec<f64>| vec![t.len()];
    if pose_times_s.len() >= n_params + 2 {
        return pose_times_s.iter().map(whole).collect();
    }
    pose_times_s
        .iter()
        .map(|t| {
            let span = match (t.first(), t.last()) {
                (Some(a), Some(b)) => b - a,
                _ => 0.0,
            };
            let k = ((span / MIN_SEGMENT_S).floor() as usize).clamp(1, (t.len() / 2).max(1));
            if k == 1 {
                return whole(t);
            }
            // Pose i belongs to segment ⌊k (t_i − t_0) / span⌋ (the last pose to the last segment).
            let mut counts = vec![0usize; k];
            for &ti in t {
                let s = ((k as f64 * (ti - t[0]) / span) as usize).min(k - 1);
                counts[s] += 1;
            }
            counts.retain(|&c| c > 0);
            counts
        })
        .collect()
}

/// Residual rows per ground-truth pose: x, y, heading.
pub const ROWS_PER_POSE: usize = 3;
/// Share of a segment's last poses whose mean residual anchors the next segment (see
/// [`Moments::add_run_segments`]): an average, so one pose's measurement noise does not count twice.
pub const ANCHOR_SHARE: f64 = 0.1;

/// The row ranges `[start, end)` of consecutive segments of `rows` residual rows: `segment_rows` each (cut
/// to what is left), then the rest if any; empty segments dropped.
fn segment_bounds(rows: usize, segment_rows: &[usize]) -> Vec<(usize, usize)> {
    let mut out = Vec::with_capacity(segment_rows.len() + 1);
    let mut start = 0;
    for &k in segment_rows.iter().chain(std::iter::once(&usize::MAX)) {
        let end = start + k.min(rows - start);
        if end > start {
            out.push((start, end));
        }
        start = end;
    }
    out
}

/// The anchor of segment `g`: 0 for the first; else the mean residual, per component, over the last
/// [`ANCHOR_SHARE`] of segment `g − 1`'s poses (at least one).
fn anchor(r: &[f64], bounds: &[(usize, usize)], g: usize) -> [f64; ROWS_PER_POSE] {
    let mut a = [0.0; ROWS_PER_POSE];
    let Some(&(start, end)) = g.checked_sub(1).and_then(|p| bounds.get(p)) else { return a };
    let poses = (end - start) / ROWS_PER_POSE;
    let m = ((poses as f64 * ANCHOR_SHARE).ceil() as usize).clamp(1, poses.max(1));
    let first = end.saturating_sub(m * ROWS_PER_POSE).max(start);
    for row in first..end {
        a[row % ROWS_PER_POSE] += r[row];
    }
    let count = ((end - first) / ROWS_PER_POSE).max(1) as f64;
    a.iter_mut().for_each(|v| *v /= count);
    a
}

/// What the analysis needs from the residuals `r` and their Jacobian `J`, accumulated run by run so the
/// full Jacobian never has to be held: `JᵀJ`, each cluster's score `J_gᵀ r_g`, `rᵀr` and the row count.
#[derive(Clone, Debug)]
pub struct Moments {
    /// `JᵀJ` (parameter units).
    pub jtj: DMatrix<f64>,
    /// Per cluster (a run, or a segment of one: [`Moments::add_run_segments`]), `J_gᵀ r_g`.
    pub scores: Vec<DVector<f64>>,
    /// Runs added.
    pub runs: usize,
    /// `rᵀr`.
    pub rtr: f64,
    /// Residual rows.
    pub rows: usize,
    /// Every entry seen was finite.
    pub finite: bool,
}

impl Moments {
    /// Empty, for `n` parameters.
    pub fn new(n: usize) -> Self {
        Self { jtj: DMatrix::zeros(n, n), scores: Vec::new(), runs: 0, rtr: 0.0, rows: 0, finite: true }
    }

    /// Add one run's Jacobian rows and residuals (one cluster).
    pub fn add_run(&mut self, j: &DMatrix<f64>, r: &[f64]) {
        self.add_run_segments(j, r, &[r.len()]);
    }

    /// Add one run's Jacobian rows and residuals as consecutive clusters (segments) of `segment_rows` rows
    /// each, whole ground-truth poses ([`ROWS_PER_POSE`] rows per pose); the rest of the rows, if any, form
    /// one more.
    ///
    /// A path residual is the error accumulated since the run started, so raw segment scores `J_gᵀ r_g` of
    /// one run share every earlier segment's error: as clusters they give standard errors about 2× too
    /// small. Each segment's score here counts what its own motion adds instead (summation by parts): its
    /// residuals measured from its anchor `a_g` (the mean residual over the last [`ANCHOR_SHARE`] of the
    /// previous segment's poses; 0 for the first), plus the change of anchor it causes, `a_{g+1} − a_g`,
    /// times the Jacobian rows of every later pose. The segments' scores sum to the run's score `Jᵀ r`
    /// exactly, whatever the anchors.
    pub fn add_run_segments(&mut self, j: &DMatrix<f64>, r: &[f64], segment_rows: &[usize]) {
        self.finite &= j.iter().all(|v| v.is_finite()) && r.iter().all(|v| v.is_finite());
        if !self.finite {
            return;
        }
        self.runs += 1;
        self.jtj += j.transpose() * j;
        self.rtr += r.iter().map(|v| v * v).sum::<f64>();
        self.rows += r.len();
        let bounds = segment_bounds(r.len(), segment_rows);
        if bounds.len() <= 1 {
            self.scores.push(j.transpose() * DVector::from_column_slice(r));
            return;
        }
        let anchors: Vec<[f64; ROWS_PER_POSE]> = (0..=bounds.len()).map(|g| anchor(r, &bounds, g)).collect();
        // Jacobian rows summed per residual component over every pose after each segment.
        let mut after = vec![DMatrix::zeros(ROWS_PER_POSE, j.ncols()); bounds.len()];
        for g in (0..bounds.len() - 1).rev() {
            let (next_start, next_end) = bounds[g + 1];
            let mut sum = after[g + 1].clone();
            for row in next_start..next_end {
                let mut target = sum.row_mut(row % ROWS_PER_POSE);
                target += j.row(row);
            }
            after[g] = sum;
        }
        for (g, &(start, end)) in bounds.iter().enumerate() {
            let local = DVector::from_fn(end - start, |i, _| r[start + i] - anchors[g][(start + i) % ROWS_PER_POSE]);
            let mut score = j.rows(start, end - start).transpose() * local;
            if g + 1 < bounds.len() {
                let step = DVector::from_fn(ROWS_PER_POSE, |c, _| anchors[g + 1][c] - anchors[g][c]);
                score += after[g].transpose() * step;
            }
            self.scores.push(score);
        }
    }

    /// From a stacked Jacobian and residuals; `run_rows[g]` rows per run, in order.
    pub fn from_dense(j: &DMatrix<f64>, r: &[f64], run_rows: &[usize]) -> Self {
        let mut m = Self::new(j.ncols());
        let mut row = 0;
        for &k in run_rows {
            let k = k.min(j.nrows().saturating_sub(row)).min(r.len().saturating_sub(row));
            m.add_run(&j.rows(row, k).into_owned(), &r[row..row + k]);
            row += k;
        }
        m
    }
}

/// Each column's standard error from the residuals' [`Moments`] (parameter units; NaN where the runs do
/// not determine it): the covariance [`analyse`](super::analyse) uses — the per-run sandwich
/// `B (Σ_g s_g s_gᵀ) B · G/(G − 1) · (m − 1)/(m − p)` with `B = (JᵀJ)⁺` and `s_g = J_gᵀ r_g`, or `s² B`
/// with fewer than `p + 2` runs — without [`analyse`](super::analyse)'s naming of weak directions, for fits whose columns
/// are not a [`Model`](omni_kin::Model)'s parameters (the explorer's free subset). `rcond`: relative singular value of the
/// column-normalised Jacobian below which a direction is dropped; a column whose normalised `B` entry
/// exceeds 1e6 is undetermined.
pub fn column_std_errors(moments: &Moments, rcond: f64) -> Vec<f64> {
    let n = moments.jtj.ncols();
    let noise = analysis::Noise::new(Some(moments), n);
    // Normalise the columns (d_k = ‖J_k‖) so the pseudo-inverse's tolerance is relative to each column.
    let d: Vec<f64> =
        (0..n).map(|k| moments.jtj[(k, k)].sqrt()).map(|v| if v > 0.0 && v.is_finite() { v } else { 1.0 }).collect();
    let jtj = DMatrix::from_fn(n, n, |a, b| moments.jtj[(a, b)] / (d[a] * d[b]));
    if !moments.finite || !jtj.iter().all(|v| v.is_finite()) {
        return vec![f64::NAN; n];
    }
    let Ok(b) = jtj.clone().pseudo_inverse(rcond * rcond * jtj.norm()) else {
        return vec![f64::NAN; n];
    };
    let v = match noise.kind {
        CovarianceKind::PerRun => {
            let mut meat = DMatrix::zeros(n, n);
            for s in &moments.scores {
                let s = DVector::from_fn(n, |k, _| s[k] / d[k]);
                meat += &s * s.transpose();
            }
            &b * meat * &b * noise.cr1
        }
        CovarianceKind::Iid | CovarianceKind::Stated => &b * noise.s2,
    };
    (0..n)
        .map(|k| {
            let var = v[(k, k)];
            if b[(k, k)] > 1e6 || !var.is_finite() { f64::NAN } else { var.max(0.0).sqrt() / d[k] }
        })
        .collect()
}
