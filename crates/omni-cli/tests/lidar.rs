//! The 2D-lidar reference (issue 28): simulated scans written to MCAP, read back and matched into the
//! sensor's path, against the true sensor path (base pose ∘ mount); bad inputs (no scan topic, a corridor,
//! a room the robot leaves, a bad room file) through the real binary.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use omni_cli::dataset::mcap::{LidarTrack, SIM_EPOCH_S, WriteOptions, write_run};
use omni_cli::lidar::{self, MatchSettings, Room, ScanSettings};
use omni_kin::simulate::{SimConfig, flower_commands, simulate_sampled};
use omni_kin::{FittedModel, IkMatrix, Model, Pose2, StampedPose};
use support::{json, ok, refused};

/// Drift of a chained sensor path against the true one: end position error per metre travelled (m/m) and
/// end heading error per metre (rad/m); and the path length (m).
fn drift(path: &[StampedPose], truth: &[StampedPose]) -> (f64, f64, f64) {
    let at = |t: f64| truth.iter().find(|p| (p.t_s - t).abs() < 1e-6).unwrap_or_else(|| panic!("no truth at {t}")).pose;
    let start = at(path[0].t_s);
    let (end, true_end) = (path[path.len() - 1].pose, start.inverse().compose(&at(path[path.len() - 1].t_s)));
    let length: f64 =
        path.windows(2).map(|w| (w[1].pose.x_m - w[0].pose.x_m).hypot(w[1].pose.y_m - w[0].pose.y_m)).sum();
    let e = end.error_to(&true_end);
    (e.dx_m.hypot(e.dy_m) / length, e.dtheta_rad.abs() / length, length)
}

#[test]
fn chained_scan_path_of_simulated_runs_matches_the_true_sensor_path_within_millimetres_per_metre() {
    let tmp = tempfile::tempdir().unwrap();
    let mount = Pose2::new(0.2, 0.0, 5f64.to_radians());
    let room = Room::builtin("room").unwrap();
    let settings = ScanSettings::default();
    // Eight flower commands (straight, turning both ways), 10 s each.
    let commands = flower_commands().into_iter().step_by(5).collect();
    let config = SimConfig { commands, runs_per_command: 1, seed: 11, ..SimConfig::default() };
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    let runs = simulate_sampled(&config, &truth, "", 0.1).unwrap();
    let (mut worst_m_per_m, mut worst_rad_per_m, mut travelled) = (0.0f64, 0.0f64, 0.0);
    let (mut worst_window_m, mut worst_window_rad) = (0.0f64, 0.0f64);
    for (i, s) in runs.iter().enumerate() {
        assert!(lidar::first_collision(&room, &s.base, lidar::CLEARANCE_M).is_none(), "{}", s.run.name());
        let scans = lidar::simulate_scans(&room, &s.base, &mount, &settings, config.seed, i as u64);
        let file = tmp.path().join(format!("{i}.mcap"));
        let lidar = Some(LidarTrack { scans, base_from_sensor: Some(mount) });
        write_run(&file, &s.run, &WriteOptions { origin_s: SIM_EPOCH_S, lidar, ..Default::default() }).unwrap();

        let read = lidar::read_scans(&file, "/scan").unwrap();
        assert_eq!((read.origin_s, read.frame_id.as_str(), read.scans.len()), (SIM_EPOCH_S, "laser", s.base.len()));
        let m = read.base_from_sensor.unwrap();
        assert!((m.x_m - 0.2).abs() < 1e-12 && m.y_m.abs() < 1e-12 && (m.theta_rad - mount.theta_rad).abs() < 1e-12);
        let path = lidar::sensor_path(&read.scans, &MatchSettings::default()).unwrap();
        assert_eq!(
            (path.matched, path.rejected, path.segments.len()),
            (s.base.len() - 1, 0, 1),
            "{}: {:?}",
            s.run.name(),
            path.rejected_why
        );
        // The true sensor path: room_from_base ∘ base_from_sensor.
        let sensor: Vec<StampedPose> =
            s.base.iter().map(|b| StampedPose { t_s: b.t_s, pose: b.pose.compose(&mount) }).collect();
        let (m_per_m, rad_per_m, length) = drift(&path.segments[0], &sensor);
        // Relative motion over 1 s windows (10 scans), as a windowed relative reference compares it.
        let seg = &path.segments[0];
        for w in seg.windows(11) {
            let at = |t: f64| sensor.iter().find(|p| (p.t_s - t).abs() < 1e-6).unwrap().pose;
            let truth = at(w[0].t_s).inverse().compose(&at(w[10].t_s));
            let e = w[0].pose.inverse().compose(&w[10].pose).error_to(&truth);
            worst_window_m = worst_window_m.max(e.dx_m.hypot(e.dy_m));
            worst_window_rad = worst_window_rad.max(e.dtheta_rad.abs());
        }
        worst_m_per_m = worst_m_per_m.max(m_per_m);
        worst_rad_per_m = worst_rad_per_m.max(rad_per_m);
        travelled += length;
    }
    eprintln!(
        "8 runs, {travelled:.2} m of sensor travel: worst end drift {:.2} mm/m, {:.4}°/m; worst 1 s window {:.2} mm, \
         {:.4}°",
        1e3 * worst_m_per_m,
        worst_rad_per_m.to_degrees(),
        1e3 * worst_window_m,
        worst_window_rad.to_degrees()
    );
    assert!(travelled > 8.0, "{travelled}");
    assert!(worst_m_per_m < 0.003, "worst drift {:.2} mm per m", 1e3 * worst_m_per_m);
    assert!(worst_window_m < 0.005, "worst 1 s window {:.2} mm", 1e3 * worst_window_m);
    assert!(worst_window_rad.to_degrees() < 0.1, "worst 1 s window {:.4}°", worst_window_rad.to_degrees());
    assert!(worst_rad_per_m.to_degrees() < 0.05, "worst heading drift {:.4}° per m", worst_rad_per_m.to_degrees());
}

