//! Whether a fitted model is a calibration of its start at all ([`implausible`]): a calibration corrects radii,
//! spacings and matrix entries by a few per cent, and a robot description far from its robot by a factor; a
//! fit that reverses a row, scales translation and rotation far apart, shrinks one wheel against the others,
//! or turns a row of the matrix to another direction has fitted something else (a sensor mount it could not
//! find, a reference of another robot), and is refused (`api::fit::check_fit`). Judged on the twist-from-wheels
//! matrix, which every base model has, against its start's, row by row (vx, vy, ω) and wheel by wheel.

use omni_kin::{FittedModel, IkMatrix};

/// A row or column of the fitted matrix more than this factor larger or smaller than its start's (or than
/// another's, relative to theirs) is beyond what a calibration corrects (the wheel-scale check at loading
/// uses the same factor).
pub const MAX_FACTOR: f64 = 3.0;
/// A fitted row farther than this from its start's direction (the part across it, over the start row's
/// length) points elsewhere.
pub const MAX_ACROSS: f64 = 0.5;

/// Why a fit is implausible, as facts.
#[derive(Clone, Debug, PartialEq)]
pub enum Reason {
    /// A row (0 vx, 1 vy, 2 ω) or a wheel's column points against its start's.
    Reversed {
        /// `row vx` or `wheel wheel_left`.
        what: String,
        /// Its scale along the start's.
        scale: f64,
    },
    /// The rows, or the wheels' columns, scaled far apart.
    Lopsided {
        /// The smallest scale, with what it is of.
        low: (String, f64),
        /// The largest scale, with what it is of.
        high: (String, f64),
    },
    /// Everything scaled alike, by a factor far from 1: a unit, or a design of another robot.
    Scaled {
        /// The common scale (the rows' geometric mean).
        scale: f64,
    },
    /// A row turned away from its start's direction.
    Turned {
        /// `row vx`.
        what: String,
        /// Its part across the start's direction, over the start row's length.
        across: f64,
    },
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Reason::Reversed { what, scale } => {
                write!(f, "{what} is reversed ({scale:.3} times its start's): a negative radius, spacing or sign")
            }
            Reason::Lopsided { low, high } => write!(
                f,
                "{} is {:.3} times its start's and {} {:.3} times, {:.1} times apart (a calibration scales them alike, \
                 within {MAX_FACTOR}×)",
                low.0,
                low.1,
                high.0,
                high.1,
                high.1 / low.1
            ),
            Reason::Scaled { scale } => write!(
                f,
                "the whole matrix is {scale:.3} times its start's: wheel data in another unit (rpm, deg/s, counts) \
                 or a start of another robot"
            ),
            Reason::Turned { what, across } => write!(
                f,
                "{what} turned away from its start's direction ({:.0} % of its length across it)",
                100.0 * across
            ),
        }
    }
}

/// The reasons `fitted` is no calibration of `start` (empty: plausible). Rows and wheels whose start is all
/// zero (a differential drive's vy row) are not judged.
pub fn implausible(fitted: &IkMatrix, start: &IkMatrix, wheel_names: &[String]) -> Vec<Reason> {
    const ROWS: [&str; 3] = ["row vx", "row vy", "row ω"];
    let n = start.n_wheels();
    if fitted.n_wheels() != n {
        return Vec::new();
    }
    let rows: Vec<(String, Vec<f64>, Vec<f64>)> =
        (0..3).map(|r| (ROWS[r].to_string(), fitted.row(r).to_vec(), start.row(r).to_vec())).collect();
    let columns: Vec<(String, Vec<f64>, Vec<f64>)> = (0..n)
        .map(|c| {
            let name = wheel_names.get(c).cloned().unwrap_or_else(|| format!("{}", c + 1));
            let col = |m: &IkMatrix| (0..3).map(|r| m.get(r, c)).collect();
            (format!("wheel {name}"), col(fitted), col(start))
        })
        .collect();
    let mut reasons = Vec::new();
    let row_scales = scales(&rows, &mut reasons);
    let column_scales = scales(&columns, &mut reasons);
    if !reasons.is_empty() {
        return reasons;
    }
    for s in [&row_scales, &column_scales] {
        let low = s.iter().min_by(|a, b| a.1.total_cmp(&b.1));
        let high = s.iter().max_by(|a, b| a.1.total_cmp(&b.1));
        if let (Some(low), Some(high)) = (low, high)
            && high.1 > MAX_FACTOR * low.1
        {
            reasons.push(Reason::Lopsided { low: low.clone(), high: high.clone() });
            return reasons;
        }
    }
    let mean = (row_scales.iter().map(|s| s.1.ln()).sum::<f64>() / row_scales.len().max(1) as f64).exp();
    if !(1.0 / MAX_FACTOR..=MAX_FACTOR).contains(&mean) {
        reasons.push(Reason::Scaled { scale: mean });
    }
    for ((what, f, d), (_, s)) in rows.iter().filter(|(_, _, d)| norm2(d) > 0.0).zip(&row_scales) {
        let across = f.iter().zip(d).map(|(f, d)| (f - s * d).powi(2)).sum::<f64>().sqrt() / norm2(d).sqrt();
        if across > MAX_ACROSS {
            reasons.push(Reason::Turned { what: what.clone(), across });
        }
    }
    reasons
}

