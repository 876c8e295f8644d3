//! `--json` through the real binary: every command that produces results takes it (checked against the
//! parser's list of subcommands, so a new command cannot forget it), prints one JSON document on stdout
//! and nothing else, with `schema_version` 1 and its name as `command`, and its numbers are the ones the
//! text output prints.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use clap::CommandFactory;
use omni_cli::cli::Cli;
use omni_cli::cmd::WITHOUT_RESULTS;
use serde_json::Value;
use std::path::Path;
use support::{apr02_wheel_urdf, stdout, succeeded_on_two_threads};

/// `omnical --threads 2 -q ARGS` in `dir`, which must succeed: its stdout.
fn text(args: &[&str], dir: &Path) -> String {
    stdout(&succeeded_on_two_threads(args, dir))
}

/// The command's `--json` output: the whole of stdout is one JSON object with `schema_version` 1 and
/// `command` = the subcommand's name.
fn json(args: &[&str], dir: &Path) -> Value {
    let out = succeeded_on_two_threads(&[args, &["--json"]].concat(), dir);
    let v: Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{args:?} --json: stdout is not one JSON document ({e}):\n{}", stdout(&out)));
    assert_eq!(v["schema_version"], 1, "{args:?}");
    assert_eq!(v["command"], args[0], "{args:?}");
    v
}

/// The number after `key` in `text` (the first occurrence).
fn number_after(text: &str, key: &str) -> f64 {
    let rest = &text[text.find(key).unwrap_or_else(|| panic!("no {key:?} in:\n{text}")) + key.len()..];
    let word = rest.split_whitespace().next().unwrap();
    word.trim_end_matches([',', ';', ')']).parse().unwrap_or_else(|e| panic!("{key:?} {word:?}: {e}"))
}

/// The numbers on the line of `text` that starts with `label`.
fn numbers_on(text: &str, label: &str) -> Vec<f64> {
    let line = text.lines().find(|l| l.starts_with(label)).unwrap_or_else(|| panic!("no {label:?} line in:\n{text}"));
    line.split_whitespace().filter_map(|w| w.parse().ok()).collect()
}

/// `value` printed with `decimals` decimals, as the text output prints it.
fn printed(value: &Value, decimals: usize) -> f64 {
    format!("{:.*}", decimals, value.as_f64().unwrap_or_else(|| panic!("not a number: {value}"))).parse().unwrap()
}

#[test]
fn every_command_with_results_takes_json_and_no_other_does() {
    let cli = Cli::command();
    let names: Vec<&str> = cli.get_subcommands().map(|c| c.get_name()).collect();
    for name in WITHOUT_RESULTS {
        assert!(names.contains(name), "WITHOUT_RESULTS names {name}, which is no subcommand of {names:?}");
    }
    for sub in cli.get_subcommands() {
        let name = sub.get_name();
        let json = sub.get_arguments().find(|a| a.get_id() == "json");
        if WITHOUT_RESULTS.contains(&name) {
            assert!(json.is_none(), "{name} is listed in cmd::WITHOUT_RESULTS but takes --json");
        } else {
            let json = json.unwrap_or_else(|| {
                panic!(
                    "`omnical {name}` has no --json: flatten cmd::OutputArgs into its Args (docs/json.md), or list \
                     it in cmd::WITHOUT_RESULTS if it produces no results"
                )
            });
            assert_eq!(json.get_long(), Some("json"), "{name}");
            assert!(json.get_help().unwrap().to_string().contains("docs/json.md"), "{name}: the shared OutputArgs");
        }
    }
}

/// A three-wheel omni base like APR-02 with the simulator's joint names (for `init`).
fn omni3_urdf() -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"omni3\">\n<link name=\"base_link\"/>\n{}{}{}</robot>\n",
        apr02_wheel_urdf("wheel_a", 60.0),
        apr02_wheel_urdf("wheel_b", 180.0),
        apr02_wheel_urdf("wheel_c", 300.0)
    )
}

