//! An IMU's yaw rate as a rotation reference: each recording's wheels and gyro read, the wheel matrix's
//! rotation row and the gyro's bias fitted by least squares over windows ([`omni_kin::gyro`]), and the
//! design's matrix with that row written as a model file when asked. `omnical imu` prints the result
//! ([`ImuFit`]) or its JSON ([`document`]); Python's `omnical.imu` returns the JSON as a dict. The
//! translation rows need a reference that senses translation (motion capture, `--gt-scans`, end poses).

use super::load::{DataOptions, LoadError, LoadRequest};
use crate::dataset::{self, DatasetError};
use crate::design::{self, DesignError};
use crate::model_file::{self, ModelTextError};
use crate::out_path::{self, OutPathError};
use crate::{atomic, dataset::Dataset};
use omni_kin::gyro::{GyroSample, RotationFit, fit_rotation_row};
use omni_kin::{FittedModel, KinError, KinematicsKind, Run};
use serde_json::json;
use std::path::{Path, PathBuf};

/// The default Imu topic.
pub const DEFAULT_IMU_TOPIC: &str = "/imu";
/// The default window of the fit. s.
pub const DEFAULT_WINDOW_S: f64 = 1.0;

/// What `omnical imu` is asked to do.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuRequest {
    /// ROS recordings (`.mcap`, `.db3` or `.bag` files, rosbag2 folders, or folders of them), each with the
    /// wheels' JointState and the IMU's `sensor_msgs/msg/Imu`; each recording is one run.
    pub recordings: Vec<PathBuf>,
    /// The IMU's topic (its `angular_velocity.z` is the yaw rate). Default [`DEFAULT_IMU_TOPIC`].
    pub topic: String,
    /// Window of the fit: each window's turn as the gyro integrates it against the wheels' angles. s.
    /// Default [`DEFAULT_WINDOW_S`].
    pub window_s: f64,
    /// Where to write the design's matrix with the fitted rotation row as a model file.
    pub out: Option<PathBuf>,
    /// How the wheels are read (robot description, joints, file size cap). The ground-truth options and
    /// `split_s` are not read: the IMU is the reference, and each recording one run.
    pub data: DataOptions,
}

/// Why `omnical imu` could not fit the rotation row, or not write it.
#[derive(Debug, thiserror::Error)]
pub enum ImuError {
    /// `out` cannot be written.
    #[error(transparent)]
    OutPath(#[from] OutPathError),
    /// The recordings' wheels could not be read.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The IMU topic could not be read (the message names the file and the topic).
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// The paths hold no ROS recording.
    #[error("no recording read")]
    NoRecording,
    /// The gyro and the wheels make no fit (too little turn, too little overlap, a bad window).
    #[error("topic {topic:?}")]
    Fit {
        /// The Imu topic.
        topic: String,
        /// Why.
        source: KinError,
    },
    /// The data's robot has no design model.
    #[error(transparent)]
    Design(#[from] DesignError),
    /// The model file's text could not be made.
    #[error(transparent)]
    ModelText(#[from] ModelTextError),
    /// The model file could not be written.
    #[error("writing {}", path.display())]
    Write {
        /// The model file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// The fitted rotation row beside the design's.
#[derive(Clone, Debug)]
pub struct ImuFit {
    /// The Imu topic read.
    pub topic: String,
    /// Window of the fit. s.
    pub window_s: f64,
    /// The rotation row, its standard errors, the gyro's bias and the fit's windows.
    pub fit: RotationFit,
    /// The design's rotation row, one entry per wheel. rad/s per rad/s.
    pub design_row: Vec<f64>,
    /// The wheels' names, in the rows' order.
    pub wheel_names: Vec<String>,
    /// The model file written.
    pub out: Option<PathBuf>,
}

/// The wheels of every recording (one run each) and their gyro samples on the run's clock, with the first
/// recording's dataset (its robot gives the design).
struct Recordings {
    first: Dataset,
    runs: Vec<Run>,
    gyro: Vec<Vec<GyroSample>>,
}

/// Reads each recording's wheels and gyro; the gyro on the run's clock.
fn read(request: &ImuRequest) -> Result<Recordings, ImuError> {
    let (mut runs, mut gyro) = (Vec::new(), Vec::new());
    let mut first = None;
    let max_bytes = request.data.max_file_mb.saturating_mul(1 << 20);
    for path in &dataset::ros_recordings(&request.recordings)? {
        let load = LoadRequest { wheels_only: true, ..LoadRequest::new(std::slice::from_ref(path), &request.data) };
        let ds = load.read_for_robot(load.robot().map_err(LoadError::from)?)?;
        let sink = dataset::feed_ros(path, max_bytes, |zstd| dataset::mcap::ImuSink::new(&request.topic, zstd))?;
        let mut read = sink.finish(path)?;
        for run in &ds.runs {
            if let Some(&origin) = ds.time_origins_s.get(run.name()) {
                read.rebase(origin);
            }
            runs.push(run.clone());
            gyro.push(read.samples.clone());
        }
        first.get_or_insert(ds);
    }
    Ok(Recordings { first: first.ok_or(ImuError::NoRecording)?, runs, gyro })
}

/// Fits the rotation row and the gyro's bias from the recordings' IMU, beside the design's row; writes the
/// design's matrix with the fitted row to `request.out` when given (checked writable before anything is
/// read).
pub fn imu(request: &ImuRequest) -> Result<ImuFit, ImuError> {
    if let Some(out) = &request.out {
        out_path::check_file(out, "--out")?;
    }
    let rec = read(request)?;
    let fit = fit_rotation_row(&rec.runs, &rec.gyro, request.window_s)
        .map_err(|source| ImuError::Fit { topic: request.topic.clone(), source })?;
    let design = FittedModel::nominal(design::model(KinematicsKind::Ik, &rec.first)?);
    let n = design.model.n_wheels();
    let design_row = design.params[2 * n..3 * n].to_vec();
    if let Some(out) = &request.out {
        write_model(&design, &fit, out)?;
    }
    Ok(ImuFit {
        topic: request.topic.clone(),
        window_s: request.window_s,
        fit,
        design_row,
        wheel_names: design.model.kinematics.wheel_names(),
        out: request.out.clone(),
    })
}

/// The design's matrix with the fitted rotation row, written atomically.
fn write_model(design: &FittedModel, fit: &RotationFit, out: &Path) -> Result<(), ImuError> {
    let mut model = design.clone();
    let n = model.model.n_wheels();
    model.params[2 * n..3 * n].copy_from_slice(&fit.row);
    let mut table = toml::Table::new();
    table.insert("reference".into(), "imu: the rotation row fitted, the translation rows the design's".into());
    table.insert("gyro_bias_rad_s".into(), fit.bias_rad_s.into());
    let text = model_file::to_toml(&model, Some(table))?;
    atomic::write_atomic(out, text.as_bytes()).map_err(|source| ImuError::Write { path: out.to_path_buf(), source })
}

/// The whole `omnical imu --json` document (docs/json.md): the fit's fields with `schema_version` and
/// `command: "imu"`.
pub fn document(result: &ImuFit) -> serde_json::Value {
    let mut doc = json!({
        "topic": result.topic, "window_s": result.window_s, "fit": result.fit, "design_row": result.design_row,
        "wheel_names": result.wheel_names,
        "out": result.out.as_ref().map(|p| p.display().to_string()),
    });
    if let serde_json::Value::Object(fields) = &mut doc {
        fields.insert("schema_version".into(), super::JSON_SCHEMA_VERSION.into());
        fields.insert("command".into(), "imu".into());
    }
    doc
}
