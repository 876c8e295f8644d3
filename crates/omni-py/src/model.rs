//! Models: base kinematics (the 3 × W IK matrix, or wheel geometry) plus effects, with parameter values;
//! model files (TOML, the CLI's format).

use crate::arrays::{matrix, shape_text, to_matrix, to_vector};
use crate::effect::{EffectErrors, PyEffect, effect_from, stage_name};
use crate::errors::{ModelFileError as PyModelFileError, PyResultExt, ToPyErr, value_error};
use numpy::{PyArray1, PyArray2};
use omni_cli::model_file::{self, ModelFile, ModelFileError};
use omni_kin::effect::{Effect, ParamSpec};
use omni_kin::{EffectKind, FittedModel, IkMatrix, KinematicsKind, Model};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

/// A model with parameter values: base kinematics (``"ik"``: the 3 × W IK matrix; ``"geometry"``:
/// per-wheel radius, distance and angle) plus effects. Immutable: ``with_effect`` and ``with_params``
/// return new models.
///
/// >>> m = omnical.Model.paper().with_effect("time_offset", tau_s=0.06)  # Eq. 9 and a 60 ms clock lag
/// >>> m.kinematics, m.effects, m.get("time_offset.tau_s"), m.matrix.shape
/// ('ik', ['time_offset'], 0.06, (3, 3))
#[pyclass(frozen, name = "Model", module = "omnical._omnical")]
pub struct PyModel {
    pub inner: FittedModel,
    /// The Python effects among `inner`'s effects.
    pub py_effects: Vec<Arc<PyEffect>>,
}

impl PyModel {
    pub fn from_fitted(inner: FittedModel, py_effects: Vec<Arc<PyEffect>>) -> Self {
        // Keep only the adapters this model uses.
        let used: Vec<Arc<PyEffect>> = py_effects
            .into_iter()
            .filter(|a| {
                inner.model.effects.iter().any(|e| match e {
                    EffectKind::Custom(c) => std::ptr::addr_eq(Arc::as_ptr(c), Arc::as_ptr(a)),
                    _ => false,
                })
            })
            .collect();
        Self { inner, py_effects: used }
    }

    /// Error slots of this model's Python effects, cleared.
    pub fn errors(&self) -> EffectErrors {
        EffectErrors::new(self.py_effects.iter().cloned())
    }
}

/// A parameter spec as a dict: name, unit, null, lower, upper.
pub fn spec_dict<'py>(py: Python<'py>, s: &ParamSpec) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &s.name)?;
    d.set_item("unit", &s.unit)?;
    d.set_item("null", s.null)?;
    d.set_item("lower", s.lower)?;
    d.set_item("upper", s.upper)?;
    Ok(d)
}

fn ik_model(matrix_obj: &Bound<'_, PyAny>, name: &str) -> PyResult<IkMatrix> {
    let (data, rows, cols) = matrix(matrix_obj, name, "(3, W)")?;
    if rows != 3 {
        return Err(value_error(format!("{name} must have shape (3, W), got {}", shape_text(&[rows, cols]))));
    }
    IkMatrix::new(cols, data).py()
}

#[pymethods]
impl PyModel {
    /// The design model of a robot, at its design values: ``robot`` is the path of a robot description
    /// (``robot.toml``, docs/formats.md) or ``"apr02"``, the paper's APR-02 robot (Eq. 7), built in.
    /// ``kinematics="ik"`` fits the 3 × W matrix entries (around the robot's design matrix); the
    /// parametric models fit the geometry: ``"geometry"`` (omni: per-wheel radius r [m], distance R [m],
    /// angle delta [rad]), ``"diff"`` (both radii and the separation [m]), ``"mecanum"`` (radii and the
    /// half-extents [m]), ``"skid"`` (a skid-steer base: each side's radius and the centres of rotation
    /// [m]). The model's wheel names are the description's joints (model files carry them).
    ///
    /// >>> omnical.Model.design("robot.toml").design_matrix  # doctest: +SKIP
    /// >>> omnical.Model.design("apr02", kinematics="geometry").param_names[:3]
    /// ['r_a', 'r_b', 'r_c']
    #[staticmethod]
    #[pyo3(signature = (robot = PathBuf::from(omni_cli::robot_file::BUILTIN_APR02), *, kinematics = "ik"), text_signature = "(robot='apr02', *, kinematics='ik')")]
    fn design(robot: PathBuf, kinematics: &str) -> PyResult<Self> {
        let kind: KinematicsKind = kinematics.parse().map_err(|e| value_error(format!("kinematics {e}")))?;
        let r = omni_cli::robot_file::from_arg(&robot.to_string_lossy()).map_err(crate::robot::robot_error)?;
        Ok(Self::from_fitted(crate::robot::robot_design(&r, kind)?, Vec::new()))
    }

