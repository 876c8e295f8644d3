//! `omnical eval`'s absolute pose error (issue 44) against evo_ape on the TUM files of `omnical export`:
//! evo's own code as `evo_ape tum GT EST` runs it (association within 0.01 s, translation part, no
//! alignment) and with `--align`, every statistic within 1e-6 m.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::Path;
use std::process::Command;
use support::ok;

/// `omnical ARGS --json` in `dir`, which must succeed: the document.
fn json(args: &[&str], dir: &Path) -> serde_json::Value {
    support::json(&[args, &["--json"]].concat(), dir)
}

/// What `evo_ape tum GT EST [-a]` computes (evo/cli/ape.py: read, associate with `--t_max_diff` 0.01,
/// `main_ape.ape` with the translation part), its statistics printed with all their digits.
const EVO: &str = r#"
import sys
from evo import main_ape
from evo.core import metrics, sync
from evo.tools import file_interface
ref = file_interface.read_tum_trajectory_file(sys.argv[1])
est = file_interface.read_tum_trajectory_file(sys.argv[2])
ref, est = sync.associate_trajectories(ref, est, max_diff=0.01)
for align in (False, True):
    r = main_ape.ape(ref, est, metrics.PoseRelation.translation_part, align=align)
    print(len(r.np_arrays["error_array"]), *(repr(float(r.stats[k])) for k in ("rmse", "mean", "median", "max")))
"#;

#[test]
#[cfg_attr(not(python_evo), ignore = "needs evo beside $OMNICAL_PYTHON: bash scripts/test.sh installs evo")]
fn eval_agrees_with_evo_ape_with_and_without_alignment() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    ok(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "12", "--seed", "5", "-q"], d);
    let runs = ["sim/validation/03-r0.mcap", "sim/validation/17-r0.mcap", "sim/validation/30-r0.mcap"];
    ok(&[&["export", "--model", "design", "--tum", "tum"][..], &runs].concat(), d);
    let v = json(&[&["eval", "--model", "design"][..], &runs].concat(), d);
    let python = std::env::var_os("OMNICAL_PYTHON").unwrap();
    for (run, ours) in runs.iter().zip(v["runs"].as_array().unwrap()) {
        let stem = Path::new(run).file_stem().unwrap().to_str().unwrap();
        let (gt, est) = (format!("tum/{stem}.gt.tum"), format!("tum/{stem}.design.tum"));
        let out = Command::new(&python).args(["-c", EVO, &gt, &est]).current_dir(d).output().unwrap();
        assert!(out.status.success(), "evo: {}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8(out.stdout).unwrap();
        for (line, key) in text.lines().zip(["translation_m", "aligned_translation_m"]) {
            let cols: Vec<f64> = line.split_whitespace().map(|c| c.parse().unwrap()).collect();
            assert_eq!(ours["ape"]["poses"].as_f64(), Some(cols[0]), "{stem}: poses, evo {text}");
            for (k, stat) in ["rmse", "mean", "median", "max"].iter().enumerate() {
                let got = ours["ape"][key][stat].as_f64().unwrap();
                assert!((got - cols[k + 1]).abs() < 1e-6, "{stem} {key} {stat}: ours {got} m, evo {}", cols[k + 1]);
            }
        }
        let (plain, aligned) = (
            ours["ape"]["translation_m"]["rmse"].as_f64().unwrap(),
            ours["ape"]["aligned_translation_m"]["rmse"].as_f64().unwrap(),
        );
        // The design's error is not small, and alignment takes some of it away.
        assert!(plain > 1e-3 && aligned < plain, "{stem}: {plain} m, aligned {aligned} m");
    }
}

#[test]
fn eval_prints_the_ape_beside_the_path_cost() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    ok(&["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "4", "--seed", "5", "-q"], d);
    let text = ok(&["eval", "--model", "design", "sim/validation/03-r0.mcap"], d);
    let v = json(&["eval", "--model", "design", "sim/validation/03-r0.mcap"], d);
    let row = text.lines().find(|l| l.starts_with("evo_ape default")).unwrap_or_else(|| panic!("{text}"));
    let rmse: f64 = row.split_whitespace().nth(4).unwrap().parse().unwrap();
    let json_rmse = v["ape"]["translation_m"]["rmse"].as_f64().unwrap();
    assert!((rmse - json_rmse).abs() < 1e-4, "{row} vs {json_rmse}");
    // The first pose counts (error 0): the mean over n poses of errors whose first is 0.
    let run = &v["runs"][0]["ape"];
    assert_eq!(run["poses"], v["ape"]["poses"]);
    assert!(text.contains("evo_ape --align"), "{text}");
}
