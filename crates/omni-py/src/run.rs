//! Runs and datasets: loaded from files (`load`) or built from numpy arrays (`Run(...)`), validated by
//! `omni_kin::Run::new` either way.

use crate::arrays::{matrix, matrix_to_poses, poses_to_matrix, shape_text, to_matrix, to_vector, vector};
use crate::errors::{PyResultExt, value_error};
use crate::model::PyModel;
use numpy::{PyArray1, PyArray2};
use omni_cli::dataset::{self, LoadOptions, mcap::McapOptions};
use omni_kin::{Command, FittedModel, Run, RunData};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::PathBuf;

/// One recorded (or simulated) run: wheel-speed samples, ground-truth poses and the command.
///
/// Build one from arrays with ``Run(t_s, wheel_rad_s, truth, name=...)``; it is validated on
/// construction (``ValueError`` for NaN, stamps that do not increase, wheel data that does not cover the
/// ground truth, bad shapes). Immutable.
#[pyclass(frozen, name = "Run", module = "omnical._omnical")]
#[derive(Clone)]
pub struct PyRun {
    pub inner: Run,
}

#[pymethods]
impl PyRun {
    /// t_s: (N,) wheel-sample stamps [s], strictly increasing. wheel_rad_s: (N, W) wheel speeds
    /// [rad/s]. truth: (M, 4) ground-truth poses t_s [s], x_m [m], y_m [m], theta_rad [rad] of the
    /// measured point, M >= 2, inside the wheel samples' time span. command: (v_m_s, alpha_rad,
    /// omega_rad_s) when known. wheel_start_rad: (W,) wheel angles at the first sample [rad], when known.
    #[new]
    #[pyo3(signature = (t_s, wheel_rad_s, truth, *, name = "run", command = None, repetition = None, wheel_start_rad = None))]
    fn new(
        t_s: &Bound<'_, PyAny>,
        wheel_rad_s: &Bound<'_, PyAny>,
        truth: &Bound<'_, PyAny>,
        name: &str,
        command: Option<(f64, f64, f64)>,
        repetition: Option<u32>,
        wheel_start_rad: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let wheel_t_s = vector(t_s, "t_s")?;
        let (wheels, rows, n_wheels) = matrix(wheel_rad_s, "wheel_rad_s", "(N, W)")?;
        if rows != wheel_t_s.len() {
            return Err(value_error(format!(
                "wheel_rad_s must have one row per stamp in t_s: shape (N, W) with N = {}, got {}",
                wheel_t_s.len(),
                shape_text(&[rows, n_wheels])
            )));
        }
        let truth = matrix_to_poses(truth, "truth")?;
        let wheel_start_rad = match wheel_start_rad {
            Some(a) => vector(a, "wheel_start_rad")?,
            None => Vec::new(),
        };
        let data = RunData {
            name: name.to_string(),
            wheel_t_s,
            wheel_rad_s: wheels,
            n_wheels,
            truth,
            command: command.map(|(v_m_s, alpha_rad, omega_rad_s)| Command { v_m_s, alpha_rad, omega_rad_s }),
            repetition,
            recorded_odometry: Vec::new(),
            wheel_start_rad,
        };
        Ok(Self { inner: Run::new(data).py()? })
    }

