//! Project defaults (`omnical.toml`, `--config FILE`) and `omnical config` through the real binary
//! (issue 19): where each value came from, a flag over the file, the file's values reaching `train`, and
//! bad keys and values refused with the file, line and key (exit 2).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::Path;
use support::{json, ok, omnical, refused};

/// `omnical config`'s rows as (key, value, source), split at runs of two or more spaces.
fn rows(text: &str) -> Vec<(String, String, String)> {
    text.lines()
        .skip(1)
        .take_while(|l| !l.is_empty())
        .map(|l| {
            let cells: Vec<&str> = l.split("  ").map(str::trim).filter(|c| !c.is_empty()).collect();
            assert_eq!(cells.len(), 3, "{l}");
            (cells[0].to_string(), cells[1].to_string(), cells[2].to_string())
        })
        .collect()
}

fn row<'a>(rows: &'a [(String, String, String)], key: &str) -> (&'a str, &'a str) {
    let r = rows.iter().find(|r| r.0 == key).unwrap_or_else(|| panic!("no {key} in {rows:?}"));
    (r.1.as_str(), r.2.as_str())
}

fn simulate(dir: &Path) {
    ok(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "2", "--seed", "4", "-q"], dir);
}

const PROJECT: &str = "# omnical.toml\nseed = 5\njoints_topic = \"/wheels\"\nthreads = 1\n\n[simulate]\nseed = 11\n";

#[test]
fn config_shows_where_each_value_came_from() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d);
    // Without a project file: the robot.toml beside the data, with its lines, and defaults.
    let text = ok(&["config", "sim/train"], d);
    let r = rows(&text);
    assert_eq!(row(&r, "robot"), ("sim/train/robot.toml", "found beside the data or in the working directory"));
    assert_eq!(row(&r, "joints"), ("wheel_a, wheel_b, wheel_c", "sim/train/robot.toml:6"));
    assert_eq!(row(&r, "joints_topic"), ("the only JointState topic", "default"));
    assert_eq!(row(&r, "seed"), ("0 (train), 7 (simulate)", "default"));
    assert_eq!(row(&r, "preset"), ("default", "default"));
    assert!(text.contains("\nno project file (omnical.toml in the working directory or --config FILE)"), "{text}");
    // With omnical.toml: its values with their lines; a flag wins over the file.
    std::fs::write(d.join("omnical.toml"), PROJECT).unwrap();
    let r = rows(&ok(&["config", "sim/train", "--joints", "x,y,z"], d));
    assert_eq!(row(&r, "seed"), ("5", "omnical.toml:2"));
    assert_eq!(row(&r, "joints_topic"), ("/wheels", "omnical.toml:3"));
    assert_eq!(row(&r, "threads"), ("1", "omnical.toml:4"));
    assert_eq!(row(&r, "simulate.seed"), ("11", "omnical.toml:7"));
    assert_eq!(row(&r, "joints"), ("x, y, z", "command line"));
    let r = rows(&ok(&["config", "sim/train", "--seed", "8", "--joints-topic", "/js"], d));
    assert_eq!(row(&r, "seed"), ("8", "command line"));
    assert_eq!(row(&r, "joints_topic"), ("/js", "command line"));
    // A robot.toml's topics, with the line.
    let robot = std::fs::read_to_string(d.join("sim/train/robot.toml")).unwrap();
    std::fs::write(d.join("robot.toml"), format!("{robot}\n[topics]\nground_truth = \"/mocap\"\n")).unwrap();
    let line = robot.lines().count() + 3;
    let r = rows(&ok(&["config", "--robot", "robot.toml"], d));
    assert_eq!(row(&r, "gt_topic"), ("/mocap", format!("robot.toml:{line}").as_str()));
    assert_eq!(row(&r, "robot"), ("robot.toml", "command line"));
    // The same rows as JSON.
    let v: serde_json::Value = json(&["config", "--robot", "robot.toml", "--json"], d);
    assert_eq!((v["command"].as_str(), v["schema_version"].as_u64()), (Some("config"), Some(1)));
    assert_eq!(v["project_file"], "omnical.toml");
    let gt = v["settings"].as_array().unwrap().iter().find(|s| s["key"] == "gt_topic").unwrap();
    assert_eq!(
        (gt["value"].as_str(), gt["source"].as_str()),
        (Some("/mocap"), Some(format!("robot.toml:{line}").as_str()))
    );
}

