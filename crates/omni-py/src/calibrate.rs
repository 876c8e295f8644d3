//! `train`: fit a model to runs (the GA and Levenberg–Marquardt of omni-ga), with a progress callback and
//! Ctrl-C that stops the GA and keeps the best so far.

mod calibration;

pub use calibration::{_calibration_from_state, PyCalibration};

use crate::effect::{EffectErrors, effect_from};
use crate::errors::{CalibrationError, PyResultExt, value_error};
use crate::model::PyModel;
use crate::robot::{model_or_design, model_spec, robot_arg};
use crate::run::runs_from;
use calibration::Step;
use omni_cli::api::ModelSpec;
use omni_cli::api::fit::{FitOptions, Refused, check_step, prior_half_widths};
use omni_cli::api::train::{Fitted, Prepared, Recipe, TrainError, fit_prepared};
use omni_ga::calibrate::{Calibration, Plan, Preset};
use omni_ga::observe::{Control, Iteration, Observer};
use omni_kin::choice::UnknownChoice;
use omni_kin::effect::Effect;
use omni_kin::{FittedModel, KinematicsKind};
use pyo3::exceptions::{PyKeyboardInterrupt, PyUserWarning};
use pyo3::prelude::*;

/// Takes the GIL once per iteration (a GA generation evaluates a whole population, so this is cheap): checks
/// Ctrl-C, calls the progress callback, and stops when a Python effect has raised.
struct PyObserver<'a> {
    progress: Option<Py<PyAny>>,
    errors: &'a EffectErrors,
    history: Vec<Step>,
    interrupted: bool,
    stopped_by_callback: bool,
    failure: Option<PyErr>,
}

impl Observer for PyObserver<'_> {
    fn on_iteration(&mut self, it: &Iteration) -> Control {
        let step = Step {
            optimizer: it.optimizer.to_string(),
            iteration: it.iteration,
            best_cost: it.best_cost,
            mean_cost: it.mean_cost,
            evaluations: it.evaluations,
            elapsed_s: it.elapsed_s,
        };
        self.history.push(step.clone());
        if self.interrupted || self.stopped_by_callback || self.failure.is_some() || self.errors.any() {
            return Control::Stop;
        }
        Python::attach(|py| {
            let outcome = py.check_signals().and_then(|()| match &self.progress {
                Some(cb) => {
                    let r = cb.call1(py, (step.dict(py)?,))?;
                    // Returning False stops; None or anything else goes on.
                    Ok(r.bind(py).is_instance_of::<pyo3::types::PyBool>() && !r.bind(py).is_truthy()?)
                }
                None => Ok(false),
            });
            match outcome {
                Ok(false) => Control::Continue,
                Ok(true) => {
                    self.stopped_by_callback = true;
                    Control::Stop
                }
                Err(e) if e.is_instance_of::<PyKeyboardInterrupt>(py) => {
                    self.interrupted = true;
                    Control::Stop
                }
                Err(e) => {
                    self.failure = Some(e);
                    Control::Stop
                }
            }
        })
    }
}

