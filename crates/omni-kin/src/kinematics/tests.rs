use super::*;
use crate::Model;
use approx::assert_relative_eq;
use std::f64::consts::PI;

fn models() -> Vec<Kinematics> {
    vec![
        Kinematics::Ik(MatrixKinematics::new(IkMatrix::paper_design())),
        Kinematics::Geometry(GeometryKinematics { design: RobotGeometry::apr02() }),
        Kinematics::Geometry(GeometryKinematics { design: RobotGeometry::omni_regular(4, 0.05, 0.25, 0.3) }),
        Kinematics::Geometry(GeometryKinematics { design: RobotGeometry::omni_regular(6, 0.05, 0.3, 0.1) }),
        Kinematics::Geometry(GeometryKinematics { design: RobotGeometry::mecanum4(0.05, 0.2, 0.15) }),
        Kinematics::Ik(MatrixKinematics::new(
            RobotGeometry::omni_regular(6, 0.05, 0.3, 0.1).twist_from_wheels().unwrap(),
        )),
        Kinematics::Diff(DiffKinematics::new(super::robot_type_tests::diff_left_first(0.041, 0.043, 0.21)).unwrap()),
        Kinematics::Mecanum(MecanumKinematics::new(RobotGeometry::mecanum4(0.05, 0.2, 0.15)).unwrap()),
        Kinematics::Skid(SkidKinematics::new(RobotGeometry::skid4(0.165, 0.256, 0.2775)).unwrap()),
    ]
}

fn nominal(k: &Kinematics) -> Vec<f64> {
    k.params().iter().map(|s| s.null).collect()
}

/// A parameter vector a few per cent off the design, different for every entry.
fn perturbed(k: &Kinematics) -> Vec<f64> {
    nominal(k).iter().enumerate().map(|(i, v)| v * (1.0 + 0.03 * ((i as f64) * 1.7).sin())).collect()
}

#[test]
fn specs_agree_with_the_model() {
    for k in models() {
        let specs = k.params();
        assert_eq!(specs.len(), k.n_params(), "{}", k.id());
        assert_eq!(k.wheel_names().len(), k.n_wheels());
        assert_eq!(k.param_scales(&nominal(&k)).len(), k.n_params());
        let names: std::collections::HashSet<&str> = specs.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names.len(), specs.len(), "names are unique");
        for s in &specs {
            assert!(s.lower <= s.null && s.null <= s.upper, "{}: {} ∉ [{}, {}]", s.name, s.null, s.lower, s.upper);
        }
        let m = k.twist_from_wheels(&nominal(&k)).unwrap();
        assert_eq!(m.n_wheels(), k.n_wheels());
    }
    let ik = &models()[0];
    let names: Vec<String> = ik.params().into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["m11", "m12", "m13", "m21", "m22", "m23", "m31", "m32", "m33"]);
    let geo = &models()[1];
    let names: Vec<String> = geo.params().into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["r_a", "r_b", "r_c", "R_a", "R_b", "R_c", "delta_a", "delta_b", "delta_c"]);
    assert_eq!(geo.params()[6].unit, "rad");
    assert_eq!(ik.params()[6].unit, "rad");
    assert_eq!(ik.params()[3].unit, "m");
}

#[test]
fn derivative_matches_finite_differences() {
    for k in models() {
        let p = perturbed(&k);
        let j = k.twist_from_wheels_jacobian(&p).unwrap();
        assert_eq!((j.nrows(), j.ncols()), (3 * k.n_wheels(), k.n_params()));
        // An independent, coarser central difference (Richardson-extrapolated): agrees to ~1e-7 relative.
        let entries = |q: &[f64]| k.twist_from_wheels(q).unwrap().entries().to_vec();
        let scale = j.abs().max();
        for c in 0..k.n_params() {
            let d = |h: f64| -> Vec<f64> {
                let (mut a, mut b) = (p.clone(), p.clone());
                a[c] += h;
                b[c] -= h;
                entries(&a).iter().zip(entries(&b)).map(|(x, y)| (x - y) / (2.0 * h)).collect()
            };
            let h = 1e-4 * p[c].abs().max(1e-2);
            let (d1, d2) = (d(h), d(h / 2.0));
            for r in 0..3 * k.n_wheels() {
                let rich = (4.0 * d2[r] - d1[r]) / 3.0;
                assert!(
                    (j[(r, c)] - rich).abs() <= 1e-6 * scale,
                    "{} d entry {r} / d param {c}: {} vs {rich}",
                    k.id(),
                    j[(r, c)]
                );
            }
        }
        if k.params_are_ik_entries() {
            assert_eq!(j, DMatrix::identity(k.n_params(), k.n_params()));
        }
    }
}

