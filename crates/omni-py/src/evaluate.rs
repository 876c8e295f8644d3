//! `evaluate` (costs and per-run residuals as arrays) and `integrate` (one run's odometry path).

use crate::arrays::{to_matrix, to_vector};
use crate::errors::{PyResultExt, value_error};
use crate::robot::{check_order, model_spec, per_run};
use crate::run::{PyRun, origin_of, runs_from};
use numpy::{PyArray1, PyArray2};
use omni_kin::cost::{self, CostKind};
use omni_kin::odometry::{self, Residual};
use omni_kin::relative::{RelativeErrors, RpeSummary};
use omni_kin::{PoseError, RpeDelta, Stats};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use std::path::PathBuf;

/// One run's residuals at every ground-truth pose after the first.
///
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)
/// >>> r = omnical.evaluate("paper", runs).runs[0]
/// >>> r.name, r.error.shape == (len(r.t_s), 3), r.end_error.shape
/// ('train/00-r0', True, (3,))
#[pyclass(frozen, name = "RunResiduals", module = "omnical._omnical")]
pub struct PyRunResiduals {
    /// Run name.
    #[pyo3(get)]
    name: String,
    /// RMS of the pose errors over the path [m, with 1 m/rad for heading].
    #[pyo3(get)]
    path_rms: f64,
    residuals: Vec<Residual>,
    end: PoseError,
    rpe: RpeSummary,
}

/// `mean`, `median`, `rmse`, `max` (NaN where there was no value).
fn stats_dict<'py>(py: Python<'py>, s: Stats) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in [("mean", s.mean), ("median", s.median), ("rmse", s.rmse), ("max", s.max)] {
        d.set_item(k, v)?;
    }
    Ok(d)
}

/// The relative pose error of some pairs as `omnical eval --json`'s `rpe` object (without the window).
fn rpe_dict<'py>(py: Python<'py>, s: &RpeSummary) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("pairs", s.pairs)?;
    d.set_item("translation_m", stats_dict(py, s.translation_m)?)?;
    d.set_item("rotation_rad", stats_dict(py, s.rotation_rad)?)?;
    d.set_item("drift_pairs", s.drift_pairs)?;
    d.set_item("drift_pct", stats_dict(py, s.drift_pct)?)?;
    Ok(d)
}

#[pymethods]
impl PyRunResiduals {
    /// (K,) times of the ground-truth poses [s].
    #[getter]
    fn t_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_vector(py, self.residuals.iter().map(|r| r.t_s).collect())
    }
    /// (K,) indices of those poses in the run's ``truth``.
    #[getter]
    fn truth_index(&self) -> Vec<usize> {
        self.residuals.iter().map(|r| r.truth_index).collect()
    }
    /// (K, 3) predicted poses of the measured point: x_m [m], y_m [m], theta_rad [rad].
    #[getter]
    fn predicted<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = self.residuals.iter().flat_map(|r| [r.predicted.x_m, r.predicted.y_m, r.predicted.theta_rad]);
        to_matrix(py, self.residuals.len(), 3, d.collect())
    }
    /// (K, 3) predicted minus measured: dx_m [m], dy_m [m], dtheta_rad [rad] (world frame, heading wrapped).
    #[getter]
    fn error<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = self.residuals.iter().flat_map(|r| [r.error.dx_m, r.error.dy_m, r.error.dtheta_rad]);
        to_matrix(py, self.residuals.len(), 3, d.collect())
    }
    /// (3,) end-pose error dx_m, dy_m, dtheta_rad (the run's term of Eq. 6).
    #[getter]
    fn end_error<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_vector(py, vec![self.end.dx_m, self.end.dy_m, self.end.dtheta_rad])
    }
    /// The run's relative pose error over the evaluation's window, as ``omnical eval --json``'s
    /// ``runs[].rpe``: ``pairs``, ``translation_m`` [m] and ``rotation_rad`` [rad] (each ``mean``,
    /// ``median``, ``rmse``, ``max``), ``drift_pairs``, ``drift_pct`` [% of distance].
    #[getter]
    fn rpe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        rpe_dict(py, &self.rpe)
    }
    fn __repr__(&self) -> String {
        format!("RunResiduals({:?}, {} poses, path RMS {:.4})", self.name, self.residuals.len(), self.path_rms)
    }
}

