//! `train_files`: `omnical train` on files, inside a Python process that runs many of them (the fleet's
//! Dask workers). The same code path as the command (`omni_cli::api::train::train_quietly`), so the model
//! file it writes is byte-identical to `omnical train … --out FILE`; nothing is printed and no Ctrl-C
//! handler is installed (the host process keeps its own).

use crate::errors::{OmnicalError, chain_text_as_flags, value_error};
use omni_cli::api::diagnose::diagnose_quietly;
use omni_cli::api::train::{Trained, train_quietly};
use omni_cli::argv::{ArgvError, diagnose_request, diagnose_request_reading_as, fleet_request, train_request};
use omni_kin::FittedModel;
use pyo3::prelude::*;
use serde_json::json;

/// Trains as ``omnical train ARGS...`` would (``args`` without the program and subcommand names, e.g.
/// ``["rec/", "--seed", "3", "--out", "model.toml"]``) and returns plain data: ``summary`` (what
/// ``--json`` prints), ``design`` (parameter name → start value), ``start_s`` / ``end_s`` (the earliest and
/// latest wheel stamps of the runs [s]), ``runs``, ``notes``, ``skipped`` ([source, reason]) and
/// ``warnings``. Bad arguments raise ``ValueError``; a failed load or fit raises ``OmnicalError`` with the
/// command's message. The GIL is released while it runs.
///
/// >>> import tempfile
/// >>> out = tempfile.mkdtemp()
/// >>> omnical._omnical.cli_main(["omnical", "simulate", "--out", out, "--runs-per-command", "1", "--duration", "1"])
/// 0
/// >>> t = omnical._omnical.train_files([out + "/train", "--seed", "0", "--out", out + "/fit.toml"])
/// >>> t["runs"], t["summary"]["objective"], omnical.load_model(out + "/fit.toml").kinematics
/// (36, 'path', 'ik')
#[pyfunction]
pub fn train_files<'py>(py: Python<'py>, args: Vec<String>) -> PyResult<Bound<'py, PyAny>> {
    let request = train_request(&args).map_err(|e| argv_error("train_files", e))?;
    let t = py.detach(|| train_quietly(&request)).map_err(|e| OmnicalError::new_err(chain_text_as_flags(&e)))?;
    let text = serde_json::to_string(&session_json(&t)).map_err(|e| value_error(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Diagnoses as ``omnical diagnose ARGS...`` would (``args`` without the program and subcommand names, e.g.
/// ``["--model", "model.toml", "rec/"]``) and returns what ``--json`` prints (``verdict``, ``verdict_text``,
/// ``ranking``, ``ladder``, ...). With ``train_args`` (``omnical train``'s arguments, e.g. ``["rec/",
/// "--gt-scans", "/scan"]``) the runs are read as that training read them: its data options replace those
/// of ``args`` (the fleet diagnoses each session on the reference it was trained on). Errors as
/// :func:`train_files`. The GIL is released while it runs.
///
/// >>> import tempfile
/// >>> out = tempfile.mkdtemp()
/// >>> args = ["--effect", "time_offset=0.06", "--runs-per-command", "1", "--duration", "2"]
/// >>> omnical._omnical.cli_main(["omnical", "simulate", "--out", out, *args])
/// 0
/// >>> d = omnical._omnical.diagnose_files(["--model", "paper", out + "/train", "--candidates", "time_offset"])
/// >>> d["verdict"]
/// 'time_offset'
#[pyfunction]
#[pyo3(signature = (args, train_args = None))]
pub fn diagnose_files<'py>(
    py: Python<'py>,
    args: Vec<String>,
    train_args: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyAny>> {
    let request = match &train_args {
        Some(t) => diagnose_request_reading_as(&args, t),
        None => diagnose_request(&args),
    }
    .map_err(|e| argv_error("diagnose_files", e))?;
    let d = py.detach(|| diagnose_quietly(&request)).map_err(|e| OmnicalError::new_err(chain_text_as_flags(&e)))?;
    let text = serde_json::to_string(&d).map_err(|e| value_error(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// An argument list that is not the command's, as `ValueError` (the parser's own message, or `what` and
/// the command it should have been).
fn argv_error(what: &str, e: ArgvError) -> PyErr {
    match e {
        ArgvError::Parse(message) => value_error(message),
        other => value_error(format!("{what}: {other}")),
    }
}

/// The plain data [`train_files`] returns.
fn session_json(t: &Trained) -> serde_json::Value {
    let start: &FittedModel = &t.calibration.start;
    let design: serde_json::Map<String, serde_json::Value> =
        start.model.params().into_iter().zip(&start.params).map(|(s, v)| (s.name, json!(v))).collect();
    let runs = &t.dataset.runs;
    let first = runs.iter().filter_map(|r| r.wheel_t_s().first().copied()).fold(f64::INFINITY, f64::min);
    let last = runs.iter().filter_map(|r| r.wheel_t_s().last().copied()).fold(f64::NEG_INFINITY, f64::max);
    json!({
        "summary": t.summary,
        "design": design,
        "start_s": first.is_finite().then_some(first),
        "end_s": last.is_finite().then_some(last),
        "runs": runs.len(),
        "notes": t.dataset.notes.iter().map(|n| omni_cli::api::settings::as_flags(&n.to_string())).collect::<Vec<_>>(),
        "skipped": t.dataset.skipped.iter().map(|s| [s.source.clone(), omni_cli::api::settings::as_flags(&s.reason)]).collect::<Vec<_>>(),
        "warnings": t.warnings.iter().map(|w| omni_cli::api::settings::as_flags(w)).collect::<Vec<_>>(),
    })
}

/// ``omnical fleet ARGS...`` (``args`` without the program and subcommand names) parsed by the command
/// line's own parser, where its options are declared: ``(options, "", 0)`` with the options as a dict
/// (``fleet_dir``, ``out``, ``scheduler``, ``workers``, ``preset``, ``seed``, ``model``, ``diagnose``,
/// ``train_args``, ``quiet``), or ``(None, text, status)`` for ``--help`` (status 0) and bad arguments
/// (status 2, the parser's message).
#[pyfunction]
pub fn _fleet_args<'py>(py: Python<'py>, args: Vec<String>) -> PyResult<(Option<Bound<'py, PyAny>>, String, i32)> {
    let r = match fleet_request(&args) {
        Ok(r) => r,
        Err(e) => return Ok((None, e.render().to_string(), e.exit_code())),
    };
    let doc = json!({
        "fleet_dir": r.fleet_dir.to_string_lossy(),
        "out": r.out.to_string_lossy(),
        "scheduler": r.scheduler,
        "workers": r.workers,
        "preset": r.preset,
        "seed": r.seed,
        "model": r.model,
        "diagnose": r.diagnose,
        "train_args": r.train_args,
        "quiet": r.quiet,
    });
    let text = serde_json::to_string(&doc).map_err(|e| value_error(e.to_string()))?;
    Ok((Some(py.import("json")?.call_method1("loads", (text,))?), String::new(), 0))
}
