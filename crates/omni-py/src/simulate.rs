//! `simulate`: the benchmark runs of a robot (the paper's flower by default) on a true robot (any model,
//! Python effects included).

use crate::errors::{PyResultExt, value_error};
use crate::model::model_arg;
use crate::robot::{robot_arg, robot_design};
use crate::run::PyRun;
use omni_kin::simulate::{SimConfig, benchmark_commands, simulate as rs_simulate};
use omni_kin::{IkMatrix, KinematicsKind};
use pyo3::prelude::*;
use std::path::PathBuf;

/// Simulate the benchmark (its commands × ``runs_per_command``) on the true robot ``truth``: the runs
/// ``omnical simulate`` writes into its ``train/`` folder (the same defaults: 5 runs per command of 10 s,
/// seed 7, names ``train/NN-rK``; its ``validation/`` folder is ``seed=8, prefix="validation/"``).
///
/// ``robot``: the simulated base, a ``robot.toml`` path or ``"apr02"`` (as ``omnical simulate --robot``;
/// default ``"apr02"``, the paper's robot): its design turns the commands into wheel targets, and the
/// commands are those it can perform (the 36 flower commands; for a differential drive forward and
/// turning ones, no sideways runs). ``truth`` (default: the paper's Eq. 9 matrix on APR-02, the design
/// itself on any other robot; give a model with effects to hide them in the data) must have the robot's
/// wheel count. Returns the runs, named ``{prefix}{command:02}-r{repetition}``. Deterministic for a
/// ``seed``; the GIL is released.
///
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)  # 36 flower commands, 1 s each
/// >>> len(runs), runs[0].name, runs[0].n_wheels
/// (36, 'train/00-r0', 3)
#[pyfunction]
// The defaults are `omnical simulate`'s (SimConfig::default() and its --seed default, 7),
// spelt out so that help() shows them; tests/test_mirror.py compares them with the CLI's --help.
#[pyo3(signature = (truth = None, *, robot = None, runs_per_command = 5, duration_s = 10.0, seed = 7, noise_free = false, prefix = "train/", sample_drop_probability = 0.0, sample_jitter_s = 0.0))]
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    truth: Option<&Bound<'_, PyAny>>,
    robot: Option<PathBuf>,
    runs_per_command: usize,
    duration_s: f64,
    seed: u64,
    noise_free: bool,
    prefix: &str,
    sample_drop_probability: f64,
    sample_jitter_s: f64,
) -> PyResult<Vec<PyRun>> {
    let mut config = SimConfig {
        runs_per_command,
        duration_s,
        seed,
        sample_drop_probability,
        sample_jitter_s,
        ..SimConfig::default()
    };
    let robot = robot_arg(robot.as_ref())?;
    let design = match &robot {
        Some(r) => {
            let g = r.description.to_geometry().map_err(|e| value_error(format!("robot {}: {e}", r.source)))?;
            config.commands = benchmark_commands(&g);
            config.design = g;
            Some(robot_design(r, KinematicsKind::Ik)?)
        }
        None => None,
    };
    let (truth, adapters) = match (truth, &design) {
        (Some(t), _) => model_arg(t)?,
        // The paper's calibration on APR-02, the design itself on any other robot (as the CLI).
        (None, Some(d)) if d.ik().py()? != IkMatrix::paper_design() => (d.clone(), Vec::new()),
        (None, _) => (omni_cli::design::paper_calibrated(), Vec::new()),
    };
    if let Some(r) = &robot
        && truth.model.n_wheels() != config.design.n_wheels()
    {
        return Err(value_error(format!(
            "truth has {} wheels and robot {} has {} ({})",
            truth.model.n_wheels(),
            r.source,
            config.design.n_wheels(),
            config.design.wheel_names.join(", ")
        )));
    }
    if noise_free {
        config = config.noise_free();
    }
    let errors = crate::effect::EffectErrors::new(adapters);
    let runs = py.detach(|| rs_simulate(&config, &truth, prefix));
    let runs = errors.check(runs)?.py()?;
    Ok(runs.into_iter().map(|inner| PyRun { inner }).collect())
}
