//! `Diagnosis::unexplained` on simulated data whose truth is known: clean data (nothing missing), an effect
//! outside the catalogue whose remaining error is below 3× the noise floor (the repeats reveal it), a
//! catalogued effect that diagnose accepts (nothing left after it), and runs without repeats (the
//! noise-floor ratio decides, and says so).
#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

mod support;

use omni_ga::diagnose::{DecidedBy, DiagnoseOptions, Diagnosis, diagnose};
use omni_kin::simulate::{SimConfig, flower_commands, simulate};
use omni_kin::{EffectKind, FittedModel, IkMatrix, Model, Run};
use std::sync::Arc;
use support::HeadingDrift;

/// The true base (the paper's calibrated APR-02), the model diagnosed.
fn base() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))
}

/// `base` plus `effect` at `values`.
fn truth_with(effect: EffectKind, values: &[f64]) -> FittedModel {
    let mut t = base().with_effect(effect);
    let n = t.params.len();
    t.params[n - values.len()..].copy_from_slice(values);
    t
}

/// Every third flower command (12: straight, left and right turns), `repeats` times, 4 s each.
fn runs(truth: &FittedModel, repeats: usize, seed: u64) -> Vec<Run> {
    let commands = flower_commands().into_iter().step_by(3).collect();
    let cfg = SimConfig { commands, runs_per_command: repeats, duration_s: 4.0, seed, ..SimConfig::default() };
    simulate(&cfg, truth, "u/").unwrap()
}

/// Diagnose the true base on `train` (2-fold cross-validation over repetitions) with `candidates`.
fn diagnosis(train: &[Run], candidates: &[&str]) -> Diagnosis {
    let opts = DiagnoseOptions { candidates: candidates.iter().map(|s| s.to_string()).collect(), ..Default::default() };
    diagnose(&base(), &base(), train, None, &opts).unwrap()
}

#[test]
fn clean_data_leaves_nothing_unexplained() {
    for seed in [1, 2, 3, 4, 5] {
        let d = diagnosis(&runs(&base(), 4, seed), &["time_offset", "rotation_slip"]);
        let e = &d.unexplained_evidence;
        eprintln!("clean seed {seed}: {e:?}\n  {}", d.verdict_text);
        assert!(!d.unexplained, "seed {seed}: {}", d.verdict_text);
        assert_eq!(e.decided_by, DecidedBy::Repeats);
        assert_eq!(e.groups_total, 12);
        assert!(e.groups_biased <= 2, "seed {seed}: {} of 12 biased", e.groups_biased);
        assert!(d.verdict_text.contains("no systematic error remains, decided by the repeats"), "{}", d.verdict_text);
    }
}

#[test]
fn an_uncatalogued_effect_below_three_times_the_noise_floor_is_found_by_the_repeats() {
    // 0.1 rad of heading per metre travelled: wheel_asymmetry takes part of it (the verdict), the rest
    // stays 2× the noise floor, where a ratio test (3×) would call it noise.
    let truth = truth_with(EffectKind::Custom(Arc::new(HeadingDrift)), &[0.1]);
    for seed in [7, 8] {
        let d = diagnosis(&runs(&truth, 4, seed), omni_kin::effect::CATALOGUE);
        let e = &d.unexplained_evidence;
        eprintln!("uncatalogued seed {seed}: {e:?}\n  {}", d.verdict_text);
        let ratio = e.ratio.unwrap();
        assert!(ratio < 3.0, "the noise-floor ratio alone would hide it: {ratio}");
        assert!(d.unexplained, "{}", d.verdict_text);
        assert_eq!(e.decided_by, DecidedBy::Repeats);
        assert!(e.share_biased.unwrap() >= 0.5 && e.chance_probability.unwrap() < 1e-4, "{e:?}");
        assert!(e.late_m.unwrap() > 2.0 * e.early_m.unwrap(), "the error grows along the path: {e:?}");
        let text = &d.verdict_text;
        assert!(text.contains("something physical is still missing, decided by the repeats"), "{text}");
        assert!(text.contains("command groups end biased beyond their repeat scatter"), "{text}");
    }
}

#[test]
fn an_accepted_catalogued_effect_leaves_nothing_unexplained() {
    let truth = truth_with(EffectKind::from_id("time_offset", 3).unwrap(), &[0.05]);
    let train = runs(&truth, 4, 11);
    let d = diagnosis(&train, &["time_offset", "rotation_slip"]);
    eprintln!("time_offset: {:?}\n  {}", d.unexplained_evidence, d.verdict_text);
    assert_eq!(d.verdict.as_deref(), Some("time_offset"));
    assert!(!d.unexplained, "{}", d.verdict_text);
    assert_eq!(d.unexplained_evidence.decided_by, DecidedBy::Repeats);
}

#[test]
fn without_repeats_the_noise_floor_ratio_decides_and_says_so() {
    let d = diagnosis(&runs(&base(), 1, 5), &["time_offset"]);
    let e = &d.unexplained_evidence;
    assert_eq!((e.decided_by, e.groups_total, e.share_biased), (DecidedBy::NoiseFloorRatio, 0, None));
    assert!(!d.unexplained);
    assert!(e.ratio.unwrap() < 3.0, "{e:?}");
    assert!(
        d.verdict_text.contains(
            "no command was repeated and no two runs are of one kind, so the group test could not be made; decided by the noise floor alone"
        ),
        "{}",
        d.verdict_text
    );
}
