//! The ground truth of the runs read: each run's measured end pose set (`--gt-kind end-pose`), the ground
//! truth moved to the base (`--gt-mount`), a relative reference's runs cut into windows; and the check that
//! the wheels travel about as far as the ground truth.

use super::{DataOptions, LoadError};
use crate::api::settings::{named, named_with};
use crate::dataset::{self, Dataset, Note};
use crate::robot_file;
use omni_kin::reference::ReferenceKind;
use std::f64::consts::TAU;

/// Each run's placeholder end replaced by its measured end pose from `file`; a row naming no run read, or a
/// run without a row, is an error naming both.
pub(super) fn set_end_poses(
    ds: &mut Dataset,
    file: &std::path::Path,
    robot: Option<&robot_file::RobotFile>,
) -> Result<(), LoadError> {
    let measured = dataset::end_poses::read(file)?;
    // Each row against where the wheels put its run, through the design (when the robot has one).
    if let Some(ik) = robot.and_then(|r| r.description.design_ik().ok()) {
        for run in &ds.runs {
            let Some(e) = measured.iter().find(|e| e.run == run.name()) else { continue };
            if let Some((column, what)) = super::end_pose_check::check(run, e, &ik) {
                return Err(LoadError::EndPoseOff { file: file.to_path_buf(), line: e.line, column, what });
            }
        }
    }
    let names: Vec<&str> = ds.runs.iter().map(omni_kin::Run::name).collect();
    if let Some(e) = measured.iter().find(|e| !names.contains(&e.run.as_str())) {
        return Err(LoadError::EndPoseOfNoRun {
            file: file.to_path_buf(),
            line: e.line,
            run: e.run.clone(),
            runs: names.iter().map(|n| n.to_string()).collect(),
        });
    }
    let runs = std::mem::take(&mut ds.runs);
    ds.runs = runs
        .into_iter()
        .map(|run| {
            let Some(e) = measured.iter().find(|e| e.run == run.name()) else {
                return Err(LoadError::NoEndPose { run: run.name().to_string(), file: file.to_path_buf() });
            };
            let mut d = run.into_data();
            d.truth[1].pose = e.pose;
            Ok(omni_kin::Run::new(d)?)
        })
        .collect::<Result<_, LoadError>>()?;
    ds.notes.push(Note::general(format!(
        "measured end poses: {} runs from {}, each from rest at the origin at its first wheel sample to its measured \
         pose at its last (the end-pose cost)",
        ds.runs.len(),
        file.display()
    )));
    ds.reference = ReferenceKind::EndPose;
    Ok(())
}

/// The ground truth of every run moved from the measured point to the base by `--gt-mount`, with a note.
pub(super) fn move_to_base(ds: &mut Dataset, data: &DataOptions) -> Result<(), LoadError> {
    let Some(mount) = data.gt_mount else { return Ok(()) };
    let to_base = mount.inverse();
    let runs = std::mem::take(&mut ds.runs);
    ds.runs = runs
        .into_iter()
        .map(|run| {
            let mut d = run.into_data();
            for p in &mut d.truth {
                p.pose = p.pose.compose(&to_base);
            }
            omni_kin::Run::new(d)
        })
        .collect::<Result<_, _>>()?;
    ds.notes.push(Note::general(format!(
        "ground truth moved to the base from the measured point at x {:.4} m, y {:.4} m, yaw {:.3}° ({})",
        mount.x_m,
        mount.y_m,
        mount.theta_rad.to_degrees(),
        named("gt_mount")
    )));
    ds.mount = Some(mount);
    Ok(())
}

