//! The explorer's words (issue 18): what a family's fitted terms mean, and the exploration in a few lines.

use crate::science::explore::{Exploration, FamilyResult, FamilyStatus, Term, Unconverged};
use omni_kin::effect::Family;

/// Terms that stand out: at least two standard errors from zero.
fn significant(f: &FamilyResult) -> Vec<&Term> {
    f.terms.iter().filter(|t| strength(f, t) >= 2.0).collect()
}

/// How far a term stands out: `|value| / std_error` ([`Term::z`]). A held term (part of a direction the runs
/// do not constrain, so without a standard error of its own) that still moved is judged against the largest
/// standard error of the family's terms in its unit: an oval wheel's 3 % harmonic that carries a tenth of a
/// weak direction is still the finding, not a 0.3 % term beside it.
fn strength(f: &FamilyResult, t: &Term) -> f64 {
    if !t.held || t.std_error.is_finite() {
        return t.z();
    }
    let se =
        f.terms.iter().filter(|u| u.unit == t.unit && u.std_error.is_finite()).map(|u| u.std_error).fold(0.0, f64::max);
    if se > 0.0 { t.value.abs() / se } else { 0.0 }
}

fn term<'a>(f: &'a FamilyResult, name: &str) -> Option<&'a Term> {
    f.terms.iter().find(|t| t.name == name)
}

/// What a family's fit says physically, in units, with possible causes: "a world-frame drift of
/// (+3.9, −2.1) mm/s while moving, one drift shared by the runs: a tilted floor, or a ground-truth frame that
/// moves".
pub fn explore_hint(f: &FamilyResult) -> String {
    if f.status != FamilyStatus::Fitted {
        return family_status(f);
    }
    let sig = significant(f);
    let Some(top) = sig.iter().max_by(|a, b| strength(f, a).total_cmp(&strength(f, b))) else {
        return "no term stands out from its standard error".into();
    };
    let value = |n: &str| term(f, n).map_or(0.0, |t| t.value);
    match f.family {
        Family::World if top.name.starts_with("omega") => format!(
            "a turn rate that depends on the world heading (amplitude {:.2} mrad/s): a tilted floor turning the robot downhill",
            1e3 * value("omega_cos1").hypot(value("omega_sin1"))
        ),
        Family::World if top.name.starts_with("grain") => {
            let (c, s) = (value("grain_cos2"), value("grain_sin2"));
            format!(
                "the floor has a grain: the speed along the world direction {:.0}° is {:.1} % higher than across it \
                 (a carpet's pile, floor boards, a brushed surface)",
                // An axis: 0°…179° from the world x axis, rounded first (−0.2° is 0°, not 180°; + 0.0 makes −0
                // print as 0).
                (0.5 * s.atan2(c).to_degrees()).round().rem_euclid(180.0) + 0.0,
                100.0 * ((1.0 + c.hypot(s)) / (1.0 - c.hypot(s)) - 1.0)
            )
        }
        Family::World => format!(
            "a world-frame drift of ({:+.1}, {:+.1}) mm/s while moving, one drift shared by the runs: a tilted floor, or a ground-truth frame that moves",
            1e3 * value("drift_x"),
            1e3 * value("drift_y")
        ),
        Family::Wheel => wheel_hint(f, top),
        Family::Body => body_hint(top),
        Family::Time => format!(
            "{} grows with the time since the run started ({} = {:+.3e} {}): a ground-truth frame that drifts, tyres or motors warming, a falling battery voltage",
            if top.name.starts_with("drift") {
                "a world-frame drift"
            } else if top.name.starts_with("omega") {
                "the turn rate"
            } else {
                "the translation scale"
            },
            top.name,
            top.value,
            top.unit
        ),
        Family::GroundTruth => format!(
            "the ground-truth sensor sits ({:+.1}, {:+.1}) mm from the rotation centre, turned {:+.2}°: its lever arm (the catalogue's sensor_offset_yaw)",
            1e3 * value("lever_x_m"),
            1e3 * value("lever_y_m"),
            value("yaw_rad").to_degrees()
        ),
    }
}

/// Up to four names, then how many more.
fn some_names(names: &[&str]) -> String {
    match names.len() {
        0..=4 => names.join(", "),
        n => format!("{}, … ({} more)", names[..4].join(", "), n - 4),
    }
}

