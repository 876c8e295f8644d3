//! `omnical export --robot-config DIR` on the real binary: the files parse as YAML (yaml-rust2) and as C,
//! the written matrix is the model's, and the controller parameters reproduce the fitted odometry — exactly
//! when the robot is of the controller's form (APR-02's design, a differential drive, a mecanum base), and
//! within a stated tolerance for the paper's calibrated APR-02 (Eq. 9).
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "robot_config/helpers.rs"]
mod helpers;
mod support;

use helpers::{
    assert_close, check_header, diff_matrix, loss_pct, omni_controller_twist, omnical_with_stderr, real,
    rms_twist_difference, simulate_apr02, strings, write_model, write_runs, written_matrix, yaml,
};
use omni_cli::dataset::{self, LoadOptions};
use omni_kin::{FittedModel, IkMatrix, Model, RobotGeometry, Scheme, Wheel};
use std::path::Path;
use support::{omnical, stderr, stdout, succeeded_on_two_threads};
use yaml_rust2::Yaml;

#[test]
fn apr02_design_is_exactly_an_omni_wheel_drive_controller() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    simulate_apr02(dir);
    let (out, err) =
        omnical_with_stderr(&["export", "--model", "design", "--robot-config", "rc", "sim/validation"], dir);
    let rc = dir.join("rc");
    // The written matrix is Eq. 7 bit for bit.
    assert_eq!(written_matrix(&rc), IkMatrix::paper_design());
    let y = yaml(&rc.join("ros2_controllers.yaml"));
    assert_eq!(
        y["controller_manager"]["ros__parameters"]["omni_wheel_drive_controller"]["type"].as_str(),
        Some("omni_wheel_drive_controller/OmniWheelDriveController")
    );
    let p = &y["omni_wheel_drive_controller"]["ros__parameters"];
    assert_eq!(strings(&p["wheel_names"]), ["wheel_a", "wheel_b", "wheel_c"]);
    // Eq. 7 holds its digits to ~1e-16: the controller's r = 0.148 m, R = 0.195 m, first wheel at 60°.
    assert!((real(&p["wheel_radius"]) - 0.148).abs() < 1e-12, "{out}");
    assert!((real(&p["robot_radius"]) - 0.195).abs() < 1e-12, "{out}");
    assert!((real(&p["wheel_offset"]) - std::f64::consts::FRAC_PI_3).abs() < 1e-12, "{out}");
    // Nothing is given up, and the sign convention is warned about on stderr (APR-02 counts anticlockwise).
    assert!(loss_pct(&out).iter().all(|p| p.abs() < 0.05), "{out}");
    assert!(err.starts_with("warning: omni_wheel_drive_controller counts a wheel speed positive when it"), "{err}");
    assert!(err.contains("these joints count the other way: wheel_a, wheel_b, wheel_c"), "{err}");
    assert!(!out.contains("warning"), "warnings go to stderr, results to stdout: {out}");
}

#[test]
fn calibrated_apr02_matrix_header_and_nearest_controller() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    simulate_apr02(dir);
    let out = omnical_with_stderr(&["export", "--model", "paper", "--robot-config", "rc", "sim/validation"], dir).0;
    let rc = dir.join("rc");
    let eq9 = IkMatrix::paper_calibrated();
    let written = written_matrix(&rc);
    assert_close(written.entries(), eq9.entries(), 1e-12, "omnical_odometry.yaml vs the model's matrix");
    check_header(&rc, &eq9, Scheme::ExactArc);

    // The controller's twist (its own formula, with the reversed joints negated) against Eq. 9's over the
    // runs' wheel speeds, RMS per run then over runs: within 3 mm/s and 3 mrad/s, and closer than the
    // design controller (Eq. 7) is.
    let y = yaml(&rc.join("ros2_controllers.yaml"));
    let p = &y["omni_wheel_drive_controller"]["ros__parameters"];
    let (r, big_r, offset) = (real(&p["wheel_radius"]), real(&p["robot_radius"]), real(&p["wheel_offset"]));
    let runs = dataset::load(&[dir.join("sim/validation")], &LoadOptions::default()).unwrap().runs;
    let design = IkMatrix::paper_design();
    let fitted = rms_twist_difference(&runs, &eq9, |w| omni_controller_twist(r, big_r, offset, w.map(|x| -x)));
    let nominal = rms_twist_difference(&runs, &eq9, |w| {
        let t = design.twist(&w);
        [t.vx_m_s, t.vy_m_s, t.omega_rad_s]
    });
    for k in 0..3 {
        assert!(fitted[k] < 3e-3, "component {k}: {fitted:?}\n{out}");
        assert!(fitted[k] < nominal[k], "component {k}: fitted {fitted:?} vs design {nominal:?}");
    }
    // The simpler model gives something up on these runs, and says how much.
    let [end_pose, path] = loss_pct(&out);
    assert!(end_pose > 0.05 && path > 0.05, "{out}");
}

