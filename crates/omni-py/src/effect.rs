//! User effects written in Python, wrapped as an `omni_kin::Effect` (`EffectKind::Custom`), so the
//! simulator, the cost, `train` and `diagnose` use them exactly like built-in effects.
//!
//! The Python object (duck-typed; `omnical.Effect` is a convenient base class) has:
//! - `id: str`, `stage: str` (`"wheel"`, `"twist"`, `"clock"` or `"measurement"`),
//!   `params`: a sequence of `(name, unit, null, lower, upper)`, and optionally `describe() -> str`;
//! - the hook of its stage:
//!   - wheel: `wheel_rates(p, t_s, dt_s, wheel_rad_s) -> (N, W)`, once per run and cost evaluation, on
//!     whole columns: `p` (P,) parameters, `t_s` (N,) sample times on the ground-truth clock [s],
//!     `dt_s` (N,) integrated step of each sample [s], `wheel_rad_s` (N, W) [rad/s];
//!   - twist: `twist(p, twist, wheel_rad_s) -> (vx_m_s, vy_m_s, omega_rad_s)`, once per **sample** (slow);
//!     or, when the object has it, `twist_at(p, twist, wheel_rad_s, heading_rad, since_start_s)` with the
//!     body's world heading at the start of the step [rad] and the time since the run's first
//!     ground-truth pose [s] (for world-frame physics: a tilted floor, a drifting ground-truth frame);
//!   - clock: `clock_lag_s(p) -> float` [s], once per cost evaluation;
//!   - measurement: `sensor_from_body(p) -> (x_m, y_m, theta_rad)`, once per cost evaluation.
//!
//! Threads: the hooks run on rayon worker threads, which take the GIL for each call, so Python effects
//! serialise the otherwise parallel cost. Errors: an exception raised by a hook is kept (the first one),
//! the hook's output becomes NaN (the cost becomes non-finite), a training stops at its next iteration,
//! and the calling function re-raises the exception.

use crate::arrays::{matrix, to_matrix, to_vector};
use crate::errors::value_error;
use omni_kin::effect::{Effect, ParamSpec, Stage, TwistAt, WheelContext};
use omni_kin::{EffectKind, Pose2, Twist2};
use pyo3::prelude::*;
use std::fmt;
use std::sync::{Arc, Mutex};

/// A Python object acting as an effect.
pub struct PyEffect {
    obj: Py<PyAny>,
    id: String,
    physics: String,
    stage: Stage,
    specs: Vec<ParamSpec>,
    /// The object has `twist_at` (with heading and time), called instead of `twist`.
    has_twist_at: bool,
    /// The first exception raised by a hook since the last [`PyEffect::take_error`].
    error: Mutex<Option<PyErr>>,
}

impl fmt::Debug for PyEffect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PyEffect").field("id", &self.id).field("stage", &self.stage).finish()
    }
}

fn stage_from(s: &str) -> PyResult<Stage> {
    Ok(match s {
        "wheel" => Stage::Wheel,
        "twist" => Stage::Twist,
        "clock" => Stage::Clock,
        "measurement" => Stage::Measurement,
        other => {
            return Err(value_error(format!(
                "effect stage {other:?} is not supported for Python effects; use \"wheel\", \"twist\", \"clock\" or \"measurement\""
            )));
        }
    })
}

/// Stage name as Python effects spell it.
pub fn stage_name(s: Stage) -> &'static str {
    match s {
        Stage::Wheel => "wheel",
        Stage::Twist => "twist",
        Stage::Clock => "clock",
        Stage::Measurement => "measurement",
        Stage::Integration => "integration",
    }
}

