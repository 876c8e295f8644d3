//! The `Calibration` class: what `train` returns to Python (the fitted and start models, costs, warnings,
//! the search's history of [`Step`]s), its getters, and its pickling.

use crate::errors::{PyResultExt, value_error};
use crate::model::PyModel;
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// One iteration as recorded for `Calibration.history` and passed to the progress callback.
#[derive(Clone, Debug)]
pub(super) struct Step {
    pub(super) optimizer: String,
    pub(super) iteration: usize,
    pub(super) best_cost: f64,
    pub(super) mean_cost: f64,
    pub(super) evaluations: usize,
    pub(super) elapsed_s: f64,
}

impl Step {
    pub(super) fn dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("optimizer", &self.optimizer)?;
        d.set_item("iteration", self.iteration)?;
        d.set_item("best_cost", self.best_cost)?;
        d.set_item("mean_cost", self.mean_cost)?;
        d.set_item("evaluations", self.evaluations)?;
        d.set_item("elapsed_s", self.elapsed_s)?;
        Ok(d)
    }

    fn from_dict(d: &Bound<'_, PyDict>) -> PyResult<Self> {
        Ok(Self {
            optimizer: item(d, "optimizer")?,
            iteration: item(d, "iteration")?,
            best_cost: item(d, "best_cost")?,
            mean_cost: item(d, "mean_cost")?,
            evaluations: item(d, "evaluations")?,
            elapsed_s: item(d, "elapsed_s")?,
        })
    }
}

/// A required entry of a pickled state dict.
fn item<'py, T: pyo3::conversion::FromPyObjectOwned<'py>>(d: &Bound<'py, PyDict>, key: &str) -> PyResult<T> {
    d.get_item(key)?
        .ok_or_else(|| value_error(format!("pickled calibration: missing {key:?}")))?
        .extract::<T>()
        .map_err(|e| value_error(format!("pickled calibration: {key:?}: {}", Into::<PyErr>::into(e))))
}

/// The outcome of ``train``: the fitted model, its costs, and how the search went.
///
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)
/// >>> fit = omnical.train("ik", runs, robot="apr02", seed=0)
/// >>> fit.costs["improvement_pct"] > 50, fit.history[0]["optimizer"], fit.model.kinematics
/// (True, 'ga', 'ik')
#[pyclass(frozen, name = "Calibration", module = "omnical._omnical")]
pub struct PyCalibration {
    pub(super) model: Py<PyModel>,
    pub(super) start: Py<PyModel>,
    /// Objective minimised: ``"path"`` (RMS over every ground-truth pose, m with 1 m/rad) or ``"end_pose"``
    /// (the paper's Eq. 6).
    #[pyo3(get)]
    pub(super) objective: String,
    /// Objective at the start model.
    #[pyo3(get)]
    pub(super) objective_start: f64,
    /// Objective at the fit.
    #[pyo3(get)]
    pub(super) objective_fitted: f64,
    /// The paper's Eq. 6 end-pose cost on the training runs at the start (m and rad mixed).
    #[pyo3(get)]
    pub(super) cost_start: f64,
    /// Eq. 6 cost on the training runs at the fit.
    #[pyo3(get)]
    pub(super) cost_fitted: f64,
    /// Relative fall of the Eq. 6 cost from start to fit, in %.
    pub(super) improvement_pct: f64,
    /// Cost evaluations (GA + polish).
    #[pyo3(get)]
    pub(super) evaluations: usize,
    /// Wall time [s].
    #[pyo3(get)]
    pub(super) seconds: f64,
    /// Parameters the GA left on a bound of its box (a trapped fit).
    #[pyo3(get)]
    pub(super) at_bound: Vec<String>,
    /// Parameters the polish moved outside the GA box.
    #[pyo3(get)]
    pub(super) outside_box: Vec<String>,
    /// Ctrl-C (KeyboardInterrupt) stopped the search; the model is the best found so far.
    #[pyo3(get)]
    pub(super) interrupted: bool,
    /// The progress callback returned False; the model is the best found so far.
    #[pyo3(get)]
    pub(super) stopped: bool,
    /// One line per direction of parameter space the training runs do not constrain (empty: all are).
    #[pyo3(get)]
    pub(super) warnings: Vec<String>,
    /// Directions held at the start values by the truncated update (their descriptions).
    #[pyo3(get)]
    pub(super) held: Vec<String>,
    pub(super) identifiability: String,
    pub(super) steps: Vec<Step>,
    /// The model file's `[fit]` summary (`omni_cli::api::train::summarize`, the CLI's own).
    pub(super) summary: serde_json::Value,
}

