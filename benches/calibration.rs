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
use omnical::kin::fast::{PreparedRuns, SimdPath, limit_simd_path};
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

/// The cost kernel (fast path, Eq. 6, Eq. 1 Euler 10 ms, the paper-size set) on every lane-arithmetic path
/// this CPU has ([`SimdPath`], capped as `OMNICAL_SIMD` does), on 1 and 2 threads; then this machine's
/// limit: the bare arithmetic of the same steps ([`limit::eq1_steps`]) at the widest lanes.
fn lane_paths(c: &mut Criterion) {
    let runs = paper_size(1, "train/");
    let samples: usize = runs.iter().map(Run::n_samples).sum();
    let model = Model::ik(IkMatrix::paper_design()).with_integration(Integration::PAPER);
    let params = model.nominal();
    let (Ok(res), Ok(ev)) = (model.resolve(&params), Evaluator::new(&model, &runs, Selection::End)) else { return };
    let mut g = c.benchmark_group("issue 29, lane paths");
    g.throughput(Throughput::Elements(samples as u64));
    for path in SimdPath::available() {
        for threads in [1, 2] {
            let Some(pool) = pool(threads) else { continue };
            limit_simd_path(path);
            g.bench_function(format!("fast, Eq. 6, Eq. 1 Euler 10 ms, {}, {threads} thread(s)", path.name()), |b| {
                pool.install(|| b.iter(|| black_box(ev.cost(&res, CostKind::EndPose))))
            });
        }
    }
    // The first 32 runs (≈ 0.9 MB of increments, within a core's L2): the kernel without the L3 traffic.
    let few = &runs[..32];
    let few_samples: usize = few.iter().map(Run::n_samples).sum();
    if let (Ok(few_ev), Some(pool)) = (Evaluator::new(&model, few, Selection::End), pool(1)) {
        g.throughput(Throughput::Elements(few_samples as u64));
        for path in SimdPath::available().into_iter().filter(|p| *p != SimdPath::Portable) {
            limit_simd_path(path);
            g.bench_function(format!("fast, Eq. 6, Eq. 1 Euler 10 ms, 32 runs, {}, 1 thread", path.name()), |b| {
                pool.install(|| b.iter(|| black_box(few_ev.cost(&res, CostKind::EndPose))))
            });
        }
    }
    limit_simd_path(SimdPath::Avx512);
    let steps = 1 << 16;
    for chains in [1, 2, 3] {
        g.throughput(Throughput::Elements((steps * 8 * chains) as u64));
        g.bench_function(format!("limit: bare Eq. 1 steps, widest lanes, {chains} chain(s), 1 thread"), |b| {
            b.iter(|| black_box(limit::run(chains, steps, black_box(1.0))))
        });
    }
    g.finish();
}

/// The bare arithmetic of the kernel's Eq. 1 step (3 wheels, Euler) on eight f64 lanes, every operand in
/// registers: no loads, no stores, no queries; the measured limit the kernel is compared with.
mod limit {
    use pulp::{Simd, f64x8};
    use std::hint::black_box;

