//! Ground truth from a separate file (`--gt PATH`, or `[ground_truth] file` in robot.toml): a motion
//! capture or SLAM trajectory recorded apart from the robot, usually on another clock.
//!
//! # Formats (by extension)
//! - **TUM** (`.tum`, `.txt`; evo's `read_tum_trajectory_file`): `t x y z qx qy qz qw` per line, space
//!   separated, exactly 8 columns; `#` comments and blank lines are skipped. t in s (read as a decimal, exact
//!   to the nanosecond whatever the epoch; exponent notation as float64), x, y in m, quaternion with **qw
//!   last**. z is ignored.
//! - **CSV** (`.csv`) with a header row. Columns by name ([`CsvColumns`], from `--gt-columns` or
//!   robot.toml): time, x, y and either a heading (`yaw`) or a quaternion (`qx`, `qy`, `qz`, `qw`), in the
//!   units given (`--gt-units time=ns,length=mm,angle=deg`; default s, m, rad). Other columns are ignored.
//!
//! The heading is unwrapped so it is continuous. Rows must have strictly increasing times and finite values;
//! errors name the file, the line and the column.
//!
//! # Matching files to recordings
//! `PATH` is a file when one recording is read, or a folder holding `<recording>.tum` or `<recording>.csv`
//! per recording (the recording's folder name, or the bag file's stem).
//!
//! The clock offset between the file and the wheel data is estimated ([`omni_kin::clock`]) unless
//! [`GroundTruthOptions::time_offset_s`] forces it.
//!
//! # Submodules
//! - `options.rs`: [`GroundTruthOptions`] and [`CsvColumns`]: the file, a forced offset, CSV columns, units;
//!   [`CsvColumnsError`].
//! - `formats.rs`: the TUM and CSV readers, row by row, and [`parse_stamp_ns`].

mod formats;
mod options;

pub use formats::parse_stamp_ns;
pub use options::{CsvColumns, CsvColumnsError, GroundTruthOptions, TimeUnit};

use crate::api::settings::named;
use crate::dataset::DatasetError;
use formats::{read_csv, read_tum, unwrap_yaw};
use std::path::{Path, PathBuf};

/// One ground-truth pose, on the file's clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSample {
    /// Time. ns (on the file's clock).
    pub t_ns: i64,
    /// Position. m.
    pub x_m: f64,
    /// Position. m.
    pub y_m: f64,
    /// Heading, unwrapped. rad. 0 in a position-only file ([`ExternalTruth::position_only`]).
    pub yaw_rad: f64,
}

/// A ground-truth file, read, for one recording.
#[derive(Clone, Debug, PartialEq)]
pub struct ExternalTruth {
    /// The file.
    pub path: PathBuf,
    /// Its poses, in time order.
    pub samples: Vec<TruthSample>,
    /// The forced clock offset, if any. s.
    pub time_offset_s: Option<f64>,
    /// When no file of a `--gt` folder is named after the recording: every file of the folder, read, to be
    /// matched to each run by time overlap ([`ExternalTruth::overlapping`]). Empty otherwise.
    pub by_time: Vec<(PathBuf, Vec<TruthSample>)>,
    /// The file gives positions without a heading (UWB, GNSS, a tracker without heading: a CSV with no
    /// heading column, or `--gt-columns t,x,y`); its headings are 0 and never compared.
    pub position_only: bool,
}

/// The share of a run's span a ground-truth file must cover to be matched to it by time.
pub const MIN_TIME_OVERLAP: f64 = 0.5;

