//! Datasets: runs loaded from files (CSV, OptiOdom folders, ROS 2 MCAP bags) and written back.
//!
//! Every error names the file and, where it applies, the line, topic, message, run and field.

pub mod csv;
pub mod mcap;
pub mod optiodom;

use omni_kin::{KinError, RobotGeometry, Run};
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
    /// The design geometry the data declares (OptiOdom metadata), if any.
    pub robot: Option<RobotGeometry>,
    /// The robot description the data was read with (`--robot`, or a `robot.toml` found beside it), if any.
    /// Set by the command line, not by [`load`].
    pub robot_file: Option<crate::robot_file::RobotFile>,
}

/// The default cap on one input file's size (`--max-file-mb`). Bytes: 1 GiB.
pub const DEFAULT_MAX_FILE_BYTES: u64 = 1 << 30;

/// How to load.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Skip runs that fail (listed in [`Dataset::skipped`]) instead of stopping.
    pub skip_invalid: bool,
    /// Encoder ticks per wheel revolution for CSV tick columns (overrides the file).
    pub ticks_per_rev: Option<f64>,
    /// How to read MCAP bags (topics, joint names, frames, splitting).
    pub mcap: mcap::McapOptions,
    /// Keep the robot's recorded odometry (MCAP `/odom`, CSV odometry columns) in the runs; overrides
    /// [`mcap::McapOptions::recorded_odometry`]. Calibration never reads it and it takes as much memory as
    /// the wheel data. Default true.
    pub recorded_odometry: bool,
    /// Refuse a CSV or MCAP file larger than this: each is read into memory whole (MCAP chunks are then
    /// decompressed one at a time), so the cap keeps a huge or mistaken input from exhausting memory.
    /// Bytes. Default [`DEFAULT_MAX_FILE_BYTES`].
    pub max_file_bytes: u64,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            skip_invalid: false,
            ticks_per_rev: None,
            mcap: mcap::McapOptions::default(),
            recorded_odometry: true,
            max_file_bytes: DEFAULT_MAX_FILE_BYTES,
        }
    }
}

/// Supported inputs, for messages.
pub const SUPPORTED: &str = ".csv (omnical run), .mcap (ROS 2 bag), or a folder of them / an OptiOdom set folder";

/// Load runs from files and folders, in the order given (folders: files sorted by name).
pub fn load(paths: &[PathBuf], opts: &LoadOptions) -> Result<Dataset, DatasetError> {
    let mut ds = Dataset::default();
    for p in paths {
        load_path(p, opts, &mut ds)?;
    }
    if ds.runs.is_empty() {
        let what = paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
        return Err(match ds.skipped.first() {
            Some(s) => DatasetError::file(
                Path::new(&what),
                format!("no valid runs ({} skipped; first: {}: {})", ds.skipped.len(), s.source, s.reason),
            ),
            None => DatasetError::file(Path::new(&what), format!("no runs found (expected {SUPPORTED})")),
        });
    }
    Ok(ds)
}

fn keep_or_fail(ds: &mut Dataset, opts: &LoadOptions, source: &Path, e: DatasetError) -> Result<(), DatasetError> {
    if opts.skip_invalid {
        ds.skipped.push(Skipped { source: source.display().to_string(), reason: e.to_string() });
        Ok(())
    } else {
        Err(e)
    }
}

fn load_path(p: &Path, opts: &LoadOptions, ds: &mut Dataset) -> Result<(), DatasetError> {
    let meta = std::fs::metadata(p).map_err(|e| DatasetError::io(p, e))?;
    if meta.is_dir() {
        if optiodom::metadata_file(p).is_some() {
            let mut skipped = Vec::new();
            let (runs, robot) = optiodom::read_set(p, |e| {
                if opts.skip_invalid {
                    skipped.push(Skipped { source: p.display().to_string(), reason: e.to_string() });
                    Ok(())
                } else {
                    Err(e)
                }
            })?;
            ds.skipped.extend(skipped);
            ds.runs.extend(runs);
            ds.robot = Some(robot);
            return Ok(());
        }
        let mut entries: Vec<PathBuf> = std::fs::read_dir(p)
            .map_err(|e| DatasetError::io(p, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|q| q.is_dir() || q.extension().is_some_and(|e| e == "csv" || e == "mcap"))
            .collect();
        entries.sort();
        for e in entries {
            load_path(&e, opts, ds)?;
        }
        return Ok(());
    }
    let ext = p.extension().and_then(|e| e.to_str());
    if matches!(ext, Some("csv" | "mcap")) && meta.len() > opts.max_file_bytes {
        return Err(DatasetError::file(
            p,
            format!(
                "the file is {:.1} MiB, above the limit of {:.1} MiB per input file (files are read into memory \
                 whole); raise the limit with --max-file-mb if the machine has the memory",
                meta.len() as f64 / MIB,
                opts.max_file_bytes as f64 / MIB
            ),
        ));
    }
    match ext {
        Some("csv") => match csv::read_run(p, opts.ticks_per_rev) {
            Ok(r) if opts.recorded_odometry => ds.runs.push(r),
            Ok(r) => ds.runs.push(r.without_recorded_odometry()),
            Err(e) => keep_or_fail(ds, opts, p, e)?,
        },
        Some("mcap") => {
            let mo = mcap::McapOptions {
                skip_invalid: opts.skip_invalid,
                recorded_odometry: opts.recorded_odometry,
                ..opts.mcap.clone()
            };
            match mcap::read_file(p, &mo) {
                Ok(r) => {
                    ds.runs.extend(r.runs);
                    ds.notes.extend(r.notes);
                    ds.skipped.extend(r.skipped.into_iter().map(|(source, reason)| Skipped { source, reason }));
                }
                Err(e) => keep_or_fail(ds, opts, p, e)?,
            }
        }
        _ => return Err(DatasetError::file(p, format!("unsupported input (expected {SUPPORTED})"))),
    }
    Ok(())
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
