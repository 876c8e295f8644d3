//! The robot-type models (`diff`, `mecanum`): design matrices against closed forms, exact derivatives,
//! model-file records, refusals.
#![allow(clippy::unwrap_used)]

use super::*;
use approx::assert_relative_eq;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// A differential drive as robot.toml describes one: left wheel first, at +y.
pub(super) fn diff_left_first(r_left: f64, r_right: f64, b: f64) -> RobotGeometry {
    let wheel = |r, angle, offset| Wheel {
        radius_m: r,
        distance_m: b / 2.0,
        angle_rad: angle,
        drive_offset_rad: offset,
        roller_angle_rad: 0.0,
    };
    RobotGeometry {
        wheel_names: vec!["left".into(), "right".into()],
        wheels: vec![wheel(r_left, FRAC_PI_2, PI), wheel(r_right, -FRAC_PI_2, 0.0)],
    }
}

#[test]
fn diff_matrix_is_the_closed_form_in_either_column_order() {
    let (rl, rr, b) = (0.041, 0.043, 0.21);
    let k = DiffKinematics::design_for(Some(&diff_left_first(rl, rr, b))).unwrap();
    let names: Vec<String> = k.params().into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["r_right", "r_left", "b"]);
    let p: Vec<f64> = k.params().iter().map(|s| s.null).collect();
    assert_eq!(p, [rr, rl, b]);
    let m = k.twist_from_wheels(&p).unwrap();
    let want = [rl / 2.0, rr / 2.0, 0.0, 0.0, -rl / b, rr / b];
    for (got, want) in m.entries().iter().zip(want) {
        assert_relative_eq!(*got, want, epsilon = 1e-15);
    }
    // A wheel that drives backward at positive speed flips its column.
    let mut g = diff_left_first(rl, rr, b);
    g.wheels[0].drive_offset_rad = 0.0;
    let m = DiffKinematics::new(g).unwrap().twist_from_wheels(&p).unwrap();
    assert_relative_eq!(m.get(0, 0), -rl / 2.0, epsilon = 1e-15);
    assert_relative_eq!(m.get(2, 0), rl / b, epsilon = 1e-15);
    // The geometry at a parameter vector has the same matrix (the rim-speed inverse of a rank-2 base).
    let q = [0.044, 0.0405, 0.2];
    let g = k.geometry_at(&q).unwrap().unwrap();
    assert_relative_eq!(g.wheels[0].distance_m + g.wheels[1].distance_m, 0.2, epsilon = 1e-15);
    let from_geometry = g.twist_from_wheels().unwrap();
    for (a, b) in k.twist_from_wheels(&q).unwrap().entries().iter().zip(from_geometry.entries()) {
        assert_relative_eq!(*a, *b, epsilon = 1e-14);
    }
}

#[test]
fn diff_refuses_what_is_not_an_axle() {
    let msg = |g: RobotGeometry| DiffKinematics::new(g).unwrap_err().to_string();
    let mut g = diff_left_first(0.04, 0.04, 0.2);
    g.wheels[1].angle_rad = FRAC_PI_2;
    assert!(msg(g).contains("one wheel must sit on each side"), "same side");
    let mut g = diff_left_first(0.04, 0.04, 0.2);
    g.wheels[1].drive_offset_rad = 0.3;
    assert!(msg(g).contains("drive along x"), "skewed drive");
    assert!(msg(RobotGeometry::apr02()).contains("exactly two wheels"));
    assert!(DiffKinematics::design_for(None).unwrap_err().to_string().contains("needs the robot's geometry"));
    let k = DiffKinematics::new(diff_left_first(0.04, 0.04, 0.2)).unwrap();
    assert!(k.twist_from_wheels(&[0.04, -0.04, 0.2]).is_err());
}

/// A mecanum base as robot.toml describes one (wheels driving forward, rollers ±45°), slightly asymmetric.
fn mecanum() -> RobotGeometry {
    let mut g = RobotGeometry::mecanum4(0.05, 0.2, 0.15);
    g.wheels[1].radius_m = 0.051;
    g
}

