//! An IMU's yaw rate as a rotation reference: each recording's wheels and gyro read, the wheel matrix's
//! rotation row and the gyro's bias fitted by least squares over windows ([`omni_kin::gyro`]), and the
//! design's matrix with that row written as a model file when asked. `omnical imu` prints the result
//! ([`ImuFit`]) or its JSON ([`document`]); Python's `omnical.imu` returns the JSON as a dict. The
//! translation rows need a reference that senses translation (motion capture, `--gt-scans`, end poses).
//!
//! The IMU's mount: the yaw rate is the base-z component of the IMU's angular velocity turned into the base
//! frame, by the mount given (`--mount`), else the recording's static transforms from `base_link` (else
//! `base_footprint`) to the messages' `header.frame_id`, else upright; a fit made upright whose row points
//! against the design's (their dot product below 0) is refused: the IMU is upside down, its mount unstated.

mod error;

use super::load::{DataOptions, LoadError, LoadRequest};
use crate::dataset::mcap::GyroRead;
use crate::dataset::{self, DatasetError};
use crate::design;
use crate::model_file;
use crate::out_path;
use crate::{atomic, dataset::Dataset};
pub use error::ImuError;
use omni_kin::gyro::{GyroSample, ImuMount, RotationFit, fit_rotation_row};
use omni_kin::{FittedModel, KinematicsKind, Run};
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
    /// The IMU's mount on the base (`--mount ROLL,PITCH,YAW_DEG`), used instead of the recordings' static
    /// transforms. Default: theirs, else upright.
    pub mount: Option<ImuMount>,
    /// A model fitted on a reference that senses the turning (motion capture, `--gt-scans`, a localization,
    /// end poses): its rotation row calibrates the gyro (scale and bias, [`AgainstModel`]).
    pub model: Option<super::ModelSpec>,
    /// How the wheels are read (robot description, joints, file size cap). The ground-truth options and
    /// `split_s` are not read: the IMU is the reference, and each recording one run.
    pub data: DataOptions,
}

/// A calibration corrects a few per cent; a gyro whose fitted row is more than this factor larger, or
/// smaller, than the design's measures in another unit, or the wheels do (`check_wheel_scale` has the same
/// factor for a ground truth).
const GYRO_MAX_FACTOR: f64 = 3.0;

/// The least windows a units refusal is made on.
const UNITS_MIN_WINDOWS: usize = 20;

/// What a fitted row `scale` times the design's says: the unit it is near (gyro or wheels), and what to do.
fn units_text(scale: f64) -> String {
    use std::f64::consts::TAU;
    // (factor, what), the row's scale when the gyro, or the wheels, report in another unit than rad/s.
    let units = [
        (
            360.0 / TAU,
            "the gyro reports deg/s (sensor_msgs/msg/Imu's angular_velocity is rad/s): convert it in the \
                       driver (× π/180)",
        ),
        (1000.0, "the gyro reports mrad/s: convert it to rad/s in the driver"),
        (
            TAU / 60.0,
            "the wheels' JointState velocities are rpm, not rad/s: convert them, or give the robot's wheel \
                      units",
        ),
        (TAU / 360.0, "the wheels' JointState velocities are deg/s, not rad/s: convert them"),
    ];
    match units.iter().find(|(f, _)| (scale / f - 1.0).abs() < 0.15) {
        Some((f, what)) => format!("{f:.3} is the factor when {what}"),
        None => "the gyro or the wheels measure in another unit than rad/s, or the design's wheel radii or spacing \
                 are far from the robot's: check the IMU's angular_velocity unit, the wheels' velocity unit and the \
                 robot description"
            .to_string(),
    }
}

