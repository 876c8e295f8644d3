//! Speed figures (issue 7): odometry per run, one model's cost over the paper-size set (180 runs) through
//! the literal walk and the fast kernel on 1 and 2 threads, one GA generation, the LM polish from a GA
//! result (by the crate's QR and on the normal equations), the `default` and `paper` calibrations and a whole-catalogue diagnosis. Run with
//! `cargo bench --bench calibration`; figures go to benches/README.md.
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use omnical::ga::calibrate::{BoxRule, CalibrationProblem, Plan, Preset, calibrate, search_box};
use omnical::ga::diagnose::{DiagnoseOptions, diagnose};
use omnical::ga::{LevenbergMarquardt, LmConfig, NoopObserver, Optimizer, Problem};
use omnical::kin::RobotGeometry;
use omnical::kin::cost::{CostKind, mean_end_pose_error};
use omnical::kin::evaluate::{Evaluator, Route};
use omnical::kin::fast::PreparedRuns;
use omnical::kin::odometry::end_pose_error;
use omnical::kin::simulate::{SimConfig, simulate};
use omnical::kin::{FittedModel, IkMatrix, Integration, Model, Run, Selection};
use std::hint::black_box;

fn paper_size(seed: u64, prefix: &str) -> Vec<Run> {
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    simulate(&SimConfig { seed, ..SimConfig::default() }, &truth, prefix).unwrap_or_default()
}

fn pool(threads: usize) -> Option<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().ok()
}

/// long: the benchmark list, one `bench_function` after another over shared prepared data.
fn benches(c: &mut Criterion) {
    let runs = paper_size(1, "train/");
    let validation = paper_size(2, "validation/");
    let samples: usize = runs.iter().map(Run::n_samples).sum();
    let design = FittedModel::paper_design();
    let Ok(res) = design.model.resolve(&design.params) else { return };
    let paper_model = Model::ik(IkMatrix::paper_design()).with_integration(Integration::PAPER);
    let paper_params = paper_model.nominal();
    let Ok(paper_res) = paper_model.resolve(&paper_params) else { return };

    let mut g = c.benchmark_group("odometry");
    g.throughput(Throughput::Elements(runs[0].n_samples() as u64));
    g.bench_function("one run, end pose, literal walk", |b| b.iter(|| black_box(end_pose_error(&res, &runs[0]))));
    g.finish();

    let mut g = c.benchmark_group("cost over 180 runs");
    g.throughput(Throughput::Elements(samples as u64));
    let walk = |sel| Evaluator::with_route(&design.model, &runs, sel, Route::Walk).ok();
    if let (Some(end_walk), Some(path_walk)) = (walk(Selection::End), walk(Selection::Path(1))) {
        g.bench_function("end pose (Eq. 6), literal walk", |b| {
            b.iter(|| black_box(end_walk.cost(&res, CostKind::EndPose)))
        });
        g.bench_function("path, literal walk", |b| b.iter(|| black_box(path_walk.cost(&res, CostKind::PATH))));
        // What `eval` computes (Eq. 6 and path cost from one walk per run), then through the evaluator's
        // fast path, preparation included.
        g.bench_function("eval: Eq. 6 + path, literal walk", |b| {
            b.iter(|| {
                let e = path_walk.errors(&res);
                black_box((e.end_pose_cost(), e.path_cost(1.0)))
            })
        });
        g.bench_function("eval: Eq. 6 + path, evaluator (fast path, preparation included)", |b| {
            b.iter(|| {
                let e = Evaluator::new(&design.model, &runs, Selection::Path(1)).map(|ev| ev.errors(&res));
                black_box(e.map(|e| (e.end_pose_cost(), e.path_cost(1.0))).ok())
            })
        });
    }
    let ev = |m: &Model, sel| Evaluator::new(m, &runs, sel).ok();
    let (Some(end_paper), Some(end_default), Some(path_default)) =
        (ev(&paper_model, Selection::End), ev(&design.model, Selection::End), ev(&design.model, Selection::Path(1)))
    else {
        return;
    };
    // Increments redone on every walk, as for datasets beyond `KEPT_INCREMENTS_MAX_BYTES`.
    let end_paper_redone = PreparedRuns::with_increment_budget(&runs, Some(0.01), Selection::End, 0);
    for threads in [1, 2] {
        let Some(pool) = pool(threads) else { continue };
        g.bench_function(format!("fast, Eq. 6, Eq. 1 Euler 10 ms, {threads} thread(s)"), |b| {
            pool.install(|| b.iter(|| black_box(end_paper.cost(&paper_res, CostKind::EndPose))))
        });
        g.bench_function(format!("fast, Eq. 6, Eq. 1 Euler 10 ms, increments redone, {threads} thread(s)"), |b| {
            pool.install(|| {
                b.iter(|| {
                    black_box(end_paper_redone.end_pose_errors(&paper_res, &runs).map(|e| mean_end_pose_error(&e)))
                })
            })
        });
        g.bench_function(format!("fast, Eq. 6, exact arcs, {threads} thread(s)"), |b| {
            pool.install(|| b.iter(|| black_box(end_default.cost(&res, CostKind::EndPose))))
        });
        g.bench_function(format!("fast, path, exact arcs, {threads} thread(s)"), |b| {
            pool.install(|| b.iter(|| black_box(path_default.cost(&res, CostKind::PATH))))
        });
    }
    g.finish();

    let mut g = c.benchmark_group("calibration");
    g.sample_size(10);
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    if let Ok(bounds) = search_box(&paper_model, &paper_params, BoxRule::PerValue(0.1))
        && let Ok(problem) = CalibrationProblem::new(&paper_model, &runs, CostKind::EndPose, bounds)
    {
        let pop: Vec<Vec<f64>> =
            (0..200).map(|i| paper_params.iter().map(|v| v * (1.0 + 1e-4 * i as f64)).collect()).collect();
        g.bench_function("one GA generation (200 individuals, Eq. 6, paper)", |b| {
            b.iter(|| black_box(problem.costs(&pop)))
        });
    }
    let plan = Plan::preset(Preset::Default, 9);
    // The polish alone, from the default preset's GA result.
    if let Ok(cal) = calibrate(&start, &runs, &plan, &mut NoopObserver)
        && let Some(ga) = cal.solution("ga")
    {
        let model = start.model.clone().with_integration(plan.integration);
        if let Ok(bounds) = search_box(&model, &start.params, plan.box_rule)
            && let Ok(problem) = CalibrationProblem::new(&model, &runs, plan.objective, bounds)
        {
            g.bench_function("LM polish from the GA result (analytic Jacobian)", |b| {
                b.iter(|| {
                    black_box(LevenbergMarquardt::default().minimize(&problem, &ga.params, &mut NoopObserver).ok())
                })
            });
            // The same on the normal equations (the route of problems above 50,000 residuals).
            let normal = LmConfig { normal_equations_above: 0, ..LmConfig::default() };
            g.bench_function("LM polish from the GA result, normal equations", |b| {
                b.iter(|| {
                    let mut lm = LevenbergMarquardt { config: normal.clone() };
                    black_box(lm.minimize(&problem, &ga.params, &mut NoopObserver).ok())
                })
            });
        }
    }
    g.bench_function("train --preset default", |b| {
        b.iter(|| black_box(calibrate(&start, &runs, &plan, &mut NoopObserver).ok()))
    });
    let paper = Plan::preset(Preset::Paper, 9);
    g.bench_function("train --preset paper", |b| {
        b.iter(|| black_box(calibrate(&start, &runs, &paper, &mut NoopObserver).ok()))
    });
    if let Ok(fit) = calibrate(&start, &runs, &plan, &mut NoopObserver) {
        let opts = DiagnoseOptions::default();
        g.bench_function("diagnose, whole catalogue, 180 + 180 runs", |b| {
            b.iter(|| black_box(diagnose(&fit.fitted, &design, &runs, Some(&validation), &opts).ok()))
        });
    }
    g.finish();
}