#[test]
fn simulate_writes_the_lidar_and_scan_odometry_follows_it_whatever_the_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sim = ["simulate", "--runs-per-command", "1", "--duration", "4", "--seed", "3", "-q"];
    let lidar = ["--lidar", "room", "--lidar-mount", "0.2,0,5"];
    ok(&[&["--threads", "1"][..], &sim, &lidar, &["--out", "one"]].concat(), d);
    ok(&[&["--threads", "2"][..], &sim, &lidar, &["--out", "two"]].concat(), d);
    // Same seed, same bytes, whatever the thread count.
    for run in ["train/00-r0.mcap", "validation/17-r0.mcap"] {
        assert!(std::fs::read(d.join("one").join(run)).unwrap() == std::fs::read(d.join("two").join(run)).unwrap());
    }
    let truth: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("one/truth.json")).unwrap()).unwrap();
    assert_eq!(truth["lidar"]["room"], "room");
    assert_eq!(truth["lidar"]["base_from_sensor"]["x_m"], 0.2);
    let j: serde_json::Value = json(&["scan-odometry", "one/train/12-r0.mcap", "--tum", "s.tum", "--json"], d);
    // 4 s of motion between two rests of 0.4 s: scans at 0, 0.1, …, 4.8 s.
    assert_eq!((j["scans"].as_u64(), j["matched"].as_u64(), j["rejected"].as_u64()), (Some(49), Some(48), Some(0)));
    assert_eq!(j["segments"].as_array().unwrap().len(), 1);
    assert!((j["base_from_sensor"]["theta_rad"].as_f64().unwrap() - 5f64.to_radians()).abs() < 1e-12);
    assert_eq!(j["mount_chain"], serde_json::json!(["base_link", "laser"]));
    assert!(j["quality"]["rms_m"]["median"].as_f64().unwrap() < 0.012, "{j}");
    assert!(j["quality"]["condition"]["max"].as_f64().unwrap() < 10.0, "{j}");
    let tum = std::fs::read_to_string(d.join("s.tum")).unwrap();
    assert_eq!(tum.lines().filter(|l| !l.starts_with('#')).count(), 49);
    assert!(tum.lines().nth(1).unwrap().starts_with("1700000000.000000000 0.000000000 0.000000000 "), "{tum}");
    // 0.2 m/s for 4 s (command 12: straight ahead, no turn): about 0.8 m, whatever the mount
    let length = j["segments"][0]["travelled_m"].as_f64().unwrap();
    assert!((0.7..0.85).contains(&length), "{length}");

    // The same bag as a rosbag2 recording (MCAP storage): the same scans, matches and path.
    std::fs::create_dir(d.join("rec")).unwrap();
    std::fs::copy(d.join("one/train/12-r0.mcap"), d.join("rec/rec_0.mcap")).unwrap();
    std::fs::write(
        d.join("rec/metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  relative_file_paths: [rec_0.mcap]\n",
    )
    .unwrap();
    let r: serde_json::Value = json(&["scan-odometry", "rec", "--json"], d);
    for key in ["scans", "matched", "rejected", "segments", "quality", "base_from_sensor"] {
        assert_eq!(r[key], j[key], "{key}");
    }
}

