//! What a new user hits in the first hour (issue 30), through the real binary: output folders that hold
//! runs already, result files checked before the work, diagnostics on stderr, a mistyped flag, a headerless
//! OptiOdom file, a diff robot's matrix units, one run in the singular, and the report's worst run.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::Path;
use support::{entries, ok_with_stderr, omnical, refused, succeeded, test_data};

/// A small simulated set in `dir/sim`: `repeats` × 36 runs of 2 s per split.
fn simulate(dir: &Path, repeats: &str, extra: &[&str]) -> (String, String) {
    ok_with_stderr(
        &[&["simulate", "--out", "sim", "--runs-per-command", repeats, "--duration", "2"], extra].concat(),
        dir,
    )
}

/// A second simulation into a folder that holds runs is refused, the folder untouched; `--force` replaces
/// it whole, so that `eval` reads only the new runs (issue 30 item 1: 72 stale runs were read before).
#[test]
fn simulate_refuses_a_folder_with_runs_and_force_replaces_it_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "3", &[]);
    assert_eq!(entries(&d.join("sim/train")).len(), 108 + 1);
    let err = refused(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "2"], d);
    assert_eq!(
        err,
        "error: --out sim: the folder already holds files (train, truth.json, truth_model.toml, …); give --force to \
         replace it whole, or another --out\n"
    );
    assert_eq!(entries(&d.join("sim/train")).len(), 108 + 1, "the refused command changed nothing");
    let (out, _) = simulate(d, "1", &["--force"]);
    assert!(out.starts_with("train: 36 runs, design cost"), "{out}");
    assert_eq!(entries(&d.join("sim/train")).len(), 36 + 1);
    assert_eq!(entries(d), ["sim"], "no staging or old folder left beside it");
    let (_, err) = ok_with_stderr(&["-v", "eval", "--model", "design", "sim/train"], d);
    assert!(err.contains("info: read 36 runs from sim/train"), "{err}");
    // An empty folder is new enough.
    std::fs::create_dir(d.join("empty")).unwrap();
    succeeded(&["simulate", "--out", "empty", "--runs-per-command", "1", "--duration", "1", "--format", "csv"], d);
    assert_eq!(entries(&d.join("empty")), ["train", "truth.json", "truth_model.toml", "validation"]);
}

/// `demo --out` refuses a folder with files before simulating anything; `export --tum`/`--mcap` the same,
/// and one folder for both is refused.
#[test]
fn demo_and_export_refuse_folders_with_files() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir(d.join("old")).unwrap();
    std::fs::write(d.join("old/report.html"), "an earlier demo's").unwrap();
    let out = omnical(&["demo", "--out", "old"], d);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty(), "refused before the first step: {}", String::from_utf8_lossy(&out.stdout));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        "error: --out old: the folder already holds files (report.html); give --force to replace it whole, or \
         another --out\n"
    );
    simulate(d, "1", &["--format", "csv"]);
    fn export<'a>(extra: &[&'a str]) -> Vec<&'a str> {
        [&["export", "--model", "design", "sim/validation"], extra].concat()
    }
    assert_eq!(
        refused(&export(&["--tum", "t", "--mcap", "t/"]), d),
        "error: --tum and --mcap name the same folder t: give each its own\n"
    );
    succeeded(&export(&["--tum", "tum"]), d);
    std::fs::write(d.join("tum/other_run.gt.tum"), "# a run of another export\n").unwrap();
    assert_eq!(
        refused(&export(&["--tum", "tum"]), d),
        "error: --tum tum: the folder already holds files (other_run.gt.tum, validation_00-r0.calibrated.tum, \
         validation_00-r0.design.tum, …); give --force to replace it whole, or another --tum\n"
    );
    succeeded(&export(&["--tum", "tum", "--force"]), d);
    let files = entries(&d.join("tum"));
    assert_eq!(files.len(), 3 * 36);
    assert!(!files.contains(&"other_run.gt.tum".to_string()), "replaced whole");
}

/// `report --png DIR` keeps the folder's other files and removes a figure an earlier report drew that this
/// one does not (the ranking, without a diagnosis).
#[test]
fn report_png_keeps_other_files_and_drops_stale_figures() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "1", &["--format", "csv"]);
    std::fs::create_dir(d.join("figs")).unwrap();
    std::fs::write(d.join("figs/ranking.png"), "an earlier report's ranking").unwrap();
    std::fs::write(d.join("figs/notes.txt"), "mine").unwrap();
    succeeded(&["report", "--model", "design", "sim/train", "--no-diagnose", "--out", "r.html", "--png", "figs"], d);
    let figs = entries(&d.join("figs"));
    assert_eq!(
        figs,
        [
            "flower.png",
            "growth.png",
            "heat-map.png",
            "ladder.png",
            "notes.txt",
            "overlay-typical.png",
            "overlay-worst.png"
        ]
    );
}

