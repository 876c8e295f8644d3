//! `info`: what ROS recordings hold and what a read with the data options makes of them, as the CLI's
//! `omnical info --json` document ([`omni_cli::api::info`]).

use crate::errors::value_error;
use crate::run::{data_options, load_error};
use omni_cli::api::info as api;
use pyo3::prelude::*;
use std::path::PathBuf;

/// What the ROS recordings at ``paths`` hold and what :func:`load` with the same keywords makes of them:
/// the CLI's ``omnical info --json`` document as a dict.
///
/// ``paths``: ``.mcap``, ``.db3`` or ``.bag`` files, rosbag2 folders, or folders of them (a CSV run is no
/// recording: ``DatasetError``; a path that does not exist: ``FileNotFoundError``). The keywords are
/// :func:`load`'s (the CLI's data options), so ``info`` shows the read ``load`` would make.
///
/// Returns ``{"recordings": [...], "schema_version": 1, "command": "info"}``; each recording is a dict with
/// ``path``, ``start_unix_s`` [s], ``duration_s`` [s], ``messages``, ``topics`` (each ``topic``, ``type``,
/// ``messages``, ``rate_hz`` [Hz], ``joint_names``, ``role`` and ``why``) and ``read``: ``{"ok": True,
/// "runs": [...], "notes", "skipped", "clocks"}`` (each run's ``duration_s`` [s], ``wheel_samples``,
/// ``wheel_rate_hz`` [Hz], ``largest_wheel_gap_s`` [s], ``truth_poses``, ``truth_rate_hz`` [Hz],
/// ``largest_truth_gap_s`` [s], ``path_length_m`` [m]) or ``{"ok": False, "error": "..."}`` when the
/// read fails. The GIL is released.
///
/// >>> import tempfile
/// >>> out = tempfile.mkdtemp()
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0, out=out + "/train", imu=True)
/// >>> rec = omnical.info(out + "/train/00-r0.mcap")["recordings"][0]
/// >>> [t["role"] for t in rec["topics"] if t["topic"] == "/imu"], rec["read"]["runs"][0]["wheel_samples"]
/// (['imu'], 279)
#[pyfunction]
#[pyo3(signature = (*paths, robot = None, joints = None, joints_topic = None, gt_topic = None, gt_parent_frame = None, gt_child_frame = None, gt = None, gt_time_offset = None, gt_columns = None, gt_units = None, gt_kind = None, gt_window_s = None, gt_mount = None, gt_mount_start = None, gt_scans = None, split_s = None, skip_invalid = false, ticks_per_rev = None, max_file_mb = 1024))]
#[allow(clippy::too_many_arguments)]
pub fn info(
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
) -> PyResult<Py<PyAny>> {
    if paths.is_empty() {
        return Err(value_error("info() needs at least one path"));
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
    let text = py.detach(|| {
        api::info(&paths, &data).map(|infos| {
            let mut doc = api::document(&infos);
            keywords_in(&mut doc);
            doc.to_string()
        })
    });
    Ok(py.import("json")?.call_method1("loads", (text.map_err(load_error)?,))?.unbind())
}

/// Every string of `v` with the settings the library names as Python's keywords ([`crate::errors::keywords`]),
/// as the command line's `info --json` spells them as its flags.
fn keywords_in(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::String(s) => *s = crate::errors::keywords(s),
        serde_json::Value::Array(a) => a.iter_mut().for_each(keywords_in),
        serde_json::Value::Object(o) => o.values_mut().for_each(keywords_in),
        _ => {}
    }
}
