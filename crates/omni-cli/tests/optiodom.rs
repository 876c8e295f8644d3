//! OptiOdom set folders of every supported robot type, on small synthetic sets written by the tests (CI
//! has no ../shared/data): the ground truth is integrated from the wheel ticks with OptiOdom's own nominal
//! model (the formulas of the data's README), so the design model read from the metadata must reproduce it
//! to rounding; and bad metadata or rows are refused naming the file, the line and the field.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use omni_cli::dataset::{self, LoadOptions};
use omni_kin::cost::{self, CostKind};
use omni_kin::{FittedModel, Model};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

/// A synthetic OptiOdom set: robot type and metadata values.
struct Set {
    kind: &'static str,
    ngear: f64,
    enc_res: f64,
    li: Vec<f64>,
    di: Vec<f64>,
    dt_s: f64,
}

impl Set {
    fn omni4() -> Self {
        Self {
            kind: "omni4",
            ngear: 1.0,
            enc_res: 1.0,
            li: vec![0.205, 0.215],
            di: vec![0.06, 0.0592, 0.0607, 0.06],
            dt_s: 0.01,
        }
    }
    fn diff() -> Self {
        Self { kind: "diff", ngear: 43.7, enc_res: 64.0, li: vec![0.2], di: vec![0.084, 0.0832], dt_s: 0.05 }
    }
    fn omni3() -> Self {
        Self { kind: "omni3", ngear: 12.0, enc_res: 1024.0, li: vec![0.195], di: vec![0.102, 0.1, 0.103], dt_s: 0.04 }
    }

    /// OptiOdom's nominal robot-frame displacement (dx m, dy m, dθ rad) of one cycle from the wheel arc
    /// lengths (m): the README formulas, written out independently of the reader.
    fn nominal(&self, s: &[f64]) -> [f64; 3] {
        match self.kind {
            "omni3" => {
                let l = self.li[0];
                [
                    (3f64.sqrt() / 3.0) * (s[1] - s[0]),
                    (2.0 * s[2] - s[0] - s[1]) / 3.0,
                    -(s[0] + s[1] + s[2]) / (3.0 * l),
                ]
            }
            "omni4" => {
                let (l1, l2) = (self.li[0], self.li[1]);
                [
                    (s[0] - s[1] + s[2] - s[3]) / 4.0,
                    (-s[0] - s[1] + s[2] + s[3]) / 4.0,
                    -(s[0] + s[1] + s[2] + s[3]) / (2.0 * (l1 + l2)),
                ]
            }
            "diff" => [(s[0] + s[1]) / 2.0, 0.0, (s[0] - s[1]) / self.li[0]],
            k => panic!("no nominal model for {k}"),
        }
    }

    /// Writes `<dir>/<id>/` with a metadata file and `runs` run files; returns the set folder.
    fn write(&self, dir: &Path, id: &str, runs: usize) -> std::path::PathBuf {
        let set = dir.join(id);
        std::fs::create_dir_all(&set).unwrap();
        let row =
            |k: &str, v: &[f64]| format!("{k},{}\n", v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(","));
        let mut meta = format!("type,{},,\n", self.kind);
        meta += &row("ngear", &[self.ngear]);
        meta += &row("encRes", &[self.enc_res]);
        meta += &row("Li", &self.li);
        meta += &row("Di", &self.di);
        meta += "Thi,,,\n";
        meta += &row("N", &[runs as f64]);
        std::fs::write(set.join(format!("{id}_metadata.csv")), meta).unwrap();
        for r in 0..runs {
            std::fs::write(set.join(format!("{id}_run-{:02}.csv", r + 1)), self.run_text(r)).unwrap();
        }
        set
    }