impl PyEffect {
    /// Reads `id`, `stage`, `params` and `describe()` from a Python object and checks that it has its
    /// stage's hook.
    pub fn from_object(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        let id: String = obj
            .getattr("id")
            .and_then(|v| v.extract())
            .map_err(|_| value_error("a Python effect needs a string attribute `id`"))?;
        let stage: String = obj
            .getattr("stage")
            .and_then(|v| v.extract())
            .map_err(|_| value_error(format!("effect {id}: needs a string attribute `stage`")))?;
        let stage = stage_from(&stage)?;
        let mut specs = Vec::new();
        let params = obj.getattr("params").map_err(|_| value_error(format!("effect {id}: needs `params`")))?;
        for (i, p) in params.try_iter()?.enumerate() {
            let (name, unit, null, lower, upper): (String, String, f64, f64, f64) = p?.extract().map_err(|_| {
                value_error(format!("effect {id}: params[{i}] must be (name, unit, null, lower, upper)"))
            })?;
            if !(null.is_finite() && lower <= upper) {
                return Err(value_error(format!(
                    "effect {id}: params[{i}] ({name}) needs a finite null value and lower <= upper"
                )));
            }
            specs.push(ParamSpec::new(name, &unit, null, lower, upper));
        }
        let hook = match stage {
            Stage::Wheel => "wheel_rates",
            Stage::Twist => "twist",
            Stage::Clock => "clock_lag_s",
            _ => "sensor_from_body",
        };
        let has_twist_at = stage == Stage::Twist && obj.hasattr("twist_at")?;
        if !has_twist_at && !obj.hasattr(hook)? {
            return Err(value_error(format!("effect {id}: stage {:?} needs a method `{hook}`", stage_name(stage))));
        }
        let physics = match obj.getattr("describe") {
            Ok(d) if d.is_callable() => d.call0()?.extract()?,
            _ => String::new(),
        };
        Ok(Self { obj: obj.clone().unbind(), id, physics, stage, specs, has_twist_at, error: Mutex::new(None) })
    }

    /// The Python object.
    pub fn object<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.obj.bind(py).clone()
    }

    fn record(&self, e: PyErr) {
        if let Ok(mut slot) = self.error.lock()
            && slot.is_none()
        {
            *slot = Some(e);
        }
    }

    /// A hook has raised since the last `take_error`.
    pub fn failed(&self) -> bool {
        self.error.lock().map(|s| s.is_some()).unwrap_or(false)
    }

    /// The first exception raised by a hook, clearing it.
    pub fn take_error(&self) -> Option<PyErr> {
        self.error.lock().ok().and_then(|mut s| s.take())
    }

    fn call<T>(&self, f: impl for<'py> FnOnce(Python<'py>, &Bound<'py, PyAny>) -> PyResult<T>) -> Option<T> {
        if self.failed() {
            return None;
        }
        Python::attach(|py| match f(py, self.obj.bind(py)) {
            Ok(v) => Some(v),
            Err(e) => {
                self.record(e);
                None
            }
        })
    }

    fn three(&self, hook: &str, v: &Bound<'_, PyAny>) -> PyResult<[f64; 3]> {
        let (a, b, c): (f64, f64, f64) = match v.extract() {
            Ok(t) => t,
            Err(_) => {
                let x: Vec<f64> = v
                    .extract()
                    .map_err(|_| value_error(format!("effect {}: {hook} must return 3 numbers", self.id)))?;
                match x.as_slice() {
                    [a, b, c] => (*a, *b, *c),
                    _ => {
                        return Err(value_error(format!(
                            "effect {}: {hook} must return 3 numbers, got {}",
                            self.id,
                            x.len()
                        )));
                    }
                }
            }
        };
        Ok([a, b, c])
    }
}

