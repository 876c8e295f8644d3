//! What a run's ground truth is a measurement of. Motion capture gives the pose of a point on the robot in a
//! fixed world frame ([`ReferenceKind::Absolute`]). A sensor's own odometry (lidar scan matching, visual
//! odometry) gives the motion of the sensor, mounted at an unknown pose on the robot, in a frame of its own
//! that drifts ([`ReferenceKind::Relative`]): such a path is trusted only over short windows. [`windows`] cuts a
//! run into windows, each a run of its own that starts at the reference's pose there, so that every
//! objective compares the model's motion with the sensor's over the window only; the sensor's mount is the
//! `sensor_offset_yaw` effect, fitted with the wheels (the model's predicted sensor pose is the body pose
//! composed with the mount, and each window starts the body at the reference pose composed with the
//! mount's inverse, which makes the comparison exactly `mount⁻¹ · Δbody · mount` against the sensor's motion).

use crate::choice;
use crate::error::KinError;
use crate::pose::StampedPose;
use crate::run::{Run, RunData};

/// What the ground truth measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceKind {
    /// The pose of a point on the robot in a fixed world frame (motion capture, a total station).
    Absolute,
    /// The motion of a sensor mounted on the robot at an unknown pose, in a frame of its own that may drift
    /// (lidar or visual odometry): compared over windows, the mount fitted with the wheels.
    Relative,
    /// Hand-measured end poses (a tape measure, UMBmark): the robot starts at rest at the origin and its
    /// measured pose where it stopped is the only reference; the paper's end-pose cost.
    EndPose,
}

choice!(ReferenceKind, default = Absolute, {
    Absolute => "absolute": "the pose of a point on the robot in a fixed world frame (motion capture)",
    Relative => "relative": "a sensor's own motion (lidar or visual odometry): compared over windows, the \
                             sensor's mount fitted with the wheels",
    EndPose => "end_pose": "hand-measured end poses (a tape measure): --gt names a table run,x_m,y_m,yaw_deg, each \
                            in the frame of the run's start",
});

/// Windows of a relative reference shorter than this are not cut (s).
pub const MIN_WINDOW_S: f64 = 0.2;
/// The default window of a relative reference (s): long enough for the wheels' errors to show against the
/// reference's noise, short enough for its drift to stay small.
pub const DEFAULT_WINDOW_S: f64 = 4.0;
/// A window whose reference moves less than this (m) and turns less than [`STILL_RAD`] says nothing.
pub const STILL_M: f64 = 0.01;
/// See [`STILL_M`] (rad, about 0.6°).
pub const STILL_RAD: f64 = 0.01;
/// A gap in the reference longer than this many of its median intervals ends a window: the sensor lost
/// track (rejected scan matches), and its path across the gap is not to be trusted.
pub const GAP_INTERVALS: f64 = 10.0;
/// Wheel samples kept beyond each end of a window (s), so that a clock lag still finds wheel data.
pub const WHEEL_MARGIN_S: f64 = 0.5;

/// A run cut into windows.
#[derive(Clone, Debug, Default)]
pub struct Windows {
    /// The windows, in time order, named `RUN#K` (K from 1).
    pub runs: Vec<Run>,
    /// Windows dropped because the reference stood still in them.
    pub still: usize,
    /// Gaps in the reference that ended a window.
    pub gaps: usize,
}

/// Cuts `run` into consecutive windows of at most `window_s` seconds of its reference (adjacent windows
/// share their boundary pose), each with the wheel samples that cover it (and [`WHEEL_MARGIN_S`] more on
/// each side), its wheel start angles carried forward when the run has them. Windows where the reference
/// stands still are dropped and counted; a gap of more than [`GAP_INTERVALS`] median intervals ends a window.
pub fn windows(run: &Run, window_s: f64) -> Result<Windows, KinError> {
    if !(window_s.is_finite() && window_s >= MIN_WINDOW_S) {
        return Err(KinError::Invalid {
            what: "the window of a relative reference".into(),
            why: format!("{window_s} s: it must be at least {MIN_WINDOW_S} s"),
        });
    }
    let truth = run.truth();
    let mut dts: Vec<f64> = truth.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    dts.sort_by(f64::total_cmp);
    let gap_s = GAP_INTERVALS * dts[dts.len() / 2];
    let mut out = Windows::default();
    let mut start = 0;
    while start + 1 < truth.len() {
        let mut end = start;
        while end + 1 < truth.len() && truth[end + 1].t_s - truth[start].t_s <= window_s {
            if truth[end + 1].t_s - truth[end].t_s > gap_s {
                break;
            }
            end += 1;
        }
        if end == start {
            // A gap right after `start`: skip it.
            out.gaps += usize::from(truth[start + 1].t_s - truth[start].t_s > gap_s);
            start += 1;
            continue;
        }
        let (a, b) = (truth[start].pose, truth[end].pose);
        let moved = (b.x_m - a.x_m).hypot(b.y_m - a.y_m) >= STILL_M
            || truth[start..=end].iter().any(|p| (p.pose.theta_rad - a.theta_rad).abs() >= STILL_RAD)
            || truth[start..=end].iter().any(|p| (p.pose.x_m - a.x_m).hypot(p.pose.y_m - a.y_m) >= STILL_M);
        if moved {
            out.runs.push(window(run, start, end, out.runs.len() + out.still + 1)?);
        } else {
            out.still += 1;
        }
        start = end;
    }
    Ok(out)
}

