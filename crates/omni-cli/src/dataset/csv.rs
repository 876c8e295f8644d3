//! The omnical CSV run format: one file per run (see `docs/formats.md`).
//!
//! ```text
//! # omnical run v1
//! # name: train/run-003
//! # command_v_m_s: 0.2
//! # command_alpha_rad: 0.5235987755982988
//! # command_omega_rad_s: 0.35
//! # repetition: 0
//! # wheel_start_rad: 0.1,2.3,4.0
//! # ticks_per_rev: 49152
//! t_s,wheel_a_rad_s,wheel_b_rad_s,wheel_c_rad_s,x_m,y_m,theta_rad,odom_x_m,odom_y_m,odom_theta_rad
//! ```
//! A row is a wheel sample when its wheel cells are filled and a ground-truth pose when its pose cells are
//! filled (either or both). Wheel columns are `<joint>_rad_s` or `<joint>_ticks` (counts since the previous
//! sample; rad/s = ticks · 2π / ticks_per_rev / Δt, the first sample using the second's Δt). Headings are
//! unwrapped on load.

use super::DatasetError;
use crate::atomic;
use omni_kin::error::Sample;
pub use omni_kin::pose::unwrap_headings;
use omni_kin::run::MAX_HEADING_RAD;
use omni_kin::{Command, KinError, Pose2, Run, RunData, StampedPose};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::Path;

const POSE: [&str; 3] = ["x_m", "y_m", "theta_rad"];
const ODOM: [&str; 3] = ["odom_x_m", "odom_y_m", "odom_theta_rad"];

fn parse_num(path: &Path, line: usize, col: &str, cell: &str) -> Result<f64, DatasetError> {
    cell.trim()
        .parse::<f64>()
        .map_err(|_| DatasetError::at(path, format!("line {line}, column {col}"), format!("{cell:?} is not a number")))
}

/// The wheel columns `cols` (of `headers`, ending in `_ticks` when `ticks`, else `_rad_s`) in the order of
/// `joints`; `cols` unchanged when `joints` is empty. An error names the file, the header line, the joint
/// without a column, and both lists of joints.
fn joint_columns(
    path: &Path,
    header_line: usize,
    headers: &[String],
    cols: Vec<usize>,
    ticks: bool,
    joints: &[String],
) -> Result<Vec<usize>, DatasetError> {
    if joints.is_empty() {
        return Ok(cols);
    }
    let suffix = if ticks { "_ticks" } else { "_rad_s" };
    let in_file: Vec<&str> = cols.iter().map(|&c| headers[c].strip_suffix(suffix).unwrap_or(&headers[c])).collect();
    let mismatch = |what: String| {
        DatasetError::at(
            path,
            format!("line {header_line}"),
            format!(
                "{what} (the robot's joints: {}; the file's wheel columns: {})",
                joints.join(", "),
                in_file.join(", ")
            ),
        )
    };
    if in_file.len() != joints.len() {
        return Err(mismatch(format!("{} wheel columns for {} joints", in_file.len(), joints.len())));
    }
    joints
        .iter()
        .map(|j| {
            in_file
                .iter()
                .position(|f| f == j)
                .map(|i| cols[i])
                .ok_or_else(|| mismatch(format!("no column {j}{suffix}")))
        })
        .collect()
}

/// Read one omnical CSV run. `ticks_per_rev` overrides the file's.
pub fn read_run(path: &Path, ticks_per_rev: Option<f64>) -> Result<Run, DatasetError> {
    read_run_for(path, ticks_per_rev, &[])
}

/// [`read_run`] with the wheel columns in the order of `joints` (a robot description's or `--joints`:
/// columns `<joint>_rad_s` or `<joint>_ticks`); empty `joints`: the file's order.
pub fn read_run_for(path: &Path, ticks_per_rev: Option<f64>, joints: &[String]) -> Result<Run, DatasetError> {
    let bytes = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    parse_run_for(path, &bytes, ticks_per_rev, joints)
}

