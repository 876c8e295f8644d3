//! The clock of a sensor recorded with the wheels whose motion becomes the reference (a lidar's scans,
//! `--gt-scans`; an IMU's yaw rate, `omnical imu`): estimated against the wheels ([`omni_kin::clock::align_clocks`]) and judged by the rules
//! every reference recorded with the wheels follows ([`omni_kin::clock::SameRecording`]): a lag is named, an
//! offset beyond the same-clock band is applied when clear, and an unclear or implausible one never is.

use super::Note;
use omni_kin::clock::{self, ClockAlignment, SameRecording};
use omni_kin::{Run, StampedPose};
use std::path::Path;

/// A sensor's clock against the wheels: the estimate, how the rules judge it, and the share of the
/// sensor's motion the wheels explain as recorded.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SensorClock {
    /// The estimate (`t_wheel = t_sensor + offset_s`).
    pub estimate: ClockAlignment,
    /// What it means.
    pub judged: SameRecording,
    /// The explained share at offset 0, when the overlap allows one.
    pub r_squared_as_recorded: Option<f64>,
    /// The estimate is the sensor's rotation alone against the wheels (clearer than its whole motion).
    pub rotation_only: bool,
}

/// The clock of the sensor's `segment` of path (on the wheel clock as recorded) against the run of `runs`
/// that overlaps it most; `None` when none allows an estimate (too short, too still).
pub(crate) fn sensor_clock(runs: &[Run], segment: &[StampedPose]) -> Option<SensorClock> {
    let (g0, g1) = (segment.first()?.t_s, segment.last()?.t_s);
    let overlap = |r: &&Run| {
        let t = r.wheel_t_s();
        t[t.len() - 1].min(g1) - t[0].max(g0)
    };
    let run = runs.iter().max_by(|a, b| overlap(a).total_cmp(&overlap(b)))?;
    let (t, rad, n) = (run.wheel_t_s(), run.wheel_rad_s(), run.n_wheels());
    // The whole motion or the rotation alone, whichever is clearer (a scan matcher's heading is less noisy).
    let (estimate, used, rotation_only) = clock::align_clocks_clearest(t, rad, n, segment)?;
    Some(SensorClock {
        estimate,
        judged: estimate.same_recording(t[t.len() - 1] - t[0]),
        r_squared_as_recorded: clock::explained_at(t, rad, n, &used, 0.0),
        rotation_only,
    })
}

/// The clock of a gyro's yaw rates (on the wheel clock as recorded) against `run`'s wheels: the rates
/// integrated into a heading (trapezoids), a reference with its rotation alone.
pub(crate) fn gyro_clock(run: &Run, rates: &[omni_kin::gyro::GyroSample]) -> Option<SensorClock> {
    let mut heading_rad = 0.0;
    let mut poses = Vec::with_capacity(rates.len());
    for (k, g) in rates.iter().enumerate() {
        if k > 0 {
            heading_rad += 0.5 * (g.z_rad_s + rates[k - 1].z_rad_s) * (g.t_s - rates[k - 1].t_s);
        }
        poses.push(StampedPose { t_s: g.t_s, pose: omni_kin::Pose2::new(0.0, 0.0, heading_rad) });
    }
    sensor_clock(std::slice::from_ref(run), &poses)
}

impl SensorClock {
    /// The offset to add to the sensor's stamps: the estimate when the rules move them, else 0.
    pub fn applied_s(&self) -> f64 {
        if self.judged == SameRecording::Move { self.estimate.offset_s } else { 0.0 }
    }

    /// The note for the load, when there is something to say (`what`: `lidar "/scan"`).
    pub fn note(&self, path: &Path, what: &str) -> Option<Note> {
        let a = &self.estimate;
        let at_zero = self.r_squared_as_recorded.map_or(String::new(), |r| format!(", {:.0} % as recorded", r * 100.0));
        let motion = if self.rotation_only { "rotation (its translation is noisier)" } else { "motion" };
        let estimate = format!(
            "{:+.3} s ± {:.1} ms (t_wheel = t_sensor + offset; the wheels explain {:.0} % of its {motion} there{at_zero})",
            a.offset_s,
            a.std_error_s * 1e3,
            a.r_squared * 100.0
        );
        let text = match self.judged {
            SameRecording::Agree => return None,
            SameRecording::Lag => format!(
                "{what}: a clock offset between the wheels and the sensor of {estimate}; the stamps are kept (a lag \
                 within ±{} s is the `time_offset` effect's): `train --effect time_offset` fits it, `diagnose` \
                 weighs it",
                clock::SAME_CLOCK_MAX_OFFSET_S
            ),
            SameRecording::UnclearLag => format!(
                "{what}: a clock offset between the wheels and the sensor of {estimate} is suggested but not clear \
                 (a clear one has a standard error of at most {:.0} ms and explains at least {:.0} %): the stamps \
                 are kept; `train --effect time_offset` fits it if it is there",
                clock::CLEAR_MAX_STD_ERROR_S * 1e3,
                clock::CLEAR_MIN_R_SQUARED * 100.0
            ),
            SameRecording::Move => format!("{what}: on another clock; its stamps are moved by {estimate}"),
            SameRecording::Unclear => format!(
                "{what}: the clock estimate, {estimate}, is not clear (a clear one has a standard error of at most \
                 {:.0} ms and explains at least {:.0} %): its stamps are kept as recorded",
                clock::CLEAR_MAX_STD_ERROR_S * 1e3,
                clock::CLEAR_MIN_R_SQUARED * 100.0
            ),
            SameRecording::Implausible => format!(
                "{what}: the clock estimate, {estimate}, is longer than the recording: its stamps are kept as recorded"
            ),
        };
        Some(Note::about(path, text))
    }
}
