//! What the data itself allows: the measurement noise floor at standstill, the repeat scatter of the
//! end-pose error, and whether the runs excite wheel-stage effects at all.

use super::{GroupReport, NoiseFloor};
use crate::science::text;
use omni_kin::Run;

/// Why the runs cannot tell a wheel-stage effect: one entry per wheel that is not excited.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExcitationGap {
    /// The wheels that are not excited, in wheel order.
    pub wheels: Vec<WheelGap>,
}

/// One wheel that the runs do not excite.
#[derive(Clone, Debug, PartialEq)]
pub struct WheelGap {
    /// The wheel's name.
    pub wheel: String,
    /// How it falls short.
    pub kind: GapKind,
}

/// How a wheel's motion falls short of exciting a wheel-stage effect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GapKind {
    /// It turns one way only (less than 5 % of its moving samples the other way).
    OneWay {
        /// Share of its moving samples that turn forward. %.
        forward_pct: f64,
    },
    /// It runs at one speed only (90th/10th percentile of |speed| below 1.5).
    OneSpeed {
        /// 10th percentile of |speed|. rad/s.
        low_rad_s: f64,
        /// 90th percentile of |speed|. rad/s.
        high_rad_s: f64,
    },
}

/// Whether the runs can tell a wheel-stage effect: every wheel must turn both ways (≥ 5 % of its moving
/// samples each way) and at several distinct speeds (90th/10th percentile of |speed| ≥ 1.5). `None` when
/// they can, else which wheels fall short and how (`wheel_names`: one per wheel).
pub fn wheel_excitation(runs: &[Run], wheel_names: &[String]) -> Option<ExcitationGap> {
    const MOVING_RAD_S: f64 = 0.05;
    let mut wheels = Vec::new();
    for (w, name) in wheel_names.iter().enumerate() {
        let mut speeds: Vec<f64> = Vec::new();
        let (mut pos, mut neg) = (0usize, 0usize);
        for r in runs {
            for k in 0..r.n_samples() {
                let v = r.wheel_sample(k).get(w).copied().unwrap_or(0.0);
                if v > MOVING_RAD_S {
                    pos += 1;
                } else if v < -MOVING_RAD_S {
                    neg += 1;
                } else {
                    continue;
                }
                speeds.push(v.abs());
            }
        }
        let moving = (pos + neg).max(1) as f64;
        let gap = |kind| WheelGap { wheel: name.clone(), kind };
        if (pos as f64) < 0.05 * moving || (neg as f64) < 0.05 * moving {
            wheels.push(gap(GapKind::OneWay { forward_pct: 100.0 * pos as f64 / moving }));
            continue;
        }
        speeds.sort_by(f64::total_cmp);
        let q = |f: f64| speeds[((speeds.len() - 1) as f64 * f) as usize];
        if q(0.9) < 1.5 * q(0.1) {
            wheels.push(gap(GapKind::OneSpeed { low_rad_s: q(0.1), high_rad_s: q(0.9) }));
        }
    }
    (!wheels.is_empty()).then_some(ExcitationGap { wheels })
}

/// [`wheel_excitation`] in words (`None` when the runs excite every wheel).
pub fn wheel_excitation_gap(runs: &[Run], wheel_names: &[String]) -> Option<String> {
    wheel_excitation(runs, wheel_names).map(|g| text::excitation_gap(&g))
}

/// Repeat scatter of the end-pose error (see [`super::Diagnosis::repeatability_floor`]).
pub(super) fn repeatability_floor(groups: &[GroupReport]) -> Option<f64> {
    let (mut sum, mut count) = (0.0, 0usize);
    for g in groups.iter().filter(|g| g.runs >= 2) {
        let n = g.runs as f64;
        sum += g.scatter * g.scatter * n / (n - 1.0);
        count += 1;
    }
    (count > 0).then(|| (sum / count as f64).sqrt())
}

/// Estimate the ground-truth noise from poses while every wheel is still.
pub fn noise_floor(runs: &[Run]) -> Option<NoiseFloor> {
    const STILL_RAD_S: f64 = 0.02;
    let (mut sp, mut sth, mut dof) = (0.0, 0.0, 0usize);
    let mut used = 0;
    for r in runs {
        let t = r.wheel_t_s();
        let moving: Vec<usize> =
            (0..r.n_samples()).filter(|&k| r.wheel_sample(k).iter().any(|w| w.abs() > STILL_RAD_S)).collect();
        let (Some(&first), Some(&last)) = (moving.first(), moving.last()) else { continue };
        let (t_start, t_end) = (t[first] - 0.05, t[last] + 0.05);
        for window in [
            r.truth().iter().filter(|p| p.t_s < t_start).collect::<Vec<_>>(),
            r.truth().iter().filter(|p| p.t_s > t_end).collect(),
        ] {
            if window.len() < 2 {
                continue;
            }
            let n = window.len() as f64;
            let mx = window.iter().map(|p| p.pose.x_m).sum::<f64>() / n;
            let my = window.iter().map(|p| p.pose.y_m).sum::<f64>() / n;
            let mt = window.iter().map(|p| p.pose.theta_rad).sum::<f64>() / n;
            for p in &window {
                sp += (p.pose.x_m - mx).powi(2) + (p.pose.y_m - my).powi(2);
                sth += (p.pose.theta_rad - mt).powi(2);
            }
            dof += window.len() - 1;
            used += window.len();
        }
    }
    if dof == 0 {
        return None;
    }
    let position_m = (sp / (2.0 * dof as f64)).sqrt();
    let heading_rad = (sth / dof as f64).sqrt();
    let one = 2.0 * position_m * position_m + heading_rad * heading_rad;
    Some(NoiseFloor { position_m, heading_rad, path_rms: (2.0 * one).sqrt(), samples: used })
}
