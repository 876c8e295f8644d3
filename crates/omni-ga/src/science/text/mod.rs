//! Every sentence the science layer says, made from its facts in one place: the diagnosis's findings and
//! verdict, the held-out protocol, labels of groups, kinds of path and ladder rungs, why runs do not excite
//! an effect, and what an unconstrained direction is and which runs would constrain it.
//!
//! Nothing else in the science layer writes words for people, and nothing branches on these words: they
//! are made last, from the structured findings ([`Finding`], [`Verdict`],
//! [`WeakDirection`](crate::science::identify::WeakDirection), …), and stored beside them in the results so
//! that JSON, the CLI and Python show the same text. The explorer's words are in `explore.rs`, the
//! identifiability analysis's in `identify.rs`.

use crate::science::coverage::{MotionCoverage, MotionGap, MotionKind};
use crate::science::diagnose::{
    Conclusion, DecidedBy, ExcitationGap, Finding, GapKind, GroupBasis, HeldOut, NoiseSource, RungKind, Turn,
    UnexplainedEvidence, Verdict,
};

mod explore;
mod identify;
pub use explore::{exploration, explore_conclusion, explore_hint, family_status};
pub use identify::{advice, covariance, warning, weak_direction};

/// How the held-out costs were obtained.
pub fn held_out(protocol: HeldOut) -> &'static str {
    match protocol {
        HeldOut::ValidationSet => "validation set",
        HeldOut::TrainingRuns => "training runs (too few to hold any out)",
        HeldOut::CrossValidation => "2-fold cross-validation over repetitions (even → odd)",
    }
}

/// The label of a command group: `α=30° ω>0` (direction of travel in degrees, turn), or `all` for runs
/// without a command.
pub fn command_group(group: Option<(f64, Turn)>) -> String {
    match group {
        Some((alpha_deg, turn)) => {
            let turn = match turn {
                Turn::Left => "ω>0",
                Turn::Right => "ω<0",
                Turn::Straight => "ω=0",
            };
            format!("α={alpha_deg:.0}° {turn}")
        }
        None => "all".into(),
    }
}

/// The name of a kind of path.
pub fn path_kind(turn: Turn) -> &'static str {
    match turn {
        Turn::Straight => "straight",
        Turn::Left => "turning left",
        Turn::Right => "turning right",
    }
}

/// The label of a rung of the error ladder: `design`, `model`, `+ time_offset`.
pub fn rung(kind: &RungKind) -> String {
    match kind {
        RungKind::Design => "design".into(),
        RungKind::Model => "model".into(),
        RungKind::Added(effect) => format!("+ {effect}"),
    }
}

/// A share (0…1) as a percentage with one decimal: `-` when it is not a number (nothing measured), and
/// `0.0` for a share that rounds to zero from below (never `-0.0`).
pub fn percent_1(share: f64) -> String {
    if !share.is_finite() {
        return "-".into();
    }
    let p = 100.0 * share;
    if p.abs() < 0.05 { "0.0".into() } else { format!("{p:.1}") }
}

/// Why the runs cannot tell an effect without parameters (`sample_timing`): switching it on changes no
/// predicted pose, so no refit or share can say anything about it. `uses_stamps`: it integrates with the
/// measured sample stamps (then every sample is at the nominal step).
pub fn changes_nothing(uses_stamps: bool) -> String {
    if uses_stamps {
        "every wheel sample is at the nominal step, so integrating with the measured stamps changes no \
         predicted pose (not identifiable on these runs)"
            .into()
    } else {
        "it has no parameters and changes no predicted pose (not identifiable on these runs)".into()
    }
}

/// Why the runs cannot tell a wheel-stage effect, wheel by wheel.
pub fn excitation_gap(gap: &ExcitationGap) -> String {
    let wheels: Vec<String> = gap
        .wheels
        .iter()
        .map(|w| match w.kind {
            GapKind::OneWay { forward_pct } => format!("{} turns one way only ({forward_pct:.0} % forward)", w.wheel),
            GapKind::OneSpeed { low_rad_s, high_rad_s } => {
                format!("{} runs at one speed only (|ω| {low_rad_s:.2}–{high_rad_s:.2} rad/s)", w.wheel)
            }
        })
        .collect();
    wheels.join("; ")
}

