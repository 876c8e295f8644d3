//! Why `omnical imu` could not fit the rotation row, or not write it ([`ImuError`]): each variant names the
//! recordings, topic or file it is about.

use super::{side_mount, units_text};
use crate::api::load::LoadError;
use crate::dataset::DatasetError;
use crate::design::DesignError;
use crate::model_file::ModelTextError;
use crate::out_path::OutPathError;
use omni_kin::KinError;
use std::path::PathBuf;

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
    /// The fit, made with the IMU upright for want of a stated mount, points against the design's row.
    #[error(
        "{}: topic {topic:?} (frame {frame_id:?}): the rotation row fitted with the IMU upright points against the \
         design's (their dot product is {dot:.3e} < 0): the IMU's z axis seems to point down. Publish its mount \
         on /tf_static (base_link → {frame_id}, as robot_state_publisher does from the URDF) or give it: \
         --mount 180,0,0 (ROLL,PITCH,YAW_DEG in degrees; Python: mount=(180, 0, 0))",
        files_text(recordings)
    )]
    UpsideDown {
        /// The recordings read upright.
        recordings: Vec<PathBuf>,
        /// The Imu topic.
        topic: String,
        /// The IMU's frame.
        frame_id: String,
        /// The fitted row · the design's row.
        dot: f64,
    },
    /// Read upright for want of a stated mount, the IMU's x or y axis turns more than its z: it is on its side.
    #[error(
        "{}: topic {topic:?} (frame {frame_id:?}): the IMU's {axis} axis turns with the base more than its z axis \
         (RMS x {:.2e}, y {:.2e}, z {:.2e} rad/s): the IMU seems mounted on its side. Publish its mount on \
         /tf_static (base_link → {frame_id}, as robot_state_publisher does from the URDF) or give it: --mount \
         {} if its {axis} axis points up ({} if down; ROLL,PITCH,YAW_DEG in degrees; Python: mount=…)",
        files_text(recordings), rms_rad_s[0], rms_rad_s[1], rms_rad_s[2], side_mount(axis, 1.0), side_mount(axis, -1.0)
    )]
    OnItsSide {
        /// The recordings read upright.
        recordings: Vec<PathBuf>,
        /// The Imu topic.
        topic: String,
        /// The IMU's frame.
        frame_id: String,
        /// `x` or `y`: the axis that turns most.
        axis: char,
        /// RMS of the angular velocity's x, y and z over those recordings. rad/s.
        rms_rad_s: [f64; 3],
    },
    /// The gyro turns the base many times more, or less, than the wheels through the design do: a unit
    /// (a gyro in deg/s, wheels in rpm) or a design far from the robot.
    #[error(
        "{}: topic {topic:?}: the rotation row the gyro fits is {scale:.3} times the design's (the gyro turns the \
         base {scale:.3} times as far as the wheels do through the design): {}",
        files_text(recordings), units_text(*scale)
    )]
    Units {
        /// The recordings read.
        recordings: Vec<PathBuf>,
        /// The Imu topic.
        topic: String,
        /// The fitted row over the design's (least squares along the design's row).
        scale: f64,
    },
    /// The data's robot has no design model.
    #[error(transparent)]
    Design(#[from] DesignError),
    /// The design's matrix, or the matrix with the fitted row, is not usable.
    #[error(transparent)]
    Kin(#[from] KinError),
    /// The model to calibrate the gyro against could not be read, or has another wheel count.
    #[error("--model")]
    Model(#[source] Box<dyn std::error::Error + Send + Sync>),
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

/// The first recordings of `paths`, named (three at most, then how many more).
fn files_text(paths: &[PathBuf]) -> String {
    let mut names: Vec<String> = paths.iter().take(3).map(|p| p.display().to_string()).collect();
    if paths.len() > 3 {
        names.push(format!("and {} more recordings", paths.len() - 3));
    }
    names.join(", ")
}
