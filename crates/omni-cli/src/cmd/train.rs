//! `omnical train`: fit a model to training runs.

use super::{DataArgs, OutputArgs, load_runs};
use crate::cli::{choice, effect_help};
use crate::dataset::Dataset;
use crate::robot_file::{self, Design};
use crate::units::{count, std_error_text, value_text};
use crate::{atomic, design, interrupt, model_file, out_path, progress};
use anyhow::Context;
use omni_ga::calibrate::{Calibration, Plan, Preset, Unexcited, calibrate_with_effects};
use omni_ga::identify::IdentifyOptions;
use omni_ga::science::text;
use omni_kin::cost::{CostKind, CostName};
use omni_kin::effect::Effect;
use omni_kin::robot::PRIOR_BOX_SIGMAS;
use omni_kin::{EffectKind, FittedModel, KinematicsKind, Model};
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `omnical train`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Training run files or folders.
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Base model to fit.
    #[arg(long, value_parser = choice::<KinematicsKind>(), default_value_t = KinematicsKind::default())]
    pub model: KinematicsKind,
    /// Start from this model file instead of the design.
    #[arg(long)]
    pub start: Option<PathBuf>,
    /// Training recipe: search method, objective and limits.
    #[arg(long, value_parser = choice::<Preset>(), default_value_t = Preset::default())]
    pub preset: Preset,
    /// Seed of the genetic algorithm's random search: the same seed gives the same model, whatever
    /// --threads.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Add an effect to fit (an effect id). Repeatable.
    #[arg(long = "effect", value_name = "NAME", help = effect_help("Add an effect to fit. Repeatable."))]
    pub effects: Vec<String>,
    /// Write the fitted model here (TOML; read back by `--model FILE`). Without it the fit is printed and
    /// nothing is written. Its folder must exist (checked before the fit).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Fit and write even when the fit is refused: a preset whose fixed step misses the runs' sampling,
    /// or a fitted model worse than its start on its own training runs (each then a warning).
    #[arg(long)]
    pub force: bool,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Objective and unconstrained directions.
    #[command(flatten)]
    pub fit: FitArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// Overrides of a preset's objective and its handling of unconstrained directions.
#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// Objective (default: the preset's; paper: end-pose, default: path).
    #[arg(long, value_parser = choice::<CostName>())]
    pub objective: Option<CostName>,
    /// Path objective: use every k-th ground-truth pose (odometry is evaluated at its stamp).
    #[arg(long, default_value_t = CostKind::PATH_EVERY, value_name = "K")]
    pub every: usize,
    /// Path objective: weight of heading errors against position errors (m/rad).
    #[arg(long, default_value_t = CostKind::PATH_HEADING_WEIGHT_M_PER_RAD, value_name = "M_PER_RAD")]
    pub heading_weight: f64,
    /// Directions the runs do not constrain: hold them at the start or let them move (default: the
    /// preset's; paper: move, default: hold).
    #[arg(long, value_parser = choice::<Unexcited>())]
    pub unexcited: Option<Unexcited>,
    /// A direction is unconstrained when its standard error exceeds this fraction of the parameters'
    /// scale.
    #[arg(long, default_value_t = IdentifyOptions::default().max_std_error, value_name = "FRACTION")]
    pub max_std_error: f64,
    /// A direction is unconstrained when its singular value (scaled Jacobian) is below this fraction of
    /// the largest.
    #[arg(long, default_value_t = IdentifyOptions::default().min_excitation, value_name = "FRACTION")]
    pub min_excitation: f64,
}

