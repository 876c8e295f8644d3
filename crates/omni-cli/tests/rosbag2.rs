//! rosbag2 recordings as ROS 2 records them (folders with metadata.yaml, split files, sqlite3 and MCAP
//! storage, zstd compression), written by a real client: Python `rosbags` (`tests/rosbag2/make_recordings.py`
//! writes one simulated recording in every layout, and broken ones). Every layout must give exactly the runs
//! of the reference bare MCAP file; broken inputs exit with status 2 naming the file and the problem.
//! `omnical init` inspects every layout as `train` reads it.
//!
//! The interpreter is `$OMNICAL_PYTHON` (default `python3`); without `rosbags` and `numpy` there the tests
//! are reported as ignored with the reason (build.rs). `bash scripts/test.sh` installs them.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a failed unwrap is a failed test

#[path = "rosbag2/helpers.rs"]
mod helpers;
mod support;

use helpers::{LAYOUTS, exit_code_and_output, fixtures};
use omni_cli::dataset::mcap::{McapOptions, McapRead, read_file};
use omni_cli::dataset::{self, LoadOptions, rosbag2};
use serde_json::Value;
use std::path::{Path, PathBuf};
use support::omnical_command;

fn split(s: Option<f64>) -> McapOptions {
    McapOptions { split: s, ..Default::default() }
}

