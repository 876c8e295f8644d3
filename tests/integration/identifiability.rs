//! Identifiability: unexcited directions are named and held at the design; standard errors match the
//! spread of fits over repeated datasets.
use crate::common::{paper_truth, small_config};
use omnical::ga::calibrate::{Plan, Preset, Unexcited, calibrate};
use omnical::ga::observe::NoopObserver;
use omnical::kin::cost::{CostKind, cost};
use omnical::kin::simulate::{SimConfig, flower_commands, simulate};
use omnical::kin::{FittedModel, IkMatrix, Model};

fn design() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_design()))
}

/// Train on translations only (ω = 0): the matrix's response to the rotation wheel pattern is not
/// excited. The warning must say so, and the fit must not be worse than the design on runs that rotate.
#[test]
fn no_rotation_is_named_and_held_at_the_design() {
    let truth = paper_truth();
    let still: Vec<_> = flower_commands().into_iter().filter(|c| c.omega_rad_s == 0.0).step_by(2).collect();
    let turning: Vec<_> = flower_commands().into_iter().filter(|c| c.omega_rad_s != 0.0).step_by(3).collect();
    let base = SimConfig { runs_per_command: 2, duration_s: 6.0, seed: 21, ..SimConfig::default() };
    let train = simulate(&SimConfig { commands: still, ..base.clone() }, &truth, "train/").unwrap();
    let held_out = simulate(&SimConfig { commands: turning, seed: 22, ..base }, &truth, "turning/").unwrap();

    let plan = Plan::preset(Preset::Default, 9).seed(4);
    let c = calibrate(&design(), &train, &plan, &mut NoopObserver).unwrap();
    let warnings = c.identifiability.warnings();
    assert!(!c.held.is_empty(), "nothing held; warnings {warnings:?}");
    assert_eq!(c.held.len(), 3, "one direction per matrix row: {warnings:?}");
    for w in &c.held {
        let t = w.motion.expect("a base-kinematics direction has a motion");
        // The missing motion is a rotation on the spot: ω dominates (0.2 m lever arm).
        assert!((0.2 * t[2]).abs() > 3.0 * t[0].hypot(t[1]), "{t:?}: {}", w.text);
        assert!(w.text.contains("rotating on the spot"), "{}", w.text);
        assert!(w.advice.contains("ω ≠ 0"), "{}", w.advice);
    }
    assert!(warnings.iter().all(|w| w.contains("m3") || w.contains("m1") || w.contains("m2")));

    let path = CostKind::PATH;
    let design_cost = cost(&design().model, &design().params, &held_out, path).unwrap();
    let held_cost = cost(&c.fitted.model, &c.fitted.params, &held_out, path).unwrap();
    assert!(held_cost <= design_cost, "held-out (turning) path {held_cost} vs design {design_cost}");

    // Moving freely along the unexcited directions is what the hold prevents.
    let free = Plan { unexcited: Unexcited::Move, ..plan };
    let f = calibrate(&design(), &train, &free, &mut NoopObserver).unwrap();
    let free_cost = cost(&f.fitted.model, &f.fitted.params, &held_out, path).unwrap();
    eprintln!("turning runs, path RMS: design {design_cost:.4}, hold {held_cost:.4}, move {free_cost:.4}");
    assert!(held_cost < free_cost, "hold {held_cost} vs move {free_cost}");
}

/// The reported standard errors agree with the scatter of fits over independent datasets (factor 1.5).
#[test]
fn standard_errors_match_the_spread_of_repeated_fits() {
    let truth = paper_truth();
    let plan = Plan::preset(Preset::Default, 9).seed(2);
    let datasets = 16;
    let mut fits: Vec<Vec<f64>> = Vec::new();
    let mut se: Vec<Vec<f64>> = Vec::new();
    let mut se_iid: Vec<Vec<f64>> = Vec::new();
    for seed in 0..datasets {
        let train = simulate(&small_config(100 + seed, 3, 2, 6.0), &truth, "train/").unwrap();
        let c = calibrate(&design(), &train, &plan, &mut NoopObserver).unwrap();
        assert!(c.held.is_empty(), "the flower subset excites every direction: {:?}", c.identifiability.warnings());
        fits.push(c.fitted.params.clone());
        se.push(c.identifiability.params.iter().map(|p| p.std_error.unwrap()).collect());
        se_iid.push(c.identifiability.params.iter().map(|p| p.std_error_iid.unwrap()).collect());
    }
    let n = datasets as f64;
    for i in 0..9 {
        let mean = fits.iter().map(|f| f[i]).sum::<f64>() / n;
        let spread = (fits.iter().map(|f| (f[i] - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let reported = (se.iter().map(|s| s[i] * s[i]).sum::<f64>() / n).sqrt();
        let iid = (se_iid.iter().map(|s| s[i] * s[i]).sum::<f64>() / n).sqrt();
        eprintln!(
            "param {i}: spread {spread:.3e}  reported {reported:.3e} (ratio {:.2})  iid {iid:.3e} (ratio {:.2})",
            reported / spread,
            iid / spread
        );
        assert!(
            reported / spread < 1.5 && spread / reported < 1.5,
            "param {i}: reported {reported} vs spread {spread}"
        );
    }
}
