//! Scan matching speed (issues 28 and 43): the sensor path of a 10-minute recording of a 10 Hz, 720-beam
//! lidar (6000 scans) in the simulated `room`, the robot on a Lissajous loop (up to 0.36 m/s, turning as it
//! goes), the lidar mounted at (0.2 m, 0, 5°): an ideal scanner, and one whose scans come out as an
//! RPLidar A2's (`LidarModel::Rplidar`: 720 beams, noise growing with range, dropouts, mixed pixels, a
//! sweep). Target: ≤ 5 s on 2 cores, 2 threads measurably faster than 1. Run with
//! `cargo bench --bench scan_matching`; prints scans/s on 2 threads and on 1 for each recording, and the
//! speed-up. Figures go to benches/README.md.
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use omnical::kin::lidar::{LidarModel, MatchSettings, Room, Scan, ScanSettings, sensor_path, simulate_scans};
use omnical::kin::{Pose2, StampedPose};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Scans per second of the recording. Hz.
const RATE_HZ: f64 = 10.0;
/// Scans in 10 minutes at 10 Hz.
const SCANS: usize = 6000;

/// The base on x = 2 sin(0.1 t), y = 1.5 sin(0.2 t) (m), heading along its motion.
fn loop_poses() -> Vec<StampedPose> {
    (0..SCANS)
        .map(|k| {
            let t = k as f64 / RATE_HZ;
            let (x, y) = (2.0 * (0.1 * t).sin(), 1.5 * (0.2 * t).sin());
            let (vx, vy) = (0.2 * (0.1 * t).cos(), 0.3 * (0.2 * t).cos());
            StampedPose { t_s: t, pose: Pose2::new(x, y, vy.atan2(vx)) }
        })
        .collect()
}

/// The recording by a scanner with `settings`.
fn recording(settings: &ScanSettings) -> Vec<Scan> {
    let Some(room) = Room::builtin("room") else { return Vec::new() };
    let mount = Pose2::new(0.2, 0.0, 5f64.to_radians());
    simulate_scans(&room, &loop_poses(), &mount, settings, 1, 0)
}

/// Matches the recording once on `threads` threads, prints the figure and returns the wall time (s).
fn report(name: &str, scans: &[Scan], threads: usize) -> f64 {
    let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else { return f64::NAN };
    let started = Instant::now();
    let path = pool.install(|| sensor_path(scans, &MatchSettings::default()));
    let s = started.elapsed().as_secs_f64();
    if let Ok(p) = path {
        println!(
            "scan matching, {name}, {threads} thread(s): {} scans in {s:.2} s = {:.0} scans/s ({} accepted, {} \
             rejected, {} segment(s), {} keyframe fallbacks, {} de-skewed)",
            scans.len(),
            scans.len() as f64 / s,
            p.matched,
            p.rejected,
            p.segments.len(),
            p.keyframe_fallbacks,
            p.deskewed
        );
    }
    s
}

/// Prints 2 threads against 1 for a recording (each the best of three runs).
fn speed_up(name: &str, scans: &[Scan]) {
    let best = |threads: usize| (0..3).map(|_| report(name, scans, threads)).fold(f64::INFINITY, f64::min);
    let (two, one) = (best(2), best(1));
    println!("scan matching, {name}: best of 3, 2 threads {two:.2} s, 1 thread {one:.2} s: {:.2}× faster", one / two);
}

fn benches(c: &mut Criterion) {
    let realistic = recording(&ScanSettings::of_model(LidarModel::Rplidar));
    speed_up("RPLidar-like (sweep, dropouts, mixed pixels)", &realistic);
    let scans = recording(&ScanSettings::default());
    speed_up("ideal", &scans);
    let mut g = c.benchmark_group("scan matching");
    g.throughput(Throughput::Elements(scans.len() as u64));
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(30));
    g.bench_function("sensor path, 6000 scans of 720 beams", |b| {
        b.iter(|| black_box(sensor_path(&scans, &MatchSettings::default())))
    });
    g.bench_function("sensor path, 6000 RPLidar-like scans", |b| {
        b.iter(|| black_box(sensor_path(&realistic, &MatchSettings::default())))
    });
    g.finish();
}

criterion_group!(scan_matching, benches);
criterion_main!(scan_matching);
