//! OptiOdom datasets (Sousa et al. 2022): a set folder `<id>/` with `<id>_metadata.csv` (key, values…)
//! and `<id>_run-NN.csv` files without header: `time s, x_gt m, y_gt m, theta_gt rad (unwrapped), the
//! wheels' rotation in the control cycle` (encoder ticks; one column per wheel). Every row is both a wheel
//! sample and a ground-truth pose.
//!
//! Wheel speed = ticks · 2π / (ngear · encRes) / Δt. OptiOdom maps each cycle's wheel arc lengths
//! `s_i = π D_i ticks_i / (ngear · encRes) = (D_i/2) θ_i` to the robot-frame displacement with a fixed
//! nominal model per robot type; the design geometry below reproduces each exactly (its design IK matrix
//! is OptiOdom's model with `s_i = (D_i/2) θ_i`; tests to 1e-12):
//!
//! | `type` | wheel columns | OptiOdom's nominal model | design geometry |
//! |---|---|---|---|
//! | `omni3` | 1, 2, 3 | `dx = (√3/3)(s2 − s1)`, `dy = (2 s3 − s1 − s2)/3`, `dθ = −(s1 + s2 + s3)/(3 L)` | radius `D_i/2`, distance `Li`, wheels at δ = 300°, 60°, 180° driving clockwise |
//! | `omni4` | 1, 2, 3, 4 | `dx = (s1 − s2 + s3 − s4)/4`, `dy = (−s1 − s2 + s3 + s4)/4`, `dθ = −Σs/(2(l1 + l2))` | omni wheels at δ = 45°, 315°, 135°, 225° driving clockwise, radius `D_i/(2√2)`, distance `(l1 + l2)/(2√2)` |
//! | `diff` | right, left | `dx = (s_R + s_L)/2`, `dy = 0`, `dθ = (s_R − s_L)/b` | right wheel at δ = −90°, left at +90°, both driving forward, distance `b/2` (`Li` = b), radius `D_i/2` |
//!
//! The omni4 model is a least-squares inverse of four wheels pushing along ±45°; as a tangential
//! X-configuration it needs both the wheel radius and the distance scaled by 1/√2 against `D/2` and
//! `(l1 + l2)/2` (a plain X-configuration of radius `D/2` at distance `(l1 + l2)/2` turns the same but
//! translates √2 × farther). Other types (OptiOdom's tricycle) are refused with a message.

use super::DatasetError;
use super::csv::unwrap_headings;
use omni_kin::{Pose2, RobotGeometry, Run, RunData, StampedPose, Wheel};
use std::collections::BTreeMap;
use std::f64::consts::{FRAC_1_SQRT_2, PI};
use std::path::{Path, PathBuf};

/// The robot types this reader understands, as OptiOdom's metadata names them.
pub const SUPPORTED_TYPES: [&str; 3] = ["omni3", "omni4", "diff"];

/// The metadata file of a set folder, if it has one.
pub fn metadata_file(dir: &Path) -> Option<PathBuf> {
    let entries = std::fs::read_dir(dir).ok()?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().ends_with("_metadata.csv")))
        .collect();
    found.sort();
    found.into_iter().next()
}

/// Metadata rows by key: (line, values).
type Metadata = BTreeMap<String, (usize, Vec<String>)>;

fn read_metadata(path: &Path) -> Result<Metadata, DatasetError> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_path(path)
        .map_err(|e| DatasetError::file(path, e.to_string()))?;
    let mut m = BTreeMap::new();
    for (i, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| DatasetError::at(path, format!("line {}", i + 1), e.to_string()))?;
        let mut it = rec.iter();
        if let Some(key) = it.next() {
            let vals: Vec<String> = it.map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect();
            m.insert(key.trim().to_string(), (i + 1, vals));
        }
    }
    Ok(m)
}