impl ExternalTruth {
    /// The file of the folder whose poses cover most of the absolute span `[t0_ns, t1_ns]` of a run (at
    /// least [`MIN_TIME_OVERLAP`]), as the truth to read the run with, and the share covered; or an error
    /// listing each file's span.
    pub fn overlapping(&self, t0_ns: i64, t1_ns: i64) -> Result<(Self, f64), String> {
        let span = (t1_ns - t0_ns).max(1) as f64;
        let cover = |s: &[TruthSample]| match (s.first(), s.last()) {
            (Some(a), Some(b)) => (b.t_ns.min(t1_ns) - a.t_ns.max(t0_ns)).max(0) as f64 / span,
            _ => 0.0,
        };
        let best = self.by_time.iter().map(|(p, s)| (p, s, cover(s))).max_by(|a, b| a.2.total_cmp(&b.2));
        match best {
            Some((path, samples, share)) if share >= MIN_TIME_OVERLAP => Ok((
                Self {
                    path: path.clone(),
                    samples: samples.clone(),
                    time_offset_s: self.time_offset_s,
                    by_time: vec![],
                    position_only: self.position_only,
                },
                share,
            )),
            _ => {
                let secs = |ns: i64| ns as f64 * 1e-9;
                let spans: Vec<String> = self
                    .by_time
                    .iter()
                    .map(|(p, s)| {
                        let name =
                            p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into());
                        format!("{name} {:.3}..{:.3} s", secs(s[0].t_ns), secs(s[s.len() - 1].t_ns))
                    })
                    .collect();
                Err(format!(
                    "no ground-truth file is named after it and none covers half of its span {:.3}..{:.3} s (files: \
                     {}); name the file after the recording, or give it with --gt FILE",
                    secs(t0_ns),
                    secs(t1_ns),
                    spans.join(", ")
                ))
            }
        }
    }
}

/// The clock offset a recording's ground-truth file was read with.
#[derive(Clone, Debug, PartialEq)]
pub struct GtClock {
    /// The recording's name.
    pub recording: String,
    /// The ground-truth file.
    pub file: PathBuf,
    /// `t_wheel = t_truth + offset_s`: added to the file's stamps. s.
    pub offset_s: f64,
    /// The estimate (offset, standard error, fit), or `None` when the offset was forced.
    pub estimate: Option<omni_kin::clock::ClockAlignment>,
    /// Why the estimate was not applied, when it was not: the stamps are kept as recorded (`offset_s` 0)
    /// and the note ([`GtClock::describe`]) says so.
    pub kept: Option<Kept>,
}

/// Why a clock estimate was not applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kept {
    /// It is not clear ([`omni_kin::clock::ClockAlignment::is_clear`]).
    Unclear,
    /// It is clear but longer than the recording while the stamps overlap as recorded.
    Implausible,
    /// There is none: the file gives positions only, and the estimate needs a heading.
    PositionOnly,
}

impl GtClock {
    /// One line for stderr: `ground truth F for recording R: clock offset +3.2170 s ± 0.4 ms (estimated …)`.
    pub fn describe(&self) -> String {
        let head = format!(
            "ground truth {} for recording {}: clock offset {:+.4} s",
            self.file.display(),
            self.recording,
            self.offset_s
        );
        match &self.estimate {
            None if self.kept == Some(Kept::PositionOnly) => format!(
                "{head}: stamps kept as recorded, since a file of positions only (no heading column, or a heading \
                 that never changes) gives no heading to estimate the offset with; give it with --gt-time-offset \
                 SECONDS if the clocks differ (diagnose names a clock offset that the path shows)"
            ),
            None => format!("{head} (forced; wheel time = ground-truth time + offset)"),
            Some(a) if self.kept.is_some() => format!(
                "{head}: stamps kept as recorded, since the estimate, {:+.4} s ± {:.2} ms explaining {:.1} % of the \
                 ground truth's motion, {}; give the offset with --gt-time-offset SECONDS if it is known",
                a.offset_s,
                a.std_error_s * 1e3,
                a.r_squared * 100.0,
                match self.kept {
                    Some(Kept::Implausible) => "is longer than the recording".to_string(),
                    _ => format!(
                        "is not clear (a clear one has a standard error of at most {:.0} ms and explains at least \
                         {:.0} %)",
                        omni_kin::clock::CLEAR_MAX_STD_ERROR_S * 1e3,
                        omni_kin::clock::CLEAR_MIN_R_SQUARED * 100.0
                    ),
                }
            ),
            Some(a) => format!(
                "{head} ± {:.2} ms (estimated: coarse {:+.3} s on a {:.0} ms grid, refined; explains {:.1} % of the \
                 ground truth's motion over {:.1} s; wheel time = ground-truth time + offset)",
                a.std_error_s * 1e3,
                a.coarse_offset_s,
                a.step_s * 1e3,
                a.r_squared * 100.0,
                a.overlap_s
            ),
        }
    }

