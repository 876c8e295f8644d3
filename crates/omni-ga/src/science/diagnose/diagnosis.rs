//! What a diagnosis returns: the costs of each rung of the error ladder, each candidate effect's evidence,
//! the noise floor, per-run and per-group errors, and the findings and verdict, as facts with their words.

use super::{ExcitationGap, Explored, Finding, GroupBasis, UnexplainedEvidence, Verdict};
use crate::science::coverage::MotionCoverage;
use crate::science::explore::Exploration;
use crate::science::identify::Identifiability;
use omni_kin::FittedModel;
use serde::{Deserialize, Serialize};

/// Costs of a model on training and held-out runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Costs {
    /// Path RMS on training runs. m (heading 1 m/rad).
    pub train_path: f64,
    /// Path RMS on held-out runs.
    pub held_out_path: f64,
    /// Eq. 6 on training runs.
    pub train_end_pose: f64,
    /// Eq. 6 on held-out runs.
    pub held_out_end_pose: f64,
}

/// Per-run comparison.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunReport {
    /// Run name.
    pub name: String,
    /// Command label, when known.
    pub command: Option<String>,
    /// Path RMS of the model. m.
    pub path_rms: f64,
    /// Path RMS of the design model. m.
    pub design_path_rms: f64,
    /// End-pose error (Eq. 6 term) of the model.
    pub end_error: f64,
    /// End-pose error of the design model.
    pub design_end_error: f64,
}

/// Errors of a group of runs sharing a command direction and turn sign, or (runs without a command) the
/// same kind of path ([`MotionKind`](super::MotionKind)).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GroupReport {
    /// `α=30° ω>0` style label, or the kind of path (`arcs, net turn left, ~0.20 m/s, ~4.00 m`).
    pub group: String,
    /// Whether the runs repeat one command or only share a kind of path.
    #[serde(default)]
    pub basis: GroupBasis,
    /// Runs in it.
    pub runs: usize,
    /// Mean end-pose error vector (dx m, dy m, dθ rad) in the world frame.
    pub mean_end_error: [f64; 3],
    /// Its norm: the systematic part.
    pub bias: f64,
    /// Scatter between runs (RMS deviation from the mean): the random part.
    pub scatter: f64,
    /// Smallest two-sided p-value of the t-tests of the mean's components (dx, dy, dθ) against their
    /// standard errors from the repeats, Bonferroni-corrected (×3); `None` for a single run.
    pub p_value: Option<f64>,
    /// The bias is beyond the repeat scatter: `p_value` below 5 % (never for a single run).
    pub systematic: bool,
}

/// How the error grows along the runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Growth {
    /// Fraction of run time at the bin centres (0…1).
    pub fraction: Vec<f64>,
    /// Mean position error in each bin. m.
    pub position_m: Vec<f64>,
    /// Mean |heading error| in each bin. rad.
    pub heading_rad: Vec<f64>,
}

/// One candidate effect's evidence.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Candidate {
    /// Effect id.
    pub effect: String,
    /// Physics in one line.
    pub physics: String,
    /// Share of the training residual the effect could explain to first order (0…1); for an effect without
    /// parameters (`sample_timing`), the exact share switching it on removes; NaN (JSON null) when switching
    /// it on changes no residual (then `not_excited` says so).
    pub first_order_explained: f64,
    /// Smallest share of the effect's sensitivity outside the model's (0 = fully absorbed).
    pub separability: f64,
    /// The model already expresses it (separability < 5 %).
    pub absorbed: bool,
    /// Effect values the model's change from design implies (when absorbed).
    pub implied: Vec<ParamValue>,
    /// Costs after refitting with the effect (None when absorbed or the refit failed).
    pub refit: Option<Costs>,
    /// Relative fall of the held-out path cost (positive = better).
    pub held_out_gain: f64,
    /// Share of the held-out excess variance over the noise floor that the effect removes:
    /// `(before² − after²) / (before² − floor²)` (NaN without a noise floor).
    pub excess_closed: f64,
    /// Fitted effect parameters with standard errors.
    pub params: Vec<ParamValue>,
    /// Why the training runs cannot tell this effect (not ranked), when they cannot: `excitation_gap` in
    /// words.
    #[serde(default)]
    pub not_excited: Option<String>,
    /// Why the training runs cannot tell this effect, as facts.
    #[serde(skip)]
    pub excitation_gap: Option<ExcitationGap>,
    /// The effect's parameters the refit held at their null values (truncated update: the runs do not
    /// constrain them), as `train --effect` holds them; the held-out gain is with them held.
    #[serde(default)]
    pub held: Vec<String>,
    /// The refit model with the effect (None when absorbed, not excited or the refit failed).
    #[serde(skip)]
    pub fitted: Option<FittedModel>,
}

/// A named value with unit and optional standard error.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ParamValue {
    /// Name.
    pub name: String,
    /// Value.
    pub value: f64,
    /// Unit.
    pub unit: String,
    /// Standard error (same unit), when estimated.
    pub std_error: Option<f64>,
}

/// A candidate judged on whole kinds of path it was not fitted on.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct KindOut {
    /// Effect id.
    pub effect: String,
    /// Per kind left out: (kind, path RMS without the effect, with it). m.
    pub folds: Vec<(String, f64, f64)>,
    /// Relative fall of the path cost over all left-out kinds (positive = better).
    pub gain: f64,
}

