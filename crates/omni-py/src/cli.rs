//! The `omnical` console command of the wheel: the same entry point as the native binary.

use pyo3::prelude::*;
use std::ffi::OsString;

/// Run the ``omnical`` command line with ``argv`` (program name first); returns the exit status. The GIL
/// is released while it runs. Its output goes to the process's stdout and stderr.
///
/// >>> omnical._omnical.cli_main(["omnical", "eval", "no-such-run.csv"])  # "error: ..." on stderr
/// 2
#[pyfunction]
pub fn cli_main(py: Python<'_>, argv: Vec<String>) -> i32 {
    let args: Vec<OsString> = argv.into_iter().map(OsString::from).collect();
    py.detach(|| omni_cli::entry::main_with_args(args))
}
