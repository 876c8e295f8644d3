//! A 2D lidar as the reference of a ROS recording (`--gt-scans TOPIC`): its scans matched into the
//! sensor's own path ([`omni_kin::lidar::sensor_path`]), which replaces the runs' placeholder ground truth (the
//! recording was read wheels only). Each stretch of the path (a segment ends where the matches failed) is a
//! run of its own; a relative reference's windows cut them further (`api::load`). When the recording's
//! static transforms hold the lidar's pose on the base, the path is moved to the base by it (the fit then
//! corrects the mount around it); otherwise the mount is fitted, started where the motions put it.

use super::{DatasetError, Loaded, Note};
use crate::api::settings::named;
use omni_kin::lidar::{self, MatchSettings, Scan};
use omni_kin::{Run, StampedPose};
use std::path::Path;

/// Where the lidar's mount comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mount {
    /// The recording's static transforms, when they place the lidar.
    Stated,
    /// Given by the user (`--gt-mount`, `--gt-mount-start`): the static transforms are not used.
    Given,
}

/// The runs of `loaded` (read wheels only from the recording at `path`, with its scans on `topic`: the
/// recording is read once) with the lidar's path (matched with `settings`) as their ground truth, the mount
/// from the recording's static transforms (looked up from `[frames] base`; default `base_link`, else
/// `base_footprint`) unless `mount` is given.
pub(super) fn with_lidar_path(
    path: &Path,
    (topic, settings): (&str, &MatchSettings),
    mount: Mount,
    mut loaded: Loaded,
) -> Result<Loaded, DatasetError> {
    let Some(mut read) = loaded.scans.take() else {
        return Err(DatasetError::at(path, format!("topic {topic:?}"), "the scans were not read with the wheels"));
    };
    if mount == Mount::Given {
        read.base_from_sensor = None;
    }
    let sensor = lidar::sensor_path(&read.scans, settings)
        .map_err(|e| DatasetError::at(path, format!("topic {topic:?}"), e.to_string()))?;
    if sensor.matched == 0 {
        return Err(DatasetError::at(
            path,
            format!("topic {topic:?}"),
            format!(
                "no scan matched the one before it ({} rejected: {}; {}): the scans see too little structure, or \
                 the robot moves too far between scans; the lidar cannot be the reference here",
                sensor.rejected,
                rejections(&sensor.rejected_why),
                returns_text(&read.scans, settings)
            ),
        ));
    }
    // Scan times on the runs' clock (seconds since the recording's first wheel message's second).
    let shift_s = loaded.origin_s.map_or(0.0, |o| (read.origin_s - o) as f64);
    let to_base = read.base_from_sensor.map(|m| m.inverse());
    let segments: Vec<Vec<StampedPose>> = sensor
        .segments
        .iter()
        .map(|seg| {
            seg.iter()
                .map(|p| StampedPose { t_s: p.t_s + shift_s, pose: to_base.map_or(p.pose, |b| p.pose.compose(&b)) })
                .collect()
        })
        .collect();
    // The lidar's clock against the wheels (dataset::sensor_clock): the stretch that gives the sharpest
    // estimate (the longest may not give one at all: its match noise can hide the motion's shape).
    let clock = segments
        .iter()
        .filter_map(|s| super::sensor_clock::sensor_clock(&loaded.runs, s))
        .min_by(|a, b| a.estimate.std_error_s.total_cmp(&b.estimate.std_error_s));
    let clock_shift_s = clock.map_or(0.0, |c| c.applied_s());
    let segments: Vec<Vec<StampedPose>> = segments
        .into_iter()
        .map(|seg| seg.into_iter().map(|p| StampedPose { t_s: p.t_s + clock_shift_s, ..p }).collect())
        .collect();
    let mut runs = Vec::new();
    for run in &loaded.runs {
        runs.extend(stretches(run, &segments).map_err(|e| DatasetError::Run { path: path.to_path_buf(), error: e })?);
    }
    if runs.is_empty() {
        return Err(DatasetError::at(
            path,
            format!("topic {topic:?}"),
            "the lidar's path does not overlap the wheel data (two matched scans within it are needed)",
        ));
    }
    loaded.notes.extend(notes(path, topic, (&read, mount), &sensor, runs.len()));
    loaded.notes.extend(clock.and_then(|c| c.note(path, &format!("lidar {topic:?}"))));
    loaded.runs = runs;
    loaded.lidar_mount_from_tf = Some(read.base_from_sensor.is_some());
    Ok(loaded)
}

