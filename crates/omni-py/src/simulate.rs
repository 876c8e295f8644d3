//! `simulate`: the paper's flower benchmark on a true robot (any model, Python effects included).

use crate::errors::PyResultExt;
use crate::model::model_or;
use crate::run::PyRun;
use omni_kin::simulate::{SimConfig, simulate as rs_simulate};
use pyo3::prelude::*;

/// Simulate the flower benchmark (36 commands × ``runs_per_command``) on the true robot ``truth``
/// (default: the paper's Eq. 9 matrix; give a model with effects to hide them in the data). Returns the
/// runs, named ``{prefix}{command:02}-r{repetition}``. Deterministic for a ``seed``; the GIL is released.
#[pyfunction]
#[pyo3(signature = (truth = None, *, runs_per_command = 1, duration_s = 4.0, seed = 0, noise_free = false, prefix = "run/", sample_drop_probability = 0.0, sample_jitter_s = 0.0))]
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    truth: Option<&Bound<'_, PyAny>>,
    runs_per_command: usize,
    duration_s: f64,
    seed: u64,
    noise_free: bool,
    prefix: &str,
    sample_drop_probability: f64,
    sample_jitter_s: f64,
) -> PyResult<Vec<PyRun>> {
    let (truth, adapters) = model_or(truth, omni_cli::design::paper_calibrated)?;
    let mut config = SimConfig {
        runs_per_command,
        duration_s,
        seed,
        sample_drop_probability,
        sample_jitter_s,
        ..SimConfig::default()
    };
    if noise_free {
        config = config.noise_free();
    }
    let errors = crate::effect::EffectErrors::new(adapters);
    let runs = py.detach(|| rs_simulate(&config, &truth, prefix));
    let runs = errors.check(runs)?.py()?;
    Ok(runs.into_iter().map(|inner| PyRun { inner }).collect())
}
