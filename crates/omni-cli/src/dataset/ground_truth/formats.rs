//! The two file formats, line by line: TUM rows and CSV records into [`TruthSample`]s, with exact decimal
//! stamps, quaternion headings and errors naming the line and column; and the heading's unwrapping.

use super::{CsvColumns, TruthSample};
use crate::api::settings::named;
use crate::dataset::DatasetError;
use std::path::Path;

pub(super) fn read_tum(path: &Path, text: &str, uprights: &mut Vec<f64>) -> Result<Vec<TruthSample>, DatasetError> {
    const COLUMNS: [&str; 8] = ["t", "x", "y", "z", "qx", "qy", "qz", "qw"];
    let mut out: Vec<TruthSample> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        let at = |col: &str| format!("line {line_no}, column {col}");
        if fields.len() != 8 {
            return Err(DatasetError::at(
                path,
                format!("line {line_no}"),
                format!("has {} columns; TUM has 8: t x y z qx qy qz qw", fields.len()),
            ));
        }
        let t_ns = parse_stamp_ns(fields[0], 1_000_000_000)
            .ok_or_else(|| DatasetError::at(path, at("t"), format!("{:?} is not a time in seconds", fields[0])))?;
        let mut v = [0.0; 8];
        for c in 1..8 {
            v[c] = finite(path, &at(COLUMNS[c]), fields[c])?;
        }
        let yaw = yaw_of(path, &format!("line {line_no}"), [v[4], v[5], v[6], v[7]])?;
        uprights.push(upright([v[4], v[5], v[6], v[7]]));
        push(path, &mut out, line_no, TruthSample { t_ns, x_m: v[1], y_m: v[2], yaw_rad: yaw })?;
    }
    Ok(out)
}

pub(super) fn read_csv(
    path: &Path,
    text: &str,
    cols: &CsvColumns,
    uprights: &mut Vec<f64>,
) -> Result<Vec<TruthSample>, DatasetError> {
    let mut rdr = ::csv::ReaderBuilder::new().trim(::csv::Trim::All).from_reader(text.as_bytes());
    let header: Vec<String> = rdr
        .headers()
        .map_err(|e| DatasetError::file(path, format!("cannot read the header row: {e}")))?
        .iter()
        .map(String::from)
        .collect();
    let find = |name: &str| header.iter().position(|h| h == name);
    let need = |name: &str, what: &str| {
        find(name).ok_or_else(|| {
            DatasetError::file(
                path,
                format!(
                    "no column {name:?} for the {what} (columns: {}); name it with {} or [ground_truth] in \
                     robot.toml",
                    header.join(", "),
                    named("gt_columns")
                ),
            )
        })
    };
    let (ti, xi, yi) = (need(&cols.t, "time")?, need(&cols.x, "x position")?, need(&cols.y, "y position")?);
    let quaternion = ["qx", "qy", "qz", "qw"];
    let heading = match find(&cols.yaw) {
        _ if cols.yaw == CsvColumns::NO_HEADING => Heading::None,
        Some(i) => Heading::Yaw(i),
        None if quaternion.iter().all(|q| find(q).is_none()) => Heading::None,
        None => Heading::Quaternion([
            need("qx", "heading")?,
            need("qy", "heading")?,
            need("qz", "heading")?,
            need("qw", "heading")?,
        ]),
    };
    let mut out = Vec::new();
    for (r, record) in rdr.records().enumerate() {
        let line_no = r + 2;
        let record = record.map_err(|e| DatasetError::at(path, format!("line {line_no}"), e.to_string()))?;
        let field = |i: usize| record.get(i).unwrap_or("");
        let at = |i: usize| format!("line {line_no}, column {}", header[i]);
        let t_ns = parse_stamp_ns(field(ti), cols.time_unit.ns())
            .ok_or_else(|| DatasetError::at(path, at(ti), format!("{:?} is not a time", field(ti))))?;
        let x = finite(path, &at(xi), field(xi))? * cols.m_per_length_unit;
        let y = finite(path, &at(yi), field(yi))? * cols.m_per_length_unit;
        let yaw = match heading {
            // Marks a position-only file for `read_file`, which sets the headings to 0.
            Heading::None => f64::NAN,
            Heading::Yaw(i) => finite(path, &at(i), field(i))? * cols.rad_per_angle_unit,
            Heading::Quaternion(q) => {
                let mut v = [0.0; 4];
                for (k, &i) in q.iter().enumerate() {
                    v[k] = finite(path, &at(i), field(i))?;
                }
                uprights.push(upright(v));
                yaw_of(path, &format!("line {line_no}"), v)?
            }
        };
        push(path, &mut out, line_no, TruthSample { t_ns, x_m: x, y_m: y, yaw_rad: yaw })?;
    }
    Ok(out)
}