#[test]
fn mecanum_matrix_is_the_textbook_form_with_per_wheel_radii() {
    let k = MecanumKinematics::design_for(Some(&mecanum())).unwrap();
    let names: Vec<String> = k.params().into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["r_a", "r_b", "r_c", "r_d", "lx", "ly"]);
    let p = [0.05, 0.051, 0.049, 0.0502, 0.21, 0.14];
    let m = k.twist_from_wheels(&p).unwrap();
    // Front-left, front-right, rear-left, rear-right; rollers ∓45°: vx = Σ r ω / 4, vy = (−a + b + c − d) / 4,
    // ω = (−a + b − c + d) / (4 (lx + ly)).
    let signs = [[1.0, 1.0, 1.0, 1.0], [-1.0, 1.0, 1.0, -1.0], [-1.0, 1.0, -1.0, 1.0]];
    let div = [4.0, 4.0, 4.0 * (0.21 + 0.14)];
    for r in 0..3 {
        for c in 0..4 {
            assert_relative_eq!(m.get(r, c), signs[r][c] * p[c] / div[r], epsilon = 1e-15);
        }
    }
    // Design values reproduce the design geometry's own matrix.
    let d: Vec<f64> = k.params().iter().map(|s| s.null).collect();
    let own = mecanum().twist_from_wheels().unwrap();
    for (a, b) in k.twist_from_wheels(&d).unwrap().entries().iter().zip(own.entries()) {
        assert_relative_eq!(*a, *b, epsilon = 1e-15);
    }
    // The geometry at p: wheels on the new rectangle, still driving forward.
    let g = k.geometry_at(&p).unwrap().unwrap();
    let w = &g.wheels[3];
    assert_relative_eq!(w.distance_m * w.angle_rad.cos(), -0.21, epsilon = 1e-15);
    assert_relative_eq!(w.distance_m * w.angle_rad.sin(), -0.14, epsilon = 1e-15);
    assert_relative_eq!((w.angle_rad + FRAC_PI_2 + w.drive_offset_rad).cos(), 1.0, epsilon = 1e-15);
    for (a, b) in m.entries().iter().zip(g.twist_from_wheels().unwrap().entries()) {
        assert_relative_eq!(*a, *b, epsilon = 1e-14);
    }
}

#[test]
fn mecanum_serves_an_omni_x_and_refuses_other_layouts() {
    // Four omni wheels at 45°, 135°, 225°, 315° pushing along the tangents: a rectangle too.
    let x = RobotGeometry::omni_regular(4, 0.03, 0.2, FRAC_PI_4);
    let k = MecanumKinematics::new(x.clone()).unwrap();
    let d: Vec<f64> = k.params().iter().map(|s| s.null).collect();
    assert_relative_eq!(d[4], 0.2 * FRAC_PI_4.cos(), epsilon = 1e-15);
    for (a, b) in k.twist_from_wheels(&d).unwrap().entries().iter().zip(x.twist_from_wheels().unwrap().entries()) {
        assert_relative_eq!(*a, *b, epsilon = 1e-15);
    }
    // A regular square with wheels on the axes is not a rectangle of corners.
    let plus = RobotGeometry::omni_regular(4, 0.03, 0.2, 0.0);
    assert!(MecanumKinematics::new(plus).unwrap_err().to_string().contains("each quadrant"));
    assert!(MecanumKinematics::new(RobotGeometry::apr02()).unwrap_err().to_string().contains("four wheels"));
    assert!(MecanumKinematics::design_for(None).is_err());
}