    /// The JSON object of `--json` outputs.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "recording": self.recording,
            "file": self.file.display().to_string(),
            "offset_s": self.offset_s,
            "std_error_s": self.estimate.map(|a| a.std_error_s),
            "estimated": self.estimate.is_some(),
            "clear": self.estimate.map(|a| a.is_clear()),
            "applied": self.kept.is_none(),
            "r_squared": self.estimate.map(|a| a.r_squared),
        })
    }
}

/// The ground-truth file for the recording named `name` at `recording`: `opts.path` itself when it is a
/// file, else `<name>.tum`, `<name>.txt` or `<name>.csv` in that folder.
pub fn file_for(opts: &GroundTruthOptions, recording: &Path, name: &str) -> Result<PathBuf, DatasetError> {
    if !opts.path.is_dir() {
        return Ok(opts.path.clone());
    }
    for ext in ["tum", "txt", "csv"] {
        let p = opts.path.join(format!("{name}.{ext}"));
        if p.is_file() {
            return Ok(p);
        }
    }
    Err(DatasetError::file(
        recording,
        format!(
            "no ground-truth file for recording {name:?} in {} folder {} (expected {name}.tum, {name}.txt or \
             {name}.csv)",
            named("gt"),
            opts.path.display()
        ),
    ))
}

/// Reads the ground truth for the recording named `name` at `recording`.
/// When no file is named after the recording, every file of a `--gt` folder is read, to be matched to the
/// recording's runs by time ([`ExternalTruth::overlapping`]); a folder without such files is the error
/// [`file_for`] gives.
pub fn read_for(opts: &GroundTruthOptions, recording: &Path, name: &str) -> Result<ExternalTruth, DatasetError> {
    let path = match file_for(opts, recording, name) {
        Ok(path) => path,
        Err(e) => {
            let mut position_only = false;
            let by_time = folder_files(&opts.path)
                .into_iter()
                .map(|p| {
                    let (samples, positions) = read_file(&p, &opts.csv)?;
                    position_only |= positions;
                    Ok((p, samples))
                })
                .collect::<Result<Vec<_>, DatasetError>>()?;
            if by_time.is_empty() {
                return Err(e);
            }
            return Ok(ExternalTruth {
                path: opts.path.clone(),
                samples: vec![],
                time_offset_s: opts.time_offset_s,
                by_time,
                position_only,
            });
        }
    };
    let (samples, position_only) = read_file(&path, &opts.csv)?;
    Ok(ExternalTruth { path, samples, time_offset_s: opts.time_offset_s, by_time: vec![], position_only })
}

/// The ground-truth files (`.tum`, `.txt`, `.csv`) of a folder, sorted; none when it is not a folder.
fn folder_files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else { return vec![] };
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_file() && p.extension().and_then(|e| e.to_str()).is_some_and(|e| ["tum", "txt", "csv"].contains(&e))
        })
        .collect();
    files.sort();
    files
}

/// Reads a ground-truth file (TUM or CSV, by extension).
pub fn read(path: &Path, csv: &CsvColumns) -> Result<Vec<TruthSample>, DatasetError> {
    Ok(read_file(path, csv)?.0)
}