    /// The paper's calibrated APR-02 matrix (Eq. 9), around the Eq. 7 design.
    #[staticmethod]
    fn paper() -> PyResult<Self> {
        let model = Model::ik(IkMatrix::paper_design());
        let m = FittedModel::new(model, IkMatrix::paper_calibrated().entries().to_vec()).py()?;
        Ok(Self::from_fitted(m, Vec::new()))
    }

    /// An ``"ik"`` model with this (3, W) matrix [rows vx m/s, vy m/s, omega rad/s per wheel rad/s];
    /// ``design`` (3, W) is the search centre for training (default: the matrix itself).
    #[staticmethod]
    #[pyo3(signature = (matrix, *, design = None))]
    fn from_matrix(matrix: &Bound<'_, PyAny>, design: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let m = ik_model(matrix, "matrix")?;
        let d = match design {
            Some(d) => ik_model(d, "design")?,
            None => m.clone(),
        };
        if d.n_wheels() != m.n_wheels() {
            return Err(value_error(format!("design has {} wheels but matrix has {}", d.n_wheels(), m.n_wheels())));
        }
        let f = FittedModel::new(Model::ik(d), m.entries().to_vec()).py()?;
        Ok(Self::from_fitted(f, Vec::new()))
    }

    /// ``"ik"`` or ``"geometry"``.
    #[getter]
    fn kinematics(&self) -> &'static str {
        self.inner.model.kinematics.id()
    }
    /// Number of wheels W.
    #[getter]
    fn n_wheels(&self) -> usize {
        self.inner.model.n_wheels()
    }
    /// Wheel (joint) names in column order: a robot description's joints, else ``wheel_a``, ``wheel_b``, ….
    /// Model files carry them; ``omnical export`` writes them beside the matrix.
    #[getter]
    fn wheel_names(&self) -> Vec<String> {
        self.inner.model.kinematics.wheel_names()
    }
    /// (3, W) IK matrix: rows vx [m/s], vy [m/s], omega [rad/s] per wheel speed [rad/s].
    #[getter]
    fn matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.inner.ik().py()?;
        to_matrix(py, 3, m.n_wheels(), m.entries().to_vec())
    }
    /// (3, W) IK matrix at the design (nominal) parameters.
    #[getter]
    fn design_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let nominal = self.inner.model.nominal();
        let m = self.inner.model.kinematics.twist_from_wheels(&nominal[..self.inner.model.n_base()]).py()?;
        to_matrix(py, 3, m.n_wheels(), m.entries().to_vec())
    }
    /// Effect ids, in pipeline order.
    #[getter]
    fn effects(&self) -> Vec<String> {
        self.inner.model.effects.iter().map(|e| e.id().to_string()).collect()
    }
    /// Parameter names: base first (``m11`` … or ``r_a`` …), then ``<effect>.<name>``.
    #[getter]
    fn param_names(&self) -> Vec<String> {
        self.inner.model.params().into_iter().map(|p| p.name).collect()
    }
    /// (P,) parameter values, in ``param_names`` order (units: see ``param_specs``).
    #[getter]
    fn param_values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_vector(py, self.inner.params.clone())
    }
    /// Parameters by name (a new dict).
    #[getter]
    fn params(&self) -> BTreeMap<String, f64> {
        self.inner.model.params().into_iter().map(|p| p.name).zip(self.inner.params.iter().copied()).collect()
    }
    /// One dict per parameter: name, unit, null (design / no-effect value), lower, upper.
    #[getter]
    fn param_specs<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.inner.model.params().iter().map(|s| spec_dict(py, s)).collect()
    }

    /// The value of a parameter by its qualified name (``"time_offset.tau_s"``).
    fn get(&self, name: &str) -> PyResult<f64> {
        self.inner
            .get(name)
            .ok_or_else(|| value_error(format!("unknown parameter {name:?}; known: {}", self.param_names().join(", "))))
    }

    /// This model with another effect: a catalogue id (see ``effect_catalogue()``) or a Python effect
    /// object; its parameters start at their null values, or at ``values`` (by unqualified name).
    #[pyo3(signature = (effect, **values))]
    fn with_effect(&self, effect: &Bound<'_, PyAny>, values: Option<BTreeMap<String, f64>>) -> PyResult<Self> {
        let (kind, adapter) = effect_from(effect, self.inner.model.n_wheels())?;
        let id = kind.id().to_string();
        let mut f = self.inner.with_effect(kind);
        for (name, v) in values.unwrap_or_default() {
            f.set(&format!("{id}.{name}"), v).map_err(|_| {
                let known: Vec<String> =
                    f.model.effects[f.model.effects.len() - 1].params().into_iter().map(|p| p.name).collect();
                value_error(format!("effect {id}: unknown parameter {name:?}; known: {}", known.join(", ")))
            })?;
        }
        let f = FittedModel::new(f.model, f.params).py()?;
        let mut py_effects = self.py_effects.clone();
        py_effects.extend(adapter);
        Ok(Self::from_fitted(f, py_effects))
    }

    /// This model with some parameters changed (by qualified name).
    fn with_params(&self, values: BTreeMap<String, f64>) -> PyResult<Self> {
        let mut f = self.inner.clone();
        for (name, v) in values {
            f.set(&name, v).py()?;
        }
        let f = FittedModel::new(f.model, f.params).py()?;
        Ok(Self::from_fitted(f, self.py_effects.clone()))
    }

    /// The model file text (TOML, as ``omnical train --out`` writes).
    fn to_toml(&self) -> PyResult<String> {
        model_file::to_toml(&self.inner, None).map_err(|e| value_error(e.to_string()))
    }

    /// Write the model file (TOML); ``load_model`` and ``omnical eval --model FILE`` read it back exactly.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let text = self.to_toml()?;
        py.detach(|| omni_cli::atomic::write_atomic(&path, text.as_bytes()))
            .map_err(|error| ModelFileError::Io { path: path.display().to_string(), error }.to_py_err())
    }

    /// Pickling: the model file text (exact: floats are written in their shortest round-trip form) and the
    /// Python effect objects it names (pickled by Python).
    fn __reduce__<'py>(&self, py: Python<'py>) -> crate::pickle::Reduced<'py, (String, Vec<Py<PyAny>>)> {
        let rebuild = py.import("omnical._omnical")?.getattr("_model_from_toml")?;
        let effects = self.py_effects.iter().map(|e| e.object(py).unbind()).collect();
        Ok((rebuild, (self.to_toml()?, effects)))
    }

    fn __repr__(&self) -> String {
        let effects = self.effects();
        format!("Model({}, {} wheels, effects [{}])", self.kinematics(), self.n_wheels(), effects.join(", "))
    }
}