/// Refuses a fitted row more than [`GYRO_MAX_FACTOR`] times larger or smaller than the design's (along it),
/// over at least [`UNITS_MIN_WINDOWS`] windows (a single short recording that barely turns says nothing:
/// measured, one 6 s run of the flower gives 0.26 with a rad/s gyro).
fn check_units(rec: &Recordings, topic: &str, fit: &RotationFit, design_row: &[f64]) -> Result<(), ImuError> {
    let dot: f64 = fit.row.iter().zip(design_row).map(|(a, b)| a * b).sum();
    let norm: f64 = design_row.iter().map(|b| b * b).sum();
    let scale = dot / norm;
    let within = (1.0 / GYRO_MAX_FACTOR..=GYRO_MAX_FACTOR).contains(&scale);
    if norm.is_nan() || norm <= 0.0 || scale <= 0.0 || within || fit.windows < UNITS_MIN_WINDOWS {
        return Ok(());
    }
    Err(ImuError::Units { recordings: rec.paths.clone(), topic: topic.to_string(), scale })
}

/// The `--mount` that turns the IMU's `axis` (`x` or `y`) to the base's z (`sign` 1) or against it (−1).
fn side_mount(axis: &char, sign: f64) -> String {
    match axis {
        'x' => format!("0,{},0", -90.0 * sign),
        _ => format!("{},0,0", 90.0 * sign),
    }
}

/// Sums of the squared angular velocity per axis (x, y, z) and the samples summed. rad²/s², count.
#[derive(Clone, Copy, Debug, Default)]
struct AxisPower {
    sum_sq: [f64; 3],
    count: usize,
}

impl AxisPower {
    fn add(&mut self, read: &GyroRead) {
        for r in &read.rates {
            (0..3).for_each(|i| self.sum_sq[i] += r.imu_rad_s[i] * r.imu_rad_s[i]);
        }
        self.count += read.rates.len();
    }

    /// RMS per axis. rad/s.
    fn rms(&self) -> [f64; 3] {
        self.sum_sq.map(|s| (s / self.count.max(1) as f64).sqrt())
    }
}

/// Where the IMU's mount came from.
#[derive(Clone, Debug, PartialEq)]
pub enum MountSource {
    /// Given (`--mount`, Python `mount=`).
    Given,
    /// The recording's static transforms, from this base frame.
    Transforms {
        /// `base_link` or `base_footprint`.
        base_frame: String,
    },
    /// None stated: upright.
    Assumed,
}

/// One mount used, and on how many recordings.
#[derive(Clone, Debug, PartialEq)]
pub struct MountUsed {
    /// Where it came from.
    pub source: MountSource,
    /// The IMU's frame (`header.frame_id`).
    pub frame_id: String,
    /// The mount.
    pub mount: ImuMount,
    /// Recordings read with it.
    pub recordings: usize,
}

impl MountUsed {
    /// Roll, pitch, yaw. Degrees.
    pub fn rpy_deg(&self) -> [f64; 3] {
        // + 0.0: −0.0 shows as 0.
        self.mount.rpy_rad().map(|a| a.to_degrees() + 0.0)
    }
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
    /// The IMU's mounts used (one unless the recordings state different ones).
    pub mounts: Vec<MountUsed>,
    /// The fitted row points against the design's (their dot product below 0) although every mount was
    /// stated: the mount or the wheels' signs are wrong.
    pub against_design: bool,
    /// The gyro against the `model`'s rotation row, when one was given.
    pub against_model: Option<AgainstModel>,
}

/// The gyro against a model fitted on a reference that senses the turning: the IMU alone cannot tell its
/// scale from the row; with the model's row known, it can.
#[derive(Clone, Debug)]
pub struct AgainstModel {
    /// The model, as given (`--model`).
    pub model: String,
    /// Its rotation row, one entry per wheel. rad/s per rad/s.
    pub row: Vec<f64>,
    /// The gyro's scale and bias against that row.
    pub gyro: omni_kin::gyro::GyroScaleFit,
    /// The row the IMU fits minus the model's, in the IMU fit's standard errors, per wheel: beyond about 3
    /// (with the gyro's scale at 1) the model's turning and the gyro's disagree.
    pub difference_sigmas: Vec<f64>,
}

