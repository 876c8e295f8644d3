//! The whole `train --preset paper` against the bare cost kernel on one dataset, in CPU time (robust to a
//! busy machine), for issue 15's targets: training ≥ 85 % of the kernel's rate, 2 threads ≥ 1.8 × one.
//!
//! ```text
//! omnical simulate --out /tmp/sim
//! cargo run --release --example engine_rate -- /tmp/sim/train 1
//! ```
//! Prints evaluations, wheel samples per evaluation, CPU and wall seconds of the calibration and of as
//! many kernel evaluations (Eq. 6, Eq. 1 Euler 10 ms, the design matrix), and the ratio of their rates.
use omnical::cli::dataset::{LoadOptions, load};
use omnical::ga::NoopObserver;
use omnical::ga::calibrate::{Plan, Preset, calibrate};
use omnical::kin::cost::CostKind;
use omnical::kin::evaluate::Evaluator;
use omnical::kin::{FittedModel, IkMatrix, Integration, Model, Run, Selection};
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

/// CPU seconds of this process (user + system), from /proc/self/stat (clock ticks of 10 ms).
fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = after.split_whitespace().map(|v| v.parse().unwrap_or(0.0)).collect();
    (f.get(11).copied().unwrap_or(0.0) + f.get(12).copied().unwrap_or(0.0)) / 100.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = PathBuf::from(args.get(1).map_or("sim/train", String::as_str));
    let threads: usize = args.get(2).and_then(|t| t.parse().ok()).unwrap_or(1);
    let runs: Vec<Run> = load(&[dir], &LoadOptions::default())?.runs;
    let samples: usize = runs.iter().map(Run::n_samples).sum();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    pool.install(|| -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
        let start = FittedModel::paper_design();
        let plan = Plan::preset(Preset::Paper, start.model.n_params()).seed(0);
        let (c0, w0) = (cpu_s(), Instant::now());
        let cal = calibrate(&start, &runs, &plan, &mut NoopObserver)?;
        let (train_cpu, train_wall) = (cpu_s() - c0, w0.elapsed().as_secs_f64());
        let model = Model::ik(IkMatrix::paper_design()).with_integration(Integration::PAPER);
        let ev = Evaluator::new(&model, &runs, Selection::End)?;
        let params = model.nominal();
        let res = model.resolve(&params)?;
        let (c0, w0) = (cpu_s(), Instant::now());
        for _ in 0..cal.evaluations {
            black_box(ev.cost(&res, CostKind::EndPose));
        }
        let (kernel_cpu, kernel_wall) = (cpu_s() - c0, w0.elapsed().as_secs_f64());
        let rate = |s: f64| (cal.evaluations * samples) as f64 / s / 1e6;
        println!(
            "threads {threads}: {} runs, {samples} samples per evaluation, {} evaluations",
            runs.len(),
            cal.evaluations
        );
        println!("training: {train_cpu:.2} s CPU, {train_wall:.2} s wall, {:.0} M samples/s (wall)", rate(train_wall));
        println!(
            "kernel:   {kernel_cpu:.2} s CPU, {kernel_wall:.2} s wall, {:.0} M samples/s (wall)",
            rate(kernel_wall)
        );
        println!(
            "training / kernel rate: {:.1} % (CPU), {:.1} % (wall)",
            100.0 * kernel_cpu / train_cpu,
            100.0 * kernel_wall / train_wall
        );
        Ok(())
    })
    .map_err(|e| e as Box<dyn std::error::Error>)
}
