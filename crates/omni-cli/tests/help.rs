//! `omnical --help` and the subcommands' help, read as a new user would, and the `--validate` spelling
//! (issue 19): the real binary.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::process::Output;
use support::{ok, omnical, omnical_command};

/// `omnical ARGS` in a fresh empty folder; its output, whatever its exit status.
fn in_empty_dir(args: &[&str]) -> Output {
    omnical(args, tempfile::tempdir().unwrap().path())
}

/// `omnical ARGS` in a fresh empty folder, which must succeed: its stdout (the help text).
fn help(args: &[&str]) -> String {
    ok(args, tempfile::tempdir().unwrap().path())
}

const SUBCOMMANDS: [&str; 9] = ["simulate", "eval", "train", "diagnose", "report", "export", "plan", "init", "demo"];
/// The subcommands that read runs (and take the data options).
const READING_RUNS: [&str; 6] = ["eval", "train", "diagnose", "report", "export", "plan"];
const EFFECT_IDS: &str = "sensor_offset, sensor_offset_yaw, time_offset, wheel_asymmetry, speed_scale, rotation_slip, turn_scrub, \
                          accel_slip, backlash, wheel_eccentricity, sample_timing";

#[test]
fn top_of_the_help_describes_the_tool() {
    for flag in ["-h", "--help"] {
        let text = help(&[flag]);
        let first = text.lines().next().unwrap().trim_end_matches('.');
        assert_eq!(
            first, "Calibrate a wheeled robot's odometry from recorded runs, and find out why the model still misses",
            "{flag}"
        );
        assert!(!text.contains("omnical datasets (MCAP, CSV)"), "{text}");
    }
    let long = help(&["--help"]);
    assert!(long.contains("ground-truth pose"), "{long}");
    assert!(long.contains("omnical demo"), "{long}");
}

#[test]
fn help_has_no_markdown_escapes_and_units_in_parentheses() {
    for cmd in SUBCOMMANDS {
        let text = help(&[cmd, "--help"]);
        assert!(!text.contains('\\'), "{cmd}: {text}");
        for unit in ["s", "m", "rad", "Hz", "MiB", "m/s", "rad/s", "m/rad"] {
            for end in [" ", "\n", "."] {
                assert!(!text.contains(&format!(". {unit}{end}")), "{cmd}: '. {unit}' in\n{text}");
            }
        }
    }
    assert!(help(&["simulate", "--help"]).contains("Duration of each command (s)\n"));
    let plan = help(&["plan", "--help"]);
    for line in ["Translation speed of the commands (m/s)", "Ground-truth rate (Hz)", "heading noise (rad)"] {
        assert!(plan.contains(line), "{line}:\n{plan}");
    }
    assert!(help(&["eval", "--help"]).contains("at least this long (s)"));
    assert!(help(&["train", "--help"]).contains("Per-wheel radius, distance from the centre and mounting angle"));
}

#[test]
fn data_options_have_their_own_heading_in_every_command_that_reads_runs() {
    for cmd in READING_RUNS {
        let text = help(&[cmd, "--help"]);
        let (own, data) = text.split_once("\nData options:\n").unwrap_or_else(|| panic!("{cmd}:\n{text}"));
        for flag in ["--robot <", "--joints <", "--gt-topic <", "--split <", "--skip-invalid\n", "--max-file-mb <"] {
            assert!(data.contains(flag) && !own.contains(flag), "{cmd}: {flag} outside Data options:\n{text}");
        }
        assert!(own.contains("--help"), "{cmd}: {text}");
    }
}

