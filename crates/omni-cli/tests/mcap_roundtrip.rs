//! MCAP tests that always run: the committed bag written by rosbags (`tests/data/tiny_rosbags.mcap`, made by
//! `tests/mcap/make_bags.py --tiny`), write → read round trips, and damaged files.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a failed unwrap is a failed test

#[path = "mcap/helpers.rs"]
mod helpers;
mod support;

use helpers::{check_run, close, design_odometry, simulated_run};
use omni_cli::dataset::mcap::{McapOptions, WriteOptions, read_file, write_run};
use omni_kin::{Pose2, Run, RunData, StampedPose};
use std::path::PathBuf;
use support::test_data;

#[test]
fn committed_rosbags_bag_gives_the_values_written() {
    let path = test_data("tiny_rosbags.mcap");
    assert!(std::fs::metadata(&path).unwrap().len() < 50_000);
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(test_data("tiny_rosbags.json")).unwrap()).unwrap();
    let r = read_file(&path, &McapOptions::default()).unwrap();
    assert_eq!(r.origin_s, 1_700_000_000);
    assert_eq!(r.runs.len(), 1);
    assert_eq!(r.runs[0].name(), "tiny_rosbags");
    check_run(&r.runs[0], &expected);
    assert!(r.runs[0].recorded_odometry().is_empty());
}

/// Writes `run` into a fresh temporary directory and reads it back.
fn round_trip(run: &Run, w: &WriteOptions) -> (tempfile::TempDir, PathBuf, omni_cli::dataset::mcap::McapRead) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("{}.mcap", run.name()));
    write_run(&path, run, w).unwrap();
    let read = read_file(&path, &McapOptions::default()).unwrap();
    (dir, path, read)
}

fn same_poses(got: &[StampedPose], want: &[StampedPose], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: lengths differ");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((g.t_s - w.t_s).abs() <= 1e-9, "{what}[{i}]: t {} vs {}", g.t_s, w.t_s);
        let (g, w) = (g.pose, w.pose);
        close(&[g.x_m, g.y_m, g.theta_rad], &[w.x_m, w.y_m, w.theta_rad], 1e-12, &format!("{what}[{i}] pose"));
    }
}

#[test]
fn written_runs_read_back_equal() {
    let run = simulated_run("sim-007", 10.5);
    for origin_s in [0, 1_700_000_000] {
        let w = WriteOptions { design_odometry: Some(design_odometry(&run)), origin_s, ..Default::default() };
        let (_dir, _path, r) = round_trip(&run, &w);
        assert_eq!(r.origin_s, origin_s);
        assert!(r.skipped.is_empty());
        // The command is a TwistStamped: no note that its times are log times.
        assert!(r.notes.is_empty(), "{:?}", r.notes);
        let back = &r.runs[0];
        assert_eq!(back.name(), "sim-007");
        assert_eq!(back.n_samples(), 1051);
        // Stamps to the nanosecond; values exactly as written (to 1e-12).
        close(back.wheel_t_s(), run.wheel_t_s(), 1e-9, "wheel_t_s");
        close(back.wheel_rad_s(), run.wheel_rad_s(), 1e-12, "wheel_rad_s");
        close(back.wheel_start_rad(), run.wheel_start_rad(), 1e-12, "wheel_start_rad");
        same_poses(back.truth(), run.truth(), "truth");
        same_poses(back.recorded_odometry(), &design_odometry(&run), "recorded odometry");
        let (c, b) = (run.command().unwrap(), back.command().unwrap());
        close(&[b.v_m_s, b.alpha_rad, b.omega_rad_s], &[c.v_m_s, c.alpha_rad, c.omega_rad_s], 1e-12, "command");
        // The heading turned almost 21 rad (from -3 rad) and came back unwrapped.
        assert!((back.end().pose.theta_rad - 17.96).abs() < 1e-12);
    }
}

