//! The ground truth from a `--gt` file (named after the recording, or the folder's file that covers it) for
//! a recording's or a CSV run's wheels: its clock aligned to the wheels' or refused, and notes that say which
//! file and which clock.

use super::{overlapping_file, within_wheels};
use crate::dataset::ground_truth::{ExternalTruth, GtClock, Kept, TruthSample};
use crate::dataset::mcap::common::{NS_PER_S, seconds_since};
use crate::dataset::{DatasetError, Note};
use omni_kin::clock::ClockAlignment;
use omni_kin::{Pose2, StampedPose};
use std::path::Path;

/// A `--gt` file's poses for wheel data that is not a ROS recording's (a CSV run, times `t_s` in seconds as
/// written): the file named after the recording `stem`, or the folder's file that covers it, on the wheel
/// clock by the same rules as a recording's ([`external_truth`]); notes say which file and its clock.
pub(crate) fn truth_for_wheels(
    path: &Path,
    ext: &ExternalTruth,
    stem: &str,
    t_s: &[f64],
    rad_s: &[f64],
    n_wheels: usize,
    notes: &mut Vec<Note>,
) -> Result<(Vec<StampedPose>, GtClock), DatasetError> {
    // Small numbers for the estimate: times since the first whole second.
    let origin_s = t_s.first().map_or(0.0, |t| t.floor());
    let rel: Vec<f64> = t_s.iter().map(|t| t - origin_s).collect();
    let origin = origin_s as i64;
    let folder_file;
    let ext = if ext.by_time.is_empty() {
        ext
    } else {
        folder_file = overlapping_file(path, ext, origin, &rel, notes)?;
        &folder_file
    };
    let (all, truth_where, label, clock) = external_file(ext, stem, origin, &rel, rad_s, n_wheels)?;
    let clock = clock.ok_or_else(|| {
        DatasetError::file(path, format!("no clock for the {} file", crate::api::settings::named("gt")))
    })?;
    let poses = within_wheels(path, &all, &rel, ("the wheel columns", &truth_where, &label), notes)?;
    Ok((poses.into_iter().map(|p| StampedPose { t_s: p.t_s + origin_s, ..p }).collect(), clock))
}

/// The poses of a ground-truth file on the wheel clock (seconds since `origin_s`), with the clock offset:
/// the forced one, or one estimated from the wheel data (`omni_kin::clock`). Errors name the file.
/// A `--gt` file's poses for a run on the wheel clock, its place for messages (`in FILE (+0.1 s clock
/// offset)`), its label (`ground truth FILE`) and its clock.
pub(super) fn external_file(
    ext: &ExternalTruth,
    stem: &str,
    origin_s: i64,
    t_s: &[f64],
    rad_s: &[f64],
    n_wheels: usize,
) -> Result<(Vec<StampedPose>, String, String, Option<GtClock>), DatasetError> {
    let (poses, clock) = external_truth(ext, stem, origin_s, t_s, rad_s, n_wheels)?;
    let file = ext.path.display();
    Ok((
        poses,
        format!("in {file} ({:+.4} s clock offset)", clock.offset_s),
        format!("ground truth {file}"),
        Some(clock),
    ))
}

