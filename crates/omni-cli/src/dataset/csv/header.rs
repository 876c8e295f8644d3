//! The head of an omnical CSV run: the `# key: value` metadata lines, then the header row resolved to the
//! columns each part of a row (time, wheels, ground truth, recorded odometry) is read from.

use super::{ODOM, POSE, parse_num};
use crate::api::settings::named;
use crate::dataset::DatasetError;
use std::collections::BTreeMap;
use std::path::Path;

/// The metadata comments (and blank lines) before the header row.
pub(super) struct Preamble {
    /// Each `# key: value` line's value with its line number, by key.
    pub(super) meta: BTreeMap<String, (usize, String)>,
    /// Where the header row starts in the text. Bytes.
    pub(super) body_start: usize,
    /// The header row's line number (from 1).
    pub(super) header_line: usize,
}

impl Preamble {
    /// The comment and blank lines at the top of `text`, up to the header row.
    pub(super) fn read(text: &str) -> Self {
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
        Preamble { meta, body_start, header_line }
    }

    /// Metadata `key` as a number (`None` when absent); an error names its line.
    pub(super) fn number(&self, path: &Path, key: &str) -> Result<Option<f64>, DatasetError> {
        match self.meta.get(key) {
            Some((line, v)) => parse_num(path, *line, key, v).map(Some),
            None => Ok(None),
        }
    }
}

/// The header row's trimmed names; an unreadable row is an error naming its line.
pub(super) fn read_headers<R: std::io::Read>(
    path: &Path,
    reader: &mut csv::Reader<R>,
    header_line: usize,
) -> Result<Vec<String>, DatasetError> {
    Ok(reader
        .headers()
        .map_err(|e| DatasetError::at(path, format!("line {header_line}"), e.to_string()))?
        .iter()
        .map(|h| h.trim().to_string())
        .collect())
}

/// Where each part of a row is read from, resolved once from the header row.
pub(super) struct Columns {
    /// The header row's names, for messages.
    pub(super) headers: Vec<String>,
    /// The time column, `t_s`.
    pub(super) t: usize,
    /// The wheel columns, in the robot's joint order when one is given.
    pub(super) wheel: Vec<usize>,
    /// The wheel columns hold tick counts (`_ticks`) rather than speeds (`_rad_s`).
    pub(super) ticks: bool,
    /// Encoder ticks per wheel revolution (1 when the columns are speeds).
    pub(super) ticks_per_rev: f64,
    /// The ground-truth pose columns (`x_m`, `y_m`, `theta_rad`); none when the poses come from elsewhere.
    pub(super) pose: Vec<usize>,
    /// The recorded odometry columns, when the file has all three.
    pub(super) odom: Option<Vec<usize>>,
}

impl Columns {
    /// The columns of `headers` (at line `preamble.header_line`): `ticks_per_rev` overrides the file's,
    /// `joints` orders the wheel columns, and `external` says the ground truth comes from elsewhere (so the
    /// file must have no pose columns). Each error names the file and the header line.
    pub(super) fn resolve(
        path: &Path,
        preamble: &Preamble,
        headers: Vec<String>,
        ticks_per_rev: Option<f64>,
        joints: &[String],
        external: bool,
    ) -> Result<Self, DatasetError> {
        let header_line = preamble.header_line;
        if headers.iter().all(|h| h.is_empty()) {
            return Err(DatasetError::at(
                path,
                format!("line {header_line}"),
                "no header row (expected t_s, wheel columns <joint>_rad_s or <joint>_ticks, x_m, y_m, theta_rad)",
            ));
        }
        let find = |name: &str| headers.iter().position(|h| h == name);
        let t = find("t_s").ok_or_else(|| {
            DatasetError::at(
                path,
                format!("line {header_line}"),
                format!("missing column t_s (columns: {}){}", headers.join(","), headerless_hint(path, &headers)),
            )
        })?;
        let (wheel, ticks) = wheel_columns(path, header_line, &headers)?;
        let wheel = joint_columns(path, header_line, &headers, wheel, ticks, joints)?;
        let ticks_per_rev = match (ticks, ticks_per_rev.or(preamble.number(path, "ticks_per_rev")?)) {
            (true, None) => {
                return Err(DatasetError::file(
                    path,
                    format!(
                        "wheel columns are ticks but no ticks_per_rev is given (add '# ticks_per_rev: N' or {})",
                        named("ticks_per_rev")
                    ),
                ));
            }
            (_, v) => v.unwrap_or(1.0),
        };
        let pose = pose_columns(path, header_line, &headers, external)?;
        let odom: Vec<Option<usize>> = ODOM.iter().map(|n| find(n)).collect();
        let odom: Option<Vec<usize>> = odom.into_iter().collect();
        Ok(Columns { t, wheel, ticks, ticks_per_rev, pose, odom, headers })
    }
}

/// The wheel columns of `headers` in the file's order, and whether they are ticks: all `_rad_s` or all
/// `_ticks`, at least one.
fn wheel_columns(path: &Path, header_line: usize, headers: &[String]) -> Result<(Vec<usize>, bool), DatasetError> {
    let rad_cols: Vec<usize> = (0..headers.len()).filter(|&i| headers[i].ends_with("_rad_s")).collect();
    let tick_cols: Vec<usize> = (0..headers.len()).filter(|&i| headers[i].ends_with("_ticks")).collect();
    match (rad_cols.is_empty(), tick_cols.is_empty()) {
        (false, true) => Ok((rad_cols, false)),
        (true, false) => Ok((tick_cols, true)),
        (true, true) => Err(DatasetError::at(
            path,
            format!("line {header_line}"),
            "no wheel columns: expected <joint>_rad_s or <joint>_ticks columns",
        )),
        (false, false) => {
            Err(DatasetError::at(path, format!("line {header_line}"), "mixes _rad_s and _ticks wheel columns"))
        }
    }
}

/// The ground-truth pose columns of `headers`: all three, or none when the poses come from elsewhere
/// (`external`).
fn pose_columns(
    path: &Path,
    header_line: usize,
    headers: &[String],
    external: bool,
) -> Result<Vec<usize>, DatasetError> {
    let pose_cols: Vec<Option<usize>> = POSE.iter().map(|n| headers.iter().position(|h| h == n)).collect();
    if external && pose_cols.iter().any(Option::is_some) {
        return Err(DatasetError::at(
            path,
            format!("line {header_line}"),
            format!(
                "has ground-truth columns of its own ({}), and {gt} gives another: drop {gt}, or remove the \
                 columns to use the {gt} file",
                POSE.join(", "),
                gt = named("gt")
            ),
        ));
    }
    if !external && pose_cols.iter().any(Option::is_none) {
        let missing: Vec<&str> = POSE.iter().zip(&pose_cols).filter(|(_, c)| c.is_none()).map(|(n, _)| *n).collect();
        return Err(DatasetError::at(
            path,
            format!("line {header_line}"),
            format!("missing column {}", missing.join(", ")),
        ));
    }
    Ok(pose_cols.into_iter().flatten().collect())
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
