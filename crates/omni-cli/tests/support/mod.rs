//! What omni-cli's integration tests share: runners of the `omnical` binary under test (each says what it
//! asserts about the exit status) and the fixtures several tests read (the real robot logs, the committed
//! test data, recordings made by a Python script, folder listings). Included with `mod support;`.
// Each test binary uses only some of these.
#![allow(dead_code)]

use serde_json::Value;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `omnical` binary under test with `args`, to run in `dir`; `RUST_LOG` is removed so that the caller's
/// environment cannot change what it prints on stderr. For spawning it, or setting its environment.
pub fn omnical_command<I: IntoIterator<Item = S>, S: AsRef<OsStr>>(args: I, dir: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_omnical"));
    command.args(args).current_dir(dir).env_remove("RUST_LOG");
    command
}

/// Runs `omnical ARGS` in `dir`; its output, whatever its exit status.
pub fn omnical(args: &[&str], dir: &Path) -> Output {
    omnical_command(args, dir).output().expect("run omnical")
}

/// Runs `omnical ARGS` in `dir` and asserts that it succeeded (the failure shows its stderr); its output.
pub fn succeeded(args: &[&str], dir: &Path) -> Output {
    let out = omnical(args, dir);
    assert!(out.status.success(), "omnical {args:?} failed ({}):\n{}", out.status, stderr(&out));
    out
}

/// [`succeeded`] with `--threads 2 -q` before `args`: results that do not depend on the machine's cores, and
/// no progress bars on stderr.
pub fn succeeded_on_two_threads(args: &[&str], dir: &Path) -> Output {
    succeeded(&[&["--threads", "2", "-q"], args].concat(), dir)
}

/// [`succeeded`]'s stdout as text.
pub fn ok(args: &[&str], dir: &Path) -> String {
    stdout(&succeeded(args, dir))
}

/// [`succeeded`]'s stdout and stderr as text.
pub fn ok_with_stderr(args: &[&str], dir: &Path) -> (String, String) {
    let out = succeeded(args, dir);
    (stdout(&out), stderr(&out))
}

/// [`succeeded`]'s stdout, which must be one JSON document (the caller passes `--json`).
pub fn json(args: &[&str], dir: &Path) -> Value {
    let out = succeeded(args, dir);
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("omnical {args:?}: stdout is not JSON ({e}):\n{}", stdout(&out)))
}

/// Runs `omnical ARGS` in `dir` and asserts that it was refused with exit status 2 (the failure shows its
/// stdout); its stderr.
pub fn refused(args: &[&str], dir: &Path) -> String {
    let out = omnical(args, dir);
    assert_eq!(out.status.code(), Some(2), "omnical {args:?}:\n{}", stdout(&out));
    stderr(&out)
}

/// A command's stdout as text.
pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A command's stderr as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The value of the parameter `name` in a `train --json` summary's `params`.
pub fn param(summary: &Value, name: &str) -> f64 {
    let p = summary["params"].as_array().unwrap().iter().find(|p| p["name"] == name);
    p.unwrap_or_else(|| panic!("no {name} in {}", summary["params"]))["value"].as_f64().unwrap()
}

/// A fitted parameter's value and standard error from a `train --json` summary.
pub fn param_se(fit: &Value, name: &str) -> (f64, f64) {
    let se = fit["identifiability"]["params"].as_array().unwrap().iter().find(|p| p["name"] == name);
    (param(fit, name), se.and_then(|p| p["std_error"].as_f64()).unwrap_or(f64::NAN))
}

/// The simulated diff drive of the relative-reference tests: its true wheels (the left 2 % large). m.
pub const DIFF_WHEELS: [(&str, f64); 3] = [("r_left", 0.03366), ("r_right", 0.033), ("b", 0.287)];

/// Asserts that `fit` (trained on another reference, `what`) gives the diff drive's wheels within 2
/// standard errors of `mocap`'s fit on the same runs and 0.1 % of the truth ([`DIFF_WHEELS`]).
pub fn assert_wheels_as_motion_capture(fit: &Value, mocap: &Value, what: &str) {
    for (name, truth) in DIFF_WHEELS {
        let (m, m_se) = param_se(mocap, name);
        let (r, r_se) = param_se(fit, name);
        eprintln!("{name}: {what} {r:.6} ± {r_se:.1e}, motion capture {m:.6} ± {m_se:.1e} (true {truth})");
        assert!((r - m).abs() <= 2.0 * m_se.max(r_se), "{name}: {what} {r} vs motion capture {m} ± {m_se}");
        assert!((r - truth).abs() < 1e-3 * truth, "{name}: {what} {r} vs {truth}");
    }
}

/// The URDF link and joint of one of APR-02's omni wheels (r = 0.148 m, 0.195 m out) at `angle_deg`: the
/// joint frame is yawed to the wheel's angle and turns about −x (the axle points inwards), so positive speed
/// pushes along the counter-clockwise tangent.
pub fn apr02_wheel_urdf(name: &str, angle_deg: f64) -> String {
    let a = angle_deg.to_radians();
    format!(
        r#"<link name="{name}_link"><collision><origin xyz="0 0 0" rpy="0 1.5707963267948966 0"/>
  <geometry><cylinder radius="0.148" length="0.04"/></geometry></collision></link>
<joint name="{name}" type="continuous"><parent link="base_link"/><child link="{name}_link"/>
  <origin xyz="{} {} 0.0" rpy="0 0 {a}"/><axis xyz="-1 0 0"/></joint>
"#,
        0.195 * a.cos(),
        0.195 * a.sin()
    )
}

/// The real OptiOdom logs of robot type `robot` (`optiodom-<robot>-square`), found by build.rs: the tests that
/// read them are ignored (`cfg(shared_data)`) when they are not here.
pub fn shared_data(robot: &str) -> PathBuf {
    Path::new(option_env!("OMNICAL_SHARED_DATA").unwrap_or("")).join(format!("optiodom-{robot}-square"))
}

/// One set folder of [`shared_data`], as an argument.
pub fn shared_set(robot: &str, set: &str) -> String {
    shared_data(robot).join(set).to_str().unwrap().to_string()
}

/// A committed file of `crates/omni-cli/tests/data`.
pub fn test_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// The Python interpreter of the test tools: `$OMNICAL_PYTHON`, default `python3` (see build.rs).
pub fn python() -> String {
    std::env::var("OMNICAL_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// Runs the Python script `script` (relative to `crates/omni-cli/tests`) with the folder `out` as its
/// argument, and asserts that it succeeded; returns `out`.
pub fn made_by_python(script: &str, out: PathBuf) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join(script);
    let run = Command::new(python()).arg(&path).arg(&out).output().unwrap();
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(run.status.success(), "{name} failed: {}", String::from_utf8_lossy(&run.stderr));
    out
}

/// The `expected.json` a fixture script wrote beside its recordings in `dir`.
pub fn expected_json(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap()
}

/// The names in a folder, sorted.
pub fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// Copies the folder `from` to `to`, recursively.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// A robot.toml of omni wheels `name`, each at `distance_m` from the centre at one of `angles_deg` (polar
/// position), driving along the counter-clockwise tangent.
pub fn omni_toml(name: &str, radius_m: f64, distance_m: f64, angles_deg: &[f64]) -> String {
    let mut s = format!("name = \"{name}\"\nkind = \"omni\"\n");
    for (i, a) in angles_deg.iter().enumerate() {
        s += &format!(
            "[[wheels]]\njoint = \"w{i}\"\ndistance_m = {distance_m}\nangle_deg = {a}\nradius_m = {radius_m}\n"
        );
    }
    s
}
