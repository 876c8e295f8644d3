//! The library's output-folder rules (`omni_cli::out_path`, `omni_cli::atomic`) for omnical's pure-Python
//! parts (`omnical.fleet`), so that they follow the rules every omnical command follows instead of a copy:
//! a result folder of per-run files is claimed ([`PyOutDir`]: new or empty unless `force`, staged beside
//! and swapped in whole), a folder of fixed file names is prepared ([`_prepare_dir`]), a file is written
//! atomically ([`_write_atomic`]), and none of them may hold or lie inside an input, whatever `force`.
//!
//! Private (`_`-named): the rules' messages name the option as the caller spells it (`out=` from Python,
//! `--out` from a command line), so only omnical's own front ends call them.

use crate::errors::out_error;
use omni_cli::out_path::{Inputs, OutDir, check_apart, prepare_dir};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use std::path::PathBuf;

/// What the command reads, as `(what, path)` pairs (`("the data", "fleet/")`), and the project file in force.
fn inputs_from(pairs: Vec<(String, PathBuf)>) -> Inputs {
    pairs.into_iter().fold(Inputs::new(), |i, (what, path)| i.with(&what, path))
}

/// A result folder of per-run files claimed by the library's rule (``omnical simulate --out``'s): refused
/// when it holds or lies inside one of ``inputs`` (whatever ``force``), refused when it already holds files
/// unless ``force`` (then replaced whole at :meth:`commit`). Fill :attr:`path` (a staging folder beside the
/// target), then :meth:`commit` puts it in place with renames; :meth:`discard` (or leaving a ``with``
/// block without a commit) removes what was written and leaves the target as it was.
///
/// >>> import pathlib, tempfile
/// >>> target = pathlib.Path(tempfile.mkdtemp()) / "out"
/// >>> with omnical._omnical._OutDir.claim(target, flag="out=") as d:
/// ...     _ = (pathlib.Path(d.path) / "a.txt").write_text("a")
/// ...     d.commit()
/// >>> sorted(p.name for p in target.iterdir())
/// ['a.txt']
#[pyclass(name = "_OutDir", module = "omnical._omnical")]
pub struct PyOutDir {
    /// The claim until it is committed or discarded.
    inner: Option<OutDir>,
    /// Where the folder ends up.
    target: PathBuf,
}

impl PyOutDir {
    /// The claim still open, or `ValueError` naming what closed it.
    fn open(&self) -> PyResult<&OutDir> {
        self.inner.as_ref().ok_or_else(|| {
            PyValueError::new_err(format!("{}: this claim was already committed or discarded", self.target.display()))
        })
    }
}

#[pymethods]
impl PyOutDir {
    /// Claims ``target`` for the option ``flag`` (``"out="``, ``"--out"``: the refusals name it, and say
    /// ``force=True`` for a keyword, ``--force`` for a flag). ``inputs``: ``(what, path)`` pairs the
    /// command reads. ``FileExistsError`` for a folder that holds files without ``force``, ``ValueError``
    /// for one that holds or lies inside an input, ``OSError`` for a folder that takes no files.
    #[staticmethod]
    #[pyo3(signature = (target, *, flag, force = false, inputs = Vec::new()))]
    fn claim(target: PathBuf, flag: &str, force: bool, inputs: Vec<(String, PathBuf)>) -> PyResult<Self> {
        let inner = OutDir::claim(&target, flag, force, &inputs_from(inputs)).map_err(out_error)?;
        Ok(Self { inner: Some(inner), target })
    }

    /// The folder to write into now (a staging folder beside the target).
    #[getter]
    fn path(&self) -> PyResult<String> {
        Ok(self.open()?.path().display().to_string())
    }

    /// Where the folder ends up.
    #[getter]
    fn target(&self) -> String {
        self.target.display().to_string()
    }

    /// Puts the folder in place: an old one is moved aside, the new one renamed to the target, the old one
    /// removed.
    fn commit(&mut self) -> PyResult<()> {
        self.open()?;
        match self.inner.take() {
            Some(d) => d.commit().map_err(out_error),
            None => Ok(()),
        }
    }

    /// Removes what was written (nothing once committed); the target stays as it was.
    fn discard(&mut self) {
        self.inner = None;
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    /// Leaving a ``with`` block discards a claim that was not committed (an exception inside included).
    #[pyo3(signature = (*_exc))]
    fn __exit__(&mut self, _exc: &Bound<'_, pyo3::types::PyTuple>) -> bool {
        self.discard();
        false
    }
}

/// Makes the folder ``dir`` for results of fixed file names, as ``export --robot-config`` does: refused
/// (``ValueError``) when it holds or lies inside one of ``inputs`` (``(what, path)`` pairs), created with
/// its parents when missing, checked to take files; files already in it stay. ``flag`` names the option in
/// messages (``"out="``, ``"--out"``).
#[pyfunction]
#[pyo3(signature = (dir, *, flag, inputs = Vec::new()))]
pub fn _prepare_dir(dir: PathBuf, flag: &str, inputs: Vec<(String, PathBuf)>) -> PyResult<()> {
    check_apart(&dir, flag, &inputs_from(inputs)).map_err(out_error)?;
    prepare_dir(&dir, flag).map_err(out_error)
}

/// Writes ``data`` to ``path`` atomically, as every omnical result file is written: a temporary file in the
/// same folder (``.NAME.tmp-PID``), synced, then renamed over ``path``; a failure leaves the old file and no
/// temporary. ``OSError`` (``FileNotFoundError`` for a missing folder) names the path.
#[pyfunction]
pub fn _write_atomic(py: Python<'_>, path: PathBuf, data: Vec<u8>) -> PyResult<()> {
    py.detach(|| omni_cli::atomic::write_atomic(&path, &data)).map_err(|e| {
        let errno = e.raw_os_error().unwrap_or(0);
        PyOSError::new_err((errno, e.to_string(), path.display().to_string()))
    })
}
