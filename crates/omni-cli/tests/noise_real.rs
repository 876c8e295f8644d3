//! How far to trust the odometry on OptiOdom's real robots (issue 46, docs/real-robots.md): each set trained
//! with `train`'s defaults, its noise model judged on its robot's other set(s) by `eval`: the share of
//! held-out windows inside the 95 % ellipse at 1 m and 5 m. Reported as ignored without the data (build.rs).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::Path;
use support::{json, omnical, shared_data};

/// The fitted model's coverage at 1 m and 5 m (`None`: no held-out window drives that far) of the model
/// trained on `train_set`, judged on `held_out`.
fn coverage(dir: &Path, train_set: &Path, held_out: &[&Path]) -> Vec<Option<f64>> {
    json(&["train", "--json", "-q", train_set.to_str().unwrap(), "--out", "m.toml"], dir);
    judged(dir, "m.toml", train_set, held_out)
}

/// The coverage at 1 m and 5 m of the noise model `model` carries, judged on `held_out`.
fn judged(dir: &Path, model: &str, train_set: &Path, held_out: &[&Path]) -> Vec<Option<f64>> {
    let mut args = vec!["eval", "--model", model, "--json"];
    args.extend(held_out.iter().map(|p| p.to_str().unwrap()));
    let e = json(&args, dir);
    let fitted = &e["noise_coverage"][0];
    assert_eq!(fitted["predictor"], "fitted");
    let got: Vec<Option<f64>> =
        fitted["horizons"].as_array().unwrap()[..2].iter().map(|h| h["coverage"].as_f64()).collect();
    eprintln!("{} -> {held_out:?}: {got:?}", train_set.display());
    got
}

/// The differential drive, trained on one day (…2042) and judged on the other three sets: within 90–98 %
/// at 1 m and 5 m (measured 90.6 % and 93.6 %). Without the per-run biases it was too bold (77.6 %, 82.0 %):
/// the other days carry systematic errors of their own, which grow with the distance itself.
#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn real_diff_drive_noise_model_covers_the_other_days() {
    let data = shared_data("diff");
    let dir = tempfile::tempdir().unwrap();
    let others: Vec<_> = ["230620202144", "231220200029", "231220200040"].iter().map(|s| data.join(s)).collect();
    let others: Vec<&Path> = others.iter().map(|p| p.as_path()).collect();
    let train_set = data.join("230620202042");
    let got = coverage(dir.path(), &train_set, &others);
    // The same after the systematic part `diagnose` finds is taken out: its final model (a wheel's
    // eccentricity added) carries its own noise model; measured 91.6 % and 93.7 %.
    let args = ["diagnose", "--model", "m.toml", train_set.to_str().unwrap(), "--auto", "--out", "final.toml", "-q"];
    let out = omnical(&args, dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let final_model = std::fs::read_to_string(dir.path().join("final.toml")).unwrap();
    assert!(final_model.contains("[[effects]]") && final_model.contains("[noise.rates]"), "{final_model}");
    let after = judged(dir.path(), "final.toml", &train_set, &others);
    for c in got.into_iter().chain(after) {
        let c = c.unwrap();
        assert!((0.90..=0.98).contains(&c), "{c}");
    }
}

/// The omni bases: within 90–98 % at 1 m (omni3 …1934 → …1953: 97.4 %; omni4 …1715 → …0521: 93.5 %) and
/// too cautious at 5 m (100 %): the squares' errors cancel over a closed loop, which no noise of the odometry
/// itself does (docs/real-robots.md says so, and `eval` prints why).
#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn real_omni_noise_models_hold_at_1_m_and_are_cautious_at_5_m() {
    for (robot, train_set, held_out) in
        [("omni3", "221220201934", "221220201953"), ("omni4", "080920201715", "231220200521")]
    {
        let data = shared_data(robot);
        let dir = tempfile::tempdir().unwrap();
        let got = coverage(dir.path(), &data.join(train_set), &[&data.join(held_out)]);
        assert!((0.90..=0.98).contains(&got[0].unwrap()), "{robot} at 1 m: {got:?}");
        assert!(got[1].unwrap() > 0.98, "{robot} at 5 m: {got:?}");
    }
}
