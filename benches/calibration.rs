//! Speed figures: odometry per run, cost over the paper-size set (180 runs), one GA generation, and the
//! `default` calibration. Run with `cargo bench --bench calibration`; figures go to benches/README.md.
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use omnical::ga::calibrate::{CalibrationProblem, Plan, Preset, calibrate, search_box};
use omnical::ga::{NoopObserver, Problem};
use omnical::kin::cost::{CostKind, cost_resolved};
use omnical::kin::odometry::end_pose_error;
use omnical::kin::simulate::{SimConfig, simulate};
use omnical::kin::{FittedModel, IkMatrix, Model, Run};
use std::hint::black_box;

fn paper_size() -> Vec<Run> {
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    simulate(&SimConfig { seed: 1, ..SimConfig::default() }, &truth, "train/").unwrap_or_default()
}

fn benches(c: &mut Criterion) {
    let runs = paper_size();
    let samples: usize = runs.iter().map(Run::n_samples).sum();
    let design = FittedModel::paper_design();
    let res = design.model.resolve(&design.params).ok();
    let Some(res) = res else { return };

    let mut g = c.benchmark_group("odometry");
    g.throughput(Throughput::Elements(runs[0].n_samples() as u64));
    g.bench_function("one run, end pose", |b| b.iter(|| black_box(end_pose_error(&res, &runs[0]))));
    g.finish();

    let mut g = c.benchmark_group("cost over 180 runs");
    g.throughput(Throughput::Elements(samples as u64));
    g.bench_function("end pose (Eq. 6)", |b| b.iter(|| black_box(cost_resolved(&res, &runs, CostKind::EndPose))));
    g.bench_function("path", |b| b.iter(|| black_box(cost_resolved(&res, &runs, CostKind::PATH))));
    g.finish();

    let mut g = c.benchmark_group("calibration");
    g.sample_size(10);
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let model = start.model.clone();
    if let Ok(bounds) = search_box(&model, &start.params, omnical::ga::calibrate::BoxRule::PerValue(0.1))
        && let Ok(problem) = CalibrationProblem::new(&model, &runs, CostKind::EndPose, bounds)
    {
        let pop: Vec<Vec<f64>> =
            (0..200).map(|i| start.params.iter().map(|v| v * (1.0 + 1e-4 * i as f64)).collect()).collect();
        g.bench_function("one GA generation (200 individuals, Eq. 6)", |b| b.iter(|| black_box(problem.costs(&pop))));
    }
    let plan = Plan::preset(Preset::Default, 9);
    g.bench_function("train --preset default", |b| {
        b.iter(|| black_box(calibrate(&start, &runs, &plan, &mut NoopObserver).ok()))
    });
    g.finish();
}

criterion_group!(calibration, benches);
criterion_main!(calibration);