/// `run` once per stretch of `segments` that has two poses within its wheel data: named as the run when
/// there is one, `RUN~K` when there are more.
fn stretches(run: &Run, segments: &[Vec<StampedPose>]) -> Result<Vec<Run>, omni_kin::KinError> {
    let (w0, w1) = (run.wheel_t_s()[0], run.wheel_t_s()[run.n_samples() - 1]);
    let within: Vec<Vec<StampedPose>> = segments
        .iter()
        .map(|s| s.iter().copied().filter(|p| (w0..=w1).contains(&p.t_s)).collect::<Vec<_>>())
        .filter(|s| s.len() >= 2)
        .collect();
    let many = within.len() > 1;
    within
        .into_iter()
        .enumerate()
        .map(|(k, truth)| {
            let name = if many { format!("{}~{}", run.name(), k + 1) } else { run.name().to_string() };
            omni_kin::reference::with_truth(run, truth, name)
        })
        .collect()
}

/// Rejection counts as `kind N, kind M`.
fn rejections(why: &std::collections::BTreeMap<&'static str, usize>) -> String {
    if why.is_empty() {
        return "none".into();
    }
    why.iter().map(|(k, n)| format!("{k} {n}")).collect::<Vec<_>>().join(", ")
}

/// Where the lidar's mount came from, in words: given, the chain of static transforms, or why there is none.
fn mount_text(read: &super::mcap::ScanRead, mount: Mount) -> String {
    let frame = &read.frame_id;
    let upside_down = if read.mirrored { " (mounted upside down: its scans are read mirrored)" } else { "" };
    let from_zero = "the lidar's mount is fitted, started where the motions put it";
    if mount == Mount::Given {
        return format!(
            "its mount is given ({} or {}): the static transforms are not used{upside_down}",
            named("gt_mount"),
            named("gt_mount_start")
        );
    }
    match read.base_from_sensor {
        Some(m) => format!(
            "its path moved to the base by the static transforms {}{upside_down} (x {:.3} m, y {:.3} m, yaw \
             {:.2}°); a base model that can tell a mount from the base corrects it (a free matrix keeps it)",
            read.chain_text(),
            m.x_m,
            m.y_m,
            m.theta_rad.to_degrees()
        ),
        None if frame.is_empty() => {
            format!("the scans' header.frame_id is empty, so no static transform places the lidar: {from_zero}")
        }
        None => format!(
            "no static transform from the base (base_link, base_footprint or [frames] base) to {frame:?}: {from_zero}"
        ),
    }
}

/// The notes a lidar reference leaves: where the mount came from (the same words for every recording, so a
/// load says it once), and the rejected matches and stretches when there were any.
fn notes(
    path: &Path,
    topic: &str,
    (read, mount): (&super::mcap::ScanRead, Mount),
    sensor: &lidar::SensorPath,
    runs: usize,
) -> Vec<Note> {
    let text = format!("lidar {topic:?} matched scan to scan as the reference; {}", mount_text(read, mount));
    let mut out = vec![Note::about(path, text)];
    if read.by_log_time {
        out.push(Note::about(
            path,
            format!(
                "lidar {topic:?}: header.stamp is 0 (never filled by the driver): the scans are timed by their log time"
            ),
        ));
    }
    if let Some(m) = &read.angle_max_mismatch {
        out.push(Note::about(path, m.describe(topic)));
    }
    if sensor.deskewed > 0 {
        out.push(Note::about(
            path,
            format!(
                "lidar {topic:?}: {} scans de-skewed (beams measured over the sweep: LaserScan time_increment)",
                sensor.deskewed
            ),
        ));
    }
    if sensor.rejected > 0 {
        let rms = {
            let mut r: Vec<f64> = sensor.qualities.iter().map(|q| q.rms_m).collect();
            r.sort_by(f64::total_cmp);
            r.get(r.len() / 2).copied().unwrap_or(f64::NAN)
        };
        out.push(Note::about(
            path,
            format!(
                "lidar {topic:?}: {} of {} scan matches rejected ({}), median match RMS {:.1} mm; {} stretch{} of \
                 accepted matches",
                sensor.rejected,
                sensor.rejected + sensor.matched,
                rejections(&sensor.rejected_why),
                rms * 1e3,
                runs,
                if runs == 1 { "" } else { "es" },
            ),
        ));
    }
    out
}

/// What the scans returned, for a message about matches that failed: `each scan returned a median of N of
/// its M beams (range_min … range_max m; a match needs K)`. A lidar whose range is short for its room
/// (most beams beyond `range_max`) returns too few points to match.
pub fn returns_text(scans: &[Scan], settings: &MatchSettings) -> String {
    let mut returns: Vec<usize> =
        scans.iter().map(|s| (0..s.ranges_m.len()).filter(|&i| s.is_return(i)).count()).collect();
    returns.sort_unstable();
    let Some(first) = scans.first() else { return "no scans".into() };
    format!(
        "each scan returned a median of {} of its {} beams (range {:.2} to {:.2} m; a match needs {} points)",
        returns[returns.len() / 2],
        first.ranges_m.len(),
        first.range_min_m,
        first.range_max_m,
        settings.min_inliers
    )
}