    /// One run: 6 s of smoothly varying wheel motion (each wheel its own frequency and phase), the
    /// ground truth integrated from it with [`Self::nominal`] held over each cycle (an exact arc).
    fn run_text(&self, seed: usize) -> String {
        let n = self.di.len();
        let cycles = (6.0 / self.dt_s).round() as usize;
        let (mut x, mut y, mut th) = (0.0f64, 0.0f64, 0.0f64);
        let mut text = String::new();
        for k in 0..=cycles {
            let t = k as f64 * self.dt_s;
            let ticks: Vec<f64> = (0..n)
                .map(|i| {
                    if k == 0 {
                        return 0.0;
                    }
                    let f = 0.3 + 0.17 * i as f64 + 0.05 * seed as f64;
                    let speed_m_s = 0.3 * (2.0 * PI * f * t + i as f64 + seed as f64).sin() + 0.1 * (i as f64 - 1.0);
                    speed_m_s * self.dt_s * self.ngear * self.enc_res / (PI * self.di[i])
                })
                .collect();
            let s: Vec<f64> = (0..n).map(|i| PI * self.di[i] * ticks[i] / (self.ngear * self.enc_res)).collect();
            let [dx, dy, a] = self.nominal(&s);
            let (f1, f2) =
                if a.abs() < 1e-6 { (1.0 - a * a / 6.0, a / 2.0) } else { (a.sin() / a, (1.0 - a.cos()) / a) };
            let (bx, by) = (f1 * dx - f2 * dy, f2 * dx + f1 * dy);
            let (sn, cs) = th.sin_cos();
            x += cs * bx - sn * by;
            y += sn * bx + cs * by;
            th += a;
            write!(text, "{t},{x},{y},{th}").unwrap();
            for v in &ticks {
                write!(text, ",{v}").unwrap();
            }
            text.push('\n');
        }
        text
    }
}

fn omnical(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_omnical")).args(args).current_dir(dir).output().expect("run omnical")
}

/// The design model of a synthetic set follows its ground truth to rounding: the metadata's geometry is
/// OptiOdom's nominal model, whatever the robot type, with unequal wheel diameters.
#[test]
fn design_of_every_type_reproduces_optiodom_nominal_model() {
    let dir = tempfile::tempdir().unwrap();
    for (set, wheels) in [
        (Set::omni3(), vec!["wheel_1", "wheel_2", "wheel_3"]),
        (Set::omni4(), vec!["wheel_1", "wheel_2", "wheel_3", "wheel_4"]),
        (Set::diff(), vec!["wheel_right", "wheel_left"]),
    ] {
        let folder = set.write(dir.path(), &format!("{}0001", set.kind), 3);
        let ds = dataset::load(&[folder], &LoadOptions::default()).unwrap();
        assert_eq!(ds.runs.len(), 3, "{}", set.kind);
        assert_eq!(ds.runs[0].name(), format!("{}0001/run-01", set.kind));
        assert!(ds.runs.iter().all(|r| r.n_wheels() == wheels.len() && r.truth().len() == r.n_samples()));
        let robot = ds.robot.expect("the metadata declares the robot");
        assert_eq!(robot.wheel_names, wheels);
        let design = FittedModel::nominal(Model::ik(robot.twist_from_wheels().unwrap()));
        let end = cost::cost(&design.model, &design.params, &ds.runs, CostKind::EndPose).unwrap();
        let path = cost::cost(&design.model, &design.params, &ds.runs, CostKind::PATH).unwrap();
        assert!(end < 1e-9 && path < 1e-9, "{}: Eq. 6 {end}, path {path}", set.kind);
        // The runs move: a wrong model would show.
        let far = ds.runs.iter().map(|r| r.truth().last().unwrap().pose.x_m.abs()).fold(0.0, f64::max);
        assert!(far > 0.05, "{}: runs end within {far} m of the start", set.kind);
    }
}

/// `omnical eval --model design` on a folder of each type: exit 0 and a cost at rounding level.
#[test]
fn eval_reads_omni4_and_diff_folders() {
    let dir = tempfile::tempdir().unwrap();
    for set in [Set::omni4(), Set::diff()] {
        let id = format!("{}0002", set.kind);
        set.write(dir.path(), &id, 2);
        let out = omnical(&["eval", "--model", "design", &id, "--json"], dir.path());
        assert!(out.status.success(), "{}: {}", set.kind, String::from_utf8_lossy(&out.stderr));
        let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(e["runs"].as_array().unwrap().len(), 2);
        assert!(e["cost"].as_f64().unwrap() < 1e-9, "{}: {}", set.kind, e["cost"]);
    }
}

