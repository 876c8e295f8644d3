//! The `omnical` binary end to end, in a temporary folder: exit codes, messages, files.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use support::{omnical, omnical_command, shared_data};

#[test]
fn simulate_train_eval_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let out =
        omnical(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "4", "--seed", "3"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("sim/truth.json")).unwrap()).unwrap();
    let (design, oracle) =
        (truth["design_cost"]["train"].as_f64().unwrap(), truth["oracle_cost"]["train"].as_f64().unwrap());
    assert!(oracle * 5.0 < design, "oracle {oracle} design {design}");
    let files: Vec<String> = std::fs::read_dir(dir.path().join("sim/train"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(files.iter().filter(|f| f.ends_with(".mcap")).count(), 36);
    assert!(files.iter().any(|f| f == "robot.toml"), "{files:?}");

    let out = omnical(&["train", "sim/train", "--out", "fit.toml", "--json"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in ["cost_design", "cost_fitted", "evaluations", "seconds"] {
        assert!(s[key].is_number(), "missing {key}");
    }
    assert_eq!(s["matrix"].as_array().unwrap().len(), 3);
    let fitted = s["cost_fitted"].as_f64().unwrap();

    // The model file reads back exactly: eval on the training runs gives the same Eq. 6 cost.
    let out = omnical(&["eval", "--model", "fit.toml", "sim/train", "--json"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(e["cost"].as_f64().unwrap(), fitted);
    assert_eq!(e["runs"].as_array().unwrap().len(), 36);

    // The same simulation written as CSV gives the same costs as the MCAP bags.
    let out = omnical(
        &["simulate", "--out", "csv", "--format", "csv", "--runs-per-command", "1", "--duration", "4", "--seed", "3"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let cost_of = |path: &str| {
        let out = omnical(&["eval", "--model", "fit.toml", path, "--json"], dir.path());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()["cost"].as_f64().unwrap()
    };
    let (mcap, csv) = (cost_of("sim/validation"), cost_of("csv/validation"));
    assert!((mcap - csv).abs() <= 1e-12 * csv, "MCAP {mcap} vs CSV {csv}");
}

#[test]
fn bad_input_names_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.csv"), "t_s,wheel_a_rad_s,x_m,y_m,theta_rad\n0,1,0,0,0\n0.01,abc,,,\n")
        .unwrap();
    let out = omnical(&["eval", "bad.csv"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim(),
        "error: bad.csv: line 3, column wheel_a_rad_s: \"abc\" is not a number"
    );

    let out = omnical(&["eval", "missing.csv"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).starts_with("error: missing.csv: No such file"));

    std::fs::write(dir.path().join("m.toml"), "format = \"omnical-model/1\"\nkinematics = \"ik\"\n").unwrap();
    std::fs::write(
        dir.path().join("ok.csv"),
        "t_s,wheel_a_rad_s,wheel_b_rad_s,wheel_c_rad_s,x_m,y_m,theta_rad\n0,0,0,0,0,0,0\n1,0,0,0,0,0,0\n",
    )
    .unwrap();
    let out = omnical(&["eval", "--model", "m.toml", "ok.csv"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("m.toml"), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn design_model_on_real_optiodom_runs() {
    let data = shared_data("omni3");
    let dir = tempfile::tempdir().unwrap();
    let set = data.join("221220201934");
    let out = omnical(&["eval", "--model", "design", set.to_str().unwrap(), "--json"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let runs = e["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 11);
    let cost = e["cost"].as_f64().unwrap();
    // Measured: 0.1856 (Eq. 6 over the 11 runs of this set); the robot's position errors stay < 0.5 m.
    assert!((cost - 0.1856).abs() < 0.001, "cost {cost}");
    for r in runs {
        assert!(r["dx_m"].as_f64().unwrap().hypot(r["dy_m"].as_f64().unwrap()) < 0.5);
    }
    // Training lowers the cost.
    let out = omnical(&["train", set.to_str().unwrap(), "--json"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(s["cost_fitted"].as_f64().unwrap() < 0.5 * s["cost_design"].as_f64().unwrap());
}

#[test]
fn plan_proposes_runs_that_excite_every_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let out = omnical(
        &["plan", "--robot", "apr02", "--effect", "wheel_asymmetry", "--runs", "8", "--out", "plan.csv", "--json"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let plan = &v["plan"];
    assert_eq!(plan["total_runs"].as_u64(), Some(8));
    let params = plan["expected"]["params"].as_array().unwrap();
    assert_eq!(params.len(), 12, "9 matrix entries + 3 asymmetries");
    for p in params {
        let se = p["std_error"].as_f64().unwrap_or_else(|| panic!("{} undetermined", p["name"]));
        let scale = p["scale"].as_f64().unwrap();
        assert!(se > 0.0 && se < 0.01 * scale, "{}: ±{se} of scale {scale}", p["name"]);
    }
    assert!(plan["expected"]["weak"].as_array().unwrap().is_empty());
    // Wheel asymmetry needs every wheel turning both ways: the pick has commands in opposite directions.
    let csv = std::fs::read_to_string(dir.path().join("plan.csv")).unwrap();
    assert!(csv.starts_with("v_m_s,alpha_deg,omega_rad_s,repetitions\n"), "{csv}");
    assert_eq!(csv.lines().count(), 9, "{csv}");
    // The flower set is reported beside it, with 36 runs.
    assert_eq!(v["flower"]["total_runs"].as_u64(), Some(36));

    let out = omnical(&["plan", "--robot", "apr02", "--runs", "0"], dir.path());
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("at least one run"));
}

/// The paper's end-pose objective on the OptiOdom square runs leaves directions unconstrained: train
/// warns and holds them; the path objective constrains all nine entries.
#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn square_runs_warn_under_the_end_pose_objective() {
    let data = shared_data("omni3");
    let dir = tempfile::tempdir().unwrap();
    let train = data.join("221220201934");
    let train = train.to_str().unwrap();
    let out = omnical(&["train", train, "--objective", "end-pose", "--out", "end.toml"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // Warnings and notes are diagnostics: on stderr, the fit on stdout (issue 30).
    let (text, err) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    // Two directions along the sideways wheel pattern (±59.8 %, ±66.3 % of scale), held.
    assert_eq!(err.matches("warning: ").count(), 2, "{err}");
    assert!(err.contains("note: 2 direction(s) held"), "{err}");
    assert!(err.contains("fit the path objective"), "{err}");
    assert!(err.contains("held at the start values"), "{err}");
    assert!(!text.contains("warning") && !text.contains("note:"), "{text}");
    assert!(text.contains("identifiability: condition number"), "{text}");
    let out = omnical(&["train", train, "--json"], dir.path());
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(s["warnings"].as_array().unwrap().is_empty(), "{}", s["warnings"]);
    assert_eq!(s["identifiability"]["covariance_kind"], "per_run");
    // The model file keeps the fit's identifiability (TOML has no null: undetermined errors are dropped).
    let toml = std::fs::read_to_string(dir.path().join("end.toml")).unwrap();
    assert!(toml.contains("condition_number"), "{toml}");
    // The paper's fixed 10 ms step on 40 ms runs is refused (exit 1) before fitting, and says why;
    // --force fits anyway and still says so.
    let out = omnical(&["train", train, "--preset", "paper", "--json"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("sampled every 40 ms") && err.contains("factor 0.25"), "{err}");
    let out = omnical(&["train", train, "--preset", "paper", "--json", "--force"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("sampled every 40 ms") && err.contains("factor 0.25"), "{err}");
}

/// `omnical eval … | head -1`: the reader closes the pipe before omnical has written; omnical must end
/// quietly (exit 0, as for any closed pipe) instead of panicking with "failed printing to stdout".
#[test]
fn a_closed_stdout_pipe_ends_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let sim = ["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "2", "--seed", "5", "-q"];
    assert!(omnical(&sim, dir.path()).status.success());
    for args in [&["eval", "--model", "design", "sim/validation"][..], &["eval", "--model", "design", "sim/train"]] {
        let mut child = omnical_command(args, dir.path())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // the reader is gone before the first line is written
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{stderr}");
        assert!(!stderr.contains("panicked") && !stderr.contains("Broken pipe"), "{stderr}");
    }
}

/// Issue 44, item 1: `--force` never deletes or overwrites what a command reads. A result folder that holds,
/// or lies inside, any input is refused before any work, naming both paths, with or without `--force`.
#[test]
fn force_never_replaces_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let sim = ["simulate", "--out", "data", "--runs-per-command", "1", "--duration", "2", "--seed", "3"];
    let out = omnical(&sim, dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let listing = |p: &str| {
        let mut v: Vec<String> = std::fs::read_dir(dir.path().join(p))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let before = listing("data/train");
    let refused = |args: &[&str], expected: &str| {
        for force in [false, true] {
            let mut args = args.to_vec();
            if force {
                args.push("--force");
            }
            let out = omnical(&args, dir.path());
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains(expected), "{args:?}: {err}");
            assert!(err.contains("(--force never replaces an input)"), "{err}");
        }
    };
    // export --tum and --mcap into the folder of the recording being exported, or its parent.
    let run = "data/train/00-r0.mcap";
    refused(
        &["export", "--model", "design", run, "--tum", "data/train"],
        "error: --tum data/train: this folder holds the data data/train/00-r0.mcap, which this command reads",
    );
    refused(
        &["export", "--model", "design", "data/train", "--mcap", "data"],
        "--mcap data: this folder holds the data data/train",
    );
    // An export inside the data folder would be read back as data.
    refused(
        &["export", "--model", "design", "data/train", "--tum", "data/train/tum"],
        "this folder is inside the data data/train",
    );
    // The model file read.
    std::fs::create_dir(dir.path().join("models")).unwrap();
    std::fs::copy(dir.path().join("data/truth.json"), dir.path().join("models/keep.json")).unwrap();
    let out = omnical(&["train", "data/train", "--out", "models/fit.toml"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    refused(
        &["export", "--model", "models/fit.toml", run, "--tum", "models"],
        "this folder holds --model models/fit.toml",
    );
    // simulate --out over its own --robot and --commands.
    std::fs::create_dir(dir.path().join("setup")).unwrap();
    std::fs::copy(dir.path().join("data/train/robot.toml"), dir.path().join("setup/robot.toml")).unwrap();
    std::fs::write(dir.path().join("setup/cmds.csv"), "v_m_s,alpha_deg,omega_rad_s,repetitions\n0.2,0,0,1\n").unwrap();
    refused(
        &["simulate", "--out", "setup", "--robot", "setup/robot.toml", "--duration", "2"],
        "--out setup: this folder holds --robot setup/robot.toml",
    );
    refused(
        &["simulate", "--out", "setup", "--commands", "setup/cmds.csv", "--duration", "2"],
        "--out setup: this folder holds --commands setup/cmds.csv",
    );
    // demo --out over its --robot.
    refused(&["demo", "--out", "setup", "--robot", "setup/robot.toml"], "this folder holds --robot setup/robot.toml");
    // The project file the defaults came from.
    std::fs::write(dir.path().join("setup/omnical.toml"), "seed = 5\n").unwrap();
    refused(
        &["--config", "setup/omnical.toml", "simulate", "--out", "setup", "--duration", "2"],
        "--out setup: this folder holds the project file setup/omnical.toml",
    );
    // Nothing was touched.
    assert_eq!(listing("data/train"), before);
    assert_eq!(listing("setup"), ["cmds.csv", "omnical.toml", "robot.toml"]);
    assert_eq!(listing("models"), ["fit.toml", "keep.json"]);
    // A folder apart from the inputs is still replaced with --force.
    let out = omnical(&["export", "--model", "design", run, "--tum", "models", "--force"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}