/// [`read`], and whether the file gives positions only (a CSV without a heading; headings 0).
pub fn read_file(path: &Path, csv: &CsvColumns) -> Result<(Vec<TruthSample>, bool), DatasetError> {
    let text = super::read_text(path)?;
    let mut uprights = Vec::new();
    let (mut samples, hint) = match path.extension().and_then(|e| e.to_str()) {
        Some("csv") => (read_csv(path, &text, csv, &mut uprights)?, "--gt-units length=mm (or cm)"),
        _ => (read_tum(path, &text, &mut uprights)?, "a TUM file holds metres: convert it"),
    };
    // No heading column, or a heading written but never changing (a fixed quaternion beside GNSS or UWB).
    let position_only = samples.iter().any(|s| s.yaw_rad.is_nan())
        || omni_kin::position_only::heading_never_changes(samples.iter().map(|s| (s.x_m, s.y_m, s.yaw_rad)));
    if position_only {
        samples.iter_mut().for_each(|s| s.yaw_rad = 0.0);
    }
    if samples.len() < 2 {
        return Err(DatasetError::file(path, format!("has {} poses; at least 2 are needed", samples.len())));
    }
    plausible(path, &samples, &uprights, hint)?;
    unwrap_yaw(&mut samples);
    Ok((samples, position_only))
}

/// Fastest plausible ground robot, as the 90th percentile of the speeds between poses. m/s.
pub const MAX_PLAUSIBLE_SPEED_M_S: f64 = 30.0;

/// Largest median tilt of the poses from upright (body z against world z) a ground robot's ground truth may
/// show. deg.
pub const MAX_MEDIAN_TILT_DEG: f64 = 30.0;

