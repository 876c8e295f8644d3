//! Pickling of runs and datasets (the fleet's Dask workers, `multiprocessing`): a run as compact bytes
//! (little-endian f64 columns, every field, re-validated by `Run::new` on the way back, so an unpickled
//! run is the same run bit for bit); a dataset as its runs, notes, skipped inputs and design model file.
//! Models and calibrations pickle through the model file text (`model.rs`, `calibrate.rs`).

use crate::errors::{PyResultExt, value_error};
use omni_kin::{Command, Pose2, Run, RunData, StampedPose};
use pyo3::PyResult;

/// What a `__reduce__` returns: the function that rebuilds the object, and its arguments.
pub type Reduced<'py, Args> = PyResult<(pyo3::Bound<'py, pyo3::PyAny>, Args)>;

/// The first bytes of a pickled run (format version 1).
const MAGIC: &[u8; 8] = b"omnrun2\0";

fn put_f64s(out: &mut Vec<u8>, values: impl IntoIterator<Item = f64>) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

fn put_poses(out: &mut Vec<u8>, poses: &[StampedPose]) {
    put_f64s(out, poses.iter().flat_map(|p| [p.t_s, p.pose.x_m, p.pose.y_m, p.pose.theta_rad]));
}

/// A run as bytes: header (name, counts, command, repetition), then the f64 columns.
pub fn run_to_bytes(run: &Run) -> Vec<u8> {
    let mut out = Vec::with_capacity(128 + 8 * (run.wheel_t_s().len() + run.wheel_rad_s().len()));
    out.extend_from_slice(MAGIC);
    let name = run.name().as_bytes();
    let counts = [
        name.len(),
        run.n_samples(),
        run.n_wheels(),
        run.truth().len(),
        run.recorded_odometry().len(),
        run.wheel_start_rad().len(),
    ];
    for n in counts {
        out.extend_from_slice(&(n as u64).to_le_bytes());
    }
    out.extend_from_slice(name);
    match run.command() {
        Some(c) => {
            out.push(1);
            put_f64s(&mut out, [c.v_m_s, c.alpha_rad, c.omega_rad_s]);
        }
        None => out.push(0),
    }
    match run.repetition() {
        Some(r) => {
            out.push(1);
            out.extend_from_slice(&r.to_le_bytes());
        }
        None => out.push(0),
    }
    put_f64s(&mut out, run.wheel_t_s().iter().copied());
    put_f64s(&mut out, run.wheel_rad_s().iter().copied());
    put_poses(&mut out, run.truth());
    put_poses(&mut out, run.recorded_odometry());
    put_f64s(&mut out, run.wheel_start_rad().iter().copied());
    out.push(u8::from(run.truth_position_only()));
    out
}

/// Reads the bytes of [`run_to_bytes`] in order; running out is an error.
struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> PyResult<&'a [u8]> {
        if self.0.len() < n {
            return Err(value_error("pickled run: the data ends early"));
        }
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        Ok(head)
    }
    fn u8(&mut self) -> PyResult<u8> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> PyResult<u32> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn u64(&mut self) -> PyResult<usize> {
        let mut a = [0u8; 8];
        a.copy_from_slice(self.take(8)?);
        usize::try_from(u64::from_le_bytes(a)).map_err(|_| value_error("pickled run: a count is too large"))
    }
    fn f64s(&mut self, n: usize) -> PyResult<Vec<f64>> {
        let bytes = n.checked_mul(8).ok_or_else(|| value_error("pickled run: a count is too large"))?;
        Ok(self
            .take(bytes)?
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
            .collect())
    }
    fn poses(&mut self, n: usize) -> PyResult<Vec<StampedPose>> {
        let v = self.f64s(n.checked_mul(4).ok_or_else(|| value_error("pickled run: a count is too large"))?)?;
        Ok(v.chunks_exact(4).map(|c| StampedPose { t_s: c[0], pose: Pose2::new(c[1], c[2], c[3]) }).collect())
    }
}

/// The run of [`run_to_bytes`], validated again by `Run::new`.
pub fn run_from_bytes(bytes: &[u8]) -> PyResult<Run> {
    let mut r = Reader(bytes);
    if r.take(MAGIC.len())? != MAGIC {
        return Err(value_error("pickled run: not a run written by this version of omnical"));
    }
    let [name_len, n_samples, n_wheels, n_truth, n_odometry, n_start] =
        [r.u64()?, r.u64()?, r.u64()?, r.u64()?, r.u64()?, r.u64()?];
    let name = String::from_utf8(r.take(name_len)?.to_vec()).map_err(|_| value_error("pickled run: bad name"))?;
    let command = match r.u8()? {
        0 => None,
        _ => {
            let c = r.f64s(3)?;
            Some(Command { v_m_s: c[0], alpha_rad: c[1], omega_rad_s: c[2] })
        }
    };
    let repetition = match r.u8()? {
        0 => None,
        _ => Some(r.u32()?),
    };
    let wheel_t_s = r.f64s(n_samples)?;
    let wheels = n_samples.checked_mul(n_wheels).ok_or_else(|| value_error("pickled run: a count is too large"))?;
    let data = RunData {
        name,
        wheel_t_s,
        wheel_rad_s: r.f64s(wheels)?,
        n_wheels,
        truth: r.poses(n_truth)?,
        command,
        repetition,
        recorded_odometry: r.poses(n_odometry)?,
        wheel_start_rad: r.f64s(n_start)?,
        truth_position_only: r.u8()? != 0,
    };
    if !r.0.is_empty() {
        return Err(value_error("pickled run: unexpected bytes after the run"));
    }
    Run::new(data).py()
}