/// Fit a model to training runs, as ``omnical train RUNS`` (the options carry its flags' names).
///
/// ``model``: what to start from. A kinematics, as the CLI's ``--model``: ``"ik"`` (the 3 x W matrix),
/// ``"geometry"``, ``"diff"``, ``"mecanum"`` or ``"skid"``, at the design of ``robot`` (a ``robot.toml`` path or
/// ``"apr02"``, the paper's robot), else of the data's robot (a Dataset's); these parametric fits use the
/// robot description's ``[priors]`` to bound the search, as the CLI does. ``"design"``: the data's (or
/// ``robot``'s) design model as ``evaluate`` uses it. Or a start model, as the CLI's ``--start``: an
/// :class:`omnical.Model` or a model file path. Without a known design it raises ``ValueError`` saying how
/// to describe the robot: there is no default robot. ``effects``: catalogue ids or Python effects to add.
///
/// ``preset="default"`` (path cost, short GA + Levenberg–Marquardt) or ``"paper"`` (the paper's Eq. 6
/// GA). ``objective`` (``"path"`` or ``"end_pose"``), ``unexcited`` (``"hold"`` or ``"move"``): default the
/// preset's; ``every``, ``heading_weight`` [m/rad], ``max_std_error``, ``min_excitation``: as the CLI's
/// flags. ``progress(dict)`` is called after each iteration; returning False stops. Ctrl-C stops the GA and
/// returns the best so far (``interrupted`` is True). The GIL is released while the search runs.
///
/// Refused with ``omnical.CalibrationError`` as the CLI refuses: a preset whose fixed step misses the runs'
/// sampling (the paper's 10 ms on 40 ms data; before fitting), and a fit worse than its start on its own
/// training runs (both objectives in the message). ``force=True`` fits and returns it anyway, with a
/// ``UserWarning``.
///
/// >>> runs = omnical.simulate(runs_per_command=1, duration_s=1.0)  # on the paper's Eq. 9 robot
/// >>> fit = omnical.train("ik", runs, robot="apr02", seed=0)
/// >>> fit.objective, fit.cost_fitted < fit.cost_start
/// ('path', True)
/// >>> fit.matrix.shape
/// (3, 3)
#[pyfunction]
#[pyo3(signature = (model, runs, *, robot = None, effects = Vec::new(), preset = "default", seed = 0, objective = None, every = 1, heading_weight = 1.0, unexcited = None, max_std_error = 0.05, min_excitation = 0.01, progress = None, force = false))]
#[allow(clippy::too_many_arguments)]
pub fn train(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    runs: &Bound<'_, PyAny>,
    robot: Option<std::path::PathBuf>,
    effects: Vec<Bound<'_, PyAny>>,
    preset: &str,
    seed: u64,
    objective: Option<&str>,
    every: usize,
    heading_weight: f64,
    unexcited: Option<&str>,
    max_std_error: f64,
    min_excitation: f64,
    progress: Option<Py<PyAny>>,
    force: bool,
) -> PyResult<PyCalibration> {
    crate::robot::check_order(model, runs, "omnical.train")?;
    let preset: Preset = preset.parse().map_err(|e: UnknownChoice| value_error(format!("preset {e}")))?;
    let fit = fit_args(objective, every, heading_weight, unexcited, max_std_error, min_excitation)?;
    let mut origin = crate::run::origin_of(runs);
    let (runs, design) = runs_from(runs, "runs")?;
    let (start, mut adapters, from_design) = start_model(py, model, robot.as_ref(), design, &mut origin)?;
    // As `omnical train`: a relative reference's runs fit the sensor's mount with the base.
    let start = omni_cli::api::train::with_sensor_mount(start, &origin);
    let made = effects.iter().map(|e| effect_from(e, start.model.n_wheels())).collect::<PyResult<Vec<_>>>()?;
    let (kinds, added): (Vec<_>, Vec<_>) = made.into_iter().unzip();
    adapters.extend(added.into_iter().flatten());
    // As `omnical train`: the parameter count with the effects (the paper preset's GA fits them all at once).
    let plan = Plan::preset(preset, start.model.n_params() + kinds.iter().map(|e| e.params().len()).sum::<usize>());
    let plan = plan.seed(seed);
    let mut plan = fit.apply(plan).map_err(|e| value_error(crate::errors::keywords(&format!("omnical.train: {e}"))))?;
    if from_design {
        plan.half_widths = prior_half_widths(&start, &origin).into_iter().collect();
    }
    // The CLI's refusals (`omnical train` without --force): the preset's fixed step against the runs.
    if let Some(w) = check_step(&plan, &runs, force).map_err(refused)? {
        warn(py, &w)?;
    }
    // The training sequence of `omnical train` (api::train::fit_prepared): the fit, its refusal, the model
    // file's summary (with the priors of a fit from the robot's design).
    let priors = if from_design { omni_cli::api::fit::priors_of(&start, &origin) } else { Vec::new() };
    origin.runs = runs;
    let prepared = Prepared { ds: origin, start, effects: kinds, plan, priors };
    let recipe = Recipe { preset, seed, from_design };
    let errors = crate::effect::EffectErrors::new(adapters.iter().cloned());
    let mut observer = PyObserver {
        progress,
        errors: &errors,
        history: Vec::new(),
        interrupted: false,
        stopped_by_callback: false,
        failure: None,
    };
    let result = py.detach(|| fit_prepared(&prepared, recipe, force, &mut observer));
    if let Some(e) = observer.failure.take() {
        return Err(e);
    }
    let Fitted { calibration: c, summarized, warning } = match errors.check(result)? {
        Ok(f) => f,
        Err(TrainError::Calibrate(e)) => return Err::<PyCalibration, _>(e).py(),
        // A fit worse than its start on its own training runs is refused (force=True keeps it, with a warning).
        Err(TrainError::Refused(r)) => return Err(refused(r)),
        Err(e) => return Err(value_error(format!("omnical.train: {}", crate::errors::chain_text(&e)))),
    };
    for w in warning.iter().chain(&summarized.mount) {
        warn(py, w)?;
    }
    let summary = interrupted_summary(py, summarized.summary, observer.interrupted)?;
    let stopped = (observer.interrupted, observer.stopped_by_callback);
    calibration_of(py, c, adapters, stopped, observer.history, summary)
}

