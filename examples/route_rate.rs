use omnical::cli::dataset::{LoadOptions, load};
use omnical::kin::cost::CostKind;
use omnical::kin::evaluate::{Evaluator, Route};
use omnical::kin::{EffectKind, FittedModel, Model, Run, Selection};
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = PathBuf::from(&args[1]);

    let runs: Vec<Run> = load(&[dir], &LoadOptions::default())?.runs;
    let samples: usize = runs.iter().map(Run::n_samples).sum();
    let base: FittedModel = omnical::cli::model_file::read(std::path::Path::new(&args[2]))?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    pool.install(|| {
        for (id, vals) in [
            ("", vec![]),
            ("time_offset", vec![0.03]),
            ("rotation_slip", vec![0.05]),
            ("world_drift", vec![0.001, 0.002]),
            ("learned:body", vec![0.01; 9]),
            ("wheel_eccentricity", vec![0.01; 8]),
        ] {
            let mut m = base.clone();
            if args.len() > 3 && args[3] != id {
                continue;
            }
            if !id.is_empty() {
                m = m.with_effect(EffectKind::from_id(id, m.model.n_wheels()).unwrap());
                let n = m.params.len();
                m.params[n - vals.len()..].copy_from_slice(&vals);
            }
            for route in [Route::Fast, Route::Walk] {
                if args.len() > 4 && route == Route::Walk {
                    continue;
                }
                let ev = Evaluator::with_route(&m.model, &runs, Selection::Path(1), route).unwrap();
                let res = m.model.resolve(&m.params).unwrap();
                let n = 100;
                let t = Instant::now();
                for _ in 0..n {
                    black_box(ev.residual_vector(&res, CostKind::PATH));
                }
                let ns = t.elapsed().as_secs_f64() / (n * samples) as f64 * 1e9;
                println!("{id:20} {route:?}: {ns:.1} ns/sample");
            }
        }
    });
    Ok(())
}
