//! A JointState topic with both `position` and `velocity`: the wheel rate each gives, compared. Drivers
//! outside ros2_control often fill them from different shafts or in different units (wheel encoder counts
//! beside motor rpm), so that the two disagree by a gear ratio; the speeds read must come from the one the
//! user declares (`[wheel_data] source`) when they do.

use omni_kin::robot::WheelData;

/// The rates agree when one is within this factor of the other (a driver's filtered velocity lags its
/// counts by a few per cent over a window; a unit or a gear is 1.5× and more).
pub(super) const AGREE_FACTOR: f64 = 1.2;
/// The windows the rates are compared over: long enough that a count's quantum and a velocity filter's lag
/// do not matter. s.
const WINDOW_S: f64 = 0.5;
/// Below this much turning (rad, summed over wheels and windows) the wheels barely moved: nothing to compare.
const MIN_TURN_RAD: f64 = 1.0;
/// A window counts when a wheel turned this much in it by either field, on average (rad): a robot at rest
/// says nothing about the fields' units.
const MIN_WINDOW_TURN_RAD: f64 = 0.01;

/// The wheel rate (rad/s) that `velocity` gives and the one `position` gives (both `samples × w`, in the
/// wheel's units): over windows of [`WINDOW_S`], the turn `∫ velocity dt` and the change of `position` in
/// absolute value, averaged over the wheels and the window's time; the median over the windows where either
/// moves (a spike in one message, refused later on its own, moves neither median). `None` when the wheels
/// barely move by either field, or `position` never changes (a driver that fills it with zeros).
pub(super) fn rates(t_s: &[f64], velocity: &[f64], position: &[f64], w: usize) -> Option<(f64, f64)> {
    let n = t_s.len();
    if n < 2 || w == 0 {
        return None;
    }
    let (mut by_velocity, mut by_position) = (Vec::new(), Vec::new());
    let (mut turned, mut changed) = (0.0, 0.0);
    let mut a = 0;
    for b in 1..n {
        if t_s[b] - t_s[a] < WINDOW_S && b + 1 < n {
            continue;
        }
        let (mut v, mut p) = (0.0, 0.0);
        for j in 0..w {
            let turn: f64 = (a + 1..=b).map(|k| velocity[k * w + j] * (t_s[k] - t_s[k - 1])).sum();
            v += turn.abs();
            p += (position[b * w + j] - position[a * w + j]).abs();
        }
        let span = (t_s[b] - t_s[a]) * w as f64;
        (turned, changed) = (turned + v, changed + p);
        if v.max(p) > MIN_WINDOW_TURN_RAD * w as f64 && span > 0.0 {
            by_velocity.push(v / span);
            by_position.push(p / span);
        }
        a = b;
    }
    let median = |mut x: Vec<f64>| {
        x.sort_by(f64::total_cmp);
        x.get(x.len() / 2).copied()
    };
    let moved = turned.max(changed) >= MIN_TURN_RAD && changed > 0.0;
    let (v, p) = (median(by_velocity)?, median(by_position)?);
    (moved && v.is_finite() && p.is_finite() && p > 0.0).then_some((v, p))
}

/// The note, or the refusal, on a topic whose `velocity` (read by default) and `position` (`samples × w`,
/// converted by `units`, unwrapped) give different rates: read with `units.source` declared, the note says which
/// field is read and what the other gives; undeclared, the read is refused naming both rates and the
/// setting that chooses. Agreeing fields say nothing.
pub(super) fn compare(
    t_s: &[f64],
    velocity: &[f64],
    position: &[f64],
    w: usize,
    units: &WheelData,
) -> Result<Option<String>, (usize, String)> {
    // A speed no wheel turns at is refused on its own, naming its message, when the run is built.
    if velocity.iter().any(|v| v.abs() > omni_kin::run::MAX_WHEEL_RAD_S) {
        return Ok(None);
    }
    let Some((v, p)) = rates(t_s, velocity, position, w) else { return Ok(None) };
    let ratio = v / p;
    if (1.0 / AGREE_FACTOR..=AGREE_FACTOR).contains(&ratio) {
        return Ok(None);
    }
    let (factor, more) = if ratio > 1.0 { (ratio, "velocity") } else { (1.0 / ratio, "position") };
    // The factor between two units, within 3 %: a unit declared wrong rather than a gear.
    let tau = std::f64::consts::TAU;
    let units_apart = [(60.0 / tau, "rad/s and rpm"), (360.0 / tau, "rad and degrees"), (tau, "turns and rad")]
        .into_iter()
        .find(|(f, _)| (factor / f - 1.0).abs() < 0.03)
        .map_or_else(String::new, |(f, what)| format!(", near {f:.3}, the factor between {what}"));
    let rates = format!(
        "field velocity gives a wheel rate of {v:.3} rad/s and field position {p:.3} rad/s (medians over 0.5 s \
         windows: {factor:.2} times more by {more}{units_apart}; {})",
        units_text(units)
    );
    match units.source {
        Some(field) => Ok(Some(format!(
            "{rates}: the wheel speeds come from field {} ([wheel_data] source = {:?})",
            field.name(),
            field.name()
        ))),
        None => Err((
            0,
            format!(
                "{rates}: the two fields disagree beyond noise (more than {AGREE_FACTOR}×), so one of them is in \
                 another unit or on another shaft (motor rpm beside wheel encoder counts?). Say which to read in \
                 robot.toml: [wheel_data] source = \"position\" or \"velocity\", with that field's unit and \
                 gear_ratio (docs/formats.md)"
            ),
        )),
    }
}

/// The units the rates were computed in, as declared.
fn units_text(units: &WheelData) -> String {
    if units.is_identity() {
        "both read as rad and rad/s".to_string()
    } else {
        format!(
            "position read in {} and velocity in {}, as [wheel_data] declares",
            units.position.name(),
            units.velocity.name()
        )
    }
}
