//! # omni-ga
//!
//! Optimizers and the science built on them: a bounded genetic algorithm (rayon-parallel fitness, the
//! paper's method), a Levenberg–Marquardt polish, the calibration presets, and the model-error diagnosis.
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
pub use science::{diagnose, excitation, identify};

pub use error::{Error, OptimizeError};
pub use fit::{Calibration, Plan, Preset, calibrate};
pub use ga::{Ga, GaConfig, StallRule};
pub use lm::{LevenbergMarquardt, LmConfig};
pub use observe::{Control, FnObserver, Iteration, NoopObserver, Observer};
pub use optimizer::{Optimizer, Solution, Termination};
pub use problem::{Bounds, LeastSquares, NormalEquations, Problem};
pub use science::diagnose::{DiagnoseOptions, Diagnosis, diagnose};