/// Whether a family was fitted, and if not, why not, in words: "fitted", "fitted; 5 of 9 terms undetermined (…)",
/// "not fitted: …", "not converged: …".
pub fn family_status(f: &FamilyResult) -> String {
    let n = f.terms.len();
    match f.status {
        FamilyStatus::Fitted => {
            let held: Vec<&str> = f.terms.iter().filter(|t| t.held).map(|t| t.name.as_str()).collect();
            if held.is_empty() {
                "fitted".into()
            } else {
                format!(
                    "fitted; {} of {n} terms undetermined ({}): part of directions the runs do not constrain, held at the start as train holds them",
                    held.len(),
                    some_names(&held)
                )
            }
        }
        FamilyStatus::NotExcited => {
            format!("not fitted: the runs do not excite its {n} terms (no residual changes with them); all stay 0")
        }
        FamilyStatus::Singular => format!(
            "not fitted: the runs cannot tell its {n} terms from the base kinematics or from each other, so all are held at 0, as train holds them"
        ),
        FamilyStatus::NotConverged { reason } => match reason {
            Unconverged::Budget { evaluations } => format!(
                "not converged: Levenberg–Marquardt spent its {evaluations} evaluations before the training cost settled (the terms as it left them)"
            ),
            Unconverged::NoStep => {
                "not converged: no step lowered the training cost from the start; all terms stay 0".into()
            }
            Unconverged::AtZero => "not converged: the fit left every term at 0".into(),
        },
    }
}

/// The `wheel` family's hint from its strongest term `top` (`cos2_b`, `speed_a`, …).
fn wheel_hint(f: &FamilyResult, top: &Term) -> String {
    let (kind, wheel) = top.name.split_once('_').unwrap_or((top.name.as_str(), "?"));
    let value = |n: String| term(f, &n).map_or(0.0, |t| t.value);
    if kind == "accel"
        && let Some(lag_s) = common_lag(f)
    {
        return format!(
            "every wheel's encoder reads {:.1} ms {} the wheel moves (accel on all {} wheels, equal within their standard errors): one clock offset for all wheels, the catalogue's `time_offset`",
            1e3 * lag_s.abs(),
            if lag_s > 0.0 { "after" } else { "before" },
            f.terms.iter().filter(|t| t.name.starts_with("accel_")).count()
        );
    }
    match kind {
        "cos1" | "sin1" | "cos2" | "sin2" | "cos3" | "sin3" => {
            let n = &kind[3..];
            let amp = value(format!("cos{n}_{wheel}")).hypot(value(format!("sin{n}_{wheel}")));
            let cause = match n {
                "1" => "an off-centre hub or a bent axle",
                "2" => "an oval wheel",
                _ => "a three-lobed wheel or its roller pattern",
            };
            format!("wheel {wheel}'s effective radius varies by ±{:.2} % {n} time(s) per turn: {cause}", 100.0 * amp)
        }
        "speed" => format!(
            "wheel {wheel}'s effective radius changes with its speed ({:+.4} s/rad): tyre deformation",
            top.value
        ),
        "sign" => format!(
            "wheel {wheel} covers {:+.2} % more distance per turn one way than the other: a forward/backward radius difference",
            100.0 * top.value
        ),
        // δω = θ dω/dt ≈ ω(t + θ) − ω(t): θ < 0, the wheel moves |θ| after its encoder reads.
        _ if top.value < 0.0 => format!(
            "wheel {wheel} moves {:.1} ms after its encoder reads (accel_{wheel} = {:+.4} s): compliance in the drive (belt, coupling, tyre)",
            -1e3 * top.value,
            top.value
        ),
        _ => format!(
            "wheel {wheel}'s encoder reads {:.1} ms after the wheel moves (accel_{wheel} = {:+.4} s): a late encoder sample or filter",
            1e3 * top.value,
            top.value
        ),
    }
}

/// The `wheel` family's `accel` terms as one clock offset (s): their mean, when there are two or more, none
/// held, each at least 2 standard errors from 0 and within 2 of the mean (a lag common to every wheel is
/// the catalogue's `time_offset`, not a per-wheel filter).
fn common_lag(f: &FamilyResult) -> Option<f64> {
    let accel: Vec<&Term> = f.terms.iter().filter(|t| t.name.starts_with("accel_")).collect();
    let mean = accel.iter().map(|t| t.value).sum::<f64>() / accel.len().max(1) as f64;
    let agree = |t: &&Term| !t.held && t.z() >= 2.0 && (t.value - mean).abs() <= 2.0 * t.std_error;
    (accel.len() >= 2 && accel.iter().all(agree)).then_some(mean)
}

