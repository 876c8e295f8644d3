//! The fixture bags of the `mcap_rosbags` tests (included with `#[path]`): written once per test binary by
//! Python `rosbags` (`tests/mcap/make_bags.py`) with the values it wrote, and read back by name.
#![allow(dead_code)]

use crate::support::{expected_json, made_by_python};
use omni_cli::dataset::mcap::{McapOptions, McapRead, read_file};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The generated bags and their expected values (the tests using them are ignored, with the reason in
/// cargo's summary, when the Python tools are missing: see build.rs).
pub fn fixtures() -> &'static (PathBuf, Value) {
    static FIXTURES: OnceLock<(PathBuf, Value)> = OnceLock::new();
    FIXTURES.get_or_init(|| {
        // One folder per test binary (`mcap_rosbags`, `mcap_rosbags_errors`), so that none removes another's.
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(env!("CARGO_CRATE_NAME"));
        let _ = std::fs::remove_dir_all(&dir);
        let dir = made_by_python("mcap/make_bags.py", dir);
        let expected = expected_json(&dir);
        (dir, expected)
    })
}

macro_rules! fixtures_or_skip {
    () => {{
        let (dir, expected) = fixtures();
        (dir, expected)
    }};
}

/// `read_file`'s runs or its error, the settings it names as the command line's flags (as `omnical` says it).
pub fn read(dir: &Path, name: &str, opts: &McapOptions) -> Result<McapRead, String> {
    read_file(&dir.join(format!("{name}.mcap")), opts).map_err(|e| omni_cli::api::settings::as_flags(&e.to_string()))
}

pub fn read_ok(dir: &Path, name: &str) -> McapRead {
    read(dir, name, &McapOptions::default()).unwrap()
}

/// The error reading `name`, without the leading `<path>: `.
pub fn error(dir: &Path, name: &str, opts: &McapOptions) -> String {
    let e = read(dir, name, opts).unwrap_err();
    let prefix = format!("{}: ", dir.join(format!("{name}.mcap")).display());
    e.strip_prefix(&prefix).unwrap_or_else(|| panic!("{e:?} does not start with the path")).to_string()
}
