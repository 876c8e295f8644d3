//! Datasets: runs loaded from files (CSV, OptiOdom folders, ROS 2 MCAP bags) and written back.
//!
//! Every error names the file and, where it applies, the line, topic, message, run and field.

pub mod mcap;

use omni_kin::{KinError, Run};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A set of runs, with what was skipped and what was noticed while loading.
#[derive(Debug, Default)]
pub struct Dataset {
    /// The runs, in the order their files were given.
    pub runs: Vec<Run>,
    /// Inputs skipped with `--skip-invalid`, with the reason.
    pub skipped: Vec<Skipped>,
    /// Things the user should know (e.g. "velocity empty: differentiated position").
    pub notes: Vec<String>,
}

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
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
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
    /// The data parsed but does not form a valid run.
    #[error("{path}: {source}")]
    Run {
        /// The file.
        path: PathBuf,
        /// The validation error (names run, sample and field).
        source: KinError,
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
        Self::Io { path: path.to_path_buf(), source }
    }
}
