//! The README's code blocks run as written (issue 30). Every block is claimed by exactly one test
//! ([`CLAIMS`]; a new block fails `every_block_is_claimed_by_a_test` until it is):
//! - the ```sh blocks of the CLI sections run here, each in a temporary folder standing for a fresh clone's
//!   root, with `omnical` the binary built here (the README's `omnical() { cargo run … }` line and `cargo run
//!   … --` are what give a fresh clone that command), `HOME` a fresh folder, and the user's own files (a bag,
//!   a URDF, a rosbag2 recording, a motion-capture file) made for the block that names them;
//! - the ```rust block is compiled and run by tests/integration/readme.rs (checked here to be the same text);
//! - the ```python blocks and the shell blocks of the Python sections (pip, the wheel's Python-side commands)
//!   run in crates/omni-py/tests/test_readme.py against the installed wheel.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use support::{copy_dir, entries, made_by_python};

/// A fenced code block of the README.
#[derive(Debug)]
struct Block {
    /// The `## ` heading it is under.
    section: String,
    /// The fence's language (`sh`, `python`, `rust,ignore`, or empty).
    lang: String,
    /// Its place among the blocks of its section and language, from 0.
    index: usize,
    /// The line of its opening fence, from 1.
    line: usize,
    /// Its text, without the fences.
    text: String,
}

fn readme_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")
}

fn blocks() -> Vec<Block> {
    let readme = std::fs::read_to_string(readme_path()).unwrap();
    let (mut out, mut section, mut open): (Vec<Block>, String, Option<Block>) = (Vec::new(), String::new(), None);
    for (i, line) in readme.lines().enumerate() {
        match (open.as_mut(), line.strip_prefix("```")) {
            (None, Some(lang)) => {
                let lang = lang.trim().to_string();
                let index = out.iter().filter(|b| b.section == section && b.lang == lang).count();
                open = Some(Block { section: section.clone(), lang, index, line: i + 1, text: String::new() });
            }
            (Some(_), Some("")) => out.extend(open.take()),
            (Some(b), _) => {
                b.text.push_str(line);
                b.text.push('\n');
            }
            (None, None) => {
                if let Some(h) = line.strip_prefix("## ") {
                    section = h.trim().to_string();
                }
            }
        }
    }
    assert!(open.is_none(), "README.md ends inside a code block");
    out
}

/// Which test runs each block: (section, language, index among that section's blocks of that language, test).
const CLAIMS: &[(&str, &str, usize, &str)] = &[
    ("Set up", "sh", 0, "readme.rs: set_up_and_quick_example_run_as_written"),
    ("Quick example (CLI)", "sh", 0, "readme.rs: set_up_and_quick_example_run_as_written"),
    ("Quick example (CLI)", "sh", 1, "readme.rs: your_robot_block_runs_on_recordings"),
    ("Are my runs enough? (identifiability)", "sh", 0, "readme.rs: identifiability_block_runs_as_written"),
    ("Rust", "rust,ignore", 0, "tests/integration/readme.rs (the text checked by rust_block_is_the_tested_code)"),
    ("Python", "sh", 0, "crates/omni-py/tests/test_readme.py"),
    ("Python", "python", 0, "crates/omni-py/tests/test_readme.py"),
    ("Fleet (Dask)", "sh", 0, "crates/omni-py/tests/test_readme.py"),
    ("Fleet (Dask)", "python", 0, "crates/omni-py/tests/test_readme.py"),
];

#[test]
fn every_block_is_claimed_by_a_test() {
    let found: Vec<(String, String, usize)> = blocks().into_iter().map(|b| (b.section, b.lang, b.index)).collect();
    let claimed: Vec<(String, String, usize)> =
        CLAIMS.iter().map(|(s, l, i, _)| (s.to_string(), l.to_string(), *i)).collect();
    for f in &found {
        assert!(claimed.contains(f), "README block {f:?} is run by no test: add it to CLAIMS and run it");
    }
    for c in &claimed {
        assert!(found.contains(c), "CLAIMS names {c:?}, which the README no longer has");
    }
}

fn block(section: &str, lang: &str, index: usize) -> Block {
    blocks()
        .into_iter()
        .find(|b| b.section == section && b.lang == lang && b.index == index)
        .unwrap_or_else(|| panic!("README has no {lang} block {index} under '## {section}'"))
}

