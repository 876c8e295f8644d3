//! The cost of one evaluation (the path residuals at every ground-truth pose) on each odometry route, per
//! wheel sample, for a model and that model with one effect of each stage added: the lane kernel or the
//! general fast walk (`Route::Fast`, whichever serves) against the literal walk (`Route::Walk`). One
//! thread, wall time.
//!
//! ```text
//! omnical train RUNS --out fit.toml
//! cargo run --release --example route_rate -- RUNS fit.toml [EFFECT]
//! ```
use omnical::cli::dataset::{LoadOptions, load};
use omnical::kin::cost::CostKind;
use omnical::kin::evaluate::{Evaluator, Route};
use omnical::kin::{EffectKind, FittedModel, Run, Selection};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Evaluations timed per route.
const EVALUATIONS: usize = 20;

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(dir), Some(model)) = (args.get(1), args.get(2)) else {
        return Err("usage: route_rate RUNS MODEL.toml [EFFECT]".into());
    };
    let runs: Vec<Run> = load(&[PathBuf::from(dir)], &LoadOptions::default())?.runs;
    let samples: usize = runs.iter().map(Run::n_samples).sum();
    let base = omnical::cli::model_file::read(Path::new(model))?;
    let effects: [(&str, &[f64]); 6] = [
        ("", &[]),
        ("time_offset", &[0.03]),
        ("rotation_slip", &[0.05]),
        ("world_drift", &[0.001, 0.002]),
        ("learned:body", &[0.01; 9]),
        ("wheel_eccentricity", &[0.01; 8]),
    ];
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    pool.install(|| -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
        for (id, values) in effects.into_iter().filter(|(id, _)| args.get(3).is_none_or(|e| e == id)) {
            let mut m: FittedModel = base.clone();
            if !id.is_empty() {
                m = m.with_effect(EffectKind::from_id(id, m.model.n_wheels())?);
                let n = m.params.len();
                m.params[n - values.len()..].copy_from_slice(values);
            }
            let res = m.model.resolve(&m.params)?;
            for route in [Route::Fast, Route::Walk] {
                let ev = Evaluator::with_route(&m.model, &runs, Selection::Path(1), route)?;
                let t = Instant::now();
                for _ in 0..EVALUATIONS {
                    black_box(ev.residual_vector(&res, CostKind::PATH));
                }
                let ns = t.elapsed().as_secs_f64() / (EVALUATIONS * samples) as f64 * 1e9;
                println!("{:20} {route:?}: {ns:.1} ns per wheel sample", if id.is_empty() { "(model)" } else { id });
            }
        }
        Ok(())
    })
}
