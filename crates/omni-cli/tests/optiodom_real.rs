//! OptiOdom's real sets (../shared/data, docs/real-robots.md): what training finds on the real four-wheel
//! omni base and differential drive, each set evaluated with its own design, and the paper preset refused on
//! their 40 and 50 ms sampling. Reported as ignored without the data (build.rs).
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "optiodom/helpers.rs"]
mod helpers;
mod support;

use helpers::{eval_cost, train};
use omni_cli::dataset::{self, LoadOptions};
use omni_kin::Model;
use omni_kin::cost::{self, CostKind};
use std::path::Path;
use support::{json, omnical, param, shared_data};

/// The real four-wheel robot (docs/real-robots.md): the design's Eq. 6 on set 080920201715, the fitted
/// matrix on it and on the other set, and identifiability's finding: the runs hardly contain the wheels
/// fighting each other, so the three matrix directions along that pattern are held at the design; with
/// the per-run standard errors of the runs cut into segments (8 runs are fewer than 12 parameters + 2),
/// two more directions, how the translation answers turning on the spot, are poorly constrained (±5.8 %,
/// ±6.6 % of scale) and held.
#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn real_omni4_runs_hold_the_fighting_pattern() {
    let data = shared_data("omni4");
    let dir = tempfile::tempdir().unwrap();
    let (train_set, other) = (data.join("080920201715"), data.join("231220200521"));
    let s = train(dir.path(), &[train_set.to_str().unwrap(), "--model", "ik", "--out", "ik.toml"]);
    // Measured: design 0.39375, fitted 0.04518 (Eq. 6), 5 directions held, 88 segments of 8 runs.
    assert!((s["cost_design"].as_f64().unwrap() - 0.39375).abs() < 1e-4, "{}", s["cost_design"]);
    assert!(s["cost_fitted"].as_f64().unwrap() < 0.05, "{}", s["cost_fitted"]);
    assert_eq!(s["identifiability"]["covariance_kind"], "per_run");
    assert!(s["identifiability"]["clusters"].as_u64().unwrap() > 8 * 5, "{}", s["identifiability"]["clusters"]);
    let weak = s["identifiability"]["weak"].as_array().unwrap();
    assert_eq!(s["held_at_start"].as_array().unwrap().len(), 5, "{}", s["warnings"]);
    let fighting = weak
        .iter()
        .filter(|w| {
            let u: Vec<f64> = w["wheel_pattern"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let want = [0.5, -0.5, -0.5, 0.5].map(|v| v * u[0].signum());
            u.iter().zip(want).all(|(a, b)| (a - b).abs() < 0.05)
        })
        .inspect(|w| assert!(w["text"].as_str().unwrap().contains("moves the robot nowhere"), "{}", w["text"]))
        .count();
    assert_eq!(fighting, 3, "{}", s["warnings"]);
    // Held out: the other set (another declared geometry, longer runs). Measured 0.1113 vs design 0.9840.
    let (held_out, _) = eval_cost(dir.path(), "ik.toml", &[&other]);
    let (design, _) = eval_cost(dir.path(), "design", &[&other]);
    assert!(held_out < 0.2 * design, "held-out {held_out} vs design {design}");
}

/// The real differential drive: `--model diff` on one set finds a separation near 0.2007 m and radii
/// near 41.9 mm, and beats the design on the three other sets.
#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn real_diff_runs_fit_the_axle() {
    let data = shared_data("diff");
    let dir = tempfile::tempdir().unwrap();
    let sets: Vec<std::path::PathBuf> =
        ["230620202042", "230620202144", "231220200029", "231220200040"].iter().map(|s| data.join(s)).collect();
    let s = train(dir.path(), &[sets[0].to_str().unwrap(), "--model", "diff", "--out", "diff.toml"]);
    // Measured: b 0.200672 m, r_right 0.041891 m, r_left 0.041925 m; Eq. 6 0.04623 → 0.00835.
    assert!((param(&s, "b") - 0.2007).abs() < 5e-4, "{}", param(&s, "b"));
    for r in ["r_right", "r_left"] {
        assert!((param(&s, r) - 0.0419).abs() < 2e-4, "{r} {}", param(&s, r));
    }
    assert!(s["cost_fitted"].as_f64().unwrap() < 0.25 * s["cost_design"].as_f64().unwrap());
    for other in &sets[1..] {
        let (fitted, _) = eval_cost(dir.path(), "diff.toml", &[other]);
        let (design, _) = eval_cost(dir.path(), "design", &[other]);
        assert!(fitted < 0.7 * design, "{}: fitted {fitted} vs design {design}", other.display());
    }
}