/// The cost kernel (fast path, Eq. 6 with exact arcs, one thread) on a differential drive (2 wheels) and
/// on omni bases with 3, 4 and 6 wheels, each on its own benchmark set (`SimConfig::for_robot`: the flower
/// for omni bases, forward arcs and turns for the diff drive; 5 repetitions, 10 s runs). Throughput counts
/// time samples (each carrying one speed per wheel), so the figures show what a wheel more costs.
fn by_wheel_count(c: &mut Criterion) {
    let robots = [
        ("diff, 2 wheels", RobotGeometry::diff_drive(0.0335, 0.0335, 0.29)),
        ("omni, 3 wheels", RobotGeometry::omni_regular(3, 0.05, 0.2, 0.0)),
        ("omni, 4 wheels", RobotGeometry::omni_regular(4, 0.05, 0.2, std::f64::consts::FRAC_PI_4)),
        ("omni, 6 wheels", RobotGeometry::omni_regular(6, 0.05, 0.2, 0.0)),
    ];
    let mut g = c.benchmark_group("cost kernel by wheel count");
    let Some(pool) = pool(1) else { return };
    for (name, geometry) in robots {
        let Ok(ik) = geometry.twist_from_wheels() else { continue };
        let truth = FittedModel::nominal(Model::ik(ik));
        let Ok(runs) = simulate(&SimConfig { seed: 1, ..SimConfig::for_robot(geometry) }, &truth, "bench/") else {
            continue;
        };
        let Ok(res) = truth.model.resolve(&truth.params) else { continue };
        let Ok(ev) = Evaluator::new(&truth.model, &runs, Selection::End) else { continue };
        g.throughput(Throughput::Elements(runs.iter().map(Run::n_samples).sum::<usize>() as u64));
        g.bench_function(format!("{name}, {} runs, fast, Eq. 6, 1 thread", runs.len()), |b| {
            pool.install(|| b.iter(|| black_box(ev.cost(&res, CostKind::EndPose))))
        });
    }
    g.finish();
}

criterion_group!(calibration, benches, by_wheel_count);
criterion_main!(calibration);