/// long: one simulated set, every command in turn (each needs the files of the ones before).
#[test]
fn every_json_document_is_versioned_and_says_what_the_text_says() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sim = ["simulate", "--runs-per-command", "1", "--duration", "4", "--seed", "3", "--effect", "time_offset=0.04"];
    let s = json(&[&sim[..], &["--out", "sim"]].concat(), d);
    let t = text(&[&sim[..], &["--out", "sim2"]].concat(), d);
    assert_eq!(s["splits"]["train"]["runs"], 36);
    assert_eq!(s["splits"]["train"]["files"].as_array().unwrap().len(), 36);
    assert_eq!(s["splits"]["validation"]["seed"], 4);
    assert_eq!(s["format"], "mcap");
    assert!(d.join(s["truth_json"].as_str().unwrap()).is_file());
    assert!(d.join(s["splits"]["train"]["files"][0].as_str().unwrap()).is_file());
    assert_eq!(printed(&s["splits"]["train"]["design_end_pose"], 4), number_after(&t, "design cost "));

    let e = json(&["eval", "sim/validation"], d);
    let t = text(&["eval", "sim/validation"], d);
    assert_eq!(printed(&e["cost"], 5), number_after(&t, "cost (Eq. 6) "));
    assert_eq!(printed(&e["path_cost"], 5), number_after(&t, "path RMS "));
    assert_eq!(printed(&e["end_position_error_m"]["mean"], 4), number_after(&t, "position m"));
    let heading_deg = e["end_heading_error_rad"]["max"].as_f64().unwrap().to_degrees();
    assert_eq!(format!("{heading_deg:.4}").parse::<f64>().unwrap(), *numbers_on(&t, "heading deg").last().unwrap());
    assert_eq!(e["runs"].as_array().unwrap().len(), 36);
    assert!(e["runs"][0].get("pos_err_m").is_some(), "{}", e["runs"][0]);
    // 4 s runs are 0.8 m long: 0.5 m windows.
    let e = json(&["eval", "sim/validation", "--rpe-delta", "0.5m"], d);
    let t = text(&["eval", "sim/validation", "--rpe-delta", "0.5m"], d);
    assert_eq!(e["rpe"]["pairs"], 36);
    assert_eq!(printed(&e["rpe"]["translation_m"]["rmse"], 4), numbers_on(&t, "translation m")[2]);
    assert_eq!(printed(&e["rpe"]["drift_pct"]["mean"], 4), numbers_on(&t, "drift % of distance")[0]);
    assert_eq!(
        e["rpe"]["pairs"].as_u64(),
        e["runs"].as_array().unwrap().iter().map(|r| r["rpe"]["pairs"].as_u64()).sum()
    );

    let tr = json(&["train", "sim/train", "--out", "fit.toml"], d);
    let t = text(&["train", "sim/train"], d);
    assert_eq!(printed(&tr["cost_fitted"], 5), number_after(&t, "fitted "));
    assert_eq!(tr["out"], "fit.toml");
    assert!(d.join("fit.toml").is_file());
    let model_file = std::fs::read_to_string(d.join("fit.toml")).unwrap();
    assert!(!model_file.contains("schema_version"), "the model file's [fit] table is the fit, not the document");

    // A geometry fit prints its wheel angles in degrees (radians in parentheses); JSON keeps radians.
    let geometry = ["train", "sim/train", "--model", "geometry"];
    let (g, t) = (json(&geometry, d), text(&geometry, d));
    let delta_a = g["params"].as_array().unwrap().iter().find(|p| p["name"] == "delta_a").unwrap();
    assert_eq!(delta_a["unit"], "rad");
    let rad = delta_a["value"].as_f64().unwrap();
    assert!((rad.to_degrees() - 60.0).abs() < 1.0, "delta_a {rad} rad: APR-02's first wheel is at 60°");
    let line = t.lines().find(|l| l.trim_start().starts_with("delta_a ")).unwrap_or_else(|| panic!("{t}"));
    assert_eq!(
        line.split_whitespace().collect::<Vec<_>>(),
        ["delta_a".to_string(), format!("{:.4}°", rad.to_degrees()), format!("({rad:.6}"), "rad)".to_string()]
    );
    assert!(
        t.contains(&format!(
            "delta_a ±{:.2e}° (",
            g["identifiability"]["params"][6]["std_error"].as_f64().unwrap().to_degrees()
        )),
        "{t}"
    );

    let diag = ["diagnose", "--model", "fit.toml", "sim/train", "--validate", "sim/validation"];
    let g = json(&diag, d);
    assert_eq!(g["verdict"], "time_offset", "{}", g["verdict_text"]);
    assert_eq!(g["out"], Value::Null);
    let x = json(&["explore", "--model", "fit.toml", "sim/train", "--validate", "sim/validation"], d);
    assert!(x["families"].as_array().is_some_and(|f| !f.is_empty()), "{x}");

    let p = json(&["plan", "--robot", "apr02", "--runs", "4", "--out", "plan.csv"], d);
    assert_eq!(p["plan"]["runs"].as_array().unwrap().len(), 4);
    assert_eq!(p["out"], "plan.csv");

    let r = json(&["report", "--model", "fit.toml", "sim/train", "--no-diagnose", "--out", "r.html"], d);
    assert_eq!(r["html"], "r.html");
    assert!(d.join("r.html").is_file() && !r["figures"].as_array().unwrap().is_empty());
    assert_eq!(r["models"][1]["label"], "fitted matrix", "{}", r["models"]);

    let x = json(&["export", "--model", "fit.toml", "sim/validation", "--tum", "tum", "--robot-config", "rc"], d);
    let tum = x["tum"]["files"].as_array().unwrap();
    assert_eq!(tum.len(), 3 * 36);
    assert!(tum.iter().all(|f| d.join(f.as_str().unwrap()).is_file()));
    assert_eq!(x["robot_config"]["controller"], "omni_wheel_drive_controller");
    assert!(
        x["robot_config"]["controller_params"]["wheel_radius_m"].as_f64().is_some_and(|r| (r - 0.148).abs() < 0.01)
    );

    std::fs::write(d.join("omni3.urdf"), omni3_urdf()).unwrap();
    let i = json(&["init", "sim/train/00-r0.mcap", "--urdf", "omni3.urdf", "--out", "robot.toml"], d);
    assert_eq!(i["kind"], "omni");
    assert_eq!(i["joints"], serde_json::json!(["wheel_a", "wheel_b", "wheel_c"]));
    assert_eq!(i["out"], "robot.toml");
    let radius = i["description"]["wheels"][0]["radius_m"].as_f64().unwrap();
    assert!((radius - 0.148).abs() < 1e-9, "{radius}");
}

