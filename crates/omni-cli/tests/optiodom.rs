//! OptiOdom set folders of every supported robot type, on small synthetic sets written by the tests (CI
//! has no ../shared/data): the ground truth is integrated from the wheel ticks with OptiOdom's own nominal
//! model (the formulas of the data's README), so the design model read from the metadata must reproduce it
//! to rounding; and bad metadata or rows are refused naming the file, the line and the field.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "optiodom/helpers.rs"]
mod helpers;
mod support;

use helpers::{eval_cost, train};
use omni_cli::dataset::{self, LoadOptions};
use omni_kin::cost::{self, CostKind};
use omni_kin::{FittedModel, Model};
use set::Set;
use std::path::Path;
use support::{json, omnical, param};

#[path = "optiodom/set.rs"]
mod set;

/// The design model of a synthetic set follows its ground truth to rounding: the metadata's geometry is
/// OptiOdom's nominal model, whatever the robot type, with unequal wheel diameters.
#[test]
fn design_of_every_type_reproduces_optiodom_nominal_model() {
    let dir = tempfile::tempdir().unwrap();
    for (set, wheels) in [
        (Set::omni3(), vec!["wheel_1", "wheel_2", "wheel_3"]),
        (Set::omni4(), vec!["wheel_1", "wheel_2", "wheel_3", "wheel_4"]),
        (Set::diff(), vec!["wheel_right", "wheel_left"]),
    ] {
        let folder = set.write(dir.path(), &format!("{}0001", set.kind), 3);
        let ds = dataset::load(&[folder], &LoadOptions::default()).unwrap();
        assert_eq!(ds.runs.len(), 3, "{}", set.kind);
        assert_eq!(ds.runs[0].name(), format!("{}0001/run-01", set.kind));
        assert!(ds.runs.iter().all(|r| r.n_wheels() == wheels.len() && r.truth().len() == r.n_samples()));
        assert_eq!(ds.declared.len(), 1, "the metadata declares the robot");
        assert_eq!((ds.declared[0].kind.as_str(), ds.declared[0].runs.len()), (set.kind, 3));
        let robot = ds.declared[0].geometry.clone();
        assert_eq!(robot.wheel_names, wheels);
        let design = FittedModel::nominal(Model::ik(robot.twist_from_wheels().unwrap()));
        let end = cost::cost(&design.model, &design.params, &ds.runs, CostKind::EndPose).unwrap();
        let path = cost::cost(&design.model, &design.params, &ds.runs, CostKind::PATH).unwrap();
        assert!(end < 1e-9 && path < 1e-9, "{}: Eq. 6 {end}, path {path}", set.kind);
        // The runs move: a wrong model would show.
        let far = ds.runs.iter().map(|r| r.truth().last().unwrap().pose.x_m.abs()).fold(0.0, f64::max);
        assert!(far > 0.05, "{}: runs end within {far} m of the start", set.kind);
    }
}

/// `omnical eval --model design` on a folder of each type: exit 0 and a cost at rounding level.
#[test]
fn eval_reads_omni4_and_diff_folders() {
    let dir = tempfile::tempdir().unwrap();
    for set in [Set::omni4(), Set::diff()] {
        let id = format!("{}0002", set.kind);
        set.write(dir.path(), &id, 2);
        let out = omnical(&["eval", "--model", "design", &id, "--json"], dir.path());
        assert!(out.status.success(), "{}: {}", set.kind, String::from_utf8_lossy(&out.stderr));
        let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(e["runs"].as_array().unwrap().len(), 2);
        assert!(e["cost"].as_f64().unwrap() < 1e-9, "{}: {}", set.kind, e["cost"]);
    }
}

/// Refusals: exit 2, `error: <file>: line N, <field>: …`.
fn refused(dir: &Path, id: &str) -> String {
    support::refused(&["eval", id], dir).trim().to_string()
}

