//! `explore`: which family of physical features (wheel, body, world, time, ground truth) explains the error
//! a model leaves, fitted on training runs and judged on held-out runs (issue 18). The records are the
//! CLI's `explore --json`.

use crate::errors::PyResultExt;
use crate::model::PyModel;
use crate::robot::{check_order, model_spec};
use crate::run::runs_from;
use omni_ga::explore::{Exploration, ExploreOptions, explore as rs_explore};
use pyo3::prelude::*;

/// The outcome of ``explore``: each family of features fitted on the training runs, judged on held-out ones.
///
/// >>> truth = omnical.Model.paper().with_effect("learned:world", drift_x=0.004)
/// >>> runs = omnical.simulate(truth, runs_per_command=1, duration_s=2.0)
/// >>> held_out = omnical.simulate(truth, runs_per_command=1, duration_s=2.0, seed=8, prefix="validation/")
/// >>> e = omnical.explore("paper", runs, validate=held_out)
/// >>> e.families[0]["family"], e.model.effects
/// ('world', ['learned:world'])
#[pyclass(frozen, name = "Exploration", module = "omnical._omnical")]
pub struct PyExploration {
    inner: Exploration,
    json: String,
}

impl PyExploration {
    fn record<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?.call_method1("loads", (self.json.as_str(),))
    }
}

#[pymethods]
impl PyExploration {
    /// Every family, largest held-out gain first: dicts with family, effect (``learned:<family>``), status
    /// (``fitted``, ``not_excited``, ``singular``, ``not_converged``), status_reason, status_text,
    /// held_out_gain (fraction), gain_std_error, passes, held_out_cost_m, terms (name, value, std_error,
    /// unit, held), held, hint, curve. Each family is fitted as ``train(..., effects=["learned:<family>"])``
    /// fits it after the base, holding what train holds.
    #[getter]
    fn families<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.record(py)?.get_item("families")
    }
    /// Something physical is still missing with the best passing family (or none): the same decision as
    /// ``Diagnosis.unexplained``.
    #[getter]
    fn unexplained(&self) -> bool {
        self.inner.unexplained
    }
    /// The best passing family's id (``world``, ``wheel``, …), or None.
    #[getter]
    fn best(&self) -> Option<String> {
        self.inner.best().map(|f| f.family.id().to_string())
    }
    /// The training runs' motions against the held-out runs' (the CLI's ``coverage``): shares of
    /// translating, rotating and translating while rotating per set, ``gaps`` (what the training runs lack,
    /// with commands to ``record``) and ``unseen_effects``.
    #[getter]
    fn coverage<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.record(py)?.get_item("coverage")
    }
    /// The conclusion in words (as the CLI prints it).
    #[getter]
    fn conclusion(&self) -> String {
        omni_ga::science::text::explore_conclusion(&self.inner)
    }
    /// The model with the best passing family's learned effect at its fitted values, or None.
    #[getter]
    fn model(&self, py: Python<'_>) -> PyResult<Option<Py<PyModel>>> {
        self.inner.best().map(|f| Py::new(py, PyModel::from_fitted(f.fitted.clone(), Vec::new()))).transpose()
    }
    /// Everything as plain data (the CLI's ``--json``).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.record(py)
    }
    fn __repr__(&self) -> String {
        let best = self.inner.best().map_or("None".to_string(), |f| format!("'{}'", f.family.id()));
        format!("Exploration(best={best}, unexplained={})", if self.inner.unexplained { "True" } else { "False" })
    }
}

/// Explore which family of features explains what ``model`` leaves on ``runs``, judged on the held-out
/// runs ``validate`` (required), as ``omnical explore --model MODEL RUNS --validate V``. ``model``: as in
/// :func:`evaluate`. ``min_gain``: the smallest held-out gain that passes (it must also exceed two standard
/// errors). The GIL is released.
///
/// >>> truth = omnical.Model.paper().with_effect("learned:world", drift_x=0.004)
/// >>> runs = omnical.simulate(truth, runs_per_command=1, duration_s=2.0)
/// >>> held_out = omnical.simulate(truth, runs_per_command=1, duration_s=2.0, seed=8, prefix="validation/")
/// >>> e = omnical.explore("paper", runs, validate=held_out)
/// >>> e.best
/// 'world'
#[pyfunction]
#[pyo3(signature = (model, runs, *, validate, min_gain = 0.05, robot = None))]
pub fn explore(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    runs: &Bound<'_, PyAny>,
    validate: &Bound<'_, PyAny>,
    min_gain: f64,
    robot: Option<std::path::PathBuf>,
) -> PyResult<PyExploration> {
    check_order(model, runs, "omnical.explore")?;
    let (train, declared) = runs_from(runs, "runs")?;
    let (held_out, _) = runs_from(validate, "validate")?;
    let (fm, _, _) = model_spec(py, model, robot.as_ref(), declared, "omnical.explore")?;
    let opts = ExploreOptions { min_gain, ..ExploreOptions::default() };
    let e = py.detach(|| rs_explore(&fm, &train, &held_out, &opts)).py()?;
    let json = omni_cli::api::explore::to_json(&e).to_string();
    Ok(PyExploration { inner: e, json })
}
