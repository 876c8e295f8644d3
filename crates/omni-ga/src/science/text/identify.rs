//! The identifiability analysis in words: which standard errors it gives, what an unconstrained direction
//! is (its parameters, how badly it is constrained, the wheel-speed pattern behind it) and which runs would
//! constrain it.

use crate::science::identify::{
    Advice, Combination, CovarianceKind, Identifiability, MIN_SEGMENT_S, MotionParts, PatternPresence, WeakDirection,
    WheelEvidence,
};

/// Which standard errors an identifiability analysis gives: `per run (robust to correlated errors along a
/// path)`, with the segments when the runs were cut.
pub fn covariance(id: &Identifiability) -> String {
    match id.covariance_kind {
        CovarianceKind::PerRun if id.clusters > id.runs => format!(
            "per run (robust to correlated errors along a path; {} runs cut into {} segments of ≥ {MIN_SEGMENT_S:.0} s)",
            id.runs, id.clusters
        ),
        CovarianceKind::PerRun => "per run (robust to correlated errors along a path)".into(),
        CovarianceKind::Iid => "iid (too few runs for the per-run estimate)".into(),
        CovarianceKind::Stated => "from the stated noise".into(),
    }
}

/// An unconstrained direction in words: the parameters carrying it, how badly it is constrained, and the
/// wheel-speed pattern behind it.
pub fn weak_direction(w: &WeakDirection) -> String {
    if let Advice::OneCombination(c) = &w.remedy {
        return combination(c);
    }
    let names: Vec<&str> = w.loadings.iter().map(|(n, _)| n.as_str()).collect();
    let same_sign = w.loadings.iter().all(|(_, d)| *d > 0.0);
    let who = match names.len() {
        1 => format!("{} is", names[0]),
        2 if same_sign => format!("{} and {} move together and are", names[0], names[1]),
        2 => format!("{} and {} trade off (one up, the other down) and are", names[0], names[1]),
        _ => {
            let signed: Vec<String> =
                w.loadings.iter().map(|(n, d)| format!("{}{n}", if *d > 0.0 { "+" } else { "−" })).collect();
            format!("the combination {} is", signed.join(" "))
        }
    };
    let how = match w.std_error {
        None => "not excited at all".to_string(),
        Some(se) => format!("poorly constrained (±{:.1} % of scale)", 100.0 * se),
    };
    let mut text = format!("{who} {how}");
    if let (Some(e), Some(u)) = (&w.evidence, &w.wheel_pattern) {
        text.push_str(&format!(": {}", wheel_evidence(e, u)));
    }
    text
}

/// Parameters that enter the kinematics only together: `lx and ly enter the kinematics only as lx + ly
/// (0.37000 m at the fit)`.
fn combination(c: &Combination) -> String {
    let names = match &c.names[..] {
        [a, b] => format!("{a} and {b}"),
        many => many.join(", "),
    };
    match (&c.names[..], c.sum) {
        ([a, b], Some(([_, k], value))) => {
            let term = if (k.abs() - 1.0).abs() < 1e-3 { b.clone() } else { format!("{:.3} {b}", k.abs()) };
            let sign = if k < 0.0 { "−" } else { "+" };
            format!("{names} enter the kinematics only as {a} {sign} {term} ({value:.5} {} at the fit)", c.unit)
        }
        _ => format!("{names} enter the kinematics only together"),
    }
}

/// What the runs say about the wheel-speed pattern `u` of a direction.
fn wheel_evidence(e: &WheelEvidence, u: &[f64]) -> String {
    let named: Vec<String> = e.wheels.iter().zip(u).map(|(w, x)| format!("{w} {x:+.2}")).collect();
    let motion = if e.moves_nowhere {
        "the wheels fighting each other, a pattern that moves the robot nowhere".to_string()
    } else {
        motion_name(e.motion)
    };
    let named = named.join(", ");
    match e.presence {
        PatternPresence::Present(share) => format!(
            "the runs contain the wheel-speed pattern ({named}) — {motion} under the design matrix — ({:.0} % of the wheel motion), but the residuals barely respond to how the robot answers it",
            100.0 * share
        ),
        PatternPresence::Scarce(share) => format!(
            "the runs hardly contain the wheel-speed pattern ({named}) — {motion} under the design matrix — ({:.0} % of the wheel motion), so the robot's response to it is not measured",
            100.0 * share
        ),
        PatternPresence::Unknown => format!(
            "the robot's response to the wheel-speed pattern ({named}) — {motion} under the design matrix — is not measured"
        ),
    }
}

/// The translational components of a motion, in words.
fn translations(m: MotionParts) -> Vec<&'static str> {
    let mut parts = Vec::new();
    if m.forward {
        parts.push("forward/backward (vx)");
    }
    if m.sideways {
        parts.push("sideways (vy)");
    }
    parts
}

/// A design motion: "moving sideways (vy) while rotating (ω)".
fn motion_name(m: MotionParts) -> String {
    let translate = translations(m);
    match (translate.is_empty(), m.rotating) {
        (true, true) => "rotating on the spot (ω)".into(),
        (false, false) => format!("moving {}", translate.join(" and ")),
        (false, true) => format!("moving {} while rotating (ω)", translate.join(" and ")),
        (true, false) => "no motion".into(),
    }
}

/// Which runs would constrain a direction.
pub fn advice(a: &Advice) -> String {
    match a {
        Advice::PathObjective => {
            "fit the path objective (every ground-truth pose), or add runs along different paths".to_string()
        }
        Advice::AddRuns { motion, alpha_deg } => {
            let translate = translations(*motion);
            let what = match (translate.is_empty(), motion.rotating) {
                (true, true) => "turning on the spot in both directions (ω ≠ 0)".to_string(),
                (false, false) => format!("translating {} in both directions", translate.join(" and ")),
                (false, true) => format!("with ω ≠ 0 while translating {}", translate.join(" and ")),
                (true, false) => "with other motions".to_string(),
            };
            let rotation = if motion.rotating { " with rotation" } else { "" };
            format!("add runs {what} (e.g. a command along α ≈ {alpha_deg:.0}°{rotation})")
        }
        Advice::HeldAtDesign => "no run can show it: it stays at the design (the default fit holds it; \
                                 `--unexcited move` lets it drift with the noise)"
            .into(),
        Advice::OtherMotions => "add runs with other motions (see `omnical plan`)".into(),
        Advice::ExerciseEffects(effects) => {
            format!("add runs that exercise {} (see `omnical plan --effect …`)", effects.join(", "))
        }
        Advice::OneCombination(_) => "no run can separate them: read them as one combination (the fit holds the \
                                      rest at the design)"
            .into(),
    }
}

/// One warning line for an unconstrained direction: its text and advice.
pub fn warning(w: &WeakDirection) -> String {
    format!("{}; {}", w.text, w.advice)
}
