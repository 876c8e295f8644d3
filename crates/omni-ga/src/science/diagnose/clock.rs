//! A clock offset between the wheels and the reference, measured without any model: each run's reference
//! motion regressed on its wheel speeds at every offset ([`omni_kin::clock::align_clocks`]), the runs'
//! estimates pooled by their standard errors. It names the offset the catalogue's `time_offset` fits, and
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

/// The runs' clock estimates pooled (inverse-variance weighted); `None` when no run gives one.
pub fn clock_lag(runs: &[Run]) -> Option<ClockLag> {
    let estimates: Vec<(ClockAlignment, f64)> = runs
        .iter()
        .filter_map(|r| {
            let (t, rad, n) = (r.wheel_t_s(), r.wheel_rad_s(), r.n_wheels());
            let a = clock::align_clocks(t, rad, n, r.truth()).ok()?;
            let at_zero = clock::explained_at(t, rad, n, r.truth(), 0.0)?;
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
