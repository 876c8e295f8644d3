//! Golden outputs: model files, `--json` outputs, reports and exports of the real binary on a small
//! simulated set (with a hidden clock lag) must stay byte-identical across refactors. A changed output
//! fails with the first differing line; `OMNICAL_BLESS=1 cargo test -p omni-cli --test golden` rewrites the
//! files under `tests/golden/` when a change of output is intended (say why in the commit).
//!
//! Wall-clock fields (`seconds`) are removed from JSON before comparing; nothing else is normalised.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::{Path, PathBuf};
use support::{omnical_command, succeeded_on_two_threads};

/// `omnical --threads 2 -q ARGS` in `dir`, which must succeed: its stdout.
fn stdout_of(args: &[&str], dir: &Path) -> Vec<u8> {
    succeeded_on_two_threads(args, dir).stdout
}

/// JSON with the wall-clock fields removed, pretty-printed.
fn json_without_timing(bytes: &[u8]) -> String {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.remove("seconds");
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut v: serde_json::Value = serde_json::from_slice(bytes).expect("valid JSON");
    strip(&mut v);
    serde_json::to_string_pretty(&v).unwrap() + "\n"
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

/// Compares `actual` with the golden file `name` (or rewrites it when blessing); collects failures.
fn check(name: &str, actual: &str, failures: &mut Vec<String>) {
    let path = golden_dir().join(name);
    if std::env::var_os("OMNICAL_BLESS").is_some() {
        std::fs::create_dir_all(golden_dir()).unwrap();
        std::fs::write(&path, actual).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if expected != actual {
        let line = expected.lines().zip(actual.lines()).position(|(a, b)| a != b);
        let detail = match line {
            Some(i) => format!(
                "line {}:\n  golden: {}\n  actual: {}",
                i + 1,
                expected.lines().nth(i).unwrap_or(""),
                actual.lines().nth(i).unwrap_or("")
            ),
            None => format!("lengths differ ({} vs {} lines)", expected.lines().count(), actual.lines().count()),
        };
        failures.push(format!("{name}: {detail}"));
    }
}

fn read(dir: &Path, file: &str) -> String {
    std::fs::read_to_string(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

#[test]
fn outputs_are_byte_identical_to_the_golden_files() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let mut failures = Vec::new();
    let sim = ["simulate", "--runs-per-command", "1", "--duration", "4", "--seed", "3"];
    stdout_of(&[&sim[..], &["--out", "sim", "--effect", "time_offset=0.04"]].concat(), d);
    check("truth.json", &read(d, "sim/truth.json"), &mut failures);
    check("truth_model.toml", &read(d, "sim/truth_model.toml"), &mut failures);
    stdout_of(
        &[&sim[..], &["--out", "csv", "--format", "csv", "--effect", "wheel_asymmetry=0.02,-0.02,0.0"]].concat(),
        d,
    );
    check("sim_csv_run.csv", &read(d, "csv/validation/17-r0.csv"), &mut failures);

    let trainings: [(&str, &[&str]); 4] = [
        ("fit", &[]),
        ("paper", &["--preset", "paper"]),
        ("geometry_tau", &["--model", "geometry", "--effect", "time_offset"]),
        ("end_pose", &["--objective", "end-pose", "--every", "5"]),
    ];
    for (name, extra) in trainings {
        let model = format!("{name}.toml");
        let json = stdout_of(&[&["train", "sim/train", "--json", "--out", &model], extra].concat(), d);
        check(&format!("train_{name}.json"), &json_without_timing(&json), &mut failures);
        check(&model, &read(d, &model), &mut failures);
    }
    let json = stdout_of(&["train", "csv/train", "--json", "--effect", "wheel_asymmetry"], d);
    check("train_csv_wheel_asymmetry.json", &json_without_timing(&json), &mut failures);

    for (name, model) in [("design", "design"), ("fit", "fit.toml"), ("geometry_tau", "geometry_tau.toml")] {
        let json = stdout_of(&["eval", "--model", model, "sim/validation", "--json"], d);
        check(&format!("eval_{name}.json"), &json_without_timing(&json), &mut failures);
        let text = stdout_of(&["eval", "--model", model, "sim/validation", "--per-run"], d);
        check(&format!("eval_{name}.txt"), &String::from_utf8_lossy(&text), &mut failures);
    }
    let diag = ["diagnose", "--model", "fit.toml", "sim/train", "--validate", "sim/validation"];
    let json = stdout_of(&[&diag[..], &["--json"]].concat(), d);
    check("diagnose.json", &json_without_timing(&json), &mut failures);
    let json = stdout_of(&[&diag[..], &["--json", "--auto", "--out", "auto.toml"]].concat(), d);
    check("diagnose_auto.json", &json_without_timing(&json), &mut failures);
    check("diagnose_auto.toml", &read(d, "auto.toml"), &mut failures);
    let text = stdout_of(&diag, d);
    check("diagnose.txt", &String::from_utf8_lossy(&text), &mut failures);

    let json = stdout_of(&["plan", "--robot", "apr02", "--json", "--effect", "time_offset"], d);
    check("plan.json", &json_without_timing(&json), &mut failures);

    stdout_of(&["report", "--model", "fit.toml", "sim/train", "--validate", "sim/validation", "--out", "r.html"], d);
    check("report.html", &read(d, "r.html"), &mut failures);

    stdout_of(&["export", "--model", "fit.toml", "sim/validation", "--tum", "tum"], d);
    for kind in ["gt", "design", "calibrated"] {
        let file = format!("tum/00-r0.{kind}.tum");
        check(&format!("export_00-r0.{kind}.tum"), &read(d, &file), &mut failures);
    }
    assert!(failures.is_empty(), "outputs changed:\n{}", failures.join("\n"));
}

/// `OMNICAL_SIMD` caps the cost kernel's lane arithmetic; whatever the path (portable, AVX2, AVX-512, as the
/// CPU allows), training gives the golden files byte for byte (the paths are the same bits).
#[test]
fn training_is_the_same_bits_on_every_simd_path() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sim = ["simulate", "--runs-per-command", "1", "--duration", "4", "--seed", "3"];
    stdout_of(&[&sim[..], &["--out", "sim", "--effect", "time_offset=0.04"]].concat(), d);
    let mut failures = Vec::new();
    for path in ["portable", "avx2", "avx512"] {
        for (name, extra) in [("paper", &["--preset", "paper"][..]), ("geometry_tau", &["--model", "geometry"])] {
            let model = format!("{name}.toml");
            let args = [&["train", "sim/train", "--json", "--out", &model][..], extra].concat();
            let args = if name == "geometry_tau" { [&args[..], &["--effect", "time_offset"]].concat() } else { args };
            let out = omnical_command([&["--threads", "2", "-q"][..], &args].concat(), d)
                .env("OMNICAL_SIMD", path)
                .output()
                .unwrap();
            assert!(out.status.success(), "{path}: {}", String::from_utf8_lossy(&out.stderr));
            let before = failures.len();
            check(&format!("train_{name}.json"), &json_without_timing(&out.stdout), &mut failures);
            check(&format!("{name}.toml"), &read(d, &model), &mut failures);
            failures[before..].iter_mut().for_each(|f| *f = format!("OMNICAL_SIMD={path}: {f}"));
        }
    }
    assert!(failures.is_empty(), "outputs changed:\n{}", failures.join("\n"));
    let out = omnical_command(["train", "sim/train"], d).env("OMNICAL_SIMD", "sse9").output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&out.stderr), "error: OMNICAL_SIMD=sse9: expected avx512, avx2 or portable\n");
}