#[test]
fn the_project_file_sets_defaults_and_flags_win() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d);
    let seed_of = |args: &[&str]| -> u64 {
        let base = ["train", "sim/train", "--json", "-q", "--preset", "paper"];
        let v: serde_json::Value = json(&[&base[..], args].concat(), d);
        v["seed"].as_u64().unwrap()
    };
    assert_eq!(seed_of(&[]), 0);
    std::fs::write(d.join("omnical.toml"), "seed = 5\n").unwrap();
    assert_eq!(seed_of(&[]), 5);
    assert_eq!(seed_of(&["--seed", "6"]), 6);
    // A command's own table wins over the top level, for that command only.
    std::fs::write(d.join("omnical.toml"), "seed = 5\n[train]\nseed = 9\n").unwrap();
    assert_eq!(seed_of(&[]), 9);
    // --config FILE elsewhere, its robot path relative to it.
    std::fs::remove_file(d.join("omnical.toml")).unwrap();
    std::fs::create_dir(d.join("proj")).unwrap();
    std::fs::copy(d.join("sim/train/robot.toml"), d.join("proj/r.toml")).unwrap();
    std::fs::write(d.join("proj/p.toml"), "seed = 3\nrobot = \"r.toml\"\n").unwrap();
    assert_eq!(seed_of(&["--config", "proj/p.toml"]), 3);
    let r = rows(&ok(&["config", "--config", "proj/p.toml"], d));
    assert_eq!(row(&r, "robot"), ("proj/r.toml", "proj/p.toml:2"));
    assert_eq!(row(&r, "joints"), ("wheel_a, wheel_b, wheel_c", "proj/r.toml:6"));
}

/// eval's RPE window from the project file (its own table or the top level); the flag wins; a bad window
/// is refused with the file, line and key.
#[test]
fn the_project_file_sets_evals_rpe_window() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d);
    let window = |args: &[&str]| -> (f64, String) {
        let v: serde_json::Value = json(&[&["eval", "sim/validation", "--json"][..], args].concat(), d);
        (v["rpe"]["delta"].as_f64().unwrap(), v["rpe"]["delta_unit"].as_str().unwrap().to_string())
    };
    assert_eq!(window(&[]), (1.0, "m".into()));
    std::fs::write(d.join("omnical.toml"), "[eval]\nrpe_delta = \"0.5s\"\n").unwrap();
    assert_eq!(window(&[]), (0.5, "s".into()));
    assert_eq!(window(&["--rpe-delta", "2m"]), (2.0, "m".into()));
    std::fs::write(d.join("omnical.toml"), "rpe_delta = \"0.25m\"\n").unwrap();
    assert_eq!(window(&[]), (0.25, "m".into()));
    std::fs::write(d.join("omnical.toml"), "seed = 1\nrpe_delta = \"1km\"\n").unwrap();
    assert_eq!(
        refused(&["eval", "sim/validation"], d).lines().next().unwrap(),
        "error: omnical.toml: line 2: rpe_delta: invalid value '1km' for '--rpe-delta <WINDOW>': expected a \
         distance in metres or a time in seconds, as 1m or 2s"
    );
}

#[test]
fn bad_project_files_name_the_file_line_and_key() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let cases = [
        (
            "seed = 5\nsed = 3\n",
            "error: omnical.toml: line 2: sed: unknown key; known keys: threads, robot, joints, joints_topic, \
             gt_topic, gt_parent_frame, gt_child_frame, gt, gt_time_offset, gt_kind, gt_window, gt_mount, gt_mount_start, gt_scans, \
             split, skip_invalid, ticks_per_rev, max_file_mb, preset, seed, objective, every, heading_weight, unexcited, rpe_delta",
        ),
        (
            "preset = \"fast\"\n",
            "error: omnical.toml: line 1: preset: invalid value 'fast' for '--preset <PRESET>' [possible values: \
             paper, default]",
        ),
        ("# x\n\n[eval]\nseed = 3\n", "error: omnical.toml: line 4: eval.seed: `omnical eval` has no --seed"),
        ("seed = [1]\n", "error: omnical.toml: line 1: seed: expected a string, number or boolean, found array"),
        (
            "seed = \n",
            "error: omnical.toml: not TOML: line 1, column 8: string values must be quoted, expected literal string",
        ),
    ];
    for (text, want) in cases {
        std::fs::write(d.join("omnical.toml"), text).unwrap();
        for args in [&["config"][..], &["eval", "--model", "design", "x"]] {
            let got = refused(args, d);
            assert_eq!(got.lines().next().unwrap(), want, "{text:?} {args:?}");
        }
    }
    // Help and version do not read the file.
    assert!(omnical(&["--help"], d).status.success());
    let missing = refused(&["--config", "nope.toml", "eval", "x"], d);
    assert!(missing.starts_with("error: nope.toml: No such file"), "{missing}");
}

