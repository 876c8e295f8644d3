//! What is wrong with a place for results ([`OutPathError`]): each variant names the option and the path it
//! gave, with the OS error chained as the source.

use crate::api::settings::named;
use std::path::PathBuf;

/// What is wrong with a place for results. Every variant names the option (`flag`: `--out`, `out=`) and
/// the path it gave; an OS error is chained as the source.
#[derive(Debug, thiserror::Error)]
pub enum OutPathError {
    /// A result file named a folder.
    #[error("{flag} {}: this is a folder; give a file name in it", path.display())]
    IsFolder {
        /// The option.
        flag: String,
        /// The path given.
        path: PathBuf,
    },
    /// A result file's folder does not exist.
    #[error(
        "{flag} {}: the folder {} does not exist (create it first: mkdir -p {})",
        path.display(),
        folder.display(),
        folder.display()
    )]
    NoFolder {
        /// The option.
        flag: String,
        /// The path given.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// A result folder named a file.
    #[error("{flag} {}: this is a file, not a folder", dir.display())]
    IsFile {
        /// The option.
        flag: String,
        /// The path given.
        dir: PathBuf,
    },
    /// No file can be created in `folder`, where the result `path` goes.
    #[error("{flag} {}: cannot write in {}", path.display(), folder.display())]
    CannotWriteIn {
        /// The option.
        flag: String,
        /// The path given.
        path: PathBuf,
        /// The folder that takes no files.
        folder: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// No file can be created in the result folder `dir` itself.
    #[error("{flag} {}: cannot write in it", dir.display())]
    CannotWrite {
        /// The option.
        flag: String,
        /// The folder.
        dir: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A folder could not be created.
    #[error("{flag}: creating {}", dir.display())]
    Create {
        /// The option.
        flag: String,
        /// The folder.
        dir: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A result folder's entries could not be listed.
    #[error("{flag}: reading {}", dir.display())]
    Read {
        /// The option.
        flag: String,
        /// The folder.
        dir: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A result folder already holds files, claimed without `--force`.
    #[error(
        "{flag} {}: the folder already holds files ({entries}); give {force} to replace it whole, or another {flag}",
        dir.display(),
        force = named("force")
    )]
    NotEmpty {
        /// The option.
        flag: String,
        /// The folder.
        dir: PathBuf,
        /// Some of its entries, for the message.
        entries: String,
    },
    /// A folder to replace could not be resolved to its canonical path.
    #[error("{flag} {}", dir.display())]
    Canonicalize {
        /// The option.
        flag: String,
        /// The folder.
        dir: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// `--force` on a folder that holds the working directory.
    #[error("{flag} {}: {} will not replace a folder that holds the working directory", dir.display(), named("force"))]
    HoldsWorkingDirectory {
        /// The option.
        flag: String,
        /// The folder.
        dir: PathBuf,
    },
    /// `--force` on the home folder.
    #[error("{flag} {}: {} will not replace the home folder", dir.display(), named("force"))]
    Home {
        /// The option.
        flag: String,
        /// The folder.
        dir: PathBuf,
    },
    /// A staging folder left by an earlier process with the same id could not be removed.
    #[error("removing {}", staging.display())]
    RemoveStaging {
        /// The staging folder.
        staging: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The new folder could not be renamed to the target.
    #[error("moving the results into {}", target.display())]
    MoveIn {
        /// The result folder.
        target: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The old folder could not be moved aside.
    #[error("moving the old {} aside", target.display())]
    MoveAside {
        /// The result folder.
        target: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A result folder holds, or lies inside, an input of the command (refused with or without `--force`).
    #[error(
        "{flag} {}: {relation} {what} {}, which this command reads; give {flag} a folder apart from its inputs \
         ({} never replaces an input)",
        dir.display(),
        input.display(),
        named("force")
    )]
    OverlapsInput {
        /// The option.
        flag: String,
        /// The folder.
        dir: PathBuf,
        /// `this folder holds` or `this folder is inside`.
        relation: &'static str,
        /// What the input is (`the data`, `--robot`).
        what: String,
        /// The input's path as given.
        input: PathBuf,
    },
    /// The old folder, moved aside, could not be removed.
    #[error("removing the old {} ({})", target.display(), old.display())]
    RemoveOld {
        /// The result folder.
        target: PathBuf,
        /// Where the old one was moved.
        old: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}