/// Costs of a model on runs, and each run's residuals.
///
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)
/// >>> ev = omnical.evaluate("paper", runs)  # the true robot: what remains is measurement noise
/// >>> ev.end_errors.shape, ev.names[0], ev.path_cost < 0.01
/// ((36, 3), 'train/00-r0', True)
#[pyclass(frozen, name = "Evaluation", module = "omnical._omnical")]
pub struct PyEvaluation {
    /// The paper's Eq. 6: mean end-pose error (m and rad mixed).
    #[pyo3(get)]
    cost: f64,
    /// RMS error over every ground-truth pose [m, with 1 m/rad].
    #[pyo3(get)]
    path_cost: f64,
    runs: Vec<Py<PyRunResiduals>>,
    rpe_delta: RpeDelta,
    rpe: RpeSummary,
}

#[pymethods]
impl PyEvaluation {
    /// Per-run residuals, in run order.
    #[getter]
    fn runs(&self, py: Python<'_>) -> Vec<Py<PyRunResiduals>> {
        self.runs.iter().map(|r| r.clone_ref(py)).collect()
    }
    /// Run names, in run order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.runs.iter().map(|r| r.get().name.clone()).collect()
    }
    /// (R, 3) end-pose errors of all runs: dx_m, dy_m, dtheta_rad.
    #[getter]
    fn end_errors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = self.runs.iter().flat_map(|r| {
            let e = r.get().end;
            [e.dx_m, e.dy_m, e.dtheta_rad]
        });
        to_matrix(py, self.runs.len(), 3, d.collect())
    }
    /// The relative pose error over every pair of every run, as ``omnical eval --json``'s ``rpe``:
    /// ``delta`` and ``delta_unit`` (``"m"`` travelled or ``"s"``), ``pairs``, ``translation_m`` [m],
    /// ``rotation_rad`` [rad] (each ``mean``, ``median``, ``rmse``, ``max``), ``drift_pairs``,
    /// ``drift_pct`` [% of distance].
    #[getter]
    fn rpe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = rpe_dict(py, &self.rpe)?;
        d.set_item("delta", self.rpe_delta.value())?;
        d.set_item("delta_unit", self.rpe_delta.unit())?;
        Ok(d)
    }
    fn __repr__(&self) -> String {
        format!("Evaluation(Eq. 6 cost {:.5}, path cost {:.5}, {} runs)", self.cost, self.path_cost, self.runs.len())
    }
}