#[pymethods]
impl PyCalibration {
    /// The fitted model.
    #[getter]
    fn model(&self, py: Python<'_>) -> Py<PyModel> {
        self.model.clone_ref(py)
    }
    /// The start model (with the preset's integration settings).
    #[getter]
    fn start(&self, py: Python<'_>) -> Py<PyModel> {
        self.start.clone_ref(py)
    }
    /// (3, W) fitted IK matrix: rows vx [m/s], vy [m/s], omega [rad/s] per wheel speed [rad/s].
    #[getter]
    fn matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.model.get().inner.ik().py()?;
        crate::arrays::to_matrix(py, 3, m.n_wheels(), m.entries().to_vec())
    }
    /// Effect ids of the fitted model.
    #[getter]
    fn effects(&self) -> Vec<String> {
        use omni_kin::effect::Effect;
        self.model.get().inner.model.effects.iter().map(|e| e.id().to_string()).collect()
    }
    /// Fitted parameters by qualified name.
    #[getter]
    fn params(&self) -> std::collections::BTreeMap<String, f64> {
        let f = &self.model.get().inner;
        f.model.params().into_iter().map(|p| p.name).zip(f.params.iter().copied()).collect()
    }
    /// Costs as a dict: cost_start, cost_fitted (Eq. 6), objective_start, objective_fitted, improvement_pct.
    #[getter]
    fn costs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("cost_start", self.cost_start)?;
        d.set_item("cost_fitted", self.cost_fitted)?;
        d.set_item("objective_start", self.objective_start)?;
        d.set_item("objective_fitted", self.objective_fitted)?;
        d.set_item("improvement_pct", self.improvement_pct)?;
        Ok(d)
    }
    /// What the training runs constrain, as plain data: per-parameter standard errors (``params``: name,
    /// unit, value, scale, std_error [unit] or None when undetermined, std_error_iid), ``condition_number``
    /// (None when infinite), ``covariance_kind``, ``residual_rms`` [m], ``weak`` directions.
    #[getter]
    fn identifiability<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?.call_method1("loads", (self.identifiability.as_str(),))
    }
    /// One dict per optimizer iteration: optimizer (``"ga"``/``"lm"``), iteration, best_cost, mean_cost,
    /// evaluations, elapsed_s.
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.steps.iter().map(|s| s.dict(py)).collect()
    }
    /// Write the model file as ``omnical train --out`` writes it: the model and its ``[fit]`` summary (how
    /// it was made, the identifiability, the noise model, the robot's priors), atomically. The same runs,
    /// preset and seed give the same bytes as the CLI's file. A model with Python effects cannot be
    /// written (a model file names catalogue effects only).
    fn save(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        let summary = self.summary.clone();
        let fitted = self.model.get().inner.clone();
        py.detach(|| omni_cli::api::train::write_model(&fitted, &summary, &path))
            .map_err(|e| value_error(format!("Calibration.save: {}", crate::errors::chain_text(&e))))
    }
    /// Pickling: every field in a dict (the models pickle through their model file text, floats exactly).
    fn __reduce__<'py>(&self, py: Python<'py>) -> crate::pickle::Reduced<'py, (Bound<'py, PyDict>,)> {
        let d = PyDict::new(py);
        d.set_item("model", self.model.clone_ref(py))?;
        d.set_item("start", self.start.clone_ref(py))?;
        d.set_item("objective", &self.objective)?;
        d.set_item("objective_start", self.objective_start)?;
        d.set_item("objective_fitted", self.objective_fitted)?;
        d.set_item("cost_start", self.cost_start)?;
        d.set_item("cost_fitted", self.cost_fitted)?;
        d.set_item("improvement_pct", self.improvement_pct)?;
        d.set_item("evaluations", self.evaluations)?;
        d.set_item("seconds", self.seconds)?;
        d.set_item("at_bound", self.at_bound.clone())?;
        d.set_item("outside_box", self.outside_box.clone())?;
        d.set_item("interrupted", self.interrupted)?;
        d.set_item("stopped", self.stopped)?;
        d.set_item("warnings", self.warnings.clone())?;
        d.set_item("held", self.held.clone())?;
        d.set_item("identifiability", &self.identifiability)?;
        d.set_item("history", self.history(py)?)?;
        d.set_item("summary", self.summary.to_string())?;
        let rebuild = py.import("omnical._omnical")?.getattr("_calibration_from_state")?;
        Ok((rebuild, (d,)))
    }
    fn __repr__(&self) -> String {
        format!(
            "Calibration(Eq. 6 cost {:.5} -> {:.5}, {} evaluations, {:.2} s{})",
            self.cost_start,
            self.cost_fitted,
            self.evaluations,
            self.seconds,
            if self.interrupted { ", interrupted" } else { "" }
        )
    }
}

/// Unpickling a `Calibration` (the dict of its `__reduce__`).
#[pyfunction]
pub fn _calibration_from_state(state: &Bound<'_, PyDict>) -> PyResult<PyCalibration> {
    let history: Vec<Bound<'_, PyDict>> = item(state, "history")?;
    Ok(PyCalibration {
        model: item(state, "model")?,
        start: item(state, "start")?,
        objective: item(state, "objective")?,
        objective_start: item(state, "objective_start")?,
        objective_fitted: item(state, "objective_fitted")?,
        cost_start: item(state, "cost_start")?,
        cost_fitted: item(state, "cost_fitted")?,
        improvement_pct: item(state, "improvement_pct")?,
        evaluations: item(state, "evaluations")?,
        seconds: item(state, "seconds")?,
        at_bound: item(state, "at_bound")?,
        outside_box: item(state, "outside_box")?,
        interrupted: item(state, "interrupted")?,
        stopped: item(state, "stopped")?,
        warnings: item(state, "warnings")?,
        held: item(state, "held")?,
        identifiability: item(state, "identifiability")?,
        steps: history.iter().map(Step::from_dict).collect::<PyResult<_>>()?,
        summary: serde_json::from_str(&item::<String>(state, "summary")?).map_err(|e| value_error(e.to_string()))?,
    })
}
