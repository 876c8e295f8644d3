//! Diagnostics on stderr through the real binary (issue 19): `-q`/`-v`/`-vv` and `RUST_LOG` change only
//! stderr, never stdout; a note many files raise is one line with a count, once per command (training and
//! held-out runs together); omnical's own simulated bags raise no note.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::Path;
use std::process::Output;
use support::{omnical, omnical_command, stderr, succeeded, test_data};

/// `omnical ARGS` in `dir` with `RUST_LOG=filter`, which must succeed.
fn with_rust_log(args: &[&str], dir: &Path, filter: &str) -> Output {
    let out = omnical_command(args, dir).env("RUST_LOG", filter).output().unwrap();
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    out
}

/// `train/r1..r4.mcap` and `held/h1..h3.mcap`: copies of the committed rosbags bag, whose `/cmd_vel` is a
/// header-less Twist (one note per file).
fn twist_bags(dir: &Path) {
    let bag = test_data("tiny_rosbags.mcap");
    for (sub, names) in [("train", &["r1", "r2", "r3", "r4"][..]), ("held", &["h1", "h2", "h3"])] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
        for n in names {
            std::fs::copy(&bag, dir.join(sub).join(format!("{n}.mcap"))).unwrap();
        }
    }
}

const TWIST_NOTE: &str =
    "note: train/r1.mcap: topic \"/cmd_vel\" (geometry_msgs/msg/Twist) has no header: command times are log times";

#[test]
fn a_note_from_many_files_is_one_line_per_command() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    twist_bags(d);
    let eval = succeeded(&["eval", "--robot", "apr02", "--model", "design", "train"], d);
    let lines: Vec<String> = stderr(&eval).lines().filter(|l| l.contains("has no header")).map(String::from).collect();
    assert_eq!(lines, [format!("{TWIST_NOTE} (and 3 more files)")]);
    // Training and held-out runs are read by one command: one line counting all seven files.
    for cmd in ["diagnose", "report"] {
        let mut args = vec![cmd, "--robot", "apr02", "--model", "design", "train", "--validate", "held"];
        if cmd == "report" {
            args.extend(["--out", "r.html", "--no-diagnose"]);
        }
        // The held-out bags are copies of the training ones, which the held-out check refuses (exit 2)
        // after loading: the notes of the load are printed all the same.
        let out = omnical(&args, d);
        assert_eq!(out.status.code(), Some(2), "{cmd}");
        assert!(stderr(&out).contains("is the same recording as training run"), "{cmd}: {}", stderr(&out));
        let lines: Vec<&str> = std::str::from_utf8(&out.stderr).unwrap().lines().collect();
        let notes: Vec<&&str> = lines.iter().filter(|l| l.contains("has no header")).collect();
        assert_eq!(notes, [&format!("{TWIST_NOTE} (and 6 more files)")], "{cmd}: {lines:?}");
        assert!(!String::from_utf8_lossy(&out.stdout).contains("note:"), "{cmd}: notes go to stderr only");
    }
    // Two files: "1 more file".
    let two = succeeded(&["eval", "--robot", "apr02", "--model", "design", "train/r1.mcap", "train/r2.mcap"], d);
    assert!(stderr(&two).contains(&format!("{TWIST_NOTE} (and 1 more file)\n")), "{}", stderr(&two));
}

#[test]
fn verbosity_changes_stderr_only() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    twist_bags(d);
    let args = |flag: &'static str| {
        let mut a = vec!["eval", "--robot", "apr02", "--model", "design", "--json", "train/r1.mcap", "train/r2.mcap"];
        if !flag.is_empty() {
            a.insert(0, flag);
        }
        a
    };
    let normal = succeeded(&args(""), d);
    let quiet = succeeded(&args("-q"), d);
    let verbose = succeeded(&args("-v"), d);
    let debug = succeeded(&args("-vv"), d);
    for (name, out) in [("-q", &quiet), ("-v", &verbose), ("-vv", &debug)] {
        assert_eq!(out.stdout, normal.stdout, "{name}: stdout differs");
    }
    let e = stderr(&normal);
    assert!(e.contains(TWIST_NOTE) && !e.contains("info:") && !e.contains("debug:"), "{e}");
    assert_eq!(stderr(&quiet), "", "-q hides notes");
    let v = stderr(&verbose);
    for line in [
        "info: robot: apr02 (built in: the paper's APR-02), named by --robot\n",
        "info: read train/r1.mcap: 1 run\n",
        "info: read train/r2.mcap: 1 run\n",
        "info: read 2 runs from train/r1.mcap, train/r2.mcap in ",
        TWIST_NOTE,
        "info: finished in ",
    ] {
        assert!(v.contains(line), "-v lacks {line:?}:\n{v}");
    }
    assert!(!v.contains("debug:"), "{v}");
    let vv = stderr(&debug);
    assert!(vv.contains("debug: run r1: 101 wheel samples over 1.000 s, 21 ground-truth poses\n"), "{vv}");
    assert!(vv.contains("info: read train/r1.mcap: 1 run\n"), "{vv}");
    // RUST_LOG replaces the flags' level; a bad one is said and the flags' level kept.
    let env = with_rust_log(&args(""), d, "debug");
    assert!(stderr(&env).contains("debug: run r2: 101 wheel samples"), "{}", stderr(&env));
    let bad = with_rust_log(&args("-q"), d, "=[{");
    assert!(stderr(&bad).starts_with("warning: RUST_LOG=\"=[{\" is not a filter"), "{}", stderr(&bad));
    assert_eq!(bad.stdout, normal.stdout);
}

#[test]
fn quiet_and_verbose_conflict() {
    let tmp = tempfile::tempdir().unwrap();
    let out = omnical(&["-q", "-v", "eval", "x"], tmp.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("the argument '--quiet' cannot be used with '--verbose...'"));
}

#[test]
fn simulated_bags_need_no_note() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    succeeded(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "2", "-q"], d);
    let out = succeeded(&["diagnose", "--model", "design", "sim/train", "--validate", "sim/validation"], d);
    let e = stderr(&out);
    assert!(!e.contains("note:"), "{e}");
    // The robot.toml beside each set is said once per file, never twice in one command.
    assert_eq!(e.matches("robot: sim/train/robot.toml (found beside the data)\n").count(), 1, "{e}");
}

#[test]
fn the_entry_runs_twice_in_one_process() {
    // The Python wheel's console entry calls this function for every command; the second call changes
    // the level of the subscriber the first installed, and neither fails.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().to_str().unwrap();
    let sim = |out: &str, verbosity: &str| {
        let args = ["omnical", verbosity, "simulate", "--out", out, "--runs-per-command", "1", "--duration", "1"];
        omni_cli::entry::main_with_args(args.iter().map(Into::into))
    };
    assert_eq!(sim(&format!("{d}/a"), "-q"), 0);
    assert_eq!(sim(&format!("{d}/b"), "-vv"), 0);
    assert_eq!(
        std::fs::read(format!("{d}/a/truth.json")).unwrap(),
        std::fs::read(format!("{d}/b/truth.json")).unwrap()
    );
}