/// The geometry OptiOdom's omni3 model implies.
pub fn omni3_geometry(wheel_radius_m: [f64; 3], distance_m: f64) -> RobotGeometry {
    let angles = [300f64, 60.0, 180.0];
    let wheels = angles
        .iter()
        .zip(wheel_radius_m)
        .map(|(a, r)| Wheel {
            radius_m: r,
            distance_m,
            angle_rad: a.to_radians(),
            drive_offset_rad: PI,
            roller_angle_rad: 0.0,
        })
        .collect();
    RobotGeometry { wheel_names: vec!["wheel_1".into(), "wheel_2".into(), "wheel_3".into()], wheels }
}

/// The geometry OptiOdom's omni4 model implies, from the metadata's diameters `D_i` and `Li = (l1, l2)`
/// (see the module docs for the 1/√2).
pub fn omni4_geometry(wheel_diameter_m: [f64; 4], l1_m: f64, l2_m: f64) -> RobotGeometry {
    let angles = [45f64, 315.0, 135.0, 225.0];
    let distance_m = (l1_m + l2_m) * 0.5 * FRAC_1_SQRT_2;
    let wheels = angles
        .iter()
        .zip(wheel_diameter_m)
        .map(|(a, d)| Wheel {
            radius_m: d * 0.5 * FRAC_1_SQRT_2,
            distance_m,
            angle_rad: a.to_radians(),
            drive_offset_rad: PI,
            roller_angle_rad: 0.0,
        })
        .collect();
    let wheel_names = (1..=4).map(|i| format!("wheel_{i}")).collect();
    RobotGeometry { wheel_names, wheels }
}

/// A differential drive: the right wheel (column 1) at δ = −90°, the left one at +90°, both driving
/// forward, `separation_m / 2` from the centre. Its forward matrix has rank 2 (no sideways motion).
pub fn diff_geometry(radius_right_m: f64, radius_left_m: f64, separation_m: f64) -> RobotGeometry {
    let half = 0.5 * separation_m;
    let right =
        Wheel { radius_m: radius_right_m, distance_m: half, angle_rad: -0.5 * PI, ..Wheel::omni(1.0, 0.0, 0.0) };
    let left = Wheel {
        radius_m: radius_left_m,
        distance_m: half,
        angle_rad: 0.5 * PI,
        drive_offset_rad: PI,
        roller_angle_rad: 0.0,
    };
    RobotGeometry { wheel_names: vec!["wheel_right".into(), "wheel_left".into()], wheels: vec![right, left] }
}

/// A set's metadata: its file and rows by key.
struct Meta<'a> {
    path: &'a Path,
    rows: Metadata,
}

impl Meta<'_> {
    /// The values of `key`, with its line.
    fn values(&self, key: &str) -> Result<(usize, &[String]), DatasetError> {
        let (line, vals) =
            self.rows.get(key).ok_or_else(|| DatasetError::file(self.path, format!("missing key {key}")))?;
        Ok((*line, vals))
    }

    /// Exactly `count` finite numbers > 0 under `key`; `what` says what they are in errors.
    fn positive(&self, key: &str, count: usize, what: &str) -> Result<Vec<f64>, DatasetError> {
        let (line, vals) = self.values(key)?;
        let at = || format!("line {line}, key {key}");
        if vals.len() != count {
            return Err(DatasetError::at(
                self.path,
                at(),
                format!("expected {count} value(s) ({what}), got {}", vals.len()),
            ));
        }
        vals.iter()
            .map(|v| match v.parse::<f64>() {
                Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
                Ok(_) => Err(DatasetError::at(self.path, at(), format!("{v:?} must be a number > 0 ({what})"))),
                Err(_) => Err(DatasetError::at(self.path, at(), format!("{v:?} is not a number ({what})"))),
            })
            .collect()
    }
}

