#![allow(clippy::unwrap_used)]
use super::*;
use approx::assert_relative_eq;

fn omni_wheel(joint: &str, distance_m: f64, angle_deg: f64, radius_m: f64) -> WheelSpec {
    WheelSpec {
        joint: joint.into(),
        distance_m: Some(distance_m),
        angle_deg: Some(angle_deg),
        radius_m,
        ..WheelSpec::default()
    }
}

fn xy_wheel(joint: &str, x_m: f64, y_m: f64, radius_m: f64, roller_deg: f64) -> WheelSpec {
    WheelSpec {
        joint: joint.into(),
        x_m: Some(x_m),
        y_m: Some(y_m),
        radius_m,
        roller_angle_deg: Some(roller_deg),
        ..WheelSpec::default()
    }
}

fn base(kind: BaseKind, wheels: Vec<WheelSpec>) -> RobotDescription {
    RobotDescription {
        name: None,
        kind,
        wheels,
        diff: None,
        topics: Topics::default(),
        frames: Frames::default(),
        ground_truth: None,
        priors: None,
        wheel_data: Default::default(),
    }
}

fn diff(separation_m: f64, left_m: f64, right_m: f64) -> RobotDescription {
    RobotDescription {
        diff: Some(DiffSpec {
            wheel_separation_m: separation_m,
            left_joint: "left".into(),
            right_joint: "right".into(),
            left_radius_m: left_m,
            right_radius_m: right_m,
        }),
        ..base(BaseKind::Diff, vec![])
    }
}

fn assert_ik_close(a: &IkMatrix, b: &IkMatrix, tol: f64) {
    assert_eq!(a.n_wheels(), b.n_wheels());
    for (i, (x, y)) in a.entries().iter().zip(b.entries()).enumerate() {
        assert!((x - y).abs() < tol, "entry {i}: {x} vs {y}");
    }
}

#[test]
fn apr02_gives_the_papers_eq7_exactly() {
    let d = RobotDescription::apr02();
    assert_eq!(d.design_ik().unwrap(), IkMatrix::paper_design());
    // The conversion itself, without the recognition of APR-02, already agrees to 1e-12.
    let computed = d.unchecked_geometry().unwrap().twist_from_wheels().unwrap();
    assert_ik_close(&computed, &IkMatrix::paper_design(), 1e-12);
    // And the geometry is the built-in one, bit for bit, with the description's joints.
    assert_eq!(d.to_geometry().unwrap(), RobotGeometry::apr02());
    assert_eq!(d.joints(), ["wheel_a", "wheel_b", "wheel_c"]);
}

#[test]
fn apr02_in_cartesian_form_and_explicit_drive_is_the_same_robot() {
    let wheels = [60.0f64, 180.0, 300.0]
        .iter()
        .zip(["front_left", "back", "front_right"])
        .map(|(&a, j)| WheelSpec {
            joint: j.into(),
            x_m: Some(0.195 * a.to_radians().cos()),
            y_m: Some(0.195 * a.to_radians().sin()),
            drive_deg: Some(a + 90.0),
            radius_m: 0.148,
            ..WheelSpec::default()
        })
        .collect();
    let d = base(BaseKind::Omni, wheels);
    let computed = d.unchecked_geometry().unwrap().twist_from_wheels().unwrap();
    assert_ik_close(&computed, &IkMatrix::paper_design(), 1e-12);
    // The same robot, but its angles are written differently (−60° for 300°), so its geometry is kept as
    // written rather than replaced by the built-in one (a geometry fit searches around these values).
    let g = d.to_geometry().unwrap();
    assert_relative_eq!(g.wheels[2].angle_rad, -60f64.to_radians(), epsilon = 1e-15);
    assert_eq!(g.wheel_names, ["front_left", "back", "front_right"]);
    // A robot 1 mm larger is not APR-02.
    let mut bigger = RobotDescription::apr02();
    bigger.wheels[1].distance_m = Some(0.196);
    let ik = bigger.design_ik().unwrap();
    assert!((ik.get(2, 0) - IkMatrix::paper_design().get(2, 0)).abs() > 1e-4);
}

#[test]
fn mecanum_matches_the_textbook_and_the_builtin() {
    let (r, lx, ly) = (0.05, 0.2, 0.15);
    let d = base(
        BaseKind::Mecanum,
        vec![
            xy_wheel("fl", lx, ly, r, -45.0),
            xy_wheel("fr", lx, -ly, r, 45.0),
            xy_wheel("rl", -lx, ly, r, 45.0),
            xy_wheel("rr", -lx, -ly, r, -45.0),
        ],
    );
    let m = d.wheels_from_twist().unwrap();
    let expect = [[1.0, -1.0, -(lx + ly)], [1.0, 1.0, lx + ly], [1.0, 1.0, -(lx + ly)], [1.0, -1.0, lx + ly]];
    for (i, row) in expect.iter().enumerate() {
        for j in 0..3 {
            assert_relative_eq!(m[(i, j)], row[j] / r, epsilon = 1e-12);
        }
    }
    assert_ik_close(&d.design_ik().unwrap(), &RobotGeometry::mecanum4(r, lx, ly).twist_from_wheels().unwrap(), 1e-12);
}