#[test]
fn records_round_trip_exactly() {
    for k in models() {
        let p = perturbed(&k);
        let rec = k.record(&p).unwrap();
        let (back, q) = Kinematics::from_record(k.kind(), &rec).unwrap();
        assert_eq!(back, k, "{}", k.id());
        assert_eq!(
            q.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            p.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(back.record(&q).unwrap(), rec);
        assert_eq!(rec.wheel_names, k.wheel_names());
    }
}

/// The wheel-based models (geometry, diff, mecanum) share one record: the fitted wheels under `wheels`,
/// the design's under `design_wheels`, the design's names, no matrix. (A skid-steer model's parameters
/// are no wheels: its record is the design's wheels and `[skid]`, tested in `skid_model.rs`.)
#[test]
fn wheel_models_record_fitted_and_design_wheels_apart() {
    for k in models().into_iter().filter(|k| !matches!(k.kind(), KinematicsKind::Ik | KinematicsKind::Skid)) {
        let p = perturbed(&k);
        let rec = k.record(&p).unwrap();
        let design = k.record(&nominal(&k)).unwrap();
        assert_eq!((rec.matrix.as_ref(), rec.design_matrix.as_ref()), (None, None), "{}", k.id());
        assert_eq!(rec.design_wheels, design.wheels, "{}", k.id());
        assert_ne!(rec.wheels, rec.design_wheels, "{}: the fitted wheels are the perturbed ones", k.id());
        assert_eq!(
            rec,
            BaseRecord::of_wheels(&k.geometry_at(&nominal(&k)).unwrap().unwrap(), k.geometry_at(&p).unwrap().unwrap())
        );
    }
}

#[test]
fn record_errors_name_the_key() {
    let text = |k: KinematicsKind, r: &BaseRecord| Kinematics::from_record(k, r).unwrap_err().to_string();
    let empty = BaseRecord::default();
    assert_eq!(text(KinematicsKind::Ik, &empty), "kinematics = \"ik\" needs `matrix`");
    assert_eq!(text(KinematicsKind::Geometry, &empty), "kinematics = \"geometry\" needs `[[wheels]]`");
    let ik = models()[0].record(&nominal(&models()[0])).unwrap();
    let two = BaseRecord { design_matrix: Some(vec![vec![1.0, 2.0]; 3]), ..ik.clone() };
    assert_eq!(text(KinematicsKind::Ik, &two), "design_matrix and matrix have different wheel counts");
    let bad = BaseRecord { matrix: Some(vec![vec![1.0]; 2]), ..ik };
    assert_eq!(text(KinematicsKind::Ik, &bad), "matrix: IK matrix rows has 2 entries, expected 3");
    let geo = models()[1].record(&nominal(&models()[1])).unwrap();
    let mut wheels = geo.wheels.clone().unwrap();
    wheels[1].radius_m = 0.0;
    let bad = BaseRecord { wheels: Some(wheels), ..geo };
    assert_eq!(text(KinematicsKind::Geometry, &bad), "wheels: wheel 1: radius_m = 0 is not valid (must be > 0)");
}

#[test]
fn kind_ids_parse_and_print() {
    for kind in KinematicsKind::ALL {
        assert_eq!(kind.id().parse::<KinematicsKind>(), Ok(kind));
        assert_eq!(kind.to_string(), kind.id());
    }
    for k in models() {
        assert_eq!(k.id(), k.kind().id());
    }
    let err = "tricycle".parse::<KinematicsKind>().unwrap_err();
    assert_eq!(err.to_string(), "\"tricycle\": expected \"ik\", \"geometry\", \"diff\", \"mecanum\" or \"skid\"");
}

#[test]
fn design_models() {
    let robot = RobotGeometry::mecanum4(0.05, 0.2, 0.15);
    let ik = Kinematics::design(KinematicsKind::Ik, None).unwrap();
    assert_eq!(nominal(&ik), IkMatrix::paper_design().entries());
    let ik = Kinematics::design(KinematicsKind::Ik, Some(&robot)).unwrap();
    assert_eq!(nominal(&ik), robot.twist_from_wheels().unwrap().entries());
    let geo = Kinematics::design(KinematicsKind::Geometry, None).unwrap();
    assert_eq!(geo.geometry_at(&nominal(&geo)).unwrap().unwrap(), RobotGeometry::apr02());
    let geo = Kinematics::design(KinematicsKind::Geometry, Some(&robot)).unwrap();
    assert_eq!(geo.n_wheels(), 4);
    assert!(ik.geometry_at(&nominal(&ik)).is_none());
    assert_eq!((ik.noun(), geo.noun()), ("matrix", "geometry"));
    assert_relative_eq!(models()[1].lever_arm_m(), 0.195, epsilon = 1e-15);
    assert_eq!(ik.lever_arm_m(), DEFAULT_LEVER_ARM_M);
}

/// The geometry model's IK matrix for N evenly spaced omni wheels recovers any twist from consistent wheel
/// speeds; two omni wheels cannot span the plane and are rejected with their rank.
#[test]
fn geometry_ik_for_2_3_4_6_wheels() {
    for n in [3, 4, 6] {
        let k =
            Kinematics::Geometry(GeometryKinematics { design: RobotGeometry::omni_regular(n, 0.05, 0.25, PI / 7.0) });
        let p = perturbed(&k);
        let g = k.geometry_at(&p).unwrap().unwrap();
        let m = k.twist_from_wheels(&p).unwrap();
        assert_eq!((m.n_wheels(), g.rank()), (n, 3));
        let fk = g.wheels_from_twist();
        let twist = [0.3, -0.2, 0.7];
        let w: Vec<f64> = (0..n).map(|i| (0..3).map(|j| fk[(i, j)] * twist[j]).sum()).collect();
        let t = m.twist(&w);
        assert_relative_eq!(t.vx_m_s, twist[0], epsilon = 1e-12);
        assert_relative_eq!(t.vy_m_s, twist[1], epsilon = 1e-12);
        assert_relative_eq!(t.omega_rad_s, twist[2], epsilon = 1e-12);
    }
    let two = RobotGeometry::omni_regular(2, 0.05, 0.25, 0.0);
    assert_eq!(two.rank(), 2);
    assert!(two.validate_for(2).is_ok(), "a base needing rank 2 (a differential drive) accepts it");
    let k = Kinematics::Geometry(GeometryKinematics { design: two });
    let err = k.twist_from_wheels(&nominal(&k)).unwrap_err();
    assert_eq!(err, KinError::Singular { wheels: 2, rank: 2, needed: 3 });
    assert_eq!(
        err.to_string(),
        "robot with 2 wheels cannot produce every planar twist (the wheel matrix has rank 2 < 3)"
    );
    let ik2 = Kinematics::Ik(MatrixKinematics::new(IkMatrix::new(2, vec![0.1, 0.2, 0.0, 0.0, 0.3, -0.3]).unwrap()));
    assert_eq!(ik2.twist_from_wheels(&nominal(&ik2)).unwrap().n_wheels(), 2);
}

#[test]
fn unexcited_names_the_wheel_pattern() {
    // Along m31 + m32 + m33 (scaled) the IK matrix changes only in its ω row, uniformly over the wheels:
    // the pattern is all wheels alike, which the design turns into a rotation.
    let k = &models()[0];
    let p = nominal(k);
    let scales = k.param_scales(&p);
    let mut dir = vec![0.0; 9];
    dir[6..].iter_mut().for_each(|d| *d = 1.0 / 3f64.sqrt());
    let u = k.unexcited(&p, &dir, &scales).unwrap();
    for w in &u.wheel_pattern {
        assert_relative_eq!(*w, 1.0 / 3f64.sqrt(), epsilon = 1e-9);
    }
    assert!(u.motion[2] > 0.0 && u.motion[0].abs() < 1e-9 && u.motion[1].abs() < 1e-9, "{:?}", u.motion);
}

/// The model's serde form is the old struct-variant form (`kind`, `design`), byte for byte.
#[test]
fn serde_form_is_unchanged() {
    #[derive(Serialize, Deserialize)]
    #[serde(tag = "kind", rename_all = "snake_case")]
    enum Old {
        Ik { design: IkMatrix },
        Geometry { design: RobotGeometry },
    }
    let ik = Old::Ik { design: IkMatrix::paper_design() };
    let geo = Old::Geometry { design: RobotGeometry::mecanum4(0.05, 0.2, 0.15) };
    let new_ik = Model::ik(IkMatrix::paper_design());
    let new_geo = Model::geometry(RobotGeometry::mecanum4(0.05, 0.2, 0.15));
    assert_eq!(json(&new_ik.kinematics), json(&ik));
    assert_eq!(json(&new_geo.kinematics), json(&geo));
    // Read back (serde_json's float parsing may move the last bit, the same for both shapes).
    for text in [json(&ik), json(&geo)] {
        let new: Kinematics = serde_json::from_str(&text).unwrap();
        let old: Old = serde_json::from_str(&text).unwrap();
        assert_eq!(json(&new), json(&old));
    }
    let text = serde_json::to_string(&new_ik).unwrap();
    assert!(
        text.starts_with(r#"{"kinematics":{"kind":"ik","design":{"n_wheels":3,"entries":[-0.0854478398400646,"#),
        "{text}"
    );
}

fn json<T: Serialize>(v: &T) -> String {
    serde_json::to_string(v).unwrap()
}
