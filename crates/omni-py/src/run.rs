//! Runs and datasets: loaded from files (`load`) or built from numpy arrays (`Run(...)`), validated by
//! `omni_kin::Run::new` either way.

mod dataset;

pub use dataset::{_dataset_from_state, PyDataset};

use crate::arrays::{matrix, matrix_to_poses, poses_to_matrix, shape_text, to_matrix, to_vector, vector};
use crate::errors::{PyResultExt, ToPyErr, chain_text, keywords, value_error};
use crate::robot::robot_error;
use numpy::{PyArray1, PyArray2};
use omni_cli::api::load::{DataOptions, LoadError, LoadRequest};
use omni_cli::robot_file;
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
///
/// >>> import numpy as np
/// >>> t = np.arange(0.0, 1.0, 0.01)
/// >>> wheels = np.full((t.size, 3), 2.0)  # every wheel at 2 rad/s: APR-02 turns on the spot
/// >>> truth = np.array([[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.43], [0.99, 0.0, 0.0, 0.85]])
/// >>> run = omnical.Run(t, wheels, truth, name="spin")
/// >>> run.name, run.n_samples, run.n_wheels, run.truth.shape
/// ('spin', 100, 3, (3, 4))
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
            truth_position_only: false,
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
    /// Whether the ground truth gives positions only (UWB, GNSS, a tracker without heading): its headings are
    /// placeholders (0), never compared; each run's start heading is fitted with the model.
    #[getter]
    fn truth_position_only(&self) -> bool {
        self.inner.truth_position_only()
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

/// Unpickling a `Run`.
#[pyfunction]
pub fn _run_from_bytes(data: &[u8]) -> PyResult<PyRun> {
    Ok(PyRun { inner: crate::pickle::run_from_bytes(data)? })
}

/// Load runs from files and folders: omnical CSV (``.csv``), ROS 2 bags (``.mcap``, rosbag2 folders),
/// folders of them, or OptiOdom set folders. Options mirror the CLI's data flags.
///
/// ``robot``: the robot description (``robot.toml``, docs/formats.md) or ``"apr02"`` (the paper's robot);
/// default: a ``robot.toml`` beside the data (the first path's folder, or that folder itself) or in the
/// working directory, as the CLI's ``--robot``. Its joint names, topics, frames and ground-truth file fill
/// what the other options leave open, and its design becomes ``Dataset.design``.
///
/// ``gt``: the ground truth from a separate file instead of a topic, a TUM (``t x y z qx qy qz qw``) or CSV
/// file for one recording or a folder of files named after the recordings (``--gt``); ``gt_time_offset``
/// forces its clock offset [s] (wheel time = ground-truth time + offset; default: estimated from the data,
/// see ``Dataset.ground_truth_clocks``), ``gt_columns`` / ``gt_units`` name its CSV columns and units
/// (``{"t": "stamp_ns", "x": "pos_x_mm"}``, ``{"time": "ns", "length": "mm", "angle": "deg"}``).
/// ``gt_kind``: what the ground truth measures, ``"absolute"`` (motion capture, the default) or ``"relative"`` (a
/// sensor's own motion, as lidar or visual odometry: the runs become windows of ``gt_window_s`` seconds,
/// default 4, and ``train`` fits the sensor's mount with the wheels); ``gt_mount``: the measured point's pose
/// in the base frame when known, ``(x_m, y_m, yaw_deg)`` (the ground truth is moved to the base by it);
/// ``gt_mount_start``: where ``train`` starts the relative reference's sensor mount, ``(x_m, y_m, yaw_deg)``,
/// fitted from there (default: found from the motions, any yaw).
/// ``gt_scans``: the ground truth from a 2D lidar, its LaserScan topic (``"/scan"``) matched scan to scan
/// into the lidar's path (a relative reference).
/// ``recorded_odometry``: keep the runs' recorded odometry (for ``export``'s MCAP bags).
///
/// >>> import tempfile
/// >>> out = tempfile.mkdtemp()
/// >>> omnical._omnical.cli_main(["omnical", "simulate", "--out", out, "--runs-per-command", "1", "--duration", "1"])
/// 0
/// >>> ds = omnical.load(out + "/train")  # MCAP bags and the robot.toml beside them
/// >>> len(ds), ds[0].name, ds.design.n_wheels
/// (36, '00-r0', 3)
#[pyfunction]
#[pyo3(signature = (*paths, robot = None, joints = None, joints_topic = None, gt_topic = None, gt_parent_frame = None, gt_child_frame = None, gt = None, gt_time_offset = None, gt_columns = None, gt_units = None, gt_kind = None, gt_window_s = None, gt_mount = None, gt_mount_start = None, gt_scans = None, split_s = None, skip_invalid = false, ticks_per_rev = None, max_file_mb = 1024, recorded_odometry = false))]
// long: one parameter per keyword (the CLI's data flags, 21 of them) passed on to data_options, then the
// Dataset the binding keeps.
#[allow(clippy::too_many_arguments)]
pub fn load(
    py: Python<'_>,
    paths: Vec<PathBuf>,
    robot: Option<PathBuf>,
    joints: Option<Vec<String>>,
    joints_topic: Option<String>,
    gt_topic: Option<String>,
    gt_parent_frame: Option<String>,
    gt_child_frame: Option<String>,
    gt: Option<PathBuf>,
    gt_time_offset: Option<f64>,
    gt_columns: Option<std::collections::BTreeMap<String, String>>,
    gt_units: Option<std::collections::BTreeMap<String, String>>,
    gt_kind: Option<&str>,
    gt_window_s: Option<f64>,
    gt_mount: Option<(f64, f64, f64)>,
    gt_mount_start: Option<(f64, f64, f64)>,
    gt_scans: Option<String>,
    split_s: Option<f64>,
    skip_invalid: bool,
    ticks_per_rev: Option<f64>,
    max_file_mb: u64,
    recorded_odometry: bool,
) -> PyResult<PyDataset> {
    if paths.is_empty() {
        return Err(value_error("load() needs at least one path"));
    }
    let data = data_options(
        robot,
        joints,
        joints_topic,
        gt_topic,
        gt_parent_frame,
        gt_child_frame,
        gt,
        gt_time_offset,
        gt_columns,
        gt_units,
        gt_kind,
        gt_window_s,
        gt_mount,
        gt_mount_start,
        gt_scans,
        split_s,
        skip_invalid,
        ticks_per_rev,
        max_file_mb,
    )?;
    let request = LoadRequest { paths, data, recorded_odometry, wheels_only: false };
    // The CLI's lookup: robot=, else a robot.toml beside the data or in the working directory.
    let robot = request.robot().map_err(robot_error)?;
    let ds = py.detach(|| request.read_for_robot(robot)).map_err(load_error)?;
    let design = omni_cli::design::declared(&ds).map_err(|e| value_error(chain_text(&e)))?;
    let source = ds.robot_file.as_ref().map(|f| f.source.clone());
    let mut notes: Vec<String> = ds.notes.iter().map(|n| keywords(&n.to_string())).collect();
    if let Some(s @ robot_file::Source::Discovered(_)) = &source {
        notes.insert(0, format!("robot: {s}"));
    }
    let origin = omni_cli::dataset::Dataset {
        declared: ds.declared,
        robot_kind: ds.robot_kind,
        robot_file: ds.robot_file,
        ground_truth_clocks: ds.ground_truth_clocks,
        reference: ds.reference,
        mount: ds.mount,
        sensor_mount_from_recordings: ds.sensor_mount_from_recordings,
        mount_start: ds.mount_start,
        time_origins_s: ds.time_origins_s,
        recordings: ds.recordings,
        // The paths as given (a data folder too, so that no export lands inside it), then each file read.
        sources: request.paths.iter().map(|p| p.to_path_buf()).chain(ds.sources).collect(),
        ..Default::default()
    };
    Ok(PyDataset {
        runs: ds.runs,
        notes,
        skipped: ds.skipped.into_iter().map(|s| (s.source, keywords(&s.reason))).collect(),
        design,
        robot: source.map(|s| s.to_string()),
        origin,
    })
}

/// The data options of `load`'s (and `info`'s) keywords, as the CLI's data options.
#[allow(clippy::too_many_arguments)]
pub(crate) fn data_options(
    robot: Option<PathBuf>,
    joints: Option<Vec<String>>,
    joints_topic: Option<String>,
    gt_topic: Option<String>,
    gt_parent_frame: Option<String>,
    gt_child_frame: Option<String>,
    gt: Option<PathBuf>,
    gt_time_offset: Option<f64>,
    gt_columns: Option<std::collections::BTreeMap<String, String>>,
    gt_units: Option<std::collections::BTreeMap<String, String>>,
    gt_kind: Option<&str>,
    gt_window_s: Option<f64>,
    gt_mount: Option<(f64, f64, f64)>,
    gt_mount_start: Option<(f64, f64, f64)>,
    gt_scans: Option<String>,
    split_s: Option<f64>,
    skip_invalid: bool,
    ticks_per_rev: Option<f64>,
    max_file_mb: u64,
) -> PyResult<DataOptions> {
    Ok(DataOptions {
        robot: robot.map(|r| r.to_string_lossy().into_owned()),
        joints,
        joints_topic,
        gt_topic,
        gt_parent_frame,
        gt_child_frame,
        gt,
        gt_time_offset_s: gt_time_offset,
        gt_columns: key_values(gt_columns),
        gt_units: key_values(gt_units),
        gt_kind: gt_kind
            .map(str::parse)
            .transpose()
            .map_err(|e| value_error(format!("gt_kind {e}")))?
            .unwrap_or_default(),
        gt_window_s,
        gt_mount: gt_mount.map(|(x, y, yaw_deg)| omni_kin::Pose2::new(x, y, yaw_deg.to_radians())),
        gt_mount_start: gt_mount_start.map(|(x, y, yaw_deg)| omni_kin::Pose2::new(x, y, yaw_deg.to_radians())),
        gt_scans,
        split_s,
        split_every_s: None,
        skip_invalid,
        ticks_per_rev,
        max_file_mb,
    })
}

/// A dict of CSV columns or units as the CLI's `KEY=VALUE` list.
fn key_values(map: Option<std::collections::BTreeMap<String, String>>) -> Vec<String> {
    map.unwrap_or_default().into_iter().map(|(k, v)| format!("{k}={v}")).collect()
}

/// An error of the CLI's loading as the Python exception of its cause (`DatasetError`, `FileNotFoundError`,
/// `ValueError` for a robot description or a bad option).
pub(crate) fn load_error(e: LoadError) -> PyErr {
    match e {
        LoadError::Dataset(d) => d.to_py_err(),
        LoadError::Robot(r) => robot_error(r),
        e => value_error(chain_text(&e)),
    }
}

/// Runs from a `Dataset`, a `Run` or an iterable of `Run`s, and the design model the data declares (a
/// `Dataset`'s, else None).
pub fn runs_from(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<Run>, Option<FittedModel>)> {
    if let Ok(ds) = obj.cast::<PyDataset>() {
        let ds = ds.get();
        return Ok((ds.runs.clone(), ds.design.clone()));
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

/// Where the design of runs given as a `Dataset` came from (its robot description and declared geometry,
/// no runs); an empty one for other runs.
pub fn origin_of(obj: &Bound<'_, PyAny>) -> omni_cli::dataset::Dataset {
    match obj.cast::<PyDataset>() {
        Ok(ds) => {
            let o = &ds.get().origin;
            omni_cli::dataset::Dataset {
                declared: o.declared.clone(),
                robot_kind: o.robot_kind.clone(),
                robot_file: o.robot_file.clone(),
                reference: o.reference,
                mount: o.mount,
                sensor_mount_from_recordings: o.sensor_mount_from_recordings,
                mount_start: o.mount_start,
                time_origins_s: o.time_origins_s.clone(),
                recordings: o.recordings.clone(),
                sources: o.sources.clone(),
                ..Default::default()
            }
        }
        Err(_) => Default::default(),
    }
}
