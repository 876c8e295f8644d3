//! `report`: the HTML report of a model on runs, as `omnical report` writes it.

use crate::effect::EffectErrors;
use crate::errors::{OmnicalError, PyResultExt};
use crate::model::model_arg;
use crate::run::runs_from;
use omni_cli::design::design_for;
use omni_cli::report::{self as rs_report, ReportInput};
use omni_ga::diagnose::DiagnoseOptions;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError};
use pyo3::prelude::*;
use std::path::PathBuf;

/// Write the HTML report of ``model`` on ``runs`` to ``out`` (one self-contained file, inline SVG figures);
/// with ``png_dir`` also each figure as PNG. ``validation``: held-out runs the figures use (default: the
/// training runs). ``diagnose``: run the diagnosis (with ``auto``) and show its ranking and error ladder.
/// Returns the ids of the figures written. The GIL is released.
#[pyfunction]
#[pyo3(signature = (model, runs, *, out, validation = None, png_dir = None, diagnose = true, title = None))]
#[allow(clippy::too_many_arguments)]
pub fn report(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    runs: &Bound<'_, PyAny>,
    out: PathBuf,
    validation: Option<&Bound<'_, PyAny>>,
    png_dir: Option<PathBuf>,
    diagnose: bool,
    title: Option<String>,
) -> PyResult<Vec<String>> {
    let (train, _) = runs_from(runs, "runs")?;
    let held_out = validation.map(|v| runs_from(v, "validation")).transpose()?.map(|(r, _)| r).unwrap_or_default();
    let (fm, adapters) = model_arg(model)?;
    let errors = EffectErrors::new(adapters.iter().cloned());
    let design = design_for(&fm);
    let d = if diagnose {
        let opts = DiagnoseOptions { auto: true, ..DiagnoseOptions::default() };
        let held = (!held_out.is_empty()).then_some(held_out.as_slice());
        let d = py.detach(|| omni_ga::diagnose::diagnose(&fm, &design, &train, held, &opts));
        Some(errors.check(d)?.py()?)
    } else {
        None
    };
    let input = ReportInput {
        title: title.unwrap_or_else(|| "omnical report".to_string()),
        models: rs_report::models_for(&design, &fm, d.as_ref()),
        train: &train,
        held_out: &held_out,
        diagnosis: d.as_ref(),
        sources: Vec::new(),
    };
    let written = py.detach(|| rs_report::write(&input, &out, png_dir.as_deref()));
    match written {
        Ok(w) => Ok(w.figures),
        Err(e) => {
            let message = format!("{e:#}");
            let io = e.chain().find_map(|c| c.downcast_ref::<std::io::Error>());
            Err(match io {
                Some(io) if io.kind() == std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
                Some(_) => PyOSError::new_err(message),
                None => OmnicalError::new_err(message),
            })
        }
    }
}