#[test]
fn diff_drive_multipliers_reproduce_a_differential_drive_exactly() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // Design: separation 0.40 m, radii 0.05 m; the robot: 0.42 m, left 0.050 m, right 0.0505 m.
    let truth = diff_matrix(0.42, 0.05, 0.0505);
    // The design's vy row is zero throughout: a structural zero, not a parameter (rows vx and ω are).
    let free: Vec<f64> = [truth.row(0), truth.row(2)].concat();
    let fitted = FittedModel::new(Model::ik(diff_matrix(0.4, 0.05, 0.05)), free).unwrap();
    let names = vec!["right_wheel_joint".to_string(), "left_wheel_joint".to_string()];
    write_runs(&dir.join("runs"), &fitted, &names);
    write_model(&dir.join("diff.toml"), &fitted);
    let (out, err) = omnical_with_stderr(
        &[
            "export",
            "--model",
            "diff.toml",
            "--robot-config",
            "rc",
            "runs",
            "--joints",
            "right_wheel_joint,left_wheel_joint",
        ],
        dir,
    );
    let rc = dir.join("rc");
    assert_eq!(written_matrix(&rc), truth);
    let y = yaml(&rc.join("ros2_controllers.yaml"));
    let p = &y["diff_drive_controller"]["ros__parameters"];
    assert_eq!(strings(&p["left_wheel_names"]), ["left_wheel_joint"]);
    assert_eq!(strings(&p["right_wheel_names"]), ["right_wheel_joint"]);
    let got = [
        real(&p["wheel_separation"]),
        real(&p["wheel_radius"]),
        real(&p["wheel_separation_multiplier"]),
        real(&p["left_wheel_radius_multiplier"]),
        real(&p["right_wheel_radius_multiplier"]),
    ];
    assert_close(&got, &[0.4, 0.05, 1.05, 1.0, 1.01], 1e-12, "diff_drive_controller parameters");
    // The controller's own formula with these parameters is the robot's matrix.
    let (s, rl, rr) = (got[0] * got[2], got[1] * got[3], got[1] * got[4]);
    assert_close(diff_matrix(s, rl, rr).entries(), truth.entries(), 1e-12, "controller odometry");
    assert!(loss_pct(&out).iter().all(|p| p.abs() < 0.05), "{out}");
    assert!(!err.contains("warning"), "{err}");
}

