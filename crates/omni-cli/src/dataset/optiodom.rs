//! OptiOdom datasets (Sousa et al. 2022): a set folder `<id>/` with `<id>_metadata.csv` (key, values…)
//! and `<id>_run-NN.csv` files without header: `time s, x_gt m, y_gt m, theta_gt rad (unwrapped), ticks of
//! wheels 1–3 in the control cycle`. Every row is both a wheel sample and a ground-truth pose.
//!
//! Wheel speed = ticks · 2π / (ngear · encRes) / Δt. OptiOdom's nominal omni3 model,
//! `dx = (√3/3)(s2 − s1)`, `dy = (2 s3 − s1 − s2)/3`, `dθ = −(s1 + s2 + s3)/(3 L)`, is the geometry with
//! wheel radius `D_i/2`, distance `Li`, wheels at δ = 300°, 60°, 180° driving clockwise
//! (`drive_offset_rad = π`).

use super::DatasetError;
use super::csv::unwrap_headings;
use omni_kin::{Pose2, RobotGeometry, Run, RunData, StampedPose, Wheel};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

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

fn read_metadata(path: &Path) -> Result<BTreeMap<String, (usize, Vec<String>)>, DatasetError> {
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

/// The robot geometry OptiOdom's omni3 model implies.
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

/// Read every run of an OptiOdom set folder, with the geometry its metadata declares. Per-run errors go to
/// `on_error` (return `Err` to stop).
pub fn read_set(
    dir: &Path,
    mut on_error: impl FnMut(DatasetError) -> Result<(), DatasetError>,
) -> Result<(Vec<Run>, RobotGeometry), DatasetError> {
    let meta_path = metadata_file(dir).ok_or_else(|| DatasetError::file(dir, "no *_metadata.csv in this folder"))?;
    let meta = read_metadata(&meta_path)?;
    let get = |key: &str| -> Result<Vec<f64>, DatasetError> {
        let (line, vals) = meta.get(key).ok_or_else(|| DatasetError::file(&meta_path, format!("missing key {key}")))?;
        vals.iter()
            .map(|v| {
                v.parse::<f64>().map_err(|_| {
                    DatasetError::at(&meta_path, format!("line {line}, key {key}"), format!("{v:?} is not a number"))
                })
            })
            .collect()
    };
    let kind = meta.get("type").and_then(|(_, v)| v.first().cloned()).unwrap_or_default();
    if kind != "omni3" {
        return Err(DatasetError::file(&meta_path, format!("robot type {kind:?} is not supported (only omni3)")));
    }
    let ngear = get("ngear")?.first().copied().unwrap_or(f64::NAN);
    let enc = get("encRes")?.first().copied().unwrap_or(f64::NAN);
    let li = get("Li")?.first().copied().unwrap_or(f64::NAN);
    let di = get("Di")?;
    if di.len() != 3 || !(ngear > 0.0 && enc > 0.0 && li > 0.0) {
        return Err(DatasetError::file(&meta_path, "needs ngear > 0, encRes > 0, Li > 0 and three Di values"));
    }
    let robot = omni3_geometry([di[0] / 2.0, di[1] / 2.0, di[2] / 2.0], li);
    let rad_per_tick = 2.0 * PI / (ngear * enc);
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
    let mut runs = Vec::new();
    for f in files {
        match read_run(&f, &set, rad_per_tick) {
            Ok(r) => runs.push(r),
            Err(e) => on_error(e)?,
        }
    }
    Ok((runs, robot))
}

fn read_run(path: &Path, set: &str, rad_per_tick: f64) -> Result<Run, DatasetError> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(false)
        .from_path(path)
        .map_err(|e| DatasetError::file(path, e.to_string()))?;
    const COLS: [&str; 7] = ["time", "x_gt", "y_gt", "theta_gt", "ticks_1", "ticks_2", "ticks_3"];
    let (mut t, mut ticks, mut truth) = (Vec::new(), Vec::new(), Vec::new());
    for (i, rec) in r.records().enumerate() {
        let line = i + 1;
        let rec = rec.map_err(|e| DatasetError::at(path, format!("line {line}"), e.to_string()))?;
        if rec.len() != 7 {
            return Err(DatasetError::at(
                path,
                format!("line {line}"),
                format!("has {} columns, expected 7", rec.len()),
            ));
        }
        let mut v = [0.0; 7];
        for (c, cell) in rec.iter().enumerate() {
            v[c] = cell.trim().parse::<f64>().map_err(|_| {
                DatasetError::at(path, format!("line {line}, column {}", COLS[c]), format!("{cell:?} is not a number"))
            })?;
        }
        t.push(v[0]);
        ticks.extend_from_slice(&v[4..7]);
        truth.push(StampedPose { t_s: v[0], pose: Pose2::new(v[1], v[2], v[3]) });
    }
    let mut wheel = ticks;
    for s in 0..t.len() {
        let dt = if s == 0 { t.get(1).map_or(1.0, |t1| t1 - t[0]) } else { t[s] - t[s - 1] };
        for w in &mut wheel[3 * s..3 * s + 3] {
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
        n_wheels: 3,
        truth,
        ..RunData::default()
    })
    .map_err(|source| DatasetError::Run { path: path.to_path_buf(), error: source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometry_reproduces_optiodom_model() {
        let (r, l) = (0.051, 0.195);
        let ik = omni3_geometry([r; 3], l).twist_from_wheels().unwrap();
        let s3 = 3f64.sqrt() / 3.0;
        let expect = [[-s3 * r, s3 * r, 0.0], [-r / 3.0, -r / 3.0, 2.0 * r / 3.0], [-r / (3.0 * l); 3]];
        for (row, e) in expect.iter().enumerate() {
            for (c, want) in e.iter().enumerate() {
                assert!((ik.get(row, c) - want).abs() < 1e-12, "m{}{}", row + 1, c + 1);
            }
        }
    }
}
