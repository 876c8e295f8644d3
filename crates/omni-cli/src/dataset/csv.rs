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

mod header;
mod rows;
#[cfg(test)]
mod tests;

use super::DatasetError;
use crate::atomic;
use header::{Columns, Preamble, read_headers};
pub use omni_kin::pose::unwrap_headings;
use omni_kin::{Command, Pose2, Run, RunData, StampedPose};
use rows::{Rows, read_rows};
use std::path::Path;

const POSE: [&str; 3] = ["x_m", "y_m", "theta_rad"];
const ODOM: [&str; 3] = ["odom_x_m", "odom_y_m", "odom_theta_rad"];

fn parse_num(path: &Path, line: usize, col: &str, cell: &str) -> Result<f64, DatasetError> {
    cell.trim()
        .parse::<f64>()
        .map_err(|_| DatasetError::at(path, format!("line {line}, column {col}"), format!("{cell:?} is not a number")))
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

/// [`parse_run_for`], the poses from `external` when given ([`read_run_with_truth`]): the metadata lines,
/// the header row resolved to columns, the rows, then the run assembled from them.
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
    let preamble = Preamble::read(text);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(false)
        .from_reader(&text.as_bytes()[preamble.body_start..]);
    let headers = read_headers(path, &mut reader, preamble.header_line)?;
    let cols = Columns::resolve(path, &preamble, headers, ticks_per_rev, joints, external.is_some())?;
    let mut rows = read_rows(path, &mut reader, &cols, preamble.header_line)?;
    let n_w = cols.wheel.len();
    if cols.ticks {
        rows.speeds_from_ticks(n_w, cols.ticks_per_rev);
    }
    if let Some(external) = external.as_mut() {
        rows.truth = external(&rows.wheel_t_s, &rows.wheel, n_w)?;
    }
    unwrap_headings(&mut rows.truth);
    assemble_run(path, &preamble, rows, n_w)
}

/// The run from its `rows` (`n_w` wheels, speeds) and the metadata of its `preamble` (command, repetition,
/// wheel start angles, name: the file's stem when not given); a bad sample or pose is named by its line.
fn assemble_run(path: &Path, preamble: &Preamble, rows: Rows, n_w: usize) -> Result<Run, DatasetError> {
    let meta = &preamble.meta;
    let number = |key: &str| preamble.number(path, key);
    let command = match (number("command_v_m_s")?, number("command_alpha_rad")?, number("command_omega_rad_s")?) {
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
    let Rows { wheel_t_s, wheel, truth, odom, lines } = rows;
    Run::new(RunData {
        name,
        wheel_t_s,
        wheel_rad_s: wheel,
        n_wheels: n_w,
        truth,
        command,
        repetition,
        recorded_odometry: odom,
        wheel_start_rad,
        truth_position_only: false,
    })
    .map_err(|error| lines.locate(path, error))
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
