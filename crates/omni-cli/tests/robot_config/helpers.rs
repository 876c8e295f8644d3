//! Helpers of the `robot_config` tests (included with `#[path]`): running the binary, reading what it wrote
//! (YAML, the C header's matrix), the controllers' own odometry, and writing the runs and models they use.

use crate::support::{stderr, stdout, succeeded_on_two_threads};
use omni_cli::dataset;
use omni_kin::{FittedModel, IkMatrix, Run, RunData, Scheme, StampedPose};
use std::path::Path;
use std::process::Command;
use yaml_rust2::{Yaml, YamlLoader};

/// `omnical --threads 2 -q ARGS` in `dir`, which must succeed: stdout (the results) and stderr (warnings: `-q`
/// keeps them).
pub fn omnical_with_stderr(args: &[&str], dir: &Path) -> (String, String) {
    let out = succeeded_on_two_threads(args, dir);
    (stdout(&out), stderr(&out))
}

pub fn yaml(path: &Path) -> Yaml {
    let text = std::fs::read_to_string(path).unwrap();
    let mut docs = YamlLoader::load_from_str(&text).unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()));
    assert_eq!(docs.len(), 1);
    docs.remove(0)
}

/// A ROS 2 double: YAML must type it as a float (`1.0`, never `1`), or the parameter is refused.
pub fn real(y: &Yaml) -> f64 {
    assert!(matches!(y, Yaml::Real(_)), "not a YAML float: {y:?}");
    y.as_f64().unwrap()
}

pub fn strings(y: &Yaml) -> Vec<String> {
    y.as_vec().unwrap_or_else(|| panic!("not a list: {y:?}")).iter().map(|s| s.as_str().unwrap().to_string()).collect()
}

/// The matrix written in omnical_odometry.yaml (row-major 3 × N).
pub fn written_matrix(dir: &Path) -> IkMatrix {
    let y = yaml(&dir.join("omnical_odometry.yaml"));
    let p = &y["/**"]["ros__parameters"];
    let n = strings(&p["wheel_names"]).len();
    let entries: Vec<f64> = p["twist_from_wheels"].as_vec().unwrap().iter().map(real).collect();
    IkMatrix::new(n, entries).unwrap()
}

pub fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() <= tol, "{what}: {a:?} vs {b:?}");
    }
}

/// The controller's loss against the full model in % (Eq. 6, path RMS), as printed.
pub fn loss_pct(stdout: &str) -> [f64; 2] {
    let line = stdout.lines().find(|l| l.contains("given up by the controller")).unwrap_or_else(|| panic!("{stdout}"));
    let v: Vec<f64> = line.split_whitespace().filter_map(|t| t.parse().ok()).collect();
    v.try_into().unwrap_or_else(|_| panic!("{line}"))
}

/// Twist from wheel speeds through ros2_controllers' omni_wheel_drive_controller formula, N = 3 (A is
/// square: twist = A⁻¹ r ω), written out independently of omnical's code.
pub fn omni_controller_twist(r: f64, big_r: f64, offset: f64, w: [f64; 3]) -> [f64; 3] {
    let a: Vec<[f64; 3]> = (0..3)
        .map(|i| {
            let th = offset + std::f64::consts::TAU * i as f64 / 3.0;
            [th.sin(), -th.cos(), -big_r]
        })
        .collect();
    let det = |m: &[[f64; 3]]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&a);
    // Cramer's rule for A x = r w.
    (0..3)
        .map(|j| {
            let mut m = a.clone();
            for i in 0..3 {
                m[i][j] = r * w[i];
            }
            det(&m) / d
        })
        .collect::<Vec<_>>()
        .try_into()
        .unwrap()
}