/// Read a model file (TOML). ``effects``: Python effect objects the file names by id (files store only
/// ids and parameter values of effects).
///
/// >>> import tempfile, pathlib
/// >>> path = pathlib.Path(tempfile.mkdtemp()) / "model.toml"
/// >>> omnical.Model.paper().with_effect("time_offset", tau_s=0.06).save(path)
/// >>> omnical.load_model(path).params["time_offset.tau_s"]
/// 0.06
#[pyfunction]
#[pyo3(signature = (path, *, effects = Vec::new()))]
pub fn load_model(py: Python<'_>, path: PathBuf, effects: Vec<Bound<'_, PyAny>>) -> PyResult<PyModel> {
    if effects.is_empty() {
        let (f, interrupted) = py.detach(|| model_file::read_marked(&path)).py()?;
        warn_if_interrupted(py, &path, interrupted)?;
        return Ok(PyModel::from_fitted(f, Vec::new()));
    }
    let name = path.display().to_string();
    let text = py
        .detach(|| std::fs::read_to_string(&path))
        .map_err(|error| ModelFileError::Io { path: name.clone(), error }.to_py_err())?;
    let model = model_from_text(&text, &name, &effects)?;
    warn_if_interrupted(py, &path, toml::from_str::<ModelFile>(&text).is_ok_and(|f| f.interrupted()))?;
    Ok(model)
}