/// The line of the Quick example that makes the `omnical` command on a fresh clone.
const OMNICAL_FUNCTION: &str = r#"omnical() { cargo run --release -q -p omni-cli -- "$@"; }"#;

/// A block as the test runs it: the ways a fresh clone gets the `omnical` command become the binary built
/// here, and `bash scripts/test.sh` (the command running this test) is left out. Nothing else changes.
fn as_run(b: &Block) -> String {
    let mut script = String::new();
    for line in b.text.lines() {
        let line = if line.starts_with(OMNICAL_FUNCTION) {
            ": omnical is the binary under test".to_string()
        } else if line.trim() == "bash scripts/test.sh" {
            ": the test command itself, which runs this test".to_string()
        } else {
            line.replace("cargo run --release -p omni-cli -- ", "omnical ")
        };
        assert!(!line.contains("cargo "), "README line {} runs cargo, which this test cannot: {line}", b.line);
        script.push_str(&line);
        script.push('\n');
    }
    script
}

/// Runs `b` with bash in `dir` (its root), with `omnical` on the PATH and `HOME` at `home`; returns stdout
/// and stderr, after checking that every command succeeded.
fn run(b: &Block, dir: &Path, home: &Path) -> (String, String) {
    let bin = home.parent().unwrap().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let link = bin.join("omnical");
    if !link.exists() {
        std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_omnical"), &link).unwrap();
    }
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let script = format!("set -euo pipefail\nset -x\n{}", as_run(b));
    let out = Command::new("bash")
        .args(["-c", &script])
        .current_dir(dir)
        .env("PATH", path)
        .env("HOME", home)
        .env_remove("RUST_LOG")
        .output()
        .expect("run bash");
    let (stdout, stderr) =
        (String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned());
    assert!(
        out.status.success(),
        "README block at line {} ('## {}') failed ({}):\n--- stdout\n{stdout}\n--- stderr (commands traced)\n{stderr}",
        b.line,
        b.section,
        out.status
    );
    (stdout, stderr)
}

/// A fresh clone's root (`repo/`) beside a `shared/` holding the real robot logs, a fresh `home/`.
fn fresh_clone() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let (root, home) = (tmp.path().join("repo"), tmp.path().join("home"));
    std::fs::create_dir_all(&root).unwrap();
    std::fs::create_dir_all(&home).unwrap();
    std::fs::create_dir_all(tmp.path().join("shared")).unwrap();
    if let Some(data) = option_env!("OMNICAL_SHARED_DATA") {
        std::os::unix::fs::symlink(data, tmp.path().join("shared/data")).unwrap();
    }
    (tmp, root, home)
}

/// The Set up block (the demo) and the Quick example on a fresh clone: each command succeeds; the demo and
/// the diagnosis name the hidden clock lag; everything is written under two git-ignored folders and nothing
/// else lands in the root; the completion script and the man pages are where the lines put them.
#[test]
#[cfg_attr(
    not(shared_data),
    ignore = "the Quick example reads the real robot logs ../shared/data (crates/omni-cli/build.rs)"
)]
fn set_up_and_quick_example_run_as_written() {
    let (_tmp, root, home) = fresh_clone();
    let quick = block("Quick example (CLI)", "sh", 0);
    assert!(quick.text.contains(OMNICAL_FUNCTION), "the Quick example defines `omnical` as {OMNICAL_FUNCTION}");
    let (setup, _) = run(&block("Set up", "sh", 0), &root, &home);
    assert!(setup.contains("\nverdict: add time_offset: held-out path cost falls"), "{setup}");
    assert!(root.join("omnical-demo/report.html").is_file());
    let (out, err) = run(&quick, &root, &home);
    assert!(out.contains("\nverdict: add time_offset: held-out path cost falls"), "{out}");
    // `eval … --json | jq .cost`: the Eq. 6 cost as a bare number.
    assert!(out.lines().any(|l| l.parse::<f64>().is_ok_and(|c| c > 0.0 && c < 0.1)), "{out}");
    // `-v` says what was read.
    assert!(err.contains("info: read 72 runs from sim/validation"), "{err}");
    assert_eq!(entries(&root), ["omnical-demo", "omnical-try"], "the README's commands leave only these in the root");
    let gitignore = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.gitignore")).unwrap();
    for ignored in ["omnical-demo/", "/omnical-try/"] {
        assert!(gitignore.lines().any(|l| l == ignored), ".gitignore lacks {ignored}");
    }
    let try_dir = root.join("omnical-try");
    for f in ["sim/train", "fitted.toml", "fitted_tau.toml", "paper.toml", "report.html", "figs/ladder.png"] {
        assert!(try_dir.join(f).exists(), "omnical-try/{f} missing");
    }
    for f in ["tum", "bags", "robot", "man"] {
        assert!(!entries(&try_dir.join(f)).is_empty(), "omnical-try/{f} is empty");
    }
    let completion = home.join(".local/share/bash-completion/completions/omnical");
    assert!(std::fs::read_to_string(completion).unwrap().contains("_omnical()"));
}