#[test]
fn tricycle_and_unknown_types_are_refused_naming_file_and_type() {
    let dir = tempfile::tempdir().unwrap();
    for kind in ["tricycle", "omni5"] {
        let id = format!("{kind}0003");
        let set = Set::diff().write(dir.path(), &id, 1);
        let meta = set.join(format!("{id}_metadata.csv"));
        let text = std::fs::read_to_string(&meta).unwrap().replacen("type,diff", &format!("type,{kind}"), 1);
        std::fs::write(&meta, text).unwrap();
        assert_eq!(
            refused(dir.path(), &id),
            format!(
                "error: {id}/{id}_metadata.csv: line 1, key type: robot type \"{kind}\" is not supported (omnical \
                 reads OptiOdom's omni3, omni4, diff sets)"
            )
        );
    }
}

#[test]
fn bad_metadata_and_rows_name_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let edit = |id: &str, file: &str, from: &str, to: &str| {
        let p = dir.path().join(id).join(format!("{id}_{file}"));
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains(from), "{from:?} not in {file}");
        std::fs::write(&p, text.replacen(from, to, 1)).unwrap();
    };
    Set::omni4().write(dir.path(), "o4", 1);
    edit("o4", "metadata.csv", "Di,0.06,0.0592,0.0607,0.06", "Di,0.06,0.0592,0.0607");
    assert_eq!(
        refused(dir.path(), "o4"),
        "error: o4/o4_metadata.csv: line 5, key Di: expected 4 value(s) (wheel diameters, m), got 3"
    );
    Set::diff().write(dir.path(), "d1", 1);
    edit("d1", "metadata.csv", "Li,0.2", "Li,-0.2");
    assert_eq!(
        refused(dir.path(), "d1"),
        "error: d1/d1_metadata.csv: line 4, key Li: \"-0.2\" must be a number > 0 (wheel separation b, m)"
    );
    Set::diff().write(dir.path(), "d2", 1);
    edit("d2", "metadata.csv", "encRes,64", "encRes,sixty-four");
    assert_eq!(
        refused(dir.path(), "d2"),
        "error: d2/d2_metadata.csv: line 3, key encRes: \"sixty-four\" is not a number (encoder counts per motor \
         revolution)"
    );
    Set::diff().write(dir.path(), "d3", 1);
    edit("d3", "metadata.csv", "ngear,43.7\n", "");
    assert_eq!(refused(dir.path(), "d3"), "error: d3/d3_metadata.csv: missing key ngear");
    // Rows: a bad cell names its line and column, a short row its line and the expected count.
    Set::diff().write(dir.path(), "d4", 1);
    let run = std::fs::read_to_string(dir.path().join("d4/d4_run-01.csv")).unwrap();
    let line3: Vec<&str> = run.lines().nth(2).unwrap().split(',').collect();
    edit("d4", "run-01.csv", &line3.join(","), &[&line3[..5], &["x"]].concat().join(","));
    assert_eq!(refused(dir.path(), "d4"), "error: d4/d4_run-01.csv: line 3, column ticks_left: \"x\" is not a number");
    Set::omni4().write(dir.path(), "o5", 1);
    let run = std::fs::read_to_string(dir.path().join("o5/o5_run-01.csv")).unwrap();
    let line2 = run.lines().nth(1).unwrap();
    edit("o5", "run-01.csv", line2, line2.rsplit_once(',').unwrap().0);
    assert_eq!(
        refused(dir.path(), "o5"),
        "error: o5/o5_run-01.csv: line 2: has 7 columns, expected 8 (time, x, y, θ and 4 wheels)"
    );
}