/// One finding of a diagnosis.
pub fn finding(f: &Finding) -> String {
    match f {
        Finding::WorstRun { run, command, path_rms_m, design_path_rms_m } => format!(
            "worst training run {run} ({}): path RMS {path_rms_m:.4} m (design {design_path_rms_m:.4})",
            command.as_deref().unwrap_or("-")
        ),
        Finding::SystematicGroups { systematic, groups, largest } => format!(
            "{systematic} of {groups} {} end with a systematic error (bias beyond the {}); largest: {} bias {:.4}, scatter {:.4}",
            groups_noun(largest.basis),
            scatter_noun(largest.basis),
            largest.group,
            largest.bias,
            largest.scatter
        ),
        Finding::ErrorGrowth { early_m, late_m } => {
            format!("position error grows from {early_m:.4} m early to {late_m:.4} m late in the runs")
        }
        // No "equivalent" value: the runs cannot tell the effect's value from a change of the model (issue 45).
        Finding::Absorbed { effect, .. } => format!(
            "{effect}: indistinguishable from the model on these runs (absorbed by it: they cannot tell its value from a change of the model's parameters; runs that excite it differently would)"
        ),
        Finding::NotExcited { effect, gap } => {
            format!("{effect}: not tested, the training runs do not excite it ({})", excitation_gap(gap))
        }
        Finding::WorseThanDesign { worse, runs } => format!(
            "{worse} of {runs} held-out runs end with a larger path error than the design: the fit does not serve every motion (compare the training runs' motions with these)"
        ),
        Finding::Unconstrained(w) => format!("the model itself: {}", warning(w)),
        Finding::MissingMotions(c) => motion_coverage(c),
        Finding::ClockLag(l) => clock_lag(l),
        Finding::RepeatabilityFloor { scatter, basis: GroupBasis::Command } => format!(
            "repeatability floor: end-pose errors scatter by {scatter:.4} between repeats of the same command (no deterministic effect removes that part)"
        ),
        Finding::RepeatabilityFloor { scatter, basis: GroupBasis::Motion } => format!(
            "end-pose errors scatter by {scatter:.4} between runs of the same kind of path (not repeats of one command: part of it is the paths' own differences)"
        ),
    }
}

/// A kind of motion: `translating while rotating (arcs)`.
pub fn motion_kind(kind: MotionKind) -> &'static str {
    match kind {
        MotionKind::Translating => "translating without rotating (straight lines)",
        MotionKind::Rotating => "rotating on the spot",
        MotionKind::TranslatingWhileRotating => "translating while rotating (arcs)",
    }
}

/// A command to record: `v 0.20 m/s α 0° ω +0.35 rad/s`.
fn command(c: &omni_kin::Command) -> String {
    format!("v {:.2} m/s α {:.0}° ω {:+.2} rad/s", c.v_m_s, c.alpha_rad.to_degrees(), c.omega_rad_s)
}

/// One gap: `translating while rotating (arcs): 93 % of the held-out motion (|v| ≈ 0.20 m/s with
/// |ω| ≈ 0.35 rad/s), 2 % of the training motion`.
fn motion_gap(g: &MotionGap) -> String {
    let magnitudes = match g.kind {
        MotionKind::Translating => format!("|v| ≈ {:.2} m/s", g.speed_m_s),
        MotionKind::Rotating => format!("|ω| ≈ {:.2} rad/s", g.turn_rate_rad_s),
        MotionKind::TranslatingWhileRotating => {
            format!("|v| ≈ {:.2} m/s with |ω| ≈ {:.2} rad/s", g.speed_m_s, g.turn_rate_rad_s)
        }
    };
    format!(
        "{}: {} % of the held-out motion ({magnitudes}) where the training runs never go; {} % of the training \
         motion is of this kind",
        motion_kind(g.kind),
        percent_0(g.held_out_share),
        percent_0(g.train_share)
    )
}

/// A share (0…1) as a whole percentage, `<1` for a small non-zero share.
fn percent_0(share: f64) -> String {
    let p = 100.0 * share;
    if p > 0.0 && p < 0.5 { "<1".into() } else { format!("{p:.0}") }
}

/// What the training runs lack against the held-out runs, and what to record.
pub fn motion_coverage(c: &MotionCoverage) -> String {
    if !c.lacking() {
        return format!(
            "the training runs cover the held-out motions ({} % of the held-out motion falls where they go)",
            percent_0(c.covered)
        );
    }
    let gaps: Vec<String> = c.gaps.iter().map(motion_gap).collect();
    let mut text = format!("the training runs lack motions the held-out runs contain: {}", gaps.join("; "));
    if !c.unseen_effects.is_empty() {
        text.push_str(&format!("; no fit on these runs can see {}", c.unseen_effects.join(", ")));
    }
    let record: Vec<String> = c.gaps.iter().flat_map(|g| g.record.iter().map(command)).collect();
    if !record.is_empty() {
        text.push_str(&format!("; record {}", record.join(", ")));
    }
    if !c.unseen_effects.is_empty() {
        let flags: Vec<String> = c.unseen_effects.iter().map(|e| format!("--effect {e}")).collect();
        text.push_str(&format!(" (`omnical plan {}` proposes runs that excite them)", flags.join(" ")));
    }
    text
}