    /// Run name (file name or ``train/03-r1``), used in every message about it.
    #[getter]
    fn name(&self) -> &str {
        self.inner.name()
    }
    /// Number of wheels W.
    #[getter]
    fn n_wheels(&self) -> usize {
        self.inner.n_wheels()
    }
    /// Number of wheel samples N.
    #[getter]
    fn n_samples(&self) -> usize {
        self.inner.n_samples()
    }
    /// (N,) wheel-sample stamps [s] (a copy).
    #[getter]
    fn t_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_vector(py, self.inner.wheel_t_s().to_vec())
    }
    /// (N, W) wheel speeds [rad/s] (a copy).
    #[getter]
    fn wheel_rad_s<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        to_matrix(py, self.inner.n_samples(), self.inner.n_wheels(), self.inner.wheel_rad_s().to_vec())
    }
    /// (M, 4) ground truth: t_s [s], x_m [m], y_m [m], theta_rad [rad] (a copy).
    #[getter]
    fn truth<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        poses_to_matrix(py, self.inner.truth())
    }
    /// (K, 4) the robot's own recorded odometry, same columns as ``truth`` (K = 0 when absent).
    #[getter]
    fn recorded_odometry<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        poses_to_matrix(py, self.inner.recorded_odometry())
    }
    /// (v_m_s, alpha_rad, omega_rad_s), or None when unknown.
    #[getter]
    fn command(&self) -> Option<(f64, f64, f64)> {
        self.inner.command().map(|c| (c.v_m_s, c.alpha_rad, c.omega_rad_s))
    }
    /// Repetition index of the same command (0-based), or None.
    #[getter]
    fn repetition(&self) -> Option<u32> {
        self.inner.repetition()
    }
    /// Pickling: every field as compact bytes (see `pickle.rs`), validated again on the way back.
    fn __reduce__<'py>(&self, py: Python<'py>) -> crate::pickle::Reduced<'py, (Bound<'py, PyBytes>,)> {
        let rebuild = py.import("omnical._omnical")?.getattr("_run_from_bytes")?;
        Ok((rebuild, (PyBytes::new(py, &crate::pickle::run_to_bytes(&self.inner)),)))
    }
    fn __repr__(&self) -> String {
        format!(
            "Run({:?}, {} samples × {} wheels, {} truth poses, {:.2} s)",
            self.inner.name(),
            self.inner.n_samples(),
            self.inner.n_wheels(),
            self.inner.truth().len(),
            self.inner.truth_duration_s()
        )
    }
}

/// Runs loaded from files, with what was skipped or noticed, and the design model the data declares.
///
/// Behaves as a sequence of :class:`Run` (``len``, indexing, iteration) and is accepted wherever runs
/// are.
#[pyclass(frozen, name = "Dataset", module = "omnical._omnical")]
pub struct PyDataset {
    pub runs: Vec<Run>,
    notes: Vec<String>,
    skipped: Vec<(String, String)>,
    pub design: FittedModel,
}

#[pymethods]
impl PyDataset {
    /// The runs, in the order their files were given.
    #[getter]
    fn runs(&self) -> Vec<PyRun> {
        self.runs.iter().map(|r| PyRun { inner: r.clone() }).collect()
    }
    /// Things to know about the data (e.g. "velocity empty: differentiated position").
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }
    /// (source, reason) of each input skipped with ``skip_invalid=True``.
    #[getter]
    fn skipped(&self) -> Vec<(String, String)> {
        self.skipped.clone()
    }
    /// The design model of the data: its declared geometry (OptiOdom metadata), else the paper's Eq. 7.
    #[getter]
    fn design(&self) -> PyModel {
        PyModel::from_fitted(self.design.clone(), Vec::new())
    }
    fn __len__(&self) -> usize {
        self.runs.len()
    }
    fn __getitem__(&self, index: isize) -> PyResult<PyRun> {
        let n = self.runs.len() as isize;
        let i = if index < 0 { index + n } else { index };
        if i < 0 || i >= n {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!(
                "run index {index} out of range for {n} runs"
            )));
        }
        Ok(PyRun { inner: self.runs[i as usize].clone() })
    }
    /// Pickling: the runs (as `Run` pickles them), notes, skipped inputs and the design's model file text.
    fn __reduce__<'py>(&self, py: Python<'py>) -> crate::pickle::Reduced<'py, DatasetState<'py>> {
        let rebuild = py.import("omnical._omnical")?.getattr("_dataset_from_state")?;
        let runs = self.runs.iter().map(|r| PyBytes::new(py, &crate::pickle::run_to_bytes(r))).collect();
        let design = omni_cli::model_file::to_toml(&self.design, None).map_err(value_error)?;
        Ok((rebuild, (runs, self.notes.clone(), self.skipped.clone(), design)))
    }
    fn __repr__(&self) -> String {
        format!("Dataset({} runs, {} skipped)", self.runs.len(), self.skipped.len())
    }
}

/// A pickled `Dataset`: its runs' bytes, notes, skipped inputs, design model file text.
type DatasetState<'py> = (Vec<Bound<'py, PyBytes>>, Vec<String>, Vec<(String, String)>, String);

