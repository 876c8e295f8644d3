//! Unit tests of the omnical CSV run format: ticks, BOM and CRLF, messages, the write–read round trip.

use super::*;
use omni_kin::{Command, Pose2, Run, RunData, StampedPose};
use std::f64::consts::PI;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn ticks_bom_crlf_and_sparse_rows() {
    let dir = tempfile::tempdir().unwrap();
    let text = "\u{feff}# ticks_per_rev: 1000\r\n# repetition: 2\r\nt_s,a_ticks,b_ticks,c_ticks,x_m,y_m,theta_rad\r\n\
                0.00,0,0,0,0,0,3.1\r\n0.01,10,-5,5,,,\r\n0.02,10,-5,5,0.01,0,-3.1\r\n";
    let run = read_run(&write(dir.path(), "r.csv", text), None).unwrap();
    assert_eq!(run.n_samples(), 3);
    assert_eq!(run.truth().len(), 2);
    // 10 ticks in 10 ms at 1000 ticks/rev = 2π rad/s.
    assert!((run.wheel_sample(1)[0] - 2.0 * PI).abs() < 1e-12);
    // Heading unwrapped: 3.1 → −3.1 becomes 3.1 → 2π − 3.1.
    assert!((run.truth()[1].pose.theta_rad - (2.0 * PI - 3.1)).abs() < 1e-12);
    assert_eq!(run.repetition(), Some(2));
}

#[test]
fn messages_name_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "a.csv", "t_s,w_ticks,x_m,y_m,theta_rad\n0,1,0,0,0\n");
    assert_eq!(
        crate::api::settings::as_flags(&read_run(&p, None).unwrap_err().to_string()),
        format!(
            "{}: wheel columns are ticks but no ticks_per_rev is given (add '# ticks_per_rev: N' or --ticks-per-rev)",
            p.display()
        )
    );
    let p = write(dir.path(), "b.csv", "t_s,w_rad_s,x_m,y_m\n0,1,0,0\n");
    assert_eq!(
        read_run(&p, None).unwrap_err().to_string(),
        format!("{}: line 1: missing column theta_rad", p.display())
    );
    let p = write(dir.path(), "c.csv", "t_s,w_rad_s,x_m,y_m,theta_rad\n0,1,0,,0\n");
    assert_eq!(
        read_run(&p, None).unwrap_err().to_string(),
        format!("{}: line 2: partly filled row: y_m empty", p.display())
    );
}

#[test]
fn write_then_read_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let d = RunData {
        name: "x/run-1".into(),
        wheel_t_s: vec![0.0, 0.1 + 0.2, 0.7],
        wheel_rad_s: vec![1.0 / 3.0, -2.5e-17, 7.0, 0.1, 0.2, 0.3],
        n_wheels: 2,
        truth: vec![
            StampedPose { t_s: 0.0, pose: Pose2::new(0.1, 0.2, 0.3) },
            StampedPose { t_s: 0.7, pose: Pose2::new(1.0 / 7.0, 2.0, -0.5) },
        ],
        command: Some(Command { v_m_s: 0.2, alpha_rad: 0.523, omega_rad_s: -0.35 }),
        repetition: Some(4),
        recorded_odometry: vec![
            StampedPose { t_s: 0.05, pose: Pose2::new(0.01, 0.0, 0.001) },
            StampedPose { t_s: 0.7, pose: Pose2::new(0.2, -0.1, 0.5) },
        ],
        wheel_start_rad: vec![0.25, 6.0],
        truth_position_only: false,
    };
    let run = Run::new(d).unwrap();
    let p = dir.path().join("r.csv");
    write_run(&p, &run, &["a".into(), "b".into()]).unwrap();
    assert_eq!(read_run(&p, None).unwrap(), run);
}