fn reference(dir: &Path, opts: &McapOptions) -> McapRead {
    read_file(&dir.join("ref/rec.mcap"), opts).unwrap()
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn every_layout_gives_the_runs_of_the_bare_mcap() {
    let (dir, expected) = fixtures();
    for opts in [split(None), split(Some(1.0))] {
        let want = reference(dir, &opts);
        assert_eq!(want.origin_s, expected["origin_s"].as_i64().unwrap());
        assert!(want.notes.is_empty(), "{:?}", want.notes);
        for layout in LAYOUTS {
            let got = rosbag2::read_recording(&dir.join(layout).join("rec"), &opts, u64::MAX, None)
                .unwrap_or_else(|e| panic!("{layout}: {e}"));
            assert_eq!(got, want, "{layout}, split {:?}", opts.split);
        }
        let bare = rosbag2::read_db3(&dir.join("bare/rec.db3"), &opts, u64::MAX, None).unwrap();
        assert_eq!(bare, want, "bare .db3");
    }
    // Three motion segments between 2 s standstills: three runs, the wheel samples shared at the cuts.
    let runs = reference(dir, &split(Some(1.0))).runs;
    let names: Vec<&str> = runs.iter().map(|r| r.name()).collect();
    assert_eq!(names, ["rec#1", "rec#2", "rec#3"]);
    let n = expected["n_wheel"].as_u64().unwrap() as usize;
    assert_eq!(runs.iter().map(|r| r.wheel_t_s().len()).sum::<usize>(), n + 2);
    // The split files are one recording: without --split, one run over all 30 s.
    let whole = rosbag2::read_recording(&dir.join("split_db3/rec"), &split(None), u64::MAX, None).unwrap();
    assert_eq!(whole.runs.len(), 1);
    assert_eq!(whole.runs[0].wheel_t_s().len(), n);
    assert_eq!(whole.runs[0].truth().len(), expected["n_truth"].as_u64().unwrap() as usize);
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn a_folder_of_recordings_reads_each_in_name_order() {
    let (dir, _) = fixtures();
    let ds = dataset::load(&[dir.join("several")], &LoadOptions::default()).unwrap();
    let names: Vec<&str> = ds.runs.iter().map(|r| r.name()).collect();
    assert_eq!(names, ["a", "b"]);
    assert_eq!(ds.runs[0].wheel_rad_s(), ds.runs[1].wheel_rad_s());
    assert_eq!(ds.runs[0].truth(), ds.runs[1].truth());
    assert_eq!(ds.runs[0].wheel_rad_s(), reference(dir, &split(None)).runs[0].wheel_rad_s());
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn eval_gives_the_same_costs_from_mcap_and_db3() {
    let (dir, _) = fixtures();
    let eval = |input: &Path| {
        let (code, out, err) = exit_code_and_output(&[
            "eval",
            input.to_str().unwrap(),
            "--robot",
            "apr02",
            "--model",
            "paper",
            "--split",
            "1",
            "--json",
        ]);
        assert_eq!(code, 0, "{err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        v
    };
    let want = eval(&dir.join("ref/rec.mcap"));
    assert!(want["cost"].as_f64().unwrap() > 0.0, "{want}");
    for input in [dir.join("db3/rec"), dir.join("split_mcap/rec"), dir.join("bare/rec.db3")] {
        assert_eq!(eval(&input), want, "{}", input.display());
    }
}

/// The error of `omnical eval INPUT`: exit status 2 and the message.
fn error(input: &Path) -> String {
    let (code, _, err) =
        exit_code_and_output(&["eval", input.to_str().unwrap(), "--robot", "apr02", "--model", "paper"]);
    assert_eq!(code, 2, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err.trim_end().to_string()
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn bad_recordings_exit_2_naming_the_file_and_the_problem() {
    let (dir, expected) = fixtures();
    let bad = dir.join("bad");
    let d = bad.display();
    assert_eq!(
        error(&bad.join("missing_file")),
        format!(
            "error: {d}/missing_file/metadata.yaml: key relative_file_paths: lists {d}/missing_file/missing_file_1.db3, \
             which does not exist"
        )
    );
    assert_eq!(
        error(&bad.join("unknown_storage")),
        format!(
            "error: {d}/unknown_storage/metadata.yaml: key storage_identifier: storage \"hdf5\" is not supported \
             (omnical reads rosbag2's \"sqlite3\" and \"mcap\")"
        )
    );
    assert_eq!(
        error(&bad.join("empty.db3")),
        format!(
            "error: {d}/empty.db3: the sqlite3 file is empty (0 bytes): the recording holds no messages (was it \
             interrupted before anything was written?)"
        )
    );
    let k = expected["truncated_blob_message"].as_u64().unwrap();
    assert_eq!(
        error(&bad.join("truncated_blob.db3")),
        format!(
            "error: {d}/truncated_blob.db3: topic \"/joint_states\", message {k}: cannot decode CDR: the 40-byte \
             message ends before its last field (cut short, or a length inside it is corrupted); is the message \
             type right?"
        )
    );
}

/// `omnical eval` on the recording without a ground-truth topic, with `--gt` and more; the JSON output.
fn eval_json(dir: &Path, args: &[&str]) -> Value {
    let input = dir.join("nogt/rec");
    let mut all = vec!["eval", input.to_str().unwrap(), "--robot", "apr02", "--model", "paper", "--json"];
    all.extend_from_slice(args);
    let (code, out, err) = exit_code_and_output(&all);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("clock offset"), "{err}");
    serde_json::from_str(&out).unwrap()
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn ground_truth_files_on_other_clocks_are_aligned_within_5_ms() {
    let (dir, expected) = fixtures();
    let csv_args = [
        "--gt-columns",
        "t=stamp_ns,x=pos_x_mm,y=pos_y_mm,yaw=heading_deg",
        "--gt-units",
        "time=ns,length=mm,angle=deg",
    ];
    for (name, truth) in expected["offsets_s"].as_object().unwrap() {
        let truth = truth.as_f64().unwrap();
        for format in ["tum", "csv"] {
            // A folder of files matched by recording name (nogt/rec ↔ rec.tum / rec.csv).
            let gt = dir.join(format!("gt/{format}_{name}"));
            let mut args = vec!["--gt", gt.to_str().unwrap()];
            if format == "csv" {
                args.extend_from_slice(&csv_args);
            }
            let v = eval_json(dir, &args);
            let clock = &v["ground_truth_clock"][0];
            let offset = clock["offset_s"].as_f64().unwrap();
            let se = clock["std_error_s"].as_f64().unwrap();
            assert!((offset - truth).abs() < 0.005, "{format} {name}: {offset} s, true {truth} s");
            assert!(se > 0.0 && se < 0.005, "{format} {name}: standard error {se} s");
            assert!(clock["r_squared"].as_f64().unwrap() > 0.99, "{clock}");
            assert_eq!(clock["recording"], "rec");
        }
    }
}

/// Exports keep the recording's time base: the TUM ground truth of a recording carries the absolute stamps
/// of its ground-truth topic (those a TUM file on the same clock has), and the exported MCAP starts at the
/// recording's own second, so both line up with the original in evo and Foxglove.
#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn exports_keep_the_recordings_time_base() {
    let (dir, _) = fixtures();
    let work = tempfile::tempdir().unwrap();
    let w = work.path();
    let rec = dir.join("db3/rec");
    let (code, _, err) = exit_code_and_output(&[
        "export",
        rec.to_str().unwrap(),
        "--robot",
        "apr02",
        "--model",
        "paper",
        "--tum",
        w.join("tum").to_str().unwrap(),
        "--mcap",
        w.join("mcap").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let stamps = |text: &str| -> Vec<String> {
        text.lines().filter(|l| !l.starts_with('#')).map(|l| l.split(' ').next().unwrap().to_string()).collect()
    };
    let exported = stamps(&std::fs::read_to_string(w.join("tum/rec.gt.tum")).unwrap());
    let same_clock = stamps(&std::fs::read_to_string(dir.join("gt/same_clock.tum")).unwrap());
    assert!(exported[0].starts_with("17000000"), "{}", exported[0]);
    assert!(same_clock.contains(&exported[0]) && same_clock.contains(&exported[exported.len() - 1]), "{exported:?}");
    // make_recordings.py's ORIGIN_S: the recording's first second.
    let back = read_file(&w.join("mcap/rec.mcap"), &McapOptions::default()).unwrap();
    assert_eq!(back.origin_s, 1_700_000_000);
}

/// Recordings read with one `--gt` folder share its clock: one whose ground truth is too short to align on
/// its own (1.5 s of poses, one every 0.25 s) is read at the offset the other was aligned at, with a note,
/// instead of stopping the command.
#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn a_recording_too_sparse_to_align_takes_the_clock_of_the_others() {
    let (dir, expected) = fixtures();
    let work = tempfile::tempdir().unwrap();
    let w = work.path();
    for name in ["full", "sparse"] {
        let to = w.join(name);
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(dir.join("nogt/rec")).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
    std::fs::create_dir_all(w.join("mocap")).unwrap();
    let tum = std::fs::read_to_string(dir.join("gt/tum_3s/rec.tum")).unwrap();
    std::fs::write(w.join("mocap/full.tum"), &tum).unwrap();
    let rows: Vec<&str> = tum.lines().filter(|l| !l.starts_with('#')).collect();
    let t0: f64 = rows[0].split(' ').next().unwrap().parse().unwrap();
    // Past the first motion's start (0.5 s after the wheels' first stamp), 1.5 s of one pose per 0.25 s.
    let sparse: Vec<&str> = rows
        .iter()
        .copied()
        .filter(|l| {
            let t: f64 = l.split(' ').next().unwrap().parse::<f64>().unwrap() - t0;
            (2.0..3.5).contains(&t) && (t * 4.0 - (t * 4.0).round()).abs() < 0.02
        })
        .collect();
    assert!(sparse.len() >= 5, "{}", sparse.len());
    std::fs::write(w.join("mocap/sparse.tum"), sparse.join("\n") + "\n").unwrap();
    let args = |gt: &str| -> Vec<String> {
        ["eval", "full", "sparse", "--robot", "apr02", "--model", "paper", "--json", "--gt", gt]
            .map(String::from)
            .to_vec()
    };
    let out = omnical_command(args("mocap"), w).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let clocks = v["ground_truth_clock"].as_array().unwrap();
    assert_eq!(clocks.len(), 2, "{v}");
    let truth = expected["offsets_s"]["3s"].as_f64().unwrap();
    let found = clocks[0]["offset_s"].as_f64().unwrap();
    assert!((found - truth).abs() < 0.005, "{found}");
    assert_eq!((clocks[1]["offset_s"].as_f64().unwrap(), &clocks[1]["estimated"]), (found, &Value::Bool(false)));
    assert!(
        err.contains("mocap/sparse.tum: cannot align its clock with recording \"sparse\": ")
            && err.contains(&format!(
                "; the ground truth is read at {found:+.4} s, the median offset of the 1 recording(s) aligned \
                 clearly with the same --gt (one clock)"
            )),
        "{err}"
    );
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn bag_and_tum_give_the_costs_of_the_bag_with_its_topic() {
    let (dir, _) = fixtures();
    let (code, out, err) = exit_code_and_output(&[
        "eval",
        dir.join("db3/rec").to_str().unwrap(),
        "--robot",
        "apr02",
        "--model",
        "paper",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let want: Value = serde_json::from_str(&out).unwrap();
    // The same clock, forced: exactly the poses of the topic (TUM stamps are read as exact decimals).
    let tum = dir.join("gt/same_clock.tum");
    let got = eval_json(dir, &["--gt", tum.to_str().unwrap(), "--gt-time-offset", "0"]);
    assert_eq!(got["cost"], want["cost"]);
    // The end-pose errors bit for bit; the relative pose error, read off the ground-truth poses themselves
    // (the two sources' poses need not agree to the bit), within 1e-12.
    let without_rpe = |v: &Value| -> Value {
        let mut runs = v["runs"].clone();
        runs.as_array_mut().unwrap().iter_mut().for_each(|r| drop(r.as_object_mut().unwrap().remove("rpe")));
        runs
    };
    assert_eq!(without_rpe(&got), without_rpe(&want));
    let rmse = |v: &Value| v["runs"][0]["rpe"]["translation_m"]["rmse"].as_f64().unwrap();
    assert!((rmse(&got) - rmse(&want)).abs() < 1e-12, "{} vs {}", rmse(&got), rmse(&want));
    assert_eq!(got["ground_truth_clock"][0]["estimated"], false);
    // Estimated: within a few microseconds of it, so the same cost to 1e-6.
    let got = eval_json(dir, &["--gt", tum.to_str().unwrap()]);
    let (a, b) = (got["cost"].as_f64().unwrap(), want["cost"].as_f64().unwrap());
    assert!((a - b).abs() < 1e-6 * b, "{a} vs {b}");
    // A folder whose files are not named after the recording (a mocap take's own name): the file that covers
    // the recording's span is its ground truth; a take 1000 s later is not.
    let takes = dir.join("gt_takes");
    std::fs::create_dir_all(&takes).unwrap();
    let text = std::fs::read_to_string(&tum).unwrap();
    let later: String = text
        .lines()
        .map(|l| match l.split_once(' ') {
            Some((t, rest)) if !l.starts_with('#') => format!("{} {rest}\n", t.parse::<f64>().unwrap() + 1000.0),
            _ => format!("{l}\n"),
        })
        .collect();
    std::fs::write(takes.join("take_002.tum"), later).unwrap();
    std::fs::write(takes.join("take_001.tum"), &text).unwrap();
    let got = eval_json(dir, &["--gt", takes.to_str().unwrap(), "--gt-time-offset", "0"]);
    assert_eq!(got["cost"], want["cost"]);
    assert!(got["ground_truth_clock"][0]["file"].as_str().unwrap().ends_with("take_001.tum"), "{got}");
    std::fs::remove_file(takes.join("take_001.tum")).unwrap();
    let input = dir.join("nogt/rec");
    let (code, _, err) =
        exit_code_and_output(&["eval", input.to_str().unwrap(), "--robot", "apr02", "--gt", takes.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("none covers half of its span"), "{err}");
    assert!(err.contains("(files: take_002.tum "), "{err}");
    assert!(err.ends_with("name the file after the recording, or give it with --gt FILE\n"), "{err}");
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn bad_ground_truth_files_exit_2_naming_the_file_and_row() {
    let (dir, _) = fixtures();
    let rec = dir.join("nogt/rec");
    let bad = dir.join("bad");
    let run = |gt: &str, extra: &[&str]| {
        let gt = bad.join(gt);
        let mut args = vec!["eval", rec.to_str().unwrap(), "--robot", "apr02", "--model", "paper", "--gt"];
        args.push(gt.to_str().unwrap());
        args.extend_from_slice(extra);
        let (code, _, err) = exit_code_and_output(&args);
        assert_eq!(code, 2, "{err}");
        err.trim_end().replace(&format!("{}/", bad.display()), "")
    };
    assert_eq!(run("nan.tum", &[]), "error: nan.tum: line 12, column y: value NaN is not finite");
    assert_eq!(
        run("decreasing.tum", &[]),
        "error: decreasing.tum: line 23: time 1700000000.363000000 s is not after the previous row's \
         1700000000.371000000 s (times must increase)"
    );
    let e = run("elsewhen.tum", &["--gt-time-offset", "0"]);
    assert!(
        e.starts_with(&format!(
            "error: {}: wheel data on \"/joint_states\" spans 0.25..30.25 s but the ground truth in \
             elsewhen.tum (+0.0000 s clock offset) spans 3600.253..",
            rec.display()
        )),
        "{e}"
    );
    assert!(e.ends_with("no ground-truth pose lies within the wheel data"), "{e}");
    // A recording without a ground-truth topic and no --gt names what is missing.
    let (code, _, err) = exit_code_and_output(&["eval", rec.to_str().unwrap(), "--robot", "apr02", "--model", "paper"]);
    assert_eq!(code, 2);
    assert!(err.contains("no ground truth"), "{err}");
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn parallel_loading_gives_the_serial_order_and_results() {
    let (dir, _) = fixtures();
    let paths: Vec<PathBuf> = ["several", "ref/rec.mcap", "db3/rec", "bad/truncated_blob.db3", "split_mcap", "bare"]
        .iter()
        .map(|p| dir.join(p))
        .collect();
    let opts = LoadOptions {
        skip_invalid: true,
        mcap: McapOptions { split: Some(1.0), ..Default::default() },
        ..Default::default()
    };
    let load = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| dataset::load(&paths, &opts).unwrap())
    };
    let serial = load(1);
    let names: Vec<&str> = serial.runs.iter().map(|r| r.name()).collect();
    assert_eq!(
        names,
        [
            "a#1", "a#2", "a#3", "b#1", "b#2", "b#3", "rec#1", "rec#2", "rec#3", "rec#1", "rec#2", "rec#3", "rec#1",
            "rec#2", "rec#3", "rec#1", "rec#2", "rec#3"
        ]
    );
    assert_eq!(serial.skipped.len(), 1);
    assert!(serial.skipped[0].source.ends_with("truncated_blob.db3"), "{:?}", serial.skipped);
    for threads in [2, 4] {
        let parallel = load(threads);
        assert_eq!(parallel.runs, serial.runs, "{threads} threads");
        assert_eq!(parallel.notes, serial.notes);
        let reasons =
            |d: &dataset::Dataset| d.skipped.iter().map(|s| (s.source.clone(), s.reason.clone())).collect::<Vec<_>>();
        assert_eq!(reasons(&parallel), reasons(&serial));
    }
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn db3_files_in_wal_mode_or_out_of_id_order_are_read_in_time_order() {
    let (dir, expected) = fixtures();
    let opts = split(Some(1.0));
    // In WAL mode, closed cleanly (read whole into memory); ids counting backwards in time: the same runs.
    for file in ["wal_clean/rec.db3", "reversed_ids/rec.db3"] {
        let got = rosbag2::read_db3(&dir.join(file), &opts, u64::MAX, None).unwrap();
        assert_eq!(got, reference(dir, &opts), "{file}");
    }
    // Its writer killed: the change in the log is read (the message it cut short).
    let k = expected["truncated_blob_message"].as_u64().unwrap();
    let pending = dir.join("wal_pending/rec.db3");
    assert_eq!(
        rosbag2::read_db3(&pending, &opts, u64::MAX, None).unwrap_err().to_string(),
        format!(
            "{}: topic \"/joint_states\", message {k}: cannot decode CDR: the 40-byte message ends before its last \
             field (cut short, or a length inside it is corrupted); is the message type right?",
            pending.display()
        )
    );
}