#[test]
fn derivatives_are_exact() {
    let cases: Vec<(Box<dyn BaseKinematics>, Vec<f64>)> = vec![
        (Box::new(DiffKinematics::new(diff_left_first(0.041, 0.043, 0.21)).unwrap()), vec![0.044, 0.0405, 0.2]),
        (Box::new(MecanumKinematics::new(mecanum()).unwrap()), vec![0.05, 0.051, 0.049, 0.0502, 0.21, 0.14]),
        (
            Box::new(MecanumKinematics::new(RobotGeometry::omni_regular(4, 0.03, 0.2, 0.7)).unwrap()),
            vec![0.03, 0.031, 0.029, 0.03, 0.16, 0.13],
        ),
    ];
    for (k, p) in cases {
        let j = k.twist_from_wheels_jacobian(&p).unwrap();
        for c in 0..p.len() {
            let h = 1e-6 * p[c];
            let (mut a, mut b) = (p.clone(), p.clone());
            a[c] += h;
            b[c] -= h;
            let (ma, mb) = (k.twist_from_wheels(&a).unwrap(), k.twist_from_wheels(&b).unwrap());
            for (r, (x, y)) in ma.entries().iter().zip(mb.entries()).enumerate() {
                let fd = (x - y) / (2.0 * h);
                assert!(
                    (j[(r, c)] - fd).abs() <= 1e-7 * j.abs().max(),
                    "{} d{r}/d{c}: {} vs {fd}",
                    k.noun(),
                    j[(r, c)]
                );
            }
        }
    }
}

#[test]
fn records_round_trip_and_refuse_tampered_wheels() {
    let models = [
        (Kinematics::Diff(DiffKinematics::new(diff_left_first(0.041, 0.043, 0.21)).unwrap()), vec![0.044, 0.0405, 0.2]),
        (Kinematics::Mecanum(MecanumKinematics::new(mecanum()).unwrap()), vec![0.05, 0.051, 0.049, 0.0502, 0.21, 0.14]),
    ];
    for (k, p) in models {
        let rec = k.record(&p).unwrap();
        let (back, q) = Kinematics::from_record(k.kind(), &rec).unwrap();
        assert_eq!(back, k);
        for (a, b) in p.iter().zip(&q) {
            assert_relative_eq!(*a, *b, epsilon = 1e-15);
        }
        let mut bad = rec.clone();
        if let Some(w) = bad.wheels.as_mut() {
            w[0].roller_angle_rad += 0.1;
        }
        let e = Kinematics::from_record(k.kind(), &bad).unwrap_err().to_string();
        assert!(e.starts_with("wheels: "), "{e}");
        let mut missing = rec;
        missing.wheels = None;
        assert_eq!(
            Kinematics::from_record(k.kind(), &missing).unwrap_err().to_string(),
            format!("kinematics = \"{}\" needs `[[wheels]]`", k.id())
        );
    }
}

#[test]
fn a_zero_design_row_is_held_at_zero_by_the_matrix_model() {
    let design = DiffKinematics::new(diff_left_first(0.041, 0.043, 0.21)).unwrap();
    let d: Vec<f64> = design.params().iter().map(|s| s.null).collect();
    let k = Kinematics::Ik(MatrixKinematics::new(design.twist_from_wheels(&d).unwrap()));
    let names: Vec<String> = k.params().into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["m11", "m12", "m31", "m32"], "no vy-row parameters");
    assert!(!k.params_are_ik_entries());
    let p = [0.02, 0.0215, -0.19, 0.2];
    let m = k.twist_from_wheels(&p).unwrap();
    assert_eq!(m.entries(), [0.02, 0.0215, 0.0, 0.0, -0.19, 0.2]);
    let j = k.twist_from_wheels_jacobian(&p).unwrap();
    assert_eq!((j.nrows(), j.ncols(), j.sum()), (6, 4, 4.0));
    assert_eq!(j[(4, 2)], 1.0);
    assert!(k.twist_from_wheels(&[0.0; 6]).is_err(), "a full-length vector is refused");
    // Model files: the matrix as a whole; a non-zero entry in a zero design row is refused.
    let rec = k.record(&p).unwrap();
    assert_eq!(rec.matrix.as_ref().unwrap()[1], [0.0, 0.0]);
    let (back, q) = Kinematics::from_record(KinematicsKind::Ik, &rec).unwrap();
    assert_eq!((back, q), (k, p.to_vec()));
    let mut bad = rec;
    bad.matrix.as_mut().unwrap()[1][1] = 1e-3;
    assert_eq!(
        Kinematics::from_record(KinematicsKind::Ik, &bad).unwrap_err().to_string(),
        "matrix: entry m22: 0.001 is not zero, but its row is zero throughout design_matrix (a motion \
         the base cannot make)"
    );
}