#[test]
fn four_wheel_omni_inverts_its_forward_matrix() {
    // An X-layout four-wheel omni base: wheels at 45°, 135°, 225°, 315°, 0.2 m out, r = 0.04 m.
    let d = base(
        BaseKind::Omni,
        [45.0, 135.0, 225.0, 315.0]
            .iter()
            .enumerate()
            .map(|(i, &a)| omni_wheel(&format!("w{i}"), 0.2, a, 0.04))
            .collect(),
    );
    let ik = d.design_ik().unwrap();
    assert_eq!(ik.n_wheels(), 4);
    // Wheel 0 at 45° pushes along 135°: (−√½, √½) per unit rim speed; the ω column is R/r.
    let m = d.wheels_from_twist().unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert_relative_eq!(m[(0, 0)], -h / 0.04, epsilon = 1e-12);
    assert_relative_eq!(m[(0, 1)], h / 0.04, epsilon = 1e-12);
    assert_relative_eq!(m[(0, 2)], 0.2 / 0.04, epsilon = 1e-12);
    let twist = [0.3, -0.2, 0.7];
    let w: Vec<f64> = (0..4).map(|i| (0..3).map(|j| m[(i, j)] * twist[j]).sum()).collect();
    let t = ik.twist(&w);
    assert_relative_eq!(t.vx_m_s, 0.3, epsilon = 1e-12);
    assert_relative_eq!(t.vy_m_s, -0.2, epsilon = 1e-12);
    assert_relative_eq!(t.omega_rad_s, 0.7, epsilon = 1e-12);
}

#[test]
fn diff_drive_closed_form() {
    let d = diff(0.3, 0.05, 0.052);
    assert_eq!(d.joints(), ["left", "right"]);
    let ik = d.design_ik().unwrap();
    assert_eq!(ik.rows(), vec![vec![0.025, 0.026], vec![0.0, 0.0], vec![-0.05 / 0.3, 0.052 / 0.3]]);
    // Forward rows: left r_l ω_l = vx − ω s/2, right r_r ω_r = vx + ω s/2, no vy.
    let m = d.wheels_from_twist().unwrap();
    assert_relative_eq!(m[(0, 0)], 1.0 / 0.05, epsilon = 1e-12);
    assert_relative_eq!(m[(0, 1)], 0.0, epsilon = 1e-12);
    assert_relative_eq!(m[(0, 2)], -0.15 / 0.05, epsilon = 1e-12);
    assert_relative_eq!(m[(1, 2)], 0.15 / 0.052, epsilon = 1e-12);
    // IK after FK is the identity on (vx, ω).
    for twist in [[0.4, 0.0, 0.0], [0.0, 0.0, 1.0], [0.2, 0.0, -0.5]] {
        let w: Vec<f64> = (0..2).map(|i| (0..3).map(|j| m[(i, j)] * twist[j]).sum()).collect();
        let t = ik.twist(&w);
        assert_relative_eq!(t.vx_m_s, twist[0], epsilon = 1e-12);
        assert_relative_eq!(t.vy_m_s, 0.0, epsilon = 1e-12);
        assert_relative_eq!(t.omega_rad_s, twist[2], epsilon = 1e-12);
    }
    let g = d.to_geometry().unwrap();
    assert_eq!(g.rank(), 2);
    assert_eq!(g.wheel_names, ["left", "right"]);
    assert_eq!((g.wheels[0].distance_m, g.wheels[1].radius_m), (0.15, 0.052));
}

fn problem(d: &RobotDescription) -> (String, String) {
    let e = d.validate().unwrap_err();
    (e.field.clone(), e.to_string())
}

#[test]
fn wrong_wheel_counts_and_layouts() {
    let two = base(BaseKind::Omni, vec![omni_wheel("a", 0.2, 0.0, 0.05), omni_wheel("b", 0.2, 180.0, 0.05)]);
    assert_eq!(
        problem(&two),
        (
            "wheels".into(),
            "wheels: a omni base needs at least 3 (2 wheels on one axle: kind = \"diff\") wheels, this one has 2"
                .into()
        )
    );
    let mut three = RobotDescription::apr02();
    three.kind = BaseKind::Mecanum;
    assert_eq!(problem(&three).1, "wheels: a mecanum base needs exactly 4 wheels, this one has 3");
    let mut d = diff(0.3, 0.05, 0.05);
    d.wheels = RobotDescription::apr02().wheels;
    assert_eq!(problem(&d).1, "wheels: a diff base takes [diff], not [[wheels]]");
    assert_eq!(problem(&base(BaseKind::Diff, vec![])).0, "diff");
    let mut omni_with_axle = RobotDescription::apr02();
    omni_with_axle.diff = diff(0.3, 0.05, 0.05).diff;
    assert_eq!(problem(&omni_with_axle).1, "diff: [diff] is only for kind = \"diff\"");
}

