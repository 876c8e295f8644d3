//! Helpers of the rosbag2 tests (`rosbag2`, `rosbag2_init`; included with `#[path]`): the recordings Python
//! `rosbags` writes in every layout (once per test binary), and the binary run with its exit status.
#![allow(dead_code)]

use crate::support::{expected_json, made_by_python, omnical_command, stderr, stdout};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The recordings and their expected values.
pub fn fixtures() -> &'static (PathBuf, Value) {
    static FIXTURES: OnceLock<(PathBuf, Value)> = OnceLock::new();
    FIXTURES.get_or_init(|| {
        // One folder per test binary (`rosbag2`, `rosbag2_init`), so that none writes into another's.
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(concat!(env!("CARGO_CRATE_NAME"), "_recordings"));
        let dir = made_by_python("rosbag2/make_recordings.py", dir);
        let expected = expected_json(&dir);
        (dir, expected)
    })
}

pub const LAYOUTS: [&str; 7] =
    ["mcap", "db3", "split_mcap", "split_db3", "db3_file_zstd", "db3_message_zstd", "mcap_message_zstd"];

/// `omnical ARGS` in the package's folder (as `cargo test` runs it), without backtraces: exit status, stdout,
/// stderr.
pub fn exit_code_and_output(args: &[&str]) -> (i32, String, String) {
    let out = omnical_command(args, Path::new(env!("CARGO_MANIFEST_DIR"))).env("RUST_BACKTRACE", "0").output().unwrap();
    (out.status.code().unwrap_or(-1), stdout(&out), stderr(&out))
}