#[derive(Clone, Copy)]
enum Heading {
    /// Positions only.
    None,
    Yaw(usize),
    Quaternion([usize; 4]),
}

/// Appends a sample whose time must be after the previous one's.
fn push(path: &Path, out: &mut Vec<TruthSample>, line_no: usize, s: TruthSample) -> Result<(), DatasetError> {
    if let Some(prev) = out.last()
        && s.t_ns <= prev.t_ns
    {
        return Err(DatasetError::at(
            path,
            format!("line {line_no}"),
            format!(
                "time {} s is not after the previous row's {} s (times must increase)",
                seconds_text(s.t_ns),
                seconds_text(prev.t_ns)
            ),
        ));
    }
    out.push(s);
    Ok(())
}

fn seconds_text(ns: i64) -> String {
    format!("{}.{:09}", ns.div_euclid(1_000_000_000), ns.rem_euclid(1_000_000_000))
}

fn finite(path: &Path, at: &str, text: &str) -> Result<f64, DatasetError> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(DatasetError::at(path, at, format!("value {v} is not finite"))),
        Err(_) => Err(DatasetError::at(path, at, format!("{text:?} is not a number"))),
    }
}

/// Heading of a quaternion `[qx, qy, qz, qw]` (rotation about z). rad.
fn yaw_of(path: &Path, at: &str, q: [f64; 4]) -> Result<f64, DatasetError> {
    let [x, y, z, w] = q;
    let norm = (x * x + y * y + z * z + w * w).sqrt();
    if !(0.9..=1.1).contains(&norm) {
        return Err(DatasetError::at(path, at, format!("the quaternion has norm {norm}, not 1")));
    }
    // As the MCAP reader computes it (common.rs), so the same poses give the same bits.
    Ok((2.0 * (w * z + x * y)).atan2(w * w + x * x - y * y - z * z))
}

/// The z component of the body's z axis for a quaternion `[qx, qy, qz, qw]` (1 when upright), normalised.
fn upright(q: [f64; 4]) -> f64 {
    let [x, y, z, w] = q;
    1.0 - 2.0 * (x * x + y * y) / (x * x + y * y + z * z + w * w)
}

pub(super) fn unwrap_yaw(samples: &mut [TruthSample]) {
    use std::f64::consts::{PI, TAU};
    for k in 1..samples.len() {
        let prev = samples[k - 1].yaw_rad;
        let d = samples[k].yaw_rad - prev;
        samples[k].yaw_rad = prev + (d + PI).rem_euclid(TAU) - PI;
    }
}

/// A time in `unit_ns` nanoseconds per unit, read as a decimal (exact to the nanosecond); exponent notation
/// is read as float64.
pub fn parse_stamp_ns(text: &str, unit_ns: i64) -> Option<i64> {
    let text = text.trim();
    if text.contains(['e', 'E']) {
        let v = text.parse::<f64>().ok().filter(|v| v.is_finite())? * unit_ns as f64;
        return (v.abs() < 9.2e18).then(|| v.round() as i64);
    }
    let (neg, digits) = match text.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, text.strip_prefix('+').unwrap_or(text)),
    };
    let (int, frac) = digits.split_once('.').unwrap_or((digits, ""));
    if (int.is_empty() && frac.is_empty()) || !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit()) {
        return None;
    }
    let int: i128 = if int.is_empty() { 0 } else { int.parse().ok()? };
    let frac = &frac[..frac.len().min(18)];
    let frac_ns: i128 = if frac.is_empty() {
        0
    } else {
        let scale = 10i128.pow(frac.len() as u32);
        (frac.parse::<i128>().ok()? * i128::from(unit_ns) + scale / 2) / scale
    };
    let ns = int.checked_mul(i128::from(unit_ns))? + frac_ns;
    i64::try_from(if neg { -ns } else { ns }).ok()
}
