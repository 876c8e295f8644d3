//! Costs over a set of runs.
//!
//! - End pose (the paper's Eq. 6): `CF = (1/Z) Σ_i sqrt(dx_i² + dy_i² + dθ_i²)` at each run's last
//!   ground-truth pose, metres and radians mixed with weight 1.
//! - Path: `sqrt( mean_runs mean_poses (dx² + dy² + (w dθ)²) )` over every `k`-th ground-truth pose, with
//!   `w` the heading weight in m/rad; each run counts equally whatever its length. It sees effects the end
//!   pose cannot (a clock offset when the robot rests at both ends) and constrains directions a few end
//!   poses leave free.
//!
//! The errors come from the [`Evaluator`], which also aggregates them ([`crate::evaluate::RunErrors`]).

use crate::error::KinError;
use crate::evaluate::Evaluator;
use crate::model::Model;
use crate::odometry::Selection;
use crate::pose::PoseError;
use crate::run::Run;
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

    /// The ground-truth poses the cost reads.
    pub fn selection(&self) -> Selection {
        match *self {
            CostKind::EndPose => Selection::End,
            CostKind::Path { every, .. } => Selection::Path(every),
        }
    }

    /// Weight of heading errors in the residuals (1 for the end pose, as Eq. 6). m/rad.
    pub fn heading_weight(&self) -> f64 {
        match *self {
            CostKind::EndPose => 1.0,
            CostKind::Path { heading_weight_m_per_rad, .. } => heading_weight_m_per_rad,
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

/// Mean of the Eq. 6 terms, summed in run order.
pub fn mean_end_pose_error(errors: &[PoseError]) -> f64 {
    if errors.is_empty() {
        return 0.0;
    }
    errors.iter().map(PoseError::norm).sum::<f64>() / errors.len() as f64
}

/// One run's path RMS from its pose errors: `sqrt(mean |e|²)` over the poses, with `|e|² = dx² + dy² + dθ²`
/// (heading 1 m/rad). m. 0 without errors. What diagnosis and Python report per run
/// (`RunErrors::run(i)` of a path selection).
pub fn path_rms(errors: &[PoseError]) -> f64 {
    (errors.iter().map(|e| e.norm().powi(2)).sum::<f64>() / errors.len().max(1) as f64).sqrt()
}

/// The cost `kind` of `model` at `params` over `runs`, through [`Evaluator::for_report`]. Checks wheel
/// counts.
pub fn cost(model: &Model, params: &[f64], runs: &[Run], kind: CostKind) -> Result<f64, KinError> {
    let evaluator = Evaluator::for_report(model, runs, kind.selection())?;
    let res = model.resolve(params)?;
    Ok(evaluator.cost(&res, kind))
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