/// The window of `run` over its ground-truth poses `first..=last`, the `k`-th of the run.
fn window(run: &Run, first: usize, last: usize, k: usize) -> Result<Run, KinError> {
    with_truth(run, run.truth()[first..=last].to_vec(), format!("{}#{k}", run.name()))
}

/// `run`'s wheel samples that cover `truth` (and [`WHEEL_MARGIN_S`] more on each side, clamped to the run),
/// with `truth` as the ground truth, named `name`; the wheel start angles carried forward to the first
/// sample kept when the run has them. A sensor's path replaces a placeholder truth this way, one run per
/// stretch of the path.
pub fn with_truth(run: &Run, truth: Vec<StampedPose>, name: String) -> Result<Run, KinError> {
    let t = run.wheel_t_s();
    let (Some(first), Some(last)) = (truth.first(), truth.last()) else {
        return Err(KinError::TooShort { run: name, what: "ground-truth poses", got: 0, min: 2 });
    };
    let (t0, t1) = (first.t_s - WHEEL_MARGIN_S, last.t_s + WHEEL_MARGIN_S);
    // The last sample at or before t0 and the first at or after t1 (clamped to the run).
    let a = t.partition_point(|&s| s <= t0).saturating_sub(1);
    let b = (t.partition_point(|&s| s < t1) + 1).min(t.len());
    let n = run.n_wheels();
    let wheel_start_rad = if run.wheel_start_rad().is_empty() {
        Vec::new()
    } else {
        // Each wheel's angle carried to sample `a` by the speeds (each held over its interval, as the
        // integrator holds them).
        let mut angle = run.wheel_start_rad().to_vec();
        for k in 0..a {
            for (j, v) in angle.iter_mut().enumerate() {
                *v += run.wheel_sample(k)[j] * (t[k + 1] - t[k]);
            }
        }
        angle
    };
    Run::new(RunData {
        name,
        wheel_t_s: t[a..b].to_vec(),
        wheel_rad_s: run.wheel_rad_s()[a * n..b * n].to_vec(),
        n_wheels: n,
        truth,
        command: None,
        repetition: None,
        recorded_odometry: Vec::new(),
        wheel_start_rad,
        truth_position_only: run.truth_position_only(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::Pose2;

    /// A run of `secs` seconds at 100 Hz wheels and 50 Hz truth, turning in place for the first half and
    /// standing still for the second, with the truth missing over `gap`.
    fn run(secs: f64, gap: Option<(f64, f64)>) -> Run {
        let n = (secs * 100.0) as usize + 1;
        let wheel_t_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
        let wheel_rad_s =
            wheel_t_s.iter().flat_map(|&t| if t < secs / 2.0 { [1.0, 2.0] } else { [0.0, 0.0] }).collect();
        let truth = (0..=(secs * 50.0) as usize)
            .map(|k| k as f64 * 0.02)
            .filter(|t| gap.is_none_or(|(a, b)| *t <= a || *t >= b))
            .map(|t| StampedPose { t_s: t, pose: Pose2::new(0.0, 0.0, 0.5 * t.min(secs / 2.0)) })
            .collect();
        Run::new(RunData {
            name: "r".into(),
            wheel_t_s,
            wheel_rad_s,
            n_wheels: 2,
            truth,
            wheel_start_rad: vec![0.1, 0.2],
            ..Default::default()
        })
        .unwrap()
    }

    #[test]
    fn windows_cover_the_motion_and_drop_the_standstill() {
        let w = windows(&run(20.0, None), 4.0).unwrap();
        // 0–4, 4–8, 8–12 move (the turn ends at 10 s); 12–16 and 16–20 stand still.
        assert_eq!((w.runs.len(), w.still, w.gaps), (3, 2, 0));
        let names: Vec<&str> = w.runs.iter().map(Run::name).collect();
        assert_eq!(names, ["r#1", "r#2", "r#3"]);
        let second = &w.runs[1];
        assert_eq!((second.start().t_s, second.end().t_s), (4.0, 8.0));
        // Wheel samples from 3.5 s to 8.5 s, the start angles carried by the speeds to 3.5 s.
        assert!((second.wheel_t_s()[0] - 3.5).abs() < 1e-9 && (second.wheel_t_s().last().unwrap() - 8.5).abs() < 1e-9);
        assert!((second.wheel_start_rad()[0] - (0.1 + 3.5)).abs() < 1e-9);
        assert!((second.wheel_start_rad()[1] - (0.2 + 7.0)).abs() < 1e-9);
    }

    #[test]
    fn a_gap_in_the_reference_ends_a_window() {
        let w = windows(&run(8.0, Some((1.0, 2.0))), 4.0).unwrap();
        assert_eq!(w.gaps, 1);
        assert_eq!(w.runs[0].end().t_s, 1.0);
        assert_eq!(w.runs[1].start().t_s, 2.0);
    }

    #[test]
    fn a_window_too_short_is_refused() {
        let err = windows(&run(4.0, None), 0.05).unwrap_err().to_string();
        assert_eq!(err, "the window of a relative reference: 0.05 s: it must be at least 0.2 s");
    }
}