pub fn simulate_apr02(dir: &Path) {
    succeeded_on_two_threads(
        &["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "3", "--format", "csv", "--noise-free"],
        dir,
    );
}

pub fn rms_twist_difference(runs: &[Run], m: &IkMatrix, controller: impl Fn([f64; 3]) -> [f64; 3]) -> [f64; 3] {
    let mut total = [0.0; 3];
    for run in runs {
        let mut sum = [0.0; 3];
        for k in 0..run.n_samples() {
            let w: [f64; 3] = run.wheel_sample(k).try_into().unwrap();
            let t = m.twist(&w);
            let c = controller(w);
            for (j, v) in [t.vx_m_s, t.vy_m_s, t.omega_rad_s].iter().enumerate() {
                sum[j] += (c[j] - v).powi(2);
            }
        }
        for j in 0..3 {
            total[j] += sum[j] / run.n_samples() as f64 / runs.len() as f64;
        }
    }
    total.map(f64::sqrt)
}

/// Compiles a C program with the header and compares its twist and 500 integration steps with omnical's.
pub fn check_header(rc: &Path, m: &IkMatrix, scheme: Scheme) {
    let prog = rc.join("prog.c");
    std::fs::write(
        &prog,
        r#"#include <stdio.h>
#include "omnical_odometry.h"
int main(void) {
    double w[OMNICAL_N_WHEELS], t[3], pose[3] = {0.1, -0.2, 0.3};
    for (int i = 0; i < OMNICAL_N_WHEELS; ++i) w[i] = 1.0 + 0.5 * i - 0.75 * i * i;
    omnical_twist(w, t);
    for (int k = 0; k < 500; ++k) omnical_step(pose, t, 0.01);
    printf("%s %.17g %.17g %.17g %.17g %.17g %.17g\n", OMNICAL_WHEEL_NAMES[0], t[0], t[1], t[2], pose[0], pose[1], pose[2]);
    return 0;
}
"#,
    )
    .unwrap();
    let exe = rc.join("prog");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let built = Command::new(&cc)
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(&exe)
        .arg(&prog)
        .arg("-lm")
        .output()
        .unwrap_or_else(|e| panic!("{cc}: {e}"));
    assert!(built.status.success(), "{}", String::from_utf8_lossy(&built.stderr));
    let run = Command::new(&exe).output().unwrap();
    let text = String::from_utf8(run.stdout).unwrap();
    let fields: Vec<&str> = text.split_whitespace().collect();
    assert_eq!(fields[0], "wheel_a");
    let c: Vec<f64> = fields[1..].iter().map(|f| f.parse().unwrap()).collect();
    let w: Vec<f64> = (0..m.n_wheels()).map(|i| 1.0 + 0.5 * i as f64 - 0.75 * (i * i) as f64).collect();
    let t = m.twist(&w);
    let mut pose = omni_kin::Pose2 { x_m: 0.1, y_m: -0.2, theta_rad: 0.3 };
    for _ in 0..500 {
        pose = omni_kin::odometry::step(scheme, pose, t, 0.01);
    }
    let rust = [t.vx_m_s, t.vy_m_s, t.omega_rad_s, pose.x_m, pose.y_m, pose.theta_rad];
    assert_close(&c, &rust, 1e-12, "C header vs omnical");
}

/// Runs of a robot driven by smooth, deterministic wheel-speed patterns (no command needed), with ground
/// truth from the model's own odometry every 0.25 s (plus noise), written as omnical CSV.
pub fn write_runs(dir: &Path, truth: &FittedModel, names: &[String]) {
    std::fs::create_dir_all(dir).unwrap();
    let n = truth.model.n_wheels();
    let res = truth.model.resolve(&truth.params).unwrap();
    let mut seed = 12345u64;
    let mut next = move || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for r in 0..12 {
        let coef: Vec<[f64; 3]> = (0..n).map(|_| [6.0 * next(), 3.0 * next(), 0.5 + next().abs()]).collect();
        let t: Vec<f64> = (0..=600).map(|k| k as f64 * 0.01).collect();
        let w: Vec<f64> = t.iter().flat_map(|&t| coef.iter().map(move |c| c[0] + c[1] * (c[2] * t).sin())).collect();
        let origin = omni_kin::Pose2 { x_m: 0.0, y_m: 0.0, theta_rad: 0.0 };
        let mut data = RunData {
            name: format!("run-{r:02}"),
            wheel_t_s: t,
            wheel_rad_s: w,
            n_wheels: n,
            truth: vec![StampedPose { t_s: 0.0, pose: origin }, StampedPose { t_s: 6.0, pose: origin }],
            ..RunData::default()
        };
        let path = omni_kin::odometry::integrate(&res, &Run::new(data.clone()).unwrap());
        // Ground truth with ±1 mm / ±1 mrad of noise, so that no model fits it perfectly.
        data.truth = (0..path.t_s.len())
            .step_by(25)
            .map(|i| {
                let p = path.poses[i];
                let pose = omni_kin::Pose2 {
                    x_m: p.x_m + 1e-3 * next(),
                    y_m: p.y_m + 1e-3 * next(),
                    theta_rad: p.theta_rad + 1e-3 * next(),
                };
                StampedPose { t_s: path.t_s[i], pose }
            })
            .collect();
        let run = Run::new(data).unwrap();
        dataset::csv::write_run(&dir.join(format!("run-{r:02}.csv")), &run, names).unwrap();
    }
}

pub fn write_model(path: &Path, f: &FittedModel) {
    std::fs::write(path, omni_cli::model_file::to_toml(f, None).unwrap()).unwrap();
}

/// omnical's matrix of a differential drive, columns (right, left) as a robot may list its joints.
pub fn diff_matrix(s: f64, rl: f64, rr: f64) -> IkMatrix {
    IkMatrix::from_rows(&[vec![rr / 2.0, rl / 2.0], vec![0.0, 0.0], vec![rr / s, -rl / s]]).unwrap()
}
