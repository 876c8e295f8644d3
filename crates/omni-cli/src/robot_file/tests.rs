#![allow(clippy::unwrap_used)]
use super::*;
use omni_kin::IkMatrix;

const APR02: &str = r#"name = "APR-02"
kind = "omni"

[[wheels]]
joint = "wheel_a"
distance_m = 0.195
angle_deg = 60.0
radius_m = 0.148

[[wheels]]
joint = "wheel_b"
distance_m = 0.195
angle_deg = 180.0
radius_m = 0.148

[[wheels]]
joint = "wheel_c"
distance_m = 0.195
angle_deg = 300.0
radius_m = 0.148
"#;

fn error(text: &str) -> String {
    parse(text, Path::new("robots/r.toml")).unwrap_err().to_string()
}

/// The ```toml blocks of docs/formats.md that are robot descriptions.
fn docs_examples() -> Vec<(String, String)> {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/formats.md")).unwrap();
    doc.split("```toml\n")
        .skip(1)
        .filter_map(|b| b.split("```").next())
        .filter(|b| b.starts_with("# robot.toml: "))
        .map(|b| (b.lines().next().unwrap().trim_start_matches("# robot.toml: ").to_string(), b.to_string()))
        .collect()
}

#[test]
fn docs_examples_parse() {
    let examples = docs_examples();
    let titles: Vec<&str> = examples.iter().map(|(t, _)| t.as_str()).collect();
    assert_eq!(titles, ["APR-02", "four-wheel omni", "mecanum", "differential drive", "skid-steer"]);
    let parsed: Vec<RobotDescription> =
        examples.iter().map(|(t, text)| parse(text, Path::new(t)).unwrap_or_else(|e| panic!("{e}"))).collect();
    // APR-02: exactly the paper's Eq. 7 and the built-in description's geometry.
    assert_eq!(parsed[0].design_ik().unwrap(), IkMatrix::paper_design());
    assert_eq!(parsed[0].to_geometry().unwrap(), RobotDescription::apr02().to_geometry().unwrap());
    assert_eq!(parsed[0].topics.ground_truth.as_deref(), Some("/ground_truth/pose"));
    // Four-wheel omni: a 3 × 4 matrix; wheel 0 at 45° moves the robot along 135°, and turns it by r/(4R).
    let ik = parsed[1].design_ik().unwrap();
    assert_eq!(ik.n_wheels(), 4);
    assert!((ik.get(2, 0) - 0.0508 / (4.0 * 0.21)).abs() < 1e-12, "{}", ik.get(2, 0));
    assert!((ik.get(0, 0) + 0.0508 / 2.0 * std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12, "{}", ik.get(0, 0));
    assert_eq!(parsed[1].frames.ground_truth_child.as_deref(), Some("omni4/base_link"));
    // Mecanum: vx is the mean of the four rim speeds; vy alternates in sign.
    let ik = parsed[2].design_ik().unwrap();
    for c in 0..4 {
        assert!((ik.get(0, c) - 0.05 / 4.0).abs() < 1e-12);
        assert!((ik.get(1, c).abs() - 0.05 / 4.0).abs() < 1e-12);
    }
    assert_eq!(parsed[2].joints()[3], "rear_right_wheel_joint");
    // Diff: vx = r (ω_l + ω_r)/2, vy = 0, ω = r (ω_r − ω_l)/s.
    let ik = parsed[3].design_ik().unwrap();
    assert_eq!(ik.rows(), vec![vec![0.0165, 0.0165], vec![0.0, 0.0], vec![-0.033 / 0.287, 0.033 / 0.287]]);
    // Skid-steer: the differential drive of the sides, each wheel a half of its side's rim speed.
    let ik = parsed[4].design_ik().unwrap();
    for (c, side) in [-1.0, -1.0, 1.0, 1.0].into_iter().enumerate() {
        assert!((ik.get(0, c) - 0.165 / 4.0).abs() < 1e-12 && ik.get(1, c) == 0.0);
        assert!((ik.get(2, c) - side * 0.165 / (2.0 * 0.555)).abs() < 1e-12, "{}", ik.get(2, c));
    }
    assert_eq!(parsed[3].joints(), ["wheel_left_joint", "wheel_right_joint"]);
}

#[test]
fn written_files_read_back_to_the_same_description() {
    for (title, text) in docs_examples() {
        let d = parse(&text, Path::new(&title)).unwrap();
        let comments = Comments { header: vec!["written by a test".into()], wheels: vec![vec!["first wheel".into()]] };
        let out = to_toml(&d, &comments);
        assert!(out.starts_with("# written by a test\n"), "{out}");
        assert_eq!(parse(&out, Path::new("out.toml")).unwrap(), d, "{title}:\n{out}");
    }
}

#[test]
fn syntax_and_schema_errors_name_file_line_and_field() {
    let typo = APR02.replacen("angle_deg = 180.0", "angle_deg = 180.0\nradus_m = 0.15", 1);
    let e = error(&typo);
    assert!(
        e.starts_with("robots/r.toml: line 14: wheels[1].radus_m: unknown field `radus_m`, expected one of"),
        "{e}"
    );
    let e = error(&APR02.replace("kind = \"omni\"", "kind = \"tricycle\""));
    assert_eq!(
        e,
        "robots/r.toml: line 2: kind: unknown variant `tricycle`, expected one of `omni`, `mecanum`, `diff`, `skid`"
    );
    let e = error(&format!("wheelbase = 3\n{APR02}"));
    assert!(e.starts_with("robots/r.toml: line 1: wheelbase: unknown field `wheelbase`"), "{e}");
    let e = error(
        &APR02.replace("radius_m = 0.148\n\n[[wheels]]\njoint = \"wheel_c\"", "\n[[wheels]]\njoint = \"wheel_c\""),
    );
    assert!(e.contains(": wheels[1]: missing field `radius_m`"), "{e}");
    let e = error(&APR02.replace("angle_deg = 180.0", "angle_deg = \"180\""));
    assert!(e.starts_with("robots/r.toml: line 13: wheels[1].angle_deg: invalid type: string"), "{e}");
    let e = error("kind = \"omni\"\n[[wheels]\n");
    assert_eq!(e, "robots/r.toml: not TOML: line 2, column 10: unclosed array table, expected `]`");
}

#[test]
fn bad_robots_name_file_line_and_field() {
    let e = error(&APR02.replace("joint = \"wheel_c\"", "joint = \"wheel_a\""));
    assert_eq!(
        e,
        "robots/r.toml: line 17: wheels[2].joint: joint \"wheel_a\" is also the joint of wheels[0]; each wheel needs \
         its own joint"
    );
    let e = error(&APR02.replacen("radius_m = 0.148", "radius_m = -0.1", 3).replacen(
        "radius_m = -0.1",
        "radius_m = 0.148",
        2,
    ));
    assert_eq!(e, "robots/r.toml: line 20: wheels[2].radius_m: -0.1 must be > 0");
    let e = error(&APR02.replacen("radius_m = 0.148", "radius_m = 0", 1));
    assert_eq!(e, "robots/r.toml: line 8: wheels[0].radius_m: 0 must be > 0");
    let two = APR02.split("\n[[wheels]]\njoint = \"wheel_c\"").next().unwrap();
    let e = error(two);
    assert_eq!(
        e,
        "robots/r.toml: line 4: wheels: a omni base needs at least 3 (2 wheels on one axle: kind = \"diff\") wheels, \
         this one has 2"
    );
    let e = error(&APR02.replace("kind = \"omni\"", "kind = \"mecanum\""));
    assert!(e.starts_with("robots/r.toml: line 4: wheels: a mecanum base needs exactly 4 wheels"), "{e}");
    // Collinear: every wheel on the x axis driving along it.
    let collinear =
        APR02.replace("angle_deg = 180.0", "angle_deg = 60.0").replace("angle_deg = 300.0", "angle_deg = 60.0");
    let e = error(&collinear);
    assert!(e.starts_with("robots/r.toml: line 4: wheels: the wheels can produce only 1 of the 3 independent"), "{e}");
    let diff = "kind = \"diff\"\n[diff]\nwheel_separation_m = 0.3\nleft_joint = \"l\"\nright_joint = \"l\"\n\
                left_radius_m = 0.05\nright_radius_m = 0.05\n";
    assert_eq!(
        error(diff),
        "robots/r.toml: line 5: diff.right_joint: joint \"l\" is also the joint of diff.left_joint; each wheel needs \
         its own joint"
    );
    assert_eq!(
        error("kind = \"diff\"\n"),
        "robots/r.toml: line 1: diff: a diff base needs a [diff] table (wheel_separation_m, …)"
    );
}

#[test]
fn builtin_files_and_discovery() {
    let apr = from_arg("apr02").unwrap();
    assert_eq!(apr.source, Source::Builtin);
    assert_eq!(apr.description.design_ik().unwrap(), IkMatrix::paper_design());
    let e = from_arg("no/such/robot.toml").unwrap_err().to_string();
    assert!(e.starts_with("no/such/robot.toml: "), "{e}");

    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    let cwd = tmp.path().join("work");
    std::fs::create_dir_all(&data).unwrap();
    std::fs::create_dir_all(&cwd).unwrap();
    let run = data.join("a.mcap");
    assert_eq!(discover(std::slice::from_ref(&run), &cwd), None);
    std::fs::write(cwd.join(FILE_NAME), APR02).unwrap();
    assert_eq!(discover(std::slice::from_ref(&run), &cwd), Some(cwd.join(FILE_NAME)));
    assert_eq!(discover(&[], &cwd), Some(cwd.join(FILE_NAME)));
    // Beside the data wins over the working directory; a folder argument is searched itself.
    std::fs::write(data.join(FILE_NAME), APR02).unwrap();
    assert_eq!(discover(&[run], &cwd), Some(data.join(FILE_NAME)));
    assert_eq!(discover(std::slice::from_ref(&data), &cwd), Some(data.join(FILE_NAME)));
    let r = from_arg(data.join(FILE_NAME).to_str().unwrap()).unwrap();
    assert_eq!(r.description.joints(), ["wheel_a", "wheel_b", "wheel_c"]);
}
