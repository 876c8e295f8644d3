//! # omni-py: the `omnical` Python module
//!
//! A thin pyo3 binding over omni-kin, omni-ga and omni-cli's dataset and model-file code: runs in and out
//! as numpy arrays, Rust errors as Python exceptions (`errors.rs`), the GIL released for every long call,
//! and user effects written in Python (`effect.rs`). Built by maturin as `omnical._omnical`; the Python
//! package `omnical` (crates/omni-py/python) re-exports it.
//!
//! One file per group of functions; a new function is one `#[pyfunction]` plus one line in the module
//! below (and its stub in `_omnical.pyi`).
//!
//! Fork safety: rayon's worker threads do not survive `fork()`. Call omnical in a child process only if
//! the parent has not used it yet, or use the `spawn` start method of `multiprocessing`.

// The library's errors (TrainError, ImuError, …) cross into Python once per call, where they become a
// PyErr at once: their size on the way (clippy's result_large_err) costs nothing here.
#![allow(clippy::result_large_err)]

mod arrays;
mod calibrate;
mod cli;
mod diagnose;
mod effect;
mod errors;
mod evaluate;
mod explore;
mod export;
mod imu;
mod info;
mod model;
mod out_dir;
mod pickle;
mod report;
mod robot;
mod run;
mod session;
mod simulate;

use pyo3::prelude::*;

/// The allocator of the `omnical` binary (see `omni_cli`'s main.rs): the science's per-run Jacobian blocks
/// are allocated and freed without the system allocator's map, unmap and zeroing each time.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[pymodule]
mod _omnical {
    #[pymodule_export]
    use crate::calibrate::{_calibration_from_state, PyCalibration, train};
    #[pymodule_export]
    use crate::cli::cli_main;
    #[pymodule_export]
    use crate::diagnose::{PyDiagnosis, diagnose};
    #[pymodule_export]
    use crate::evaluate::{PyEvaluation, PyRunResiduals, evaluate, integrate};
    #[pymodule_export]
    use crate::explore::{PyExploration, explore};
    #[pymodule_export]
    use crate::export::export;
    #[pymodule_export]
    use crate::imu::imu;
    #[pymodule_export]
    use crate::info::info;
    #[pymodule_export]
    use crate::model::{_model_from_toml, PyModel, effect_catalogue, load_model};
    #[pymodule_export]
    use crate::out_dir::{_prepare_dir, _write_atomic, PyOutDir};
    #[pymodule_export]
    use crate::report::report;
    #[pymodule_export]
    use crate::run::{_dataset_from_state, _run_from_bytes, PyDataset, PyRun, load};
    #[pymodule_export]
    use crate::session::{_fleet_args, diagnose_files, train_files};
    #[pymodule_export]
    use crate::simulate::simulate;

    use super::*;

    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        let py = m.py();
        m.add("__version__", env!("CARGO_PKG_VERSION"))?;
        m.add("CATALOGUE", omni_kin::effect::CATALOGUE.to_vec())?;
        m.add("OmnicalError", py.get_type::<crate::errors::OmnicalError>())?;
        m.add("DatasetError", py.get_type::<crate::errors::DatasetError>())?;
        m.add("ModelFileError", py.get_type::<crate::errors::ModelFileError>())?;
        m.add("CalibrationError", py.get_type::<crate::errors::CalibrationError>())?;
        Ok(())
    }
}
