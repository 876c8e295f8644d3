//! The `Dataset` class: runs loaded from files, with what was skipped or noticed, the robot description and
//! design they were read with, and its pickling (the runs' bytes and the reading's settings).

use super::PyRun;
use crate::errors::value_error;
use crate::model::PyModel;
use omni_kin::{FittedModel, Run};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// Runs loaded from files, with what was skipped or noticed, the robot description they were read with and
/// the design model of their robot (None when the data names no robot).
///
/// Behaves as a sequence of :class:`Run` (``len``, indexing, iteration) and is accepted wherever runs
/// are.
///
/// >>> import tempfile
/// >>> out = tempfile.mkdtemp()  # `omnical simulate` writes train/ and validation/ with a robot.toml
/// >>> omnical._omnical.cli_main(["omnical", "simulate", "--out", out, "--runs-per-command", "1", "--duration", "1"])
/// 0
/// >>> ds = omnical.load(out + "/train")
/// >>> len(ds), ds[0].n_wheels, ds.robot.endswith("(found beside the data)"), ds.design.kinematics
/// (36, 3, True, 'ik')
#[pyclass(frozen, name = "Dataset", module = "omnical._omnical")]
pub struct PyDataset {
    pub runs: Vec<Run>,
    pub(super) notes: Vec<String>,
    pub(super) skipped: Vec<(String, String)>,
    pub design: Option<FittedModel>,
    pub(super) robot: Option<String>,
    /// Where the design came from (the robot description and the geometry each input declares, with its
    /// runs: each run's own design), for the kinematics and `[priors]` of `train` and the designs runs
    /// are compared with; the declared geometries are pickled, the robot description is not.
    pub origin: omni_cli::dataset::Dataset,
}

#[pymethods]
impl PyDataset {
    /// The runs, in the order their files were given.
    #[getter]
    fn runs(&self) -> Vec<PyRun> {
        self.runs.iter().map(|r| PyRun { inner: r.clone() }).collect()
    }
    /// The clock offset each ground-truth file (``gt=``) was read with, one dict per recording: recording,
    /// file, offset_s [s] (wheel time = ground-truth time + offset_s), std_error_s [s] (None when forced by
    /// ``gt_time_offset``), estimated, r_squared. Empty without ``gt=`` (and after unpickling).
    #[getter]
    fn ground_truth_clocks<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let list: Vec<serde_json::Value> = self.origin.ground_truth_clocks.iter().map(|c| c.to_json()).collect();
        py.import("json")?.call_method1("loads", (serde_json::Value::Array(list).to_string(),))
    }
    /// Things to know about the data (e.g. "velocity empty: differentiated position", "robot: data/robot.toml
    /// (found beside the data)").
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }
    /// (source, reason) of each input skipped with ``skip_invalid=True``.
    #[getter]
    fn skipped(&self) -> Vec<(String, String)> {
        self.skipped.clone()
    }
    /// The design model of the data's robot, at its design values: the ``robot=`` description's (its
    /// design matrix), else the geometry the data declares (OptiOdom metadata), else a ``robot.toml``
    /// found beside the data or in the working directory. None when the data names no robot: ``train``
    /// and ``evaluate`` then need ``robot=`` or ``model=``.
    #[getter]
    fn design(&self) -> Option<PyModel> {
        self.design.as_ref().map(|d| PyModel::from_fitted(d.clone(), Vec::new()))
    }
    /// The robot description the runs were read with (its joints, topics and design): the ``robot=``
    /// file, ``"apr02 (built in: the paper's APR-02)"``, or ``"PATH (found beside the data)"``; None when
    /// there is none.
    #[getter]
    fn robot(&self) -> Option<String> {
        self.robot.clone()
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
    /// Pickling: the runs (as `Run` pickles them), notes, skipped inputs, the design's model file text, the
    /// declared designs and what the ground truth measures (with the sensor's mount when given).
    fn __reduce__<'py>(&self, py: Python<'py>) -> crate::pickle::Reduced<'py, DatasetState<'py>> {
        let rebuild = py.import("omnical._omnical")?.getattr("_dataset_from_state")?;
        let runs = self.runs.iter().map(|r| PyBytes::new(py, &crate::pickle::run_to_bytes(r))).collect();
        let design = match &self.design {
            Some(d) => omni_cli::model_file::to_toml(d, None).map_err(|e| value_error(e.to_string()))?,
            None => String::new(),
        };
        let declared =
            serde_json::to_string(&declared_state(&self.origin.declared)).map_err(|e| value_error(e.to_string()))?;
        let reading = reading_state(&self.origin);
        let state = (runs, self.notes.clone(), self.skipped.clone(), design, self.robot.clone(), declared, reading);
        Ok((rebuild, state))
    }
    fn __repr__(&self) -> String {
        format!("Dataset({} runs, {} skipped)", self.runs.len(), self.skipped.len())
    }
}