/// One rung of the error ladder.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Rung {
    /// `design`, `fitted matrix`, `+ time_offset`, …
    pub label: String,
    /// Costs at this rung.
    pub costs: Costs,
}

/// Measurement noise seen while the robot stands still.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct NoiseFloor {
    /// Position noise per axis. m.
    pub position_m: f64,
    /// Heading noise. rad.
    pub heading_rad: f64,
    /// Path RMS expected from this noise alone (start and current pose noise). m.
    pub path_rms: f64,
    /// Poses used (at rest; or third differences, for the jitter estimate).
    pub samples: usize,
    /// Where the estimate comes from.
    #[serde(default)]
    pub source: NoiseSource,
}

/// Where a noise floor comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseSource {
    /// The scatter of the ground truth while the robot stands still (rests at the runs' ends).
    #[default]
    Standstill,
    /// The runs never stand still: the ground truth's sample-to-sample jitter while moving (third
    /// differences).
    Jitter,
}

/// The whole diagnosis.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Effect to add (None: nothing helps beyond `min_gain`).
    pub verdict: Option<String>,
    /// The verdict in words (`conclusion`, worded by [`text::verdict`](crate::science::text::verdict)).
    pub verdict_text: String,
    /// A systematic error remains that no accepted effect (the verdict's, or those `auto` added) removes:
    /// decided by the share of command groups biased beyond their repeat scatter, or, without repeats, by
    /// the remaining held-out error against the noise floor (see `unexplained_evidence.decided_by`).
    pub unexplained: bool,
    /// The figures behind `unexplained`.
    pub unexplained_evidence: UnexplainedEvidence,
    /// How held-out costs were obtained, in words (`protocol`): `validation set` or `2-fold cross-validation
    /// over repetitions`.
    pub held_out: String,
    /// Costs of the model as given.
    pub costs: Costs,
    /// Costs of the design model.
    pub design_costs: Costs,
    /// Per-run comparison (training runs).
    pub runs: Vec<RunReport>,
    /// Per command group (training runs).
    pub groups: Vec<GroupReport>,
    /// Error growth along the path (training runs, 10 bins).
    pub growth: Growth,
    /// Where it fails, in words (`facts`, worded by [`text::finding`](crate::science::text::finding)).
    pub findings: Vec<String>,
    /// Candidates, best held-out gain first.
    pub ranking: Vec<Candidate>,
    /// Measurement noise floor, when the data has standstills.
    pub noise_floor: Option<NoiseFloor>,
    /// Error ladder: design → model → + effects (with `auto`).
    pub ladder: Vec<Rung>,
    /// What the training runs constrain in the model as given (path residuals).
    pub identifiability: Option<Identifiability>,
    /// Scatter of the end-pose error between repeats of the same command (RMS over groups of ≥ 2 runs),
    /// in Eq. 6 units: the part of the error no deterministic effect can remove. `None` without repeats.
    pub repeatability_floor: Option<f64>,
    /// The verdict's effect validated on kinds of path left out of its fit (straight, turning left,
    /// turning right), when the runs have several kinds.
    pub kind_out: Option<KindOut>,
    /// The best candidate's refit on the held-out runs by the shape of their paths (straight, turning on
    /// the spot, sides then turns, arcs, free): it is not recommended when it hurts one
    /// (`hurts_a_kind`: a kind more than 2 % worse, or the kinds pooled worse).
    pub held_out_kinds: Option<KindOut>,
    /// The training runs' motions against the held-out runs' (with a validation set): what the training
    /// runs lack.
    pub coverage: Option<MotionCoverage>,
    /// `auto` with held-out runs: the explorer's best passing family, which the final model carries and
    /// the verdict names (`unexplained` is then judged with it).
    pub explored: Option<Explored>,
    /// The final model (the input, plus effects added by `auto`, plus the family the explorer passed).
    #[serde(skip)]
    pub final_model: Option<FittedModel>,
    /// `auto` with held-out runs: the explorer's families, fitted from the ladder's model on the training
    /// runs and judged on the held-out runs (the verdict names the best passing one).
    #[serde(skip)]
    pub exploration: Option<Exploration>,
    /// How held-out costs were obtained.
    #[serde(skip)]
    pub protocol: HeldOut,
    /// Where it fails, as facts.
    #[serde(skip)]
    pub facts: Vec<Finding>,
    /// The verdict, as facts.
    #[serde(skip)]
    pub conclusion: Verdict,
}

impl Diagnosis {
    /// An error remains that the final model does not remove: something is missing, or the remaining
    /// held-out error is above `MISSING_RATIO` (3×) the noise floor.
    pub fn error_remains(&self) -> bool {
        self.unexplained || self.conclusion.remaining.is_some_and(|r| r.missing)
    }
}

/// How the held-out costs were obtained.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HeldOut {
    /// On the validation runs given.
    #[default]
    ValidationSet,
    /// On the training runs themselves (too few to hold any out).
    TrainingRuns,
    /// By 2-fold cross-validation over repetitions (even → odd).
    CrossValidation,
}

/// What a rung of the error ladder is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RungKind {
    /// The design model.
    Design,
    /// The model as given.
    Model,
    /// The model so far plus this effect, refitted.
    Added(String),
}
