//! Steps 4 and 5 of a diagnosis: where the model fails and what to do about it, as facts. Their words are
//! made by [`crate::science::text`].

use super::kinds::GroupBasis;
use super::noise::ExcitationGap;
use super::search::passes;
use super::unexplained::{MISSING_RATIO, UnexplainedEvidence, decide};
use super::{Candidate, Costs, DiagnoseOptions, GroupReport, Growth, KindOut, NoiseFloor, ParamValue, RunReport};
use crate::science::coverage::MotionCoverage;
use crate::science::identify::{Identifiability, WeakDirection};
use serde::{Deserialize, Serialize};

/// One fact about where the model fails.
#[derive(Clone, Debug)]
pub enum Finding {
    /// The run with the largest path error.
    WorstRun {
        /// Its name.
        run: String,
        /// Its command label, when known.
        command: Option<String>,
        /// Path RMS of the model. m.
        path_rms_m: f64,
        /// Path RMS of the design. m.
        design_path_rms_m: f64,
    },
    /// Command groups whose end-pose error has a bias beyond the repeat scatter.
    SystematicGroups {
        /// Groups with a systematic error (of more than one run).
        systematic: usize,
        /// All groups.
        groups: usize,
        /// The one with the largest bias.
        largest: GroupReport,
    },
    /// Mean position error early and late in the runs. m.
    ErrorGrowth {
        /// In the first bin.
        early_m: f64,
        /// In the last bin.
        late_m: f64,
    },
    /// An effect the model already expresses on these runs, with the values it implies.
    Absorbed {
        /// Effect id.
        effect: String,
        /// Implied effect values.
        implied: Vec<ParamValue>,
    },
    /// An effect the training runs do not excite.
    NotExcited {
        /// Effect id.
        effect: String,
        /// Why.
        gap: ExcitationGap,
    },
    /// Held-out runs the model follows worse than the design (path RMS).
    WorseThanDesign {
        /// Runs worse than the design.
        worse: usize,
        /// Held-out runs.
        runs: usize,
    },
    /// A direction of the model itself that the runs do not constrain.
    Unconstrained(WeakDirection),
    /// The held-out runs contain motions the training runs never do (e.g. arcs after squares).
    MissingMotions(MotionCoverage),
    /// The wheels and the reference disagree in time: a clock offset between them, measured without a
    /// model ([`super::clock_lag`]).
    ClockLag(super::ClockLag),
    /// Scatter of the end-pose error between repeats of the same command, or runs of one kind (Eq. 6
    /// units).
    RepeatabilityFloor {
        /// The scatter.
        scatter: f64,
        /// What the groups are.
        basis: GroupBasis,
    },
}

/// What the diagnosis concludes, before the noise comparison.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Conclusion {
    /// Add the effect: the held-out path cost falls by `gain` (fraction), from `before_m` to `after_m`.
    Add {
        /// Effect id.
        effect: String,
        /// Relative fall of the held-out path cost.
        gain: f64,
        /// Held-out path cost without it. m.
        before_m: f64,
        /// With it. m.
        after_m: f64,
    },
    /// The best effect passes the gain test but removes only `excess_closed` of the error above the noise
    /// floor: no verdict.
    Partial {
        /// Effect id.
        effect: String,
        /// Relative fall of the held-out path cost.
        gain: f64,
        /// Share of the excess error variance removed.
        excess_closed: f64,
    },
    /// No catalogued effect helps.
    #[default]
    Nothing,
    /// The best effect's refit hurts a kind of held-out path (more than 2 % worse on one kind): the term
    /// depends on the motion.
    HurtsKinds {
        /// Effect id.
        effect: String,
        /// Per kind of path: (kind, held-out path RMS without it, with it). m.
        folds: Vec<(String, f64, f64)>,
    },
    /// The best effect helps on repeats of the training paths but not on kinds of path left out of its fit.
    NotOnNewKinds {
        /// Effect id.
        effect: String,
        /// Relative fall of the path cost on the left-out kinds (negative: it rose).
        gain: f64,
    },
}

/// The error that would remain, against the measurement noise floor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Remaining {
    /// Held-out path RMS after the recommended effect (or the ladder's top). m.
    pub held_out_m: f64,
    /// The noise floor's path RMS. m.
    pub floor_m: f64,
    /// `held_out_m / floor_m`.
    pub ratio: f64,
    /// The ratio is above 3.
    pub missing: bool,
}

/// The verdict as facts: the conclusion, the remaining error against the noise floor (when the data has
/// standstills), and whether a systematic error remains that no accepted effect removes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Verdict {
    /// What to do.
    pub conclusion: Conclusion,
    /// The remaining held-out error against the noise floor.
    pub remaining: Option<Remaining>,
    /// A systematic error remains that no accepted effect removes.
    pub unexplained: bool,
    /// The figures behind `unexplained` and which of them decided.
    pub evidence: UnexplainedEvidence,
    /// Beyond the catalogue: the explorer's best passing family (`auto` with held-out runs), which the final
    /// model then carries; `unexplained` and `evidence` are then judged with it.
    pub explored: Option<Explored>,
}

/// A learned family the explorer passed on held-out runs, as the verdict names it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Explored {
    /// The effect id: `learned:wheel`.
    pub effect: String,
    /// Relative fall of the held-out path cost against the explorer's baseline.
    pub gain: f64,
    /// Held-out path cost of the baseline (the model refitted without a family). m.
    pub before_m: f64,
    /// Held-out path cost with the family. m.
    pub after_m: f64,
    /// What its strongest terms mean physically, in words (`an oval wheel`).
    pub hint: String,
}

