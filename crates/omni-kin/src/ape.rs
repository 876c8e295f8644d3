//! Absolute pose error (APE) as evo's `evo_ape` computes it, translation part: how far the model's
//! odometry is from the ground truth at each ground-truth sample, in metres.
//!
//! `evo_ape tum REF EST` (evo 1.x) with its defaults:
//! - **association**: each reference stamp is matched to the nearest estimate stamp within 0.01 s
//!   (`--t_max_diff`, no `--t_offset`); the exported TUM estimate holds a pose at every ground-truth stamp,
//!   so every ground-truth sample is matched, the first (where odometry starts: error 0) included;
//! - **pose relation** `trans_part`: the error of pose `i` is `|t(Q_i) − t(P_i)|`;
//! - **alignment**: none by default; with `--align` (`-a`), the estimate is first moved by the rigid
//!   transform (rotation and translation, no scale) that minimises the sum of squared position errors
//!   (Umeyama 1991), computed in 3D. On planar poses the 3D rotation may be a half turn about an axis in
//!   the plane, which acts on the plane as a mirror: the in-plane part is the nearest orthogonal matrix
//!   `U Vᵀ` of the 2 × 2 cross-covariance `C = Σ (q_i − q̄)(p_i − p̄)ᵀ = U Σ Vᵀ`, reflection allowed, as
//!   here;
//! - **statistics**: evo prints max, mean, median, min, rmse, sse and std; `rmse` is its headline.
//!
//! Over several runs each run is aligned on its own and the statistics pool every pose (a long run counts
//! more), as `evo_res` does over results.
//!
//! Plain data: no I/O. The odometry at the ground-truth stamps is read off the evaluator's errors at every
//! pose ([`crate::odometry::Selection::Path`]`(1)`), as [`crate::relative`] does.

use crate::error::KinError;
use crate::evaluate::RunErrors;
use crate::pose::Pose2;
use crate::relative::estimates_at_truth;
use crate::run::Run;
use crate::stats::Stats;
use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

/// A rigid planar alignment `p ↦ R p + t` (`R` orthogonal, possibly a mirror; see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alignment {
    /// `R`, row-major.
    pub rotation: [[f64; 2]; 2],
    /// `t`. m.
    pub translation_m: [f64; 2],
}

impl Alignment {
    /// No change.
    pub const IDENTITY: Alignment = Alignment { rotation: [[1.0, 0.0], [0.0, 1.0]], translation_m: [0.0, 0.0] };

    /// The least-squares alignment of `estimate`'s positions onto `reference`'s (same length, pose by pose):
    /// evo's `--align` (Umeyama, no scale). Identity for fewer than two poses or a degenerate spread.
    pub fn umeyama(reference: &[Pose2], estimate: &[Pose2]) -> Self {
        let n = reference.len().min(estimate.len());
        if n < 2 {
            return Self::IDENTITY;
        }
        let xy = |p: &Pose2| Vector2::new(p.x_m, p.y_m);
        let mean = |ps: &[Pose2]| ps[..n].iter().map(xy).fold(Vector2::zeros(), |a, b| a + b) / n as f64;
        let (mq, mp) = (mean(reference), mean(estimate));
        let c = reference[..n]
            .iter()
            .zip(&estimate[..n])
            .fold(Matrix2::zeros(), |acc, (q, p)| acc + (xy(q) - mq) * (xy(p) - mp).transpose());
        let svd = c.svd(true, true);
        let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else { return Self::IDENTITY };
        if svd.singular_values[0] <= 0.0 {
            return Self::IDENTITY;
        }
        let r = u * v_t;
        let t = mq - r * mp;
        Self { rotation: [[r[(0, 0)], r[(0, 1)]], [r[(1, 0)], r[(1, 1)]]], translation_m: [t[0], t[1]] }
    }

    /// The position of `p` moved by the alignment. m.
    pub fn apply(&self, p: &Pose2) -> [f64; 2] {
        let [[a, b], [c, d]] = self.rotation;
        [a * p.x_m + b * p.y_m + self.translation_m[0], c * p.x_m + d * p.y_m + self.translation_m[1]]
    }
}

/// Position error of each pose, `|t(Q_i) − t(A P_i)|` with `A` the alignment. m.
pub fn translation_errors(reference: &[Pose2], estimate: &[Pose2], alignment: &Alignment) -> Vec<f64> {
    reference
        .iter()
        .zip(estimate)
        .map(|(q, p)| {
            let [x, y] = alignment.apply(p);
            (q.x_m - x).hypot(q.y_m - y)
        })
        .collect()
}

