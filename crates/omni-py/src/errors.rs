//! Rust errors as Python exceptions, in one place. Messages are the Rust `Display` text, with the settings it
//! names as Python keywords ([`keywords`]).
//!
//! | Rust | Python |
//! |---|---|
//! | bad shape, NaN, non-increasing stamps, unknown name (`KinError`, no runs or a bad plan request (`omni_ga::Error`), binding checks) | `ValueError` |
//! | a file that does not exist | `FileNotFoundError` |
//! | other I/O | `OSError` |
//! | `DatasetError` (a file that does not parse or does not make runs) | `omnical.DatasetError` |
//! | `ModelFileError` (parse / invalid contents) | `omnical.ModelFileError` |
//! | `OptimizeError` (an optimizer refused its inputs); a refused fit (`train`: a fixed step that misses the runs' sampling, a fit worse than its start) | `omnical.CalibrationError` |
//! | `SimulateError` (`simulate`'s sensors and files): a room file that does not exist, else as the cause (`DatasetError`, `OSError`); bad sensor settings, a run that leaves the lidar's room | `FileNotFoundError`, `omnical.DatasetError`, `OSError`; `ValueError` |
//! | `ImuError` (`imu`): the IMU topic missing or unreadable, no recording, an IMU upside down or on its side with no mount stated, a gyro or wheels in another unit (deg/s); the wheels not read; too little turn or a bad window; no design; `out` not writable | `omnical.DatasetError` (`FileNotFoundError` for a path that does not exist); as `load`'s; `ValueError`; `ValueError`; `FileNotFoundError`, `OSError`, else `omnical.OmnicalError` |
//! | a report or export that fails ([`file_error`]: the first `io::Error` among the error's sources) | `FileNotFoundError`, `OSError`, else `omnical.OmnicalError`; an export folder that already holds files: `FileExistsError` |
//!
//! All omnical-specific exceptions derive from `omnical.OmnicalError`. A message made of an error and its
//! sources is [`chain_text`]: the CLI's `error: …` text. The settings the library names in its messages
//! (`` `gt_scans` ``) are Python's keywords here (`gt_scans=`), in one place: [`keywords`].