/// Where the model fails, in report order.
pub(super) fn findings(
    runs: &[RunReport],
    groups: &[GroupReport],
    growth: &Growth,
    ranking: &[Candidate],
    identifiability: Option<&Identifiability>,
    repeatability_floor: Option<f64>,
) -> Vec<Finding> {
    let mut out = Vec::new();
    let mut worst: Vec<&RunReport> = runs.iter().collect();
    worst.sort_by(|a, b| b.path_rms.total_cmp(&a.path_rms));
    if let Some(w) = worst.first() {
        out.push(Finding::WorstRun {
            run: w.name.clone(),
            command: w.command.clone(),
            path_rms_m: w.path_rms,
            design_path_rms_m: w.design_path_rms,
        });
    }
    let mut sys: Vec<&GroupReport> = groups.iter().filter(|g| g.systematic && g.runs > 1).collect();
    let systematic = sys.len();
    sys.sort_by(|a, b| b.bias.total_cmp(&a.bias));
    if let Some(largest) = sys.first() {
        out.push(Finding::SystematicGroups { systematic, groups: groups.len(), largest: (*largest).clone() });
    }
    if let (Some(first), Some(last)) = (growth.position_m.first(), growth.position_m.last()) {
        out.push(Finding::ErrorGrowth { early_m: *first, late_m: *last });
    }
    for c in ranking.iter().filter(|c| c.absorbed) {
        out.push(Finding::Absorbed { effect: c.effect.clone(), implied: c.implied.clone() });
    }
    for c in ranking {
        if let Some(gap) = &c.excitation_gap {
            out.push(Finding::NotExcited { effect: c.effect.clone(), gap: gap.clone() });
        }
    }
    for w in identifiability.map_or(&[][..], |id| &id.weak[..]) {
        out.push(Finding::Unconstrained(w.clone()));
    }
    if let Some(scatter) = repeatability_floor {
        let motion = groups.iter().any(|g| g.runs >= 2 && g.basis == GroupBasis::Motion);
        let basis = if motion { GroupBasis::Motion } else { GroupBasis::Command };
        out.push(Finding::RepeatabilityFloor { scatter, basis });
    }
    out
}

/// What the ranking, the verdict and the left-out-kinds check add up to.
pub(super) struct Judgement<'a> {
    /// Candidates, best first.
    pub ranking: &'a [Candidate],
    /// The recommended effect, after the kinds check.
    pub verdict: Option<&'a str>,
    /// The left-out-kinds check of the winner, when it ran.
    pub kind_check: Option<&'a KindOut>,
    /// The winner's refit on the held-out runs by kind of path.
    pub held_kinds: Option<&'a KindOut>,
    /// Costs of the model as given.
    pub costs: &'a Costs,
    /// Costs at the ladder's top.
    pub top: &'a Costs,
    /// The measurement noise floor.
    pub noise: Option<&'a NoiseFloor>,
    /// Command groups of the training runs with the accepted effects (the verdict's, or `auto`'s).
    pub groups: &'a [GroupReport],
    /// Error growth along the training runs with the accepted effects.
    pub growth: &'a Growth,
    /// Repeatability floor with the accepted effects.
    pub repeat_floor: Option<f64>,
}

impl Judgement<'_> {
    /// The verdict as facts.
    pub(super) fn verdict(&self, opts: &DiagnoseOptions) -> Verdict {
        let best = self.ranking.first();
        let hurting = self.held_kinds.filter(|k| self.verdict.is_none() && super::search::hurts_a_kind(k));
        let conclusion = match (self.kind_check.filter(|k| super::search::hurts_a_kind(k)), self.verdict, best) {
            _ if hurting.is_some() => {
                let k = hurting.map_or_else(KindOut::default, Clone::clone);
                Conclusion::HurtsKinds { effect: k.effect, folds: k.folds }
            }
            (Some(k), _, _) => Conclusion::NotOnNewKinds { effect: k.effect.clone(), gain: k.gain },
            (None, Some(v), Some(c)) => Conclusion::Add {
                effect: v.to_string(),
                gain: c.held_out_gain,
                before_m: self.costs.held_out_path,
                after_m: c.refit.as_ref().map(|r| r.held_out_path).unwrap_or(f64::NAN),
            },
            (None, _, Some(c)) if passes(c, opts) => {
                Conclusion::Partial { effect: c.effect.clone(), gain: c.held_out_gain, excess_closed: c.excess_closed }
            }
            _ => Conclusion::Nothing,
        };
        // The error that would remain: after the recommended effect (or the ladder's last rung).
        let held_out_m = match (self.verdict, best, opts.auto) {
            (Some(_), Some(c), false) => c.refit.as_ref().map_or(self.top.held_out_path, |c| c.held_out_path),
            _ => self.top.held_out_path,
        };
        let remaining = self.noise.map(|nf| {
            let ratio = held_out_m / nf.path_rms.max(1e-12);
            Remaining { held_out_m, floor_m: nf.path_rms, ratio, missing: ratio > MISSING_RATIO }
        });
        let (unexplained, evidence) = decide(self.groups, self.growth, self.repeat_floor, held_out_m, self.noise);
        Verdict { conclusion, remaining, unexplained, evidence, explored: None }
    }
}