#[test]
fn mecanum_controller_reproduces_a_mecanum_base_with_its_own_joint_order() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // A mecanum base whose joints come in the order rear_right, front_left, rear_left, front_right.
    let m = RobotGeometry::mecanum4(0.05, 0.2, 0.15);
    let order = [3, 0, 2, 1];
    let wheels: Vec<Wheel> = order.iter().map(|&i| m.wheels[i].clone()).collect();
    let names: Vec<String> = ["rr", "fl", "rl", "fr"].iter().map(|s| s.to_string()).collect();
    let g = RobotGeometry { wheel_names: names.clone(), wheels };
    let fitted = FittedModel::nominal(Model::geometry(g));
    write_runs(&dir.join("runs"), &fitted, &names);
    write_model(&dir.join("mecanum.toml"), &fitted);
    let out = omnical_with_stderr(&["export", "--model", "mecanum.toml", "--robot-config", "rc", "runs"], dir).0;
    let rc = dir.join("rc");
    assert_close(written_matrix(&rc).entries(), fitted.ik().unwrap().entries(), 1e-15, "matrix");
    let y = yaml(&rc.join("ros2_controllers.yaml"));
    let p = &y["mecanum_drive_controller"]["ros__parameters"];
    for (key, joint) in [("front_left", "fl"), ("front_right", "fr"), ("rear_left", "rl"), ("rear_right", "rr")] {
        assert_eq!(p[format!("{key}_wheel_command_joint_name").as_str()].as_str(), Some(joint), "{key}");
    }
    let k = &p["kinematics"];
    assert!((real(&k["wheels_radius"]) - 0.05).abs() < 1e-12, "{out}");
    assert!((real(&k["sum_of_robot_center_projection_on_X_Y_axis"]) - 0.35).abs() < 1e-12, "{out}");
    assert!(loss_pct(&out).iter().all(|p| p.abs() < 0.05), "{out}");
}

#[test]
fn a_controller_that_cannot_drive_the_base_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    simulate_apr02(dir);
    let out = omnical(
        &["export", "--model", "paper", "--robot-config", "rc", "--controller", "mecanum", "sim/validation"],
        dir,
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("mecanum_drive_controller") && err.contains("cannot drive a base with 3 wheels"), "{err}");
}

#[test]
fn effects_a_matrix_cannot_carry_are_listed_as_warnings() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    simulate_apr02(dir);
    let mut fitted = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))
        .with_effect(omni_kin::EffectKind::from_id("time_offset", 3).unwrap());
    fitted.set("time_offset.tau_s", 0.04).unwrap();
    write_model(&dir.join("lag.toml"), &fitted);
    let (out, err) =
        omnical_with_stderr(&["export", "--model", "lag.toml", "--robot-config", "rc", "sim/validation"], dir);
    let rc = dir.join("rc");
    assert_eq!(written_matrix(&rc), IkMatrix::paper_calibrated());
    let header = std::fs::read_to_string(rc.join("omnical_odometry.h")).unwrap();
    assert!(header.contains(" * WARNING: the model also has effects a plain matrix cannot carry"), "{header}");
    assert!(header.contains(" *   - time_offset: tau_s = 0.04 s"), "{header}");
    let y = yaml(&rc.join("omnical_odometry.yaml"));
    assert_eq!(strings(&y["/**"]["ros__parameters"]["effects_not_in_matrix"]), ["time_offset: tau_s = 0.04 s"]);
    // The matrix alone is measured too (the simulated robot has no clock lag, so the lag costs accuracy).
    let alone = out.lines().find(|l| l.contains("its matrix alone")).unwrap_or_else(|| panic!("{out}"));
    assert_eq!(alone.split_whitespace().filter_map(|t| t.parse::<f64>().ok()).count(), 2, "{alone}");
    assert!(err.contains("warning: the controller cannot carry the model's effects (time_offset)."), "{err}");
}

