//! `CalibrationProblem`'s per-run blocks are `residuals()` and `jacobian()` cut by run, and its normal
//! equations are their `JᵀJ`, `Jᵀr`, `rᵀr` — on every route: the fast kernel (IK or geometry, with and
//! without effect parameters) and the general walk.
#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use omni_ga::calibrate::{BoxRule, CalibrationProblem, search_box};
use omni_ga::{LeastSquares, NormalEquations};
use omni_kin::simulate::{SimConfig, simulate};
use omni_kin::{CostKind, EffectKind, FittedModel, IkMatrix, Integration, Model, RobotGeometry, Run};

fn runs() -> Vec<Run> {
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    let cfg = SimConfig { duration_s: 2.0, runs_per_command: 1, ..SimConfig::default() };
    simulate(&cfg, &truth, "t/").unwrap().into_iter().step_by(3).collect()
}

/// Checks the blocks of `model` at `x` against the stacked residuals and Jacobian.
fn check(model: &Model, x: &[f64], runs: &[Run], objective: CostKind) {
    let bounds = search_box(model, x, BoxRule::PerRow(0.1)).unwrap();
    let problem = CalibrationProblem::new(model, runs, objective, bounds).unwrap();
    let (r, j) = (problem.residuals(x), problem.jacobian(x));
    assert_eq!(problem.residual_count(x), r.len());
    let r_max = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut next_run = 0;
    let mut row = 0;
    problem.for_each_run_block(x, &mut |b| {
        assert_eq!(b.run, next_run, "runs in order");
        assert_eq!(b.row_offset, row);
        let rows = b.residuals.len();
        assert!(rows >= 3 && rows % 3 == 0);
        // The kernel's Jacobian walk is scalar (no FMA): the residuals agree to rounding.
        for (got, want) in b.residuals.iter().zip(&r[row..row + rows]) {
            assert!((got - want).abs() <= 1e-12 * r_max, "run {}: residual {got} vs {want}", b.run);
        }
        assert_eq!((b.jacobian.nrows(), b.jacobian.ncols()), (rows, x.len()));
        for i in 0..rows {
            for c in 0..x.len() {
                let (got, want) = (b.jacobian[(i, c)], j[(row + i, c)]);
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1e-3),
                    "run {} row {i} col {c}: {got} vs {want}",
                    b.run
                );
            }
        }
        next_run += 1;
        row += rows;
    });
    assert_eq!((next_run, row), (runs.len(), r.len()));
    let ne = problem.normal_equations(x);
    let full = NormalEquations::from_rows(&r, &j);
    assert_eq!(ne.rows, r.len());
    let scale = full.jtj.abs().max();
    assert!((ne.jtj - &full.jtj).abs().max() <= 1e-10 * scale, "JᵀJ");
    assert!((ne.jtr - &full.jtr).abs().max() <= 1e-10 * full.jtr.abs().max().max(1e-12), "Jᵀr");
    assert!((ne.rtr - full.rtr).abs() <= 1e-12 * full.rtr, "rᵀr");
}

#[test]
fn blocks_are_the_stacked_system_cut_by_run() {
    let runs = runs();
    let ik = Model::ik(IkMatrix::paper_design()).with_integration(Integration::DEFAULT);
    let x = IkMatrix::paper_calibrated().entries().to_vec();
    check(&ik, &x, &runs, CostKind::PATH);
    check(&ik, &x, &runs, CostKind::EndPose);
    check(&ik, &x, &runs, CostKind::Path { every: 4, heading_weight_m_per_rad: 0.5 });

    // Effect parameters: finite-difference columns beside the kernel's IK columns.
    let with_effect = ik.clone().with_effect(EffectKind::from_id("speed_scale", 3).unwrap());
    let mut xe = x.clone();
    xe.extend([0.01, -0.02, 0.015]);
    check(&with_effect, &xe, &runs, CostKind::PATH);

    // Geometry: the chain rule through the IK matrix.
    let geometry = Model::geometry(RobotGeometry::apr02()).with_integration(Integration::DEFAULT);
    check(&geometry, &geometry.nominal(), &runs, CostKind::PATH);

    // A clock lag: the general walk, whole Jacobian cut by run.
    let lagged = ik.with_effect(EffectKind::from_id("time_offset", 3).unwrap());
    let mut xl = x;
    xl.push(0.01);
    check(&lagged, &xl, &runs, CostKind::PATH);
}