/// Refuses ground truth no ground robot can have: positions whose speeds say they are not in metres, and
/// orientations that are not about z (`uprights`: the z component of the body's z axis per quaternion pose,
/// `1 − 2(qx² + qy²)`; empty for a heading column).
fn plausible(path: &Path, samples: &[TruthSample], uprights: &[f64], units_hint: &str) -> Result<(), DatasetError> {
    let mut speeds: Vec<f64> = samples
        .windows(2)
        .map(|w| (w[1].x_m - w[0].x_m).hypot(w[1].y_m - w[0].y_m) / ((w[1].t_ns - w[0].t_ns) as f64 * 1e-9))
        .collect();
    speeds.sort_by(f64::total_cmp);
    let p90 = speeds[(speeds.len() * 9 / 10).min(speeds.len() - 1)];
    if p90 > MAX_PLAUSIBLE_SPEED_M_S {
        return Err(DatasetError::file(
            path,
            format!(
                "moves at {p90:.3e} m/s (90th percentile between poses), more than any ground robot ({} m/s): \
                 are the positions in millimetres? {units_hint}; or is the time column in another unit?",
                MAX_PLAUSIBLE_SPEED_M_S
            ),
        ));
    }
    if !uprights.is_empty() {
        let mut tilts: Vec<f64> = uprights.iter().map(|u| u.clamp(-1.0, 1.0).acos().to_degrees()).collect();
        tilts.sort_by(f64::total_cmp);
        let median = tilts[tilts.len() / 2];
        if median > MAX_MEDIAN_TILT_DEG {
            return Err(DatasetError::file(
                path,
                format!(
                    "its orientations are tilted {median:.0}° from upright (median), but a ground robot turns about \
                     z: is the quaternion written w first? The order is qx qy qz qw (w last)"
                ),
            ));
        }
    }
    Ok(())
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_are_exact_decimals() {
        assert_eq!(parse_stamp_ns("1700000000.250000001", 1_000_000_000), Some(1_700_000_000_250_000_001));
        assert_eq!(parse_stamp_ns("1700000000036.5", 1_000_000), Some(1_700_000_000_036_500_000));
        assert_eq!(parse_stamp_ns("-1.5", 1_000_000_000), Some(-1_500_000_000));
        assert_eq!(parse_stamp_ns("1.700000000019999981e+09", 1_000_000_000), Some(1_700_000_000_020_000_000));
        assert_eq!(parse_stamp_ns("12a", 1), None);
        assert_eq!(parse_stamp_ns("nan", 1), None);
    }

    #[test]
    fn tum_and_csv_give_the_same_poses() {
        let tum = "# t x y z qx qy qz qw\n1.0 1 2 0 0 0 0 1\n2.5 1.5 2 0 0 0 0.7071067811865476 0.7071067811865476\n";
        let a = read_tum(Path::new("a.tum"), tum, &mut Vec::new()).unwrap();
        let csv = "n,stamp_ms,px,py,heading\n0,1000,1000,2000,0\n1,2500,1500,2000,90\n";
        let mut cols = CsvColumns::default();
        for (k, v) in [("t", "stamp_ms"), ("x", "px"), ("y", "py"), ("yaw", "heading")] {
            cols.set_column(k, v).unwrap();
        }
        for (k, v) in [("time", "ms"), ("length", "mm"), ("angle", "deg")] {
            cols.set_unit(k, v).unwrap();
        }
        let b = read_csv(Path::new("a.csv"), csv, &cols, &mut Vec::new()).unwrap();
        assert_eq!(a.len(), 2);
        for (p, q) in a.iter().zip(&b) {
            assert_eq!(p.t_ns, q.t_ns);
            assert!((p.x_m - q.x_m).abs() < 1e-12 && (p.y_m - q.y_m).abs() < 1e-12);
            assert!((p.yaw_rad - q.yaw_rad).abs() < 1e-12, "{p:?} {q:?}");
        }
        assert!((a[1].yaw_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn bad_rows_are_named() {
        let err = |text: &str| read_tum(Path::new("g.tum"), text, &mut Vec::new()).unwrap_err().to_string();
        assert_eq!(err("1 0 0 0 0 0 0 1\n2 nan 0 0 0 0 0 1\n"), "g.tum: line 2, column x: value NaN is not finite");
        assert_eq!(
            err("1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n"),
            "g.tum: line 2: time 0.500000000 s is not after the previous row's 1.000000000 s (times must increase)"
        );
        assert_eq!(err("1 0 0 0 0 0 1\n"), "g.tum: line 1: has 7 columns; TUM has 8: t x y z qx qy qz qw");
        assert_eq!(err("1 0 0 0 0 0 0 0\n"), "g.tum: line 1: the quaternion has norm 0, not 1");
        let e = read_csv(Path::new("g.csv"), "a,b\n1,2\n", &CsvColumns::default(), &mut Vec::new())
            .unwrap_err()
            .to_string();
        let e = crate::api::settings::as_flags(&e);
        assert_eq!(
            e,
            "g.csv: no column \"t\" for the time (columns: a, b); name it with --gt-columns or [ground_truth] in \
             robot.toml"
        );
    }

    /// A ground robot driving a 1 m circle at 0.5 m/s for 4 s, at 50 Hz: TUM text, the quaternion written
    /// `w_first` or last, positions times `scale`.
    fn circle_tum(scale: f64, w_first: bool) -> String {
        let mut text = String::new();
        for k in 0..200 {
            let t = 0.02 * k as f64;
            let yaw = 0.5 * t;
            let (x, y) = (scale * yaw.sin(), scale * (1.0 - yaw.cos()));
            let (qz, qw) = ((0.5 * yaw).sin(), (0.5 * yaw).cos());
            let q = if w_first { format!("{qw} 0 0 {qz}") } else { format!("0 0 {qz} {qw}") };
            text.push_str(&format!("{t} {x} {y} 0 {q}\n"));
        }
        text
    }

    #[test]
    fn ground_truth_no_ground_robot_can_have_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let read_text = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            read(&p, &CsvColumns::default())
                .map_err(|e| e.to_string().replace(&format!("{}/", dir.path().display()), ""))
        };
        let good = read_text("good.tum", &circle_tum(1.0, false)).unwrap();
        assert!((good[199].yaw_rad - 0.5 * 3.98).abs() < 1e-9);
        assert_eq!(
            read_text("mm.tum", &circle_tum(1000.0, false)).unwrap_err(),
            "mm.tum: moves at 5.000e2 m/s (90th percentile between poses), more than any ground robot (30 m/s): are \
             the positions in millimetres? a TUM file holds metres: convert it; or is the time column in another unit?"
        );
        assert_eq!(
            read_text("wfirst.tum", &circle_tum(1.0, true)).unwrap_err(),
            "wfirst.tum: its orientations are tilted 123° from upright (median), but a ground robot turns about z: is \
             the quaternion written w first? The order is qx qy qz qw (w last)"
        );
    }
}