/// The error and what follows it (the notes before it and the final newline left out).
fn from_error(stderr: &str) -> String {
    stderr[stderr.find("error:").unwrap_or(0)..].trim_end().to_string()
}

#[test]
fn errors_name_where_a_value_came_from() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d);
    let bag = "sim/train/00-r0.mcap";
    // A topic from omnical.toml is named as the file's key and line, not as the flag it set; the flag on
    // the command line is named as the flag.
    std::fs::write(d.join("omnical.toml"), "seed = 5\n[train]\njoints_topic = \"/js2\"\n").unwrap();
    let e = from_error(&refused(&["train", bag], d));
    assert!(
        e.starts_with(&format!(
            "error: {bag}: joints_topic = \"/js2\" (omnical.toml, line 3): no such topic; topics: "
        )),
        "{e}"
    );
    let e = from_error(&refused(&["train", bag, "--joints-topic", "/js3"], d));
    assert!(e.starts_with(&format!("error: {bag}: --joints-topic /js3: no such topic")), "{e}");
    // A path from omnical.toml that does not exist: the error names it, and a note the key and line.
    std::fs::write(d.join("omnical.toml"), "# project\ngt = \"mocap/take.tum\"\n").unwrap();
    let e = from_error(&refused(&["eval", bag, "--model", "design"], d));
    assert_eq!(
        e,
        "error: mocap/take.tum: No such file or directory (os error 2)\n  note: gt = \"mocap/take.tum\" is set in \
         omnical.toml, line 2"
    );
    std::fs::remove_file(d.join("omnical.toml")).unwrap();
    // A topic from robot.toml is named as its key, file and line.
    let robot = std::fs::read_to_string(d.join("sim/train/robot.toml")).unwrap();
    let line = robot.lines().count() + 3; // after a blank line and the table header
    std::fs::write(d.join("r.toml"), format!("{robot}\n[topics]\nground_truth = \"/vicon\"\n")).unwrap();
    let e = from_error(&refused(&["eval", bag, "--model", "design", "--robot", "r.toml"], d));
    let want =
        format!("error: {bag}: [topics] ground_truth = \"/vicon\" (r.toml, line {line}): no such topic; topics: ");
    assert!(e.starts_with(&want), "{e}");
}

// ---------------------------------------------------------------------------------------------------------
// One declaration per setting (issue 26): `omni_cli::api::settings::SETTINGS` against the clap parser, the
// project file's keys, the `omnical config` rows and Python's signatures (`#[pyo3(signature)]` and
// `_omnical.pyi`). A setting added to one of them and not declared (or declared and missing) fails here.

mod settings_table {
    use clap::CommandFactory;
    use omni_cli::api::settings::{Flag, SETTINGS, Setting, Where};
    use omni_cli::cli::{Cli, Command};
    use std::collections::BTreeSet;

    /// The argument ids of a command that are options (not positional, not clap's own help and version).
    fn option_ids(cmd: &clap::Command) -> BTreeSet<String> {
        cmd.get_arguments()
            .filter(|a| !a.is_positional() && !["help", "version"].contains(&a.get_id().as_str()))
            .map(|a| a.get_id().to_string())
            .collect()
    }

    fn keys(filter: impl Fn(&Setting) -> bool) -> BTreeSet<String> {
        SETTINGS.iter().filter(|s| filter(s)).map(|s| s.key.to_string()).collect()
    }

    #[test]
    fn every_option_of_train_and_config_is_declared_once() {
        let cli = Cli::command();
        let train = cli.find_subcommand("train").unwrap();
        let mut options = option_ids(train);
        options.extend(option_ids(&cli));
        let flags = keys(|s| s.flag == Flag::Train);
        assert_eq!(options, flags, "omnical train's options against SETTINGS");
        // A setting of another command is its option.
        for s in SETTINGS {
            if let Flag::Of(name) = s.flag {
                let sub = cli.find_subcommand(name).unwrap_or_else(|| panic!("{}: no command {name}", s.key));
                assert!(option_ids(sub).contains(s.key), "{}: not an option of omnical {name}", s.key);
            }
        }
        // `omnical config` shows settings: each of its options is one.
        let config = option_ids(cli.find_subcommand("config").unwrap());
        let missing: Vec<_> = config.difference(&flags).collect();
        assert!(missing.is_empty(), "options of omnical config not in SETTINGS: {missing:?}");
        // Every command that reads runs takes the same data options, all declared.
        for sub in cli.get_subcommands() {
            let data: BTreeSet<String> = sub
                .get_arguments()
                .filter(|a| a.get_help_heading() == Some(omni_cli::cmd::DATA_OPTIONS))
                .map(|a| a.get_id().to_string())
                .collect();
            let missing: Vec<_> = data.difference(&flags).collect();
            assert!(missing.is_empty(), "data options of omnical {} not in SETTINGS: {missing:?}", sub.get_name());
        }
        let mut seen = BTreeSet::new();
        for s in SETTINGS {
            assert!(seen.insert(s.key), "{} declared twice", s.key);
        }
    }

