//! The fit layer: fit a model's parameters to training runs, the paper's way (`Preset::Paper`) or ours
//! (`Preset::Default`).
//!
//! - [`CalibrationProblem`] (`problem.rs`): the model, runs and objective as an optimizer-layer problem;
//! - [`Plan`], [`Preset`], [`Unexcited`] (`plan.rs`): the recipe, a list of [`Stage`]s (`stage.rs`), each
//!   an optimizer with its own settings and stopping rules;
//! - [`search_box`] (`search_box.rs`): the GA's box around the start;
//! - [`Rescale`] (`rescale.rs`): a start whose dead reckoning travels or turns far from the ground truth
//!   (beyond 1.3×) moved to the ratios first, for a plan with a local polish;
//! - the pipeline (`pipeline.rs`): the stages in order, then the truncated update;
//! - [`calibrate`] (`calibration.rs`): all of it, and the [`Calibration`] report; [`refine`]: effects
//!   added to a fitted model and everything refitted by the refining stages and the truncated update (no
//!   GA) — the one fit behind `train --effect` ([`calibrate_with_effects`]: the base's calibration, then
//!   `refine` per effect), diagnose's candidate refit and the explorer's family fit.
//!
//! | | `paper` (reproduces the paper) | `default` (ours) |
//! |---|---|---|
//! | objective | Eq. 6 end-pose cost | path cost (every ground-truth pose, 1 m/rad) |
//! | odometry | Eq. 1, Euler, 10 ms fixed step | exact arcs, each run's median step |
//! | search | MATLAB-default GA, 200 individuals, stall 50 generations, tol 1e-6 divided by max(1, \|best\|) | stages: small GA (24 × ≤ 30 generations, scale-aware stall rule), then Levenberg–Marquardt |
//! | bounds | ±10 % of each design value (pins zero entries, e.g. m12 = 0, as Eq. 9) | GA: ±10 % of each row's largest magnitude; the polish is unbounded |
//! | unconstrained directions ([`crate::science::identify`]) | move freely | held at the start: truncated update ([`Unexcited::Hold`]) |
//!
//! Every fit reports the parameters that ended on a GA bound and those the polish moved outside the box,
//! so a trapped fit is never silent. The polish never returns a higher objective than its start.

mod calibration;
pub(crate) mod pipeline;
mod plan;
mod problem;
mod rescale;
mod search_box;
mod stage;

pub use crate::error::Error as CalibrateError;
pub(crate) use calibration::differentiable_start;
pub use calibration::{BaseFit, Calibration, WorseThanStart, calibrate, calibrate_with_effects, refine, refine_on};
pub use pipeline::StageOutcome;
pub use plan::{Plan, Preset, STEP_TOLERANCE, StepMismatch, Unexcited};
pub use problem::{CalibrationProblem, RunBlock};
pub use rescale::Rescale;
pub use search_box::{BoxRule, search_box, search_box_with};
pub use stage::Stage;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimizer::Optimizer;
    use crate::optimizer::lm::{LevenbergMarquardt, LmConfig};
    use crate::optimizer::observe::NoopObserver;
    use crate::optimizer::problem::{LeastSquares, NormalEquations, Problem};
    use crate::optimizer::subspace::Subspace;
    use nalgebra::DMatrix;
    use omni_kin::simulate::{SimConfig, simulate};
    use omni_kin::{CostKind, FittedModel, IkMatrix, Integration, Model, Run};

    #[test]
    fn subspace_normal_equations_are_the_projected_ones() {
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let cfg = SimConfig { duration_s: 2.0, runs_per_command: 1, ..SimConfig::default() };
        let runs: Vec<Run> = simulate(&cfg, &truth, "t/").unwrap().into_iter().step_by(4).collect();
        let model = Model::ik(IkMatrix::paper_design()).with_integration(Integration::DEFAULT);
        let x = IkMatrix::paper_calibrated().entries().to_vec();
        let bounds = search_box(&model, &x, BoxRule::PerRow(0.1)).unwrap();
        let problem = CalibrationProblem::new(&model, &runs, CostKind::PATH, bounds).unwrap();
        let basis = DMatrix::from_fn(9, 2, |r, c| if r % 2 == c { 0.01 } else { 0.002 * r as f64 });
        let sub = Subspace::new(&problem, x, basis);
        let z = [0.3, -0.2];
        let ne = sub.normal_equations(&z);
        let full = NormalEquations::from_rows(&sub.residuals(&z), &sub.jacobian(&z));
        assert_eq!(sub.residual_count(&z), full.rows);
        assert!((ne.jtj - &full.jtj).abs().max() <= 1e-10 * full.jtj.abs().max());
        assert!((ne.jtr - &full.jtr).abs().max() <= 1e-10 * full.jtr.abs().max());
        assert!((ne.rtr - full.rtr).abs() <= 1e-12 * full.rtr);
    }

    /// On a calibration (the default preset's objective and integration, 36 short runs), the
    /// normal-equations polish lands where the crate's does.
    #[test]
    fn both_solvers_polish_a_calibration_alike() {
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let runs = simulate(&SimConfig { duration_s: 3.0, runs_per_command: 1, ..SimConfig::default() }, &truth, "t/")
            .unwrap();
        let model = Model::ik(IkMatrix::paper_design()).with_integration(Integration::DEFAULT);
        let start = model.nominal();
        let bounds = search_box(&model, &start, BoxRule::PerRow(0.1)).unwrap();
        let problem = CalibrationProblem::new(&model, &runs, omni_kin::CostKind::PATH, bounds).unwrap();
        let by_crate = LevenbergMarquardt::default().minimize(&problem, &start, &mut NoopObserver).unwrap();
        let by_normal = LevenbergMarquardt { config: LmConfig { normal_equations_above: 0, ..LmConfig::default() } }
            .minimize(&problem, &start, &mut NoopObserver)
            .unwrap();
        let start_cost = problem.cost(&start);
        assert!(by_crate.cost < 0.5 * start_cost, "{} → {}", start_cost, by_crate.cost);
        let gap = (by_normal.cost - by_crate.cost).abs() / by_crate.cost;
        assert!(gap < 1e-6, "crate {} vs normal equations {} ({gap:e})", by_crate.cost, by_normal.cost);
        for (a, b) in by_crate.params.iter().zip(&by_normal.params) {
            assert!((a - b).abs() < 1e-6 * a.abs().max(1.0), "{:?} vs {:?}", by_crate.params, by_normal.params);
        }
    }
}