#[test]
fn duplicate_and_empty_joints() {
    let mut d = RobotDescription::apr02();
    d.wheels[2].joint = "wheel_a".into();
    assert_eq!(
        problem(&d),
        (
            "wheels[2].joint".into(),
            "wheels[2].joint: joint \"wheel_a\" is also the joint of wheels[0]; each wheel needs its own joint".into()
        )
    );
    d.wheels[2].joint = " ".into();
    assert_eq!(problem(&d).1, "wheels[2].joint: the joint name is empty");
    let mut d = diff(0.3, 0.05, 0.05);
    if let Some(x) = d.diff.as_mut() {
        x.right_joint = "left".into();
    }
    assert_eq!(problem(&d).0, "diff.right_joint");
}

#[test]
fn bad_values() {
    let mut d = RobotDescription::apr02();
    d.wheels[1].radius_m = 0.0;
    assert_eq!(problem(&d).1, "wheels[1].radius_m: 0 must be > 0");
    d.wheels[1].radius_m = -0.1;
    assert_eq!(problem(&d).1, "wheels[1].radius_m: -0.1 must be > 0");
    d.wheels[1].radius_m = f64::NAN;
    assert_eq!(problem(&d).1, "wheels[1].radius_m: NaN is not a finite number");
    let mut d = RobotDescription::apr02();
    d.wheels[0].distance_m = Some(-0.2);
    assert_eq!(problem(&d).1, "wheels[0].distance_m: -0.2 must be ≥ 0");
    let mut d = RobotDescription::apr02();
    d.wheels[0].x_m = Some(0.1);
    assert_eq!(problem(&d).0, "wheels[0]");
    d.wheels[0] = WheelSpec { joint: "a".into(), radius_m: 0.1, ..WheelSpec::default() };
    assert_eq!(
        problem(&d).1,
        "wheels[0]: give the position as x_m and y_m, or as distance_m and angle_deg (neither is given)"
    );
    let mut d = diff(0.0, 0.05, 0.05);
    assert_eq!(problem(&d).1, "diff.wheel_separation_m: 0 must be > 0");
    d = diff(0.3, 0.05, -0.05);
    assert_eq!(problem(&d).0, "diff.right_radius_m");
    let mut d = RobotDescription::apr02();
    d.priors = Some(Priors { angle_std_deg: Some(-1.0), ..Priors::default() });
    assert_eq!(problem(&d).1, "priors.angle_std_deg: -1 must be > 0");
}

#[test]
fn rollers() {
    let mut d = base(
        BaseKind::Mecanum,
        vec![
            xy_wheel("fl", 0.2, 0.15, 0.05, -45.0),
            xy_wheel("fr", 0.2, -0.15, 0.05, 45.0),
            xy_wheel("rl", -0.2, 0.15, 0.05, 45.0),
            xy_wheel("rr", -0.2, -0.15, 0.05, 30.0),
        ],
    );
    assert_eq!(problem(&d).1, "wheels[3].roller_angle_deg: 30° is not a mecanum roller angle (±45)");
    d.wheels[3].roller_angle_deg = None;
    assert_eq!(problem(&d).1, "wheels[3].roller_angle_deg: 0° is not a mecanum roller angle (±45)");
    let mut o = RobotDescription::apr02();
    o.wheels[0].roller_angle_deg = Some(85.0);
    assert_eq!(problem(&o).0, "wheels[0].roller_angle_deg");
}

#[test]
fn collinear_wheels_are_refused() {
    // Three wheels on one line, all driving along it: no sideways motion, no rotation about their line.
    let d = base(
        BaseKind::Omni,
        (0..3)
            .map(|i| WheelSpec {
                joint: format!("w{i}"),
                x_m: Some(0.1 * i as f64),
                y_m: Some(0.0),
                drive_deg: Some(0.0),
                radius_m: 0.05,
                ..WheelSpec::default()
            })
            .collect(),
    );
    let e = d.validate().unwrap_err();
    assert_eq!(e.field, "wheels");
    assert_eq!(e.problem, RobotProblem::Rank { kind: BaseKind::Omni, rank: 1, needed: 3 });
    // All four mecanum rollers the same way: vy and ω are tied (rank 2).
    let same = base(
        BaseKind::Mecanum,
        [(0.2, 0.15), (0.2, -0.15), (-0.2, 0.15), (-0.2, -0.15)]
            .iter()
            .enumerate()
            .map(|(i, &(x, y))| xy_wheel(&format!("w{i}"), x, y, 0.05, 45.0))
            .collect(),
    );
    assert_eq!(
        same.validate().unwrap_err().problem,
        RobotProblem::Rank { kind: BaseKind::Mecanum, rank: 2, needed: 3 }
    );
}