/// The wheels of every recording (one run each) and their gyro samples on the run's clock, with the first
/// recording's dataset (its robot gives the design).
struct Recordings {
    first: Dataset,
    runs: Vec<Run>,
    gyro: Vec<Vec<GyroSample>>,
    mounts: Vec<MountUsed>,
    /// The recordings read upright for want of a stated mount.
    assumed: Vec<PathBuf>,
    /// Their angular velocity per axis.
    assumed_power: AxisPower,
    /// Every recording read.
    paths: Vec<PathBuf>,
}

/// The mount `read` is taken with: the one given, else the recording's, else upright.
fn mount_of(read: &GyroRead, given: Option<ImuMount>) -> MountUsed {
    let (source, mount) = match (given, &read.stated_mount) {
        (Some(m), _) => (MountSource::Given, m),
        (None, Some(s)) => (MountSource::Transforms { base_frame: s.base_frame.clone() }, s.mount),
        (None, None) => (MountSource::Assumed, ImuMount::UPRIGHT),
    };
    MountUsed { source, frame_id: read.frame_id.clone(), mount, recordings: 1 }
}

/// Counts `m` among the mounts used (a mount within 1e-9 rad of one already there is the same).
fn tally(mounts: &mut Vec<MountUsed>, m: MountUsed) {
    let same = |u: &&mut MountUsed| {
        u.source == m.source
            && u.frame_id == m.frame_id
            && u.mount.base_from_imu.angle_to(&m.mount.base_from_imu) < 1e-9
    };
    match mounts.iter_mut().find(same) {
        Some(u) => u.recordings += 1,
        None => mounts.push(m),
    }
}

/// Refuses an IMU whose stamps do not overlap the run's wheels (another clock), naming the file and topic.
fn check_overlap(path: &Path, topic: &str, run: &Run, read: &GyroRead) -> Result<(), DatasetError> {
    let (t, g) = (run.wheel_t_s(), &read.rates);
    let (Some(t0), Some(t1), Some(g0), Some(g1)) = (t.first(), t.last(), g.first(), g.last()) else {
        return Ok(());
    };
    if t1.min(g1.t_s) > t0.max(g0.t_s) {
        return Ok(());
    }
    let at = |t_s: f64| read.origin_s as f64 + t_s;
    Err(DatasetError::at(
        path,
        format!("topic {topic:?}"),
        format!(
            "its stamps ({:.3} to {:.3} s) do not overlap the wheels' ({:.3} to {:.3} s): the IMU is stamped on \
             another clock than the wheels' JointState; record both on one clock (both ROS time, or both sim time)",
            at(g0.t_s),
            at(g1.t_s),
            at(*t0),
            at(*t1)
        ),
    ))
}

/// The gyro's yaw rates with their clock checked against `run`'s wheels by the rules of every sensor
/// recorded with them ([`dataset::sensor_clock`]): moved when clearly on another clock, a lag named, an
/// unclear estimate kept as recorded with a note.
fn on_wheel_clock(path: &Path, topic: &str, run: &Run, mut rates: Vec<GyroSample>) -> Vec<GyroSample> {
    if let Some(clock) = dataset::sensor_clock::gyro_clock(run, &rates) {
        let shift_s = clock.applied_s();
        rates.iter_mut().for_each(|g| g.t_s += shift_s);
        if let Some(note) = clock.note(path, &format!("IMU {topic:?}")) {
            crate::note!("{note}");
        }
    }
    rates
}