/// Parse one omnical CSV run from its bytes; `path` only names the source in errors. `ticks_per_rev`
/// overrides the file's.
pub fn parse_run(path: &Path, bytes: &[u8], ticks_per_rev: Option<f64>) -> Result<Run, DatasetError> {
    parse_run_for(path, bytes, ticks_per_rev, &[])
}

/// What to say when a CSV file's first line holds numbers rather than column names: an OptiOdom run file
/// (`<set>_run-NN.csv`, no header) is read with its set's `<set>_metadata.csv`; any other needs a header.
fn headerless_hint(path: &Path, headers: &[String]) -> String {
    if !headers.iter().all(|h| h.parse::<f64>().is_ok()) {
        return String::new();
    }
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    match name.split_once("_run-") {
        Some((set, _)) => format!(
            "; the first line holds numbers: this looks like an OptiOdom run file, which is read from its set's \
             folder with the set's metadata file ({set}_metadata.csv) beside it (docs/formats.md)"
        ),
        None => {
            "; the first line holds numbers: an omnical CSV file starts with a header line (docs/formats.md)".into()
        }
    }
}

/// The ground truth of a CSV run that has no pose columns, from elsewhere (a `--gt` file): given the wheel
/// times (s, as written), speeds (rad/s, row-major) and the wheel count, the poses on the same clock.
pub type ExternalPoses<'a> = &'a mut dyn FnMut(&[f64], &[f64], usize) -> Result<Vec<StampedPose>, DatasetError>;

/// [`read_run_for`] for a CSV run whose ground truth is given apart (`--gt`): the file must have no pose
/// columns (`x_m`, `y_m`, `theta_rad`); `external` gives its poses from its wheel data.
pub fn read_run_with_truth(
    path: &Path,
    ticks_per_rev: Option<f64>,
    joints: &[String],
    external: ExternalPoses<'_>,
) -> Result<Run, DatasetError> {
    let bytes = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    parse_run_inner(path, &bytes, ticks_per_rev, joints, Some(external))
}

/// [`parse_run`] with the wheel columns in the order of `joints` ([`read_run_for`]).
pub fn parse_run_for(
    path: &Path,
    bytes: &[u8],
    ticks_per_rev: Option<f64>,
    joints: &[String],
) -> Result<Run, DatasetError> {
    parse_run_inner(path, bytes, ticks_per_rev, joints, None)
}

