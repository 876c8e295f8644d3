//! A clock offset between the wheels and the reference, measured without any model: each run's reference
//! motion (or its rotation alone, when that is clearer) regressed on its wheel speeds at every offset
//! ([`omni_kin::clock::align_clocks_clearest`]), the runs' estimates pooled by their standard errors. It names the offset the catalogue's `time_offset` fits, and
//! it confirms that fit independently of the kinematic model and of the kinds of path.

use omni_kin::Run;
use omni_kin::clock::{self, ClockAlignment, SameRecording};

/// The runs' pooled clock estimate (`t_wheel = t_reference + offset_s`, the `time_offset` effect's
/// `tau_s`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClockLag {
    /// The pooled estimate, its standard error and the runs' mean explained share (overlap: the runs'
    /// total).
    pub estimate: ClockAlignment,
    /// The mean share of the reference's motion the wheels explain at offset 0.
    pub r_squared_as_recorded: f64,
    /// Runs that gave an estimate.
    pub runs: usize,
}

impl ClockLag {
    /// A lag worth naming: clear, within the same-clock band, beyond three standard errors and the smallest
    /// lag named ([`SameRecording::Lag`]).
    pub fn named(&self) -> bool {
        self.estimate.same_recording(f64::INFINITY) == SameRecording::Lag
    }

    /// A fitted `time_offset` of `tau_s` is this lag: within three standard errors of both, or a tenth of
    /// the lag.
    pub fn confirms(&self, tau_s: f64, tau_std_error_s: Option<f64>) -> bool {
        let se = self.estimate.std_error_s.hypot(tau_std_error_s.unwrap_or(0.0));
        (tau_s - self.estimate.offset_s).abs() <= (3.0 * se).max(0.1 * self.estimate.offset_s.abs())
    }
}

/// One stretch of wheel data and reference for a clock estimate: a run, or the windows of a relative
/// reference (`RUN#1`, `RUN#2`, … cut by [`omni_kin::reference::windows`]) joined back into the stretch they
/// were cut from, which is long enough for an estimate where a 4 s window is not.
struct Stretch {
    wheel_t_s: Vec<f64>,
    wheel_rad_s: Vec<f64>,
    n_wheels: usize,
    truth: Vec<omni_kin::StampedPose>,
}

/// The runs as stretches: consecutive windows of one run (names `RUN#K`) joined, each sample and pose once.
fn stretches(runs: &[Run]) -> Vec<Stretch> {
    let parent = |r: &Run| match r.name().rsplit_once('#') {
        Some((p, k)) if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) => Some(p.to_string()),
        _ => None,
    };
    let mut out: Vec<(Option<String>, Stretch)> = Vec::new();
    for r in runs {
        let name = parent(r);
        match out.last_mut() {
            Some((Some(p), s)) if name.as_ref() == Some(p) && s.n_wheels == r.n_wheels() => {
                let last_t = s.wheel_t_s.last().copied().unwrap_or(f64::NEG_INFINITY);
                for (k, &t) in r.wheel_t_s().iter().enumerate().filter(|(_, t)| **t > last_t) {
                    s.wheel_t_s.push(t);
                    s.wheel_rad_s.extend_from_slice(r.wheel_sample(k));
                }
                let last_pose = s.truth.last().map_or(f64::NEG_INFINITY, |p| p.t_s);
                s.truth.extend(r.truth().iter().filter(|p| p.t_s > last_pose));
            }
            _ => out.push((
                name,
                Stretch {
                    wheel_t_s: r.wheel_t_s().to_vec(),
                    wheel_rad_s: r.wheel_rad_s().to_vec(),
                    n_wheels: r.n_wheels(),
                    truth: r.truth().to_vec(),
                },
            )),
        }
    }
    out.into_iter().map(|(_, s)| s).collect()
}

/// The runs' clock estimates pooled (inverse-variance weighted); `None` when no run gives one. The windows
/// of a relative reference are joined back into their stretches first.
pub fn clock_lag(runs: &[Run]) -> Option<ClockLag> {
    let estimates: Vec<(ClockAlignment, f64)> = stretches(runs)
        .iter()
        .filter_map(|r| {
            let (t, rad, n, truth) = (&r.wheel_t_s[..], &r.wheel_rad_s[..], r.n_wheels, &r.truth[..]);
            // The whole motion or the rotation alone, whichever is clearer (as for a sensor's clock).
            let (a, used, _) = clock::align_clocks_clearest(t, rad, n, truth)?;
            let at_zero = clock::explained_at(t, rad, n, &used, 0.0)?;
            (a.std_error_s > 0.0 && a.std_error_s.is_finite()).then_some((a, at_zero))
        })
        .collect();
    if estimates.is_empty() {
        return None;
    }
    let (mut w, mut wx, mut r2, mut r2_zero, mut overlap) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (a, z) in &estimates {
        let wi = a.std_error_s.powi(-2);
        w += wi;
        wx += wi * a.offset_s;
        r2 += a.r_squared;
        r2_zero += z;
        overlap += a.overlap_s;
    }
    let n = estimates.len() as f64;
    let offset_s = wx / w;
    Some(ClockLag {
        estimate: ClockAlignment {
            offset_s,
            std_error_s: w.powf(-0.5),
            coarse_offset_s: offset_s,
            step_s: estimates[0].0.step_s,
            r_squared: r2 / n,
            overlap_s: overlap,
        },
        r_squared_as_recorded: r2_zero / n,
        runs: estimates.len(),
    })
}
