//! The parts of an affine wheel-stage effect ([`Effect::wheel_rates_affine`]: wheel asymmetry, speed
//! scale, acceleration slip, eccentricity, `learned:wheel`), taken once per dataset: each parameter's change
//! of the wheel speeds per unit. An evaluation then rewrites the speeds with one multiply-add per
//! parameter and sample, `w' = w + Σ_i p_i f_i`, instead of running the effect (an eccentricity takes a
//! sine and cosine per wheel and sample); the numbers are the effect's to rounding. The parts are those of
//! no clock lag: the affine effects read only the step lengths and differences of sample instants, which a
//! lag does not change.

use crate::effect::{Effect, EffectKind, WheelContext};
use crate::model::Resolved;
use crate::plan::sample_times;
use crate::run::Run;

/// One parameter's part on one wheel of one run.
#[derive(Debug)]
struct Part {
    /// Index of the parameter in the effect's.
    param: usize,
    /// The wheel.
    wheel: usize,
    /// Change of the wheel's speed per unit of the parameter, at every sample. rad/s.
    column: Vec<f64>,
}

/// The parts of one affine wheel-stage effect on every run.
#[derive(Debug)]
pub(crate) struct WheelFeatures {
    /// The effect's id and parameter count (what the parts belong to).
    id: String,
    n_params: usize,
    /// Per run, every (parameter, wheel) whose part is not zero.
    runs: Vec<Vec<Part>>,
}

impl WheelFeatures {
    /// The parts of `effect` (affine) on `runs` for fixed steps of `fixed_dt_s` (`None`: each run's
    /// median interval). Sequential: it may run inside a lock that rayon workers wait on.
    pub fn new(effect: &EffectKind, runs: &[Run], fixed_dt_s: Option<f64>) -> Self {
        let n_params = effect.params().len();
        let parts = runs
            .iter()
            .map(|run| {
                let (s, h) = sample_times(run, 0.0, fixed_dt_s, false);
                let n = run.n_wheels();
                let ctx = WheelContext { n_wheels: n, t_s: &s, dt_s: &h, start_angle_rad: run.wheel_start_rad() };
                let w = run.wheel_rad_s();
                let mut parts = Vec::new();
                for param in 0..n_params {
                    let mut unit = vec![0.0; n_params];
                    unit[param] = 1.0;
                    let mut rewritten = w.to_vec();
                    effect.wheel_rates(&unit, &ctx, &mut rewritten);
                    for wheel in 0..n {
                        let column: Vec<f64> =
                            (0..run.n_samples()).map(|k| rewritten[k * n + wheel] - w[k * n + wheel]).collect();
                        if column.iter().any(|v| *v != 0.0) {
                            parts.push(Part { param, wheel, column });
                        }
                    }
                }
                parts
            })
            .collect();
        Self { id: effect.id().to_string(), n_params, runs: parts }
    }

    /// The parameters of `res`'s wheel stage when these parts serve it (its only wheel-stage effect is
    /// this one, affine, without measured stamps).
    pub fn params<'r>(&self, res: &Resolved<'r>) -> Option<&'r [f64]> {
        match res.wheel_effects[..] {
            [(e, p)] if !res.stamps && e.wheel_rates_affine() && p.len() == self.n_params && e.id() == self.id => {
                Some(p)
            }
            _ => None,
        }
    }

    /// Number of the effect's parameters.
    pub fn n_params(&self) -> usize {
        self.n_params
    }

    /// Run `i`'s parts: (parameter, wheel, change per unit at every sample).
    pub fn run_parts(&self, i: usize) -> impl Iterator<Item = (usize, usize, &[f64])> {
        self.runs[i].iter().map(|p| (p.param, p.wheel, p.column.as_slice()))
    }

    /// Run `i`'s (`run`'s) wheel speeds rewritten with parameters `p`.
    pub fn speeds(&self, i: usize, run: &Run, p: &[f64]) -> Vec<f64> {
        let mut w = run.wheel_rad_s().to_vec();
        let n = run.n_wheels();
        for part in &self.runs[i] {
            let v = p[part.param];
            if v != 0.0 {
                for (w, f) in w.iter_mut().skip(part.wheel).step_by(n).zip(&part.column) {
                    *w += v * f;
                }
            }
        }
        w
    }
}

/// The one affine wheel-stage effect of `res` (the only kind [`WheelFeatures`] serve).
pub(super) fn affine_wheel_effect<'m>(res: &Resolved<'m>) -> Option<&'m EffectKind> {
    match res.wheel_effects[..] {
        [(e, _)] if !res.stamps && e.wheel_rates_affine() => Some(e),
        _ => None,
    }
}
