//! What goes wrong reading or writing a dataset ([`DatasetError`]: every variant names the file), inputs
//! skipped under `--skip-invalid`, and the size cap on one input file.

use omni_kin::KinError;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A file above the size cap is refused before it is read.
pub(crate) fn check_size(p: &Path, max_file_bytes: u64) -> Result<(), DatasetError> {
    let len = std::fs::metadata(p).map_err(|e| DatasetError::io(p, e))?.len();
    if len > max_file_bytes { Err(too_large(p, len, max_file_bytes)) } else { Ok(()) }
}

/// The error for a file of `len` bytes above the cap `max_file_bytes` (`--max-file-mb`).
pub(crate) fn too_large(p: &Path, len: u64, max_file_bytes: u64) -> DatasetError {
    DatasetError::file(
        p,
        format!(
            "the file is {:.1} MiB, above the limit of {:.1} MiB per input file (files are read into memory \
             whole); raise the limit with {} if the machine has the memory",
            len as f64 / MIB,
            max_file_bytes as f64 / MIB,
            crate::api::settings::named("max_file_mb")
        ),
    )
}

const MIB: f64 = (1u64 << 20) as f64;

/// An input that was skipped, and why.
#[derive(Debug, Clone)]
pub struct Skipped {
    /// File (and run within it).
    pub source: String,
    /// The full error message.
    pub reason: String,
}

/// What went wrong reading or writing a dataset. Every variant names the file.
#[derive(Debug, Error)]
pub enum DatasetError {
    /// The file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error (its text is in this message, so it is not chained again).
        error: std::io::Error,
    },
    /// A problem at a place in a file: a CSV line, an MCAP topic and message, a metadata key.
    #[error("{path}: {location}: {message}")]
    At {
        /// The file.
        path: PathBuf,
        /// Where in it: `line 12, column x_m`, `topic "/joint_states", message 88`.
        location: String,
        /// What is wrong.
        message: String,
    },
    /// A problem with the file as a whole.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A `--gt` file's clock could not be aligned with a recording's wheels from their motion (too short,
    /// too little motion, too sparse): [`super::load`] then uses the offset found on the other recordings read
    /// with the same ground truth, when there are any.
    #[error("{path}: {message}")]
    Clock {
        /// The ground-truth file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// The data parsed but does not form a valid run.
    #[error("{path}: {error}")]
    Run {
        /// The file.
        path: PathBuf,
        /// The validation error (names run, sample and field).
        error: KinError,
    },
}

impl DatasetError {
    /// An error at a place in a file.
    pub fn at(path: &Path, location: impl Into<String>, message: impl Into<String>) -> Self {
        Self::At { path: path.to_path_buf(), location: location.into(), message: message.into() }
    }
    /// An error about a whole file.
    pub fn file(path: &Path, message: impl Into<String>) -> Self {
        Self::File { path: path.to_path_buf(), message: message.into() }
    }
    /// An I/O error on a file.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Self::Io { path: path.to_path_buf(), error: source }
    }
}