/// Result files are checked before the work: a missing folder fails at once, naming it (the fit is not
/// run); `train` without `--out` says that nothing was written.
#[test]
fn result_files_are_checked_first_and_train_says_when_nothing_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "1", &["--format", "csv"]);
    let missing =
        "error: --out nowhere/m.toml: the folder nowhere does not exist (create it first: mkdir -p nowhere)\n";
    assert_eq!(refused(&["train", "sim/train", "--out", "nowhere/m.toml"], d), missing);
    assert_eq!(refused(&["diagnose", "--model", "design", "sim/train", "--out", "nowhere/m.toml"], d), missing);
    assert_eq!(
        refused(&["report", "--model", "design", "sim/train", "--out", "nowhere/r.html"], d),
        "error: --out nowhere/r.html: the folder nowhere does not exist (create it first: mkdir -p nowhere)\n"
    );
    assert_eq!(refused(&["plan", "--out", "sim"], d), "error: --out sim: this is a folder; give a file name in it\n");
    let (out, err) = ok_with_stderr(&["train", "sim/train"], d);
    assert!(
        out.starts_with(
            "preset default: 36 training runs, objective path, integration exact arcs, each run's median step\n"
        ),
        "{out}"
    );
    assert!(err.ends_with("note: the fitted model was not written (no --out FILE)\n"), "{err}");
    let (_, err) = ok_with_stderr(&["train", "sim/train", "--out", "m.toml"], d);
    assert!(!err.contains("not written"), "{err}");
    let (_, err) = ok_with_stderr(&["-q", "train", "sim/train"], d);
    assert_eq!(err, "", "-q keeps notes off stderr");
}

/// `--ot` suggests `--out` (clap's own measure suggested `--joints-topic`), with the plain usage line.
#[test]
fn a_mistyped_flag_suggests_the_nearest_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let out = omnical(&["train", "runs", "--ot", "m.toml"], tmp.path());
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.starts_with("error: unexpected argument '--ot' found\n"), "{err}");
    assert!(err.contains("tip: a similar argument exists: '--out'"), "{err}");
    assert!(err.contains("Usage: omnical train [OPTIONS] <RUNS>..."), "{err}");
    assert!(!err.contains("joints-topic"), "{err}");
    let err = String::from_utf8_lossy(&omnical(&["eval", "--model", "design", "x", "--per-rum"], tmp.path()).stderr)
        .into_owned();
    assert!(err.contains("tip: a similar argument exists: '--per-run'"), "{err}");
}

/// An OptiOdom run file read without its set's metadata file: the message says what it is and where its
/// metadata goes; another headerless CSV is told it needs a header.
#[test]
fn a_headerless_optiodom_run_says_it_needs_its_metadata() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let rows = "0,0,0,0,-0,-0,-0\n0.04,0.001,0,0.001,3,-2,1\n0.08,0.002,0,0.002,3,-2,1\n";
    std::fs::create_dir(d.join("set")).unwrap();
    std::fs::write(d.join("set/221220201934_run-01.csv"), rows).unwrap();
    std::fs::write(d.join("plain.csv"), rows).unwrap();
    assert_eq!(
        refused(&["eval", "--model", "design", "set", "--robot", "apr02"], d),
        "error: set/221220201934_run-01.csv: line 1: missing column t_s (columns: 0,0,0,0,-0,-0,-0); the first line \
         holds numbers: this looks like an OptiOdom run file, which is read from its set's folder with the set's \
         metadata file (221220201934_metadata.csv) beside it (docs/formats.md)\n"
    );
    let err = refused(&["eval", "--model", "design", "plain.csv", "--robot", "apr02"], d);
    assert!(
        err.ends_with(
            "; the first line holds numbers: an omnical CSV file starts with a header line (docs/formats.md)\n"
        ),
        "{err}"
    );
}

/// A diff robot's matrix (its vy row a structural zero) prints its ω row in its unit, rad per wheel rad,
/// never as an angle in degrees; and one run is "1 run".
#[test]
fn a_diff_matrix_keeps_its_units_and_one_run_is_singular() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let robot = test_data("diff_robot.toml");
    simulate(d, "1", &["--robot", robot.to_str().unwrap(), "--format", "csv"]);
    let (out, _) = ok_with_stderr(&["train", "sim/train", "--model", "ik"], d);
    // Degrees only in the noise model's heading rates (°/√m, °/√rad), never for an entry of the matrix.
    assert!(!out.lines().filter(|l| !l.starts_with("odometry noise")).any(|l| l.contains('°')), "{out}");
    assert!(out.lines().any(|l| l.contains("m31 ±") && l.contains(" rad")), "{out}");
    assert!(!out.lines().any(|l| l.trim_start().starts_with("m31 ")), "the matrix shows its entries: {out}");
    let one = entries(&d.join("sim/train")).into_iter().find(|f| f.ends_with(".csv")).unwrap();
    let one = format!("sim/train/{one}");
    let (out, _) = ok_with_stderr(&["train", &one, "--model", "ik"], d);
    assert!(
        out.starts_with(
            "preset default: 1 training run, objective path, integration exact arcs, each run's median step\n"
        ),
        "{out}"
    );
    let (out, _) = ok_with_stderr(&["eval", "--model", "design", &one], d);
    assert!(out.starts_with("model design: 1 run\n"), "{out}");
}