/// A relative reference's runs replaced by their windows ([`omni_kin::reference::windows`]), with a note;
/// `--gt-window` without `--gt-kind relative` is an error (it would change nothing).
pub(super) fn cut_into_windows(ds: &mut Dataset, data: &DataOptions) -> Result<(), LoadError> {
    use omni_kin::reference::{DEFAULT_WINDOW_S, windows};
    if data.gt_kind != ReferenceKind::Relative && data.gt_scans.is_none() {
        if let Some(window_s) = data.gt_window_s {
            return Err(LoadError::WindowUnused { window_s });
        }
        return Ok(());
    }
    let window_s = data.gt_window_s.unwrap_or(DEFAULT_WINDOW_S);
    let (mut runs, mut still, mut gaps) = (Vec::new(), 0, 0);
    let mut renamed: Vec<(String, Vec<String>)> = Vec::new();
    for run in &ds.runs {
        let w = windows(run, window_s).map_err(|source| LoadError::Windows { run: run.name().to_string(), source })?;
        still += w.still;
        gaps += w.gaps;
        renamed.push((run.name().to_string(), w.runs.iter().map(|r| r.name().to_string()).collect()));
        runs.extend(w.runs);
    }
    if runs.is_empty() {
        return Err(LoadError::NeverMoves { runs: ds.runs.len(), window_s });
    }
    for d in &mut ds.declared {
        d.runs = d
            .runs
            .iter()
            .flat_map(|n| renamed.iter().filter(move |(r, _)| r == n).flat_map(|(_, w)| w.clone()))
            .collect();
    }
    for (run, names) in &renamed {
        if let Some(origin) = ds.time_origins_s.remove(run) {
            ds.time_origins_s.extend(names.iter().map(|n| (n.clone(), origin)));
        }
        if let Some(recording) = ds.recordings.remove(run) {
            ds.recordings.extend(names.iter().map(|n| (n.clone(), recording.clone())));
        }
    }
    ds.notes.push(Note::general(format!(
        "relative reference: {} runs cut into {} windows of at most {window_s} s ({still} where the reference stands \
         still dropped{}){}",
        ds.runs.len(),
        runs.len(),
        if gaps > 0 { format!(", {gaps} gaps in the reference") } else { String::new() },
        match (ds.mount, ds.sensor_mount_from_recordings) {
            (Some(_), _) => "",
            (None, true) =>
                "; the sensor's mount is the recordings' static transform, corrected by a base model that \
                             can tell it from the base",
            (None, false) => "; the sensor's mount is fitted with the wheels",
        },
    )));
    ds.runs = runs;
    ds.reference = ReferenceKind::Relative;
    Ok(())
}

/// Ground truth must have gone this far (m) or turned this much (rad) to judge the wheels' scale.
const SCALE_MIN_M: f64 = 1.0;
const SCALE_MIN_RAD: f64 = std::f64::consts::PI;
/// A calibration corrects a few per cent; the wheels' distance or turning off by more than this factor
/// from the ground truth's is wheel data in another unit, or a design far from the robot.
const SCALE_MAX_FACTOR: f64 = 3.0;
/// A share of [`SCALE_MIN_M`] and [`SCALE_MIN_RAD`] enough to tell that distance or turning is *not* off by a
/// unit's factor (though not to tell that it is).
const SCALE_HINT: f64 = 0.25;
/// The wheels' distance off by more than this factor from the ground truth's (but within
/// [`SCALE_MAX_FACTOR`]) is fitted, and said: a constant of the robot's description is likely wrong.
pub const SCALE_WARN_FACTOR: f64 = 1.3;

