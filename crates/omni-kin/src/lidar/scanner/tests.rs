//! Unit tests of the simulated scanner: field of view, ray cast and max range, seeded noise, the URG-04LX model's dark
//! segments and mixed pixels.

use super::*;

/// A 270° lidar of 1081 beams (a Hokuyo UTM-30LX) spans −135° to +135° inclusive, 0.25° apart, and
/// sees nothing behind it; 360° keeps the all-round layout (−180°, 0.5° apart for 720 beams).
#[test]
fn a_partial_field_of_view_spans_it_inclusive_and_sees_nothing_behind() {
    let s = ScanSettings { beams: 1081, fov_rad: 270f64.to_radians(), dropout: 0.0, ..ScanSettings::default() };
    s.check().unwrap();
    assert!((s.angle_min_rad().to_degrees() + 135.0).abs() < 1e-12);
    assert!((s.angle_increment_rad().to_degrees() - 0.25).abs() < 1e-12);
    let all = ScanSettings::default();
    assert_eq!((all.angle_min_rad(), all.angle_increment_rad()), (-PI, 2.0 * PI / 720.0));
    let room = Room::builtin("room").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let scan = simulate_scan(&room, &Pose2::IDENTITY, 0.0, &s, &mut rng);
    let p = scan.points();
    assert!(p.xy_m.len() > 1000 && p.xy_m.iter().all(|q| q[1].atan2(q[0]).abs() < 2.357), "{}", p.xy_m.len());
    for fov_deg in [0.0, 361.0, f64::NAN] {
        assert!(ScanSettings { fov_rad: fov_deg.to_radians(), ..all.clone() }.check().is_err(), "{fov_deg}");
    }
}

#[test]
fn noise_free_scan_matches_the_ray_cast_and_the_max_range() {
    let room = Room::builtin("corridor").unwrap();
    let settings = ScanSettings { range_noise_m: 0.0, dropout: 0.0, ..ScanSettings::default() };
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let scan = simulate_scan(&room, &Pose2::new(0.0, 0.5, 0.0), 0.0, &settings, &mut rng);
    // Beam 360 looks along +x: the far end is 20 m away, beyond 12 m: no return.
    assert_eq!(scan.ranges_m[360], f32::INFINITY);
    // Beam 540 looks along +y (90°): the wall at y = 2.5, 2 m away; beam 180 along −y: 3 m.
    assert!((f64::from(scan.ranges_m[540]) - 2.0).abs() < 1e-6);
    assert!((f64::from(scan.ranges_m[180]) - 3.0).abs() < 1e-6);
}

#[test]
fn same_seed_same_scan_and_noise_has_its_sigma() {
    let room = Room::builtin("room").unwrap();
    let s = ScanSettings::default();
    let pose = Pose2::new(0.3, -0.2, 0.4);
    let a = simulate_scan(&room, &pose, 0.0, &s, &mut ChaCha8Rng::seed_from_u64(9));
    let b = simulate_scan(&room, &pose, 0.0, &s, &mut ChaCha8Rng::seed_from_u64(9));
    assert_eq!(format!("{:?}", a.ranges_m), format!("{:?}", b.ranges_m));
    let exact = simulate_scan(
        &room,
        &pose,
        0.0,
        &ScanSettings { range_noise_m: 0.0, dropout: 0.0, ..s.clone() },
        &mut ChaCha8Rng::seed_from_u64(9),
    );
    let d: Vec<f64> = a
        .ranges_m
        .iter()
        .zip(&exact.ranges_m)
        .filter(|(r, _)| r.is_finite())
        .map(|(r, e)| f64::from(*r) - f64::from(*e))
        .collect();
    let sigma = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    assert!((sigma - 0.01).abs() < 0.001, "sigma {sigma}");
    let dropped = a.ranges_m.iter().filter(|r| r.is_nan()).count();
    assert!((1..=20).contains(&dropped), "{dropped} dropouts of 720");
}

/// A URG-04LX's scan in the room: about half its beams empty, written as 0; with its noise off, the
/// mixed pixels lie between the surfaces either side of a depth jump, beams the ideal scanner reads on
/// one surface or the other.
#[test]
fn a_urg04lx_scan_is_half_empty_and_has_mixed_pixels_at_edges() {
    let room = Room::builtin("room").unwrap();
    let urg = ScanSettings::of_model(LidarModel::Urg04lx);
    urg.check().unwrap();
    assert!((urg.time_increment_s() - 0.1 / 1024.0).abs() < 1e-15);
    let pose = Pose2::new(0.5, -0.8, 2.0);
    let (mut empty, mut beams) = (0, 0);
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for k in 0..20 {
        let scan = simulate_scan(&room, &pose, 0.1 * k as f64, &urg, &mut rng);
        assert!(scan.ranges_m.iter().all(|r| r.is_finite() && *r >= 0.0));
        empty += scan.ranges_m.iter().filter(|&&r| r == 0.0).count();
        beams += scan.ranges_m.len();
    }
    assert!((0.4..0.65).contains(&(empty as f64 / beams as f64)), "{empty} of {beams} empty");
    let exact = ScanSettings {
        range_noise_m: 0.0,
        range_noise_per_m: 0.0,
        dropout: 0.0,
        dark_dropout: 0.0,
        sweeping: false,
        ..urg.clone()
    };
    let mixed = simulate_scan(&room, &pose, 0.0, &exact, &mut ChaCha8Rng::seed_from_u64(4));
    let clean = simulate_scan(&room, &pose, 0.0, &ScanSettings { mixed_pixels: false, ..exact }, &mut rng);
    let between: Vec<usize> = (1..681)
        // Beams whose footprint meets a surface beyond the range read 0 (no return): left out.
        .filter(|&i| [mixed.ranges_m[i], clean.ranges_m[i - 1], clean.ranges_m[i + 1]].iter().all(|&r| r > 0.0))
        .filter(|&i| (mixed.ranges_m[i] - clean.ranges_m[i]).abs() > 0.01)
        .inspect(|&i| {
            let (a, b) =
                (clean.ranges_m[i - 1].min(clean.ranges_m[i + 1]), clean.ranges_m[i - 1].max(clean.ranges_m[i + 1]));
            assert!(
                a < mixed.ranges_m[i] && mixed.ranges_m[i] < b,
                "beam {i}: {} not within {a}..{b}",
                mixed.ranges_m[i]
            );
        })
        .collect();
    assert!(!between.is_empty(), "no mixed pixel");
}
