//! Values with units in text output, shared by every command so that `train`, `diagnose`, … print angles
//! the same way: an angle (unit `rad`) in degrees with radians in parentheses, anything else in its unit.
//! JSON output keeps SI units (radians) and is not formatted here.

/// A value in its unit, right-aligned: an angle (unit `rad`) in degrees with radians in parentheses
/// (`    -30.0123° (-0.523813 rad)`), anything else as `{value:>14.6} {unit}`.
pub fn value_text(value: f64, unit: &str) -> String {
    if unit == "rad" {
        format!("{:>13.4}° ({value:.6} rad)", value.to_degrees())
    } else {
        format!("{value:>14.6} {unit}")
    }
}

/// A standard error in its unit: an angle (unit `rad`) in degrees with radians in parentheses
/// (`±4.01e-2° (6.99e-4 rad)`), anything else as `±{std_error:.2e} {unit}`.
pub fn std_error_text(std_error: f64, unit: &str) -> String {
    if unit == "rad" {
        format!("±{:.2e}° ({std_error:.2e} rad)", std_error.to_degrees())
    } else {
        format!("±{std_error:.2e} {unit}")
    }
}

/// A count with its noun, singular for one: `count(1, "run")` is `1 run`, `count(3, "run")` `3 runs`.
pub fn count(n: usize, noun: &str) -> String {
    if n == 1 { format!("1 {noun}") } else { format!("{n} {noun}s") }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_singular_for_one() {
        assert_eq!(count(1, "training run"), "1 training run");
        assert_eq!(count(0, "run"), "0 runs");
        assert_eq!(count(72, "run"), "72 runs");
    }

    #[test]
    fn angles_print_in_degrees_with_radians() {
        assert_eq!(value_text(1.055373, "rad"), "      60.4684° (1.055373 rad)");
        assert_eq!(value_text(-std::f64::consts::FRAC_PI_6, "rad"), "     -30.0000° (-0.523599 rad)");
        assert_eq!(std_error_text(7.0e-4, "rad"), "±4.01e-2° (7.00e-4 rad)");
    }

    #[test]
    fn other_units_print_as_they_are() {
        assert_eq!(value_text(0.0601, "s"), "      0.060100 s");
        assert_eq!(std_error_text(5.56e-4, "s"), "±5.56e-4 s");
        assert_eq!(std_error_text(2.1e-3, "s/rad"), "±2.10e-3 s/rad");
    }
}
