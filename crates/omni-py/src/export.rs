//! `export`: trajectories for other tools, as `omnical export` writes them (its own functions): TUM files
//! for evo, MCAP bags with the model's odometry on /omnical/odometry for Foxglove.

use crate::errors::{file_error, out_error, value_error};
use crate::robot::{check_order, designs_for, model_spec, per_run};
use crate::run::{origin_of, runs_from};
use omni_cli::api::load::DataOptions;
use omni_cli::export::{RecordedTopics, write_mcap, write_tum};
use omni_cli::out_path::{Inputs, OutDir};
use pyo3::prelude::*;
use std::path::PathBuf;

/// Write trajectories of ``model`` on ``runs`` for other tools, as ``omnical export --model MODEL RUNS``.
///
/// ``tum``: a folder for ``<run>.gt.tum`` (ground truth), ``<run>.design.tum`` and ``<run>.calibrated.tum``
/// (the odometry of the design and of ``model``: every wheel-sample step plus the ground-truth stamps),
/// byte for byte the CLI's files for the same model spelling and runs (``evo_ape tum A.gt.tum
/// A.calibrated.tum``). ``mcap``: a folder for one ROS 2 bag per run, the run's topics plus ``model``'s
/// odometry on ``/omnical/odometry`` (and the recorded odometry of runs loaded with
/// ``recorded_odometry=True``). Each folder must be new or empty (files of other runs left in it would be
/// taken for this export's) unless ``force=True``, which replaces it whole, as ``--force``; nothing is
/// written when the export fails. ``model``: as in :func:`evaluate`. Returns the paths written. The GIL is
/// released.
///
/// >>> import tempfile
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)[:2]
/// >>> files = omnical.export("paper", runs, tum=tempfile.mkdtemp(), mcap=tempfile.mkdtemp())
/// >>> [f.rsplit("/", 1)[1] for f in files]  # doctest: +NORMALIZE_WHITESPACE
/// ['train_00-r0.gt.tum', 'train_00-r0.design.tum', 'train_00-r0.calibrated.tum', 'train_01-r0.gt.tum',
///  'train_01-r0.design.tum', 'train_01-r0.calibrated.tum', 'train_00-r0.mcap', 'train_01-r0.mcap']
#[pyfunction]
#[pyo3(signature = (model, runs, *, tum = None, mcap = None, robot = None, force = false))]
pub fn export(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    runs: &Bound<'_, PyAny>,
    tum: Option<PathBuf>,
    mcap: Option<PathBuf>,
    robot: Option<PathBuf>,
    force: bool,
) -> PyResult<Vec<String>> {
    check_order(model, runs, "omnical.export")?;
    if tum.is_none() && mcap.is_none() {
        return Err(value_error("omnical.export: nothing to export: give tum=DIR and/or mcap=DIR"));
    }
    if tum.is_some() && tum == mcap {
        return Err(value_error("omnical.export: tum= and mcap= name the same folder: give each its own"));
    }
    let origin = origin_of(runs);
    let (runs, declared) = runs_from(runs, "runs")?;
    let (fm, adapters, spec) = model_spec(py, model, robot.as_ref(), declared, "omnical.export")?;
    let errors = crate::effect::EffectErrors::new(adapters);
    // Each run's own input's design; `"design"` is each run's own in the model's trajectories too.
    let designs = designs_for(&fm, robot.as_ref(), std::slice::from_ref(&origin));
    let models = per_run(fm.clone(), &spec, robot.as_ref(), &origin)?;
    // The joints the CLI names the wheels by: the data's robot description's, else the model's columns.
    let joints = match origin.robot_file {
        Some(_) => DataOptions::default().wheel_joints(&origin),
        None => fm.model.kinematics.wheel_names(),
    };
    // What the export reads, which neither folder may hold: the recordings, the robot and model files.
    let model_file = model.extract::<PathBuf>().ok().filter(|p| p.is_file());
    let inputs = (origin.sources.iter().chain(origin.recordings.values()))
        .fold(Inputs::new(), |i, p| i.with("the data", p))
        .with_some("robot=", origin.robot_file.as_ref().and_then(|r| r.path()))
        .with_some("robot=", robot.as_ref())
        .with_some("model=", model_file);
    // Each failure becomes the Python exception of its cause here, with the CLI's message.
    let written = py.detach(|| -> PyResult<Vec<PathBuf>> {
        let claim = |dir: &Option<PathBuf>, flag| {
            dir.as_deref().map(|d| OutDir::claim(d, flag, force, &inputs)).transpose().map_err(out_error)
        };
        let (tum, mcap) = (claim(&tum, "tum=")?, claim(&mcap, "mcap=")?);
        let mut written = Vec::new();
        if let Some(out) = tum {
            for run in &runs {
                let (design, model) = (designs.for_run(run).map_err(cause)?, models.for_run(run).map_err(cause)?);
                let origin_s = origin.time_origins_s.get(run.name()).copied();
                let files = write_tum(out.path(), run, design, model, &spec, origin_s).map_err(cause)?;
                written.extend(files.iter().map(|f| out.shown(f)));
            }
            out.commit().map_err(out_error)?;
        }
        if let Some(out) = mcap {
            let mut recorded = RecordedTopics::new(&origin.recordings, omni_cli::dataset::DEFAULT_MAX_FILE_BYTES);
            for run in &runs {
                let origin_s = origin.time_origins_s.get(run.name()).copied();
                let topics = recorded.for_run(run).map_err(cause)?;
                let model = models.for_run(run).map_err(cause)?;
                written.push(out.shown(&write_mcap(out.path(), run, model, &joints, origin_s, topics).map_err(cause)?));
            }
            out.commit().map_err(out_error)?;
        }
        Ok(written)
    });
    let written = errors.check(written)??;
    Ok(written.iter().map(|p| p.display().to_string()).collect())
}

/// An export failure as the Python exception of its cause (`FileNotFoundError`, `OSError`, else
/// `OmnicalError`), with the CLI's message.
fn cause(e: impl std::error::Error + 'static) -> PyErr {
    file_error(&e)
}