/// The report names one worst run: the diagnosis' finding says it is a training run, and without held-out
/// runs the overlay shows that same run, chosen by the same measure (path RMS).
#[test]
fn the_report_names_one_worst_run() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "1", &["--format", "csv", "--effect", "time_offset=0.06"]);
    succeeded(&["train", "sim/train", "--out", "m.toml"], d);
    succeeded(&["report", "--model", "m.toml", "sim/train", "--out", "r.html"], d);
    let html = std::fs::read_to_string(d.join("r.html")).unwrap();
    let finding = html.split("worst training run ").nth(1).unwrap_or_else(|| panic!("no finding in the report"));
    let finding_run = finding.split_whitespace().next().unwrap();
    let caption = html.split("— the worst training run by the path RMS of the fitted matrix").next().unwrap();
    let figure_run = caption.rsplit("Run ").next().unwrap().trim();
    assert_eq!(finding_run, figure_run);
    assert_eq!(html.matches("worst held-out run").count(), 0);
}

/// An option that changes nothing is an error (issue 27): `--gt-time-offset` on runs with neither a `--gt`
/// file nor a ground-truth topic; on a recording's topic it is applied and reported like a file's.
#[test]
fn a_clock_offset_that_changes_nothing_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    succeeded(&["simulate", "--out", "csv", "--runs-per-command", "1", "--duration", "2", "--format", "csv"], d);
    let err = refused(&["eval", "csv/train", "--gt-time-offset", "0.1"], d);
    assert_eq!(
        err.lines().last().unwrap(),
        "error: --gt-time-offset 0.1 changes nothing here: it applies to a --gt file or to a ground-truth topic of a \
         recording (MCAP, rosbag2), and these runs have neither"
    );
    simulate(d, "1", &[]);
    let (out, _) = ok_with_stderr(&["eval", "sim/train", "--gt-time-offset", "0", "--json"], d);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["ground_truth_clock"].as_array().map(Vec::len), Some(36), "{v}");
    assert_eq!(v["ground_truth_clock"][0]["estimated"], false);
}

/// Wheel data in another unit than the robot description says (issue 27: rpm read as rad/s, or the
/// reverse) would train a matrix off by that factor; the wheels' distance and turning against the ground
/// truth's refuse it, saying what to declare.
#[test]
fn wheels_in_another_unit_than_declared_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    simulate(d, "1", &[]);
    let robot = std::fs::read_to_string(d.join("sim/train/robot.toml")).unwrap();
    // The simulated joints are rad/s; declared rpm, they go 2π/60 as far as the ground truth.
    std::fs::write(d.join("rpm.toml"), format!("{robot}\n[wheel_data]\nvelocity = \"rpm\"\n")).unwrap();
    // The joints' positions (rad) tell it first: velocity read as rpm gives 2π/60 of their rate (issue 44).
    let err = refused(&["eval", "sim/train", "--robot", "rpm.toml"], d);
    let last = err.lines().last().unwrap();
    assert!(last.contains(": field velocity gives a wheel rate of "), "{err}");
    assert!(
        last.contains("(medians over 0.5 s windows: 9.55 times more by position, near 9.549, the factor between rad/s and rpm; position read in rad and velocity in rpm, as [wheel_data] declares)"),
        "{err}"
    );
    // A radius 60/2π too large looks like rpm read as rad/s.
    let big = robot.replace("radius_m = 0.148", &format!("radius_m = {}", 0.148 * 60.0 / std::f64::consts::TAU));
    assert_ne!(big, robot);
    std::fs::write(d.join("big.toml"), big).unwrap();
    let err = refused(&["eval", "sim/train", "--robot", "big.toml"], d);
    // 9.55 times the simulated robot's wheels, which go 9.6 % further than the design's.
    assert!(err.contains(": 8.72 times, beyond what a calibration corrects."), "{err}");
    assert!(err.contains("(docs/formats.md) (8.72 is near 9.549, the factor of velocity = \"rpm\")"), "{err}");
    succeeded(&["eval", "sim/train"], d);
}
