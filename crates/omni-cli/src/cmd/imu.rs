//! `omnical imu`: an IMU's yaw rate as a rotation reference. It reaches the wheel matrix's rotation row
//! (and the gyro's bias), by least squares over windows ([`crate::api::imu`] computes it); the translation
//! rows need a reference that senses translation (motion capture, `--gt-scans`, measured end poses).

use super::{DataArgs, OutputArgs};
use crate::api::imu::{self as api, ImuFit, ImuRequest};
use std::path::PathBuf;

pub use crate::api::imu::DEFAULT_IMU_TOPIC;

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
    #[arg(long, value_name = "SECONDS", default_value_t = api::DEFAULT_WINDOW_S)]
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

impl Args {
    /// The request these arguments make. Ground-truth options and `--split` would change nothing (the gyro
    /// is the reference, each recording one run): they are refused.
    pub fn request(&self) -> anyhow::Result<ImuRequest> {
        let d = &self.data;
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
            anyhow::bail!(
                "{flag} changes nothing for `omnical imu`: the IMU is the reference, and each recording one run"
            );
        }
        Ok(ImuRequest {
            recordings: self.recordings.clone(),
            topic: self.topic.clone(),
            window_s: self.window,
            out: self.out.clone(),
            data: d.options(),
        })
    }
}

/// Runs `omnical imu`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let result = api::imu(&a.request()?)?;
    if a.output.json {
        println!("{}", serde_json::to_string_pretty(&api::document(&result))?);
        return Ok(());
    }
    print_fit(&result);
    Ok(())
}

/// The fit as a table, with what the IMU does not reach.
fn print_fit(r: &ImuFit) {
    let fit = &r.fit;
    println!(
        "IMU {:?}: {} windows of {} s, {:.1} rad turned; residual RMS {:.2e} rad per window",
        r.topic, fit.windows, r.window_s, fit.turned_rad, fit.residual_rms_rad
    );
    println!("rotation row (ω per wheel speed):     fitted          ±        design    change");
    for (i, name) in r.wheel_names.iter().enumerate() {
        let change = 100.0 * (fit.row[i] / r.design_row[i] - 1.0);
        println!(
            "  {name:<28} {:>14.8} {:>10.2e} {:>13.8} {:>+8.3} %",
            fit.row[i], fit.row_std[i], r.design_row[i], change
        );
    }
    println!("gyro bias {:+.5} ± {:.5} rad/s", fit.bias_rad_s, fit.bias_std_rad_s);
    println!(
        "an IMU senses no translation: the translation rows are not reached (fit them with motion capture, \
         --gt-scans or measured end poses); a gyro scale error would scale this row and cannot be told from it \
         with the IMU alone"
    );
    if let Some(out) = &r.out {
        println!("model written to {} (the design's translation rows, this rotation row)", out.display());
    }
}