/// The verdict of a diagnosis, with the remaining error against the noise floor.
pub fn verdict(v: &Verdict) -> String {
    let mut text = match &v.conclusion {
        Conclusion::Add { effect, gain, before_m, after_m } => {
            format!("add {effect}: held-out path cost falls {:.1} % ({before_m:.4} → {after_m:.4} m)", 100.0 * gain)
        }
        Conclusion::Partial { effect, gain, excess_closed } => format!(
            "no catalogued effect explains most of the remaining error ({effect} helps: held-out path cost −{:.1} %, but it removes only {:.0} % of the error above the noise floor)",
            100.0 * gain,
            100.0 * excess_closed
        ),
        Conclusion::Nothing => "no catalogued effect explains the remaining error".into(),
        Conclusion::HurtsKinds { effect, folds } => hurts_kinds(effect, folds),
        Conclusion::NotOnNewKinds { effect, gain } => format!(
            "{effect} helps on repeats of the training paths but not on new kinds of path (left-out kinds: path cost {:+.1} %), so it is not recommended",
            -100.0 * gain
        ),
    };
    match &v.explored {
        Some(x) => text.push_str(&format!(
            "; beyond the catalogue, the explorer passes {}: held-out path cost falls {:.1} % ({:.4} → {:.4} m); {}; \
             with it, ",
            x.effect,
            100.0 * x.gain,
            x.before_m,
            x.after_m,
            x.hint
        )),
        None => text.push_str("; "),
    }
    text.push_str(&unexplained(v));
    text
}

/// An effect that helps some kinds of held-out path and hurts others: `folds` holds (kind, path RMS
/// without it, with it), m.
pub fn hurts_kinds(effect: &str, folds: &[(String, f64, f64)]) -> String {
    let change = |b: f64, a: f64| format!("{:+.1} %", 100.0 * (a - b) / b.max(1e-300));
    let (hurt, helped): (Vec<_>, Vec<_>) = folds.iter().partition(|(_, b, a)| *a > *b);
    let list = |v: &[&(String, f64, f64)]| {
        v.iter().map(|(k, b, a)| format!("{k} {}", change(*b, *a))).collect::<Vec<_>>().join(", ")
    };
    let helps = if helped.is_empty() { String::new() } else { format!("helps {}, ", list(&helped)) };
    format!(
        "{effect} {helps}hurts {} (held-out path RMS by kind of path): the term depends on the motion, so it is not recommended; record runs of the kinds it hurts in training, or fit it per kind",
        list(&hurt)
    )
}

/// A probability: two decimals, or in powers of ten below 1 %.
fn probability(p: f64) -> String {
    if p >= 0.01 { format!("{p:.2}") } else { format!("{p:.0e}") }
}

/// Whether a systematic error remains, and which evidence decided it.
fn unexplained(v: &Verdict) -> String {
    let e = &v.evidence;
    let floor = match &v.remaining {
        Some(r) => format!(
            "the remaining held-out error ({:.4} m) is {:.1}× the measurement noise floor ({:.4} m)",
            r.held_out_m, r.ratio, r.floor_m
        ),
        None => {
            format!("the remaining held-out error is {:.4} m (no standstills: no noise floor)", e.remaining_held_out_m)
        }
    };
    let growth = match (e.early_m, e.late_m) {
        (Some(a), Some(b)) => format!("; position error {a:.4} m early, {b:.4} m late in the runs"),
        _ => String::new(),
    };
    let repeats = |e: &UnexplainedEvidence| {
        format!(
            "{} of {} {} end biased beyond their {} (t-test at 5 %: {:.1} expected by chance, as many with probability {})",
            e.groups_biased,
            e.groups_total,
            groups_noun(e.groups_basis),
            scatter_noun(e.groups_basis),
            0.05 * e.groups_total as f64,
            probability(e.chance_probability.unwrap_or(1.0))
        )
    };
    match (e.decided_by, v.unexplained) {
        (DecidedBy::FarAboveNoise, _) => {
            let groups = if e.groups_total > 0 { format!(" ({})", repeats(e)) } else { String::new() };
            format!(
                "something physical is still missing: {floor}, far beyond what measurement noise explains{groups}{growth}"
            )
        }
        (DecidedBy::Repeats, true) => {
            format!(
                "something physical is still missing, decided by the {}: {}; {floor}{growth}",
                groups_short(e.groups_basis),
                repeats(e)
            )
        }
        (DecidedBy::Repeats, false) => format!(
            "no systematic error remains, decided by the {}: {}{}; {floor}",
            groups_short(e.groups_basis),
            repeats(e),
            e.repeatability_floor.map_or(String::new(), |f| format!(", repeatability floor {f:.4}"))
        ),
        (DecidedBy::NoiseFloorRatio, missing) => format!(
            "{}; decided by the noise floor alone: {floor}{}",
            match e.groups_total {
                0 => "no command was repeated and no two runs are of one kind, so the group test could not be made"
                    .to_string(),
                1 => "a single group of runs cannot show a bias beyond chance, so the group test could not decide"
                    .to_string(),
                n => format!(
                    "the {n} groups of runs are too small to clear a bias (their t-tests have fewer than {} degrees of \
                     freedom in all), so the group test could not decide",
                    crate::science::diagnose::MIN_DOF_TO_CLEAR
                ),
            },
            if missing { ": something physical is still missing" } else { ", close to it" }
        ),
        (DecidedBy::Undecided, _) => {
            format!("{floor}; without repeats or a noise floor, whether something is missing cannot be decided")
        }
    }
}

