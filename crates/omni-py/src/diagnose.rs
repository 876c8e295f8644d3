//! `diagnose`: compare a model with the measurements, find where it fails, and rank which effect is
//! missing (built-in catalogue and Python effects alike). Results are records (dicts), NaN kept as NaN.

use crate::effect::{EffectErrors, effect_from};
use crate::errors::PyResultExt;
use crate::model::PyModel;
use crate::robot::{check_order, designs_for, model_spec};
use crate::run::{origin_of, runs_from};
use omni_ga::diagnose::{Candidate, Costs, DiagnoseOptions, Diagnosis, ParamValue, diagnose as rs_diagnose};
use omni_kin::effect::Effect;
use pyo3::prelude::*;
use pyo3::types::PyDict;

fn costs_dict<'py>(py: Python<'py>, c: &Costs) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("train_path", c.train_path)?;
    d.set_item("held_out_path", c.held_out_path)?;
    d.set_item("train_end_pose", c.train_end_pose)?;
    d.set_item("held_out_end_pose", c.held_out_end_pose)?;
    Ok(d)
}

fn values<'py>(py: Python<'py>, v: &[ParamValue]) -> PyResult<Vec<Bound<'py, PyDict>>> {
    v.iter()
        .map(|p| {
            let d = PyDict::new(py);
            d.set_item("name", &p.name)?;
            d.set_item("value", p.value)?;
            d.set_item("unit", &p.unit)?;
            d.set_item("std_error", p.std_error)?;
            Ok(d)
        })
        .collect()
}

fn candidate_dict<'py>(py: Python<'py>, c: &Candidate) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("effect", &c.effect)?;
    d.set_item("physics", &c.physics)?;
    d.set_item("held_out_gain", c.held_out_gain)?;
    d.set_item("first_order_explained", c.first_order_explained)?;
    d.set_item("separability", c.separability)?;
    d.set_item("absorbed", c.absorbed)?;
    d.set_item("excess_closed", c.excess_closed)?;
    d.set_item("params", values(py, &c.params)?)?;
    d.set_item("implied", values(py, &c.implied)?)?;
    d.set_item("held", &c.held)?;
    d.set_item("refit", c.refit.as_ref().map(|r| costs_dict(py, r)).transpose()?)?;
    Ok(d)
}

/// The outcome of ``diagnose``: the verdict, the ranking of candidate effects, the error ladder.
///
/// >>> truth = omnical.Model.paper().with_effect("time_offset", tau_s=0.06)
/// >>> runs = omnical.simulate(truth, runs_per_command=1, duration_s=2.0)
/// >>> d = omnical.diagnose("paper", runs, candidates=["time_offset"])
/// >>> d.verdict, d.ranking[0]["effect"], d.to_dict()["verdict"]
/// ('time_offset', 'time_offset', 'time_offset')
#[pyclass(frozen, name = "Diagnosis", module = "omnical._omnical")]
pub struct PyDiagnosis {
    inner: Diagnosis,
    final_model: Option<Py<PyModel>>,
}

#[pymethods]
impl PyDiagnosis {
    /// The effect to add, or None when nothing helps enough.
    #[getter]
    fn verdict(&self) -> Option<String> {
        self.inner.verdict.clone()
    }
    /// The verdict in words (as the CLI prints it).
    #[getter]
    fn verdict_text(&self) -> String {
        self.inner.verdict_text.clone()
    }
    /// Something physical is still missing that no accepted effect removes: the held-out error is 10× the
    /// noise floor or more, or groups of runs (repeats of a command, or runs of one kind of path) are biased
    /// beyond their scatter, or without such groups it is above 3× the noise floor. The same decision as
    /// ``Exploration.unexplained``.
    #[getter]
    fn unexplained(&self) -> bool {
        self.inner.unexplained
    }
    /// The figures behind ``unexplained``: decided_by (``far_above_noise``, ``repeats``,
    /// ``noise_floor_ratio`` or ``undecided``), groups_biased, groups_total, groups_basis (``command`` or
    /// ``motion``), share_biased, chance_probability, repeatability_floor,
    /// remaining_held_out_m [m], noise_floor_m [m], ratio, growth, early_m [m], late_m [m] (None where
    /// not measured).
    #[getter]
    fn unexplained_evidence<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.inner.unexplained_evidence)
            .map_err(|e| crate::errors::value_error(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }
    /// ``auto`` with held-out runs: the explorer's best passing family, which the verdict names and
    /// ``final_model`` carries (effect ``learned:<family>``, gain (fraction), before_m [m], after_m [m],
    /// hint), or None when none passes.
    #[getter]
    fn explored<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text =
            serde_json::to_string(&self.inner.explored).map_err(|e| crate::errors::value_error(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }
    /// How held-out costs were obtained.
    #[getter]
    fn held_out(&self) -> String {
        self.inner.held_out.clone()
    }
    /// Costs of the model as given: train_path, held_out_path [m], train_end_pose, held_out_end_pose (Eq. 6).
    #[getter]
    fn costs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        costs_dict(py, &self.inner.costs)
    }
    /// Costs of the design model (same keys).
    #[getter]
    fn design_costs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        costs_dict(py, &self.inner.design_costs)
    }
    /// Candidates, best held-out gain first: one dict each (effect, physics, held_out_gain (fraction),
    /// first_order_explained, separability, absorbed, excess_closed, params, implied, held (parameters held
    /// at their null values, as ``train`` holds them), refit). The refit is the one ``train`` makes with
    /// ``effects=[effect]`` after fitting the base.
    #[getter]
    fn ranking<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.inner.ranking.iter().map(|c| candidate_dict(py, c)).collect()
    }
    /// The error ladder: dicts with label and the costs keys, design → model → + effects (``auto``).
    #[getter]
    fn ladder<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.inner
            .ladder
            .iter()
            .map(|r| {
                let d = costs_dict(py, &r.costs)?;
                d.set_item("label", &r.label)?;
                Ok(d)
            })
            .collect()
    }
    /// Where the model fails, in words.
    #[getter]
    fn findings(&self) -> Vec<String> {
        self.inner.findings.clone()
    }
    /// Measurement noise at standstill (position_m, heading_rad, path_rms, samples), or None.
    #[getter]
    fn noise_floor<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.inner
            .noise_floor
            .as_ref()
            .map(|n| {
                let d = PyDict::new(py);
                d.set_item("position_m", n.position_m)?;
                d.set_item("heading_rad", n.heading_rad)?;
                d.set_item("path_rms", n.path_rms)?;
                d.set_item("samples", n.samples)?;
                Ok(d)
            })
            .transpose()
    }
    /// The final model: the input plus the effects ``auto`` added (and, with ``validate``, the family the
    /// explorer passed: ``explored``).
    #[getter]
    fn final_model(&self, py: Python<'_>) -> Option<Py<PyModel>> {
        self.final_model.as_ref().map(|m| m.clone_ref(py))
    }
    /// The training runs' motions against the held-out runs' (with ``validate``; else None): shares of
    /// translating, rotating and translating while rotating per set, ``gaps`` (what the training runs lack,
    /// with commands to ``record``) and ``unseen_effects``.
    #[getter]
    fn coverage<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(c) = &self.inner.coverage else { return Ok(None) };
        let text = serde_json::to_string(c).map_err(|e| crate::errors::value_error(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,)).map(Some)
    }
    /// Everything as plain data (the CLI's ``--json``; NaN becomes None there).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.inner).map_err(|e| crate::errors::value_error(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }
    fn __repr__(&self) -> String {
        let verdict = self.inner.verdict.as_ref().map_or("None".to_string(), |v| format!("'{v}'"));
        format!("Diagnosis(verdict={verdict}, {} candidates)", self.inner.ranking.len())
    }
}

