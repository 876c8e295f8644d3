//! `omnical train` as a request ([`TrainRequest`]): loading, the start model, the plan and the fit, and the
//! model file it writes. The command prints around it; [`train_quietly`] runs it without a terminal.

use crate::api::fit::{FitOptions, FitOptionsError, PriorUse, Refused, check_fit, check_step, robot_priors};
use crate::api::load::{DataOptions, LoadError, LoadRequest};
use crate::dataset::Dataset;
use crate::design::DesignError;
use crate::model_file::{ModelFileError, ModelTextError};
use crate::out_path::OutPathError;
use crate::{atomic, design, model_file, out_path};
use omni_ga::calibrate::{Calibration, Plan, Preset, calibrate_with_effects};
use omni_kin::cost::CostKind;
use omni_kin::effect::Effect;
use omni_kin::robot::PRIOR_BOX_SIGMAS;
use omni_kin::{EffectKind, FittedModel, KinError, KinematicsKind, Model};
use serde_json::json;
use std::path::PathBuf;

/// Why `omnical train` (its preparation, its fit or the model file) failed.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// `--out` cannot take the model file.
    #[error(transparent)]
    Out(#[from] OutPathError),
    /// The runs could not be read.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The `--start` model file could not be read.
    #[error("reading --start")]
    Start(#[source] ModelFileError),
    /// The design model to start from could not be built.
    #[error(transparent)]
    Design(#[from] DesignError),
    /// An `--effect` id is unknown or does not fit the model.
    #[error("--effect {id}")]
    Effect {
        /// The id given.
        id: String,
        /// Why it is refused.
        source: KinError,
    },
    /// A fit setting out of its range.
    #[error(transparent)]
    FitOptions(#[from] FitOptionsError),
    /// The fit was refused (`--force` keeps it).
    #[error(transparent)]
    Refused(#[from] Refused),
    /// The fit failed.
    #[error(transparent)]
    Calibrate(#[from] omni_ga::Error),
    /// The model or runs are not usable (wheel names, the fitted matrix, a cost).
    #[error(transparent)]
    Kin(#[from] KinError),
    /// The fit summary does not make a TOML table.
    #[error("fit summary")]
    FitSummary(#[source] toml::ser::Error),
    /// The model does not make model file text.
    #[error(transparent)]
    ModelText(#[from] ModelTextError),
    /// The model file could not be written.
    #[error("writing {}", path.display())]
    Write {
        /// The model file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// What `omnical train` does: the runs and how to read them, the start, the preset and its overrides, the
/// effects to add, where the model goes.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainRequest {
    /// Training run files or folders.
    pub runs: Vec<PathBuf>,
    /// How to read them.
    pub data: DataOptions,
    /// Base model to fit (at the robot's design) when no start model is given; `None`: the robot's own
    /// ([`design::default_kind`]), or the matrix under the paper preset.
    pub model: Option<KinematicsKind>,
    /// Start from this model file instead of the design.
    pub start: Option<PathBuf>,
    /// Training recipe.
    pub preset: Preset,
    /// Seed of the genetic algorithm.
    pub seed: u64,
    /// Effect ids to add to the fit.
    pub effects: Vec<String>,
    /// Where to write the fitted model (`None`: nowhere).
    pub out: Option<PathBuf>,
    /// Fit and write even when the fit is refused.
    pub force: bool,
    /// Objective and identifiability overrides.
    pub fit: FitOptions,
}

/// The fit summary as JSON (also written into the model file's `[fit]` table).
pub fn summary(c: &Calibration, preset: &str, seed: u64, runs: usize) -> Result<serde_json::Value, KinError> {
    let mut s = json!({
        "preset": preset,
        "seed": seed,
        "runs": runs,
        "objective": c.objective.name(),
        "cost_design": c.end_pose_start,
        "cost_fitted": c.end_pose_fitted,
        "improvement_pct": c.improvement_pct(),
        "objective_design": c.objective_start,
        "objective_fitted": c.objective_fitted,
        "matrix": c.fitted.ik()?.rows(),
        "params": c.fitted.model.params().iter().zip(&c.fitted.params)
            .map(|(s, v)| json!({"name": s.name, "unit": s.unit, "value": v})).collect::<Vec<_>>(),
        "evaluations": c.evaluations,
        "seconds": c.seconds,
        "at_bound": c.at_bound,
        "outside_box": c.outside_box,
        "held_at_start": c.held.iter().map(|w| &w.text).collect::<Vec<_>>(),
        "warnings": c.identifiability.warnings(),
        "identifiability": c.identifiability,
    });
    if let Some(r) = c.start_rescaled {
        s["start_rescaled"] = json!({"distance_ratio": r.distance_ratio, "turning_ratio": r.turning_ratio});
    }
    Ok(s)
}

/// The line saying the fit started from the design rescaled to the ground truth's travel
/// ([`Calibration::start_rescaled`]), when it did.
pub fn start_rescaled_text(c: &Calibration) -> Option<String> {
    let r = c.start_rescaled?;
    Some(format!(
        "the start's dead reckoning went {:.2}× the ground truth's distance and turned {:.2}× its turning: the fit \
         started from the start rescaled by these ratios (the start as given is what the costs above compare with)",
        r.distance_ratio, r.turning_ratio
    ))
}

/// JSON made fit for TOML, which has no null: null fields are dropped, null array items become "none".
fn toml_safe(v: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Object(m) => {
            Value::Object(m.into_iter().filter(|(_, v)| !v.is_null()).map(|(k, v)| (k, toml_safe(v))).collect())
        }
        Value::Array(a) => Value::Array(
            a.into_iter().map(|v| if v.is_null() { Value::String("none".into()) } else { toml_safe(v) }).collect(),
        ),
        v => v,
    }
}

/// The design model with its columns named: the robot description's joints (already), else `--joints`
/// (the order the runs were read in); the model file carries them. `--joints` in another order than the
/// robot description's is warned about: the design's columns follow the description.
fn named_columns(design: Model, joints: Option<&[String]>) -> Result<Model, KinError> {
    let Some(joints) = joints.filter(|j| j.len() == design.n_wheels()) else { return Ok(design) };
    let names = design.kinematics.wheel_names();
    if names == omni_kin::geometry::default_wheel_names(names.len()) {
        return design.with_wheel_names(joints);
    }
    if names != joints {
        tracing::warn!(
            "{} reads the wheels as {}, but the design's columns are the robot's {}: give the joints in the \
             robot description's order",
            crate::api::settings::named("joints"),
            joints.join(", "),
            names.join(", ")
        );
    }
    Ok(design)
}

/// What `omnical train` fits: the runs, the start model, the effects to add to it, the plan and the robot
/// description's priors.
pub struct Prepared {
    /// The training runs.
    pub ds: Dataset,
    /// The start model.
    pub start: FittedModel,
    /// The effects added to it.
    pub effects: Vec<EffectKind>,
    /// The plan: the preset with the request's overrides and the priors' box.
    pub plan: Plan,
    /// The robot description's priors (none with a start model).
    pub priors: Vec<PriorUse>,
}

/// Loads the runs and builds the start model, the effects and the plan, as `omnical train` does. Ctrl-C is
/// the front end's to handle (the command checks for it after this returns).
pub fn prepare(a: &TrainRequest) -> Result<Prepared, TrainError> {
    let ds = LoadRequest::new(&a.runs, &a.data).load()?;
    let start = match &a.start {
        Some(p) => model_file::read(p).map_err(TrainError::Start)?,
        None => {
            // The paper's method fits the matrix whatever the base.
            let kind = a.model.unwrap_or_else(|| match a.preset {
                Preset::Paper => KinematicsKind::Ik,
                Preset::Default => design::default_kind(&ds),
            });
            FittedModel::nominal(named_columns(design::model(kind, &ds)?, a.data.joints.as_deref())?)
        }
    };
    let start = with_sensor_mount(start, &ds);
    let effects = a
        .effects
        .iter()
        .map(|id| {
            EffectKind::from_id(id, start.model.n_wheels())
                .map_err(|source| TrainError::Effect { id: id.clone(), source })
        })
        .collect::<Result<Vec<_>, _>>()?;
    // The parameter count with the effects: the paper preset's GA fits them all at once.
    let n_params = start.model.n_params() + effects.iter().map(|e| e.params().len()).sum::<usize>();
    let mut plan = a.fit.apply(Plan::preset(a.preset, n_params).seed(a.seed))?;
    let priors = if a.start.is_none() { robot_priors(&start, &ds) } else { Vec::new() };
    plan.half_widths = priors.iter().map(|p| (p.name.clone(), PRIOR_BOX_SIGMAS * p.std)).collect();
    Ok(Prepared { ds, start, effects, plan, priors })
}

/// `start` with the sensor's mount (`sensor_offset_yaw`, at `ds`'s [`Dataset::mount_start`]: given with
/// `--gt-mount-start` or found from the motions, else zero) when `ds`'s reference is a sensor's own motion
/// and `start` has no mount yet: the mount is part of what such a reference measures, so it is fitted with
/// the base from the first stage on. Not when the mount was given (`--gt-mount`), nor when the recordings'
/// static transforms gave it and the base model absorbs any mount (a free matrix or geometry: see
/// [`mount_warning`]), which keeps it as given.
pub fn with_sensor_mount(start: FittedModel, ds: &Dataset) -> FittedModel {
    use omni_kin::effect::SensorOffset;
    let has_mount = start.model.effects.iter().any(|e| matches!(e, EffectKind::SensorOffset(_)));
    let absorbs_mount = matches!(start.model.kinematics.kind(), KinematicsKind::Ik | KinematicsKind::Geometry);
    let kept_as_given = ds.mount.is_some() || ds.sensor_mount_from_recordings && absorbs_mount;
    if ds.reference != omni_kin::reference::ReferenceKind::Relative || kept_as_given || has_mount {
        return start;
    }
    let mut start = start.with_effect(EffectKind::SensorOffset(SensorOffset { with_yaw: true }));
    if let Some(m) = ds.mount_start {
        let n = start.params.len();
        start.params[n - 3..].copy_from_slice(&[m.x_m, m.y_m, m.theta_rad]);
    }
    start
}

/// Share of a weak direction a mount parameter must carry for the mount to be called undetermined.
const MOUNT_SHARE: f64 = 0.2;

/// A warning when the fit could not tell the sensor's mount (fitted for a relative reference) from the base:
/// some unconstrained direction moves it. A base model as free as a matrix absorbs any mount (the sensor
/// moves with the base, so its twist is a fixed linear map of the base's), whatever the motions.
pub fn mount_warning(c: &Calibration) -> Option<String> {
    let mount = |name: &str| name.starts_with(omni_kin::effect::SensorOffset::ID);
    let weak: Vec<&str> = c
        .identifiability
        .weak
        .iter()
        .flat_map(|w| w.loadings.iter().filter(|(n, s)| mount(n) && s.abs() >= MOUNT_SHARE).map(|(n, _)| n.as_str()))
        .collect();
    if weak.is_empty() {
        return None;
    }
    let kind = c.fitted.model.kinematics.kind();
    let why = match kind {
        KinematicsKind::Ik | KinematicsKind::Geometry => format!(
            "the {} model absorbs any mount: the sensor moves with the base, so its twist is a fixed linear map of the \
             base's, and a free matrix (or geometry) fits the sensor's own odometry exactly, whatever the motions",
            kind.id()
        ),
        _ => "the runs do not determine it: add runs that turn on the spot and drive straight".to_string(),
    };
    Some(format!(
        "the sensor's mount is not determined ({}): {why}. Give the mount with --gt-mount X,Y,YAW_DEG (from the \
         robot's URDF, its /tf_static or a tape measure), or fit a base model with fewer parameters than its \
         matrix (a diff drive's radii and separation)",
        weak.into_iter().collect::<std::collections::BTreeSet<_>>().into_iter().collect::<Vec<_>>().join(", ")
    ))
}

/// Writes the model file of a fit with its summary `s` as the `[fit]` table, atomically. Everything but the
/// wall time goes in: the same data, preset and seed give a byte-identical file.
pub fn write_model(fitted: &FittedModel, s: &serde_json::Value, out: &std::path::Path) -> Result<(), TrainError> {
    let mut fit: toml::Table = toml::Table::try_from(toml_safe(s.clone())).map_err(TrainError::FitSummary)?;
    fit.remove("seconds");
    fit.remove("noise");
    let mut file = model_file::ModelFile::from_fitted(fitted, Some(fit)).map_err(ModelTextError::from)?;
    file.noise = crate::api::noise::from_summary(s);
    let text = file.to_toml()?;
    atomic::write_atomic(out, text.as_bytes()).map_err(|source| TrainError::Write { path: out.to_path_buf(), source })
}

/// What [`train_quietly`] gives back.
pub struct Trained {
    /// The fit.
    pub calibration: Calibration,
    /// The JSON summary that `--json` prints (without the ground-truth clocks) and the model file holds.
    pub summary: serde_json::Value,
    /// The dataset the runs came from (notes, skipped inputs, ground-truth clocks).
    pub dataset: Dataset,
    /// What `omnical train` would print as `warning:` lines before training.
    pub warnings: Vec<String>,
}

/// A fit and what every front end makes of it ([`fit_prepared`]).
pub struct Fitted {
    /// The fit.
    pub calibration: Calibration,
    /// The model file's summary, the designs figure and the mount warning.
    pub summarized: Summarized,
    /// [`check_fit`]'s warning: a fit it refuses, kept with `force`.
    pub warning: Option<String>,
}

/// The training sequence, the one every front end runs once its start, effects and plan are made
/// ([`prepare`]; Python makes its own start from its model objects): the fit, its refusal
/// ([`check_fit`]) and the model file's summary ([`summarize`]). `omnical train`, the fleet's
/// [`train_quietly`] and Python's `train` call it and only present the result; the fixed-step refusal
/// ([`check_step`]) comes before, so that its warning is seen before the search starts.
pub fn fit_prepared(
    p: &Prepared,
    recipe: Recipe,
    force: bool,
    observer: &mut dyn omni_ga::observe::Observer,
) -> Result<Fitted, TrainError> {
    let c = calibrate_with_effects(&p.start, &p.effects, &p.ds.runs, &p.plan, observer)?;
    let warning = check_fit(&c, &p.plan, &p.ds.runs, force)?;
    let summarized = summarize(&c, &p.ds, &p.plan, &p.priors, recipe)?;
    Ok(Fitted { calibration: c, summarized, warning })
}

/// `omnical train` without a terminal, for callers that run many trainings in one process (the Python
/// wheel's fleet workers): the same loading, start model, plan and fit as the command, and the same model file
/// written to `--out` (byte-identical: the same `write_model` either way), but nothing printed, no progress bar
/// and no Ctrl-C handler installed.
pub fn train_quietly(a: &TrainRequest) -> Result<Trained, TrainError> {
    if let Some(out) = &a.out {
        out_path::check_file(out, "--out")?;
    }
    let prepared = prepare(a)?;
    let mut warnings: Vec<String> = check_step(&prepared.plan, &prepared.ds.runs, a.force)?.into_iter().collect();
    let fitted = fit_prepared(&prepared, a.recipe(), a.force, &mut omni_ga::observe::NoopObserver)?;
    let Fitted { calibration: c, summarized: Summarized { summary: s, mount, .. }, warning } = fitted;
    warnings.extend(warning.into_iter().chain(mount));
    if let Some(out) = &a.out {
        write_model(&c.fitted, &s, out)?;
    }
    Ok(Trained { calibration: c, summary: s, dataset: prepared.ds, warnings })
}

/// A fit's summary as every front end writes it into the model file ([`summarize`]).
pub struct Summarized {
    /// The JSON summary: [`summary`], the noise model, the designs, the priors, and the mount warning among
    /// its warnings.
    pub summary: serde_json::Value,
    /// The designs figure, when the inputs declare several.
    pub designs: Option<DesignsFigure>,
    /// The warning of a sensor mount the runs do not determine ([`mount_warning`]).
    pub mount: Option<String>,
}

/// How a fit was asked for, as its summary records it: the preset, the seed, and whether it started from
/// the robot's design (a kinematics named, or the default) rather than a start model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Recipe {
    /// The preset.
    pub preset: Preset,
    /// The GA seed.
    pub seed: u64,
    /// Started from the robot's design: its priors bound the search and the designs figure compares with it.
    pub from_design: bool,
}

impl TrainRequest {
    /// The request's [`Recipe`].
    pub fn recipe(&self) -> Recipe {
        Recipe { preset: self.preset, seed: self.seed, from_design: self.start.is_none() }
    }
}

/// The summary of fit `c` of `ds` by `plan` made by `recipe`, with the robot description's `priors`: the
/// one place `omnical train`, the fleet and Python's `train` build what the model file holds, so that
/// their files are the same.
pub fn summarize(
    c: &Calibration,
    ds: &Dataset,
    plan: &Plan,
    priors: &[PriorUse],
    recipe: Recipe,
) -> Result<Summarized, TrainError> {
    let mut s = summary(c, recipe.preset.id(), recipe.seed, ds.runs.len())?;
    crate::api::noise::add_to_summary(&mut s, &c.fitted, &ds.runs)?;
    let designs = designs_figure(c, ds, plan, recipe.from_design)?;
    if let Some(d) = &designs {
        s["designs"] = d.to_json();
    }
    if !priors.is_empty() {
        s["priors"] = priors.iter().map(|p| p.to_json(&c.fitted)).collect();
    }
    let mount = mount_warning(c);
    if let (Some(w), Some(list)) = (&mount, s["warnings"].as_array_mut()) {
        list.push(json!(w));
    }
    Ok(Summarized { summary: s, designs, mount })
}

/// The design figure when the training runs' inputs declare different designs: each run under its own
/// input's design (in the fit's kinematics and integration), against the one design the fit started from.
pub struct DesignsFigure {
    /// Distinct designs.
    pub designs: usize,
    /// Eq. 6 on the training runs, each under its own design.
    pub end_pose: f64,
    /// The objective on the training runs, each under its own design.
    pub objective: f64,
    /// The input whose design the fit started from (`None`: a `--start` model).
    pub start: Option<String>,
}

impl DesignsFigure {
    /// The figure as JSON (`omnical train --json`'s `designs`).
    pub fn to_json(&self) -> serde_json::Value {
        json!({ "designs": self.designs, "cost": self.end_pose, "objective": self.objective, "start": self.start })
    }

    /// The figure in words.
    pub fn describe(&self) -> String {
        let start = self.start.as_ref().map_or("the --start model".to_string(), |s| format!("{s}'s design"));
        format!(
            "each run with its own input's design ({} designs): Eq. 6 {:.5}, objective {:.5} (not the \"design\" \
             figures above: those are of the fit's start, {start}, on every run)",
            self.designs, self.end_pose, self.objective
        )
    }
}

/// [`DesignsFigure`] for a fit on `ds`'s runs, `None` when its inputs declare one design (or none).
pub fn designs_figure(
    c: &Calibration,
    ds: &Dataset,
    plan: &Plan,
    from_design: bool,
) -> Result<Option<DesignsFigure>, KinError> {
    let designs = design::designs_for(&c.start, &[ds]);
    if designs.single().is_some() {
        return Ok(None);
    }
    let start = ds.declared_start().filter(|_| from_design).map(|d| {
        d.source.file_name().map_or_else(|| d.source.display().to_string(), |n| n.to_string_lossy().into_owned())
    });
    Ok(Some(DesignsFigure {
        designs: designs.models().len(),
        end_pose: designs.cost(&ds.runs, CostKind::EndPose)?,
        objective: designs.cost(&ds.runs, plan.objective)?,
        start,
    }))
}
