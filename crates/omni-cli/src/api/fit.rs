//! The fit settings over a preset ([`FitOptions`], validated once) and the refusals of a fit ([`Refused`]):
//! what `omnical train` and Python's `train` share.

use crate::api::settings::{named, named_with};
use crate::robot_file::{self, Design};
use omni_ga::calibrate::{Calibration, Plan, Unexcited};
use omni_ga::identify::IdentifyOptions;
use omni_kin::FittedModel;
use omni_kin::cost::{CostKind, CostName};
use omni_kin::robot::PRIOR_BOX_SIGMAS;
use serde_json::json;

/// Overrides of a preset's objective and its handling of unconstrained directions (`omnical train`'s
/// flags, Python `train`'s keywords). `Default` is what no option gives.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// Objective (`None`: the preset's).
    pub objective: Option<CostName>,
    /// Path objective: every k-th ground-truth pose (k ≥ 1).
    pub every: usize,
    /// Path objective: weight of heading errors against position errors (m/rad, finite, ≥ 0).
    pub heading_weight_m_per_rad: f64,
    /// Directions the runs do not constrain: hold or move (`None`: the preset's).
    pub unexcited: Option<Unexcited>,
    /// A direction is unconstrained when its standard error exceeds this fraction of the parameters' scale
    /// (finite, > 0).
    pub max_std_error: f64,
    /// A direction is unconstrained when its singular value is below this fraction of the largest (in
    /// [0, 1)).
    pub min_excitation: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            objective: None,
            every: CostKind::PATH_EVERY,
            heading_weight_m_per_rad: CostKind::PATH_HEADING_WEIGHT_M_PER_RAD,
            unexcited: None,
            max_std_error: IdentifyOptions::default().max_std_error,
            min_excitation: IdentifyOptions::default().min_excitation,
        }
    }
}

/// A fit setting out of its range; the message names the setting ([`named`]).
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum FitOptionsError {
    /// `every` is 0.
    #[error("{} must be ≥ 1 (1 = every ground-truth pose)", named("every"))]
    Every,
    /// `heading_weight_m_per_rad` is negative or not finite.
    #[error("{} must be a finite number ≥ 0 (m/rad), got {value}", named("heading_weight"), value = .0)]
    HeadingWeight(f64),
    /// `max_std_error` is not a finite positive fraction.
    #[error("{} must be a finite fraction > 0, got {value}", named("max_std_error"), value = .0)]
    MaxStdError(f64),
    /// `min_excitation` is outside [0, 1).
    #[error("{} must be a fraction in [0, 1), got {value}", named("min_excitation"), value = .0)]
    MinExcitation(f64),
}

impl FitOptions {
    /// Checks every setting's range (the first one out of range is the error).
    pub fn validate(&self) -> Result<(), FitOptionsError> {
        if self.every == 0 {
            return Err(FitOptionsError::Every);
        }
        let w = self.heading_weight_m_per_rad;
        if !(w.is_finite() && w >= 0.0) {
            return Err(FitOptionsError::HeadingWeight(w));
        }
        if !(self.max_std_error.is_finite() && self.max_std_error > 0.0) {
            return Err(FitOptionsError::MaxStdError(self.max_std_error));
        }
        if !(self.min_excitation.is_finite() && (0.0..1.0).contains(&self.min_excitation)) {
            return Err(FitOptionsError::MinExcitation(self.min_excitation));
        }
        Ok(())
    }

    /// A preset's plan with these overrides, once [`FitOptions::validate`] passes.
    pub fn apply(&self, mut plan: Plan) -> Result<Plan, FitOptionsError> {
        self.validate()?;
        let objective = self.objective.unwrap_or(plan.objective.cost_name());
        plan.objective = objective.with_path_settings(self.every, self.heading_weight_m_per_rad);
        plan.unexcited = self.unexcited.unwrap_or(plan.unexcited);
        plan.identify.max_std_error = self.max_std_error;
        plan.identify.min_excitation = self.min_excitation;
        Ok(plan)
    }
}

/// A fit refused (the command's exit status 1, nothing written) unless `--force`: a preset whose fixed step
/// misses the runs' sampling (before fitting), a fit worse than its start on its own training runs, or one
/// implausibly far from its start.
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
         {} (each run's own step)",
        plan.preset,
        1e3 * m.step_s,
        1e3 * m.median_interval_s,
        m.factor(),
        named_with("preset", "default")
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
pub fn check_step(plan: &Plan, runs: &[omni_kin::Run], force: bool) -> Result<Option<String>, Refused> {
    match fixed_step_mismatch(plan, runs) {
        Some(m) if !force => Err(Refused(format!("{m}; {} fits with the fixed step anyway", named("force")))),
        other => Ok(other),
    }
}

/// After fitting: a fit worse than its start, or implausibly far from it ([`implausible_text`]), is refused
/// (nothing written), or with `force` a warning (returned).
pub fn check_fit(c: &Calibration, plan: &Plan, runs: &[omni_kin::Run], force: bool) -> Result<Option<String>, Refused> {
    let found: Vec<String> =
        [worse_than_start_text(c, plan, runs), implausible_text(c)].into_iter().flatten().collect();
    if found.is_empty() {
        return Ok(None);
    }
    let w = found.join("; ");
    if force {
        Ok(Some(format!("{w}; kept because of {}", named("force"))))
    } else {
        Err(Refused(format!("{w}; nothing written ({} writes it anyway)", named("force"))))
    }
}

/// A fitted model implausibly far from its start ([`crate::api::plausibility`]), in words: the reasons and
/// the base parameters that moved most.
pub fn implausible_text(c: &Calibration) -> Option<String> {
    use crate::api::plausibility::{implausible, moved_params};
    let (fitted, start) = (c.fitted.ik().ok()?, c.start.ik().ok()?);
    let reasons = implausible(&fitted, &start, &c.fitted.model.kinematics.wheel_names());
    if reasons.is_empty() {
        return None;
    }
    let moved = moved_params(&c.fitted, &c.start);
    Some(format!(
        "the fitted model is implausibly far from its start: {}{}. A mount the fit could not find (give \
         --gt-mount-start X,Y,YAW_DEG), a reference of another robot or in other units, or a robot description far \
         from the robot",
        reasons.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "),
        if moved.is_empty() { String::new() } else { format!(" (moved most: {})", moved.join(", ")) }
    ))
}

/// A robot description's prior on one parameter of the fit (docs/formats.md, `[priors]`).
pub struct PriorUse {
    /// The parameter (`r_left`).
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// Its design value (the start).
    pub design: f64,
    /// The prior's one-sigma uncertainty, in the parameter's unit.
    pub std: f64,
}

impl PriorUse {
    /// How many σ the fitted value lies from the design.
    pub fn sigmas(&self, fitted: &FittedModel) -> f64 {
        fitted.get(&self.name).map_or(f64::NAN, |v| (v - self.design) / self.std)
    }

    /// The prior and the fitted value as JSON (`omnical train --json`'s `priors`).
    pub fn to_json(&self, fitted: &FittedModel) -> serde_json::Value {
        json!({
            "name": self.name, "unit": self.unit, "design": self.design, "std": self.std,
            "fitted": fitted.get(&self.name), "sigmas": self.sigmas(fitted),
        })
    }

    /// The prior and the fitted value in words.
    pub fn describe(&self, fitted: &FittedModel) -> String {
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
pub fn robot_priors(start: &FittedModel, ds: &crate::dataset::Dataset) -> Vec<PriorUse> {
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
pub fn priors_of(start: &FittedModel, ds: &crate::dataset::Dataset) -> Vec<PriorUse> {
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