/// The `body` family's hint from its strongest term.
fn body_hint(top: &Term) -> String {
    match top.name.as_str() {
        "omega_speed" => format!(
            "the heading drifts by {:+.2} mrad per metre travelled: a floor camber, a skewed wheel, unequal load on the wheels",
            1e3 * top.value
        ),
        "omega_abs" => {
            format!("turns one way are {:+.2} % faster than the other: unequal wheel grip", 100.0 * top.value)
        }
        "scale_speed" => format!("the translation scale grows by {:+.2} % per m/s: slip at speed", 100.0 * top.value),
        "scale_turn" => format!(
            "the translation scale changes by {:+.2} % per rad/s of turning: slip while turning",
            100.0 * top.value
        ),
        "turn_omega" => format!(
            "the translation turns by {:+.3} s × ω: slip while rotating (the catalogue's rotation_slip)",
            top.value
        ),
        _ => format!(
            "the translation scale depends on the direction of travel ({} = {:+.3}): roller or wheel-mount asymmetry",
            top.name, top.value
        ),
    }
}

/// The exploration in lines: each family's held-out gain and judgement with its hint (or why it was not
/// fitted, and which terms train holds), then the conclusion.
pub fn exploration(e: &Exploration) -> Vec<String> {
    let mut lines: Vec<String> = e
        .families
        .iter()
        .map(|f| {
            let held = f.terms.iter().any(|t| t.held);
            let status = if f.status == FamilyStatus::Fitted && held {
                format!(" ({})", family_status(f))
            } else {
                String::new()
            };
            // A gain that hurts a kind of held-out path: said instead of the hint.
            let hint = match f
                .held_out_kinds
                .as_ref()
                .filter(|k| !f.passes && crate::science::diagnose::search::hurts_a_kind(k))
            {
                Some(k) => super::hurts_kinds(&format!("learned:{}", f.family.id()), &k.folds),
                None => explore_hint(f),
            };
            format!(
                "{:<13} held-out gain {:+6.1} % ± {:4.1} %  {}  {hint}{status}",
                f.family.id(),
                100.0 * f.held_out_gain,
                100.0 * f.gain_std_error,
                if f.passes { "passes" } else { "fails " },
            )
        })
        .collect();
    lines.push(explore_conclusion(e));
    lines
}

/// The explorer's conclusion in one sentence: the best family, and whether something is still missing (the
/// one decision of diagnose, [`Exploration::evidence`]).
pub fn explore_conclusion(e: &Exploration) -> String {
    let floor = match (e.noise_floor_path_rms, e.evidence.ratio) {
        (Some(_), Some(r)) => format!("{r:.1}× the measurement noise floor"),
        _ => "the noise floor is not measurable (no rest at the runs' ends, no fast ground truth)".into(),
    };
    let remaining = e.evidence.remaining_held_out_m;
    match e.best() {
        Some(f) => {
            let rest = if e.unexplained {
                format!(
                    "; with it the held-out path error ({remaining:.4} m) is still {floor}: something physical is still missing"
                )
            } else {
                String::new()
            };
            let holding = match f.terms.iter().filter(|t| t.held).count() {
                0 => String::new(),
                k => format!(", holding the same {k} terms"),
            };
            format!(
                "{} explains {:.1} % of the held-out path error ({:.4} m → {:.4} m): {}; add it with --effect learned:{} (train makes this very fit{holding}){rest}",
                f.family.id(),
                100.0 * f.held_out_gain,
                e.baseline_held_out_cost,
                f.held_out_cost,
                explore_hint(f),
                f.family.id()
            )
        }
        None if e.unexplained => format!(
            "no family passes on held-out runs, and the held-out path error ({remaining:.4} m) is {floor}: something physical is still missing that these features do not describe"
        ),
        None => format!(
            "no family passes on held-out runs; the held-out path error ({remaining:.4} m) is {floor}: nothing systematic is left to explain"
        ),
    }
}