#[test]
fn recorded_odometry_can_be_left_out() {
    let run = simulated_run("sim-008", 3.0);
    let w = WriteOptions { design_odometry: Some(design_odometry(&run)), ..Default::default() };
    let (dir, path, with) = round_trip(&run, &w);
    assert!(!with.runs[0].recorded_odometry().is_empty());
    let without = read_file(&path, &McapOptions { recorded_odometry: false, ..Default::default() }).unwrap();
    let back = &without.runs[0];
    assert!(back.recorded_odometry().is_empty());
    // Nothing else changes.
    assert_eq!(back.wheel_rad_s(), with.runs[0].wheel_rad_s());
    assert_eq!(back.truth(), with.runs[0].truth());
    assert_eq!(without.notes, with.notes);
    // Through `dataset::load`, also for CSV.
    let mut d = run.clone().into_data();
    d.recorded_odometry = design_odometry(&run);
    let csv = dir.path().join("sim-008.csv");
    omni_cli::dataset::csv::write_run(&csv, &Run::new(d).unwrap(), &["a".into(), "b".into(), "c".into()]).unwrap();
    let paths = [path, csv];
    let kept = omni_cli::dataset::load(&paths, &Default::default()).unwrap();
    assert!(kept.runs.iter().all(|r| !r.recorded_odometry().is_empty()));
    let opts = omni_cli::dataset::LoadOptions { recorded_odometry: false, ..Default::default() };
    let ds = omni_cli::dataset::load(&paths, &opts).unwrap();
    assert_eq!(ds.runs.len(), 2);
    assert!(ds.runs.iter().all(|r| r.recorded_odometry().is_empty()));
    assert_eq!(ds.runs[1].wheel_rad_s(), kept.runs[1].wheel_rad_s());
}

#[test]
fn a_run_without_command_odometry_or_start_angles() {
    let mut d = simulated_run("bare", 1.0).into_data();
    (d.command, d.wheel_start_rad) = (None, Vec::new());
    let run = Run::new(d).unwrap();
    let (_dir, _, r) = round_trip(&run, &WriteOptions::default());
    let back = &r.runs[0];
    assert_eq!(back.command(), None);
    assert!(back.recorded_odometry().is_empty());
    assert_eq!(back.wheel_start_rad(), [0.0; 3]);
    close(back.wheel_rad_s(), run.wheel_rad_s(), 1e-12, "wheel_rad_s");
}

#[test]
fn writing_is_atomic_and_checks_its_input() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    std::fs::write(&path, "old").unwrap();
    write_run(&path, &simulated_run("a", 1.0), &WriteOptions::default()).unwrap();
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names, ["run.mcap"]);
    assert!(read_file(&path, &McapOptions::default()).is_ok());

    let two = WriteOptions { wheel_joints: vec!["l".into(), "r".into()], ..Default::default() };
    let e = write_run(&path, &simulated_run("a", 1.0), &two).unwrap_err();
    assert_eq!(e.to_string(), format!("{}: run a has 3 wheels but 2 wheel joint names were given", path.display()));
    let mut d = simulated_run("early", 1.0).into_data();
    d.wheel_t_s.iter_mut().for_each(|t| *t -= 0.5);
    d.truth.iter_mut().for_each(|p| p.t_s -= 0.5);
    let e = write_run(&path, &Run::new(d).unwrap(), &WriteOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("{}: time -0.5 s after the origin 0 s is not a valid ROS 2 stamp", path.display())
    );
    // The failed writes left the earlier file alone, and no temporary file.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names, ["run.mcap"]);
    assert!(read_file(&path, &McapOptions::default()).is_ok());
}