/// [`parse_run_for`], the poses from `external` when given ([`read_run_with_truth`]).
///
/// long: one pass over header and rows, each check with its own message naming file, line and column;
/// to split into header, row and ground-truth parts (issue 15 leftover).
fn parse_run_inner(
    path: &Path,
    bytes: &[u8],
    ticks_per_rev: Option<f64>,
    joints: &[String],
    mut external: Option<ExternalPoses<'_>>,
) -> Result<Run, DatasetError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        DatasetError::file(path, format!("is not UTF-8 text (invalid byte at offset {})", e.valid_up_to()))
    })?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Metadata comments before the header.
    let mut meta: BTreeMap<String, (usize, String)> = BTreeMap::new();
    let mut body_start = 0;
    let mut header_line = 1;
    for (i, line) in text.split_inclusive('\n').enumerate() {
        let l = line.trim_end_matches(['\r', '\n']);
        if let Some(c) = l.strip_prefix('#') {
            if let Some((k, v)) = c.split_once(':') {
                meta.insert(k.trim().to_string(), (i + 1, v.trim().to_string()));
            }
            body_start += line.len();
            header_line = i + 2;
        } else if l.trim().is_empty() {
            body_start += line.len();
            header_line = i + 2;
        } else {
            break;
        }
    }
    let meta_num = |key: &str| -> Result<Option<f64>, DatasetError> {
        match meta.get(key) {
            Some((line, v)) => parse_num(path, *line, key, v).map(Some),
            None => Ok(None),
        }
    };
    let mut reader =
        csv::ReaderBuilder::new().has_headers(true).flexible(false).from_reader(&text.as_bytes()[body_start..]);
    let headers: Vec<String> = reader
        .headers()
        .map_err(|e| DatasetError::at(path, format!("line {header_line}"), e.to_string()))?
        .iter()
        .map(|h| h.trim().to_string())
        .collect();
    if headers.iter().all(|h| h.is_empty()) {
        return Err(DatasetError::at(
            path,
            format!("line {header_line}"),
            "no header row (expected t_s, wheel columns <joint>_rad_s or <joint>_ticks, x_m, y_m, theta_rad)",
        ));
    }
    let find = |name: &str| headers.iter().position(|h| h == name);
    let t_col = find("t_s").ok_or_else(|| {
        DatasetError::at(
            path,
            format!("line {header_line}"),
            format!("missing column t_s (columns: {}){}", headers.join(","), headerless_hint(path, &headers)),
        )
    })?;
    let rad_cols: Vec<usize> = (0..headers.len()).filter(|&i| headers[i].ends_with("_rad_s")).collect();
    let tick_cols: Vec<usize> = (0..headers.len()).filter(|&i| headers[i].ends_with("_ticks")).collect();
    let (wheel_cols, ticks) = match (rad_cols.is_empty(), tick_cols.is_empty()) {
        (false, true) => (rad_cols, false),
        (true, false) => (tick_cols, true),
        (true, true) => {
            return Err(DatasetError::at(
                path,
                format!("line {header_line}"),
                "no wheel columns: expected <joint>_rad_s or <joint>_ticks columns",
            ));
        }
        (false, false) => {
            return Err(DatasetError::at(path, format!("line {header_line}"), "mixes _rad_s and _ticks wheel columns"));
        }
    };
    let wheel_cols = joint_columns(path, header_line, &headers, wheel_cols, ticks, joints)?;
    let tpr = match (ticks, ticks_per_rev.or(meta_num("ticks_per_rev")?)) {
        (true, None) => {
            return Err(DatasetError::file(
                path,
                "wheel columns are ticks but no ticks_per_rev is given (add '# ticks_per_rev: N' or --ticks-per-rev)",
            ));
        }
        (_, v) => v.unwrap_or(1.0),
    };
    let pose_cols: Vec<Option<usize>> = POSE.iter().map(|n| find(n)).collect();
    if external.is_some() && pose_cols.iter().any(Option::is_some) {
        return Err(DatasetError::at(
            path,
            format!("line {header_line}"),
            format!(
                "has ground-truth columns of its own ({}), and --gt gives another: drop --gt, or remove the \
                 columns to use the --gt file",
                POSE.join(", ")
            ),
        ));
    }
    if external.is_none() && pose_cols.iter().any(Option::is_none) {
        let missing: Vec<&str> = POSE.iter().zip(&pose_cols).filter(|(_, c)| c.is_none()).map(|(n, _)| *n).collect();
        return Err(DatasetError::at(
            path,
            format!("line {header_line}"),
            format!("missing column {}", missing.join(", ")),
        ));
    }
    let pose_cols: Vec<usize> = pose_cols.into_iter().flatten().collect();
    let odom_cols: Vec<Option<usize>> = ODOM.iter().map(|n| find(n)).collect();
    let odom_cols: Option<Vec<usize>> = odom_cols.into_iter().collect();

    let n_w = wheel_cols.len();
    let (mut wheel_t, mut wheel, mut truth, mut odom) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // The line of each wheel sample and ground-truth pose, for locating `Run::new`'s errors.
    let (mut wheel_lines, mut truth_lines) = (Vec::new(), Vec::new());
    // `group` = the cells of a column group in this row: all empty → None; all filled → values; else error.
    let group = |rec: &csv::StringRecord, cols: &[usize], line: usize| -> Result<Option<Vec<f64>>, DatasetError> {
        let cells: Vec<&str> = cols.iter().map(|&c| rec.get(c).unwrap_or("").trim()).collect();
        let filled = cells.iter().filter(|c| !c.is_empty()).count();
        if filled == 0 {
            return Ok(None);
        }
        if filled < cells.len() {
            let empty: Vec<&str> =
                cols.iter().zip(&cells).filter(|(_, c)| c.is_empty()).map(|(&i, _)| headers[i].as_str()).collect();
            return Err(DatasetError::at(
                path,
                format!("line {line}"),
                format!("partly filled row: {} empty", empty.join(", ")),
            ));
        }
        cols.iter()
            .zip(&cells)
            .map(|(&i, c)| parse_num(path, line, &headers[i], c))
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    };
    for (i, rec) in reader.records().enumerate() {
        let line = header_line + 1 + i;
        let rec = rec.map_err(|e| {
            let what = match e.kind() {
                csv::ErrorKind::UnequalLengths { expected_len, len, .. } => {
                    format!("the row has {len} cells but the header has {expected_len}")
                }
                _ => e.to_string(),
            };
            DatasetError::at(path, format!("line {line}"), what)
        })?;
        if rec.iter().all(|c| c.trim().is_empty()) {
            continue;
        }
        let t = parse_num(path, line, "t_s", rec.get(t_col).unwrap_or(""))?;
        if let Some(w) = group(&rec, &wheel_cols, line)? {
            wheel_t.push(t);
            wheel.extend(w);
            wheel_lines.push(line);
        }
        if let Some(p) = group(&rec, &pose_cols, line)? {
            // Checked before unwrapping, which would turn a huge heading into an arbitrary one.
            if p[2].abs() > MAX_HEADING_RAD {
                return Err(DatasetError::at(
                    path,
                    format!("line {line}, column theta_rad"),
                    format!("{} rad is beyond the plausible limit ±{MAX_HEADING_RAD} rad", p[2]),
                ));
            }
            truth.push(StampedPose { t_s: t, pose: Pose2::new(p[0], p[1], p[2]) });
            truth_lines.push(line);
        }
        if let Some(oc) = &odom_cols
            && let Some(p) = group(&rec, oc, line)?
        {
            odom.push(StampedPose { t_s: t, pose: Pose2::new(p[0], p[1], p[2]) });
        }
    }
    if ticks && wheel_t.len() >= 2 {
        let k = 2.0 * PI / tpr;
        for s in 0..wheel_t.len() {
            let dt = if s == 0 { wheel_t[1] - wheel_t[0] } else { wheel_t[s] - wheel_t[s - 1] };
            for v in &mut wheel[s * n_w..(s + 1) * n_w] {
                *v = *v * k / dt;
            }
        }
    }
    if let Some(external) = external.as_mut() {
        truth = external(&wheel_t, &wheel, n_w)?;
    }
    unwrap_headings(&mut truth);
    let command = match (meta_num("command_v_m_s")?, meta_num("command_alpha_rad")?, meta_num("command_omega_rad_s")?) {
        (Some(v), Some(a), Some(w)) => Some(Command { v_m_s: v, alpha_rad: a, omega_rad_s: w }),
        (None, None, None) => None,
        _ => {
            return Err(DatasetError::file(
                path,
                "command needs all of command_v_m_s, command_alpha_rad, command_omega_rad_s",
            ));
        }
    };
    let repetition = match meta.get("repetition") {
        Some((line, v)) => Some(v.parse::<u32>().map_err(|_| {
            DatasetError::at(path, format!("line {line}"), format!("repetition {v:?} is not a whole number"))
        })?),
        None => None,
    };
    let wheel_start_rad = match meta.get("wheel_start_rad") {
        Some((line, v)) => {
            v.split(',').map(|c| parse_num(path, *line, "wheel_start_rad", c)).collect::<Result<Vec<_>, _>>()?
        }
        None => Vec::new(),
    };
    let name = meta.get("name").map(|(_, v)| v.clone()).unwrap_or_else(|| {
        path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| path.display().to_string())
    });
    Run::new(RunData {
        name,
        wheel_t_s: wheel_t,
        wheel_rad_s: wheel,
        n_wheels: n_w,
        truth,
        command,
        repetition,
        recorded_odometry: odom,
        wheel_start_rad,
        truth_position_only: false,
    })
    .map_err(|error| {
        // A bad sample or pose is located by its line.
        let at = match &error {
            KinError::NonFinite { what, index, .. }
            | KinError::NotIncreasing { what, index, .. }
            | KinError::Implausible { what, index, .. } => match *what {
                Sample::Wheel => wheel_lines.get(*index),
                Sample::Truth => truth_lines.get(*index),
            },
            _ => None,
        };
        match at {
            Some(line) => DatasetError::at(path, format!("line {line}"), error.to_string()),
            None => DatasetError::Run { path: path.to_path_buf(), error },
        }
    })
}

