//! What several of omni-ga's integration tests share: the paper's design, an effect outside the
//! catalogue, and simulated training and held-out runs with their held-out cost.
// Each test binary uses only some of these.
#![allow(dead_code)]

use omni_kin::effect::{Effect, ParamSpec, Stage};
use omni_kin::simulate::{SimConfig, flower_commands, simulate};
use omni_kin::{CostKind, FittedModel, IkMatrix, Model, Run, Twist2};

/// The heading drifts in proportion to the distance travelled, `ω += k |v|` (rad/m): outside the
/// catalogue, expressed by the `body` family's `omega_speed`.
#[derive(Debug)]
pub struct HeadingDrift;

impl Effect for HeadingDrift {
    fn id(&self) -> &str {
        "heading_drift"
    }
    fn describe(&self) -> String {
        "test: heading drift growing with speed".into()
    }
    fn stage(&self) -> Stage {
        Stage::Twist
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("k", "rad/m", 0.0, -1.0, 1.0)]
    }
    fn twist(&self, p: &[f64], t: Twist2, _w: &[f64]) -> Twist2 {
        Twist2 { omega_rad_s: t.omega_rad_s + p[0] * t.vx_m_s.hypot(t.vy_m_s), ..t }
    }
}

/// The paper's design matrix (Eq. 7), as a model.
pub fn design() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_design()))
}

/// Training (seed 1) and held-out (seed 2) runs of `truth`: half the flower, 6 s per command.
pub fn flower_train_and_held_out(truth: &FittedModel) -> (Vec<Run>, Vec<Run>) {
    let commands: Vec<_> = flower_commands().into_iter().step_by(2).collect();
    let cfg = |seed| SimConfig {
        commands: commands.clone(),
        runs_per_command: 1,
        duration_s: 6.0,
        seed,
        ..SimConfig::default()
    };
    (simulate(&cfg(1), truth, "train/").unwrap(), simulate(&cfg(2), truth, "val/").unwrap())
}

/// The path cost (`CostKind::PATH`) of `m` on `runs`.
pub fn held_out_cost(m: &FittedModel, runs: &[Run]) -> f64 {
    omni_kin::cost::cost(&m.model, &m.params, runs, CostKind::PATH).unwrap()
}
