//! Trajectories for other tools, as `omnical export` and Python's `export` write them: TUM files for evo,
//! MCAP bags with a model's odometry on `/omnical/odometry` for Foxglove.

use crate::atomic;
use crate::dataset::DatasetError;
use crate::dataset::mcap::copy::CopiedTopic;
use crate::dataset::mcap::{WriteOptions, write_run};
use crate::report::tum;
use omni_kin::odometry::{self, Selection};
use omni_kin::{FittedModel, KinError, Run, StampedPose};
use std::path::{Path, PathBuf};

/// Why a run's trajectories could not be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The model's parameters do not resolve for the run.
    #[error("run {run}")]
    Model {
        /// The run.
        run: String,
        /// Why.
        source: KinError,
    },
    /// A bag could not be written, or a recording's topics read.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// A TUM file could not be written.
    #[error("writing {}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// The odometry of the measured point: every wheel-sample step plus the exact predictions at the
/// ground-truth stamps (so tools that match poses by time find an exact match), in time order.
pub fn odometry_poses(model: &FittedModel, run: &Run) -> Result<Vec<StampedPose>, ExportError> {
    let res = model
        .model
        .resolve(&model.params)
        .map_err(|source| ExportError::Model { run: run.name().to_string(), source })?;
    let dense = odometry::integrate(&res, run);
    let mut poses: Vec<StampedPose> =
        dense.t_s.iter().zip(&dense.poses).map(|(&t_s, &pose)| StampedPose { t_s, pose }).collect();
    let at_truth = odometry::residuals(&res, run, Selection::Path(1));
    poses.retain(|p| !at_truth.iter().any(|r| (r.t_s - p.t_s).abs() < 1e-9));
    poses.extend(at_truth.iter().map(|r| StampedPose { t_s: r.t_s, pose: r.predicted }));
    poses.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
    Ok(poses)
}

/// Joint names in the model's column order: the model's own, or `--joints` when the model only has the
/// default names `wheel_a`, `wheel_b`, ….
pub fn joint_names(model: &FittedModel, joints: &[String]) -> Vec<String> {
    let names = model.model.kinematics.wheel_names();
    if names == omni_kin::geometry::default_wheel_names(names.len()) && joints.len() == names.len() {
        joints.to_vec()
    } else {
        names
    }
}

/// Writes one run's MCAP bag `DIR/<run>.mcap` (`--mcap`): its wheel data (joints `wheel_joints`), ground
/// truth, recorded odometry if any, and `model`'s odometry on /omnical/odometry, stamped in the recording's
/// time base (`recording_origin_s`, the Unix second its times count from); a run without one whose clock
/// starts before 0 s (a simulated one) is put at the simulator's epoch. `recorded` are the recording's own
/// topics (transforms, URDF, commands: `crate::dataset::recorded_topics`), of which the run's span is
/// carried over as recorded. Returns the path.
pub fn write_mcap(
    dir: &Path,
    run: &Run,
    model: &FittedModel,
    wheel_joints: &[String],
    recording_origin_s: Option<i64>,
    recorded: &[CopiedTopic],
) -> Result<PathBuf, ExportError> {
    let origin_s = match recording_origin_s {
        Some(o) => o,
        // Simulated clocks start before 0 s (as `simulate` does): its epoch.
        None if run.wheel_t_s().first().is_some_and(|&t| t < 0.0) => crate::dataset::mcap::SIM_EPOCH_S,
        None => 0,
    };
    // The run's span in log time (ns), saturating: stamps the bag cannot hold are refused by the writer.
    let log_ns = |t_s: f64| {
        let ns = origin_s.saturating_mul(1_000_000_000).saturating_add((t_s * 1e9).round() as i64);
        u64::try_from(ns).unwrap_or(0)
    };
    let t = run.wheel_t_s();
    let span = (log_ns(t[0]), log_ns(t[t.len() - 1]));
    let opts = WriteOptions {
        wheel_joints: wheel_joints.to_vec(),
        design_odometry: (!run.recorded_odometry().is_empty()).then(|| run.recorded_odometry().to_vec()),
        calibrated_odometry: Some(odometry_poses(model, run)?),
        origin_s,
        lidar: None,
        imu: None,
        copied: crate::dataset::mcap::copy::within(recorded, span.0, span.1),
    };
    let path = dir.join(format!("{}.mcap", tum::file_stem(run.name())));
    write_run(&path, run, &opts)?;
    Ok(path)
}

/// The recorded topics each run's MCAP export carries over, read from the run's recording
/// (`Dataset::recordings`) once for all the runs of that recording in a row.
pub struct RecordedTopics<'a> {
    recordings: &'a std::collections::BTreeMap<String, PathBuf>,
    max_file_bytes: u64,
    last: Option<(PathBuf, Vec<CopiedTopic>)>,
}

impl<'a> RecordedTopics<'a> {
    /// For runs read from `recordings` (by run name), files of at most `max_file_bytes`.
    pub fn new(recordings: &'a std::collections::BTreeMap<String, PathBuf>, max_file_bytes: u64) -> Self {
        Self { recordings, max_file_bytes, last: None }
    }

    /// The topics of `run`'s recording (none for a run not read from a ROS recording).
    pub fn for_run(&mut self, run: &Run) -> Result<&[CopiedTopic], DatasetError> {
        let Some(path) = self.recordings.get(run.name()) else { return Ok(&[]) };
        if self.last.as_ref().is_none_or(|(p, _)| p != path) {
            let topics = crate::dataset::recorded_topics(path, self.max_file_bytes)?;
            self.last = Some((path.clone(), topics));
        }
        Ok(self.last.as_ref().map_or(&[], |(_, t)| t.as_slice()))
    }
}

/// Writes one run's TUM files (`--tum`): `DIR/<run>.gt.tum`, `.design.tum` and `.calibrated.tum`, the
/// latter two the odometry of `design` and of `model` (named `spec` in the header), stamped in the
/// recording's Unix time when it has one (`recording_origin_s`). Returns the paths.
pub fn write_tum(
    dir: &Path,
    run: &Run,
    design: &FittedModel,
    model: &FittedModel,
    spec: &str,
    recording_origin_s: Option<i64>,
) -> Result<Vec<PathBuf>, ExportError> {
    let stem = tum::file_stem(run.name());
    let files = [
        ("gt", format!("run {}: ground truth", run.name()), run.truth().to_vec()),
        ("design", format!("run {}: odometry of the design model", run.name()), odometry_poses(design, run)?),
        ("calibrated", format!("run {}: odometry of {spec}", run.name()), odometry_poses(model, run)?),
    ];
    let mut written = Vec::with_capacity(files.len());
    for (kind, comment, poses) in files {
        let path = dir.join(format!("{stem}.{kind}.tum"));
        let header = format!("{comment}\ntimestamp tx ty tz qx qy qz qw (s, m, unit quaternion)");
        let text = tum::to_tum_at(&header, &poses, recording_origin_s.unwrap_or(0));
        atomic::write_atomic(&path, text.as_bytes())
            .map_err(|source| ExportError::Write { path: path.clone(), source })?;
        written.push(path);
    }
    Ok(written)
}