/// The CLI's warning on a model file marked `interrupted = true` (a training stopped by Ctrl-C), as a
/// `UserWarning`.
fn warn_if_interrupted(py: Python<'_>, path: &std::path::Path, interrupted: bool) -> PyResult<()> {
    if !interrupted {
        return Ok(());
    }
    let text = std::ffi::CString::new(format!("omnical.load_model: {}", model_file::interrupted_warning(path)))
        .map_err(|e| value_error(e.to_string()))?;
    PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyUserWarning>(), &text, 1)
}

/// Unpickling a `Model`: the model file text and the Python effects it names.
#[pyfunction]
#[pyo3(signature = (text, effects = Vec::new()))]
pub fn _model_from_toml(text: &str, effects: Vec<Bound<'_, PyAny>>) -> PyResult<PyModel> {
    model_from_text(text, "pickled model", &effects)
}

/// A model from model file text (`name` for messages) with the Python effects it names by id.
fn model_from_text(text: &str, name: &str, effects: &[Bound<'_, PyAny>]) -> PyResult<PyModel> {
    let invalid = |message: String| PyModelFileError::new_err(format!("{name}: {message}"));
    let file: ModelFile = toml::from_str(text).map_err(|e| invalid(omni_cli::toml_error::locate(text, &e)))?;
    // Python effects by id; the file's other effects must be built-ins.
    let mut custom: BTreeMap<String, (EffectKind, Arc<PyEffect>)> = BTreeMap::new();
    let n_wheels = file.wheel_names.len();
    for e in effects {
        if let (kind, Some(adapter)) = effect_from(e, n_wheels)? {
            custom.insert(kind.id().to_string(), (kind, adapter));
        }
    }
    let mut builtin = file.clone();
    builtin.effects.retain(|e| !custom.contains_key(&e.id));
    let base = builtin.to_fitted().map_err(invalid)?;
    if custom.is_empty() {
        return Ok(PyModel::from_fitted(base, Vec::new()));
    }
    let nb = base.model.n_base();
    let mut params = base.params[..nb].to_vec();
    let mut model =
        Model { kinematics: base.model.kinematics.clone(), effects: Vec::new(), integration: base.model.integration };
    let mut builtins = base.model.effects.iter().zip(base.model.effect_ranges());
    let mut adapters = Vec::new();
    for (i, entry) in file.effects.iter().enumerate() {
        if let Some((kind, adapter)) = custom.get(&entry.id) {
            for s in kind.params() {
                let v = entry.params.get(&s.name).ok_or_else(|| {
                    invalid(format!("effects[{i}] ({}): missing parameter {:?} ({})", entry.id, s.name, s.unit))
                })?;
                params.push(*v);
            }
            model.effects.push(kind.clone());
            adapters.push(adapter.clone());
        } else if let Some((e, r)) = builtins.next() {
            params.extend_from_slice(&base.params[r]);
            model.effects.push(e.clone());
        }
    }
    let f = FittedModel::new(model, params).map_err(|e| invalid(e.to_string()))?;
    Ok(PyModel::from_fitted(f, adapters))
}

/// The built-in effect catalogue: one dict per effect (id, stage, physics, params).
///
/// >>> first = omnical.effect_catalogue()[0]
/// >>> sorted(first) == ["id", "params", "physics", "stage"], first["id"] in omnical.CATALOGUE
/// (True, True)
#[pyfunction]
#[pyo3(signature = (*, n_wheels = 3))]
pub fn effect_catalogue(py: Python<'_>, n_wheels: usize) -> PyResult<Vec<Bound<'_, PyDict>>> {
    let mut out = Vec::new();
    for e in EffectKind::catalogue(n_wheels) {
        let d = PyDict::new(py);
        d.set_item("id", e.id())?;
        d.set_item("stage", stage_name(e.stage()))?;
        d.set_item("physics", e.describe())?;
        let specs: PyResult<Vec<_>> = e.params().iter().map(|s| spec_dict(py, s)).collect();
        d.set_item("params", specs?)?;
        out.push(d);
    }
    Ok(out)
}

/// A model argument: an `omnical.Model` (else `TypeError`), and its Python effects.
pub fn model_arg(o: &Bound<'_, PyAny>) -> PyResult<(FittedModel, Vec<Arc<PyEffect>>)> {
    let m = o.cast::<PyModel>().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "model must be an omnical.Model, got {}",
            o.get_type().name().map(|n| n.to_string()).unwrap_or_default()
        ))
    })?;
    let m = m.get();
    Ok((m.inner.clone(), m.py_effects.clone()))
}
