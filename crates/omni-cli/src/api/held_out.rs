//! Guards for the held-out runs of `diagnose`, `report` and `explore`.
//!
//! `--validate` takes one path per flag. The older spelling `--validate V1 V2 TRAIN` still parses, but now
//! reads V2 as training runs. Two checks catch it honestly:
//! - **the same run on both sides** (the same recording content: wheel stamps and speeds and ground
//!   truth, whatever the file name) is an error: a model judged on runs it was fitted on says nothing
//!   about held-out error, whatever the spelling that led there;
//! - **a training path named like a held-out set** (`validation`, `val_2`, `heldout`, …) gets a warning
//!   with the right spelling: only a warning, since a name proves nothing.

use omni_kin::Run;
use std::collections::HashMap;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::{Path, PathBuf};

/// The spelling of a command's runs and held-out runs, for messages.
fn spelling(command: &str) -> String {
    format!(
        "--validate takes one path (repeat it for more) and the training runs come without a flag: omnical \
         {command} --model MODEL TRAIN_RUNS... --validate HELD_OUT [--validate HELD_OUT]..."
    )
}

/// A run's content: wheel stamps and speeds and ground-truth poses, bit for bit (the name left out).
fn content_hash(run: &Run) -> u64 {
    let mut h = DefaultHasher::new();
    run.n_wheels().hash(&mut h);
    for v in run.wheel_t_s().iter().chain(run.wheel_rad_s()) {
        v.to_bits().hash(&mut h);
    }
    for p in run.truth() {
        [p.t_s, p.pose.x_m, p.pose.y_m, p.pose.theta_rad].map(f64::to_bits).hash(&mut h);
    }
    h.finish()
}

/// Fails when a held-out run holds the same recording as a training run, naming both and the spelling
/// of `command` that keeps them apart.
pub fn check_disjoint(command: &str, train: &[Run], held_out: &[Run]) -> Result<(), SameRecording> {
    let by_hash: HashMap<u64, &Run> = train.iter().map(|r| (content_hash(r), r)).collect();
    for h in held_out {
        if let Some(t) = by_hash.get(&content_hash(h)) {
            return Err(SameRecording {
                held_out: h.name().to_string(),
                train: t.name().to_string(),
                command: command.to_string(),
            });
        }
    }
    Ok(())
}

/// A held-out run that holds the same recording as a training run.
#[derive(Debug, thiserror::Error)]
#[error(
    "held-out run {held_out} is the same recording as training run {train}: a model cannot be judged on runs it \
     was fitted on. {}",
    spelling(command)
)]
pub struct SameRecording {
    /// The held-out run.
    pub held_out: String,
    /// The training run with the same content.
    pub train: String,
    /// The command (`diagnose`), for the spelling that keeps them apart.
    pub command: String,
}

/// Words of a path's last component that name a held-out set.
const HELD_OUT_WORDS: [&str; 7] = ["val", "valid", "validation", "validate", "heldout", "holdout", "held"];

/// Whether a path's file or folder name reads like a held-out set (`validation`, `val2`, `held_out`).
pub fn named_like_held_out(path: &Path) -> bool {
    let name = path.file_name().map(|n| n.to_string_lossy().to_lowercase()).unwrap_or_default();
    name.split(|c: char| !c.is_ascii_alphabetic()).any(|w| HELD_OUT_WORDS.contains(&w))
}

/// The warning (without its `warning: ` prefix) for training paths named like a held-out set (`None` when there is none).
pub fn name_warning(command: &str, train_paths: &[PathBuf]) -> Option<String> {
    let odd: Vec<String> =
        train_paths.iter().filter(|p| named_like_held_out(p)).map(|p| p.display().to_string()).collect();
    (!odd.is_empty()).then(|| {
        format!(
            "{} {} read as training runs although named like a held-out set; {}",
            odd.join(", "),
            if odd.len() == 1 { "is" } else { "are" },
            spelling(command)
        )
    })
}

/// Both checks: the name warning as a `tracing` warning (stderr, shown also with `-q`), an error on shared
/// runs.
pub fn check(command: &str, train_paths: &[PathBuf], train: &[Run], held_out: &[Run]) -> Result<(), SameRecording> {
    if held_out.is_empty() {
        return Ok(());
    }
    if let Some(w) = name_warning(command, train_paths) {
        tracing::warn!("{w}");
    }
    check_disjoint(command, train, held_out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_out_names() {
        for p in ["sim/validation", "val", "runs_val2", "held-out", "HoldOut", "v/validate_b.mcap"] {
            assert!(named_like_held_out(Path::new(p)), "{p}");
        }
        for p in ["sim/train", "validation/train", "interval", "evaluation", "valve_test", "v1"] {
            assert!(!named_like_held_out(Path::new(p)), "{p}");
        }
        let w = name_warning("diagnose", &["sim/val2".into(), "sim/train".into()]).unwrap_or_default();
        assert!(w.starts_with("sim/val2 is read as training runs although named like a held-out set;"));
        assert_eq!(name_warning("diagnose", &["sim/train".into()]), None);
    }
}