/// Parameter names each file's reader declares, from its source: ros2_controllers'
/// `diff_drive_controller/src/diff_drive_controller_parameter.yaml`,
/// `mecanum_drive_controller/src/mecanum_drive_controller.yaml` (released 2.43 / 4.x),
/// `omni_wheel_drive_controller/src/omni_wheel_drive_controller_parameters.yaml`; Nav2's
/// `nav2_amcl/src/amcl_node.cpp` (the motion-model ones); robot_localization's `params/ekf.yaml` (the ones
/// written). Nested names are dotted.
const SCHEMAS: [(&str, &[&str]); 5] = [
    (
        "diff_drive_controller",
        &[
            "left_wheel_names",
            "right_wheel_names",
            "wheel_separation",
            "wheels_per_side",
            "wheel_radius",
            "wheel_separation_multiplier",
            "left_wheel_radius_multiplier",
            "right_wheel_radius_multiplier",
            "odom_frame_id",
            "base_frame_id",
            "pose_covariance_diagonal",
            "twist_covariance_diagonal",
            "open_loop",
            "position_feedback",
            "enable_odom_tf",
            "cmd_vel_timeout",
            "publish_rate",
        ],
    ),
    (
        "mecanum_drive_controller",
        &[
            "reference_timeout",
            "front_left_wheel_command_joint_name",
            "front_right_wheel_command_joint_name",
            "rear_right_wheel_command_joint_name",
            "rear_left_wheel_command_joint_name",
            "front_left_wheel_state_joint_name",
            "front_right_wheel_state_joint_name",
            "rear_right_wheel_state_joint_name",
            "rear_left_wheel_state_joint_name",
            "kinematics.base_frame_offset.x",
            "kinematics.base_frame_offset.y",
            "kinematics.base_frame_offset.theta",
            "kinematics.wheels_radius",
            "kinematics.sum_of_robot_center_projection_on_X_Y_axis",
            "base_frame_id",
            "odom_frame_id",
            "enable_odom_tf",
            "twist_covariance_diagonal",
            "pose_covariance_diagonal",
        ],
    ),
    (
        "omni_wheel_drive_controller",
        &[
            "wheel_offset",
            "wheel_names",
            "robot_radius",
            "wheel_radius",
            "odom_frame_id",
            "base_frame_id",
            "diagonal_covariance.pose",
            "diagonal_covariance.twist",
            "open_loop",
            "position_feedback",
            "enable_odom_tf",
            "cmd_vel_timeout",
        ],
    ),
    ("amcl", &["robot_model_type", "alpha1", "alpha2", "alpha3", "alpha4", "alpha5", "update_min_d", "update_min_a"]),
    (
        "ekf_filter_node",
        &[
            "frequency",
            "two_d_mode",
            "odom0",
            "odom0_config",
            "odom0_differential",
            "odom0_relative",
            "odom0_queue_size",
        ],
    ),
];

/// The dotted names of every parameter under `node: ros__parameters:`.
fn parameter_names(y: &Yaml, node: &str) -> Vec<String> {
    fn walk(y: &Yaml, prefix: &str, out: &mut Vec<String>) {
        match y.as_hash() {
            Some(h) => {
                for (k, v) in h {
                    let k = k.as_str().unwrap();
                    walk(v, &if prefix.is_empty() { k.to_string() } else { format!("{prefix}.{k}") }, out);
                }
            }
            None => out.push(prefix.to_string()),
        }
    }
    let mut out = Vec::new();
    walk(&y[node]["ros__parameters"], "", &mut out);
    assert!(!out.is_empty(), "no parameters under {node}");
    out
}

/// Every parameter written for `node` is one its source declares.
fn assert_schema(y: &Yaml, node: &str) {
    let schema = SCHEMAS.iter().find(|(n, _)| *n == node).unwrap().1;
    for name in parameter_names(y, node) {
        assert!(schema.contains(&name.as_str()), "{node}: `{name}` is not a parameter of its source");
    }
}

/// A model file's `[noise]` table with these rates (no floor, no systematic part), as `train` writes it.
fn noise_table(holonomic: bool, rates: [f64; 5]) -> String {
    let [rr, rm, tm, tr, sm] = rates;
    let keys = format!(
        "rot_per_rad = {rr:?}\nrot_per_m = {rm:?}\ntrans_per_m = {tm:?}\ntrans_per_rad = {tr:?}\nstrafe_per_m = {sm:?}\n\
         floor_position_m2 = 4e-6\nfloor_heading_rad2 = 9e-6\n"
    );
    format!(
        "\n[noise]\nholonomic = {holonomic}\nruns = 12\nwindows = 300\n[noise.rates]\n{keys}[noise.std_errors]\n{keys}\
         [noise.systematic]\nper_displacement = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\nposition_share = 0.0\n"
    )
}