    #[test]
    fn the_project_file_takes_the_declared_keys_and_refuses_the_others() {
        // Each project key is an option (the file's value becomes its default).
        for s in SETTINGS.iter().filter(|s| s.project_file == Where::Yes) {
            assert!(!matches!(s.flag, Flag::No(_)), "{}: a project key must be an option", s.key);
        }
        let dir = tempfile::tempdir().unwrap();
        for s in SETTINGS {
            let path = dir.path().join("omnical.toml");
            std::fs::write(&path, format!("{} = \"x\"\n", s.key)).unwrap();
            let parsed = omni_cli::project_file::parse(&std::fs::read_to_string(&path).unwrap(), &path);
            let unknown = matches!(&parsed, Err(e) if e.to_string().contains("unknown key"));
            assert_eq!(unknown, s.project_file != Where::Yes, "{}: {parsed:?}", s.key);
        }
    }

    #[test]
    fn omnical_config_shows_the_declared_rows() {
        let cli = <Cli as clap::Parser>::try_parse_from(["omnical", "config"]).unwrap();
        let Command::Config(a) = cli.command else { panic!("not config") };
        let rows = omni_cli::cmd::config::rows(&a, None, None).unwrap();
        let shown: BTreeSet<String> = rows.iter().map(|r| r.key.clone()).collect();
        assert_eq!(shown, keys(|s| s.config_row == Where::Yes));
    }

    /// The parameters of a Python signature between its parentheses: (name, default), split at the commas
    /// outside brackets and strings; `*` alone and `py` left out, `*paths` named `paths`.
    fn params(list: &str, default_sep: &str) -> Vec<(String, Option<String>)> {
        let (mut depth, mut start, mut out) = (0i32, 0, Vec::new());
        let mut push = |part: &str| {
            let part = part.trim();
            if part.is_empty() || part == "*" {
                return;
            }
            let (head, default) = match part.split_once(default_sep) {
                Some((h, d)) => (h, Some(d.trim().to_string())),
                None => (part, None),
            };
            let name = head.split(':').next().unwrap().trim().trim_start_matches('*').to_string();
            if name != "py" {
                out.push((name, default));
            }
        };
        let mut quoted = false; // inside a string literal: `"0,0,0"`
        for (i, c) in list.char_indices() {
            match c {
                '"' => quoted = !quoted,
                _ if quoted => {}
                '(' | '[' | '{' => depth += 1,
                ')' | ']' | '}' => depth -= 1,
                ',' if depth == 0 => {
                    push(&list[start..i]);
                    start = i + 1;
                }
                _ => {}
            }
        }
        push(&list[start..]);
        out
    }

