//! How far to trust the odometry along the figure runs (issue 46, "seen, not only read"): each run's
//! ground truth, the fitted model's odometry, the distance driven, the position error and the noise
//! model's covariance of it at every ground-truth pose ([`omni_kin::noise::path_bases`], built step by
//! step along the run).

use omni_kin::evaluate::RunErrors;
use omni_kin::noise::{self, OdometryNoise};
use omni_kin::{KinError, Run};
use serde::Serialize;

/// χ² of 2 degrees of freedom at 95 %: a 2D position error lies inside `x Σ⁻¹ x ≤ 5.991` 95 % of the time.
pub const CHI2_2D_95: f64 = 5.991_464_547_107_979;

/// One run seen through the noise model.
#[derive(Clone, Debug, Serialize)]
pub struct TrustRun {
    /// The run's name.
    pub name: String,
    /// Ground truth positions (world frame). m.
    pub truth_xy_m: Vec<[f64; 2]>,
    /// The model's odometry at the same stamps, from the first ground-truth pose. m.
    pub odometry_xy_m: Vec<[f64; 2]>,
    /// Distance the ground truth has driven. m.
    pub distance_m: Vec<f64>,
    /// Position error |odometry − truth|. m.
    pub error_m: Vec<f64>,
    /// The noise model's position covariance of the error, world frame (xx, xy, yy). m².
    pub covariance_m2: Vec<[f64; 3]>,
}

impl TrustRun {
    /// The radius within which the error lies with 95 % probability along the ellipse's longest axis. m.
    pub fn radius_95_m(&self, k: usize) -> f64 {
        let [xx, xy, yy] = self.covariance_m2[k];
        let largest = 0.5 * (xx + yy) + (0.25 * (xx - yy).powi(2) + xy * xy).sqrt();
        (CHI2_2D_95 * largest.max(0.0)).sqrt()
    }

    /// Share of the run's poses whose error lies inside the 95 % ellipse.
    pub fn inside_share(&self) -> f64 {
        let inside = (0..self.error_m.len())
            .filter(|&k| {
                let [xx, xy, yy] = self.covariance_m2[k];
                let (ex, ey) = (
                    self.odometry_xy_m[k][0] - self.truth_xy_m[k][0],
                    self.odometry_xy_m[k][1] - self.truth_xy_m[k][1],
                );
                let det = xx * yy - xy * xy;
                det > 0.0 && (yy * ex * ex - 2.0 * xy * ex * ey + xx * ey * ey) / det <= CHI2_2D_95
            })
            .count();
        inside as f64 / self.error_m.len().max(1) as f64
    }
}

/// The noise model along every figure run.
#[derive(Clone, Debug, Serialize)]
pub struct Trust {
    /// Per run.
    pub runs: Vec<TrustRun>,
}

/// A model's odometry on `runs`, from its `errors` at every ground-truth pose (the report's, at
/// [`omni_kin::odometry::Selection::Path`]`(1)`), with the noise model `n` `train` fitted with it.
pub fn trust(runs: &[Run], errors: &RunErrors, n: &OdometryNoise) -> Result<Trust, KinError> {
    let poses = noise::run_poses(runs, errors)?;
    let mut out = Vec::with_capacity(runs.len());
    for (run, p) in runs.iter().zip(&poses) {
        let len = p.truth.len().min(p.odometry.len());
        if len < 2 {
            continue;
        }
        let bases = noise::path_bases(p, 0, n.holonomic);
        // The bases are in the frame of the odometry's first pose: turned into the world's.
        let (s, c) = p.odometry[0].theta_rad.sin_cos();
        let mut distance = 0.0;
        let mut t = TrustRun {
            name: run.name().to_string(),
            truth_xy_m: Vec::with_capacity(len),
            odometry_xy_m: Vec::with_capacity(len),
            distance_m: Vec::with_capacity(len),
            error_m: Vec::with_capacity(len),
            covariance_m2: Vec::with_capacity(len),
        };
        for k in 1..len {
            let (a, b) = (p.truth[k - 1], p.truth[k]);
            distance += (b.x_m - a.x_m).hypot(b.y_m - a.y_m);
            let cov = noise::covariance(&bases[k - 1], &n.rates);
            let (xx, xy, yy) = (cov[(0, 0)], cov[(0, 1)], cov[(1, 1)]);
            // R Σ Rᵀ for the 2 × 2 position block.
            let wxx = c * c * xx - 2.0 * c * s * xy + s * s * yy;
            let wyy = s * s * xx + 2.0 * c * s * xy + c * c * yy;
            let wxy = c * s * (xx - yy) + (c * c - s * s) * xy;
            let (o, g) = (p.odometry[k], p.truth[k]);
            t.truth_xy_m.push([g.x_m, g.y_m]);
            t.odometry_xy_m.push([o.x_m, o.y_m]);
            t.distance_m.push(distance);
            t.error_m.push((o.x_m - g.x_m).hypot(o.y_m - g.y_m));
            t.covariance_m2.push([wxx, wxy, wyy]);
        }
        out.push(t);
    }
    Ok(Trust { runs: out })
}
