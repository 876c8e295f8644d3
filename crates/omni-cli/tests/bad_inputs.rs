//! The bad-input corpus through the real `omnical` binary: every file in `tests/data/bad/` gives a clear
//! error naming the file (and topic, message or line) and a non-zero exit, never a panic; the cases and
//! their expected words are in `tests/data/bad/EXPECTED.toml`. Also replays the fuzzers' seeds
//! (`fuzz/seeds/`) through the readers in-process, so `cargo test` is the fuzz smoke run of CI.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a failed unwrap is a failed test

mod support;

use omni_cli::dataset::{csv, mcap};
use serde::Deserialize;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use support::{omnical_command, stderr};

#[derive(Deserialize)]
struct Expected {
    case: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    /// Relative to `tests/data/bad`.
    file: String,
    /// Extra arguments after the file.
    #[serde(default)]
    args: Vec<String>,
    /// Substrings of the error message.
    #[serde(default)]
    expect: Vec<String>,
    /// Why this file loads after all (then it must succeed).
    ok: Option<String>,
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn bad_dir() -> PathBuf {
    root().join("tests/data/bad")
}

fn corpus_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for sub in ["mcap", "csv", "fuzz"] {
        for e in std::fs::read_dir(bad_dir().join(sub)).unwrap() {
            files.push(e.unwrap().path());
        }
    }
    files.sort();
    files
}

/// `omnical CMD FILE ARGS --robot apr02` (and `--quiet` for `train`) in the package's folder, without
/// backtraces: the exit status and stderr.
fn exit_code_and_stderr(cmd: &str, file: &Path, args: &[String]) -> (i32, String) {
    let out = omnical_command([std::ffi::OsStr::new(cmd), file.as_os_str()], Path::new(env!("CARGO_MANIFEST_DIR")))
        .args(args)
        // The design is the paper's robot (runs without a robot description are refused).
        .args(["--robot", "apr02"])
        .args(["--quiet"].iter().filter(|_| cmd == "train"))
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    (out.status.code().unwrap_or(-1), stderr(&out))
}

#[test]
fn every_bad_file_gives_a_clear_error() {
    let expected: Expected =
        toml::from_str(&std::fs::read_to_string(bad_dir().join("EXPECTED.toml")).unwrap()).unwrap();
    let mut covered = BTreeSet::new();
    let mut failures = Vec::new();
    for case in &expected.case {
        let file = bad_dir().join(&case.file);
        assert!(file.is_file(), "EXPECTED.toml names {}, which does not exist", case.file);
        covered.insert(file.clone());
        let commands: &[&str] = if case.ok.is_some() { &["eval"] } else { &["eval", "train"] };
        for cmd in commands {
            let (code, stderr) = exit_code_and_stderr(cmd, &file, &case.args);
            let mut problems = Vec::new();
            if stderr.contains("panicked") || code == 101 {
                problems.push("panicked".to_string());
            }
            if stderr.contains('\r') {
                problems.push("a carriage return in the message".to_string());
            }
            match &case.ok {
                Some(_) if code != 0 => problems.push(format!("exit {code}, expected 0")),
                Some(_) => {}
                None => {
                    if code != 2 {
                        problems.push(format!("exit {code}, expected 2"));
                    }
                    let prefix = format!("error: {}: ", file.display());
                    if !stderr.starts_with(&prefix) {
                        problems.push(format!("does not start with {prefix:?}"));
                    }
                    for want in &case.expect {
                        if !stderr.contains(want.as_str()) {
                            problems.push(format!("lacks {want:?}"));
                        }
                    }
                    if case.expect.is_empty() {
                        problems.push("the case has no `expect`".into());
                    }
                }
            }
            if !problems.is_empty() {
                failures.push(format!("{} ({cmd}): {}\n  stderr: {}", case.file, problems.join("; "), stderr.trim()));
            }
        }
    }
    let missing: Vec<String> =
        corpus_files().into_iter().filter(|f| !covered.contains(f)).map(|f| f.display().to_string()).collect();
    assert!(missing.is_empty(), "files without a case in EXPECTED.toml: {missing:?}");
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// The fuzz smoke run: every committed fuzz seed and corpus file through both readers, in-process (a
/// panic fails the test). The real fuzzing is `scripts/fuzz.sh`.
#[test]
fn fuzz_seeds_and_corpus_replay_without_panics() {
    let mut files = corpus_files();
    for target in ["mcap_read", "csv_read"] {
        if let Ok(dir) = std::fs::read_dir(root().join("fuzz/seeds").join(target)) {
            files.extend(dir.map(|e| e.unwrap().path()));
        }
    }
    assert!(files.len() > 100, "only {} files", files.len());
    let split = mcap::McapOptions { split: Some(0.5), skip_invalid: true, ..Default::default() };
    for f in &files {
        let bytes = std::fs::read(f).unwrap();
        // Both readers on every file, as the fuzz targets do.
        let _ = mcap::read_bytes(f, &bytes, &mcap::McapOptions::default());
        let _ = mcap::read_bytes(f, &bytes, &split);
        let _ = csv::parse_run(f, &bytes, None);
    }
}
