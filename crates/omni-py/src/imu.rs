//! `imu`: an IMU's yaw rate as a rotation reference, as the CLI's `omnical imu --json` document
//! ([`omni_cli::api::imu`]).

use crate::errors::{PyResultExt, value_error};
use crate::simulate::MountArg;
use omni_cli::api::imu::{self as api, ImuRequest};
use omni_cli::api::load::DataOptions;
use pyo3::prelude::*;
use std::path::PathBuf;

/// The wheel matrix's rotation row and the gyro's bias fitted from an IMU's yaw rate in ROS recordings:
/// the CLI's ``omnical imu --json`` document as a dict.
///
/// ``recordings``: ``.mcap``, ``.db3`` or ``.bag`` files, rosbag2 folders, or folders of them, each with the
/// wheels' JointState and the IMU's ``sensor_msgs/msg/Imu`` on ``topic``; each recording is one run. The
/// yaw rate [rad/s] is the base-z component of the angular velocity turned by the IMU's mount: ``mount``
/// ``(roll_deg, pitch_deg, yaw_deg)`` or ``"ROLL,PITCH,YAW_DEG"`` (URDF's rpy: ``(180, 0, 0)`` upside down),
/// else the recording's static transforms from ``base_link`` (else ``base_footprint``) to the messages'
/// frame, else upright (a fit that then points against the design's row raises ``DatasetError``: the IMU
/// seems upside down). ``window_s`` [s]: each window's turn as the gyro integrates
/// it is fitted against the wheels' angles. ``out``: write the design's matrix with the fitted rotation row
/// as a model file (the translation rows stay the design's; ``load_model`` reads it). ``robot``,
/// ``joints``, ``joints_topic``, ``skip_invalid`` and ``max_file_mb`` [MiB] are :func:`load`'s; its
/// ground-truth keywords are not taken (the IMU is the reference). An IMU senses no translation: the
/// translation rows need motion capture, a lidar (``load(gt_scans=)``) or measured end poses.
///
/// Returns ``{"fit": {...}, "design_row": [...], "wheel_names": [...], "topic", "window_s", "out",
/// "mounts", "against_design", "schema_version": 1, "command": "imu"}``: ``fit`` has ``row`` and ``row_std`` (ω per wheel speed,
/// rad/s per rad/s, one per wheel, in ``wheel_names``' order), ``bias_rad_s`` and ``bias_std_rad_s``
/// [rad/s], ``windows``, ``turned_rad`` [rad] and ``residual_rms_rad`` [rad]; ``design_row`` is the
/// design's rotation row [rad/s per rad/s]; ``out`` the model file written or None; ``mounts`` the IMU
/// mounts used, each ``{"source": "given" | "transforms" | "assumed_upright", "base_frame", "frame_id",
/// "roll_deg", "pitch_deg", "yaw_deg", "recordings"}``.
///
/// Raises ``DatasetError`` naming the file and the topic when a recording has no such Imu topic (a CSV run
/// is no recording: ``DatasetError``; a path that does not exist: ``FileNotFoundError``), ``ValueError``
/// when the runs turn too little for a fit or the window is not positive. The GIL is released.
///
/// >>> import tempfile
/// >>> out = tempfile.mkdtemp()
/// >>> _ = omnical.simulate(runs_per_command=1, duration_s=2.0, out=out + "/train", imu=True, imu_bias=0.005)
/// >>> doc = omnical.imu(out + "/train")
/// >>> doc["command"], doc["wheel_names"], doc["fit"]["windows"] > 50
/// ('imu', ['wheel_a', 'wheel_b', 'wheel_c'], True)
#[pyfunction]
#[pyo3(signature = (*recordings, topic = "/imu", window_s = 1.0, out = None, mount = None, robot = None, joints = None, joints_topic = None, skip_invalid = false, max_file_mb = 1024))]
#[allow(clippy::too_many_arguments)]
pub fn imu(
    py: Python<'_>,
    recordings: Vec<PathBuf>,
    topic: &str,
    window_s: f64,
    out: Option<PathBuf>,
    mount: Option<MountArg>,
    robot: Option<PathBuf>,
    joints: Option<Vec<String>>,
    joints_topic: Option<String>,
    skip_invalid: bool,
    max_file_mb: u64,
) -> PyResult<Py<PyAny>> {
    if recordings.is_empty() {
        return Err(value_error("imu() needs at least one recording"));
    }
    let data = DataOptions {
        robot: robot.map(|r| r.to_string_lossy().into_owned()),
        joints,
        joints_topic,
        skip_invalid,
        max_file_mb,
        ..DataOptions::default()
    };
    let mount = mount.map(|m| m.rpy("mount")).transpose()?.flatten();
    let request = ImuRequest { recordings, topic: topic.to_string(), window_s, out, mount, data };
    let text = py.detach(|| api::imu(&request).map(|fit| api::document(&fit).to_string())).py()?;
    Ok(py.import("json")?.call_method1("loads", (text,))?.unbind())
}