/// Evaluate a model on runs, as ``omnical eval --model MODEL RUNS``: the Eq. 6 cost, the path cost, the
/// relative pose error over ``rpe_delta`` (``--rpe-delta``: ``"1m"`` travelled, or a time as ``"2s"``;
/// evo_rpe's consecutive pairs on the ground truth), and per-run residuals as arrays.
///
/// ``model``: an :class:`omnical.Model`, ``"design"`` (the design model of ``robot``, a ``robot.toml`` path
/// or ``"apr02"``, else of the data's robot: a Dataset's ``design``, each run its own input's when the
/// inputs declare different designs, the pooled costs then the run-weighted means of the runs' own; with
/// none of them ``ValueError`` says how to describe the robot), ``"paper"`` (Eq. 9) or a model file path.
/// The GIL is released.
///
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)
/// >>> ev = omnical.evaluate("design", runs, robot="apr02")  # the design (Eq. 7) on the true Eq. 9 robot
/// >>> round(ev.path_cost, 3), len(ev.runs), ev.runs[0].error.shape[1]
/// (0.016, 36, 3)
#[pyfunction]
#[pyo3(signature = (model, runs, *, robot = None, rpe_delta = "1m"))]
pub fn evaluate(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    runs: &Bound<'_, PyAny>,
    robot: Option<PathBuf>,
    rpe_delta: &str,
) -> PyResult<PyEvaluation> {
    check_order(model, runs, "omnical.evaluate")?;
    let delta: RpeDelta = rpe_delta.parse().map_err(|e| value_error(format!("rpe_delta={rpe_delta:?}: {e}")))?;
    let origin = origin_of(runs);
    let (runs, design) = runs_from(runs, "runs")?;
    let (fm, adapters, spelled) = model_spec(py, model, robot.as_ref(), design, "omnical.evaluate")?;
    // `"design"`: each run its own input's design, as the CLI's `eval --model design`.
    let models = per_run(fm, &spelled, robot.as_ref(), &origin)?;
    let errors = crate::effect::EffectErrors::new(adapters);
    let out = py.detach(|| -> Result<_, omni_kin::KinError> {
        let selection = CostKind::PATH.selection();
        let errors = models.errors(&runs, selection)?;
        let relative = RelativeErrors::new(&runs, &errors, delta)?;
        let residuals = runs
            .par_iter()
            .map(|r| {
                let fm = models.for_run(r)?;
                Ok(odometry::residuals(&fm.model.resolve(&fm.params)?, r, selection))
            })
            .collect::<Result<Vec<Vec<Residual>>, omni_kin::KinError>>()?;
        Ok((errors, residuals, relative))
    });
    let (errors, residuals, relative) = errors.check(out)?.py()?;
    let w = CostKind::PATH.heading_weight();
    let per_run = runs
        .iter()
        .zip(residuals)
        .enumerate()
        .map(|(i, (r, residuals))| {
            let (path_rms, end) = (cost::path_rms(errors.run(i)), errors.ends()[i]);
            let rpe = relative.run_summary(i);
            Py::new(py, PyRunResiduals { name: r.name().to_string(), path_rms, residuals, end, rpe })
        })
        .collect::<PyResult<_>>()?;
    let (c, path, runs) = (errors.end_pose_cost(), errors.path_cost(w), per_run);
    Ok(PyEvaluation { cost: c, path_cost: path, runs, rpe_delta: delta, rpe: relative.summary() })
}

/// Integrate one run's wheel speeds through a model, from its first ground-truth pose. ``model`` as in
/// :func:`evaluate` (``"design"`` needs ``robot``: a single run names no robot). Returns (N, 4): t_s [s],
/// x_m [m], y_m [m], theta_rad [rad] of the measured point at the sample times.
///
/// >>> run = omnical.simulate(runs_per_command=1, duration_s=1.0)[0]
/// >>> path = omnical.integrate("paper", run)
/// >>> path.shape[1], bool(np.isfinite(path).all())
/// (4, True)
#[pyfunction]
#[pyo3(signature = (model, run, *, robot = None))]
pub fn integrate<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    run: &Bound<'py, PyAny>,
    robot: Option<PathBuf>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    check_order(model, run, "omnical.integrate")?;
    let run = run
        .cast::<PyRun>()
        .map_err(|_| pyo3::exceptions::PyTypeError::new_err("omnical.integrate: run must be an omnical.Run"))?
        .get()
        .inner
        .clone();
    let (fm, adapters, _) = model_spec(py, model, robot.as_ref(), None, "omnical.integrate")?;
    let errors = crate::effect::EffectErrors::new(adapters);
    let traj = py.detach(|| -> Result<_, omni_kin::KinError> {
        cost::check_runs(&fm.model, std::slice::from_ref(&run))?;
        let res = fm.model.resolve(&fm.params)?;
        Ok(odometry::integrate(&res, &run))
    });
    let traj = errors.check(traj)?.py()?;
    let d = traj.t_s.iter().zip(&traj.poses).flat_map(|(t, p)| [*t, p.x_m, p.y_m, p.theta_rad]).collect();
    to_matrix(py, traj.t_s.len(), 4, d)
}