/// Write a run in the omnical CSV format (rad/s columns, shortest round-trip floats), atomically.
pub fn write_run(path: &Path, run: &Run, wheel_names: &[String]) -> Result<(), DatasetError> {
    let n_w = run.n_wheels();
    let names: Vec<String> =
        (0..n_w).map(|i| wheel_names.get(i).cloned().unwrap_or_else(|| format!("wheel_{i}"))).collect();
    atomic::with_atomic_writer(path, |w| {
        writeln!(w, "# omnical run v1")?;
        writeln!(w, "# name: {}", run.name())?;
        if let Some(c) = run.command() {
            writeln!(w, "# command_v_m_s: {}", c.v_m_s)?;
            writeln!(w, "# command_alpha_rad: {}", c.alpha_rad)?;
            writeln!(w, "# command_omega_rad_s: {}", c.omega_rad_s)?;
        }
        if let Some(r) = run.repetition() {
            writeln!(w, "# repetition: {r}")?;
        }
        if !run.wheel_start_rad().is_empty() {
            let v: Vec<String> = run.wheel_start_rad().iter().map(|v| v.to_string()).collect();
            writeln!(w, "# wheel_start_rad: {}", v.join(","))?;
        }
        let has_odom = !run.recorded_odometry().is_empty();
        let mut header = vec!["t_s".to_string()];
        header.extend(names.iter().map(|n| format!("{n}_rad_s")));
        header.extend(POSE.iter().map(|s| s.to_string()));
        if has_odom {
            header.extend(ODOM.iter().map(|s| s.to_string()));
        }
        writeln!(w, "{}", header.join(","))?;
        // Merge wheel samples, truth and odometry by time: one row per distinct stamp.
        let (t, truth, odom) = (run.wheel_t_s(), run.truth(), run.recorded_odometry());
        let (mut i, mut j, mut k) = (0, 0, 0);
        let pose_cells = |p: &Pose2| format!(",{},{},{}", p.x_m, p.y_m, p.theta_rad);
        while i < t.len() || j < truth.len() || k < odom.len() {
            let tw = t.get(i).copied().unwrap_or(f64::INFINITY);
            let tg = truth.get(j).map_or(f64::INFINITY, |p| p.t_s);
            let to = odom.get(k).map_or(f64::INFINITY, |p| p.t_s);
            let time = tw.min(tg).min(to);
            let mut row = time.to_string();
            if tw == time {
                for v in run.wheel_sample(i) {
                    row.push(',');
                    row.push_str(&v.to_string());
                }
                i += 1;
            } else {
                row.push_str(&",".repeat(n_w));
            }
            if tg == time {
                row.push_str(&pose_cells(&truth[j].pose));
                j += 1;
            } else {
                row.push_str(",,,");
            }
            if has_odom {
                if to == time {
                    row.push_str(&pose_cells(&odom[k].pose));
                    k += 1;
                } else {
                    row.push_str(",,,");
                }
            }
            writeln!(w, "{row}")?;
        }
        Ok(())
    })
    .map_err(|e| DatasetError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn ticks_bom_crlf_and_sparse_rows() {
        let dir = tempfile::tempdir().unwrap();
        let text = "\u{feff}# ticks_per_rev: 1000\r\n# repetition: 2\r\nt_s,a_ticks,b_ticks,c_ticks,x_m,y_m,theta_rad\r\n\
                    0.00,0,0,0,0,0,3.1\r\n0.01,10,-5,5,,,\r\n0.02,10,-5,5,0.01,0,-3.1\r\n";
        let run = read_run(&write(dir.path(), "r.csv", text), None).unwrap();
        assert_eq!(run.n_samples(), 3);
        assert_eq!(run.truth().len(), 2);
        // 10 ticks in 10 ms at 1000 ticks/rev = 2π rad/s.
        assert!((run.wheel_sample(1)[0] - 2.0 * PI).abs() < 1e-12);
        // Heading unwrapped: 3.1 → −3.1 becomes 3.1 → 2π − 3.1.
        assert!((run.truth()[1].pose.theta_rad - (2.0 * PI - 3.1)).abs() < 1e-12);
        assert_eq!(run.repetition(), Some(2));
    }

    #[test]
    fn messages_name_file_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(dir.path(), "a.csv", "t_s,w_ticks,x_m,y_m,theta_rad\n0,1,0,0,0\n");
        assert_eq!(
            read_run(&p, None).unwrap_err().to_string(),
            format!(
                "{}: wheel columns are ticks but no ticks_per_rev is given (add '# ticks_per_rev: N' or --ticks-per-rev)",
                p.display()
            )
        );
        let p = write(dir.path(), "b.csv", "t_s,w_rad_s,x_m,y_m\n0,1,0,0\n");
        assert_eq!(
            read_run(&p, None).unwrap_err().to_string(),
            format!("{}: line 1: missing column theta_rad", p.display())
        );
        let p = write(dir.path(), "c.csv", "t_s,w_rad_s,x_m,y_m,theta_rad\n0,1,0,,0\n");
        assert_eq!(
            read_run(&p, None).unwrap_err().to_string(),
            format!("{}: line 2: partly filled row: y_m empty", p.display())
        );
    }

    #[test]
    fn write_then_read_is_bit_exact() {
        let dir = tempfile::tempdir().unwrap();
        let d = RunData {
            name: "x/run-1".into(),
            wheel_t_s: vec![0.0, 0.1 + 0.2, 0.7],
            wheel_rad_s: vec![1.0 / 3.0, -2.5e-17, 7.0, 0.1, 0.2, 0.3],
            n_wheels: 2,
            truth: vec![
                StampedPose { t_s: 0.0, pose: Pose2::new(0.1, 0.2, 0.3) },
                StampedPose { t_s: 0.7, pose: Pose2::new(1.0 / 7.0, 2.0, -0.5) },
            ],
            command: Some(Command { v_m_s: 0.2, alpha_rad: 0.523, omega_rad_s: -0.35 }),
            repetition: Some(4),
            recorded_odometry: vec![
                StampedPose { t_s: 0.05, pose: Pose2::new(0.01, 0.0, 0.001) },
                StampedPose { t_s: 0.7, pose: Pose2::new(0.2, -0.1, 0.5) },
            ],
            wheel_start_rad: vec![0.25, 6.0],
            truth_position_only: false,
        };
        let run = Run::new(d).unwrap();
        let p = dir.path().join("r.csv");
        write_run(&p, &run, &["a".into(), "b".into()]).unwrap();
        assert_eq!(read_run(&p, None).unwrap(), run);
    }
}