#[test]
fn effect_options_list_the_effect_ids() {
    for (cmd, flag) in [
        ("train", "--effect"),
        ("plan", "--effect"),
        ("simulate", "--effect"),
        ("diagnose", "--candidates"),
        ("demo", "--hidden"),
    ] {
        let text = help(&[cmd, "--help"]);
        let at = text.find(&format!("{flag} ")).unwrap_or_else(|| panic!("{cmd} {flag}:\n{text}"));
        let joined = text[at..].split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(joined.contains(&format!("Effect ids: {EFFECT_IDS}")), "{cmd} {flag}:\n{text}");
        // The explorer's learned corrections are effects too (`omnical explore` finds them).
        let learned = "learned:wheel, learned:body, learned:world, learned:time, learned:ground_truth.";
        assert!(joined.contains(&format!("sample_timing, world_drift, {learned}")), "{cmd} {flag}:\n{joined}");
    }
}

#[test]
fn validate_takes_one_path_and_repeats() {
    for cmd in ["diagnose", "report"] {
        let text = help(&[cmd, "--help"]);
        assert!(text.contains("--validate <PATH>"), "{text}");
        assert!(text.contains("--validate A --validate B"), "{text}");
    }
    // The natural spelling works: the path after --validate is held out, the next one is the training runs.
    let out = in_empty_dir(&["diagnose", "--model", "design", "--validate", "missing-val", "missing-train"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("missing-train"), "the training runs are read first: {err}");
    assert!(!err.contains("required arguments"), "{err}");
    // Runs missing after --validate: clap's error, then the spelling that works.
    for cmd in ["diagnose", "report"] {
        let out = in_empty_dir(&[cmd, "--model", "fit.toml", "--validate", "sim/validation"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("the following required arguments were not provided"), "{err}");
        let tip = format!(
            "tip: --validate takes one path (repeat it for more) and the training runs come without a flag: omnical \
             {cmd} --model MODEL TRAIN_RUNS... --validate HELD_OUT [--validate HELD_OUT]..."
        );
        assert!(err.contains(&tip), "{err}");
    }
    // Without --validate the error has no tip.
    let out = in_empty_dir(&["diagnose", "--model", "fit.toml"]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("tip: --validate"));
}

#[test]
fn validate_parses_one_path_per_flag() {
    use clap::Parser;
    use omni_cli::cli::{Cli, Command};
    let cli = Cli::try_parse_from(["omnical", "diagnose", "--model", "m", "--validate", "v1", "--validate", "v2", "t"])
        .unwrap();
    let Command::Diagnose(d) = cli.command else { panic!("diagnose") };
    assert_eq!((d.validate.len(), d.runs.len()), (2, 1));
    assert_eq!((d.validate[1].to_str(), d.runs[0].to_str()), (Some("v2"), Some("t")));
    let cli = Cli::try_parse_from(["omnical", "report", "--model", "m", "t1", "t2", "--validate", "v"]).unwrap();
    let Command::Report(r) = cli.command else { panic!("report") };
    assert_eq!((r.validate.len(), r.runs.len()), (1, 2));
}

#[test]
fn fleet_is_the_python_wheels_and_the_native_binary_says_so() {
    let top = help(&["--help"]);
    assert!(top.contains("  fleet ") && top.contains("omnical[fleet]"), "{top}");
    for args in [&["fleet", "robots/", "--out", "out"][..], &["simulate", "--fleet", "3", "--out", "out"][..]] {
        let out = in_empty_dir(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        let what = if args[0] == "fleet" { "omnical fleet" } else { "omnical simulate --fleet" };
        assert!(
            err.starts_with(&format!(
                "error: {what} runs on Dask from the Python wheel: `pip install \"omnical[fleet]\"`"
            )),
            "{args:?}: {err}"
        );
    }
}

/// Every subcommand's name, from the parser itself.
fn all_subcommands() -> Vec<String> {
    use clap::CommandFactory;
    omni_cli::cli::Cli::command().get_subcommands().map(|s| s.get_name().to_string()).collect()
}

#[test]
fn completions_know_every_subcommand() {
    let names = all_subcommands();
    assert!(names.len() >= 13 && names.iter().any(|n| n == "completions") && names.iter().any(|n| n == "man"));
    for (shell, marker) in
        [("bash", "complete -F _omnical"), ("zsh", "#compdef omnical"), ("fish", "complete -c omnical")]
    {
        let script = help(&["completions", shell]);
        assert!(script.contains(marker), "{shell}: {marker} missing");
        for name in &names {
            assert!(script.contains(name.as_str()), "{shell}: no {name}");
        }
        // Options of a subcommand and the global -v are completed too.
        assert!(script.contains("validate") && script.contains("verbose") && script.contains("gt-topic"), "{shell}");
    }
    let out = in_empty_dir(&["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("[possible values: bash, elvish, fish, powershell, zsh]"));
}

#[test]
fn man_pages_cover_every_subcommand() {
    let top = help(&["man"]);
    assert!(top.contains(".TH omnical 1"), "{top}");
    assert!(top.contains("Calibrate a wheeled robot"), "{top}");
    let listed = top.split_once(".SH SUBCOMMANDS").unwrap().1;
    for name in all_subcommands() {
        assert!(listed.contains(&format!("omnical\\-{}", name.replace('-', "\\-"))), "{name} not listed:\n{listed}");
    }
    let dir = tempfile::tempdir().unwrap();
    let out = omnical_command(["man", "--out", "pages"], dir.path()).output();
    assert!(out.unwrap().status.success());
    let mut files: Vec<String> = std::fs::read_dir(dir.path().join("pages"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    files.sort();
    let mut want: Vec<String> = all_subcommands().iter().map(|n| format!("omnical-{n}.1")).collect();
    want.push("omnical.1".into());
    want.sort();
    assert_eq!(files, want);
    let train = std::fs::read_to_string(dir.path().join("pages/omnical-train.1")).unwrap();
    assert!(train.contains(".TH omnical-train 1") && train.contains("\\-\\-preset"), "{train}");
    assert_eq!(std::fs::read_to_string(dir.path().join("pages/omnical.1")).unwrap(), top);
}

#[test]
fn global_options_have_their_own_heading_and_the_top_help_guides_a_new_user() {
    for cmd in all_subcommands() {
        let text = help(&[&cmd, "--help"]);
        let (own, global) = text.split_once("\nGlobal options:\n").unwrap_or_else(|| panic!("{cmd}:\n{text}"));
        for flag in ["--threads <THREADS>", "-q, --quiet", "-v, --verbose", "--config <FILE>"] {
            assert!(global.contains(flag) && !own.contains(flag), "{cmd}: {flag} outside Global options:\n{text}");
        }
    }
    let top = help(&["--help"]);
    for words in ["`omnical config` shows the ones in force", "(`-q` fewer, `-v` more)", "`omnical completions SHELL`"]
    {
        assert!(top.contains(words), "{words}:\n{top}");
    }
    // The one-liners say what a command does without the paper at hand.
    let short = help(&["-h"]);
    for (cmd, words) in [
        ("simulate", "to try every command without a robot"),
        ("eval", "how far its odometry ends from the ground truth (the mean end-pose error"),
        ("train", "so that its odometry follows the ground truth; writes the fitted model"),
        ("config", "each with where it came from"),
        ("completions", "shell completion script"),
        ("man", "manual page"),
    ] {
        let line = short.lines().find(|l| l.trim_start().starts_with(&format!("{cmd} "))).unwrap();
        assert!(line.contains(words), "{cmd}: {line}");
    }
    let train = help(&["train", "--help"]);
    assert!(train.contains("Training recipe: search method, objective and limits"), "{train}");
    assert!(train.contains("the same seed gives the same model, whatever --threads"), "{train}");
}

#[test]
fn plan_robot_from_takes_one_path_and_repeats() {
    let text = help(&["plan", "--help"]);
    assert!(text.contains("--robot-from <RUNS>"), "{text}");
    assert!(text.contains("--robot-from A --robot-from B"), "{text}");
    // One path per flag: both flags' paths are read (the first missing one is named).
    let out = in_empty_dir(&["plan", "--robot-from", "missing-a", "--robot-from", "missing-b"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("missing-a"), "{err}");
    // The old spelling, several paths after one flag: clap names the stray path, then the spelling that works.
    let out = in_empty_dir(&["plan", "--robot-from", "runs-a", "runs-b"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("unexpected argument 'runs-b' found"), "{err}");
    assert!(
        err.contains(
            "tip: --robot-from takes one path (repeat it for more): omnical plan --robot-from RUNS [--robot-from RUNS]..."
        ),
        "{err}"
    );
    // Other stray arguments get no such tip.
    let out = in_empty_dir(&["plan", "stray"]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("tip: --robot-from"));
}

/// The old `--validate V1 V2 TRAIN` spelling reads V2 as training runs: a held-out run that is also a
/// training run is an error, and a training path named like a held-out set a warning, both with the
/// spelling that works.
#[test]
fn validate_old_spelling_is_caught() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| omnical(args, dir.path());
    let sim = ["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "2", "--seed", "5", "-q"];
    assert!(run(&sim).status.success());
    // A second copy of the validation set, as a user with two held-out folders would have.
    std::fs::create_dir(dir.path().join("sim/val2")).unwrap();
    for e in std::fs::read_dir(dir.path().join("sim/validation")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, dir.path().join("sim/val2").join(p.file_name().unwrap())).unwrap();
    }
    let spelling = "--validate takes one path (repeat it for more) and the training runs come without a flag: \
                    omnical diagnose --model MODEL TRAIN_RUNS... --validate HELD_OUT [--validate HELD_OUT]...";
    let out = run(&["diagnose", "--model", "design", "--validate", "sim/validation", "sim/val2", "sim/train"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "warning: sim/val2 is read as training runs although named like a held-out set; {spelling}"
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "error: held-out run 00-r0 is the same recording as training run 00-r0: a model cannot be judged on \
             runs it was fitted on. {spelling}"
        )),
        "{err}"
    );
    // The same folder on both sides, whatever its name.
    let out = run(&["report", "--model", "design", "sim/train", "--validate", "sim/train", "--no-diagnose"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("held-out run 00-r0 is the same recording as training run 00-r0"), "{err}");
    assert!(!err.contains("warning:"), "{err}");
    // The right spelling passes both checks quietly.
    let out = run(&["report", "--model", "design", "sim/train", "--validate", "sim/validation", "--no-diagnose", "-q"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("warning:") && !err.contains("same recording"), "{err}");
}

/// `export --controller` is a choice table: each controller listed with its line, the package names taken
/// as they are and the short forms as aliases; anything else refused with the list.
#[test]
fn export_controller_lists_each_choice() {
    let text = help(&["export", "--help"]);
    for line in [
        "diff_drive_controller:       Two wheels (or two sides of wheels): wheel separation and left/right radii",
        "mecanum_drive_controller:    Four mecanum wheels, rollers at ±45°: wheel radius and lx + ly",
        "omni_wheel_drive_controller: Three or more omni wheels equally spaced on a circle",
    ] {
        assert!(text.contains(line), "{line}\n{text}");
    }
    use clap::Parser;
    use omni_cli::cli::{Cli, Command};
    use omni_cli::controller::ControllerKind;
    for (given, want) in [
        ("omni_wheel_drive_controller", ControllerKind::OmniWheelDrive),
        ("mecanum", ControllerKind::MecanumDrive),
        ("diff-drive-controller", ControllerKind::DiffDrive),
    ] {
        let cli = Cli::try_parse_from(["omnical", "export", "--model", "m", "r", "--controller", given]).unwrap();
        let Command::Export(e) = cli.command else { panic!("export") };
        assert_eq!(e.controller, Some(want), "{given}");
    }
    let out = in_empty_dir(&["export", "--model", "m", "r", "--controller", "ackermann"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("[possible values: diff_drive_controller, mecanum_drive_controller, omni_wheel_drive_controller]"),
        "{err}"
    );
}