fn reals(y: &Yaml) -> Vec<f64> {
    y.as_vec().unwrap_or_else(|| panic!("not a list: {y:?}")).iter().map(real).collect()
}

#[test]
fn every_exported_parameter_is_its_readers_and_the_noise_model_reaches_the_ros_stack() {
    // A mecanum base (holonomic: the omni motion model) and a differential drive (the differential one).
    let rates = [4e-4, 3e-4, 6e-4, 2e-4, 5e-4];
    let m = RobotGeometry::mecanum4(0.05, 0.2, 0.15);
    let names: Vec<String> = ["fl", "fr", "rl", "rr"].iter().map(|s| s.to_string()).collect();
    let mecanum = FittedModel::nominal(Model::geometry(RobotGeometry { wheel_names: names.clone(), wheels: m.wheels }));
    let diff = FittedModel::new(Model::ik(diff_matrix(0.4, 0.05, 0.05)), {
        let d = diff_matrix(0.4, 0.05, 0.05);
        [d.row(0), d.row(2)].concat()
    })
    .unwrap();
    let diff_names = vec!["right_wheel_joint".to_string(), "left_wheel_joint".to_string()];
    for (label, fitted, joints, holonomic, node, amcl_model) in [
        ("mecanum", &mecanum, &names, true, "mecanum_drive_controller", "nav2_amcl::OmniMotionModel"),
        ("diff", &diff, &diff_names, false, "diff_drive_controller", "nav2_amcl::DifferentialMotionModel"),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        write_runs(&dir.join("runs"), fitted, joints);
        let mut text = omni_cli::model_file::to_toml(fitted, None).unwrap();
        text.push_str(&noise_table(holonomic, rates));
        std::fs::write(dir.join("m.toml"), text).unwrap();
        let joined = joints.join(",");
        omnical_with_stderr(&["export", "--model", "m.toml", "--robot-config", "rc", "runs", "--joints", &joined], dir);
        let rc = dir.join("rc");
        let controller = yaml(&rc.join("ros2_controllers.yaml"));
        assert_schema(&controller, node);
        let p = &controller[node]["ros__parameters"];
        // The pose diagonal: the covariance after 1 m driven straight; it does not grow.
        let pose = reals(&p["pose_covariance_diagonal"]);
        let strafe = if holonomic { rates[4] } else { 0.0 };
        assert_close(&[pose[0], pose[1], pose[5]], &[rates[2], strafe + rates[1] / 3.0, rates[1]], 1e-15, label);
        assert_eq!(reals(&p["twist_covariance_diagonal"]).len(), 6);
        let amcl = yaml(&rc.join("nav2_amcl.yaml"));
        assert_schema(&amcl, "amcl");
        let a = &amcl["amcl"]["ros__parameters"];
        assert_eq!(a["robot_model_type"].as_str(), Some(amcl_model), "{label}");
        let (d, turn) = (real(&a["update_min_d"]), real(&a["update_min_a"]));
        let alpha2 = if holonomic { rates[1] / d } else { rates[1] / (2.0 * d) };
        let want = [rates[0] / turn, alpha2, rates[2] / d, rates[3] / turn, strafe / d];
        let got: Vec<f64> = (1..=5).map(|k| real(&a[format!("alpha{k}").as_str()])).collect();
        assert_close(&got, &want, 1e-15, &format!("{label}: AMCL alphas"));
        let ekf = yaml(&rc.join("robot_localization.yaml"));
        assert_schema(&ekf, "ekf_filter_node");
        // Each file names the ROS distributions it is for.
        for f in ["ros2_controllers.yaml", "nav2_amcl.yaml", "robot_localization.yaml", "omnical_odometry.yaml"] {
            let text = std::fs::read_to_string(rc.join(f)).unwrap();
            assert!(text.contains("Humble") && text.contains("Rolling"), "{label} {f}:\n{text}");
        }
        assert!(std::fs::read_to_string(rc.join("omnical_odometry.h")).unwrap().contains("no ROS dependency"));
    }
}