/// A differential drive whose wheels roll 3 % more and 2 % less than declared and whose wheels sit 4 %
/// farther apart: `train --model diff` finds r_right, r_left and b; `--model ik` the same matrix, its vy
/// row held at zero (no parameter there), and both predict held-out runs to rounding.
#[test]
fn diff_models_recover_the_true_axle() {
    let dir = tempfile::tempdir().unwrap();
    let set = Set::diff().real(&[1.03, 0.98], &[0.208]);
    set.write(dir.path(), "train", 3);
    let (rr, rl, b) = (0.042 * 1.03, 0.0416 * 0.98, 0.208);
    let s = train(dir.path(), &["train", "--model", "diff", "--out", "diff.toml"]);
    let names: Vec<&str> = s["params"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["r_right", "r_left", "b"]);
    for (name, want) in [("r_right", rr), ("r_left", rl), ("b", b)] {
        assert!((param(&s, name) / want - 1.0).abs() < 1e-6, "{name} {} vs {want}", param(&s, name));
    }
    assert!(s["cost_design"].as_f64().unwrap() > 0.02, "the declared robot is off: {}", s["cost_design"]);
    let s = train(dir.path(), &["train", "--model", "ik", "--out", "ik.toml"]);
    let m = &s["matrix"];
    let want = [[rr / 2.0, rl / 2.0], [0.0, 0.0], [rr / b, -rl / b]];
    for (r, row) in want.iter().enumerate() {
        for (c, w) in row.iter().enumerate() {
            let got = m[r][c].as_f64().unwrap();
            assert!((got - w).abs() <= 1e-6 * w.abs().max(1e-3), "m{}{}: {got} vs {w}", r + 1, c + 1);
        }
    }
    assert_eq!((m[1][0].as_f64(), m[1][1].as_f64()), (Some(0.0), Some(0.0)), "vy row exactly zero");
    assert_eq!(s["params"].as_array().unwrap().len(), 4, "m11, m12, m31, m32");
    // Held-out runs (other seeds) from the same robot.
    let mut held_out = Set::diff().real(&[1.03, 0.98], &[0.208]);
    held_out.seed_offset = 5;
    held_out.write(dir.path(), "heldout", 2);
    for model in ["diff.toml", "ik.toml"] {
        let out = omnical(&["eval", "--model", model, "heldout", "--json"], dir.path());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert!(e["cost"].as_f64().unwrap() < 1e-6, "{model}: held-out Eq. 6 {}", e["cost"]);
    }
}

/// A four-wheel omni base whose wheels roll 2 %, −3 %, 1 %, 4 % off and whose l1 + l2 is 0.43 m instead
/// of 0.42 m, its wheels driven from a body twist (they never fight each other).
const OMNI4_GAINS: [f64; 4] = [1.02, 0.97, 1.01, 1.04];
fn omni4_real() -> Set {
    Set::omni4().real(&OMNI4_GAINS, &[0.21, 0.22])
}