fn external_truth(
    ext: &ExternalTruth,
    recording: &str,
    origin_s: i64,
    t_s: &[f64],
    rad_s: &[f64],
    n_wheels: usize,
) -> Result<(Vec<StampedPose>, GtClock), DatasetError> {
    let pose =
        |s: &TruthSample, t_s: f64| StampedPose { t_s, pose: Pose2 { x_m: s.x_m, y_m: s.y_m, theta_rad: s.yaw_rad } };
    let clock = |offset_s: f64, estimate: Option<ClockAlignment>| GtClock {
        recording: recording.to_string(),
        file: ext.path.clone(),
        offset_s,
        estimate,
        kept: None,
    };
    if let Some(offset_s) = ext.time_offset_s {
        let poses = ext.samples.iter().map(|s| pose(s, seconds_since(s.t_ns, origin_s) + offset_s)).collect();
        return Ok((poses, clock(offset_s, None)));
    }
    if ext.position_only {
        // The estimate compares body velocities, which need a heading: keep the stamps as recorded.
        let poses: Vec<StampedPose> = ext.samples.iter().map(|s| pose(s, seconds_since(s.t_ns, origin_s))).collect();
        let (w0, w1) = (t_s[0], t_s[t_s.len() - 1]);
        let (g0, g1) = (poses[0].t_s, poses[poses.len() - 1].t_s);
        if w1.min(g1) <= w0.max(g0) {
            return Err(DatasetError::Clock {
                path: ext.path.clone(),
                message: format!(
                    "gives positions only, so its clock cannot be estimated from the wheels (that needs a heading), \
                 and its stamps ({g0:.3}..{g1:.3} s) do not overlap the wheel data's ({w0:.3}..{w1:.3} s) of \
                 recording {recording:?} as recorded; give the offset with --gt-time-offset SECONDS"
                ),
            });
        }
        return Ok((poses, GtClock { kept: Some(Kept::PositionOnly), ..clock(0.0, None) }));
    }
    // The truth's times relative to its own first whole second (small numbers for the estimate).
    let truth_origin_s = ext.samples.first().map_or(0, |s| s.t_ns.div_euclid(NS_PER_S));
    let own: Vec<StampedPose> = ext.samples.iter().map(|s| pose(s, seconds_since(s.t_ns, truth_origin_s))).collect();
    let cannot = |message: String| DatasetError::Clock {
        path: ext.path.clone(),
        message: format!("cannot align its clock with recording {recording:?}: {message}"),
    };
    let a = omni_kin::clock::align_clocks(t_s, rad_s, n_wheels, &own).map_err(|e| cannot(e.to_string()))?;
    // t_wheel = t_truth + offset in absolute time: the relative offset less the origins' difference.
    let origins_s = (origin_s - truth_origin_s) as f64;
    let offset_s = a.offset_s + origins_s;
    let estimate = ClockAlignment { offset_s, coarse_offset_s: a.coarse_offset_s + origins_s, ..a };
    let as_recorded: Vec<StampedPose> = own.iter().map(|p| StampedPose { t_s: p.t_s - origins_s, ..*p }).collect();
    match clock_verdict(&estimate, t_s, &as_recorded) {
        ClockVerdict::Apply => {
            // own + a.offset_s is on the wheel clock since origin_s.
            let poses = own.iter().map(|p| StampedPose { t_s: p.t_s + a.offset_s, ..*p }).collect();
            Ok((poses, clock(offset_s, Some(estimate))))
        }
        ClockVerdict::KeepAsRecorded => {
            Ok((as_recorded, GtClock { kept: Some(Kept::Unclear), ..clock(0.0, Some(estimate)) }))
        }
        ClockVerdict::Refuse(why) => Err(cannot(why)),
    }
}

/// What a `--gt` file's clock estimate decides.
#[derive(Debug, PartialEq)]
enum ClockVerdict {
    /// Move the file's stamps by the estimate.
    Apply,
    /// The estimate is not clear, and the file's stamps overlap the wheel data as recorded: keep them (a
    /// note says so).
    KeepAsRecorded,
    /// Refuse, saying why.
    Refuse(String),
}

/// The rules of a clock estimate for a ground-truth file (docs/formats.md, "Ground truth from a separate
/// file"): a clear estimate ([`ClockAlignment::is_clear`]) is applied unless it is implausible (larger than
/// the recording while the stamps overlap as recorded, so both are on one time base and another stretch of
/// the file matched); one that is not clear is never applied: the stamps are kept when they overlap the
/// wheel data as recorded, else the file is refused. `t_s`: the wheel times; `as_recorded`: the file's
/// poses at their own stamps on the wheel clock (offset 0).
fn clock_verdict(a: &ClockAlignment, t_s: &[f64], as_recorded: &[StampedPose]) -> ClockVerdict {
    let (w0, w1) = (t_s[0], t_s[t_s.len() - 1]);
    let (g0, g1) = (as_recorded[0].t_s, as_recorded[as_recorded.len() - 1].t_s);
    let overlaps = w1.min(g1) > w0.max(g0);
    let clear = format!(
        "a clear estimate has a standard error of at most {:.0} ms and explains at least {:.0} % of the motion",
        omni_kin::clock::CLEAR_MAX_STD_ERROR_S * 1e3,
        omni_kin::clock::CLEAR_MIN_R_SQUARED * 100.0
    );
    let estimate = format!(
        "the best offset, {:+.4} s ± {:.1} ms, explains {:.1} % of the ground truth's motion",
        a.offset_s,
        a.std_error_s * 1e3,
        a.r_squared * 100.0
    );
    match (a.is_clear(), overlaps) {
        (true, true) if a.offset_s.abs() > w1 - w0 => ClockVerdict::Refuse(format!(
            "{estimate}, but it is longer than the recording ({:.1} s) while the file's stamps overlap the wheel \
             data as recorded (one time base): another stretch of the file looks alike; give the offset with \
             --gt-time-offset SECONDS (0 when both are on one clock)",
            w1 - w0
        )),
        (true, _) => ClockVerdict::Apply,
        (false, true) => ClockVerdict::KeepAsRecorded,
        (false, false) => ClockVerdict::Refuse(format!(
            "{estimate}: not a clear estimate ({clear}), and the file's stamps ({g0:.3}..{g1:.3} s) do not overlap \
             the wheel data's ({w0:.3}..{w1:.3} s) as recorded; give the offset with --gt-time-offset SECONDS"
        )),
    }
}