#[test]
fn damaged_files_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.mcap");
    write_run(&good, &simulated_run("good", 3.0), &WriteOptions::default()).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let bad = dir.path().join("bad.mcap");
    let read_bad = |b: &[u8]| {
        std::fs::write(&bad, b).unwrap();
        read_file(&bad, &McapOptions::default()).map_err(|e| e.to_string())
    };

    let e = read_bad(b"t,x\n0,1\n").unwrap_err();
    assert_eq!(e, format!("{}: not an MCAP file (it does not start with the MCAP magic bytes)", bad.display()));
    let e = read_bad(&bytes[..bytes.len() / 2]).unwrap_err();
    assert_eq!(
        e,
        format!(
            "{}: the file is truncated: it ends in the middle of a record, before the MCAP end marker (was the \
             recording interrupted?)",
            bad.display()
        )
    );
    let missing = dir.path().join("missing.mcap");
    let e = read_file(&missing, &McapOptions::default()).unwrap_err();
    assert_eq!(e.to_string(), format!("{}: No such file or directory (os error 2)", missing.display()));

    // The first chunk's CRC (the writer records one): records (opcode, u64 length, body) follow the magic
    // (8 bytes): the header, rosbag2's metadata, then the first chunk; its CRC follows opcode, length and
    // three u64 fields.
    let mut chunk = 8;
    while bytes[chunk] != 0x06 {
        assert!([0x01, 0x0C].contains(&bytes[chunk]), "a header or metadata record before the chunk: {}", bytes[chunk]);
        chunk += 1 + 8 + u64::from_le_bytes(bytes[chunk + 1..chunk + 9].try_into().unwrap()) as usize;
    }
    let mut flipped = bytes.clone();
    flipped[chunk + 33] ^= 0x01;
    let e = read_bad(&flipped).unwrap_err();
    assert!(
        e.starts_with(&format!("{}: the file is corrupted: a chunk's CRC is ", bad.display()))
            && e.ends_with(" was recorded"),
        "{e}"
    );

    // Any single damaged byte, or any cut, gives a result or an error, never a panic.
    let mut errors = 0;
    for i in (0..bytes.len()).step_by(bytes.len() / 400 + 1) {
        let mut b = bytes.clone();
        b[i] ^= 0x5a;
        let r = std::panic::catch_unwind(|| read_bad(&b));
        errors += usize::from(r.expect("no panic on a damaged byte").is_err());
        let r = std::panic::catch_unwind(|| read_bad(&bytes[..i]));
        assert!(r.expect("no panic on a cut file").is_err());
    }
    assert!(errors > 0);
}

#[test]
fn split_of_a_written_run_with_standstills() {
    // Three motions separated by 1 s standstills (wheels at 0, truth still).
    let n = 501;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
    let moving = |k: usize| !((100..=200).contains(&k) || (300..=400).contains(&k));
    let wheel_rad_s: Vec<f64> = (0..n).flat_map(|k| if moving(k) { [1.0, -1.0, 0.5] } else { [0.0; 3] }).collect();
    let x = |s: f64| s.min(1.0) + (s - 2.0).clamp(0.0, 1.0) + (s - 4.0).clamp(0.0, 1.0);
    let truth: Vec<StampedPose> =
        (0..=100).map(|k| k as f64 * 0.05).map(|s| StampedPose { t_s: s, pose: Pose2::new(x(s), 0.0, 0.0) }).collect();
    let run =
        Run::new(RunData { name: "three".into(), wheel_t_s: t, wheel_rad_s, n_wheels: 3, truth, ..Default::default() })
            .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("three.mcap");
    write_run(&path, &run, &WriteOptions::default()).unwrap();
    let r = read_file(&path, &McapOptions { split: Some(0.8), ..Default::default() }).unwrap();
    let spans: Vec<(String, f64, f64, usize)> = r
        .runs
        .iter()
        .map(|r| (r.name().to_string(), r.wheel_t_s()[0], *r.wheel_t_s().last().unwrap(), r.truth().len()))
        .collect();
    let expected = [("three#1", 0.0, 1.5, 31), ("three#2", 1.5, 3.5, 41), ("three#3", 3.5, 5.0, 31)];
    assert_eq!(spans.len(), 3);
    for ((name, a, b, m), (en, ea, eb, em)) in spans.iter().zip(expected) {
        assert_eq!((name.as_str(), *m), (en, em));
        assert!((a - ea).abs() < 1e-9 && (b - eb).abs() < 1e-9, "{name}: {a}..{b}");
    }
    // Each piece's truth stays within its wheel span.
    for run in &r.runs {
        let (a, b) = (run.wheel_t_s()[0], *run.wheel_t_s().last().unwrap());
        assert!(run.truth().iter().all(|p| (a..=b).contains(&p.t_s)));
    }
}
