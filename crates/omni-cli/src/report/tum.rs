//! TUM trajectory files, for evo (`evo_traj tum …`, `evo_ape tum ref est`).
//!
//! One pose per line: `timestamp tx ty tz qx qy qz qw` (seconds, metres, unit quaternion with w last),
//! space-separated, `#` comment lines allowed. Planar poses have z = 0 and a rotation about z only.

use omni_kin::StampedPose;
use std::fmt::Write;

/// The TUM text of a planar trajectory, with a leading `#` comment line.
pub fn to_tum(comment: &str, poses: &[StampedPose]) -> String {
    to_tum_at(comment, poses, 0)
}

/// [`to_tum`] with stamps `origin_s + t_s` (the recording's Unix time), written exactly to the nanosecond
/// (an f64 of 1.7e9 s would keep only about 0.2 µs).
pub fn to_tum_at(comment: &str, poses: &[StampedPose], origin_s: i64) -> String {
    let mut s = String::with_capacity(64 * (poses.len() + 1));
    for line in comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    for p in poses {
        let (qz, qw) = (0.5 * p.pose.theta_rad).sin_cos();
        if origin_s == 0 {
            let _ = write!(s, "{:.9}", p.t_s);
        } else {
            let ns = origin_s as i128 * 1_000_000_000 + (p.t_s * 1e9).round() as i128;
            let _ = write!(s, "{}.{:09}", ns.div_euclid(1_000_000_000), ns.rem_euclid(1_000_000_000));
        }
        let _ = writeln!(s, " {:.9} {:.9} 0 0 0 {:.12} {:.12}", p.pose.x_m, p.pose.y_m, qz, qw);
    }
    s
}

/// A file-name-safe version of a run name (`train/run-003` → `train_run-003`).
pub fn file_stem(run_name: &str) -> String {
    run_name.chars().map(|c| if c.is_ascii_alphanumeric() || matches!(c, '-' | '.') { c } else { '_' }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use omni_kin::Pose2;

    #[test]
    fn tum_lines_have_eight_columns_and_a_unit_quaternion() {
        let p = StampedPose { t_s: 1.5, pose: Pose2 { x_m: 1.0, y_m: -2.0, theta_rad: std::f64::consts::FRAC_PI_2 } };
        let text = to_tum("run a\nmodel b", &[p]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[..2], ["# run a", "# model b"]);
        let cols: Vec<f64> = lines[2].split(' ').map(|c| c.parse().unwrap_or(f64::NAN)).collect();
        assert_eq!(cols.len(), 8);
        assert_eq!(cols[..3], [1.5, 1.0, -2.0]);
        assert!((cols[6] - 0.5f64.sqrt()).abs() < 1e-12 && (cols[7] - 0.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn file_stems_drop_path_separators() {
        assert_eq!(file_stem("train/run-003"), "train_run-003");
        assert_eq!(file_stem("a b:c.mcap"), "a_b_c.mcap");
    }
}
