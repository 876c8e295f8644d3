//! The rows of an omnical CSV run: each a wheel sample, a ground-truth pose, a recorded odometry pose, or
//! several, each cell checked with a message naming its line and column; tick counts turned into speeds.

use super::header::Columns;
use super::parse_num;
use crate::dataset::DatasetError;
use omni_kin::error::Sample;
use omni_kin::run::MAX_HEADING_RAD;
use omni_kin::{KinError, Pose2, StampedPose};
use std::f64::consts::PI;
use std::path::Path;

/// What a run file's rows hold, in file order.
pub(super) struct Rows {
    /// Each wheel sample's time, as written. s.
    pub(super) wheel_t_s: Vec<f64>,
    /// The wheel cells, one per wheel per sample, row-major: rad/s, or ticks until
    /// [`Rows::speeds_from_ticks`].
    pub(super) wheel: Vec<f64>,
    /// The ground-truth poses.
    pub(super) truth: Vec<StampedPose>,
    /// The recorded odometry poses.
    pub(super) odom: Vec<StampedPose>,
    /// The line of each wheel sample and ground-truth pose.
    pub(super) lines: RowLines,
}

/// The line of each wheel sample and ground-truth pose, for locating `Run::new`'s errors.
pub(super) struct RowLines {
    /// The line of each wheel sample.
    wheel: Vec<usize>,
    /// The line of each ground-truth pose.
    truth: Vec<usize>,
}

/// Read every row after the header (at `header_line`) from `reader`, the cells from `cols`. A row of empty
/// cells is skipped; an error names the file, the line and, for a cell, the column.
pub(super) fn read_rows<R: std::io::Read>(
    path: &Path,
    reader: &mut csv::Reader<R>,
    cols: &Columns,
    header_line: usize,
) -> Result<Rows, DatasetError> {
    let (mut wheel_t, mut wheel, mut truth, mut odom) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut wheel_lines, mut truth_lines) = (Vec::new(), Vec::new());
    let headers = &cols.headers;
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
        let t = parse_num(path, line, "t_s", rec.get(cols.t).unwrap_or(""))?;
        if let Some(w) = group(path, headers, &rec, &cols.wheel, line)? {
            wheel_t.push(t);
            wheel.extend(w);
            wheel_lines.push(line);
        }
        if let Some(p) = group(path, headers, &rec, &cols.pose, line)? {
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
        if let Some(oc) = &cols.odom
            && let Some(p) = group(path, headers, &rec, oc, line)?
        {
            odom.push(StampedPose { t_s: t, pose: Pose2::new(p[0], p[1], p[2]) });
        }
    }
    let lines = RowLines { wheel: wheel_lines, truth: truth_lines };
    Ok(Rows { wheel_t_s: wheel_t, wheel, truth, odom, lines })
}

/// The cells of a column group (`cols` of `headers`) in this row: all empty → `None`; all filled → their
/// values; partly filled or not a number → an error naming the line (and the column).
fn group(
    path: &Path,
    headers: &[String],
    rec: &csv::StringRecord,
    cols: &[usize],
    line: usize,
) -> Result<Option<Vec<f64>>, DatasetError> {
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
}

impl Rows {
    /// Tick counts since the previous sample (`n_w` per sample) as speeds: ticks · 2π / `ticks_per_rev` /
    /// Δt, the first sample using the second's Δt. Fewer than two samples are left as they are.
    pub(super) fn speeds_from_ticks(&mut self, n_w: usize, ticks_per_rev: f64) {
        let (wheel_t, wheel) = (&self.wheel_t_s, &mut self.wheel);
        if wheel_t.len() >= 2 {
            let k = 2.0 * PI / ticks_per_rev;
            for s in 0..wheel_t.len() {
                let dt = if s == 0 { wheel_t[1] - wheel_t[0] } else { wheel_t[s] - wheel_t[s - 1] };
                for v in &mut wheel[s * n_w..(s + 1) * n_w] {
                    *v = *v * k / dt;
                }
            }
        }
    }
}

impl RowLines {
    /// `Run::new`'s `error` for the run read from `path`: a bad sample or pose located by its line.
    pub(super) fn locate(&self, path: &Path, error: KinError) -> DatasetError {
        let at = match &error {
            KinError::NonFinite { what, index, .. }
            | KinError::NotIncreasing { what, index, .. }
            | KinError::Implausible { what, index, .. } => match *what {
                Sample::Wheel => self.wheel.get(*index),
                Sample::Truth => self.truth.get(*index),
            },
            _ => None,
        };
        match at {
            Some(line) => DatasetError::at(path, format!("line {line}"), error.to_string()),
            None => DatasetError::Run { path: path.to_path_buf(), error },
        }
    }
}
