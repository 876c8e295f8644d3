//! Scan matching on scans made as real lidars make them ([`super::LidarModel`]): sparse returns, a 240°
//! field of view, 0 for no return, mixed pixels at edges and a sweep. The path's length over 1 s windows
//! against the truth's is the figure a calibration's scale inherits.

use super::{LidarModel, MatchSettings, Room, ScanSettings, sensor_path, simulate_scans};
use crate::pose::{Pose2, StampedPose};

/// The base on x = 2.2 sin(0.15 t), y = 1.6 sin(0.3 t) (m), heading along its motion, sampled at 10 Hz for
/// `seconds` (up to 0.55 m/s, turning both ways).
fn loop_poses(seconds: f64) -> Vec<StampedPose> {
    let n = (seconds * 10.0).round() as usize;
    (0..n)
        .map(|k| {
            let t = k as f64 * 0.1;
            let (x, y) = (2.2 * (0.15 * t).sin(), 1.6 * (0.3 * t).sin());
            let (vx, vy) = (0.33 * (0.15 * t).cos(), 0.48 * (0.3 * t).cos());
            StampedPose { t_s: t, pose: Pose2::new(x, y, vy.atan2(vx)) }
        })
        .collect()
}

/// Σ distances between poses `window_s` apart (greedy, from the first) of `path`, and of `truth` at the
/// same stamps (`truth` holds a pose at every stamp of `path`). m.
fn window_travel(path: &[StampedPose], truth: &[StampedPose], window_s: f64) -> (f64, f64) {
    let at = |t: f64| truth.iter().find(|p| (p.t_s - t).abs() < 1e-9).map(|p| p.pose);
    let (mut lidar, mut exact) = (0.0, 0.0);
    let mut last = 0;
    for k in 1..path.len() {
        if path[k].t_s - path[last].t_s >= window_s - 1e-9 || k + 1 == path.len() {
            let d = path[last].pose.inverse().compose(&path[k].pose);
            lidar += d.x_m.hypot(d.y_m);
            if let (Some(a), Some(b)) = (at(path[last].t_s), at(path[k].t_s)) {
                let e = a.inverse().compose(&b);
                exact += e.x_m.hypot(e.y_m);
            }
            last = k;
        }
    }
    (lidar, exact)
}

/// The lidar's path length over the truth's (1 s windows) for `model` on the loop, mounted at `mount`.
fn length_ratio(model: LidarModel, mount: Pose2, seconds: f64, seed: u64) -> f64 {
    length_ratio_with(
        &format!("{model:?}"),
        &ScanSettings::of_model(model),
        &MatchSettings::default(),
        mount,
        seconds,
        seed,
    )
}

/// [`length_ratio`] for any settings.
fn length_ratio_with(
    model: &str,
    settings: &ScanSettings,
    ms: &MatchSettings,
    mount: Pose2,
    seconds: f64,
    seed: u64,
) -> f64 {
    let room = Room::builtin("room").unwrap();
    let base = loop_poses(seconds);
    let scans = simulate_scans(&room, &base, &mount, settings, seed, 0);
    let empty = scans.iter().map(|s| (0..s.ranges_m.len()).filter(|&i| !s.is_return(i)).count()).sum::<usize>() as f64
        / scans.iter().map(|s| s.ranges_m.len()).sum::<usize>() as f64;
    let truth: Vec<StampedPose> =
        base.iter().map(|b| StampedPose { t_s: b.t_s, pose: b.pose.compose(&mount) }).collect();
    let path = sensor_path(&scans, ms).unwrap();
    let (mut lidar, mut exact) = (0.0, 0.0);
    for seg in &path.segments {
        let (l, e) = window_travel(seg, &truth, 1.0);
        (lidar, exact) = (lidar + l, exact + e);
    }
    eprintln!(
        "{model}: {:.1} % of beams empty; {} matched, {} rejected {:?}, {} segments, {} fallbacks; lidar {lidar:.3} \
         m, truth {exact:.3} m: {:+.3} %",
        100.0 * empty,
        path.matched,
        path.rejected,
        path.rejected_why,
        path.segments.len(),
        path.keyframe_fallbacks,
        100.0 * (lidar / exact - 1.0)
    );
    lidar / exact
}

/// 40 s on the loop (15 m), the lidar 0.15 m ahead as on the URG-04LX rover. Measured (seeds 1, 2): ideal
/// −0.02 %; URG-04LX −0.14 %, −0.37 % (53 % of the beams empty; 34 and 39 of 399 matches ill-conditioned
/// where the 240° view meets one wall, so 3–4 segments); RPLidar −0.07 %, −0.05 % (31 % empty). The
/// remaining error is a shortening: with twice the URG's range noise (1.2 cm more at 5 m), −0.8 % to
/// −1.1 %, around the ill-conditioned stretches.
#[test]
fn realistic_lidars_measure_the_path_length_within_half_a_per_cent() {
    let mount = Pose2::new(0.15, 0.0, 0.0);
    assert!((length_ratio(LidarModel::Ideal, mount, 40.0, 1) - 1.0).abs() < 0.001);
    for model in [LidarModel::Urg04lx, LidarModel::Rplidar] {
        for seed in [1, 2] {
            let r = length_ratio(model, mount, 40.0, seed);
            assert!((r - 1.0).abs() < 0.005, "{model:?}, seed {seed}: {r}");
        }
    }
}
