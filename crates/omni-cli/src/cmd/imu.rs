//! `omnical imu`: an IMU's yaw rate as a rotation reference. It reaches the wheel matrix's rotation row
//! (and the gyro's bias), by least squares over windows ([`crate::api::imu`] computes it); the translation
//! rows need a reference that senses translation (motion capture, `--gt-scans`, measured end poses).

use super::{DataArgs, OutputArgs};
use crate::api::imu::{self as api, ImuFit, ImuRequest, MountSource, MountUsed};
use omni_kin::gyro::ImuMount;
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
    /// The IMU's mount on the base, ROLL,PITCH,YAW in degrees (URDF's rpy: 180,0,0 is upside down, 90,0,0 on
    /// its side), used instead of the recordings' static transforms. Default: the transform from base_link
    /// (else base_footprint) to the messages' frame_id in /tf_static (or a pair repeated unchanged on /tf),
    /// else upright.
    #[arg(long, value_name = "ROLL,PITCH,YAW_DEG", value_parser = parse_mount, allow_hyphen_values = true)]
    pub mount: Option<ImuMount>,
    /// A model fitted on a reference that senses the turning (motion capture, --gt-scans, a localization,
    /// end poses; or `design`, `paper`): its rotation row calibrates the gyro (its scale and bias), which the
    /// IMU alone cannot tell from the row.
    #[arg(long, value_name = "MODEL")]
    pub model: Option<PathBuf>,
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
    /// The request these arguments make. The data options that would change nothing are refused: the
    /// ground-truth ones (the gyro is the reference), `--split` (each recording is one run) and
    /// `--ticks-per-rev` (the wheels come from ROS recordings' JointState, not CSV tick columns).
    pub fn request(&self) -> anyhow::Result<ImuRequest> {
        if let Some((flag, why)) = self.ignored().into_iter().next() {
            anyhow::bail!("{flag} changes nothing for `omnical imu`: {why}");
        }
        Ok(ImuRequest {
            recordings: self.recordings.clone(),
            topic: self.topic.clone(),
            window_s: self.window,
            out: self.out.clone(),
            mount: self.mount,
            model: self.model.as_deref().map(crate::api::ModelSpec::from_path),
            data: self.data.options(),
        })
    }

    /// The data options given that `omnical imu` does not read, each with why.
    fn ignored(&self) -> Vec<(String, &'static str)> {
        let d = &self.data;
        let given = [
            d.gt.is_some(),
            d.gt_topic.is_some(),
            d.gt_parent_frame.is_some(),
            d.gt_child_frame.is_some(),
            !d.gt_columns.is_empty(),
            !d.gt_units.is_empty(),
            d.gt_scans.is_some(),
            d.gt_kind.is_some(),
            d.gt_window.is_some(),
            d.gt_mount.is_some(),
            d.gt_mount_start.is_some(),
            d.gt_time_offset.is_some(),
            d.split.is_some(),
            d.ticks_per_rev.is_some(),
        ];
        given
            .into_iter()
            .zip(IGNORED)
            .filter(|g| g.0)
            .map(|(_, (key, why))| (format!("--{}", key.replace('_', "-")), why))
            .collect()
    }
}

/// Why `omnical imu` reads no ground-truth option.
const GT: &str = "it reads no ground truth (the IMU is the reference)";

/// The data options `omnical imu` does not read (their keys, in [`Args::ignored`]'s order), each with why:
/// given on the command line or in the project file's `[imu]` table they are refused; a project-wide key
/// of the project file leaves `omnical imu` alone ([`ignores_project_wide`]).
const IGNORED: [(&str, &str); 14] = [
    ("gt", GT),
    ("gt_topic", GT),
    ("gt_parent_frame", GT),
    ("gt_child_frame", GT),
    ("gt_columns", GT),
    ("gt_units", GT),
    ("gt_scans", GT),
    ("gt_kind", GT),
    ("gt_window", GT),
    ("gt_mount", GT),
    ("gt_mount_start", GT),
    ("gt_time_offset", GT),
    ("split", "each recording is one run"),
    (
        "ticks_per_rev",
        "it reads ROS recordings, whose JointState gives the wheel speeds (ticks per revolution convert CSV tick \
         columns)",
    ),
];

/// Whether a project-wide key of omnical.toml (`gt_topic = "/mocap"` for training) is left out of
/// `command`'s defaults: `omnical imu` does not read it, and a project's ground truth is no reason to
/// refuse the IMU.
pub fn ignores_project_wide(command: &str, key: &str) -> bool {
    command == "imu" && IGNORED.iter().any(|(k, _)| *k == key)
}

/// `ROLL,PITCH,YAW_DEG` (degrees) as an IMU mount.
fn parse_mount(s: &str) -> Result<ImuMount, String> {
    api::mount_from_text(s).ok_or_else(|| format!("expected ROLL,PITCH,YAW_DEG (three numbers in degrees), got {s:?}"))
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
    r.mounts.iter().for_each(print_mount);
    if r.against_design {
        println!(
            "warning: the fitted row points against the design's although the mount is stated: check the IMU's \
             mount and the wheels' signs (the robot description's joints)"
        );
    }
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
         with the IMU alone{}",
        if r.against_model.is_some() { " (against the model's row below, it can)" } else { "" }
    );
    if let Some(a) = &r.against_model {
        print_against_model(a);
    }
    if let Some(out) = &r.out {
        println!("model written to {} (the design's translation rows, this rotation row)", out.display());
    }
}

/// The gyro calibrated against a model's rotation row.
fn print_against_model(a: &crate::api::imu::AgainstModel) {
    let g = &a.gyro;
    println!(
        "against {}'s rotation row: gyro scale {:.5} ± {:.5} ({:+.3} %), bias {:+.5} ± {:.5} rad/s, residual RMS \
         {:.2e} rad per window",
        a.model,
        g.scale,
        g.scale_std,
        100.0 * (g.scale - 1.0),
        g.bias_rad_s,
        g.bias_std_rad_s,
        g.residual_rms_rad
    );
    let worst = a.difference_sigmas.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    println!(
        "  the IMU's row lies {worst:.1} standard errors from the model's at most (with the gyro's scale at 1){}",
        if worst > 3.0 { ": they disagree beyond the gyro's scale, or the model's turning is off" } else { "" }
    );
}

/// Which mount the IMU was read with.
fn print_mount(m: &MountUsed) {
    let [roll, pitch, yaw] = m.rpy_deg();
    let from = match &m.source {
        MountSource::Given => "given (--mount)".to_string(),
        MountSource::Transforms { base_frame } => format!("from the static transforms ({base_frame} → {})", m.frame_id),
        MountSource::Assumed => format!("upright: no static transform places {:?} on the base", m.frame_id),
    };
    let z = m.mount.z_up();
    let pose = if z > 0.5 {
        "z up"
    } else if z < -0.5 {
        "z down"
    } else {
        "on its side"
    };
    println!(
        "IMU mount {from}: roll {roll:.1}°, pitch {pitch:.1}°, yaw {yaw:.1}° ({pose}), {} recording{}",
        m.recordings,
        if m.recordings == 1 { "" } else { "s" }
    );
}