#[test]
fn a_sweeping_lidar_writes_its_beam_times_and_its_scans_are_de_skewed() {
    // --lidar-sweep: each 0.1 s scan's 720 beams are measured one after another (time_increment 1/7200 s);
    // scan-odometry de-skews every scan it places, and the straight run still travels its 0.8 m.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sim = ["simulate", "--runs-per-command", "1", "--duration", "4", "--seed", "3", "-q", "--out", "sim"];
    ok(&[&sim[..], &["--lidar", "room", "--lidar-mount", "0.2,0,5", "--lidar-sweep"]].concat(), d);
    let j: serde_json::Value = json(&["scan-odometry", "sim/train/12-r0.mcap", "--json"], d);
    assert_eq!((j["scans"].as_u64(), j["matched"].as_u64(), j["deskewed"].as_u64()), (Some(49), Some(48), Some(49)));
    let length = j["segments"][0]["travelled_m"].as_f64().unwrap();
    assert!((0.7..0.85).contains(&length), "{length}");
    let text = ok(&["scan-odometry", "sim/train/12-r0.mcap"], d);
    assert!(text.contains("49 scans de-skewed: their beams are measured over the sweep"), "{text}");
}

/// `--lidar-model urg04lx`: the scans come out as a URG-04LX's (682 beams over 239.4°, 0 for no return,
/// about half the beams empty, beams 0.1 s / 1024 apart) and the lidar's path still travels the straight
/// run's 0.8 m; the settings a real kind sets itself cannot be given beside it.
#[test]
fn a_urg04lx_like_lidar_writes_sparse_240_degree_scans_that_still_match() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sim = ["simulate", "--runs-per-command", "1", "--duration", "4", "--seed", "3", "-q", "--out", "sim"];
    ok(&[&sim[..], &["--lidar", "room", "--lidar-mount", "0.15,0,0", "--lidar-model", "urg04lx"]].concat(), d);
    let read = lidar::read_scans(&d.join("sim/train/12-r0.mcap"), "/scan").unwrap();
    let scan = &read.scans[0];
    let span_deg = (scan.angle_increment_rad * 681.0).to_degrees();
    assert_eq!(scan.ranges_m.len(), 682);
    assert!((span_deg - 239.414).abs() < 1e-3 && (scan.time_increment_s - 0.1 / 1024.0).abs() < 1e-10, "{scan:?}"); // float32 in the message
    let beams: usize = read.scans.iter().map(|s| s.ranges_m.len()).sum();
    let zeros = read.scans.iter().flat_map(|s| &s.ranges_m).filter(|&&r| r == 0.0).count();
    let empty = read.scans.iter().map(|s| (0..s.ranges_m.len()).filter(|&i| !s.is_return(i)).count()).sum::<usize>();
    eprintln!("{empty} of {beams} beams empty ({zeros} written as 0)");
    assert!((0.35..0.65).contains(&(empty as f64 / beams as f64)), "{empty} of {beams} beams empty");
    assert!(zeros > beams / 4 && read.scans.iter().flat_map(|s| &s.ranges_m).all(|r| r.is_finite()));
    let j: serde_json::Value = json(&["scan-odometry", "sim/train/12-r0.mcap", "--json"], d);
    assert_eq!((j["scans"].as_u64(), j["deskewed"].as_u64()), (Some(49), Some(49)), "{j}");
    assert!(j["matched"].as_u64().unwrap() >= 46, "{j}");
    let length = j["segments"][0]["travelled_m"].as_f64().unwrap();
    // The truth travels 0.83 m. Along the room's 10 m axis the URG's view constrains this motion poorly (the
    // front wall near its 5.6 m range, the side walls at grazing angles, where it returns nothing): the
    // lidar's path comes out 4–5 % long on this straight run (seeds 1–4: 0.86–0.87 m), against −0.14 % and
    // −0.37 % over a loop (docs/formats.md). A longer path here is a regression.
    assert!((0.8..0.88).contains(&length), "{length}");
    let e = refused(&[&sim[..], &["--lidar", "room", "--lidar-model", "urg04lx", "--lidar-beams", "100"]].concat(), d);
    assert!(e.contains("--lidar-model") && e.contains("--lidar-beams"), "{e}");
}

#[test]
fn a_recording_without_the_scan_topic_names_the_file_and_the_topic() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    ok(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "1", "-q"], d);
    let err = refused(&["scan-odometry", "sim/train/00-r0.mcap"], d);
    assert_eq!(
        err.trim(),
        "error: sim/train/00-r0.mcap: no topic \"/scan\" in the recording (its topics: /cmd_vel \
         (geometry_msgs/msg/TwistStamped), /ground_truth/pose (geometry_msgs/msg/PoseStamped), /joint_states \
         (sensor_msgs/msg/JointState), /odom (nav_msgs/msg/Odometry)); no topic holds sensor_msgs/msg/LaserScan: \
         record the lidar's scans"
    );
    let err = refused(&["scan-odometry", "sim/train/00-r0.mcap", "--topic", "/odom"], d);
    assert_eq!(
        err.trim(),
        "error: sim/train/00-r0.mcap: topic \"/odom\": is a nav_msgs/msg/Odometry, not a sensor_msgs/msg/LaserScan"
    );
}

