//! Identifiability: unexcited directions are named and held at the design; standard errors match the
//! spread of fits over repeated datasets.
use crate::common::{paper_design, paper_truth, small_config};
use omnical::ga::calibrate::{Plan, Preset, Unexcited, calibrate};
use omnical::ga::observe::NoopObserver;
use omnical::kin::cost::{CostKind, cost};
use omnical::kin::simulate::{SimConfig, flower_commands, simulate};

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
    let c = calibrate(&paper_design(), &train, &plan, &mut NoopObserver).unwrap();
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
    let design_cost = cost(&paper_design().model, &paper_design().params, &held_out, path).unwrap();
    let held_cost = cost(&c.fitted.model, &c.fitted.params, &held_out, path).unwrap();
    assert!(held_cost <= design_cost, "held-out (turning) path {held_cost} vs design {design_cost}");

    // Moving freely along the unexcited directions is what the hold prevents.
    let free = Plan { unexcited: Unexcited::Move, ..plan };
    let f = calibrate(&paper_design(), &train, &free, &mut NoopObserver).unwrap();
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
        let c = calibrate(&paper_design(), &train, &plan, &mut NoopObserver).unwrap();
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

/// Runs that drive one way only cannot tell a sign-dependent wheel effect: diagnose says so instead of
/// ranking it; a repeatability floor is reported beside the noise floor.
#[test]
fn diagnose_refuses_effects_the_runs_do_not_excite() {
    use omnical::ga::diagnose::{DiagnoseOptions, diagnose, wheel_excitation_gap};
    let truth = paper_truth();
    let forward: Vec<_> = flower_commands().into_iter().filter(|c| c.omega_rad_s == 0.0).take(1).collect();
    let base = SimConfig { commands: forward, runs_per_command: 4, duration_s: 4.0, seed: 5, ..SimConfig::default() };
    let train = simulate(&base, &truth, "fwd/").unwrap();
    let names: Vec<String> = ["wheel_a", "wheel_b", "wheel_c"].map(String::from).to_vec();
    let gap = wheel_excitation_gap(&train, &names).expect("one command: every wheel turns one way");
    assert!(gap.contains("turns one way only"), "{gap}");
    let opts =
        DiagnoseOptions { candidates: vec!["wheel_asymmetry".into(), "time_offset".into()], ..Default::default() };
    let d = diagnose(&paper_design(), &paper_design(), &train, None, &opts).unwrap();
    let c = d.ranking.iter().find(|c| c.effect == "wheel_asymmetry").unwrap();
    assert!(c.not_excited.as_deref().is_some_and(|w| w.contains("turns one way only")), "{:?}", c.not_excited);
    assert_ne!(d.verdict.as_deref(), Some("wheel_asymmetry"));
    assert!(d.findings.iter().any(|f| f.starts_with("wheel_asymmetry: not tested")), "{:?}", d.findings);
    let floor = d.repeatability_floor.expect("four repeats of one command");
    assert!(floor > 0.0 && floor < 0.05, "repeatability floor {floor}");
    // A single straight command leaves the model itself poorly constrained, and the diagnosis says so.
    let id = d.identifiability.expect("identifiability");
    assert!(!id.weak.is_empty());
    assert!(d.findings.iter().any(|f| f.starts_with("the model itself:")));
}

/// The flower subset with all three kinds of path: a real effect passes the left-out-kind check.
#[test]
fn a_real_effect_helps_on_left_out_kinds_of_path() {
    use omnical::ga::diagnose::{DiagnoseOptions, diagnose};
    use omnical::kin::EffectKind;
    let mut truth = paper_truth().with_effect(EffectKind::from_id("time_offset", 3).unwrap());
    let n = truth.params.len();
    truth.params[n - 1] = 0.06;
    let (train, val) = crate::common::dataset(&truth, &small_config(9, 3, 2, 6.0));
    let plan = Plan::preset(Preset::Default, 9).seed(1);
    let fitted = calibrate(&paper_design(), &train, &plan, &mut NoopObserver).unwrap().fitted;
    let opts = DiagnoseOptions { candidates: vec!["time_offset".into(), "rotation_slip".into()], ..Default::default() };
    let d = diagnose(&fitted, &paper_design(), &train, Some(&val), &opts).unwrap();
    assert_eq!(d.verdict.as_deref(), Some("time_offset"), "{}", d.verdict_text);
    let k = d.kind_out.expect("straight and turning runs");
    assert_eq!(k.folds.len(), 3, "{:?}", k.folds);
    assert!(k.gain > 0.3, "left-out kinds: {:?}", k.folds);
}
