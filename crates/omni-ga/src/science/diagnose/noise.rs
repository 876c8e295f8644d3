//! What the data itself allows: the measurement noise floor at standstill, the repeat scatter of the
//! end-pose error, and whether the runs excite wheel-stage effects at all.

use super::{GroupReport, NoiseFloor, NoiseSource};
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

/// Estimate the ground-truth noise from poses while every wheel is still; for runs that never stand still,
/// from the ground truth's jitter while moving (`jitter_floor`).
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
        return jitter_floor(runs);
    }
    let position_m = (sp / (2.0 * dof as f64)).sqrt();
    let heading_rad = (sth / dof as f64).sqrt();
    Some(floor_of(position_m, heading_rad, used, NoiseSource::Standstill))
}

/// A noise floor from its per-axis position and heading noise: the path RMS the noise of the start pose
/// and of each compared pose gives.
fn floor_of(position_m: f64, heading_rad: f64, samples: usize, source: NoiseSource) -> NoiseFloor {
    let one = 2.0 * position_m * position_m + heading_rad * heading_rad;
    NoiseFloor { position_m, heading_rad, path_rms: (2.0 * one).sqrt(), samples, source }
}

/// Longest median ground-truth interval for which the jitter estimate holds. s. Slower ground truth moves
/// too far between poses for the motion to vanish from the third differences.
const JITTER_MAX_DT_S: f64 = 0.05;

/// The ground truth's noise from its jitter while moving, for runs that never stand still: third
/// differences of the pose sequence, `x[k+2] − 3x[k+1] + 3x[k] − x[k−1]`, carry a smooth motion's jerk ×
/// dt³ (negligible at ≥ 20 Hz) and 20 σ² of white noise; σ from their median absolute value (robust to the
/// odd outlier, 1.4826 MAD). `None` with slower ground truth or fewer than 20 differences.
fn jitter_floor(runs: &[Run]) -> Option<NoiseFloor> {
    let (mut position, mut heading) = (Vec::new(), Vec::new());
    for r in runs {
        let p = r.truth();
        let mut dts: Vec<f64> = p.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
        if dts.is_empty() {
            continue;
        }
        dts.sort_by(f64::total_cmp);
        if dts[dts.len() / 2] > JITTER_MAX_DT_S {
            continue;
        }
        let third = |f: &dyn Fn(usize) -> f64, k: usize| f(k + 3) - 3.0 * f(k + 2) + 3.0 * f(k + 1) - f(k);
        for k in 0..p.len().saturating_sub(3) {
            position.push(third(&|i| p[i].pose.x_m, k).abs());
            position.push(third(&|i| p[i].pose.y_m, k).abs());
            heading.push(third(&|i| p[i].pose.theta_rad, k).abs());
        }
    }
    if heading.len() < 20 {
        return None;
    }
    let sigma = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        1.4826 * v[v.len() / 2] / 20f64.sqrt()
    };
    let samples = heading.len();
    Some(floor_of(sigma(&mut position), sigma(&mut heading), samples, NoiseSource::Jitter))
}

#[cfg(test)]
mod tests {
    use super::*;
    use omni_kin::pose::{Pose2, StampedPose};
    use omni_kin::run::RunData;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A run that drives a circle for 20 s at 100 Hz, never standing still, its ground truth with white
    /// noise of `sigma_m` per axis and `sigma_rad` in heading.
    fn circling(sigma_m: f64, sigma_rad: f64, seed: u64) -> Run {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let (np, nh) = (Normal::new(0.0, sigma_m).unwrap(), Normal::new(0.0, sigma_rad).unwrap());
        let n = 2001;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
        let truth = t
            .iter()
            .map(|&t_s| {
                let a = 0.4 * t_s;
                let pose = Pose2 {
                    x_m: 0.5 * a.sin() + np.sample(&mut rng),
                    y_m: 0.5 - 0.5 * a.cos() + np.sample(&mut rng),
                    theta_rad: a + nh.sample(&mut rng),
                };
                StampedPose { t_s, pose }
            })
            .collect();
        let data = RunData {
            name: "circle".into(),
            wheel_t_s: t,
            wheel_rad_s: vec![3.0; 2 * n],
            n_wheels: 2,
            truth,
            ..Default::default()
        };
        Run::new(data).unwrap()
    }

    #[test]
    fn runs_that_never_stand_still_get_their_noise_floor_from_the_jitter() {
        let runs: Vec<Run> = (0..3).map(|s| circling(1e-3, 2e-3, s)).collect();
        let nf = noise_floor(&runs).unwrap();
        assert_eq!(nf.source, NoiseSource::Jitter);
        assert!((nf.position_m / 1e-3 - 1.0).abs() < 0.05, "{}", nf.position_m);
        assert!((nf.heading_rad / 2e-3 - 1.0).abs() < 0.05, "{}", nf.heading_rad);
        assert_eq!(nf.samples, 3 * (2001 - 3));
        // Noise-free motion leaves (almost) nothing: the circle's jerk × dt³ is 6.4e-8 m.
        let clean = noise_floor(&[circling(1e-12, 1e-12, 0)]).unwrap();
        assert!(clean.position_m < 1e-7, "{}", clean.position_m);
    }
}
