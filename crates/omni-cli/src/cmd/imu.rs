//! `omnical imu`: an IMU's yaw rate as a rotation reference. It reaches the wheel matrix's rotation row
//! (and the gyro's bias), by least squares over windows ([`omni_kin::gyro`]); the translation rows need a
//! reference that senses translation (motion capture, `--gt-scans`, measured end poses).

use super::{DataArgs, OutputArgs};
use crate::api::load::LoadRequest;
use crate::{atomic, dataset, design, model_file, out_path};
use anyhow::Context;
use omni_kin::gyro::{GyroSample, RotationFit, fit_rotation_row};
use omni_kin::{FittedModel, KinematicsKind, Run};
use serde_json::json;
use std::path::{Path, PathBuf};

/// The default Imu topic.
pub const DEFAULT_IMU_TOPIC: &str = "/imu";

/// Arguments of `omnical imu`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// ROS recordings (.mcap, .db3 or .bag files, or rosbag2 folders), each with the wheels' JointState and
    /// the IMU's sensor_msgs/msg/Imu.
    #[arg(value_name = "RECORDING", required = true)]
    pub recordings: Vec<PathBuf>,
    /// The IMU's sensor_msgs/msg/Imu topic (its angular_velocity.z is the yaw rate).
    #[arg(long, default_value = DEFAULT_IMU_TOPIC)]
    pub topic: String,
    /// Window of the fit (s): each window's turn as the gyro integrates it against the wheels' angles.
    #[arg(long, value_name = "SECONDS", default_value_t = 1.0)]
    pub window: f64,
    /// Write the design's matrix with this rotation row as a model file (the translation rows stay the
    /// design's).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options (the robot description, joints).
    #[command(flatten)]
    pub data: DataArgs,
}

/// Reads each recording's wheels and gyro; the gyro on the run's clock. Ground-truth options and `--split`
/// would change nothing (the gyro is the reference, each recording one run): they are refused.
fn read(a: &Args) -> anyhow::Result<(dataset::Dataset, Vec<Run>, Vec<Vec<GyroSample>>)> {
    let d = &a.data;
    let unused = [
        (d.gt.is_some(), "--gt"),
        (d.gt_topic.is_some(), "--gt-topic"),
        (d.gt_scans.is_some(), "--gt-scans"),
        (d.gt_kind.is_some(), "--gt-kind"),
        (d.gt_window.is_some(), "--gt-window"),
        (d.gt_mount.is_some(), "--gt-mount"),
        (d.gt_time_offset.is_some(), "--gt-time-offset"),
        (d.split.is_some(), "--split"),
    ];
    if let Some((_, flag)) = unused.iter().find(|(set, _)| *set) {
        anyhow::bail!("{flag} changes nothing for `omnical imu`: the IMU is the reference, and each recording one run");
    }
    let (mut runs, mut gyro) = (Vec::new(), Vec::new());
    let mut first = None;
    for path in &dataset::ros_recordings(&a.recordings)? {
        let request = LoadRequest { wheels_only: true, ..a.data.request(std::slice::from_ref(path)) };
        let ds = request.read_for_robot(request.robot()?)?;
        let sink = dataset::feed_ros(path, dataset::DEFAULT_MAX_FILE_BYTES, |zstd| {
            dataset::mcap::ImuSink::new(&a.topic, zstd)
        })?;
        let mut read = sink.finish(path)?;
        for run in &ds.runs {
            if let Some(&origin) = ds.time_origins_s.get(run.name()) {
                read.rebase(origin);
            }
            runs.push(run.clone());
            gyro.push(read.samples.clone());
        }
        first.get_or_insert(ds);
    }
    let ds = first.context("no recording read")?;
    Ok((ds, runs, gyro))
}

/// Runs `omnical imu`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    if let Some(out) = &a.out {
        out_path::check_file(out, "--out")?;
    }
    let (ds, runs, gyro) = read(a)?;
    let fit = fit_rotation_row(&runs, &gyro, a.window).with_context(|| format!("topic {:?}", a.topic))?;
    let design = FittedModel::nominal(design::model(KinematicsKind::Ik, &ds)?);
    let n = design.model.n_wheels();
    let design_row: Vec<f64> = design.params[2 * n..3 * n].to_vec();
    if let Some(out) = &a.out {
        write_model(&design, &fit, out)?;
    }
    if a.output.json {
        return super::print_json(
            "imu",
            json!({
                "topic": a.topic, "window_s": a.window, "fit": fit, "design_row": design_row,
                "wheel_names": design.model.kinematics.wheel_names(),
                "out": a.out.as_ref().map(|p| p.display().to_string()),
            }),
        );
    }
    print_fit(a, &fit, &design_row, &design.model.kinematics.wheel_names());
    Ok(())
}

/// The design's matrix with the fitted rotation row, written atomically.
fn write_model(design: &FittedModel, fit: &RotationFit, out: &Path) -> anyhow::Result<()> {
    let mut model = design.clone();
    let n = model.model.n_wheels();
    model.params[2 * n..3 * n].copy_from_slice(&fit.row);
    let mut table = toml::Table::new();
    table.insert("reference".into(), "imu: the rotation row fitted, the translation rows the design's".into());
    table.insert("gyro_bias_rad_s".into(), fit.bias_rad_s.into());
    let text = model_file::to_toml(&model, Some(table))?;
    atomic::write_atomic(out, text.as_bytes()).with_context(|| format!("writing {}", out.display()))
}

/// The fit as a table, with what the IMU does not reach.
fn print_fit(a: &Args, fit: &RotationFit, design_row: &[f64], names: &[String]) {
    println!(
        "IMU {:?}: {} windows of {} s, {:.1} rad turned; residual RMS {:.2e} rad per window",
        a.topic, fit.windows, a.window, fit.turned_rad, fit.residual_rms_rad
    );
    println!("rotation row (ω per wheel speed):     fitted          ±        design    change");
    for (i, name) in names.iter().enumerate() {
        let change = 100.0 * (fit.row[i] / design_row[i] - 1.0);
        println!(
            "  {name:<28} {:>14.8} {:>10.2e} {:>13.8} {:>+8.3} %",
            fit.row[i], fit.row_std[i], design_row[i], change
        );
    }
    println!("gyro bias {:+.5} ± {:.5} rad/s", fit.bias_rad_s, fit.bias_std_rad_s);
    println!(
        "an IMU senses no translation: the translation rows are not reached (fit them with motion capture, \
         --gt-scans or measured end poses); a gyro scale error would scale this row and cannot be told from it \
         with the IMU alone"
    );
    if let Some(out) = &a.out {
        println!("model written to {} (the design's translation rows, this rotation row)", out.display());
    }
}
