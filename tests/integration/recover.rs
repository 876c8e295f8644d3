//! Simulate with a known matrix, calibrate, and require the matrix back.
use crate::common::{dataset, paper_truth, small_config};
use omnical::ga::calibrate::{Plan, Preset, calibrate};
use omnical::ga::observe::NoopObserver;
use omnical::kin::cost::{CostKind, cost};
use omnical::kin::{FittedModel, IkMatrix, Model};

fn max_row_relative_error(fit: &IkMatrix, truth: &IkMatrix) -> f64 {
    let mut worst = 0.0f64;
    for r in 0..3 {
        let scale = truth.row(r).iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for c in 0..truth.n_wheels() {
            worst = worst.max((fit.get(r, c) - truth.get(r, c)).abs() / scale);
        }
    }
    worst
}

#[test]
fn default_preset_recovers_the_true_matrix() {
    let truth = paper_truth();
    let (train, val) = dataset(&truth, &small_config(11, 2, 2, 8.0));
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let plan = Plan::preset(Preset::Default, 9).seed(3);
    let c = calibrate(&start, &train, &plan, &mut NoopObserver).expect("calibrate");
    let err = max_row_relative_error(&c.fitted.ik().expect("ik"), &IkMatrix::paper_calibrated());
    assert!(err < 0.01, "entry error {err} of the row scale");
    let oracle_val = cost(&truth.model, &truth.params, &val, CostKind::EndPose).expect("cost");
    let fit_val = cost(&c.fitted.model, &c.fitted.params, &val, CostKind::EndPose).expect("cost");
    assert!(fit_val <= 1.10 * oracle_val, "validation {fit_val} vs oracle {oracle_val}");
    assert!(c.end_pose_fitted < 0.25 * c.end_pose_start, "{} vs design {}", c.end_pose_fitted, c.end_pose_start);
}

#[test]
fn paper_preset_lowers_the_cost_like_the_paper() {
    let truth = paper_truth();
    let (train, _) = dataset(&truth, &small_config(5, 3, 2, 8.0));
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let mut plan = Plan::preset(Preset::Paper, 9).seed(1);
    // A smaller population keeps the test fast; the full preset runs in the benchmarks.
    if let Some(ga) = plan.ga_mut() {
        ga.population = 60;
        ga.elite = 3;
    }
    let c = calibrate(&start, &train, &plan, &mut NoopObserver).expect("calibrate");
    assert!(c.improvement_pct() > 75.0, "improvement {} %", c.improvement_pct());
    // m12 is pinned at zero by the ±10 % box, as in the paper's Eq. 9.
    assert_eq!(c.fitted.ik().expect("ik").get(0, 1), 0.0);
}