/// Refusals: exit 2, `error: <file>: line N, <field>: …`.
fn refused(dir: &Path, id: &str) -> String {
    let out = omnical(&["eval", id], dir);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stdout));
    String::from_utf8_lossy(&out.stderr).trim().to_string()
}

#[test]
fn tricycle_and_unknown_types_are_refused_naming_file_and_type() {
    let dir = tempfile::tempdir().unwrap();
    for kind in ["tricycle", "omni5"] {
        let id = format!("{kind}0003");
        let set = Set::diff().write(dir.path(), &id, 1);
        let meta = set.join(format!("{id}_metadata.csv"));
        let text = std::fs::read_to_string(&meta).unwrap().replacen("type,diff", &format!("type,{kind}"), 1);
        std::fs::write(&meta, text).unwrap();
        assert_eq!(
            refused(dir.path(), &id),
            format!(
                "error: {id}/{id}_metadata.csv: line 1, key type: robot type \"{kind}\" is not supported (omnical \
                 reads OptiOdom's omni3, omni4, diff sets)"
            )
        );
    }
}

#[test]
fn bad_metadata_and_rows_name_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let edit = |id: &str, file: &str, from: &str, to: &str| {
        let p = dir.path().join(id).join(format!("{id}_{file}"));
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains(from), "{from:?} not in {file}");
        std::fs::write(&p, text.replacen(from, to, 1)).unwrap();
    };
    Set::omni4().write(dir.path(), "o4", 1);
    edit("o4", "metadata.csv", "Di,0.06,0.0592,0.0607,0.06", "Di,0.06,0.0592,0.0607");
    assert_eq!(
        refused(dir.path(), "o4"),
        "error: o4/o4_metadata.csv: line 5, key Di: expected 4 value(s) (wheel diameters, m), got 3"
    );
    Set::diff().write(dir.path(), "d1", 1);
    edit("d1", "metadata.csv", "Li,0.2", "Li,-0.2");
    assert_eq!(
        refused(dir.path(), "d1"),
        "error: d1/d1_metadata.csv: line 4, key Li: \"-0.2\" must be a number > 0 (wheel separation b, m)"
    );
    Set::diff().write(dir.path(), "d2", 1);
    edit("d2", "metadata.csv", "encRes,64", "encRes,sixty-four");
    assert_eq!(
        refused(dir.path(), "d2"),
        "error: d2/d2_metadata.csv: line 3, key encRes: \"sixty-four\" is not a number (encoder counts per motor \
         revolution)"
    );
    Set::diff().write(dir.path(), "d3", 1);
    edit("d3", "metadata.csv", "ngear,43.7\n", "");
    assert_eq!(refused(dir.path(), "d3"), "error: d3/d3_metadata.csv: missing key ngear");
    // Rows: a bad cell names its line and column, a short row its line and the expected count.
    Set::diff().write(dir.path(), "d4", 1);
    let run = std::fs::read_to_string(dir.path().join("d4/d4_run-01.csv")).unwrap();
    let line3: Vec<&str> = run.lines().nth(2).unwrap().split(',').collect();
    edit("d4", "run-01.csv", &line3.join(","), &[&line3[..5], &["x"]].concat().join(","));
    assert_eq!(refused(dir.path(), "d4"), "error: d4/d4_run-01.csv: line 3, column ticks_left: \"x\" is not a number");
    Set::omni4().write(dir.path(), "o5", 1);
    let run = std::fs::read_to_string(dir.path().join("o5/o5_run-01.csv")).unwrap();
    let line2 = run.lines().nth(1).unwrap();
    edit("o5", "run-01.csv", line2, line2.rsplit_once(',').unwrap().0);
    assert_eq!(
        refused(dir.path(), "o5"),
        "error: o5/o5_run-01.csv: line 2: has 7 columns, expected 8 (time, x, y, θ and 4 wheels)"
    );
}
