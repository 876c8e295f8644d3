//! Shared helpers: small simulated datasets, the paper's design, and the path cost.
use omnical::kin::cost::{CostKind, cost};
use omnical::kin::simulate::{SimConfig, flower_commands, simulate};
use omnical::kin::{FittedModel, IkMatrix, Model, Run};

/// The paper's design matrix (Eq. 7), as a model.
pub fn paper_design() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_design()))
}

/// The paper's calibrated matrix (Eq. 9) as the true robot.
pub fn paper_truth() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))
}

/// `reps` repetitions of every `stride`-th flower command, `duration_s` long.
pub fn small_config(seed: u64, stride: usize, reps: usize, duration_s: f64) -> SimConfig {
    SimConfig {
        commands: flower_commands().into_iter().step_by(stride).collect(),
        runs_per_command: reps,
        duration_s,
        seed,
        ..SimConfig::default()
    }
}

/// Train and validation sets from different seeds.
pub fn dataset(truth: &FittedModel, cfg: &SimConfig) -> (Vec<Run>, Vec<Run>) {
    let train = simulate(cfg, truth, "train/").expect("simulate train");
    let val =
        simulate(&SimConfig { seed: cfg.seed + 1, ..cfg.clone() }, truth, "validation/").expect("simulate validation");
    (train, val)
}

/// The path cost (`CostKind::PATH`) of `m` on `runs`.
pub fn path_cost(m: &FittedModel, runs: &[Run]) -> f64 {
    cost(&m.model, &m.params, runs, CostKind::PATH).unwrap()
}