/// The fit summary as JSON (also written into the model file's `[fit]` table).
pub fn summary(c: &Calibration, preset: &str, seed: u64, runs: usize) -> anyhow::Result<serde_json::Value> {
    Ok(json!({
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
    }))
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

/// Exit status of a refused fit ([`Refused`]): 1 (an error in the input is 2).
pub const EXIT_REFUSED: i32 = 1;

/// A fit refused (exit status [`EXIT_REFUSED`], nothing written) unless `--force`: a preset whose fixed step
/// misses the runs' sampling (before fitting), or a fit worse than its start on its own training runs.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Refused(pub String);

/// The paper's Eq. 1 integrates fixed 10 ms steps, one per wheel sample: on runs sampled at another rate
/// every displacement is scaled by the ratio ([`Plan::step_mismatch`]). Says so, and what to use instead.
pub fn fixed_step_mismatch(plan: &Plan, runs: &[omni_kin::Run]) -> Option<String> {
    let m = plan.step_mismatch(runs)?;
    Some(format!(
        "the {} preset integrates fixed {:.0} ms steps (Eq. 1), but these runs are sampled every {:.0} ms (median \
         wheel-sample interval): odometry would be off by a factor {:.2} and the fit worse than the design; use \
         --preset default (each run's own step)",
        plan.preset,
        1e3 * m.step_s,
        1e3 * m.median_interval_s,
        m.factor()
    ))
}

/// A fit worse than its start on its training runs, in words: both objectives and, when the plan's fixed
/// step misses the runs' sampling, why.
pub fn worse_than_start_text(c: &Calibration, plan: &Plan, runs: &[omni_kin::Run]) -> Option<String> {
    let w = c.worse_than_start()?;
    let why = plan.step_mismatch(runs).map_or(String::new(), |m| {
        format!(
            " (the {} preset's fixed {:.0} ms step misses these runs' {:.0} ms sampling)",
            plan.preset,
            1e3 * m.step_s,
            1e3 * m.median_interval_s
        )
    });
    Some(format!(
        "the fitted model is worse than its start on its own training runs: {} {:.5} fitted against {:.5} for the \
         start as given ({:.1} times){why}",
        w.objective.name(),
        w.fitted,
        w.start,
        w.ratio()
    ))
}

/// Before fitting: a preset whose fixed step misses the runs' sampling is refused, or with `force` a
/// warning (returned, for the caller to say).
pub fn check_step(plan: &Plan, runs: &[omni_kin::Run], force: bool) -> anyhow::Result<Option<String>> {
    match fixed_step_mismatch(plan, runs) {
        Some(m) if !force => Err(Refused(format!("{m}; --force fits with the fixed step anyway")).into()),
        other => Ok(other),
    }
}

/// After fitting: a fit worse than its start is refused (nothing written), or with `force` a warning
/// (returned).
pub fn check_fit(c: &Calibration, plan: &Plan, runs: &[omni_kin::Run], force: bool) -> anyhow::Result<Option<String>> {
    match worse_than_start_text(c, plan, runs) {
        Some(w) if !force => Err(Refused(format!("{w}; nothing written (--force writes it anyway)")).into()),
        Some(w) => Ok(Some(format!("{w}; kept because of --force"))),
        None => Ok(None),
    }
}

/// A preset's plan with the command line's overrides.
pub fn apply_fit_args(mut plan: Plan, f: &FitArgs) -> anyhow::Result<Plan> {
    if f.every == 0 {
        anyhow::bail!("--every must be ≥ 1 (1 = every ground-truth pose)");
    }
    if !(f.heading_weight.is_finite() && f.heading_weight >= 0.0) {
        anyhow::bail!("--heading-weight must be a finite number ≥ 0 (m/rad), got {}", f.heading_weight);
    }
    if !(f.max_std_error.is_finite() && f.max_std_error > 0.0) {
        anyhow::bail!("--max-std-error must be a finite fraction > 0, got {}", f.max_std_error);
    }
    let objective = f.objective.unwrap_or(plan.objective.cost_name());
    plan.objective = objective.with_path_settings(f.every, f.heading_weight);
    plan.unexcited = f.unexcited.unwrap_or(plan.unexcited);
    if !(f.min_excitation.is_finite() && (0.0..1.0).contains(&f.min_excitation)) {
        anyhow::bail!("--min-excitation must be a fraction in [0, 1), got {}", f.min_excitation);
    }
    plan.identify.max_std_error = f.max_std_error;
    plan.identify.min_excitation = f.min_excitation;
    Ok(plan)
}

/// A robot description's prior on one parameter of the fit (docs/formats.md, `[priors]`).
struct PriorUse {
    /// The parameter (`r_left`).
    name: String,
    /// Its unit.
    unit: String,
    /// Its design value (the start).
    design: f64,
    /// The prior's one-sigma uncertainty, in the parameter's unit.
    std: f64,
}

impl PriorUse {
    /// How many σ the fitted value lies from the design.
    fn sigmas(&self, fitted: &FittedModel) -> f64 {
        fitted.get(&self.name).map_or(f64::NAN, |v| (v - self.design) / self.std)
    }

    fn to_json(&self, fitted: &FittedModel) -> serde_json::Value {
        json!({
            "name": self.name, "unit": self.unit, "design": self.design, "std": self.std,
            "fitted": fitted.get(&self.name), "sigmas": self.sigmas(fitted),
        })
    }

    fn describe(&self, fitted: &FittedModel) -> String {
        format!(
            "prior {}: design {} ± {} {} (GA box ±{PRIOR_BOX_SIGMAS} σ), fitted {:.6} ({:+.1} σ)",
            self.name,
            self.design,
            self.std,
            self.unit,
            fitted.get(&self.name).unwrap_or(f64::NAN),
            self.sigmas(fitted)
        )
    }
}

/// The `[priors]` of the robot description the design came from, on the start's base parameters they
/// cover (the parametric models' radii, positions, angles, separation). An `ik` matrix has none: a note
/// says the priors are not used then.
fn robot_priors(start: &FittedModel, ds: &crate::dataset::Dataset) -> Vec<PriorUse> {
    let Some(Design::File(f)) = robot_file::design(ds) else { return Vec::new() };
    let found = priors_of(start, ds);
    if found.is_empty() && f.description.priors.is_some() {
        // A warning, not a note (shown with -q too): a setting of the user's file goes unused.
        tracing::warn!(
            "the [priors] of {} bound the parametric models' search (--model geometry, diff or mecanum); \
             the {} model's parameters keep the preset's box",
            f.source,
            start.model.kinematics.id()
        );
    }
    found
}

/// The priors of [`robot_priors`], without its note.
fn priors_of(start: &FittedModel, ds: &crate::dataset::Dataset) -> Vec<PriorUse> {
    let Some(Design::File(f)) = robot_file::design(ds) else { return Vec::new() };
    let Some(priors) = &f.description.priors else { return Vec::new() };
    let specs = start.model.params();
    specs[..start.model.n_base()]
        .iter()
        .zip(&start.params)
        .filter_map(|(s, v)| {
            let std = priors.std_of(&s.name)?;
            Some(PriorUse { name: s.name.clone(), unit: s.unit.clone(), design: *v, std })
        })
        .collect()
}

/// The GA half-widths (parameter units) that the `[priors]` of `ds`'s robot description set on `start`'s
/// base parameters, as `omnical train` uses them (`Plan::half_widths`; `PRIOR_BOX_SIGMAS` σ each). The
/// Python binding's `train`.
pub fn prior_half_widths(start: &FittedModel, ds: &crate::dataset::Dataset) -> Vec<(String, f64)> {
    priors_of(start, ds).iter().map(|p| (p.name.clone(), PRIOR_BOX_SIGMAS * p.std)).collect()
}

/// The design model with its columns named: the robot description's joints (already), else `--joints`
/// (the order the runs were read in); the model file carries them. `--joints` in another order than the
/// robot description's is warned about: the design's columns follow the description.
fn named_columns(design: Model, joints: Option<&[String]>) -> anyhow::Result<Model> {
    let Some(joints) = joints.filter(|j| j.len() == design.n_wheels()) else { return Ok(design) };
    let names = design.kinematics.wheel_names();
    if names == omni_kin::geometry::default_wheel_names(names.len()) {
        return Ok(design.with_wheel_names(joints)?);
    }
    if names != joints {
        tracing::warn!(
            "--joints reads the wheels as {}, but the design's columns are the robot's {}: give the \
             joints in the robot description's order",
            joints.join(", "),
            names.join(", ")
        );
    }
    Ok(design)
}

/// Runs `omnical train`; `quiet` hides the progress display.
pub fn run(a: &Args, quiet: bool) -> anyhow::Result<()> {
    // Ctrl-C while loading ends the command; during the fit it stops the GA at its next generation and the
    // best model so far is reported and written.
    interrupt::install();
    if let Some(out) = &a.out {
        out_path::check_file(out, "--out")?;
    }
    let Prepared { ds, start, effects, plan, priors } = prepare(a)?;
    let preset_name = a.preset.id();
    if let Some(w) = check_step(&plan, &ds.runs, a.force)? {
        tracing::warn!("{w}");
    }
    let mut bar = progress::ProgressObserver::new(plan.ga().map_or(0, |g| g.max_generations), quiet);
    crate::note!(
        "training on {}: preset {preset_name}, seed {} (Ctrl-C stops early and keeps the best so far)",
        count(ds.runs.len(), "run"),
        a.seed
    );
    let c = calibrate_with_effects(&start, &effects, &ds.runs, &plan, &mut interrupt::StopOnInterrupt(&mut bar))?;
    bar.finish();
    if let Some(w) = check_fit(&c, &plan, &ds.runs, a.force)? {
        tracing::warn!("{w}");
    }
    let interrupted = interrupt::requested();
    let mut s = summary(&c, preset_name, a.seed, ds.runs.len())?;
    let designs = designs_figure(&c, &ds, &plan, a.start.is_none())?;
    if let Some(d) = &designs {
        s["designs"] = d.to_json();
    }
    if !priors.is_empty() {
        s["priors"] = priors.iter().map(|p| p.to_json(&c.fitted)).collect();
    }
    if interrupted {
        s["interrupted"] = json!(true);
    }
    if let Some(out) = &a.out {
        write_model(&c, &s, out)?;
    }
    if a.output.json {
        if !ds.ground_truth_clocks.is_empty() {
            s["ground_truth_clock"] = ds.ground_truth_clocks.iter().map(|g| g.to_json()).collect();
        }
        s["out"] = json!(a.out.as_ref().map(|p| p.display().to_string()));
        super::print_json("train", s)?;
    } else {
        if interrupted {
            println!("interrupted (Ctrl-C): the best model found so far (the GA stopped early; no polish)");
        }
        print_summary(&c, preset_name, ds.runs.len());
        if let Some(d) = &designs {
            println!("{}", d.describe());
        }
        for p in &priors {
            println!("{}", p.describe(&c.fitted));
        }
        if let Some(out) = &a.out {
            let what = if interrupted { "best-so-far model" } else { "model" };
            println!("{what} written to {}", out.display());
        }
    }
    if a.out.is_none() {
        crate::note!("note: the fitted model was not written (no --out FILE)");
    }
    if interrupted {
        return Err(interrupt::Interrupted.into());
    }
    Ok(())
}

/// What `omnical train` fits: the runs, the start model, the effects to add to it, the plan and the robot
/// description's priors.
struct Prepared {
    ds: Dataset,
    start: FittedModel,
    effects: Vec<EffectKind>,
    plan: Plan,
    priors: Vec<PriorUse>,
}

/// Loads the runs and builds the start model, the effects and the plan, as `omnical train` does. A Ctrl-C
/// (when the handler is installed) during loading ends it with [`interrupt::Interrupted`].
fn prepare(a: &Args) -> anyhow::Result<Prepared> {
    let ds = load_runs(&a.runs, &a.data)?;
    if interrupt::requested() {
        return Err(interrupt::Interrupted.into());
    }
    let start = match &a.start {
        Some(p) => model_file::read(p).context("reading --start")?,
        None => FittedModel::nominal(named_columns(design::model(a.model, &ds)?, a.data.joints.as_deref())?),
    };
    let effects = a
        .effects
        .iter()
        .map(|id| EffectKind::from_id(id, start.model.n_wheels()).with_context(|| format!("--effect {id}")))
        .collect::<anyhow::Result<Vec<_>>>()?;
    // The parameter count with the effects: the paper preset's GA fits them all at once.
    let n_params = start.model.n_params() + effects.iter().map(|e| e.params().len()).sum::<usize>();
    let mut plan = apply_fit_args(Plan::preset(a.preset, n_params).seed(a.seed), &a.fit)?;
    let priors = if a.start.is_none() { robot_priors(&start, &ds) } else { Vec::new() };
    plan.half_widths = priors.iter().map(|p| (p.name.clone(), PRIOR_BOX_SIGMAS * p.std)).collect();
    Ok(Prepared { ds, start, effects, plan, priors })
}

/// Writes the model file of a fit with its summary `s` as the `[fit]` table, atomically. Everything but the
/// wall time goes in: the same data, preset and seed give a byte-identical file.
fn write_model(c: &Calibration, s: &serde_json::Value, out: &std::path::Path) -> anyhow::Result<()> {
    let mut fit: toml::Table = toml::Table::try_from(toml_safe(s.clone())).context("fit summary")?;
    fit.remove("seconds");
    let text = model_file::to_toml(&c.fitted, Some(fit)).map_err(anyhow::Error::msg)?;
    atomic::write_atomic(out, text.as_bytes()).with_context(|| format!("writing {}", out.display()))
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

/// `omnical train` without a terminal, for callers that run many trainings in one process (the Python
/// wheel's fleet workers): the same loading, start model, plan and fit as [`run`], and the same model file
/// written to `--out` (byte-identical: the same `write_model` either way), but nothing printed, no progress bar
/// and no Ctrl-C handler installed.
pub fn train_quietly(a: &Args) -> anyhow::Result<Trained> {
    if let Some(out) = &a.out {
        out_path::check_file(out, "--out")?;
    }
    let Prepared { ds, start, effects, plan, .. } = prepare(a)?;
    let mut warnings: Vec<String> = check_step(&plan, &ds.runs, a.force)?.into_iter().collect();
    let c = calibrate_with_effects(&start, &effects, &ds.runs, &plan, &mut omni_ga::observe::NoopObserver)?;
    warnings.extend(check_fit(&c, &plan, &ds.runs, a.force)?);
    let mut s = summary(&c, a.preset.id(), a.seed, ds.runs.len())?;
    if let Some(d) = designs_figure(&c, &ds, &plan, a.start.is_none())? {
        s["designs"] = d.to_json();
    }
    if let Some(out) = &a.out {
        write_model(&c, &s, out)?;
    }
    Ok(Trained { calibration: c, summary: s, dataset: ds, warnings })
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
    fn to_json(&self) -> serde_json::Value {
        json!({ "designs": self.designs, "cost": self.end_pose, "objective": self.objective, "start": self.start })
    }

    fn describe(&self) -> String {
        let start = self.start.as_ref().map_or("the --start model".to_string(), |s| format!("{s}'s design"));
        format!(
            "design, each run its own input's ({} designs): Eq. 6 {:.5}, objective {:.5}; the fit started from {start} \
             (the \"design\" above)",
            self.designs, self.end_pose, self.objective
        )
    }
}

/// [`DesignsFigure`] for a fit on `ds`'s runs, `None` when its inputs declare one design (or none).
fn designs_figure(
    c: &Calibration,
    ds: &Dataset,
    plan: &Plan,
    from_design: bool,
) -> anyhow::Result<Option<DesignsFigure>> {
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

/// Human-readable fit summary on stdout; its warnings and notes go to stderr.
pub fn print_summary(c: &Calibration, preset: &str, runs: usize) {
    println!("preset {preset}: {}, objective {}", count(runs, "training run"), c.objective.name());
    println!(
        "cost (Eq. 6)  design {:.5}  fitted {:.5}  improvement {:.1} %",
        c.end_pose_start,
        c.end_pose_fitted,
        c.improvement_pct()
    );
    println!("objective     design {:.5}  fitted {:.5}", c.objective_start, c.objective_fitted);
    if let Ok(m) = c.fitted.ik() {
        println!("fitted IK matrix (rows vx m/s, vy m/s, ω rad/s per wheel rad/s):");
        for r in m.rows() {
            println!("  [{}]", r.iter().map(|v| format!("{v:>14.10}")).collect::<Vec<_>>().join(" "));
        }
    }
    let nb = c.fitted.model.n_base();
    let specs = c.fitted.model.params();
    // The matrix above shows base parameters that are its entries (all of an `ik` model's, also when some
    // entries are structural zeros, as a diff base's vy row); print the others.
    let base_shown = c.fitted.model.kinematics.kind() == KinematicsKind::Ik;
    if !base_shown || specs.len() > nb {
        for (i, s) in specs.iter().enumerate() {
            if i >= nb || !base_shown {
                println!("  {:<28} {}", s.name, value_text(c.fitted.params[i], &s.unit));
            }
        }
    }
    println!("{} evaluations, {:.2} s", c.evaluations, c.seconds);
    if !c.at_bound.is_empty() {
        tracing::warn!("ended on a bound of the GA box: {}", c.at_bound.join(", "));
    }
    if !c.outside_box.is_empty() {
        crate::note!("note: the polish left the GA box (the box was too small) for: {}", c.outside_box.join(", "));
    }
    print_identifiability(c);
}

/// Standard errors and condition number on stdout; a warning per unconstrained direction on stderr.
pub fn print_identifiability(c: &Calibration) {
    let id = &c.identifiability;
    println!(
        "identifiability: condition number {:.3e} (scaled), residual RMS {:.4} m, standard errors {}",
        id.condition_number,
        id.residual_rms,
        text::covariance(id)
    );
    // The IK matrix's ω row is in rad per wheel rad, a ratio and not an angle: it keeps its unit.
    let model = &c.fitted.model;
    let ik_entries: Vec<String> = if model.kinematics.kind() == KinematicsKind::Ik {
        model.params().into_iter().take(model.n_base()).map(|s| s.name).collect()
    } else {
        Vec::new()
    };
    let se: Vec<String> = id
        .params
        .iter()
        .map(|p| match p.std_error {
            Some(s) if ik_entries.contains(&p.name) => format!("{} ±{:.2e} {}", p.name, s, p.unit),
            Some(s) => format!("{} {}", p.name, std_error_text(s, &p.unit)),
            None => format!("{} undetermined", p.name),
        })
        .collect();
    for chunk in se.chunks(3) {
        println!("  {}", chunk.join(" · "));
    }
    for w in id.warnings() {
        tracing::warn!("{w}");
    }
    if !c.held.is_empty() {
        crate::note!(
            "note: {} direction(s) held at the start values (truncated update; `--unexcited move` lets them move)",
            c.held.len()
        );
    }
}