use omni_cli::api::imu::ImuError;
use omni_cli::api::simulate::SimulateError;
use omni_cli::dataset::DatasetError as RsDatasetError;
use omni_cli::design::DesignError;
use omni_cli::model_file::ModelFileError as RsModelFileError;
use omni_ga::{Error as GaError, OptimizeError};
use omni_kin::KinError;
use pyo3::exceptions::{PyException, PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::{PyErr, create_exception};

create_exception!(
    omnical,
    OmnicalError,
    PyException,
    "Base class of omnical's own exceptions.\n\n>>> issubclass(omnical.DatasetError, omnical.OmnicalError)\nTrue"
);
create_exception!(
    omnical,
    DatasetError,
    OmnicalError,
    "A data file could not be read as runs (the message names the file, place and field).\n\n\
     >>> import tempfile, pathlib\n\
     >>> bad = pathlib.Path(tempfile.mkdtemp()) / \"run.csv\"\n\
     >>> _ = bad.write_text(\"t_s,wheel_a\\n0.0,nan\\n\")\n\
     >>> try:\n\
     ...     omnical.load(bad)\n\
     ... except omnical.DatasetError as e:\n\
     ...     print(\"DatasetError:\", \"run.csv\" in str(e))\n\
     DatasetError: True"
);
create_exception!(
    omnical,
    ModelFileError,
    OmnicalError,
    "A model file is not valid TOML or not a valid model.\n\n\
     >>> import tempfile, pathlib\n\
     >>> bad = pathlib.Path(tempfile.mkdtemp()) / \"model.toml\"\n\
     >>> _ = bad.write_text(\"kinematics = 3\\n\")\n\
     >>> try:\n\
     ...     omnical.load_model(bad)\n\
     ... except omnical.ModelFileError as e:\n\
     ...     print(\"ModelFileError:\", \"model.toml\" in str(e))\n\
     ModelFileError: True"
);
create_exception!(
    omnical,
    CalibrationError,
    OmnicalError,
    "An optimizer refused its inputs or settings, or train refused a fit: a preset whose fixed step misses \
     the runs' sampling, or a fitted model worse than its start on its own training runs (force=True keeps \
     it).\n\n\
     >>> issubclass(omnical.CalibrationError, omnical.OmnicalError)\n\
     True"
);

/// Conversion of a Rust error into the matching Python exception.
pub trait ToPyErr {
    /// The exception, carrying the Rust message.
    fn to_py_err(self) -> PyErr;
}

/// `?`-friendly conversion: `result.py()?`.
pub trait PyResultExt<T> {
    /// Maps the error with [`ToPyErr`].
    fn py(self) -> pyo3::PyResult<T>;
}

impl<T, E: ToPyErr> PyResultExt<T> for Result<T, E> {
    fn py(self) -> pyo3::PyResult<T> {
        self.map_err(ToPyErr::to_py_err)
    }
}

pub(crate) fn io_error(message: String, error: &std::io::Error) -> PyErr {
    match error.kind() {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

impl ToPyErr for KinError {
    fn to_py_err(self) -> PyErr {
        PyValueError::new_err(keywords(&self.to_string()))
    }
}

impl ToPyErr for OptimizeError {
    fn to_py_err(self) -> PyErr {
        CalibrationError::new_err(keywords(&self.to_string()))
    }
}

impl ToPyErr for GaError {
    fn to_py_err(self) -> PyErr {
        match self {
            GaError::Kin(e) => e.to_py_err(),
            GaError::Optimize(e) => e.to_py_err(),
            GaError::NoRuns | GaError::BadPlanRequest { .. } => PyValueError::new_err(keywords(&self.to_string())),
        }
    }
}

impl ToPyErr for RsDatasetError {
    fn to_py_err(self) -> PyErr {
        let message = keywords(&self.to_string());
        match &self {
            RsDatasetError::Io { error, .. } => io_error(message, error),
            _ => DatasetError::new_err(message),
        }
    }
}

impl ToPyErr for SimulateError {
    fn to_py_err(self) -> PyErr {
        let message = chain_text(&self);
        match &self {
            SimulateError::Room(RsDatasetError::Io { error, .. })
            | SimulateError::Dataset(RsDatasetError::Io { error, .. }) => io_error(message, error),
            SimulateError::Room(_) | SimulateError::Dataset(_) => DatasetError::new_err(message),
            SimulateError::CreateDir { .. } | SimulateError::WriteRobot { .. } => file_error(&self),
            _ => PyValueError::new_err(message),
        }
    }
}

impl ToPyErr for ImuError {
    fn to_py_err(self) -> PyErr {
        match self {
            ImuError::Load(e) => crate::run::load_error(e),
            ImuError::Dataset(e) => e.to_py_err(),
            ImuError::NoRecording
            | ImuError::UpsideDown { .. }
            | ImuError::OnItsSide { .. }
            | ImuError::Units { .. } => DatasetError::new_err(keywords(&self.to_string())),
            ImuError::Design(DesignError::NoDesign(_)) => crate::robot::no_design("omnical.imu"),
            ImuError::Fit { .. } | ImuError::Design(_) | ImuError::Kin(_) => PyValueError::new_err(chain_text(&self)),
            ImuError::OutPath(_) | ImuError::ModelText(_) | ImuError::Write { .. } => file_error(&self),
            ImuError::Model(_) => ModelFileError::new_err(chain_text(&self)),
        }
    }
}

impl ToPyErr for RsModelFileError {
    fn to_py_err(self) -> PyErr {
        let message = keywords(&self.to_string());
        match &self {
            RsModelFileError::Io { error, .. } => io_error(message, error),
            _ => ModelFileError::new_err(message),
        }
    }
}

/// An error and its sources, each joined to the one before by `: `: the text the command line prints after
/// `error: `, so that Python and the CLI say the same.
pub fn chain_text(e: &(dyn std::error::Error + 'static)) -> String {
    keywords(&chain_text_as_written(e))
}

/// An error and its sources as [`chain_text`], the settings it names as the command line's flags: for the
/// commands Python runs with command-line arguments (the fleet's sessions).
pub fn chain_text_as_flags(e: &(dyn std::error::Error + 'static)) -> String {
    omni_cli::api::settings::as_flags(&chain_text_as_written(e))
}

/// An error and its sources as [`chain_text`], with the library's words for its settings as written.
fn chain_text_as_written(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text.push_str(": ");
        text.push_str(&c.to_string());
        cause = c.source();
    }
    text
}

/// `text` with the settings the library names (`` `gt_scans` ``, `` `force` ``, `` `preset=default` ``) as
/// Python's keywords (`gt_scans=`, `force=True`, `preset="default"`): the binding's one mapping of the
/// library's words, for every exception and warning ([`omni_cli::api::settings::as_keywords`]).
pub fn keywords(text: &str) -> String {
    omni_cli::api::settings::as_keywords(text)
}

/// The first OS error among `e` and its sources, if any.
fn io_cause<'e>(e: &'e (dyn std::error::Error + 'static)) -> Option<&'e std::io::Error> {
    std::iter::successors(Some(e), |c| c.source()).find_map(|c| c.downcast_ref::<std::io::Error>())
}

/// `e` as `FileNotFoundError` when an OS error among its sources is "not found", `OSError` for another OS
/// error, else `omnical.OmnicalError`; the message is [`chain_text`].
pub fn file_error(e: &(dyn std::error::Error + 'static)) -> PyErr {
    let message = chain_text(e);
    match io_cause(e) {
        Some(io) if io.kind() == std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        Some(_) => PyOSError::new_err(message),
        None => OmnicalError::new_err(message),
    }
}

/// An output folder refused or not written: `FileExistsError` for one that already holds files (without
/// `force`), `ValueError` for one that holds or lies inside an input (whatever `force`) or that `force` will
/// not replace (the folder of the working directory, the home folder), else as its cause. A refusal for a
/// keyword (`out=`, `tum=`) says `force=True` ([`keywords`]); one for a command line's flag (`--out`, the
/// fleet's commands) says `--force`, as the command line does.
pub fn out_error(e: omni_cli::out_path::OutPathError) -> PyErr {
    use omni_cli::out_path::OutPathError;
    let flag = match &e {
        OutPathError::NotEmpty { flag, .. }
        | OutPathError::OverlapsInput { flag, .. }
        | OutPathError::HoldsWorkingDirectory { flag, .. }
        | OutPathError::Home { flag, .. } => flag.starts_with("--"),
        _ => false,
    };
    let text = || {
        let text = chain_text_as_written(&e);
        if flag { omni_cli::api::settings::as_flags(&text) } else { keywords(&text) }
    };
    match e {
        OutPathError::NotEmpty { .. } => pyo3::exceptions::PyFileExistsError::new_err(text()),
        OutPathError::OverlapsInput { .. } | OutPathError::HoldsWorkingDirectory { .. } | OutPathError::Home { .. } => {
            value_error(text())
        }
        ref other => file_error(other),
    }
}

/// A `ValueError` with this message (bad shapes, bad option values).
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(keywords(&message.into()))
}