/// Refuses runs whose wheels, through the robot description's design, travel or turn more than
/// [`SCALE_MAX_FACTOR`] times more, or less, than their ground truth, in every way the ground truth moved
/// enough to tell (distance, turning, or both, all off the same way): joints in rpm, degrees or counts read as
/// rad/s, or a radius in the wrong unit. All runs together first, then every run on its own, so that a run
/// that barely turns, or one recording of several in another unit, is judged too. A distance off by more
/// than [`SCALE_WARN_FACTOR`] within that is a note naming the ratio and the likely causes (the fit
/// corrects it: a metric reference determines the scale).
pub(super) fn check_wheel_scale(ds: &mut Dataset, robot: &robot_file::RobotFile) -> Result<(), LoadError> {
    use omni_kin::travel::Travel;
    let Ok(ik) = robot.description.design_ik() else { return Ok(()) };
    let all = Travel::of(&ds.runs, &ik);
    let mismatch = all
        .distance_ratio(SCALE_MIN_M)
        .filter(|r| !(1.0 / SCALE_WARN_FACTOR..=SCALE_WARN_FACTOR).contains(r))
        .map(|r| scale_mismatch_text(&all, r, all.turning_ratio(SCALE_MIN_RAD)));
    let refuse = |travel: Travel, run: Option<&str>| {
        let ratio = scale_off(&travel)?;
        // The factor of a unit read as rad/s, within what a calibration corrects besides.
        let units = [(60.0 / TAU, "rpm"), (360.0 / TAU, "deg_s"), (TAU.recip(), "rev_s")];
        let near_unit = units.into_iter().find(|(f, _)| (ratio / f - 1.0).abs() < 0.15);
        let runs = if run.is_some() { 1 } else { ds.runs.len() };
        Some(LoadError::WheelScale {
            robot: robot.source.clone(),
            runs,
            run: run.map(str::to_string),
            travel: Box::new(travel),
            ratio,
            near_unit,
        })
    };
    let only = match &ds.runs[..] {
        [one] => Some(one.name()),
        _ => None,
    };
    if let Some(e) = refuse(all, only) {
        return Err(e);
    }
    for run in &ds.runs {
        if let Some(e) = refuse(Travel::of(std::slice::from_ref(run), &ik), Some(run.name())) {
            return Err(e);
        }
    }
    ds.notes.extend(mismatch.map(Note::general));
    Ok(())
}

/// The wheels' ratio to the ground truth when it is off beyond [`SCALE_MAX_FACTOR`]: the distance's where
/// the ground truth went far enough, else the turning's; `None` when nothing can be told or it is not off.
/// A unit scales distance and turning alike, so when both can be told both must be off the same way (one
/// alone off is the data's or the design's own business).
fn scale_off(travel: &omni_kin::travel::Travel) -> Option<f64> {
    let (lo, hi) = (1.0 / SCALE_MAX_FACTOR, SCALE_MAX_FACTOR);
    let ratios = [travel.distance_ratio(SCALE_MIN_M), travel.turning_ratio(SCALE_MIN_RAD)];
    let told: Vec<f64> = ratios.into_iter().flatten().collect();
    let off = !told.is_empty() && (told.iter().all(|&r| r > hi) || told.iter().all(|&r| r < lo));
    // The other quantity, moved too little to judge on its own but enough to say it is not off (a quarter
    // of the minimum), rules a unit out: a unit would scale it too. What is left is the design's business.
    let hinted = [travel.distance_ratio(SCALE_MIN_M * SCALE_HINT), travel.turning_ratio(SCALE_MIN_RAD * SCALE_HINT)];
    let unit_ruled_out = hinted.into_iter().flatten().any(|r| (lo..=hi).contains(&r));
    (off && !unit_ruled_out).then(|| told[0])
}

/// The note of a wheel scale off by more than [`SCALE_WARN_FACTOR`]: the ratio, and what usually causes it.
fn scale_mismatch_text(travel: &omni_kin::travel::Travel, ratio: f64, turning: Option<f64>) -> String {
    let turn = match turning {
        Some(t) => format!(" and turn {t:.2}× its turning"),
        None => String::new(),
    };
    format!(
        "wheel scale: through the robot description's design the wheels travel {ratio:.2}× the ground truth's \
         distance ({:.2} m against {:.2} m){turn}, more than {:.0} % off: the fit corrects it (the reference \
         measures distance), but a constant of the description is likely wrong: the encoder's ticks per \
         revolution, a gear ratio, the wheel radius, or the joints' unit (counts or degrees read as radians)",
        travel.wheels_m,
        travel.truth_m,
        100.0 * (SCALE_WARN_FACTOR - 1.0)
    )
}

