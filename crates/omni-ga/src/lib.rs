//! # omni-ga
//!
//! Optimizers and the science built on them: a bounded genetic algorithm (rayon-parallel fitness, the
//! paper's method), a Levenberg–Marquardt polish, the calibration presets, and the model-error diagnosis.
//!
//! Three layers, by concern:
//! - [`optimizer`]: problems, optimizers (GA, LM), observers and bounds — no dependency on the rest of the
//!   workspace;
//! - [`fit`]: the calibration problem and a pipeline of [`fit::Stage`]s over any optimizer ([`calibrate()`]);
//! - [`science`]: diagnosis, identifiability and excitation planning, returning structured findings whose
//!   sentences are all made in [`science::text`].
//!
//! Errors: [`enum@Error`] (the optimizer layer's [`OptimizeError`] converts into it).
//!
//! Determinism: the GA's random numbers come from `ChaCha8Rng::seed_from_u64(seed)` on the calling thread
//! in a fixed order; population costs are evaluated in parallel and collected in order; sums over runs are
//! sequential. The same seed gives bit-identical results with 1 thread or many.
//!
//! No file or terminal I/O happens here.
#![deny(missing_docs)]

pub mod error;
pub mod fit;
pub mod optimizer;
pub mod science;

// The first wave's module paths, kept for the CLI, Python and users: `omni_ga::calibrate::calibrate`,
// `omni_ga::diagnose::diagnose`, `omni_ga::observe::Observer`, …
pub use fit as calibrate;
pub use optimizer::{ga, lm, observe, problem};
pub use science::{coverage, diagnose, excitation, explore, identify};

pub use error::{Error, OptimizeError};
pub use fit::{Calibration, Plan, Preset, calibrate};
pub use ga::{Ga, GaConfig, StallRule};
pub use lm::{LevenbergMarquardt, LmConfig};
pub use observe::{Control, FnObserver, Iteration, NoopObserver, Observer};
pub use optimizer::{Optimizer, Solution, Termination};
pub use problem::{Bounds, LeastSquares, NormalEquations, Problem};
pub use science::diagnose::{DiagnoseOptions, Diagnosis, diagnose};

#[cfg(test)]
mod tests {
    /// The optimizer layer stays independent of the rest of the workspace, so an optimizer is written and
    /// tested against plain functions.
    #[test]
    fn the_optimizer_layer_uses_no_workspace_crate() {
        let sources = [
            ("mod.rs", include_str!("optimizer/mod.rs")),
            ("bounds.rs", include_str!("optimizer/bounds.rs")),
            ("error.rs", include_str!("optimizer/error.rs")),
            ("ga/mod.rs", include_str!("optimizer/ga/mod.rs")),
            ("lm.rs", include_str!("optimizer/lm.rs")),
            ("observe.rs", include_str!("optimizer/observe.rs")),
            ("problem.rs", include_str!("optimizer/problem.rs")),
            ("subspace.rs", include_str!("optimizer/subspace.rs")),
        ];
        for (file, text) in sources {
            for forbidden in ["omni_kin", "crate::fit", "crate::science", "crate::calibrate", "crate::diagnose"] {
                assert!(!text.contains(forbidden), "optimizer/{file} uses {forbidden}");
            }
        }
    }
}