#[test]
fn without_a_noise_model_no_amcl_file_is_written_and_the_controller_keeps_its_defaults() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let m = RobotGeometry::mecanum4(0.05, 0.2, 0.15);
    let names: Vec<String> = ["fl", "fr", "rl", "rr"].iter().map(|s| s.to_string()).collect();
    let fitted = FittedModel::nominal(Model::geometry(RobotGeometry { wheel_names: names.clone(), wheels: m.wheels }));
    write_runs(&dir.join("runs"), &fitted, &names);
    write_model(&dir.join("m.toml"), &fitted);
    omnical_with_stderr(&["export", "--model", "m.toml", "--robot-config", "rc", "runs"], dir);
    assert!(!dir.join("rc/nav2_amcl.yaml").exists() && !dir.join("rc/robot_localization.yaml").exists());
    let controller = yaml(&dir.join("rc/ros2_controllers.yaml"));
    assert_schema(&controller, "mecanum_drive_controller");
    assert!(controller["mecanum_drive_controller"]["ros__parameters"]["pose_covariance_diagonal"].is_badvalue());
}

/// `file` rewritten without the messages on `topic`.
fn without_topic(file: &Path, topic: &str) {
    let bytes = std::fs::read(file).unwrap();
    let mut out = Vec::new();
    {
        let mut w = mcap::WriteOptions::new().profile("ros2").create(std::io::Cursor::new(&mut out)).unwrap();
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            if m.channel.topic != topic {
                w.write(&m).unwrap();
            }
        }
        w.finish().unwrap();
    }
    std::fs::write(file, out).unwrap();
}

#[test]
fn robot_config_needs_no_ground_truth_and_says_what_it_measured_against() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    succeeded_on_two_threads(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "3"], dir);
    let bags: Vec<_> = std::fs::read_dir(dir.join("sim/validation"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mcap"))
        .collect();
    assert!(bags.len() >= 3, "{bags:?}");
    for b in &bags {
        without_topic(b, "/ground_truth/pose");
    }
    let args = ["export", "--model", "paper", "--robot-config", "rc", "sim/validation"];
    let run = support::succeeded(&[&["--threads", "2"], &args[..]].concat(), dir);
    let (out, err) = (stdout(&run), stderr(&run));
    assert!(err.contains("note: the runs have no ground truth ("), "{err}");
    assert!(
        out.contains("(the runs have no ground truth: measured against the calibrated model's own odometry)"),
        "{out}"
    );
    assert!(!out.contains("given up by the controller"), "a loss against a zero is meaningless: {out}");
    // The written matrix is still the model's (Eq. 9), and the model's own row is exactly zero.
    assert_close(written_matrix(&dir.join("rc")).entries(), IkMatrix::paper_calibrated().entries(), 1e-12, "matrix");
    let model_row: Vec<f64> = out
        .lines()
        .find(|l| l.trim_start().starts_with("calibrated model"))
        .unwrap_or_else(|| panic!("{out}"))
        .split_whitespace()
        .filter_map(|t| t.parse().ok())
        .collect();
    assert_eq!(model_row, [0.0, 0.0], "{out}");
    // The JSON names what the figures are against; the design is measurably away from the model.
    let json = stdout(&succeeded_on_two_threads(&[&args[..4], &["rc2", "--json", "sim/validation"]].concat(), dir));
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let acc = &v["robot_config"]["accuracy"];
    assert_eq!(acc["against"], "model_odometry", "{json}");
    assert!(acc["design"]["end_pose"].as_f64().unwrap() > 1e-3, "{json}");
    // --tum exports the ground truth, so it still needs it: refused naming the file.
    let e = stderr(&omnical(&["export", "--model", "paper", "--tum", "tum", "sim/validation"], dir));
    assert!(e.contains("no ground truth"), "{e}");
}
