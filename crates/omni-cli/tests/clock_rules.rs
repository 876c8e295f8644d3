//! The rules of a reference's clock (issue 43 item 3; docs/formats.md "Ground truth from a separate
//! file"): a CSV wheel log takes its ground truth from `--gt`; a clear estimate is applied; one that is not
//! clear is never applied (kept at 0 with a note when the stamps overlap as recorded, else refused); a clear
//! one longer than the recording, with stamps that overlap, is refused.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a failed unwrap is a failed test

use omni_cli::dataset::ground_truth::{GroundTruthOptions, Kept};
use omni_cli::dataset::{self, LoadOptions};
use omni_kin::simulate::{SimConfig, flower_commands, simulate};
use omni_kin::{FittedModel, IkMatrix, Model, Pose2, StampedPose};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One recording of several flower commands in a row (wheels at 100 Hz, truth at 125 Hz, motion-capture
/// noise `noise_m`), as wheel times and speeds and the truth's poses on the wheel clock, starting at `t0_s`.
fn recording(seed: u64, t0_s: f64, noise_m: f64) -> (Vec<f64>, Vec<[f64; 3]>, Vec<StampedPose>) {
    let commands = flower_commands().into_iter().skip(seed as usize).step_by(5).take(6).collect();
    let config = SimConfig {
        commands,
        runs_per_command: 1,
        duration_s: 4.0,
        truth_interval_s: (0.008, 0.008),
        truth_noise_m: noise_m,
        truth_noise_rad: noise_m,
        seed,
        ..SimConfig::default()
    };
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    let runs = simulate(&config, &truth, "r/").unwrap();
    let (mut t, mut rates, mut poses) = (Vec::new(), Vec::new(), Vec::<StampedPose>::new());
    let (mut start, mut at) = (Pose2::default(), t0_s);
    for run in &runs {
        let w = run.wheel_t_s();
        let shift = at - w[0];
        for (k, s) in w.iter().enumerate() {
            t.push(s + shift);
            let r = &run.wheel_rad_s()[k * 3..k * 3 + 3];
            rates.push([r[0], r[1], r[2]]);
        }
        let first = run.truth()[0].pose;
        for p in run.truth() {
            // Each run starts where the one before ended (its own truth starts at its origin).
            poses.push(StampedPose { t_s: p.t_s + shift, pose: start.compose(&first.inverse().compose(&p.pose)) });
        }
        start = poses[poses.len() - 1].pose;
        at = t[t.len() - 1] + 0.01;
    }
    (t, rates, poses)
}

/// Writes the wheels as an omnical CSV run without pose columns, and the truth as TUM with its stamps
/// moved by `-offset_s` (the truth's clock: `t_wheel = t_truth + offset_s`).
fn write(dir: &Path, name: &str, wheels: &(Vec<f64>, Vec<[f64; 3]>), truth: &[StampedPose], offset_s: f64) -> PathBuf {
    let mut csv = String::from("t_s,a_rad_s,b_rad_s,c_rad_s\n");
    for (t, r) in wheels.0.iter().zip(&wheels.1) {
        writeln!(csv, "{t},{},{},{}", r[0], r[1], r[2]).unwrap();
    }
    std::fs::write(dir.join(format!("{name}.csv")), csv).unwrap();
    let mut tum = String::new();
    for p in truth {
        let (qz, qw) = ((0.5 * p.pose.theta_rad).sin(), (0.5 * p.pose.theta_rad).cos());
        writeln!(tum, "{:.6} {} {} 0 0 0 {qz} {qw}", p.t_s - offset_s, p.pose.x_m, p.pose.y_m).unwrap();
    }
    let gt = dir.join(format!("{name}.tum"));
    std::fs::write(&gt, tum).unwrap();
    gt
}

fn load(dir: &Path, name: &str, gt: &Path) -> Result<dataset::Dataset, String> {
    let opts = LoadOptions {
        ground_truth: Some(GroundTruthOptions { path: gt.to_path_buf(), ..Default::default() }),
        ..Default::default()
    };
    dataset::load(&[dir.join(format!("{name}.csv"))], &opts)
        .map_err(|e| omni_cli::api::settings::as_flags(&e.to_string()))
}

#[test]
fn a_csv_wheel_log_takes_a_gt_file_on_another_clock() {
    let dir = tempfile::tempdir().unwrap();
    let (t, rates, truth) = recording(0, 10.0, 0.0003);
    let gt = write(dir.path(), "rec", &(t, rates), &truth, 3.217);
    let ds = load(dir.path(), "rec", &gt).unwrap();
    let clock = &ds.ground_truth_clocks[0];
    let a = clock.estimate.unwrap();
    assert!((clock.offset_s - 3.217).abs() < 0.005, "{}", clock.describe());
    assert!(a.is_clear() && clock.kept.is_none(), "{}", clock.describe());
    // The truth lands on the wheel clock: its first pose within a sample of the wheels' first motion.
    let run = &ds.runs[0];
    assert!((run.truth()[0].t_s - truth[0].t_s).abs() < 0.005, "{} vs {}", run.truth()[0].t_s, truth[0].t_s);
}

#[test]
fn a_csv_wheel_log_with_pose_columns_and_a_gt_file_is_refused_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("rec.csv"), "t_s,a_rad_s,b_rad_s,c_rad_s,x_m,y_m,theta_rad\n0,1,1,1,0,0,0\n")
        .unwrap();
    std::fs::write(dir.path().join("rec.tum"), "0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n").unwrap();
    let e = load(dir.path(), "rec", &dir.path().join("rec.tum")).unwrap_err();
    assert_eq!(
        e.replace(&format!("{}/", dir.path().display()), ""),
        "rec.csv: line 1: has ground-truth columns of its own (x_m, y_m, theta_rad), and --gt gives another: drop \
         --gt, or remove the columns to use the --gt file"
    );
}

