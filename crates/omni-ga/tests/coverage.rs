//! Standard errors that cover the truth: over independent simulated datasets whose true clock offset is
//! known, about 68 % of the fitted `tau_s` values lie within one standard error of the truth, on the
//! diagnose path (a candidate's refit) and on the train path (`calibrate`'s identifiability), and both
//! paths give the same standard error for the same parameter on the same runs (issue 19).
#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use omni_ga::calibrate::{Plan, Preset, Stage, calibrate};
use omni_ga::diagnose::{DiagnoseOptions, diagnose};
use omni_ga::{LmConfig, NoopObserver};
use omni_kin::simulate::{SimConfig, flower_commands, simulate};
use omni_kin::{EffectKind, FittedModel, IkMatrix, Model, Run};

/// The true clock offset of every dataset. s.
const TRUE_TAU_S: f64 = 0.06;

/// Independent datasets (seeds).
const SEEDS: u64 = 40;

/// The true robot: the paper's calibrated APR-02 with a clock offset of [`TRUE_TAU_S`].
fn truth() -> FittedModel {
    let mut t = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))
        .with_effect(EffectKind::from_id("time_offset", 3).unwrap());
    let n = t.params.len();
    t.params[n - 1] = TRUE_TAU_S;
    t
}

/// A small dataset: every third flower command (12: straight, left and right turns), twice, 10 s each (the default) —
/// 24 runs, enough for the per-run estimate of 10 parameters (it needs `p + 2`).
fn runs(seed: u64) -> Vec<Run> {
    let commands = flower_commands().into_iter().step_by(3).collect();
    let cfg = SimConfig { commands, runs_per_command: 2, duration_s: 10.0, seed, ..SimConfig::default() };
    simulate(&cfg, &truth(), "c/").unwrap()
}

/// `tau_s` and its standard error from `diagnose` (the `time_offset` candidate refitted on `train`; the
/// validation set is `train` itself, so the refit sees exactly the runs `calibrate` sees).
fn diagnose_tau(train: &[Run]) -> (f64, f64) {
    let design = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let model = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    let opts = DiagnoseOptions { candidates: vec!["time_offset".into()], ..Default::default() };
    let d = diagnose(&model, &design, train, Some(train), &opts).unwrap();
    let c = d.ranking.iter().find(|c| c.effect == "time_offset").unwrap();
    let p = c.params.iter().find(|p| p.name == "tau_s").unwrap();
    (p.value, p.std_error.unwrap())
}

/// `tau_s`, its standard error and its iid standard error (the plain least-squares one) from `calibrate`
/// (Levenberg–Marquardt from the design with the effect at null; the diagnosis's objective and odometry
/// integration).
fn train_tau(train: &[Run]) -> (f64, f64, f64) {
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()))
        .with_effect(EffectKind::from_id("time_offset", 3).unwrap());
    let mut plan = Plan::preset(Preset::Default, start.params.len());
    plan.stages = vec![Stage::Lm(LmConfig::default())];
    plan.integration = start.model.integration;
    let c = calibrate(&start, train, &plan, &mut NoopObserver).unwrap();
    let p = c.identifiability.params.iter().find(|p| p.name == "time_offset.tau_s").unwrap();
    (p.value, p.std_error.unwrap(), p.std_error_iid.unwrap())
}

#[test]
fn one_standard_error_covers_the_true_clock_offset_about_68_percent_of_the_time_on_both_paths() {
    let (mut covered_diagnose, mut covered_train, mut covered_iid) = (0, 0, 0);
    let mut ratio_iid = 0.0;
    for seed in 0..SEEDS {
        let train = runs(1000 + seed);
        let (vd, sd) = diagnose_tau(&train);
        let (vt, st, st_iid) = train_tau(&train);
        // The same computation on the same runs: the two fits reach the same minimum, so the values and
        // the standard errors agree to the fits' convergence (far below the standard error itself).
        assert!((vd - vt).abs() < 0.02 * sd, "seed {seed}: tau {vd} (diagnose) vs {vt} (train), se {sd}");
        assert!((sd / st - 1.0).abs() < 1e-2, "seed {seed}: se {sd} (diagnose) vs {st} (train)");
        eprintln!("seed {seed}: tau_s {vd:.5} ± {sd:.5} s (diagnose), {vt:.5} ± {st:.5} s (train)");
        covered_diagnose += usize::from((vd - TRUE_TAU_S).abs() <= sd);
        covered_train += usize::from((vt - TRUE_TAU_S).abs() <= st);
        covered_iid += usize::from((vt - TRUE_TAU_S).abs() <= st_iid);
        ratio_iid += st_iid / st / SEEDS as f64;
    }
    // With honest standard errors each dataset covers the truth with probability 0.683, so the count
    // over 40 independent datasets is Binomial(40, 0.683): mean 27.3, standard deviation 2.94. The band
    // 20…34 (50–85 %) is −2.5 to +2.3 standard deviations: an honest estimator falls outside it with
    // probability ≈ 1 %, while the plain least-squares errors (which treat the correlated residuals along
    // a path as independent; here 0.43× the per-run errors) cover 7 of 40 and fail it.
    for (path, covered) in [("diagnose", covered_diagnose), ("train", covered_train)] {
        eprintln!("{path}: {covered} of {SEEDS} datasets within one standard error of the true tau_s");
        assert!((20..=34).contains(&covered), "{path}: {covered} of {SEEDS} within one standard error");
    }
    eprintln!(
        "iid (plain least squares): {covered_iid} of {SEEDS} within one standard error, {ratio_iid:.2} × per run"
    );
    assert!(covered_iid < 20, "the band must reject the iid errors: {covered_iid} of {SEEDS} covered");
}