/// Each vector's scale along its start's (least squares), for those whose start is not zero; a scale ≤ 0 is
/// a reason.
fn scales(parts: &[(String, Vec<f64>, Vec<f64>)], reasons: &mut Vec<Reason>) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    for (what, f, d) in parts.iter().filter(|(_, _, d)| norm2(d) > 0.0) {
        let scale = f.iter().zip(d).map(|(f, d)| f * d).sum::<f64>() / norm2(d);
        if scale > 0.0 {
            out.push((what.clone(), scale));
        } else {
            reasons.push(Reason::Reversed { what: what.clone(), scale });
        }
    }
    out
}

fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum()
}

/// The base parameters of `fitted` that moved more than half their start's magnitude (or changed sign), as
/// `name fitted (start value)`.
pub fn moved_params(fitted: &FittedModel, start: &FittedModel) -> Vec<String> {
    let nb = fitted.model.n_base();
    let specs = fitted.model.params();
    specs[..nb]
        .iter()
        .zip(&fitted.params)
        .zip(&start.params)
        .filter(|((_, f), s)| (*f - *s).abs() > 0.5 * s.abs() || f.signum() != s.signum())
        .map(|((spec, f), s)| format!("{} {f:.6} {} (start {s:.6})", spec.name, spec.unit))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn diff(r_left: f64, r_right: f64, b: f64) -> IkMatrix {
        IkMatrix::new(2, vec![r_left / 2.0, r_right / 2.0, 0.0, 0.0, -r_left / b, r_right / b]).unwrap()
    }

    fn names() -> Vec<String> {
        vec!["left".into(), "right".into()]
    }

    #[test]
    fn a_calibration_and_a_uniform_double_scale_pass_and_the_issues_fits_are_refused() {
        let design = diff(0.033, 0.033, 0.287);
        assert_eq!(implausible(&diff(0.0337, 0.0331, 0.29), &design, &names()), vec![]);
        // A lidar measuring twice the wheels' distance: every row twice (a units warning elsewhere).
        assert_eq!(implausible(&diff(0.066, 0.066, 0.287), &design, &names()), vec![]);
        // Issue 43: radii 1.1 mm and the axle −93 %.
        let r = implausible(&diff(0.0011, 0.0011, 0.287 * 0.07), &design, &names());
        assert_eq!(r.len(), 1, "{r:?}");
        assert_eq!(
            r[0].to_string(),
            "row vx is 0.033 times its start's and row ω 0.476 times, 14.3 times apart (a calibration scales them \
             alike, within 3×)"
        );
        // One radius 18 times smaller.
        let r = implausible(&diff(0.033 / 18.0, 0.033, 0.287), &design, &names());
        assert!(matches!(&r[0], Reason::Lopsided { low, .. } if low.0 == "wheel left"), "{r:?}");
        // A negative axle.
        let r = implausible(&diff(0.033, 0.033, -0.287), &design, &names());
        assert_eq!(
            r[0].to_string(),
            "row ω is reversed (-1.000 times its start's): a negative radius, spacing or sign"
        );
        // Everything 18 times smaller.
        let r = implausible(&diff(0.033 / 18.0, 0.033 / 18.0, 0.287), &design, &names());
        assert!(matches!(r[..], [Reason::Scaled { scale }] if (scale - 1.0 / 18.0).abs() < 1e-9), "{r:?}");
    }

    #[test]
    fn a_row_turned_away_is_refused() {
        let design = IkMatrix::paper_design();
        assert_eq!(implausible(&IkMatrix::paper_calibrated(), &design, &[]), vec![]);
        // The vx row plus 0.8 of its length along the vy row's direction (the two are orthogonal).
        let mut rows = design.rows();
        let (vx, vy) = (norm2(&rows[0]).sqrt(), norm2(&rows[1]).sqrt());
        let tilt: Vec<f64> = rows[1].iter().map(|y| 0.8 * vx * y / vy).collect();
        rows[0].iter_mut().zip(&tilt).for_each(|(x, t)| *x += t);
        let r = implausible(&IkMatrix::from_rows(&rows).unwrap(), &design, &[]);
        assert!(
            matches!(&r[..], [Reason::Turned { what, across }] if what == "row vx" && (across - 0.8).abs() < 0.05),
            "{r:?}"
        );
    }
}
