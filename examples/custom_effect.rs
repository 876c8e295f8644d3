//! A user-defined physical effect from a downstream crate: a wheel-speed-dependent drag on one wheel,
//! injected into simulated data and then recovered by refitting. Run with
//! `cargo run --release --example custom_effect`.

use omnical::ga::diagnose::refit;
use omnical::kin::effect::{Effect, ParamSpec, Stage, WheelContext};
use omnical::kin::simulate::{SimConfig, simulate};
use omnical::kin::{EffectKind, FittedModel, IkMatrix, Model};
use std::sync::Arc;

/// Wheel `a` loses a constant speed `d` (rad/s) while it turns (a dragging brake pad).
#[derive(Debug)]
struct BrakeDrag;

impl Effect for BrakeDrag {
    fn id(&self) -> &str {
        "brake_drag"
    }
    fn describe(&self) -> String {
        "wheel a loses a constant speed while turning".into()
    }
    fn stage(&self) -> Stage {
        Stage::Wheel
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("d_rad_s", "rad/s", 0.0, 0.0, 1.0)]
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        for row in w.chunks_exact_mut(ctx.n_wheels) {
            if row[0].abs() > p[0] {
                row[0] -= p[0] * row[0].signum();
            }
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let drag = EffectKind::Custom(Arc::new(BrakeDrag));
    let mut truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated())).with_effect(drag.clone());
    let n = truth.params.len();
    truth.params[n - 1] = 0.05;
    let config = SimConfig { runs_per_command: 1, duration_s: 6.0, ..SimConfig::default() };
    let runs = simulate(&config, &truth, "run/")?;
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design())).with_effect(drag);
    let fit = refit(&start, None, &runs, 1)?.fitted;
    println!("injected d = 0.05 rad/s, recovered d = {:.4} rad/s", fit.params[n - 1]);
    Ok(())
}