/// A static transform's mount is contradicted by the motions when they move it further than this (rad,
/// 20°) or [`CONTRADICTION_M`], and by more than [`CONTRADICTION_SIGMAS`] standard errors: a rough URDF
/// (a lidar placed 0.2 m off, 5° off) is the fit's to correct, a lidar turned or reversed is not.
const CONTRADICTION_RAD: f64 = 20.0 * std::f64::consts::PI / 180.0;
/// See [`CONTRADICTION_RAD`]. m.
const CONTRADICTION_M: f64 = 0.3;
/// See [`CONTRADICTION_RAD`].
const CONTRADICTION_SIGMAS: f64 = 5.0;
/// A sensor turning against the wheels with a slope explaining at least this share of its turning is
/// mirrored, not noisy.
const MIRRORED_EXPLAINED: f64 = 0.5;
/// The motions' estimate of the mount (or of its correction) is used, to start the fit or to contradict a
/// stated mount, only within this distance of the base (m: no robot carries its sensor further) and with
/// standard errors within [`MOUNT_ESTIMATE_STD_M`] and [`MOUNT_ESTIMATE_STD_RAD`]: a short run that turns at
/// one rate determines it poorly, whatever its scatter says.
const MOUNT_ESTIMATE_MAX_M: f64 = 2.0;
/// See [`MOUNT_ESTIMATE_MAX_M`]. m.
const MOUNT_ESTIMATE_STD_M: f64 = 0.05;
/// See [`MOUNT_ESTIMATE_MAX_M`]. rad (5°).
const MOUNT_ESTIMATE_STD_RAD: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// Whether the motions' mount estimate `e` is one to use (see [`MOUNT_ESTIMATE_MAX_M`]).
fn mount_estimate_determined(e: &omni_kin::hand_eye::MountEstimate) -> bool {
    let m = e.base_from_sensor;
    m.x_m.hypot(m.y_m) <= MOUNT_ESTIMATE_MAX_M
        && e.position_std_m <= MOUNT_ESTIMATE_STD_M
        && e.yaw_std_rad <= MOUNT_ESTIMATE_STD_RAD
}

/// Where a fit starts a relative reference's sensor mount ([`Dataset::mount_start`]): `--gt-mount-start`,
/// else the mount the motions give ([`omni_kin::hand_eye`]: the sensor's motion against the design's dead
/// reckoning, any yaw), with a note. Refused: a sensor whose path turns against the wheels (a mirrored
/// frame), and a mount stated (`--gt-mount`, a lidar's static transforms) that the motions contradict.
/// Nothing when the reference is not relative or the data has no design.
pub(super) fn start_sensor_mount(ds: &mut Dataset, data: &DataOptions) -> Result<(), LoadError> {
    use omni_kin::hand_eye::{estimate_mount, motion_pairs, rotation_agreement};
    if ds.reference != ReferenceKind::Relative {
        return match data.gt_mount_start {
            Some(_) => Err(LoadError::MountStartWith { flag: "an absolute reference (motion capture)" }),
            None => Ok(()),
        };
    }
    if data.gt_mount.is_some() && data.gt_mount_start.is_some() {
        return Err(LoadError::MountStartWith { flag: "`gt_mount`" });
    }
    ds.mount_start = data.gt_mount_start;
    let Some(ik) = crate::design::model_of(omni_kin::KinematicsKind::Ik, ds)
        .ok()
        .flatten()
        .and_then(|m| omni_kin::FittedModel::nominal(m).ik().ok())
    else {
        return Ok(());
    };
    let pairs = motion_pairs(&ds.runs, &ik);
    let (reference, recordings) = (reference_text(data), recordings_text(ds));
    if let Some(a) = rotation_agreement(&pairs)
        && a.slope < 0.0
        && a.explained >= MIRRORED_EXPLAINED
    {
        let (slope, explained, pairs, lidar) = (a.slope, a.explained, a.pairs, data.gt_scans.is_some());
        return Err(LoadError::MirroredReference { reference, recordings, lidar, slope, explained, pairs });
    }
    if data.gt_mount_start.is_some() {
        return Ok(());
    }
    // A mount stated (--gt-mount, the recordings' static transforms) leaves the motions' correction of it.
    let stated = match (data.gt_mount.is_some(), ds.sensor_mount_from_recordings) {
        (true, _) => Some("--gt-mount"),
        (false, true) => Some("the recordings' static transform (base → the scans' frame)"),
        (false, false) => None,
    };
    let Some(e) = estimate_mount(&pairs).filter(mount_estimate_determined) else {
        if ds.mount.is_some() {
            return Ok(());
        }
        let what = if ds.sensor_mount_from_recordings {
            "the correction of the static transform's mount is fitted from zero"
        } else {
            "the sensor's mount is fitted from zero"
        };
        ds.notes.push(Note::general(format!(
            "{what}: the {} stretches of the reference do not determine it alone (they need both turns and \
             straight motion, at more than one turning rate)",
            pairs.len()
        )));
        return Ok(());
    };
    let m = e.base_from_sensor;
    if let Some(stated) = stated {
        check_stated(&e, stated, (&reference, &recordings))?;
    }
    if ds.mount.is_some() {
        return Ok(());
    }
    ds.notes.push(Note::general(format!(
        "the sensor's mount {} at x {:.3} m, y {:.3} m, yaw {:.1}° (± {:.1} mm, ± {:.2}°: the sensor's motion against \
         the design's dead reckoning over {} stretches, whose distance is {:.3} times the sensor's), and refined by \
         the fit",
        if ds.sensor_mount_from_recordings { "is corrected from the static transform's, started" } else { "starts" },
        m.x_m,
        m.y_m,
        m.theta_rad.to_degrees(),
        1e3 * e.position_std_m,
        e.yaw_std_rad.to_degrees(),
        e.pairs,
        e.body_per_sensor
    )));
    ds.mount_start = Some(m);
    Ok(())
}