/// The arguments of a printed `omnical …` command line (no quoting needed in these paths).
fn args_of(command: &str) -> Vec<&str> {
    let mut words = command.split_whitespace();
    assert_eq!(words.next(), Some("omnical"), "{command}");
    words.collect()
}

/// `demo --out DIR` keeps its runs and models in DIR and prints the commands that repeat each step on them:
/// the printed `train` command gives the demo's costs, the printed `eval` the held-out Eq. 6 of the model
/// with the effect that the report lists; `--json` lists the same commands and costs.
#[test]
fn demo_out_keeps_the_runs_and_its_commands_repeat_each_step() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let demo = ["demo", "--runs-per-command", "1"];
    let t = text(&[&demo[..], &["--out", "demo"]].concat(), d);
    for f in ["train/00-r0.mcap", "train/robot.toml", "validation/35-r0.mcap", "fitted_matrix.toml", "report.html"] {
        assert!(d.join("demo").join(f).is_file(), "demo/{f} missing");
    }
    let (_, repeat) = t.split_once("== repeat each step by hand on these files:\n").unwrap_or_else(|| panic!("{t}"));
    // The commands, then the demo's last line: the hidden effect and what was found of it.
    let commands: Vec<&str> = repeat.lines().map(str::trim).filter(|l| l.starts_with("omnical ")).collect();
    assert!(
        repeat.lines().last().unwrap().starts_with("hidden time_offset=0.06 → found time_offset.tau_s = "),
        "{repeat}"
    );
    assert_eq!(commands.len(), 5, "{repeat}");
    assert_eq!(commands[0], "omnical simulate --out demo --force --runs-per-command 1 --effect time_offset=0.06");
    assert_eq!(commands[1], "omnical train demo/train --out demo/fitted_matrix.toml");

    let cost_line = |text: &str| text.lines().find(|l| l.starts_with("cost (Eq. 6)  design")).unwrap().to_string();
    let again = text(&args_of(commands[1]), d);
    assert_eq!(cost_line(&again), cost_line(&t));
    let eval = commands.iter().find(|c| c.starts_with("omnical eval ")).unwrap();
    let held_out = numbers_on(&t, "fitted matrix + time_offset");
    assert_eq!(number_after(&text(&args_of(eval), d), "cost (Eq. 6) "), held_out[1]);
    // The printed simulate replaces the demo's folder with the same runs (its --force: the folder is not
    // empty; without it the command would be refused).
    let run_00 = std::fs::read(d.join("demo/train/00-r0.mcap")).unwrap();
    text(&args_of(commands[0]), d);
    assert_eq!(std::fs::read(d.join("demo/train/00-r0.mcap")).unwrap(), run_00);
    assert!(!d.join("demo/report.html").exists(), "replaced whole");

    let j = json(&[&demo[..], &["--out", "demo", "--force"]].concat(), d);
    let listed: Vec<&str> = j["commands"].as_array().unwrap().iter().map(|c| c["command"].as_str().unwrap()).collect();
    assert_eq!(listed, commands);
    assert_eq!(j["diagnosis"]["verdict"], "time_offset");
    assert_eq!(printed(&j["train"]["cost_design"], 5), number_after(&cost_line(&t), "design "));
    assert_eq!(printed(&j["train"]["cost_fitted"], 5), number_after(&cost_line(&t), "fitted "));
}