#[test]
fn an_unclear_estimate_is_never_applied() {
    let dir = tempfile::tempdir().unwrap();
    // Motion capture with 4 mm of noise at 125 Hz: the best offset explains well under 90 % of the motion.
    let (t, rates, truth) = recording(1, 10.0, 0.004);
    let wheels = (t, rates);
    // On the wheels' time base, 2 s off: the stamps overlap as recorded, so they are kept, with a note.
    let gt = write(dir.path(), "rec", &wheels, &truth, 2.0);
    let ds = load(dir.path(), "rec", &gt).unwrap();
    let clock = &ds.ground_truth_clocks[0];
    let a = clock.estimate.unwrap();
    assert!(!a.is_clear(), "{a:?}");
    assert_eq!((clock.offset_s, clock.kept), (0.0, Some(Kept::Unclear)), "{}", clock.describe());
    assert!(clock.describe().contains("stamps kept as recorded, since the estimate"), "{}", clock.describe());
    // On another time base (epoch stamps against a log from 10 s): refused, naming the file and the way out.
    let gt = write(dir.path(), "rec", &wheels, &truth, -1.7e9);
    let e = load(dir.path(), "rec", &gt).unwrap_err();
    assert!(
        e.starts_with(&format!("{}: cannot align its clock with recording \"rec\": the best offset", gt.display())),
        "{e}"
    );
    assert!(e.contains("not a clear estimate") && e.ends_with("give the offset with --gt-time-offset SECONDS"), "{e}");
}

/// Pieces of motion one after the other from `t0_s` (each re-timed and continued from where the one before
/// ended).
fn chain(pieces: &[&[StampedPose]], t0_s: f64) -> Vec<StampedPose> {
    let (mut out, mut start, mut at) = (Vec::<StampedPose>::new(), Pose2::default(), t0_s);
    for piece in pieces {
        let (first, t_first) = (piece[0].pose, piece[0].t_s);
        out.extend(piece.iter().map(|p| StampedPose {
            t_s: p.t_s - t_first + at,
            pose: start.compose(&first.inverse().compose(&p.pose)),
        }));
        start = out[out.len() - 1].pose;
        at = out[out.len() - 1].t_s + 0.008;
    }
    out
}