    fn read(path: &str) -> String {
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)).unwrap()
    }

    /// `#[pyo3(signature = (...))]` of `pub fn NAME(` in `file`.
    fn pyo3_signature(file: &str, name: &str) -> Vec<(String, Option<String>)> {
        let text = read(file);
        let at = text.find(&format!("pub fn {name}(")).unwrap_or_else(|| panic!("no fn {name} in {file}"));
        let start = text[..at].rfind("signature = (").unwrap() + "signature = (".len();
        let end = start + text[start..].find("))]").unwrap();
        params(&text[start..end], "=")
    }

    /// `def NAME(...)` of `_omnical.pyi`.
    fn stub_signature(name: &str) -> Vec<(String, Option<String>)> {
        let text = read("omni-py/python/omnical/_omnical.pyi");
        let start = text.find(&format!("\ndef {name}(")).unwrap() + format!("\ndef {name}(").len();
        let end = start + text[start..].find(") ->").unwrap();
        params(&text[start..end], " = ")
    }

    /// A default as one spelling: Rust's and Python's booleans and empty lists alike, numbers by value.
    fn normal(default: &str) -> String {
        // A Rust default built from the CLI's text (`MountArg::text("0,0,0")`) is that text.
        let d = match default.split_once("::text(") {
            Some((_, rest)) => rest.trim_end_matches(')'),
            None => default,
        };
        let d = d.trim_matches('"');
        match d {
            "false" | "False" => "false".into(),
            "true" | "True" => "true".into(),
            "Vec::new()" | "..." | "None" => "none".into(),
            // A list of numbers (`0,0,0`, Python's `(0.0, 0.0, 0.0)`) by value.
            _ if d.contains(',') => {
                let parts: Vec<String> = d.trim_matches(['(', ')']).split(',').map(|x| normal(x.trim())).collect();
                parts.join(",")
            }
            _ => d.parse::<f64>().map_or_else(|_| d.to_string(), |v| format!("{v}")),
        }
    }

    #[test]
    fn python_keywords_and_defaults_are_the_declared_ones() {
        let mut cli = Cli::command();
        cli.build(); // the implicit defaults (a switch's `false`) are set when built
        // `simulate`'s own keywords (truth, robot, seed, out, …) are Python's spelling of its CLI options
        // (tests/test_mirror.py); its sensors are declared here: `some` (declared ⊆ keywords), not `all`.
        for (function, file, data_args, command, all) in [
            ("load", "omni-py/src/run.rs", "paths", "train", true),
            ("info", "omni-py/src/info.rs", "paths", "info", true),
            ("imu", "omni-py/src/imu.rs", "recordings", "imu", true),
            ("train", "omni-py/src/calibrate.rs", "runs", "train", true),
            ("evaluate", "omni-py/src/evaluate.rs", "runs", "eval", true),
            ("simulate", "omni-py/src/simulate.rs", "truth", "simulate", false),
        ] {
            let sub = cli.find_subcommand(command).unwrap();
            let rust = pyo3_signature(file, function);
            let stub = stub_signature(function);
            let normalised = |s: &[(String, Option<String>)]| -> Vec<(String, String)> {
                s.iter().map(|(n, d)| (n.clone(), d.as_deref().map_or_else(String::new, normal))).collect()
            };
            assert_eq!(normalised(&rust), normalised(&stub), "{function}: #[pyo3(signature)] against _omnical.pyi");
            let keywords: BTreeSet<String> = rust.iter().map(|(n, _)| n.clone()).filter(|n| n != data_args).collect();
            let declared: BTreeSet<String> = SETTINGS
                .iter()
                .flat_map(|s| s.python.ok().into_iter().flatten())
                .filter(|(f, _)| *f == function)
                .map(|(_, k)| k.to_string())
                .collect();
            if all {
                assert_eq!(keywords, declared, "omnical.{function}'s keywords against SETTINGS");
            } else {
                let missing: Vec<_> = declared.difference(&keywords).collect();
                assert!(missing.is_empty(), "omnical.{function} lacks the declared keywords {missing:?}");
            }
            // A keyword that is an option has the option's default.
            for s in SETTINGS.iter().filter(|s| !matches!(s.flag, Flag::No(_))) {
                let Some((_, keyword)) = s.python.ok().into_iter().flatten().find(|(f, _)| *f == function) else {
                    continue;
                };
                let Some((_, Some(py_default))) = rust.iter().find(|(n, _)| n == keyword) else { continue };
                let arg = sub.get_arguments().chain(cli.get_arguments()).find(|a| a.get_id() == s.key).unwrap();
                let clap_default =
                    arg.get_default_values().first().map_or("none".into(), |d| normal(&d.to_string_lossy()));
                assert_eq!(
                    normal(py_default),
                    clap_default,
                    "omnical.{function}({keyword}=) against --{}",
                    s.key.replace('_', "-")
                );
            }
        }
    }

    #[test]
    fn every_simulated_sensor_option_is_declared_for_python() {
        let mut cli = Cli::command();
        cli.build();
        let simulate = cli.find_subcommand("simulate").unwrap();
        let sensors: BTreeSet<String> = simulate
            .get_arguments()
            .filter(|a| matches!(a.get_help_heading(), Some("Simulated lidar" | "Simulated IMU")))
            // The output options, flattened after the IMU's, print under its heading.
            .filter(|a| a.get_id() != "json")
            .map(|a| a.get_id().to_string())
            .collect();
        assert_eq!(sensors.len(), 17, "{sensors:?}");
        assert_eq!(sensors, keys(|s| s.flag == Flag::Of("simulate")), "omnical simulate's sensors against SETTINGS");
    }
}
