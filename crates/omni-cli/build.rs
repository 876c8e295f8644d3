//! Tells the tests which optional inputs are here, so that a test that cannot run is reported as ignored
//! (with the reason) in cargo's summary instead of passing without doing anything (a test cannot ignore
//! itself at run time):
//! - the Python test tools: `bash scripts/test.sh` installs them (requirements-dev.txt) and points
//!   `OMNICAL_PYTHON` at them (`cfg(python_bag_tools)`, `cfg(python_evo)`);
//! - the real robot logs `shared/data/optiodom-*-square`, beside the repository and not part of it
//!   (`cfg(shared_data)`, the folder in `OMNICAL_SHARED_DATA`). Looked for, in order: `$OMNICAL_SHARED_DATA`
//!   (a `data` folder), `../shared/data` beside the workspace, and, in a `git worktree`, `../shared/data`
//!   beside the main checkout.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The main checkout of a git worktree at `workspace` (its `.git` is a file `gitdir: MAIN/.git/worktrees/NAME`).
fn main_checkout(workspace: &Path) -> Option<PathBuf> {
    let text = std::fs::read_to_string(workspace.join(".git")).ok()?;
    let gitdir = PathBuf::from(text.strip_prefix("gitdir:")?.trim());
    let git = gitdir.ancestors().find(|a| a.file_name().is_some_and(|n| n == ".git"))?;
    git.parent().map(Path::to_path_buf)
}

/// `cfg(shared_data)` and `OMNICAL_SHARED_DATA` when the real robot logs are found.
fn shared_data() {
    println!("cargo::rustc-check-cfg=cfg(shared_data)");
    println!("cargo::rerun-if-env-changed=OMNICAL_SHARED_DATA");
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let workspace = manifest.join("../..");
    let mut candidates: Vec<PathBuf> = std::env::var_os("OMNICAL_SHARED_DATA").map(PathBuf::from).into_iter().collect();
    candidates.push(workspace.join("../shared/data"));
    candidates.extend(main_checkout(&workspace).map(|m| m.join("../shared/data")));
    if let Some(dir) = candidates.into_iter().find(|c| c.join("optiodom-omni3-square").is_dir()) {
        let dir = dir.canonicalize().unwrap_or(dir);
        println!("cargo::rustc-cfg=shared_data");
        println!("cargo::rustc-env=OMNICAL_SHARED_DATA={}", dir.display());
        // Seen again when the data goes away.
        println!("cargo::rerun-if-changed={}", dir.display());
    }
}

fn main() {
    shared_data();
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