    /// `steps` steps of `chains` independent lane groups (1 to 3: more chains would hide the FMA latency
    /// of the heading's rotation, if latency bound it) at the widest lanes this CPU has; returns the sum of the lanes' x (so that
    /// nothing is optimised away). `seed` (1.0) scales the increments.
    pub fn run(chains: usize, steps: usize, seed: f64) -> f64 {
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(simd) = pulp::x86::V4::try_new() {
                return simd.vectorize(|| by_chains(simd, chains, steps, seed));
            }
            if let Some(simd) = pulp::x86::V3::try_new() {
                let wide = pulp::x86::V3_512b(simd);
                return simd.vectorize(|| by_chains(wide, chains, steps, seed));
            }
        }
        let _ = (chains, steps, seed);
        f64::NAN
    }

    #[inline(always)]
    fn by_chains<S: Simd<f64s = f64x8>>(s: S, chains: usize, steps: usize, seed: f64) -> f64 {
        match chains {
            1 => eq1_steps::<S, 1>(s, steps, seed),
            2 => eq1_steps::<S, 2>(s, steps, seed),
            _ => eq1_steps::<S, 3>(s, steps, seed),
        }
    }

    /// long: one register-resident loop, the kernel's step (`crates/omni-kin/src/fast/kernel.rs`) for
    /// `ARC = false`, N = 3, operation for operation; each chain's increments advance by one add per wheel
    /// (standing in for the kernel's three loads), so the step angle changes, nothing can be hoisted out
    /// of the loop, and no chain shares a product with another.
    #[inline(always)]
    pub fn eq1_steps<S: Simd<f64s = f64x8>, const CHAINS: usize>(o: S, steps: usize, seed: f64) -> f64 {
        let sp = |v: f64| o.splat_f64s(black_box(v));
        let m: [f64x8; 9] =
            std::array::from_fn(|i| sp([-0.085, 0.0, 0.085, 0.049, -0.099, 0.049, 0.25, 0.25, 0.25][i]));
        let mut u: [[f64x8; 3]; CHAINS] =
            std::array::from_fn(|i| std::array::from_fn(|j| sp(seed * (0.01 + 0.001 * j as f64 + 0.003 * i as f64))));
        let du: [f64x8; 3] = std::array::from_fn(|j| sp(1e-9 * (1.0 + j as f64)));
        let (s1, s2, s3, s4) = (sp(-1.0 / 6.0), sp(1.0 / 120.0), sp(-1.0 / 5040.0), sp(1.0 / 362_880.0));
        let (c0, c1, c2, c3, c4) =
            (sp(0.5), sp(-1.0 / 24.0), sp(1.0 / 720.0), sp(-1.0 / 40_320.0), sp(1.0 / 3_628_800.0));
        let one = sp(1.0);
        let mut st: [[f64x8; 5]; CHAINS] = [[sp(0.0), sp(0.0), sp(0.0), sp(1.0), sp(0.0)]; CHAINS];
        for _ in 0..steps {
            for ([x, y, th, c, s], u) in st.iter_mut().zip(u.iter_mut()) {
                for j in 0..3 {
                    u[j] = o.add_f64s(u[j], du[j]);
                }
                let mut dx = o.mul_f64s(m[0], u[0]);
                let mut dy = o.mul_f64s(m[3], u[0]);
                let mut a = o.mul_f64s(m[6], u[0]);
                for j in 1..3 {
                    dx = o.mul_add_e_f64s(m[j], u[j], dx);
                    dy = o.mul_add_e_f64s(m[3 + j], u[j], dy);
                    a = o.mul_add_e_f64s(m[6 + j], u[j], a);
                }
                let a2 = o.mul_f64s(a, a);
                let p = o.mul_add_e_f64s(a2, s4, s3);
                let p = o.mul_add_e_f64s(a2, p, s2);
                let p = o.mul_add_e_f64s(a2, p, s1);
                let sinc = o.mul_add_e_f64s(a2, p, one);
                let q = o.mul_add_e_f64s(a2, c4, c3);
                let q = o.mul_add_e_f64s(a2, q, c2);
                let q = o.mul_add_e_f64s(a2, q, c1);
                let cosc = o.mul_f64s(a, o.mul_add_e_f64s(a2, q, c0));
                *x = o.mul_add_e_f64s(*c, dx, o.negate_mul_add_e_f64s(*s, dy, *x));
                *y = o.mul_add_e_f64s(*s, dx, o.mul_add_e_f64s(*c, dy, *y));
                let sa = o.mul_f64s(a, sinc);
                let ac = o.mul_f64s(a, cosc);
                let c_next = o.negate_mul_add_e_f64s(*c, ac, o.negate_mul_add_e_f64s(*s, sa, *c));
                *s = o.negate_mul_add_e_f64s(*s, ac, o.mul_add_e_f64s(*c, sa, *s));
                *c = c_next;
                *th = o.add_f64s(*th, a);
            }
        }
        let lanes: [f64; 8] = pulp::cast(st.iter().fold(sp(0.0), |acc, v| o.add_f64s(acc, v[0])));
        lanes.iter().sum()
    }
}

criterion_group!(calibration, benches, by_wheel_count, lane_paths);
criterion_main!(calibration);
