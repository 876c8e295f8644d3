//! Costs over a set of runs.
//!
//! - End pose (the paper's Eq. 6): `CF = (1/Z) Σ_i sqrt(dx_i² + dy_i² + dθ_i²)` at each run's last
//!   ground-truth pose, metres and radians mixed with weight 1.
//! - Path: `sqrt( mean_runs mean_poses (dx² + dy² + (w dθ)²) )` over every `k`-th ground-truth pose, with
//!   `w` the heading weight in m/rad; each run counts equally whatever its length. It sees effects the end
//!   pose cannot (a clock offset when the robot rests at both ends) and constrains directions a few end
//!   poses leave free.
//!
//! Runs are evaluated in parallel (rayon) and summed sequentially in run order, so a cost is bit-identical
//! whatever the thread count.

use crate::error::KinError;
use crate::model::{Model, Resolved};
use crate::odometry::{self, Residual, Selection};
use crate::pose::PoseError;
use crate::run::Run;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which cost to compute.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "cost", rename_all = "snake_case")]
pub enum CostKind {
    /// The paper's Eq. 6: mean end-pose error.
    EndPose,
    /// RMS error over the path.
    Path {
        /// Use every `every`-th ground-truth pose (1 = all).
        every: usize,
        /// Weight of heading errors. m/rad. Default 1 (as Eq. 6).
        heading_weight_m_per_rad: f64,
    },
}

impl CostKind {
    /// The path cost's default pose step: every ground-truth pose.
    pub const PATH_EVERY: usize = 1;
    /// The path cost's default heading weight (as Eq. 6). m/rad.
    pub const PATH_HEADING_WEIGHT_M_PER_RAD: f64 = 1.0;
    /// The path cost over every pose with heading weight 1 m/rad.
    pub const PATH: CostKind =
        CostKind::Path { every: Self::PATH_EVERY, heading_weight_m_per_rad: Self::PATH_HEADING_WEIGHT_M_PER_RAD };

    /// Which cost this is, without its settings.
    pub fn cost_name(&self) -> CostName {
        match self {
            CostKind::EndPose => CostName::EndPose,
            CostKind::Path { .. } => CostName::Path,
        }
    }

    /// Short name for tables: `end_pose` or `path`.
    pub fn name(&self) -> &'static str {
        self.cost_name().id()
    }
}

/// Which cost, without its settings: what the command line's `--objective` and tables name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CostName {
    /// [`CostKind::EndPose`].
    EndPose,
    /// [`CostKind::Path`].
    Path,
}

crate::choice!(CostName, {
    EndPose => "end_pose": "The paper's Eq. 6: mean end-pose error (m and rad mixed)",
    Path => "path": "RMS error over every ground-truth pose (1 m/rad)",
});

impl CostName {
    /// The cost with these path settings (the end-pose cost has none): every `every`-th ground-truth
    /// pose, heading weighted by `heading_weight_m_per_rad` (m/rad).
    pub fn with_path_settings(self, every: usize, heading_weight_m_per_rad: f64) -> CostKind {
        match self {
            CostName::EndPose => CostKind::EndPose,
            CostName::Path => CostKind::Path { every, heading_weight_m_per_rad },
        }
    }
}

/// The end-pose error of every run (Eq. 6 terms), in run order.
pub fn end_pose_errors(res: &Resolved<'_>, runs: &[Run]) -> Vec<PoseError> {
    runs.par_iter().map(|r| odometry::end_pose_error(res, r)).collect()
}

/// Mean of the Eq. 6 terms, summed in run order.
pub fn mean_end_pose_error(errors: &[PoseError]) -> f64 {
    if errors.is_empty() {
        return 0.0;
    }
    errors.iter().map(PoseError::norm).sum::<f64>() / errors.len() as f64
}

/// Mean squared path error of one run (weighted heading), and the number of poses used.
pub fn run_path_mse(res: &Resolved<'_>, run: &Run, every: usize, heading_weight: f64) -> f64 {
    let r = odometry::residuals(res, run, Selection::Path(every));
    let sum: f64 = r
        .iter()
        .map(|e| {
            let th = heading_weight * e.error.dtheta_rad;
            e.error.dx_m * e.error.dx_m + e.error.dy_m * e.error.dy_m + th * th
        })
        .sum();
    sum / r.len().max(1) as f64
}

/// One run's path RMS from its residuals: `sqrt(mean |e|²)` over the poses, with `|e|² = dx² + dy² + dθ²`
/// (heading 1 m/rad). m. 0 without residuals. What diagnosis and Python report per run.
pub fn path_rms(residuals: &[Residual]) -> f64 {
    (residuals.iter().map(|e| e.error.norm().powi(2)).sum::<f64>() / residuals.len().max(1) as f64).sqrt()
}

/// The cost of a resolved model over runs.
pub fn cost_resolved(res: &Resolved<'_>, runs: &[Run], kind: CostKind) -> f64 {
    match kind {
        CostKind::EndPose => mean_end_pose_error(&end_pose_errors(res, runs)),
        CostKind::Path { every, heading_weight_m_per_rad } => {
            let per: Vec<f64> =
                runs.par_iter().map(|r| run_path_mse(res, r, every, heading_weight_m_per_rad)).collect();
            if per.is_empty() {
                return 0.0;
            }
            (per.iter().sum::<f64>() / per.len() as f64).sqrt()
        }
    }
}

/// The cost of `model` at `params` over `runs`. Checks wheel counts once.
pub fn cost(model: &Model, params: &[f64], runs: &[Run], kind: CostKind) -> Result<f64, KinError> {
    check_runs(model, runs)?;
    let res = model.resolve(params)?;
    Ok(cost_resolved(&res, runs, kind))
}

/// Checks that every run has the model's wheel count.
pub fn check_runs(model: &Model, runs: &[Run]) -> Result<(), KinError> {
    for r in runs {
        if r.n_wheels() != model.n_wheels() {
            return Err(KinError::WheelCount { run: r.name().into(), got: r.n_wheels(), expected: model.n_wheels() });
        }
    }
    Ok(())
}

/// Stacked residual vector whose squared norm is the squared path cost (or, for `EndPose`, the mean
/// squared end-pose error): what least-squares solvers minimise. Per run, in run order: `(dx, dy, w dθ)`
/// for each selected pose, scaled by `1/sqrt(n_runs · n_poses)`.
pub fn residual_vector(res: &Resolved<'_>, runs: &[Run], kind: CostKind) -> Vec<f64> {
    let (sel, w) = match kind {
        CostKind::EndPose => (Selection::End, 1.0),
        CostKind::Path { every, heading_weight_m_per_rad } => (Selection::Path(every), heading_weight_m_per_rad),
    };
    let n_runs = runs.len().max(1) as f64;
    let per: Vec<Vec<f64>> = runs
        .par_iter()
        .map(|r| {
            let e = odometry::residuals(res, r, sel);
            let scale = 1.0 / (n_runs * e.len().max(1) as f64).sqrt();
            e.iter()
                .flat_map(|e| [e.error.dx_m * scale, e.error.dy_m * scale, w * e.error.dtheta_rad * scale])
                .collect()
        })
        .collect();
    per.concat()
}