/// `--model ik` leaves the three matrix directions along the fighting pattern to the design
/// (identifiability names them, the fit holds them) and fits the rest exactly.
#[test]
fn omni4_matrix_holds_the_pattern_that_moves_the_robot_nowhere() {
    let dir = tempfile::tempdir().unwrap();
    omni4_real().write(dir.path(), "train", 3);
    let s = train(dir.path(), &["train", "--model", "ik"]);
    let weak = s["identifiability"]["weak"].as_array().unwrap();
    assert_eq!(s["held_at_start"].as_array().unwrap().len(), 3, "{}", s["warnings"]);
    for w in weak {
        let u: Vec<f64> = w["wheel_pattern"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        let signs: Vec<f64> = u.iter().map(|v| v.signum() * u[0].signum()).collect();
        assert_eq!(signs, [1.0, -1.0, -1.0, 1.0], "the wheels fighting each other: {u:?}");
        assert!(w["text"].as_str().unwrap().contains("moves the robot nowhere"), "{}", w["text"]);
    }
    assert!(s["cost_fitted"].as_f64().unwrap() < 1e-6, "{}", s["cost_fitted"]);
}

/// `--model mecanum` finds the radii and lx + ly, and holds lx − ly, which a rectangle of wheels pushing
/// at ±45° cannot show.
#[test]
fn omni4_mecanum_model_finds_radii_and_lx_plus_ly() {
    let dir = tempfile::tempdir().unwrap();
    omni4_real().write(dir.path(), "train", 3);
    let s = train(dir.path(), &["train", "--model", "mecanum"]);
    let design_r = [0.06, 0.0592, 0.0607, 0.06].map(|d: f64| d / (2.0 * 2f64.sqrt()));
    for (i, name) in ["r_a", "r_b", "r_c", "r_d"].iter().enumerate() {
        let want = design_r[i] * OMNI4_GAINS[i];
        assert!((param(&s, name) / want - 1.0).abs() < 1e-6, "{name} {} vs {want}", param(&s, name));
    }
    let (lx, ly) = (param(&s, "lx"), param(&s, "ly"));
    assert!(((lx + ly) / 0.215 - 1.0).abs() < 1e-6, "lx + ly = {}", lx + ly);
    assert!((lx - ly).abs() < 1e-9, "lx − ly held at the design's 0: {lx} {ly}");
    let held = s["held_at_start"].as_array().unwrap();
    assert_eq!(held.len(), 1, "{}", s["warnings"]);
    let text = held[0].as_str().unwrap();
    assert!(text.starts_with("lx and ly enter the kinematics only as lx + ly ("), "{text}");
}

/// Two omni4 sets of one robot that declare different geometries (Li 0.2, 0.2 and 0.205, 0.215, as the
/// shared sets do): each run is integrated with its own set's design, so the pooled Eq. 6 is the
/// run-weighted mean of the sets' own costs and the path RMS the root of the run-weighted mean MSE, in
/// either order; the last set's design on every run (what one design for all gave) differs. Diagnose's
/// design costs are the same numbers, and training starts from the design of the most runs.
#[test]
fn each_set_is_evaluated_with_its_own_design() {
    let dir = tempfile::tempdir().unwrap();
    let robot =
        |li: &[f64]| Set::new("omni4", 1.0, 1.0, li, &[0.06; 4], 0.01).real(&[1.01, 0.99, 1.0, 1.02], &[0.208, 0.208]);
    robot(&[0.2, 0.2]).write(dir.path(), "a", 2);
    robot(&[0.205, 0.215]).write(dir.path(), "b", 3);
    Set { seed_offset: 7, ..robot(&[0.2, 0.2]) }.write(dir.path(), "c", 2);
    let (ca, pa) = eval_cost(dir.path(), "design", &[Path::new("a")]);
    let (cb, pb) = eval_cost(dir.path(), "design", &[Path::new("b")]);
    let (c, p) = eval_cost(dir.path(), "design", &[Path::new("a"), Path::new("b")]);
    let (eq6, path) = ((2.0 * ca + 3.0 * cb) / 5.0, ((2.0 * pa * pa + 3.0 * pb * pb) / 5.0).sqrt());
    assert!((c - eq6).abs() < 1e-12 && (p - path).abs() < 1e-12, "pooled {c} / {p} vs {eq6} / {path}");
    let (c2, p2) = eval_cost(dir.path(), "design", &[Path::new("b"), Path::new("a")]);
    assert!((c2 - c).abs() < 1e-12 && (p2 - p).abs() < 1e-12, "{c2} / {p2} in the other order");
    // One design for all (b's, the last folder's) on a's runs is another number.
    let a = dataset::load(&[dir.path().join("a")], &LoadOptions::default()).unwrap();
    let b = dataset::load(&[dir.path().join("b")], &LoadOptions::default()).unwrap();
    let b_design = Model::geometry(b.declared[0].geometry.clone());
    let a_with_b = cost::cost(&b_design, &b_design.nominal(), &a.runs, CostKind::EndPose).unwrap();
    assert!((a_with_b - ca).abs() > 0.05 * ca, "a's runs: own design {ca}, b's {a_with_b}");
    // Diagnose: the design costs on the training runs are eval's pooled figures, held out c's own.
    let d = json(
        &["diagnose", "--model", "design", "a", "b", "--validate", "c", "--candidates", "time_offset", "--json"],
        dir.path(),
    );
    let (cc, pc) = eval_cost(dir.path(), "design", &[Path::new("c")]);
    let costs = &d["design_costs"];
    let got =
        ["train_end_pose", "train_path", "held_out_end_pose", "held_out_path"].map(|k| costs[k].as_f64().unwrap());
    for (g, want) in got.iter().zip([c, p, cc, pc]) {
        assert!((g - want).abs() < 1e-12, "diagnose design costs {costs} vs {want}");
    }
    assert_eq!(d["ladder"][0]["costs"], d["design_costs"], "the ladder's first rung is the design");
    // Training starts from b's design (3 of 5 runs), and says so; its design figure is each run's own.
    let out = omnical(&["train", "--json", "a", "b"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(
            "note: the inputs declare 2 different designs: b (3 runs), a (2 runs); each run is evaluated with its \
             own input's design, and where one design is needed (training's start, --model design) it is that of \
             b (the most runs)"
        ),
        "{stderr}"
    );
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut all = a.runs.clone();
    all.extend(b.runs.clone());
    let start = cost::cost(&b_design, &b_design.nominal(), &all, CostKind::EndPose).unwrap();
    assert!((s["cost_design"].as_f64().unwrap() - start).abs() < 1e-9, "{} vs {start}", s["cost_design"]);
    assert_eq!(s["designs"]["designs"], 2);
    assert_eq!(s["designs"]["start"], "b");
    assert!((s["designs"]["cost"].as_f64().unwrap() - c).abs() < 1e-9, "{} vs {c}", s["designs"]);
}

/// Robots of different kinds in one command are refused (exit 2), naming both inputs and their kinds:
/// among the training runs, and between the training and the held-out runs.
#[test]
fn robots_of_different_kinds_are_refused_naming_both() {
    let dir = tempfile::tempdir().unwrap();
    Set::omni3().write(dir.path(), "o3", 1);
    Set::diff().write(dir.path(), "df", 1);
    Set::omni4().write(dir.path(), "o4", 1);
    for (args, want) in [
        (
            vec!["eval", "o3", "df"],
            "error: df: runs of robots of different kinds in one command: o3 is an OptiOdom omni3 set (3 wheels), \
             and df is an OptiOdom diff set (2 wheels); give one robot's runs (train and validate one robot at a \
             time)",
        ),
        (
            vec!["diagnose", "--model", "design", "o4", "--validate", "o3"],
            "error: o3: runs of robots of different kinds in one command: o4 is an OptiOdom omni4 set (4 wheels), \
             and o3 is an OptiOdom omni3 set (3 wheels); give one robot's runs (train and validate one robot at a \
             time)",
        ),
    ] {
        let out = omnical(&args, dir.path());
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", String::from_utf8_lossy(&out.stdout));
        assert_eq!(String::from_utf8_lossy(&out.stderr).trim(), want);
    }
}

/// The paper preset's fixed 10 ms step on 40 ms (omni3) and 50 ms (diff) sets: refused before fitting
/// (exit 1, the fix in the message, nothing written); with --force fitted and written, with a warning for
/// the step and one for a fit worse than the design it started from (both objectives).
#[test]
fn paper_preset_on_other_sampling_is_refused_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    Set { wheel_gain: vec![1.01, 0.99, 1.0], ..Set::omni3() }.write(dir.path(), "o3", 2);
    Set::diff().real(&[1.01, 0.99], &[0.205]).write(dir.path(), "df", 2);
    for (set, ms, factor) in [("o3", 40, "0.25"), ("df", 50, "0.20")] {
        let out = omnical(&["train", set, "--preset", "paper", "--out", "m.toml"], dir.path());
        assert_eq!(out.status.code(), Some(1), "{set}: {}", String::from_utf8_lossy(&out.stderr));
        assert_eq!(
            String::from_utf8_lossy(&out.stderr).trim(),
            format!(
                "error: the paper preset integrates fixed 10 ms steps (Eq. 1), but these runs are sampled every {ms} \
                 ms (median wheel-sample interval): odometry would be off by a factor {factor} and the fit worse \
                 than the design; use --preset default (each run's own step); --force fits with the fixed step \
                 anyway"
            )
        );
        assert!(!dir.path().join("m.toml").exists(), "{set}: nothing written");
        let out = omnical(&["train", set, "--preset", "paper", "--out", "m.toml", "--force", "--json"], dir.path());
        assert!(out.status.success(), "{set}: {}", String::from_utf8_lossy(&out.stderr));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(&format!("warning: the paper preset integrates fixed 10 ms steps (Eq. 1), but these runs are sampled every {ms} ms")), "{stderr}");
        assert!(
            stderr.contains("warning: the fitted model is worse than its start on its own training runs: end_pose "),
            "{stderr}"
        );
        assert!(stderr.contains("; kept because of --force"), "{stderr}");
        assert!(dir.path().join("m.toml").exists(), "{set}: written with --force");
        std::fs::remove_file(dir.path().join("m.toml")).unwrap();
    }
}