/// The shared sets that declare different designs (omni4: Li 0.2, 0.2 on 8 runs and 0.205, 0.215 on 12;
/// diff: b = 0.205 on 230620202144, 0.2 on the three others; docs/real-robots.md): `eval --model design`
/// pools the sets' own costs run-weighted, in either order (one design for all gave 0.87913 or 0.49577 by
/// folder order), and diagnose's design costs are eval's figures on its training and held-out runs (its
/// held-out design on 231220200521 was 080920201715's, 0.5638).
#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn real_sets_are_each_evaluated_with_their_own_design() {
    let omni4 = shared_data("omni4");
    let diff = shared_data("diff");
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (omni4.join("080920201715"), omni4.join("231220200521"));
    let (ca, pa) = eval_cost(dir.path(), "design", &[&a]);
    let (cb, pb) = eval_cost(dir.path(), "design", &[&b]);
    for order in [[a.as_path(), b.as_path()], [b.as_path(), a.as_path()]] {
        let (c, p) = eval_cost(dir.path(), "design", &order);
        assert!((c - (8.0 * ca + 12.0 * cb) / 20.0).abs() < 1e-12, "{c} vs {ca}, {cb}");
        assert!((p - ((8.0 * pa * pa + 12.0 * pb * pb) / 20.0).sqrt()).abs() < 1e-12, "{p} vs {pa}, {pb}");
        // Measured: 0.39375 and 0.98397 → 0.74788; path 0.19433 and 0.46753 → 0.38244.
        let rounded = [ca, cb, c, pa, pb, p].map(|x| (x * 1e5).round() / 1e5);
        assert_eq!(rounded, [0.39375, 0.98397, 0.74788, 0.19433, 0.46753, 0.38244]);
    }
    // One design for all, the last folder's (what eval gave before): 0.87913 / 0.42578 in this order,
    // 0.49577 / 0.24558 in the other; a's design on b's runs 0.5638.
    let one_for_all = |sets: &[&Path], last: &Path| -> [f64; 2] {
        let paths: Vec<std::path::PathBuf> = sets.iter().map(|p| p.to_path_buf()).collect();
        let runs = dataset::load(&paths, &LoadOptions::default()).unwrap().runs;
        let own = dataset::load(&[last.to_path_buf()], &LoadOptions::default()).unwrap();
        let m = Model::geometry(own.declared[0].geometry.clone());
        [CostKind::EndPose, CostKind::PATH]
            .map(|k| (cost::cost(&m, &m.nominal(), &runs, k).unwrap() * 1e5).round() / 1e5)
    };
    assert_eq!(one_for_all(&[&a, &b], &b), [0.87913, 0.42578]);
    assert_eq!(one_for_all(&[&b, &a], &a), [0.49577, 0.24558]);
    assert_eq!(one_for_all(&[&b], &a)[0], 0.56378);
    let d = json(
        &[
            "diagnose",
            "--model",
            "design",
            a.to_str().unwrap(),
            "--validate",
            b.to_str().unwrap(),
            "--candidates",
            "time_offset",
            "--json",
        ],
        dir.path(),
    );
    let got = ["train_end_pose", "train_path", "held_out_end_pose", "held_out_path"]
        .map(|k| d["design_costs"][k].as_f64().unwrap());
    for (g, want) in got.iter().zip([ca, pa, cb, pb]) {
        assert!((g - want).abs() < 1e-12, "omni4 diagnose design costs {} vs {want}", d["design_costs"]);
    }
    let sets = ["230620202042", "230620202144", "231220200029", "231220200040"].map(|s| diff.join(s));
    let own: Vec<(f64, f64)> = sets.iter().map(|s| eval_cost(dir.path(), "design", &[s])).collect();
    let (c, p) = eval_cost(dir.path(), "design", &sets.iter().map(|s| s.as_path()).collect::<Vec<_>>());
    let mean = own.iter().map(|o| o.0).sum::<f64>() / 4.0;
    let rms = (own.iter().map(|o| o.1 * o.1).sum::<f64>() / 4.0).sqrt();
    assert!((c - mean).abs() < 1e-12 && (p - rms).abs() < 1e-12, "diff pooled {c} / {p} vs {mean} / {rms}");
    assert_eq!([c, p].map(|x| (x * 1e5).round() / 1e5), [0.09558, 0.06663]);
    let last = dataset::load(&[sets[3].clone()], &LoadOptions::default()).unwrap();
    let m = Model::design(omni_kin::KinematicsKind::Diff, Some(&last.declared[0].geometry)).unwrap();
    let runs = dataset::load(&sets, &LoadOptions::default()).unwrap().runs;
    let before = [CostKind::EndPose, CostKind::PATH]
        .map(|k| (cost::cost(&m, &m.nominal(), &runs, k).unwrap() * 1e5).round() / 1e5);
    assert_eq!(before, [0.07874, 0.0608], "one design for all, the last folder's");
    let d = json(
        &[
            "diagnose",
            "--model",
            "design",
            sets[0].to_str().unwrap(),
            sets[1].to_str().unwrap(),
            "--validate",
            sets[2].to_str().unwrap(),
            "--validate",
            sets[3].to_str().unwrap(),
            "--candidates",
            "time_offset",
            "--json",
        ],
        dir.path(),
    );
    let (train, held) = (
        eval_cost(dir.path(), "design", &[&sets[0], &sets[1]]),
        eval_cost(dir.path(), "design", &[&sets[2], &sets[3]]),
    );
    let got = ["train_end_pose", "train_path", "held_out_end_pose", "held_out_path"]
        .map(|k| d["design_costs"][k].as_f64().unwrap());
    for (g, want) in got.iter().zip([train.0, train.1, held.0, held.1]) {
        assert!((g - want).abs() < 1e-12, "diff diagnose design costs {} vs {want}", d["design_costs"]);
    }
}

