//! `report`: the HTML report of a model on runs, as `omnical report` writes it.

use crate::effect::EffectErrors;
use crate::errors::{PyResultExt, chain_text, file_error, value_error};
use crate::robot::{check_order, designs_for, model_spec};
use crate::run::{origin_of, runs_from};
use omni_cli::report::{self as rs_report, ReportInput};
use omni_ga::diagnose::DiagnoseOptions;
use pyo3::exceptions::PyFileNotFoundError;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Write the HTML report of ``model`` on ``runs`` to ``out`` (one self-contained file, inline SVG figures),
/// as ``omnical report --model MODEL RUNS --out OUT``; with ``png`` (a folder) also each figure as PNG.
/// ``model``: as in :func:`evaluate`. ``validate``: held-out runs the figures use (default: the training
/// runs). ``diagnose``: run the diagnosis (with ``auto``) and show its ranking and error ladder (the CLI's
/// ``--no-diagnose`` is ``diagnose=False``). ``explore``: add the explorer's section (needs ``validate``).
/// Returns the ids of the figures written. The GIL is released.
///
/// >>> import tempfile, pathlib
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)
/// >>> out = pathlib.Path(tempfile.mkdtemp()) / "report.html"
/// >>> figures = omnical.report("paper", runs, out=out, diagnose=False)
/// >>> "ladder" in figures, out.read_text().startswith("<!DOCTYPE html>")
/// (True, True)
#[pyfunction]
#[pyo3(signature = (model, runs, *, out, validate = None, png = None, diagnose = true, explore = false, title = None, robot = None))]
#[allow(clippy::too_many_arguments)]
pub fn report(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    runs: &Bound<'_, PyAny>,
    out: PathBuf,
    validate: Option<&Bound<'_, PyAny>>,
    png: Option<PathBuf>,
    diagnose: bool,
    explore: bool,
    title: Option<String>,
    robot: Option<PathBuf>,
) -> PyResult<Vec<String>> {
    check_order(model, runs, "omnical.report")?;
    // Where the results go is checked before the diagnosis, as `omnical report` does.
    let outputs = omni_cli::out_path::check_file(&out, "out=")
        .and_then(|()| png.as_deref().map_or(Ok(()), |d| omni_cli::out_path::prepare_dir(d, "png=")));
    outputs.map_err(|e| PyFileNotFoundError::new_err(format!("omnical.report: {}", chain_text(&e))))?;
    let mut origins = vec![origin_of(runs)];
    origins.extend(validate.map(origin_of));
    let (train, declared) = runs_from(runs, "runs")?;
    let held_out = validate.map(|v| runs_from(v, "validate")).transpose()?.map(|(r, _)| r).unwrap_or_default();
    let (fm, adapters, label) = model_spec(py, model, robot.as_ref(), declared, "omnical.report")?;
    let errors = EffectErrors::new(adapters.iter().cloned());
    // Each run is compared with its own input's design.
    let design = designs_for(&fm, robot.as_ref(), &origins);
    let d = if diagnose {
        let opts = DiagnoseOptions { auto: true, ..DiagnoseOptions::default() };
        let held = (!held_out.is_empty()).then_some(held_out.as_slice());
        let d = py.detach(|| omni_ga::diagnose::diagnose(&fm, &design, &train, held, &opts));
        Some(errors.check(d)?.py()?)
    } else {
        None
    };
    let extra = if explore {
        if held_out.is_empty() {
            return Err(value_error(
                "omnical.report: explore=True judges each family on held-out runs; give them with validate=",
            ));
        }
        let opts = omni_ga::explore::ExploreOptions::default();
        let e = py.detach(|| omni_ga::explore::explore(&fm, &train, &held_out, &opts));
        rs_report::explore::section(&errors.check(e)?.py()?)
    } else {
        String::new()
    };
    // As the CLI: a model file's noise model draws how far to trust the odometry.
    let noise = model
        .extract::<std::path::PathBuf>()
        .ok()
        .filter(|p| p.is_file())
        .and_then(|p| omni_cli::model_file::read_noise(&p).ok().flatten());
    let input = ReportInput {
        // The CLI's title names the --model value; a Model object has none.
        title: title.unwrap_or_else(|| match model.is_instance_of::<crate::model::PyModel>() {
            true => "omnical report".to_string(),
            false => format!("omnical report: {label}"),
        }),
        models: rs_report::models_for(&design, &fm, noise, d.as_ref()),
        train: &train,
        held_out: &held_out,
        diagnosis: d.as_ref(),
        sources: Vec::new(),
    };
    let written = py.detach(|| rs_report::write_with(&input, &out, png.as_deref(), &extra));
    written.map(|w| w.figures).map_err(|e| file_error(&e))
}
