//! `omnical report` and `omnical export` end to end: the report of a simulated robot with a hidden effect,
//! its PNG figures, TUM files checked by evo, and MCAP bags with the calibrated odometry.
//!
//! The evo check uses `evo_ape` beside `$OMNICAL_PYTHON` (`bash scripts/test.sh` installs evo from
//! requirements-dev.txt); without it that test is reported as ignored, with the reason (build.rs).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use omni_cli::dataset::{self, LoadOptions};
use omni_kin::odometry::{self, Selection};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use support::{ok, omnical, shared_data, stderr, stdout, succeeded};

/// A small simulated robot with a 60 ms wheel-clock lag, and the matrix fitted to it (shared by the tests).
fn fitted() -> &'static (tempfile::TempDir, PathBuf) {
    static DATA: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    DATA.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        ok(
            &["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "6", "--effect", "time_offset=0.06"],
            dir.path(),
        );
        ok(&["train", "sim/train", "--out", "fit.toml", "-q"], dir.path());
        let root = dir.path().to_path_buf();
        (dir, root)
    })
}

/// Value of `label`'s held-out path RMS in `omnical report`'s table.
fn held_out_path(stdout: &str, label: &str) -> f64 {
    let line = stdout.lines().find(|l| l.starts_with(&format!("{label} "))).unwrap_or_else(|| panic!("{stdout}"));
    line[label.len()..].split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn report_shows_every_figure_and_the_error_falling_with_the_hidden_effect() {
    let (_keep, root) = fitted();
    // The page's folder must exist (checked before the work); the PNG folder is made.
    std::fs::create_dir_all(root.join("out")).unwrap();
    let stdout = ok(
        &[
            "report",
            "--model",
            "fit.toml",
            "sim/train",
            "--validate",
            "sim/validation",
            "--out",
            "out/report.html",
            "--png",
            "out/png",
        ],
        root,
    );
    let design = held_out_path(&stdout, "design");
    let matrix = held_out_path(&stdout, "fitted matrix");
    let with_effect = held_out_path(&stdout, "fitted matrix + time_offset");
    assert!(matrix < 0.2 * design, "{stdout}");
    assert!(with_effect < 0.7 * matrix, "the hidden clock lag should be found and help: {stdout}");

    let html = std::fs::read_to_string(root.join("out/report.html")).unwrap();
    let ids = [
        "ladder",
        "overlay-worst",
        "overlay-typical",
        "flower",
        "heat-map",
        "growth",
        "trust-ellipses",
        "trust-growth",
        "ranking",
    ];
    for id in ids {
        assert!(html.contains(&format!("data-figure=\"{id}\"")), "figure {id} missing");
        let png = std::fs::read(root.join(format!("out/png/{id}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{id}.png is not a PNG");
        assert!(png.len() > 10_000, "{id}.png is nearly empty ({} bytes)", png.len());
    }
    assert_eq!(html.matches("<figure ").count(), ids.len());
    assert_eq!(html.matches("<svg").count(), ids.len());
    // Self-contained: no scripts, no external resources.
    for bad in ["<script", "src=", "href=\"http", "url(http", "@import"] {
        assert!(!html.contains(bad), "report contains {bad}");
    }
    assert!(html.contains("Verdict.") && html.contains("add time_offset"), "verdict missing");
    assert!(html.contains("time_offset.tau_s"), "fitted effect parameter missing");
    // The ranking: sample_timing (no parameters; the simulated samples are all at the nominal step) is left
    // out with its reason, and no cell reads NaN or -0.0 (issue 19).
    let row = html.lines().find(|l| l.starts_with("<tr><td class=\"l\">sample_timing</td>")).unwrap();
    assert!(row.contains("not identifiable on these runs"), "{row}");
    for bad in ["NaN", "-0.0 %", ">-0.0<"] {
        assert!(!html.contains(bad), "report contains {bad}");
    }
    assert!(
        html.contains("What the runs can calibrate") && html.contains("condition number"),
        "identifiability missing"
    );
}

/// `omnical diagnose`'s ranking: every row has numbers or a reason, never `NaN` or `-0.0`; sample_timing,
/// which changes nothing on runs whose samples are all at the nominal step, says why it is left out.
#[test]
fn diagnose_ranking_shows_numbers_or_a_reason_never_nan() {
    let (_keep, root) = fitted();
    let stdout = ok(&["diagnose", "--model", "fit.toml", "sim/train", "--validate", "sim/validation"], root);
    let row = stdout.lines().find(|l| l.trim_start().starts_with("sample_timing ")).unwrap();
    assert_eq!(row.split_whitespace().take(5).collect::<Vec<_>>(), ["sample_timing", "-", "-", "-", "not"], "{row}");
    assert!(row.ends_with("(not identifiable on these runs)"), "{row}");
    for bad in ["NaN", " -0.0 "] {
        assert!(!stdout.contains(bad), "diagnose printed {bad}:\n{stdout}");
    }
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn report_without_diagnosis_or_commands_leaves_those_figures_out_and_says_so() {
    let data = shared_data("omni3");
    let dir = tempfile::tempdir().unwrap();
    let set = data.join("221220201934");
    let stdout =
        ok(&["report", "--model", "design", set.to_str().unwrap(), "--no-diagnose", "--out", "r.html"], dir.path());
    assert!(stdout.contains("(4 figures: ladder, overlay-worst, overlay-typical, growth)"), "{stdout}");
    let html = std::fs::read_to_string(dir.path().join("r.html")).unwrap();
    assert!(html.contains("carry no (v, α, ω) command"), "note on missing commands");
    assert!(html.contains("No diagnosis was run"), "note on missing diagnosis");
    assert!(!html.contains("data-figure=\"ranking\""));
    assert!(html.contains("data-figure=\"growth\""));
    // The OptiOdom design cost of this set (README): Eq. 6 = 0.1856.
    assert!(stdout.lines().any(|l| l.starts_with("design") && l.trim_end().ends_with("0.18560")), "{stdout}");
}

/// The TUM files of the run `03-r0` in the folder `tum` (one per test: the tests share the fitted model),
/// and our own position RMS of the calibrated odometry against its ground truth, from the library.
fn tum_export_and_our_rms(root: &Path, tum: &str) -> f64 {
    succeeded(&["export", "--model", "fit.toml", "sim/validation/03-r0.mcap", "--tum", tum], root);
    for kind in ["gt", "design", "calibrated"] {
        let text = std::fs::read_to_string(root.join(format!("{tum}/03-r0.{kind}.tum"))).unwrap();
        let rows: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
        assert!(rows.len() > 10, "{kind}: {} poses", rows.len());
        assert!(rows.iter().all(|r| r.split(' ').count() == 8), "{kind}: not 8 columns");
    }
    let ds = dataset::load(&[root.join("sim/validation/03-r0.mcap")], &LoadOptions::default()).unwrap();
    let model = omni_cli::model_file::read(&root.join("fit.toml")).unwrap();
    let res = model.model.resolve(&model.params).unwrap();
    let r = odometry::residuals(&res, &ds.runs[0], Selection::Path(1));
    // Path residuals leave out the start pose, where odometry starts (error 0); evo compares it too.
    assert_eq!(r[0].truth_index, 1);
    let n = ds.runs[0].truth().len() as f64;
    (r.iter().map(|x| x.error.position_m().powi(2)).sum::<f64>() / n).sqrt()
}

#[test]
fn tum_export_writes_the_three_trajectories() {
    let (_keep, root) = fitted();
    let ours = tum_export_and_our_rms(root, "tum");
    assert!(ours > 1e-4, "position RMS {ours}");
}

#[test]
#[cfg_attr(not(python_evo), ignore = "needs evo_ape beside $OMNICAL_PYTHON: bash scripts/test.sh installs evo")]
fn tum_export_agrees_with_evo_ape() {
    let (_keep, root) = fitted();
    let ours = tum_export_and_our_rms(root, "tum-evo");
    let python = PathBuf::from(std::env::var_os("OMNICAL_PYTHON").unwrap());
    let ape = python.parent().unwrap().join("evo_ape");
    let out = Command::new(&ape)
        .args(["tum", "03-r0.gt.tum", "03-r0.calibrated.tum", "--no_warnings"])
        .current_dir(root.join("tum-evo"))
        .env("MPLBACKEND", "Agg")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    let rmse: f64 = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("rmse"))
        .unwrap_or_else(|| panic!("no rmse in evo output: {text}"))
        .trim()
        .parse()
        .unwrap();
    // evo prints 6 decimals.
    assert!((rmse - ours).abs() < 2e-6, "evo_ape rmse {rmse} m vs ours {ours} m");
}

#[test]
fn mcap_export_adds_the_calibrated_odometry_topic() {
    let (_keep, root) = fitted();
    ok(&["export", "--model", "fit.toml", "sim/validation/07-r0.mcap", "--mcap", "bags"], root);
    let bytes = std::fs::read(root.join("bags/07-r0.mcap")).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let topics: Vec<(&str, &str)> = summary
        .channels
        .values()
        .map(|c| (c.topic.as_str(), c.schema.as_ref().map_or("", |s| s.name.as_str())))
        .collect();
    assert!(topics.contains(&("/omnical/odometry", "nav_msgs/msg/Odometry")), "{topics:?}");
    assert!(topics.contains(&("/joint_states", "sensor_msgs/msg/JointState")), "{topics:?}");
    let calibrated_id = summary.channels.values().find(|c| c.topic == "/omnical/odometry").unwrap().id;
    let count = summary.stats.as_ref().unwrap().channel_message_counts[&calibrated_id];
    // One pose per wheel step over the ground-truth span (6 s at 100 Hz) plus the ground-truth stamps.
    assert!((600..=800).contains(&count), "{count} calibrated odometry messages");
    // The bag still reads as a run, with the same ground truth.
    let back = dataset::load(&[root.join("bags/07-r0.mcap")], &LoadOptions::default()).unwrap();
    let orig = dataset::load(&[root.join("sim/validation/07-r0.mcap")], &LoadOptions::default()).unwrap();
    assert_eq!(back.runs[0].truth().len(), orig.runs[0].truth().len());
    let (a, b) = (back.runs[0].end().pose, orig.runs[0].end().pose);
    assert!((a.x_m - b.x_m).abs() < 1e-12 && (a.y_m - b.y_m).abs() < 1e-12);
    // Every channel carries the QoS rosbag2 writes (volatile here: nothing latched in this bag), and the
    // file the `rosbag2` record that says how to read it.
    for c in summary.channels.values() {
        let qos = &c.metadata["offered_qos_profiles"];
        assert!(qos.starts_with("- history: 1\n") && qos.contains("durability: 2\n"), "{}: {qos}", c.topic);
    }
    assert!(summary.metadata_indexes.iter().any(|m| m.name == "rosbag2"), "{:?}", summary.metadata_indexes);
    // /omnical/odometry names the frame its poses are in: the ground truth's (`map`; CDR: 4 bytes of
    // encapsulation, the stamp, then the frame's length and text).
    let stream = mcap::MessageStream::new(&bytes).unwrap();
    let first = stream.map(Result::unwrap).find(|m| m.channel.id == calibrated_id).unwrap();
    assert_eq!(&first.data[12..20], b"\x04\0\0\0map\0", "{:?}", &first.data[..24]);
}

#[test]
fn export_without_a_target_is_an_error() {
    let (_keep, root) = fitted();
    let out = omnical(&["export", "--model", "fit.toml", "sim/validation/07-r0.mcap"], root);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nothing to export: give --tum DIR and/or --mcap DIR"));
}