/// The paper preset on the shared omni3 (40 ms) and diff (50 ms) sets (docs/presets.md): refused before
/// fitting (exit 1, nothing written); with --force the written model is far worse than the design on its
/// own training runs (measured Eq. 6: omni3 221220201934 2.17061 against 0.18560, 11.7×; diff
/// 230620202042 1.26201 against 0.04623, 27.3×), which the warning says.
#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn real_paper_preset_is_refused_on_40_and_50_ms_runs() {
    let omni3 = shared_data("omni3");
    let diff = shared_data("diff");
    let dir = tempfile::tempdir().unwrap();
    for (set, ms, fitted, design) in
        [(omni3.join("221220201934"), 40, 2.17061, 0.18560), (diff.join("230620202042"), 50, 1.26201, 0.04623)]
    {
        let set = set.to_str().unwrap();
        let out = omnical(&["train", set, "--preset", "paper", "--out", "m.toml"], dir.path());
        assert_eq!(out.status.code(), Some(1), "{set}: {}", String::from_utf8_lossy(&out.stderr));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.starts_with(&format!(
                "error: the paper preset integrates fixed 10 ms steps (Eq. 1), but these runs are sampled every {ms} ms"
            )),
            "{stderr}"
        );
        assert!(stderr.contains("use --preset default (each run's own step); --force fits"), "{stderr}");
        assert!(!dir.path().join("m.toml").exists(), "{set}: nothing written");
        let out = omnical(&["train", set, "--preset", "paper", "--out", "m.toml", "--force"], dir.path());
        assert!(out.status.success(), "{set}: {}", String::from_utf8_lossy(&out.stderr));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(&format!("warning: the fitted model is worse than its start on its own training runs: end_pose {fitted:.5} fitted against {design:.5} for the start as given")), "{stderr}");
        let (c, _) = eval_cost(dir.path(), "m.toml", &[Path::new(set)]);
        let (d, _) = eval_cost(dir.path(), "design", &[Path::new(set)]);
        assert!((c - fitted).abs() < 1e-5 && (d - design).abs() < 1e-5, "{set}: {c} vs {d}");
        std::fs::remove_file(dir.path().join("m.toml")).unwrap();
    }
}
