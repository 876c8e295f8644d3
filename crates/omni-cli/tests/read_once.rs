//! A recording with a lidar reference is read once (issue 47 item 2): its scans and static transforms are
//! gathered in the same pass over its messages as the wheels (they were read in a second pass), and the
//! size limit (`--max-file-mb`) applies to that one read. One test in this binary: the pass counter is the
//! process's.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use omni_cli::api::load::{DataOptions, LoadRequest};
use omni_cli::dataset::message_passes;
use support::{succeeded, test_data};

#[test]
fn a_recording_with_a_lidar_reference_is_read_once_within_the_size_limit() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let robot = test_data("diff_robot.toml");
    let args = ["simulate", "--robot", robot.to_str().unwrap(), "--out", "sim", "--runs-per-command", "1"];
    let lidar = ["--lidar", "room", "--lidar-mount", "0.2,0.05,0", "--duration", "4", "-q"];
    succeeded(&[&args[..], &lidar].concat(), d);
    let train = d.join("sim/train");
    let recordings = std::fs::read_dir(&train)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "mcap"))
        .count();
    assert!(recordings > 0);
    let data = DataOptions { gt_scans: Some("/scan".into()), ..DataOptions::default() };
    let before = message_passes();
    let ds = LoadRequest::new(std::slice::from_ref(&train), &data).load().unwrap();
    assert_eq!(message_passes() - before, recordings, "passes over {recordings} recordings");
    assert!(!ds.runs.is_empty());
    // The one read honours the size limit (0 MB: every recording is larger).
    let small = DataOptions { max_file_mb: 0, ..data };
    let e = match LoadRequest::new(&[train], &small).load() {
        Ok(_) => panic!("a recording above the size limit was read"),
        Err(e) => e.to_string(),
    };
    // The library names the setting; the command line spells it as its flag.
    assert!(e.contains("`max_file_mb`"), "{e}");
    assert!(omni_cli::api::settings::as_flags(&e).contains("--max-file-mb"), "{e}");
}