/// Unpickling a `Run`.
#[pyfunction]
pub fn _run_from_bytes(data: &[u8]) -> PyResult<PyRun> {
    Ok(PyRun { inner: crate::pickle::run_from_bytes(data)? })
}

/// Unpickling a `Dataset`.
#[pyfunction]
pub fn _dataset_from_state(
    runs: Vec<Vec<u8>>,
    notes: Vec<String>,
    skipped: Vec<(String, String)>,
    design: &str,
) -> PyResult<PyDataset> {
    let runs = runs.iter().map(|b| crate::pickle::run_from_bytes(b)).collect::<PyResult<Vec<Run>>>()?;
    let file: omni_cli::model_file::ModelFile =
        toml::from_str(design).map_err(|e| value_error(format!("pickled dataset: design model: {e}")))?;
    let design = file.to_fitted().map_err(|e| value_error(format!("pickled dataset: design model: {e}")))?;
    Ok(PyDataset { runs, notes, skipped, design })
}

/// Load runs from files and folders: omnical CSV (``.csv``), ROS 2 bags (``.mcap``), folders of them,
/// or OptiOdom set folders. Options mirror the CLI's data flags.
#[pyfunction]
#[pyo3(signature = (*paths, joints = None, joints_topic = None, gt_topic = None, gt_parent_frame = None, gt_child_frame = None, split_s = None, skip_invalid = false, ticks_per_rev = None))]
#[allow(clippy::too_many_arguments)]
pub fn load(
    py: Python<'_>,
    paths: Vec<PathBuf>,
    joints: Option<Vec<String>>,
    joints_topic: Option<String>,
    gt_topic: Option<String>,
    gt_parent_frame: Option<String>,
    gt_child_frame: Option<String>,
    split_s: Option<f64>,
    skip_invalid: bool,
    ticks_per_rev: Option<f64>,
) -> PyResult<PyDataset> {
    if paths.is_empty() {
        return Err(value_error("load() needs at least one path"));
    }
    let mut mcap = McapOptions {
        joints_topic,
        truth_topic: gt_topic,
        truth_parent_frame: gt_parent_frame,
        truth_child_frame: gt_child_frame,
        split: split_s,
        skip_invalid,
        ..McapOptions::default()
    };
    if let Some(j) = joints {
        mcap.wheel_joints = j;
    }
    let opts = LoadOptions { skip_invalid, ticks_per_rev, mcap, ..LoadOptions::default() };
    let ds = py.detach(|| dataset::load(&paths, &opts)).py()?;
    // The same lookup as the CLI's `--model design`; where the data names no robot, Python still falls back
    // to the paper's APR-02 design (Eq. 7), where the CLI asks for a robot description.
    let design = omni_cli::design::declared(&ds)
        .map_err(|e| value_error(format!("{e:#}")))?
        .unwrap_or_else(FittedModel::paper_design);
    Ok(PyDataset {
        runs: ds.runs,
        notes: ds.notes,
        skipped: ds.skipped.into_iter().map(|s| (s.source, s.reason)).collect(),
        design,
    })
}

/// Runs from a `Dataset`, a `Run` or an iterable of `Run`s, and the design model the data declares (a
/// `Dataset`'s, else None).
pub fn runs_from(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<Run>, Option<FittedModel>)> {
    if let Ok(ds) = obj.cast::<PyDataset>() {
        let ds = ds.get();
        return Ok((ds.runs.clone(), Some(ds.design.clone())));
    }
    if let Ok(r) = obj.cast::<PyRun>() {
        return Ok((vec![r.get().inner.clone()], None));
    }
    let type_error = || {
        PyTypeError::new_err(format!(
            "{what} must be a Dataset, a Run or an iterable of Run, got {}",
            obj.get_type().name().map(|n| n.to_string()).unwrap_or_default()
        ))
    };
    let mut runs = Vec::new();
    for item in obj.try_iter().map_err(|_| type_error())? {
        let item = item?;
        match item.cast::<PyRun>() {
            Ok(r) => runs.push(r.get().inner.clone()),
            Err(_) => return Err(type_error()),
        }
    }
    Ok((runs, None))
}