/// Reads each recording's wheels and gyro; the gyro on the run's clock.
fn read(request: &ImuRequest) -> Result<Recordings, ImuError> {
    let (mut runs, mut gyro, mut mounts, mut assumed) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut assumed_power = AxisPower::default();
    let mut first = None;
    let paths = dataset::ros_recordings(&request.recordings)?;
    let max_bytes = request.data.max_file_mb.saturating_mul(1 << 20);
    for path in &paths {
        let load = LoadRequest { wheels_only: true, ..LoadRequest::new(std::slice::from_ref(path), &request.data) };
        let ds = load.read_for_robot(load.robot().map_err(LoadError::from)?)?;
        let sink = dataset::feed_ros(path, max_bytes, |zstd| dataset::mcap::ImuSink::new(&request.topic, zstd))?;
        let mut read = sink.finish(path)?;
        let used = mount_of(&read, request.mount);
        if used.source == MountSource::Assumed {
            assumed.push(path.clone());
            assumed_power.add(&read);
        }
        for run in &ds.runs {
            if let Some(&origin) = ds.time_origins_s.get(run.name()) {
                read.rebase(origin);
            }
            check_overlap(path, &request.topic, run, &read)?;
            runs.push(run.clone());
            gyro.push(on_wheel_clock(path, &request.topic, run, read.yaw_rates(&used.mount)));
        }
        tally(&mut mounts, used);
        first.get_or_insert(ds);
    }
    let first = first.ok_or(ImuError::NoRecording)?;
    Ok(Recordings { first, runs, gyro, mounts, assumed, assumed_power, paths })
}

/// Fits the rotation row and the gyro's bias from the recordings' IMU, beside the design's row; writes the
/// design's matrix with the fitted row to `request.out` when given (checked writable before anything is
/// read).
pub fn imu(request: &ImuRequest) -> Result<ImuFit, ImuError> {
    if let Some(out) = &request.out {
        out_path::check_file(out, "--out")?;
    }
    let rec = read(request)?;
    check_upright(&rec, &request.topic)?;
    let fit = fit_rotation_row(&rec.runs, &rec.gyro, request.window_s)
        .map_err(|source| ImuError::Fit { topic: request.topic.clone(), source })?;
    let design = FittedModel::nominal(design::model(KinematicsKind::Ik, &rec.first)?);
    // The matrix's rotation row, whatever the base (a differential drive's `ik` model leaves its structural
    // zeros, the vy row, out of its parameters).
    let design_row = design.ik()?.row(2).to_vec();
    let dot: f64 = fit.row.iter().zip(&design_row).map(|(a, b)| a * b).sum();
    check_units(&rec, &request.topic, &fit, &design_row)?;
    if dot < 0.0 && !rec.assumed.is_empty() {
        let frame_id = rec.mounts.iter().find(|m| m.source == MountSource::Assumed).map(|m| m.frame_id.clone());
        return Err(ImuError::UpsideDown {
            recordings: rec.assumed,
            topic: request.topic.clone(),
            frame_id: frame_id.unwrap_or_default(),
            dot,
        });
    }
    let against_model = request.model.as_ref().map(|m| against_model(m, &rec, &fit, request.window_s)).transpose()?;
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
        mounts: rec.mounts,
        against_design: dot < 0.0,
        against_model,
    })
}

/// The gyro's scale and bias against `spec`'s rotation row, and how far the IMU's own row lies from it.
fn against_model(
    spec: &super::ModelSpec,
    rec: &Recordings,
    fit: &RotationFit,
    window_s: f64,
) -> Result<AgainstModel, ImuError> {
    let model = spec.resolve(&rec.first).map_err(|e| ImuError::Model(Box::new(e)))?;
    let ik = model.ik().map_err(|e| ImuError::Model(Box::new(e)))?;
    let n = fit.row.len();
    if ik.n_wheels() != n {
        let why = format!("the model has {} wheels, the recordings {n}", ik.n_wheels());
        return Err(ImuError::Model(why.into()));
    }
    let row = ik.row(2).to_vec();
    let gyro = omni_kin::gyro::fit_gyro_scale(&rec.runs, &rec.gyro, window_s, &row)
        .map_err(|e| ImuError::Model(Box::new(e)))?;
    let difference_sigmas = (0..n).map(|i| (fit.row[i] - row[i]) / fit.row_std[i]).collect();
    Ok(AgainstModel { model: spec.to_string(), row, gyro, difference_sigmas })
}