/// Diagnose a model on training runs, as ``omnical diagnose --model MODEL RUNS``: compare with the design,
/// locate the error, refit each candidate effect and rank them by the fall of the held-out path cost.
///
/// ``model``: as in :func:`evaluate` (a Model, ``"design"``, ``"paper"`` or a model file path).
/// ``validate``: held-out runs (``--validate``; default: 2-fold cross-validation over repetitions).
/// ``candidates``: catalogue ids and/or Python effects (default: the whole catalogue). ``auto``: add effects
/// one at a time while the held-out cost falls (the error ladder), then with ``validate`` run the explorer
/// and name the family it passes (``explored``). The GIL is released.
///
/// >>> truth = omnical.Model.paper().with_effect("time_offset", tau_s=0.06)
/// >>> runs = omnical.simulate(truth, runs_per_command=1, duration_s=2.0)
/// >>> held_out = omnical.simulate(truth, runs_per_command=1, duration_s=2.0, seed=8, prefix="validation/")
/// >>> d = omnical.diagnose("paper", runs, validate=held_out, candidates=["time_offset", "sensor_offset"])
/// >>> d.verdict, round(d.ranking[0]["params"][0]["value"], 2)
/// ('time_offset', 0.06)
#[pyfunction]
#[pyo3(signature = (model, runs, *, validate = None, candidates = None, auto = false, min_gain = 0.05, every = 1, robot = None))]
#[allow(clippy::too_many_arguments)]
pub fn diagnose(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    runs: &Bound<'_, PyAny>,
    validate: Option<&Bound<'_, PyAny>>,
    candidates: Option<Vec<Bound<'_, PyAny>>>,
    auto: bool,
    min_gain: f64,
    every: usize,
    robot: Option<std::path::PathBuf>,
) -> PyResult<PyDiagnosis> {
    check_order(model, runs, "omnical.diagnose")?;
    let mut origins = vec![origin_of(runs)];
    origins.extend(validate.map(origin_of));
    let (train, declared) = runs_from(runs, "runs")?;
    let validation = validate.map(|v| runs_from(v, "validate")).transpose()?.map(|(r, _)| r);
    let (fm, mut adapters, _) = model_spec(py, model, robot.as_ref(), declared, "omnical.diagnose")?;
    let mut opts = DiagnoseOptions { auto, min_gain, every, ..DiagnoseOptions::default() };
    if let Some(cands) = candidates {
        opts.candidates.clear();
        for c in &cands {
            match effect_from(c, fm.model.n_wheels())? {
                (_, Some(adapter)) => {
                    opts.custom.push(omni_kin::EffectKind::Custom(adapter.clone()));
                    adapters.push(adapter);
                }
                (kind, None) => opts.candidates.push(kind.id().to_string()),
            }
        }
    }
    let errors = EffectErrors::new(adapters.iter().cloned());
    // Each run is compared with its own input's design.
    let design = designs_for(&fm, robot.as_ref(), &origins);
    let d = py.detach(|| rs_diagnose(&fm, &design, &train, validation.as_deref(), &opts));
    let d = errors.check(d)?.py()?;
    let final_model = match &d.final_model {
        Some(f) => Some(Py::new(py, PyModel::from_fitted(f.clone(), adapters))?),
        None => None,
    };
    Ok(PyDiagnosis { inner: d, final_model })
}