#[test]
fn a_clear_offset_longer_than_the_recording_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (t, rates, truth) = recording(2, 100.0, 0.0003);
    let span = t[t.len() - 1] - t[0];
    // The file: other motion, then this recording's 1.3 spans before the wheels' stamps, then more other
    // motion, so that the file overlaps the wheel data as recorded (one time base) while the matching stretch
    // lies further off than the recording is long.
    let (_, _, other) = recording(3, 0.0, 0.0003);
    let (_, _, more) = recording(4, 0.0, 0.0003);
    let start = 100.0 - 1.3 * span - (other[other.len() - 1].t_s - other[0].t_s) - 0.008;
    let file = chain(&[&other, &truth, &more, &other], start);
    let (g0, g1) = (file[0].t_s, file[file.len() - 1].t_s);
    assert!(g0 < 100.0 && g1 > 100.0, "{g0}..{g1}");
    let gt = write(dir.path(), "rec", &(t, rates), &file, 0.0);
    let e = load(dir.path(), "rec", &gt).unwrap_err();
    assert!(e.contains("but it is longer than the recording"), "{e}");
    assert!(e.contains("give the offset with --gt-time-offset SECONDS"), "{e}");
    // Forced, the same file is read.
    let opts = LoadOptions {
        ground_truth: Some(GroundTruthOptions {
            path: gt.clone(),
            time_offset_s: Some(1.3 * span),
            ..Default::default()
        }),
        ..Default::default()
    };
    let ds = dataset::load(&[dir.path().join("rec.csv")], &opts).unwrap();
    assert!(ds.notes.iter().any(|n| n.text.contains("dropped")), "{:?}", ds.notes);
}

/// The real rover of `../shared/data/breezyslam-exp1` (a URG-04LX, no ground truth): its scans are stamped
/// later than the wheels by about 0.2 s (issue 43: a plain regression of the scan-matched rotation on the
/// wheels': R² 0.88 → 0.98). The scan-matched translation over 0.1 s is noisy, so the whole motion gives no
/// clear estimate (53 %); the rotation alone, on blocks of two scan intervals, does: -0.188 s ± 2.1 ms,
/// 94 % explained (45 % as recorded), on the sharper of the path's 2 stretches. The load names the lag, and
/// `diagnose` names it too (the relative reference's 4 s windows joined back into their stretches).
#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn the_real_lidar_lags_the_wheels_and_the_load_and_diagnose_name_it() {
    let data = Path::new(option_env!("OMNICAL_SHARED_DATA").unwrap_or("")).join("breezyslam-exp1");
    let run = |args: &[&str]| {
        let out =
            std::process::Command::new(env!("CARGO_BIN_EXE_omnical")).args(args).current_dir(&data).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(0), "{err}");
        (String::from_utf8_lossy(&out.stdout).into_owned(), err)
    };
    let lidar = ["exp1.mcap", "--robot", "robot.toml", "--gt-scans", "/scan"];
    let (_, err) = run(&[&["eval"], &lidar[..], &["--gt-kind", "relative"]].concat());
    let note = err.lines().find(|l| l.contains("a clock offset between the wheels and the sensor of")).expect(&err);
    assert!(note.contains("of its rotation (its translation is noisier)") && !note.contains("not clear"), "{note}");
    let offset: f64 = note.split("sensor of ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!((-0.25..=-0.15).contains(&offset), "{note}");
    let model = tempfile::tempdir().unwrap();
    let m = model.path().join("m.toml");
    let m = m.to_str().unwrap();
    run(&[&["train"], &lidar[..], &["--out", m, "-q"]].concat());
    let (out, _) = run(&[&["diagnose", "--model", m], &lidar[..]].concat());
    let finding = out.lines().find(|l| l.contains("the wheels and the reference disagree in time")).expect(&out);
    let lag: f64 = finding.split("stamps ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!((0.15..=0.25).contains(&lag), "{finding}");
}
