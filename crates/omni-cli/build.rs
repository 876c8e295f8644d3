//! Tells the tests which optional Python test tools are installed, so that a test that cannot run is
//! reported as ignored (with the reason) in cargo's summary instead of passing without doing anything.
//! `bash scripts/test.sh` installs them (requirements-dev.txt) and points `OMNICAL_PYTHON` at them.

use std::path::Path;
use std::process::Command;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(python_bag_tools)");
    println!("cargo::rustc-check-cfg=cfg(python_evo)");
    println!("cargo::rerun-if-env-changed=OMNICAL_PYTHON");
    let python = std::env::var("OMNICAL_PYTHON").unwrap_or_else(|_| "python3".into());
    // A venv that gains packages later is seen again: its site-packages folder changes.
    if let Some(venv) = Path::new(&python).parent().and_then(Path::parent) {
        for lib in ["lib", "Lib"] {
            if venv.join(lib).exists() {
                println!("cargo::rerun-if-changed={}", venv.join(lib).display());
            }
        }
    }
    let imports = |modules: &str| {
        Command::new(&python).args(["-c", &format!("import {modules}")]).output().is_ok_and(|o| o.status.success())
    };
    if imports("rosbags, mcap, mcap_ros2, numpy") {
        println!("cargo::rustc-cfg=python_bag_tools");
    }
    let evo = Path::new(&python).parent().is_some_and(|bin| bin.join("evo_ape").exists());
    if evo {
        println!("cargo::rustc-cfg=python_evo");
    }
}