/// Refuses the recordings read upright when their IMU's x or y axis turns more than its z (RMS): the IMU
/// is on its side (tilted more than 45°), its mount unstated.
fn check_upright(rec: &Recordings, topic: &str) -> Result<(), ImuError> {
    let rms = rec.assumed_power.rms();
    if rec.assumed.is_empty() || rms[0].hypot(rms[1]) <= rms[2] {
        return Ok(());
    }
    let frame_id = rec.mounts.iter().find(|m| m.source == MountSource::Assumed).map(|m| m.frame_id.clone());
    Err(ImuError::OnItsSide {
        recordings: rec.assumed.clone(),
        topic: topic.to_string(),
        frame_id: frame_id.unwrap_or_default(),
        axis: if rms[0] > rms[1] { 'x' } else { 'y' },
        rms_rad_s: rms,
    })
}

/// The design's matrix with the fitted rotation row, written atomically. The row's entries are set by name
/// (`m31` …): a differential drive's `ik` model leaves its structural zeros (the vy row) out of its
/// parameters.
fn write_model(design: &FittedModel, fit: &RotationFit, out: &Path) -> Result<(), ImuError> {
    let mut model = design.clone();
    let names = omni_kin::IkMatrix::entry_names(fit.row.len());
    for (name, v) in names[2 * fit.row.len()..].iter().zip(&fit.row) {
        model.set(name, *v)?;
    }
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
        "mounts": result.mounts.iter().map(mount_json).collect::<Vec<_>>(),
        "against_design": result.against_design,
        "against_model": result.against_model.as_ref().map(|a| json!({
            "model": a.model, "row": a.row, "gyro_scale": a.gyro.scale, "gyro_scale_std": a.gyro.scale_std,
            "bias_rad_s": a.gyro.bias_rad_s, "bias_std_rad_s": a.gyro.bias_std_rad_s,
            "residual_rms_rad": a.gyro.residual_rms_rad, "difference_sigmas": a.difference_sigmas,
        })),
    });
    if let serde_json::Value::Object(fields) = &mut doc {
        fields.insert("schema_version".into(), super::JSON_SCHEMA_VERSION.into());
        fields.insert("command".into(), "imu".into());
    }
    doc
}

/// One mount used, as the JSON document gives it: `source` (`given`, `transforms` or `assumed_upright`),
/// `base_frame` (with `transforms`), `frame_id`, `roll_deg`, `pitch_deg`, `yaw_deg`, `recordings`.
fn mount_json(m: &MountUsed) -> serde_json::Value {
    let [roll, pitch, yaw] = m.rpy_deg();
    let (source, base) = match &m.source {
        MountSource::Given => ("given", None),
        MountSource::Transforms { base_frame } => ("transforms", Some(base_frame.as_str())),
        MountSource::Assumed => ("assumed_upright", None),
    };
    json!({
        "source": source, "base_frame": base, "frame_id": m.frame_id, "roll_deg": roll, "pitch_deg": pitch,
        "yaw_deg": yaw, "recordings": m.recordings,
    })
}

/// A mount written `ROLL,PITCH,YAW_DEG` (degrees, URDF's `rpy`: `--mount 180,0,0` is upside down); `None`
/// unless it is three finite numbers.
pub fn mount_from_text(text: &str) -> Option<ImuMount> {
    let v: Vec<f64> = text.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().ok()?;
    (v.len() == 3 && v.iter().all(|x| x.is_finite()))
        .then(|| ImuMount::from_rpy_rad(v[0].to_radians(), v[1].to_radians(), v[2].to_radians()))
}

#[cfg(test)]
mod tests;