impl Effect for PyEffect {
    fn id(&self) -> &str {
        &self.id
    }
    fn describe(&self) -> String {
        self.physics.clone()
    }
    fn stage(&self) -> Stage {
        self.stage
    }
    fn params(&self) -> Vec<ParamSpec> {
        self.specs.clone()
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        if self.stage != Stage::Wheel {
            return;
        }
        let n = ctx.t_s.len();
        let nw = ctx.n_wheels;
        let out = self.call(|py, obj| {
            let wheels = to_matrix(py, n, nw, w.to_vec())?;
            let r = obj.call_method1(
                "wheel_rates",
                (to_vector(py, p.to_vec()), to_vector(py, ctx.t_s.to_vec()), to_vector(py, ctx.dt_s.to_vec()), wheels),
            )?;
            let (v, rows, cols) = matrix(&r, &format!("effect {}: wheel_rates result", self.id), "(N, W)")?;
            if (rows, cols) != (n, nw) {
                return Err(value_error(format!(
                    "effect {}: wheel_rates must return shape ({n}, {nw}), got ({rows}, {cols})",
                    self.id
                )));
            }
            Ok(v)
        });
        match out {
            Some(v) => w.copy_from_slice(&v),
            None => w.fill(f64::NAN),
        }
    }
    fn twist(&self, p: &[f64], twist: Twist2, w: &[f64]) -> Twist2 {
        if self.stage != Stage::Twist {
            return twist;
        }
        let out = self.call(|py, obj| {
            let t = (twist.vx_m_s, twist.vy_m_s, twist.omega_rad_s);
            let r = obj.call_method1("twist", (to_vector(py, p.to_vec()), t, to_vector(py, w.to_vec())))?;
            self.three("twist", &r)
        });
        match out {
            Some([vx_m_s, vy_m_s, omega_rad_s]) => Twist2 { vx_m_s, vy_m_s, omega_rad_s },
            None => Twist2 { vx_m_s: f64::NAN, vy_m_s: f64::NAN, omega_rad_s: f64::NAN },
        }
    }
    fn twist_at(&self, p: &[f64], twist: Twist2, w: &[f64], at: &TwistAt) -> Twist2 {
        if self.stage != Stage::Twist || !self.has_twist_at {
            return self.twist(p, twist, w);
        }
        let out = self.call(|py, obj| {
            let t = (twist.vx_m_s, twist.vy_m_s, twist.omega_rad_s);
            let args = (to_vector(py, p.to_vec()), t, to_vector(py, w.to_vec()), at.pose.theta_rad, at.since_start_s);
            let r = obj.call_method1("twist_at", args)?;
            self.three("twist_at", &r)
        });
        match out {
            Some([vx_m_s, vy_m_s, omega_rad_s]) => Twist2 { vx_m_s, vy_m_s, omega_rad_s },
            None => Twist2 { vx_m_s: f64::NAN, vy_m_s: f64::NAN, omega_rad_s: f64::NAN },
        }
    }
    fn clock_lag_s(&self, p: &[f64]) -> f64 {
        if self.stage != Stage::Clock {
            return 0.0;
        }
        self.call(|py, obj| obj.call_method1("clock_lag_s", (to_vector(py, p.to_vec()),))?.extract::<f64>())
            .unwrap_or(f64::NAN)
    }
    fn sensor_from_body(&self, p: &[f64]) -> Pose2 {
        if self.stage != Stage::Measurement {
            return Pose2::IDENTITY;
        }
        match self.call(|py, obj| {
            let r = obj.call_method1("sensor_from_body", (to_vector(py, p.to_vec()),))?;
            self.three("sensor_from_body", &r)
        }) {
            Some([x, y, th]) => Pose2::new(x, y, th),
            None => Pose2::new(f64::NAN, f64::NAN, f64::NAN),
        }
    }
}

/// An effect argument: a catalogue id (`"time_offset"`) or a Python effect object. Returns the effect and,
/// for Python effects, the adapter (to collect its errors).
pub fn effect_from(obj: &Bound<'_, PyAny>, n_wheels: usize) -> PyResult<(EffectKind, Option<Arc<PyEffect>>)> {
    if let Ok(id) = obj.extract::<String>() {
        let e = EffectKind::from_id(&id, n_wheels).map_err(|e| value_error(e.to_string()))?;
        return Ok((e, None));
    }
    let adapter = Arc::new(PyEffect::from_object(obj)?);
    Ok((EffectKind::Custom(adapter.clone()), Some(adapter)))
}

/// The Python effects taking part in one call: cleared before, checked during (to stop early) and after
/// (to raise the first exception).
#[derive(Default)]
pub struct EffectErrors(pub Vec<Arc<PyEffect>>);

impl EffectErrors {
    /// Collects adapters (duplicates are harmless).
    pub fn new(effects: impl IntoIterator<Item = Arc<PyEffect>>) -> Self {
        let v: Vec<Arc<PyEffect>> = effects.into_iter().collect();
        for e in &v {
            let _ = e.take_error();
        }
        Self(v)
    }
    /// A hook has raised.
    pub fn any(&self) -> bool {
        self.0.iter().any(|e| e.failed())
    }
    /// The first exception raised, if any (all slots are cleared).
    pub fn take(&self) -> Option<PyErr> {
        let mut first = None;
        for e in &self.0 {
            if let Some(err) = e.take_error()
                && first.is_none()
            {
                first = Some(err);
            }
        }
        first
    }
    /// `Err` with the first exception raised, else `Ok(v)`.
    pub fn check<T>(&self, v: T) -> PyResult<T> {
        match self.take() {
            Some(e) => Err(e),
            None => Ok(v),
        }
    }
}