/// The summary, marked `interrupted` (as the CLI's) with a warning when Ctrl-C stopped the search.
fn interrupted_summary(
    py: Python<'_>,
    mut summary: serde_json::Value,
    interrupted: bool,
) -> PyResult<serde_json::Value> {
    if interrupted {
        PyErr::warn(
            py,
            &py.get_type::<PyUserWarning>(),
            c"omnical.train: interrupted (Ctrl-C); returning the best parameters found so far",
            1,
        )?;
        summary["interrupted"] = serde_json::json!(true);
    }
    Ok(summary)
}

/// `train`'s objective and identifiability keywords as the library's [`FitOptions`] (checked when applied).
fn fit_args(
    objective: Option<&str>,
    every: usize,
    heading_weight: f64,
    unexcited: Option<&str>,
    max_std_error: f64,
    min_excitation: f64,
) -> PyResult<FitOptions> {
    Ok(FitOptions {
        // The CLI's spelling (`end-pose`) and the id Calibration.objective gives (`end_pose`).
        objective: objective
            .map(|o| o.replace('-', "_").parse())
            .transpose()
            .map_err(|e: UnknownChoice| value_error(format!("objective {e}")))?,
        every,
        heading_weight_m_per_rad: heading_weight,
        unexcited: unexcited
            .map(str::parse)
            .transpose()
            .map_err(|e: UnknownChoice| value_error(format!("unexcited {e}")))?,
        max_std_error,
        min_excitation,
    })
}

/// The Python object of a calibration; `stopped`: (interrupted by Ctrl-C, stopped by the callback).
fn calibration_of(
    py: Python<'_>,
    c: Calibration,
    adapters: Vec<std::sync::Arc<crate::effect::PyEffect>>,
    stopped: (bool, bool),
    steps: Vec<Step>,
    summary: serde_json::Value,
) -> PyResult<PyCalibration> {
    Ok(PyCalibration {
        model: Py::new(py, PyModel::from_fitted(c.fitted.clone(), adapters.clone()))?,
        start: Py::new(py, PyModel::from_fitted(c.start.clone(), adapters))?,
        objective: c.objective.name().to_string(),
        objective_start: c.objective_start,
        objective_fitted: c.objective_fitted,
        cost_start: c.end_pose_start,
        cost_fitted: c.end_pose_fitted,
        improvement_pct: c.improvement_pct(),
        evaluations: c.evaluations,
        seconds: c.seconds,
        at_bound: c.at_bound,
        outside_box: c.outside_box,
        interrupted: stopped.0,
        stopped: stopped.1,
        warnings: c.identifiability.warnings(),
        held: c.held.iter().map(|w| w.text.clone()).collect(),
        identifiability: serde_json::to_string(&c.identifiability).map_err(|e| value_error(e.to_string()))?,
        steps,
        summary,
    })
}

/// A refusal of the CLI's `train` as `omnical.CalibrationError`, in Python's spelling.
fn refused(e: Refused) -> PyErr {
    CalibrationError::new_err(crate::errors::keywords(&format!("omnical.train: {e}")))
}

/// A `UserWarning`, the settings it names as Python's keywords.
fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let text = std::ffi::CString::new(crate::errors::keywords(&format!("omnical.train: {message}")))
        .map_err(|e| value_error(e.to_string()))?;
    PyErr::warn(py, &py.get_type::<PyUserWarning>(), &text, 1)
}

/// The start of `train` and whether it is a robot's design (then its `[priors]` bound the search, as
/// the CLI's when no `--start` is given): a kinematics id at the design of `robot`, else of the data's
/// robot (`origin`, which `robot` replaces); `"design"` as in `evaluate`; else a start model.
fn start_model(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    robot: Option<&std::path::PathBuf>,
    declared: Option<FittedModel>,
    origin: &mut omni_cli::dataset::Dataset,
) -> PyResult<(FittedModel, Vec<std::sync::Arc<crate::effect::PyEffect>>, bool)> {
    if let Some(r) = robot_arg(robot)? {
        origin.robot_file = Some(r);
    }
    let kind = model.extract::<String>().ok().and_then(|s| s.parse::<KinematicsKind>().ok());
    if let Some(kind) = kind {
        let m = omni_cli::design::model_of(kind, origin)
            .map_err(|e| value_error(format!("robot: {}", crate::errors::chain_text(&e))))?;
        return match m {
            Some(m) => Ok((FittedModel::nominal(m), Vec::new(), true)),
            None => Err(crate::robot::no_design("omnical.train")),
        };
    }
    if model.extract::<String>().is_ok_and(|s| ModelSpec::from_path(std::path::Path::new(&s)) == ModelSpec::Design) {
        let (m, a) = model_or_design(None, robot, declared, "omnical.train")?;
        return Ok((m, a, true));
    }
    let (m, a, _) = model_spec(py, model, robot, declared, "omnical.train")?;
    Ok((m, a, false))
}
