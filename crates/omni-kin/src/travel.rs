//! How far runs went by their wheels through a model's matrix, against how far their ground truth says:
//! a ratio far from 1 is not a calibration error but wheel data in another unit (rpm read as rad/s, encoder
//! counts as radians) or a design off by a large factor. Callers refuse such data before fitting.

use crate::ik::IkMatrix;
use crate::pose::wrap_angle;
use crate::run::Run;

/// Distance and turning of runs, by the wheels through a matrix and by the ground truth, over the
/// ground truth's span.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Travel {
    /// Distance of the wheels' dead reckoning, window by window. m.
    pub wheels_m: f64,
    /// Distance of the ground truth, window by window. m.
    pub truth_m: f64,
    /// Turning of the wheels' dead reckoning, window by window. rad.
    pub wheels_rad: f64,
    /// Turning of the ground truth, window by window (each on the shortest arc). rad.
    pub truth_rad: f64,
}

/// The windows travel is measured over: ground-truth poses at least this far apart, so that its noise
/// (millimetres at a few hundred hertz) does not lengthen its path. s.
pub const WINDOW_S: f64 = 0.1;

impl Travel {
    /// The travel of `runs` through `ik` (runs whose wheel count is not the matrix's are left out): over
    /// windows between ground-truth poses at least [`WINDOW_S`] apart, the straight distance and the turn
    /// of each window, summed, for the ground truth and for the wheels' dead reckoning over the same window.
    pub fn of(runs: &[Run], ik: &IkMatrix) -> Self {
        let mut t = Self::default();
        for run in runs.iter().filter(|r| r.n_wheels() == ik.n_wheels()) {
            let truth = run.truth();
            let mut a = 0;
            let mut k = 1; // the wheel sample covering (t_{k−1}, t_k]
            let ts = run.wheel_t_s();
            for b in 1..truth.len() {
                if truth[b].t_s - truth[a].t_s < WINDOW_S && b + 1 < truth.len() {
                    continue;
                }
                let (p, q) = (&truth[a].pose, &truth[b].pose);
                t.truth_m += (q.x_m - p.x_m).hypot(q.y_m - p.y_m);
                t.truth_rad += wrap_angle(q.theta_rad - p.theta_rad).abs();
                // Dead reckoning over (t_a, t_b], in the window's start frame.
                let (mut x, mut y, mut th) = (0.0, 0.0, 0.0_f64);
                while k < ts.len() && ts[k] <= truth[b].t_s {
                    let dt = ts[k] - ts[k - 1].max(truth[a].t_s);
                    if dt > 0.0 {
                        let v = ik.twist(run.wheel_sample(k));
                        x += (v.vx_m_s * th.cos() - v.vy_m_s * th.sin()) * dt;
                        y += (v.vx_m_s * th.sin() + v.vy_m_s * th.cos()) * dt;
                        th += v.omega_rad_s * dt;
                    }
                    k += 1;
                }
                t.wheels_m += x.hypot(y);
                t.wheels_rad += th.abs();
                a = b;
            }
        }
        t
    }

    /// Wheel distance over ground-truth distance, when the ground truth went at least `min_m`.
    pub fn distance_ratio(&self, min_m: f64) -> Option<f64> {
        (self.truth_m >= min_m).then(|| self.wheels_m / self.truth_m)
    }

    /// Wheel turning over ground-truth turning, when the ground truth turned at least `min_rad`.
    pub fn turning_ratio(&self, min_rad: f64) -> Option<f64> {
        (self.truth_rad >= min_rad).then(|| self.wheels_rad / self.truth_rad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::RobotGeometry;
    use crate::pose::{Pose2, StampedPose};
    use crate::run::RunData;

    /// A diff-drive run at 0.5 m/s forward and 0.2 rad/s for 4 s, its wheels scaled by `scale`.
    fn arc(scale: f64) -> (Run, IkMatrix) {
        let g = RobotGeometry::diff_drive(0.05, 0.05, 0.3);
        let ik = g.twist_from_wheels().unwrap();
        let (v, w) = (0.5, 0.2);
        let wheel = [(v - w * 0.15) / 0.05 * scale, (v + w * 0.15) / 0.05 * scale];
        let t: Vec<f64> = (0..=400).map(|k| k as f64 * 0.01).collect();
        let truth = t
            .iter()
            .step_by(10)
            .map(|&t| {
                let th = w * t;
                StampedPose { t_s: t, pose: Pose2::new(v / w * th.sin(), v / w * (1.0 - th.cos()), th) }
            })
            .collect();
        let data = RunData {
            name: "arc".into(),
            wheel_rad_s: t.iter().flat_map(|_| wheel).collect(),
            wheel_t_s: t,
            n_wheels: 2,
            truth,
            ..RunData::default()
        };
        (Run::new(data).unwrap(), ik)
    }

    #[test]
    fn wheels_in_rpm_travel_60_over_2pi_times_the_truth() {
        let (run, ik) = arc(1.0);
        let t = Travel::of(std::slice::from_ref(&run), &ik);
        // 0.8 rad and 2 m of arc, as 40 chords of 0.1 s.
        let chords = 40.0 * 2.0 * (0.5 / 0.2) * (0.2f64 * 0.1 / 2.0).sin();
        assert!((t.truth_m - chords).abs() < 1e-4 && (t.truth_rad - 0.8).abs() < 1e-9, "{t:?}");
        assert!((t.distance_ratio(1.0).unwrap() - 1.0).abs() < 1e-4, "{t:?}");
        assert!((t.turning_ratio(0.5).unwrap() - 1.0).abs() < 1e-9, "{t:?}");
        assert_eq!(t.turning_ratio(1.0), None);
        let rpm = 60.0 / std::f64::consts::TAU;
        let (run, ik) = arc(rpm);
        let t = Travel::of(std::slice::from_ref(&run), &ik);
        // Turning 9.5 times as fast, the wheels' chords are a little shorter than 9.55 times the truth's.
        assert!((t.distance_ratio(1.0).unwrap() - rpm).abs() < 0.05, "{t:?}");
        assert!((t.turning_ratio(0.5).unwrap() - rpm).abs() < 1e-9, "{t:?}");
    }
}