/// The robot type a set's metadata names (one of [`SUPPORTED_TYPES`]), its design geometry, and the wheel
/// angle of one tick (rad).
fn design_from_metadata(meta: &Meta<'_>) -> Result<(&'static str, RobotGeometry, f64), DatasetError> {
    let (line, kind) = meta.values("type")?;
    let named = kind.first().map_or("", String::as_str);
    let Some(kind) = SUPPORTED_TYPES.iter().copied().find(|t| *t == named) else {
        return Err(unsupported_type(meta, line, named));
    };
    let ngear = meta.positive("ngear", 1, "gear ratio")?[0];
    let enc = meta.positive("encRes", 1, "encoder counts per motor revolution")?[0];
    let robot = match kind {
        "omni3" => {
            let li = meta.positive("Li", 1, "wheel distance from the centre, m")?[0];
            let d = meta.positive("Di", 3, "wheel diameters, m")?;
            omni3_geometry([d[0] / 2.0, d[1] / 2.0, d[2] / 2.0], li)
        }
        "omni4" => {
            let li = meta.positive("Li", 2, "l1, l2, m")?;
            let d = meta.positive("Di", 4, "wheel diameters, m")?;
            omni4_geometry([d[0], d[1], d[2], d[3]], li[0], li[1])
        }
        "diff" => {
            let b = meta.positive("Li", 1, "wheel separation b, m")?[0];
            let d = meta.positive("Di", 2, "wheel diameters right, left, m")?;
            diff_geometry(d[0] / 2.0, d[1] / 2.0, b)
        }
        _ => return Err(unsupported_type(meta, line, kind)),
    };
    Ok((kind, robot, 2.0 * PI / (ngear * enc)))
}

/// The refusal of a robot type outside [`SUPPORTED_TYPES`] (OptiOdom's tricycle, a typo).
fn unsupported_type(meta: &Meta<'_>, line: usize, kind: &str) -> DatasetError {
    DatasetError::at(
        meta.path,
        format!("line {line}, key type"),
        format!("robot type {kind:?} is not supported (omnical reads OptiOdom's {} sets)", SUPPORTED_TYPES.join(", ")),
    )
}

/// What a set folder holds: its runs and the robot its metadata declares.
#[derive(Clone, Debug)]
pub struct Set {
    /// The runs, in file-name order.
    pub runs: Vec<Run>,
    /// The robot type the metadata names (`omni3`, `omni4`, `diff`).
    pub kind: &'static str,
    /// The design geometry it declares.
    pub robot: RobotGeometry,
}

/// Read every run of an OptiOdom set folder, with the geometry its metadata declares. Per-run errors go to
/// `on_error` (return `Err` to stop).
pub fn read_set(
    dir: &Path,
    mut on_error: impl FnMut(DatasetError) -> Result<(), DatasetError>,
) -> Result<Set, DatasetError> {
    let meta_path = metadata_file(dir).ok_or_else(|| DatasetError::file(dir, "no *_metadata.csv in this folder"))?;
    let meta = Meta { path: &meta_path, rows: read_metadata(&meta_path)? };
    let (kind, robot, rad_per_tick) = design_from_metadata(&meta)?;
    let set = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| DatasetError::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name().is_some_and(|n| n.to_string_lossy().contains("_run-"))
                && p.extension().is_some_and(|e| e == "csv")
        })
        .collect();
    files.sort();
    let columns = column_names(&robot);
    let mut runs = Vec::new();
    for f in files {
        match read_run(&f, &set, rad_per_tick, &columns) {
            Ok(r) => runs.push(r),
            Err(e) => on_error(e)?,
        }
    }
    Ok(Set { runs, kind, robot })
}

/// Column names for errors: `time, x_gt, y_gt, theta_gt` and `ticks_<wheel>` per wheel.
fn column_names(robot: &RobotGeometry) -> Vec<String> {
    let mut c: Vec<String> = ["time", "x_gt", "y_gt", "theta_gt"].iter().map(|s| s.to_string()).collect();
    c.extend(robot.wheel_names.iter().map(|n| format!("ticks_{}", n.strip_prefix("wheel_").unwrap_or(n))));
    c
}

