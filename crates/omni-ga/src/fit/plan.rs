//! Calibration recipes: a [`Plan`] is an objective, an odometry integration, a search box and a list of
//! [`Stage`]s run in order; a [`Preset`] names a plan.

use crate::fit::search_box::BoxRule;
use crate::fit::stage::Stage;
use crate::optimizer::ga::{GaConfig, StallRule};
use crate::optimizer::lm::LmConfig;
use crate::science::identify::IdentifyOptions;
use omni_kin::cost::CostKind;
use omni_kin::{Integration, Run, StepMode};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Which recipe to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// The paper's method, reproduced.
    Paper,
    /// Ours: path cost, exact arcs, short GA + LM polish.
    Default,
}

omni_kin::choice!(Preset, default = Default, {
    Paper => "paper": "The paper's method, reproduced: Eq. 6 end-pose cost, Eq. 1 Euler at 10 ms, MATLAB-default GA, ±10 % box",
    Default => "default": "Ours: path cost, exact arcs, short GA then Levenberg–Marquardt",
});

/// What a fit does along directions of parameter space the training runs do not constrain
/// ([`crate::science::identify`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Unexcited {
    /// Truncated update (default preset): after the stages, the parameters are projected back onto the
    /// start along every unconstrained direction, and the stages that refine ([`Stage::refines_held`], the
    /// polish) run again within the constrained subspace only, so the fit keeps the start (design) values
    /// where the data cannot tell, and is never worse than the start on motions the training runs did not
    /// contain.
    Hold,
    /// Move freely (the paper's GA): unconstrained directions end wherever the search left them.
    Move,
}

omni_kin::choice!(Unexcited, default = Hold, {
    Hold => "hold": "Keep the start (design) values there: truncated update (default preset)",
    Move => "move": "Let the optimizer move them (paper preset)",
});

/// A calibration recipe.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Plan {
    /// The preset it came from.
    pub preset: Preset,
    /// Objective minimised.
    pub objective: CostKind,
    /// Odometry integration used during the fit (and stored in the fitted model).
    pub integration: Integration,
    /// The optimizers, run in order, each from the best point so far (empty: keep the start).
    pub stages: Vec<Stage>,
    /// Search box of the stages that stay within a box ([`Stage::within_box`]: the GA).
    pub box_rule: BoxRule,
    /// Base parameters whose GA box is instead the start ± this half-width (the parameter's unit), by
    /// name: a robot description's priors (3 σ of the design values). Empty: `box_rule` for every one.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub half_widths: BTreeMap<String, f64>,
    /// What to do along unconstrained directions.
    #[serde(default)]
    pub unexcited: Unexcited,
    /// When a direction counts as unconstrained.
    #[serde(default)]
    pub identify: IdentifyOptions,
}

impl Plan {
    /// The recipe of a preset for a model with `n_params` parameters.
    pub fn preset(preset: Preset, n_params: usize) -> Self {
        match preset {
            Preset::Paper => Plan {
                preset,
                objective: CostKind::EndPose,
                integration: Integration::PAPER,
                stages: vec![Stage::Ga(GaConfig::matlab_defaults(n_params))],
                box_rule: BoxRule::PerValue(0.10),
                half_widths: BTreeMap::new(),
                unexcited: Unexcited::Move,
                identify: IdentifyOptions::default(),
            },
            Preset::Default => {
                let mut ga = GaConfig::matlab_defaults(n_params);
                ga.population = 24;
                ga.elite = 2;
                ga.stall_generations = 8;
                ga.function_tolerance = 1e-4;
                ga.stall_rule = StallRule::Relative;
                ga.max_generations = 30;
                Plan {
                    preset,
                    objective: CostKind::PATH,
                    integration: Integration::DEFAULT,
                    stages: vec![Stage::Ga(ga), Stage::Lm(LmConfig::default())],
                    box_rule: BoxRule::PerRow(0.10),
                    half_widths: BTreeMap::new(),
                    unexcited: Unexcited::Hold,
                    identify: IdentifyOptions::default(),
                }
            }
        }
    }

    /// The plan diagnose and explore refit with ([`crate::fit::refine`]: the refining stages and the
    /// truncated update; the GA is not run): the default preset's, as `omnical train` uses it, on the path
    /// objective at every `every`-th ground-truth pose (heading weighted 1 m/rad, train's default).
    pub fn refit(every: usize) -> Self {
        let mut plan = Self::preset(Preset::Default, 0);
        plan.objective =
            CostKind::Path { every: every.max(1), heading_weight_m_per_rad: CostKind::PATH_HEADING_WEIGHT_M_PER_RAD };
        plan
    }

    /// The same plan with another seed for every stage that draws random numbers.
    pub fn seed(mut self, seed: u64) -> Self {
        self.stages.iter_mut().for_each(|s| s.set_seed(seed));
        self
    }

    /// The settings of the plan's first GA stage, if any (the presets' search).
    pub fn ga(&self) -> Option<&GaConfig> {
        self.stages.iter().find_map(|s| match s {
            Stage::Ga(c) => Some(c),
            _ => None,
        })
    }

    /// Mutable settings of the plan's first GA stage, if any.
    pub fn ga_mut(&mut self) -> Option<&mut GaConfig> {
        self.stages.iter_mut().find_map(|s| match s {
            Stage::Ga(c) => Some(c),
            _ => None,
        })
    }

    /// Whether the plan's fixed integration step (the paper's Eq. 1: one fixed step per wheel sample)
    /// misses the runs' sampling: the median over runs of each run's median wheel-sample interval more
    /// than [`STEP_TOLERANCE`] away from the step. On such runs every displacement is scaled by step /
    /// interval, and a fit compensates in its parameters. `None` for a plan that takes each run's own
    /// steps, or without runs.
    pub fn step_mismatch(&self, runs: &[Run]) -> Option<StepMismatch> {
        let StepMode::Fixed { dt_s: Some(step_s) } = self.integration.step else { return None };
        let mut dts: Vec<f64> = runs.iter().map(Run::median_dt_s).collect();
        dts.sort_by(f64::total_cmp);
        let median_interval_s = *dts.get(dts.len() / 2)?;
        ((median_interval_s / step_s - 1.0).abs() > STEP_TOLERANCE)
            .then_some(StepMismatch { step_s, median_interval_s })
    }
}

/// Relative difference between a plan's fixed step and the runs' sampling interval beyond which they
/// do not match ([`Plan::step_mismatch`]): 10 %.
pub const STEP_TOLERANCE: f64 = 0.1;

/// A plan's fixed step against the runs' sampling ([`Plan::step_mismatch`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepMismatch {
    /// The plan's fixed step. s.
    pub step_s: f64,
    /// The median over runs of each run's median wheel-sample interval. s.
    pub median_interval_s: f64,
}

impl StepMismatch {
    /// The factor every integrated displacement is off by: step / interval.
    pub fn factor(&self) -> f64 {
        self.step_s / self.median_interval_s
    }
}
