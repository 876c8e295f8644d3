//! `omnical init` on rosbag2 recordings in every layout `train` reads (written by Python `rosbags`,
//! `tests/rosbag2/make_recordings.py`): each gives the same robot description. The interpreter and the
//! ignored-without-tools rule are `rosbag2`'s.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "rosbag2/helpers.rs"]
mod helpers;
mod support;

use helpers::{LAYOUTS, exit_code_and_output, fixtures};
use std::path::Path;

/// `omnical init INPUT --out OUT` and more: exit status, stdout, stderr.
fn init(input: &Path, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec!["init", input.to_str().unwrap(), "--out", out.to_str().unwrap(), "--force"];
    args.extend_from_slice(extra);
    exit_code_and_output(&args)
}

#[test]
#[cfg_attr(
    not(python_bag_tools),
    ignore = "needs rosbags and numpy in $OMNICAL_PYTHON: bash scripts/test.sh installs them"
)]
fn init_reads_every_layout_train_reads() {
    let (dir, expected) = fixtures();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("robot.toml");
    // The URDF from the recording's own /robot_description topic (a .db3 folder).
    let rec = dir.join("urdf/rec");
    let (code, stdout, err) = init(&rec, &out, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(
        stdout.contains(&format!("Read from the URDF (topic /robot_description of {})", rec.display())),
        "{stdout}"
    );
    let joints_line = format!(
        "/joint_states (sensor_msgs/msg/JointState): {} messages, 100.0 Hz, joints wheel_a, wheel_b, wheel_c",
        expected["n_wheel"]
    );
    assert!(stdout.contains(&joints_line), "{stdout}");
    assert!(stdout.contains("/robot_description (std_msgs/msg/String): 1 messages"), "{stdout}");
    let want = omni_cli::robot_file::read(&out).unwrap();
    assert_eq!(want.joints(), ["wheel_a", "wheel_b", "wheel_c"]);

    // The drafted design is the simulated robot's (wheels at 90°, 210°, 330°, 0.2 m out, r = 0.05 m, driving
    // along the counter-clockwise tangent): body twist = r K⁻¹ u with K's rows (−sin b, cos b, L).
    let (r, l, s3) = (0.05, 0.2, 3f64.sqrt());
    let truth = [
        [-2.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
        [0.0, -1.0 / s3, 1.0 / s3],
        [1.0 / (3.0 * l), 1.0 / (3.0 * l), 1.0 / (3.0 * l)],
    ];
    let rows = want.design_ik().unwrap().rows();
    for (row, t) in rows.iter().zip(truth) {
        for (a, b) in row.iter().zip(t) {
            assert!((a - r * b).abs() < 1e-9, "{rows:?}");
        }
    }

    // Every layout gives the same description (the URDF as a file); a folder of recordings, its first.
    let urdf = dir.join("urdf/omni3.urdf");
    let inputs = ["ref/rec.mcap", "bare/rec.db3", "several"]
        .into_iter()
        .map(|p| dir.join(p))
        .chain(LAYOUTS.iter().map(|l| dir.join(l).join("rec")));
    for input in inputs {
        let (code, stdout, err) = init(&input, &out, &["--urdf", urdf.to_str().unwrap()]);
        assert_eq!(code, 0, "{}: {err}", input.display());
        assert!(stdout.contains(&joints_line), "{}: {stdout}", input.display());
        assert_eq!(omni_cli::robot_file::read(&out).unwrap(), want, "{}", input.display());
    }
    let (_, stdout, _) = init(&dir.join("several"), &out, &["--urdf", urdf.to_str().unwrap()]);
    assert!(
        stdout.starts_with(&format!(
            "{} holds 2 recordings; inspecting the first, {}\n",
            dir.join("several").display(),
            dir.join("several/a").display()
        )),
        "{stdout}"
    );

    // Broken recordings are refused as `train` refuses them (exit 2, the file and the message).
    let bad = dir.join("bad");
    let refuse = |input: &Path| {
        let (code, _, err) = init(input, &out, &["--urdf", urdf.to_str().unwrap()]);
        assert_eq!(code, 2, "{err}");
        err.trim_end().to_string()
    };
    let d = bad.display();
    assert_eq!(
        refuse(&bad.join("truncated_blob.db3")),
        format!(
            "error: {d}/truncated_blob.db3: topic \"/joint_states\", message 5: cannot decode CDR: the 40-byte \
             message ends before its last field (cut short, or a length inside it is corrupted); is the message \
             type right?"
        )
    );
    assert_eq!(
        refuse(&bad.join("missing_file")),
        format!(
            "error: {d}/missing_file/metadata.yaml: key relative_file_paths: lists {d}/missing_file/missing_file_1.db3, \
             which does not exist"
        )
    );
    let gt = dir.join("gt/csv_3s");
    assert_eq!(
        refuse(&gt),
        format!(
            "error: {}: no ROS 2 recording here (init reads .mcap and .db3 files and rosbag2 recording folders with \
             a metadata.yaml)",
            gt.display()
        )
    );
}