fn read_run(path: &Path, set: &str, rad_per_tick: f64, columns: &[String]) -> Result<Run, DatasetError> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_path(path)
        .map_err(|e| DatasetError::file(path, e.to_string()))?;
    let (ncols, nw) = (columns.len(), columns.len() - 4);
    let (mut t, mut wheel, mut truth) = (Vec::new(), Vec::new(), Vec::new());
    let mut v = vec![0.0; ncols];
    for (i, rec) in r.records().enumerate() {
        let line = i + 1;
        let rec = rec.map_err(|e| DatasetError::at(path, format!("line {line}"), e.to_string()))?;
        if rec.len() != ncols {
            return Err(DatasetError::at(
                path,
                format!("line {line}"),
                format!("has {} columns, expected {ncols} (time, x, y, θ and {nw} wheels)", rec.len()),
            ));
        }
        for (c, cell) in rec.iter().enumerate() {
            v[c] = cell.trim().parse::<f64>().map_err(|_| {
                DatasetError::at(
                    path,
                    format!("line {line}, column {}", columns[c]),
                    format!("{cell:?} is not a number"),
                )
            })?;
        }
        t.push(v[0]);
        wheel.extend_from_slice(&v[4..]);
        truth.push(StampedPose { t_s: v[0], pose: Pose2::new(v[1], v[2], v[3]) });
    }
    // Ticks in a cycle → rad/s over that cycle (the first sample uses the second's interval).
    for s in 0..t.len() {
        let dt = if s == 0 { t.get(1).map_or(1.0, |t1| t1 - t[0]) } else { t[s] - t[s - 1] };
        for w in &mut wheel[nw * s..nw * (s + 1)] {
            *w *= rad_per_tick / dt;
        }
    }
    unwrap_headings(&mut truth);
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let run_id = stem.rsplit('_').next().unwrap_or(&stem).to_string();
    Run::new(RunData {
        name: format!("{set}/{run_id}"),
        wheel_t_s: t,
        wheel_rad_s: wheel,
        n_wheels: nw,
        truth,
        ..RunData::default()
    })
    .map_err(|source| DatasetError::Run { path: path.to_path_buf(), error: source })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// OptiOdom's nominal model (README formulas) as a 3 × N matrix on arc lengths, mapped to wheel angles
    /// (`s_i = (D_i/2) θ_i`), compared entry by entry with the design geometry's IK matrix.
    fn assert_reproduces(robot: &RobotGeometry, arc_model: &[Vec<f64>], diameters_m: &[f64]) {
        let ik = robot.twist_from_wheels().unwrap();
        for (row, e) in arc_model.iter().enumerate() {
            for (c, per_arc) in e.iter().enumerate() {
                let want = per_arc * diameters_m[c] / 2.0;
                let got = ik.get(row, c);
                assert!((got - want).abs() < 1e-12, "m{}{}: {got} vs {want}", row + 1, c + 1);
            }
        }
    }

    #[test]
    fn omni3_geometry_reproduces_optiodom_model() {
        for (d, l) in [([0.102; 3], 0.195), ([0.1, 0.104, 0.099], 0.21)] {
            let s3 = 3f64.sqrt() / 3.0;
            let arc = vec![vec![-s3, s3, 0.0], vec![-1.0 / 3.0, -1.0 / 3.0, 2.0 / 3.0], vec![-1.0 / (3.0 * l); 3]];
            assert_reproduces(&omni3_geometry([d[0] / 2.0, d[1] / 2.0, d[2] / 2.0], l), &arc, &d);
        }
    }

    #[test]
    fn omni4_geometry_reproduces_optiodom_model() {
        for (d, l1, l2) in
            [([0.06; 4], 0.2, 0.2), ([0.06; 4], 0.205, 0.215), ([0.058, 0.06, 0.0615, 0.0595], 0.19, 0.23)]
        {
            let k = -1.0 / (2.0 * (l1 + l2));
            let arc = vec![vec![0.25, -0.25, 0.25, -0.25], vec![-0.25, -0.25, 0.25, 0.25], vec![k; 4]];
            assert_reproduces(&omni4_geometry(d, l1, l2), &arc, &d);
        }
    }

    #[test]
    fn diff_geometry_reproduces_optiodom_model() {
        for (d, b) in [([0.084; 2], 0.2), ([0.083, 0.0852], 0.205)] {
            let arc = vec![vec![0.5, 0.5], vec![0.0, 0.0], vec![1.0 / b, -1.0 / b]];
            assert_reproduces(&diff_geometry(d[0] / 2.0, d[1] / 2.0, b), &arc, &d);
        }
    }
}