#[test]
fn a_corridor_leaves_motion_along_it_unconstrained_and_every_match_is_rejected() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    ok(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "2", "--lidar", "corridor", "-q"], d);
    let err = refused(&["scan-odometry", "sim/train/00-r0.mcap"], d);
    assert_eq!(
        err.trim(),
        "error: sim/train/00-r0.mcap: topic \"/scan\": none of the 28 scan matches was accepted (ill_conditioned \
         28; each scan returned a median of 617 of its 720 beams (range 0.05 to 12.00 m; a match needs 60 points)); \
         the scans do not constrain the lidar's motion (a corridor, a single wall, an empty room?) or do not \
         overlap: record where walls face several ways"
    );
    // A lidar whose range is short for its room (3.5 m in the 10 × 8 m room) returns too few points: said.
    let short = ["--lidar", "room", "--lidar-beams", "360", "--lidar-max-range", "3.5", "--out", "short"];
    ok(&[&["simulate", "--runs-per-command", "1", "--duration", "2", "-q"][..], &short[..]].concat(), d);
    let err = refused(&["train", "short/train/00-r0.mcap", "--gt-scans", "/scan"], d);
    assert!(err.contains("(28 rejected: too_few_points 28; each scan returned a median of 19 of"), "{err}");
    assert!(err.contains("of its 360 beams (range 0.05 to 3.50 m; a match needs 60 points))"), "{err}");
}

#[test]
fn rooms_the_robot_leaves_and_bad_room_files_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // A 3 × 3 m room: the flower's 2 m legs leave it.
    std::fs::write(
        d.join("small.toml"),
        "[[polygon]]\nvertices_m = [[-1.5, -1.5], [1.5, -1.5], [1.5, 1.5], [-1.5, 1.5]]\n",
    )
    .unwrap();
    let err = refused(&["simulate", "--out", "sim", "--runs-per-command", "1", "--lidar", "small.toml", "-q"], d);
    assert!(
        err.starts_with(
            "error: --lidar small.toml: run train/00-r0 leaves the room: at t = 9.5 s its base is at (0.12, -1.25) m"
        ),
        "{err}"
    );
    std::fs::write(d.join("flat.toml"), "[[polygon]]\nvertices_m = [[0, 0], [1, 0]]\n").unwrap();
    let err = refused(&["simulate", "--out", "sim", "--lidar", "flat.toml", "-q"], d);
    assert_eq!(
        err.trim(),
        "error: --lidar: flat.toml: room polygon 0: needs at least 3 vertices (polygon 0 is the outer wall, then the \
         obstacles)"
    );
    let err = refused(&["simulate", "--out", "sim", "--lidar", "nowhere", "-q"], d);
    assert_eq!(err.trim(), "error: --lidar: nowhere: no such room file, and not a built-in room (room, corridor)");
    assert!(!d.join("sim").exists());
}

/// `file` rewritten without its messages on `topic` (a robot that has no motion capture).
fn without_topic(file: &std::path::Path, topic: &str) {
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
fn a_recording_without_motion_capture_is_told_the_ways_without_it_naming_its_lidar_and_imu() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sim = ["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "2", "--lidar", "room", "--imu"];
    ok(&[&sim[..], &["-q"]].concat(), d);
    without_topic(&d.join("sim/train/00-r0.mcap"), "/ground_truth/pose");
    let err = refused(&["train", "sim/train/00-r0.mcap"], d);
    assert!(err.contains("\nerror: sim/train/00-r0.mcap: no ground truth: no geometry_msgs"), "{err}");
    assert!(
        err.trim_end().ends_with(
            ". Without motion capture: its lidar's scans as the reference: --gt-scans /scan; a sensor's or a \
             localization's own path (--gt-kind relative with --gt-topic or --gt); tape-measured end poses \
             (--gt-kind end-pose --gt TABLE; omnical plan --umbmark); its IMU for the rotation row alone: omnical \
             imu RECORDING --topic /imu"
        ),
        "{err}"
    );
    // The way it names works on the same recording. Its /tf_static places the lidar, and the free matrix
    // cannot tell a mount from the base: the mount is kept as given (none fitted, no warning).
    let (summary, stderr) =
        support::ok_with_stderr(&["train", "sim/train/00-r0.mcap", "--gt-scans", "/scan", "--json"], d);
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let names: Vec<&str> = summary["params"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["m11", "m12", "m13", "m21", "m22", "m23", "m31", "m32", "m33"], "{stderr}");
    assert!(stderr.contains("the sensor's mount is the recordings' static transform"), "{stderr}");
    assert!(!stderr.contains("not determined"), "{stderr}");
}