/// Recordings made by Python rosbags (crates/omni-cli/tests/rosbag2/make_recordings.py), as a user's own.
fn recordings() -> PathBuf {
    made_by_python("rosbag2/make_recordings.py", Path::new(env!("CARGO_TARGET_TMPDIR")).join("readme_recordings"))
}

/// The block for one's own robot, on a three-wheel robot's recordings: a bare MCAP bag and its URDF, a
/// rosbag2 folder, and a recording without ground truth with a motion-capture TUM file on another clock.
#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags, mcap, mcap-ros2-support and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn your_robot_block_runs_on_recordings() {
    let rec = recordings();
    let (_tmp, root, home) = fresh_clone();
    std::fs::create_dir_all(root.join("my_bags")).unwrap();
    std::fs::copy(rec.join("ref/rec.mcap"), root.join("my_bags/first.mcap")).unwrap();
    std::fs::copy(rec.join("urdf/omni3.urdf"), root.join("robot.urdf")).unwrap();
    copy_dir(&rec.join("mcap/rec"), &root.join("my_recording"));
    copy_dir(&rec.join("nogt/rec"), &root.join("rec"));
    std::fs::copy(rec.join("gt/tum_3s/rec.tum"), root.join("mocap.tum")).unwrap();
    let (out, err) = run(&block("Quick example (CLI)", "sh", 1), &root, &home);
    assert!(root.join("my_bags/robot.toml").is_file() && root.join("mine.toml").is_file());
    // The motion-capture clock runs 3.217 s off the wheels' (make_recordings.py): estimated, and said.
    assert!(err.contains("3.21"), "the estimated ground-truth clock offset: {err}");
    assert!(out.contains("\nverdict: "), "{out}");
    assert!(root.join("demo-mine/report.html").is_file() && root.join("sim-mine/train/robot.toml").is_file());
}

/// `plan` → `simulate --commands` → `train --objective end-pose`: the planned runs constrain every
/// direction (no warning); the OptiOdom square runs leave two unconstrained, which train warns about (on
/// stderr) and holds.
#[test]
#[cfg_attr(not(shared_data), ignore = "the block reads the real robot logs ../shared/data (crates/omni-cli/build.rs)")]
fn identifiability_block_runs_as_written() {
    let (_tmp, root, home) = fresh_clone();
    let here = root.join("omnical-try");
    std::fs::create_dir(&here).unwrap();
    let (out, err) = run(&block("Are my runs enough? (identifiability)", "sh", 0), &here, &home);
    let (planned, square) = err.split_once("+ omnical train ../../shared").unwrap();
    assert!(!planned.contains("warning") && !planned.contains("held at the start"), "{planned}");
    assert!(square.lines().any(|l| l.starts_with("warning: ") && l.contains("poorly constrained")), "{square}");
    assert!(square.contains("note: 2 direction(s) held at the start values"), "{square}");
    assert!(!out.contains("warning"), "warnings go to stderr: {out}");
    assert_eq!(entries(&root), ["omnical-try"]);
}

/// The README's Rust block is the code tests/integration/readme.rs runs, line for line.
#[test]
fn rust_block_is_the_tested_code() {
    let b = block("Rust", "rust,ignore", 0);
    let tested =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/integration/readme.rs"))
            .unwrap();
    for line in b.text.lines() {
        assert!(
            tested.lines().any(|t| t.trim() == line.trim()),
            "README line in the Rust block is not in tests/integration/readme.rs: {line}"
        );
    }
}