/// One run's translation errors at every ground-truth sample, without and with alignment. m.
#[derive(Clone, Debug, PartialEq)]
pub struct RunApe {
    /// `evo_ape tum REF EST` (no alignment).
    pub unaligned_m: Vec<f64>,
    /// `evo_ape tum REF EST --align`.
    pub aligned_m: Vec<f64>,
}

/// Statistics of the translation APE of one run or of all.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ApeSummary {
    /// Poses compared.
    pub poses: usize,
    /// Without alignment (evo_ape's default). m.
    pub translation_m: Stats,
    /// After evo's `--align`. m.
    pub aligned_translation_m: Stats,
}

impl ApeSummary {
    fn of<'a>(runs: impl IntoIterator<Item = &'a RunApe> + Clone) -> Self {
        let unaligned = runs.clone().into_iter().flat_map(|r| r.unaligned_m.iter().copied());
        Self {
            poses: runs.clone().into_iter().map(|r| r.unaligned_m.len()).sum(),
            translation_m: Stats::of(unaligned),
            aligned_translation_m: Stats::of(runs.into_iter().flat_map(|r| r.aligned_m.iter().copied())),
        }
    }
}

/// The translation APE of every run, in run order.
#[derive(Clone, Debug, PartialEq)]
pub struct AbsoluteErrors {
    runs: Vec<RunApe>,
}

impl AbsoluteErrors {
    /// The APE of `runs` from their errors at every ground-truth pose after the first (`errors` from an
    /// evaluator at [`crate::odometry::Selection::Path`]`(1)`, in run order); errors at other poses are
    /// refused, naming the run.
    pub fn new(runs: &[Run], errors: &RunErrors) -> Result<Self, KinError> {
        let each = runs
            .iter()
            .zip(estimates_at_truth(runs, errors)?)
            .map(|(r, estimate)| {
                let reference: Vec<Pose2> = r.truth().iter().map(|s| s.pose).collect();
                RunApe {
                    unaligned_m: translation_errors(&reference, &estimate, &Alignment::IDENTITY),
                    aligned_m: translation_errors(&reference, &estimate, &Alignment::umeyama(&reference, &estimate)),
                }
            })
            .collect();
        Ok(Self { runs: each })
    }

    /// Run `i`'s errors.
    pub fn run(&self, i: usize) -> &RunApe {
        &self.runs[i]
    }

    /// Run `i`'s statistics.
    pub fn run_summary(&self, i: usize) -> ApeSummary {
        ApeSummary::of(std::slice::from_ref(&self.runs[i]))
    }

    /// The statistics of every pose of every run (each run aligned on its own).
    pub fn summary(&self) -> ApeSummary {
        ApeSummary::of(&self.runs)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn square(scale: f64, turn_rad: f64, shift: [f64; 2]) -> Vec<Pose2> {
        let (s, c) = turn_rad.sin_cos();
        [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.5, 0.2)]
            .iter()
            .map(|&(x, y)| {
                let (x, y) = (scale * x, scale * y);
                Pose2::new(c * x - s * y + shift[0], s * x + c * y + shift[1], 0.0)
            })
            .collect()
    }

    #[test]
    fn a_turned_and_shifted_copy_aligns_exactly() {
        let q = square(1.0, 0.0, [0.0, 0.0]);
        let p = square(1.0, 0.7, [2.0, -1.0]);
        let a = Alignment::umeyama(&q, &p);
        assert!(translation_errors(&q, &p, &a).iter().all(|e| *e < 1e-12));
        let unaligned = translation_errors(&q, &p, &Alignment::IDENTITY);
        assert!(unaligned.iter().all(|e| *e > 0.5), "{unaligned:?}");
        // A mirror image is aligned too (a half turn out of the plane, as evo's 3D Umeyama).
        let mirrored: Vec<Pose2> = q.iter().map(|p| Pose2::new(p.x_m, -p.y_m, 0.0)).collect();
        let m = Alignment::umeyama(&q, &mirrored);
        assert!(translation_errors(&q, &mirrored, &m).iter().all(|e| *e < 1e-12));
    }

    #[test]
    fn alignment_does_not_scale() {
        // A copy 10 % larger: the best rigid fit leaves the scale error, centred.
        let q = square(1.0, 0.0, [0.0, 0.0]);
        let p = square(1.1, 0.0, [0.0, 0.0]);
        let a = Alignment::umeyama(&q, &p);
        let e = translation_errors(&q, &p, &a);
        let mean = Pose2::new(0.5, 0.44, 0.0);
        for (qi, ei) in q.iter().zip(&e) {
            let want = 0.1 * (qi.x_m - mean.x_m).hypot(qi.y_m - mean.y_m);
            assert!((ei - want).abs() < 1e-12, "{ei} vs {want}");
        }
    }
}