/// A pickled `Dataset`: its runs' bytes, notes, skipped inputs, design model file text ("" when none),
/// robot description, the geometry each input declares (JSON: [`DeclaredState`] items).
type DatasetState<'py> =
    (Vec<Bound<'py, PyBytes>>, Vec<String>, Vec<(String, String)>, String, Option<String>, String, String);

/// One input's declared design, pickled: source, robot type, geometry, run names.
type DeclaredState = (String, String, omni_kin::RobotGeometry, Vec<String>);

fn declared_state(declared: &[omni_cli::dataset::Declared]) -> Vec<DeclaredState> {
    declared
        .iter()
        .map(|d| (d.source.display().to_string(), d.kind.clone(), d.geometry.clone(), d.runs.clone()))
        .collect()
}

/// Unpickling a `Dataset`.
#[pyfunction]
#[pyo3(signature = (runs, notes, skipped, design, robot = None, declared = "", reading = ""))]
pub fn _dataset_from_state(
    runs: Vec<Vec<u8>>,
    notes: Vec<String>,
    skipped: Vec<(String, String)>,
    design: &str,
    robot: Option<String>,
    declared: &str,
    reading: &str,
) -> PyResult<PyDataset> {
    let runs = runs.iter().map(|b| crate::pickle::run_from_bytes(b)).collect::<PyResult<Vec<Run>>>()?;
    let design = if design.is_empty() {
        None
    } else {
        let file: omni_cli::model_file::ModelFile =
            toml::from_str(design).map_err(|e| value_error(format!("pickled dataset: design model: {e}")))?;
        Some(file.to_fitted().map_err(|e| value_error(format!("pickled dataset: design model: {e}")))?)
    };
    let declared: Vec<DeclaredState> = if declared.is_empty() {
        Vec::new()
    } else {
        serde_json::from_str(declared).map_err(|e| value_error(format!("pickled dataset: declared designs: {e}")))?
    };
    let declared = declared
        .into_iter()
        .map(|(source, kind, geometry, runs)| omni_cli::dataset::Declared {
            source: source.into(),
            kind,
            geometry,
            runs,
        })
        .collect();
    let origin = omni_cli::dataset::Dataset { declared, ..reading_from_state(reading)? };
    Ok(PyDataset { runs, notes, skipped, design, robot, origin })
}

/// What a pickled `Dataset` keeps of how its ground truth was read: what it measures (a relative
/// reference's runs are windows, and a fit adds the sensor's mount) and the mount when it was given
/// (x m, y m, yaw rad). JSON.
fn reading_state(ds: &omni_cli::dataset::Dataset) -> String {
    serde_json::json!({
        "reference": ds.reference.id(),
        "mount": ds.mount.map(|m| [m.x_m, m.y_m, m.theta_rad]),
        "sensor_mount_from_recordings": ds.sensor_mount_from_recordings,
        "mount_start": ds.mount_start.map(|m| [m.x_m, m.y_m, m.theta_rad]),
    })
    .to_string()
}

/// [`reading_state`]'s text back as a dataset's origin (empty: a pickle of an earlier version, read as
/// absolute ground truth).
fn reading_from_state(text: &str) -> PyResult<omni_cli::dataset::Dataset> {
    if text.is_empty() {
        return Ok(Default::default());
    }
    let bad = |what: &str| value_error(format!("pickled dataset: reference: {what}"));
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(&e.to_string()))?;
    let reference = v["reference"].as_str().ok_or_else(|| bad("no kind"))?.parse().map_err(|e| bad(&format!("{e}")))?;
    let pose = |key: &str| match v[key].as_array() {
        Some(m) => {
            let x: Vec<f64> = m.iter().filter_map(serde_json::Value::as_f64).collect();
            let [x, y, theta] = x[..] else { return Err(bad("a mount is x, y and yaw")) };
            Ok(Some(omni_kin::Pose2::new(x, y, theta)))
        }
        None => Ok(None),
    };
    let (mount, mount_start) = (pose("mount")?, pose("mount_start")?);
    let sensor_mount_from_recordings = v["sensor_mount_from_recordings"].as_bool().unwrap_or(false);
    Ok(omni_cli::dataset::Dataset { reference, mount, sensor_mount_from_recordings, mount_start, ..Default::default() })
}