/// The relative reference as its options name it: a lidar's topic, a ground-truth topic or file.
fn reference_text(data: &DataOptions) -> String {
    match (&data.gt_scans, &data.gt_topic, &data.gt) {
        (Some(t), _, _) => format!("lidar {t:?} ({})", named("gt_scans")),
        (None, Some(t), _) => format!("topic {t:?} ({})", named_with("gt_kind", "relative")),
        (None, None, Some(f)) => format!("{} ({})", f.display(), named_with("gt_kind", "relative")),
        (None, None, None) => format!("the relative reference ({})", named_with("gt_kind", "relative")),
    }
}

/// The recordings the runs were read from (three at most, then how many more), or the runs' count.
fn recordings_text(ds: &Dataset) -> String {
    let files: std::collections::BTreeSet<String> = ds.recordings.values().map(|p| p.display().to_string()).collect();
    if files.is_empty() {
        return format!("{} runs", ds.runs.len());
    }
    let mut names: Vec<String> = files.iter().take(3).cloned().collect();
    if files.len() > 3 {
        names.push(format!("and {} more recordings", files.len() - 3));
    }
    names.join(", ")
}

/// Refuses a stated mount (`stated` names it) that the motions' estimate `e` moves beyond
/// [`CONTRADICTION_RAD`] or [`CONTRADICTION_M`] (and [`CONTRADICTION_SIGMAS`]).
fn check_stated(
    e: &omni_kin::hand_eye::MountEstimate,
    stated: &'static str,
    (reference, recordings): (&str, &str),
) -> Result<(), LoadError> {
    let m = e.base_from_sensor;
    let (sigmas_m, sigmas_rad) = (m.x_m.hypot(m.y_m) / e.position_std_m, m.theta_rad.abs() / e.yaw_std_rad);
    let far = m.x_m.hypot(m.y_m) > CONTRADICTION_M && sigmas_m > CONTRADICTION_SIGMAS
        || m.theta_rad.abs() > CONTRADICTION_RAD && sigmas_rad > CONTRADICTION_SIGMAS;
    if !far {
        return Ok(());
    }
    Err(LoadError::MountContradicts {
        reference: reference.to_string(),
        recordings: recordings.to_string(),
        stated,
        correction: m,
        position_std_m: e.position_std_m,
        yaw_std_rad: e.yaw_std_rad,
    })
}