/// Where a noise floor was seen, in words: `at standstill`, or from the jitter while moving.
pub fn noise_source(source: NoiseSource) -> &'static str {
    match source {
        NoiseSource::Standstill => "at standstill",
        NoiseSource::Jitter => "from the ground truth's jitter while moving (the runs never stand still)",
    }
}

/// What the groups of a group test are, in words.
fn groups_noun(basis: GroupBasis) -> &'static str {
    match basis {
        GroupBasis::Command => "command groups",
        GroupBasis::Motion => "groups of runs of one kind of path (no command ids: grouped by their ground truth)",
    }
}

/// The scatter a group's bias is judged against, in words.
fn scatter_noun(basis: GroupBasis) -> &'static str {
    match basis {
        GroupBasis::Command => "repeat scatter",
        GroupBasis::Motion => "scatter between the group's runs",
    }
}

/// The group test's short name.
fn groups_short(basis: GroupBasis) -> &'static str {
    match basis {
        GroupBasis::Command => "repeats",
        GroupBasis::Motion => "runs of one kind",
    }
}

/// A clock offset between the wheels and the reference, in words.
fn clock_lag(l: &crate::science::diagnose::ClockLag) -> String {
    let a = &l.estimate;
    format!(
        "the wheels and the reference disagree in time: the reference's motion follows the wheels best with the \
         wheels' stamps {:.3} s ± {:.1} ms {} (explaining {:.0} % of it, {:.0} % as recorded; from {} run{}, \
         without a model): a clock offset between the wheels and the sensor, which `train --effect time_offset` \
         fits (tau_s {:+.3})",
        a.offset_s.abs(),
        a.std_error_s * 1e3,
        if a.offset_s > 0.0 { "later" } else { "earlier" },
        a.r_squared * 100.0,
        l.r_squared_as_recorded * 100.0,
        l.runs,
        if l.runs == 1 { "" } else { "s" },
        a.offset_s
    )
}

#[cfg(test)]
mod tests {
    use super::{hurts_kinds, percent_1};
    use crate::science::diagnose::KindOut;
    use crate::science::diagnose::search::hurts_a_kind;

    /// Issue 45's omni3 case: a term that helps circles and hurts joystick driving is named as such, and
    /// the one test of transfer refuses it; a 1 % rise on one kind is within the 2 % tolerance.
    #[test]
    fn a_term_that_helps_one_kind_and_hurts_another_is_refused_and_said_so() {
        let folds = vec![("arcs (6)".to_string(), 0.100, 0.064), ("free (4)".to_string(), 0.096, 0.152)];
        let k = KindOut { effect: "wheel".into(), folds: folds.clone(), gain: 0.2 };
        assert!(hurts_a_kind(&k), "a pooled gain does not excuse a kind made 58 % worse");
        assert_eq!(
            hurts_kinds("wheel", &folds),
            "wheel helps arcs (6) -36.0 %, hurts free (4) +58.3 % (held-out path RMS by kind of path): the term \
             depends on the motion, so it is not recommended; record runs of the kinds it hurts in training, or fit \
             it per kind"
        );
        let small = KindOut { folds: vec![("arcs (6)".into(), 0.1, 0.05), ("free (4)".into(), 0.1, 0.101)], ..k };
        assert!(!hurts_a_kind(&small));
        assert!(hurts_a_kind(&KindOut { gain: -0.01, folds: vec![], ..small }));
    }

    #[test]
    fn shares_print_as_percentages_never_nan_or_negative_zero() {
        assert_eq!(percent_1(0.3834), "38.3");
        assert_eq!(percent_1(-0.004), "-0.4");
        assert_eq!(percent_1(-1e-6), "0.0");
        assert_eq!(percent_1(-0.0), "0.0");
        assert_eq!(percent_1(f64::NAN), "-");
    }
}
