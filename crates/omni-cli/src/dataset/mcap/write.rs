//! Writing a run as a ROS 2 bag (one bare `.mcap`), laid out as rosbag2 records one: profile `ros2`,
//! `ros2msg` schemas with their dependencies, little-endian CDR messages, zstd chunks with CRCs, a summary
//! with chunk and message indexes. Messages are written in time order; log time = header stamp. The
//! command is a `TwistStamped` (as `diff_drive_controller` takes it since ROS 2 Jazzy), so its time is
//! the stamp the simulator gave it, not a log time a reader has to trust.

use super::WriteOptions;
use super::common::{Header, Pose, Quaternion, RosString, Time, Twist, Vector3, encode};
use super::imu;
use super::joint_state::{self, JointState};
use super::laser_scan::{self, LaserScan};
use super::odometry::{self, BASE_FRAME, ODOM_FRAME, Odometry, TwistWithCovariance};
use super::pose_stamped::{self, PoseStamped, PoseWithCovariance};
use super::twist::{self, TwistStamped, twist_of};
use crate::dataset::DatasetError;
use omni_kin::{Run, StampedPose};
use serde::Serialize;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The topics written, in channel order: the wheels.
pub const JOINTS_TOPIC: &str = "/joint_states";
/// Ground truth.
pub const TRUTH_TOPIC: &str = "/ground_truth/pose";
/// The command.
pub const COMMAND_TOPIC: &str = "/cmd_vel";
/// The robot's own (design) odometry.
pub(super) const ODOM_TOPIC: &str = "/odom";
/// The calibrated odometry (`omnical export --mcap`).
pub(super) const CALIBRATED_TOPIC: &str = "/omnical/odometry";
/// A lidar's scans (`sensor_msgs/msg/LaserScan`, [`super::WriteOptions::lidar`]).
pub const SCAN_TOPIC: &str = "/scan";
/// The lidar's frame.
pub const LASER_FRAME: &str = "laser";
/// Static transforms (the lidar's mount).
pub const TF_STATIC_TOPIC: &str = "/tf_static";
/// An IMU's messages (`sensor_msgs/msg/Imu`, [`super::WriteOptions::imu`]).
pub const IMU_TOPIC: &str = "/imu";
/// The IMU's frame (on the base, upright).
const IMU_FRAME: &str = "imu_link";
/// The world frame of the ground truth.
pub(super) const TRUTH_FRAME: &str = "map";

/// One message waiting to be written: log time (ns), channel slot, CDR bytes.
type Pending = (u64, usize, Vec<u8>);

/// Collects the messages of one file.
struct Messages<'a> {
    path: &'a Path,
    origin_s: i64,
    out: Vec<Pending>,
}

impl Messages<'_> {
    /// The stamp of `t_s` seconds after the origin, rounded to the nanosecond.
    fn stamp(&self, t_s: f64) -> Result<Time, DatasetError> {
        let ns = self.origin_s.checked_mul(super::common::NS_PER_S).and_then(|o| {
            let dt = (t_s * 1e9).round();
            (dt.abs() < 9e18).then(|| o.checked_add(dt as i64)).flatten()
        });
        ns.filter(|&ns| ns >= 0).and_then(Time::from_ns).ok_or_else(|| {
            DatasetError::file(
                self.path,
                format!("time {t_s} s after the origin {} s is not a valid ROS 2 stamp", self.origin_s),
            )
        })
    }

    fn push<T: Serialize>(&mut self, stamp: Time, slot: usize, msg: &T) -> Result<(), DatasetError> {
        let bytes = encode(msg).map_err(|e| DatasetError::file(self.path, e))?;
        // `stamp` was checked to be non-negative.
        self.out.push((u64::try_from(stamp.ns()).unwrap_or_default(), slot, bytes));
        Ok(())
    }
}

fn header(stamp: Time, frame: &str) -> Header {
    Header { stamp, frame_id: RosString(frame.to_string()) }
}

/// Body-frame twists of a pose sequence by backward differences (the first takes the second's).
fn body_twists(poses: &[StampedPose]) -> Vec<Twist> {
    let mut out: Vec<Twist> = poses
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].pose, w[1].pose);
            let dt = w[1].t_s - w[0].t_s;
            let (s, c) = a.theta_rad.sin_cos();
            let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
            let mut t = Twist::default();
            t.linear.x = (c * dx + s * dy) / dt;
            t.linear.y = (-s * dx + c * dy) / dt;
            t.angular.z = (b.theta_rad - a.theta_rad) / dt;
            t
        })
        .collect();
    if let Some(&first) = out.first() {
        out.insert(0, first);
    }
    out.resize(poses.len(), Twist::default());
    out
}

/// The channel slots written from the run: joints, truth, command, odometry, calibrated odometry, scans,
/// static transforms, IMU. The recording's copied topics follow.
const FIXED_SLOTS: usize = 8;

/// The topics the written slots use, in slot order.
const FIXED_TOPICS: [&str; FIXED_SLOTS] =
    [JOINTS_TOPIC, TRUTH_TOPIC, COMMAND_TOPIC, ODOM_TOPIC, CALIBRATED_TOPIC, SCAN_TOPIC, TF_STATIC_TOPIC, IMU_TOPIC];

/// Whether the recording's own command topic is carried over (it replaces the run's written command).
fn recorded_command(w: &WriteOptions) -> bool {
    w.copied.iter().any(|c| c.topic == COMMAND_TOPIC)
}

/// The copied topics the file carries: all but those on a topic written from the run (the command
/// excepted, see [`recorded_command`]).
fn carried(w: &WriteOptions) -> Vec<&super::copy::CopiedTopic> {
    let written = |topic: &str| {
        topic != COMMAND_TOPIC && FIXED_TOPICS.contains(&topic) && (topic != TF_STATIC_TOPIC || writes_statics(w))
    };
    w.copied.iter().filter(|c| !written(&c.topic)).collect()
}

/// Whether the file writes `/tf_static` (a lidar's or an IMU's stated mount).
fn writes_statics(w: &WriteOptions) -> bool {
    w.lidar.as_ref().is_some_and(|l| l.base_from_sensor.is_some()) || w.imu.as_ref().is_some_and(|i| i.stated.is_some())
}

/// Writes the file's messages. Channel slots: 0 joints, 1 truth, 2 command, 3 odometry, 4 calibrated
/// odometry, 5 scans, 6 static transforms, 7 IMU, then the copied topics ([`carried`]).
fn messages(path: &Path, run: &Run, w: &WriteOptions) -> Result<Vec<Pending>, DatasetError> {
    let n = run.n_wheels();
    let mut m = Messages { path, origin_s: w.origin_s, out: Vec::new() };
    let names: Vec<RosString> = w.wheel_joints.iter().map(|s| RosString(s.clone())).collect();
    let mut position = if run.wheel_start_rad().is_empty() { vec![0.0; n] } else { run.wheel_start_rad().to_vec() };
    let t = run.wheel_t_s();
    for k in 0..run.n_samples() {
        let v = run.wheel_sample(k);
        if k > 0 {
            let dt = t[k] - t[k - 1];
            position.iter_mut().zip(v).for_each(|(p, v)| *p += v * dt);
        }
        let msg = JointState {
            header: header(m.stamp(t[k])?, ""),
            name: names.clone(),
            position: position.clone(),
            velocity: v.to_vec(),
            effort: Vec::new(),
        };
        m.push(msg.header.stamp, 0, &msg)?;
    }
    for p in run.truth() {
        let msg = PoseStamped { header: header(m.stamp(p.t_s)?, TRUTH_FRAME), pose: planar(p) };
        m.push(msg.header.stamp, 1, &msg)?;
    }
    if let Some(c) = run.command().filter(|_| !recorded_command(w)) {
        for (k, twist) in [(0, twist_of(&c)), (t.len() - 1, Twist::default())] {
            let msg = TwistStamped { header: header(m.stamp(t[k])?, BASE_FRAME), twist };
            m.push(msg.header.stamp, 2, &msg)?;
        }
    }
    // The robot's odometry is in its own odom frame; the calibrated odometry starts at the ground truth's
    // first pose, so its poses are in the ground truth's frame.
    for (slot, odom, frame) in [(3, &w.design_odometry, ODOM_FRAME), (4, &w.calibrated_odometry, TRUTH_FRAME)] {
        let Some(odom) = odom else { continue };
        for (p, tw) in odom.iter().zip(body_twists(odom)) {
            let msg = Odometry {
                header: header(m.stamp(p.t_s)?, frame),
                child_frame_id: RosString(BASE_FRAME.to_string()),
                pose: PoseWithCovariance { pose: planar(p), covariance: Default::default() },
                twist: TwistWithCovariance { twist: tw, covariance: Default::default() },
            };
            m.push(msg.header.stamp, slot, &msg)?;
        }
    }
    if let Some(lidar) = &w.lidar {
        lidar_messages(&mut m, lidar, t.first().copied().unwrap_or(0.0))?;
    }
    if let Some(track) = &w.imu {
        imu_messages(&mut m, track, t.first().copied().unwrap_or(0.0))?;
    }
    for (k, c) in carried(w).into_iter().enumerate() {
        m.out.extend(c.messages.iter().map(|(t, bytes)| (*t, FIXED_SLOTS + k, bytes.clone())));
    }
    // Time order; at equal times, channel order (joints first), and message order within a channel.
    m.out.sort_by_key(|&(t, slot, _)| (t, slot));
    Ok(m.out)
}

/// The IMU's messages (frame `imu_link`: the base's yaw rate turned into the IMU's frame by its true mount)
/// and its stated mount, one `/tf_static` message at `first_t_s` (the first wheel sample), when it has one.
fn imu_messages(m: &mut Messages<'_>, track: &super::ImuTrack, first_t_s: f64) -> Result<(), DatasetError> {
    if let Some(mount) = &track.stated {
        let stamp = m.stamp(first_t_s)?;
        let mut tf = laser_scan::static_transform(header(stamp, BASE_FRAME), IMU_FRAME, &omni_kin::Pose2::IDENTITY);
        let q = mount.base_from_imu;
        tf.transforms[0].transform.rotation = Quaternion { x: q.i, y: q.j, z: q.k, w: q.w };
        m.push(stamp, 6, &tf)?;
    }
    for g in &track.samples {
        let [x, y, z] = track.mount.imu_rates(g.z_rad_s);
        let msg = imu::Imu {
            header: header(m.stamp(g.t_s)?, IMU_FRAME),
            orientation: Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 },
            // REP-145: an orientation covariance of −1 says the IMU gives no orientation.
            orientation_covariance: [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            angular_velocity: Vector3 { x, y, z },
            angular_velocity_covariance: [0.0; 9],
            linear_acceleration: Vector3::default(),
            linear_acceleration_covariance: [0.0; 9],
        };
        m.push(msg.header.stamp, 7, &msg)?;
    }
    Ok(())
}

/// The lidar's scans (frame `laser`) and its stated mount, one `/tf_static` message at `first_t_s` (the
/// first wheel sample), when it has one.
fn lidar_messages(m: &mut Messages<'_>, lidar: &super::LidarTrack, first_t_s: f64) -> Result<(), DatasetError> {
    let stamp = m.stamp(first_t_s)?;
    if let Some(mount) = &lidar.base_from_sensor {
        let tf = laser_scan::static_transform(header(stamp, BASE_FRAME), LASER_FRAME, mount);
        m.push(stamp, 6, &tf)?;
    }
    for (k, scan) in lidar.scans.iter().enumerate() {
        let n = scan.ranges_m.len();
        let scan_time = lidar
            .scans
            .get(k + 1)
            .or(k.checked_sub(1).and_then(|j| lidar.scans.get(j)))
            .map_or(0.0, |o| (o.t_s - scan.t_s).abs());
        let msg = LaserScan {
            header: header(m.stamp(scan.t_s)?, LASER_FRAME),
            angle_min: scan.angle_min_rad as f32,
            angle_max: (scan.angle_min_rad + n.saturating_sub(1) as f64 * scan.angle_increment_rad) as f32,
            angle_increment: scan.angle_increment_rad as f32,
            time_increment: scan.time_increment_s as f32,
            scan_time: scan_time as f32,
            range_min: scan.range_min_m as f32,
            range_max: scan.range_max_m as f32,
            ranges: scan.ranges_m.clone(),
            intensities: Vec::new(),
        };
        m.push(msg.header.stamp, 5, &msg)?;
    }
    Ok(())
}

fn planar(p: &StampedPose) -> Pose {
    Pose::planar(p.pose.x_m, p.pose.y_m, p.pose.theta_rad)
}

/// A temporary name beside `path`, unique within this process.
fn temp_path(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().map_or_else(|| "bag".into(), |n| n.to_string_lossy().into_owned());
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}-{k}.tmp", std::process::id()))
}

/// Writes `run` to `path` atomically (a temporary file beside it, then a rename).
pub(super) fn write_run(path: &Path, run: &Run, w: &WriteOptions) -> Result<(), DatasetError> {
    if w.wheel_joints.len() != run.n_wheels() {
        return Err(DatasetError::file(
            path,
            format!(
                "run {} has {} wheels but {} wheel joint names were given",
                run.name(),
                run.n_wheels(),
                w.wheel_joints.len()
            ),
        ));
    }
    let pending = messages(path, run, w)?;
    let tmp = temp_path(path);
    let result = write_file(&tmp, run, w, &pending)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| DatasetError::io(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn write_file(tmp: &Path, run: &Run, w: &WriteOptions, pending: &[Pending]) -> Result<(), DatasetError> {
    let mcap_err = |e: mcap::McapError| DatasetError::file(tmp, format!("cannot write MCAP: {e}"));
    let file = File::create(tmp).map_err(|e| DatasetError::io(tmp, e))?;
    let mut out = mcap::WriteOptions::new()
        .profile("ros2")
        .library(concat!("omnical-", env!("CARGO_PKG_VERSION")))
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(0)
        .create(BufWriter::new(file))
        .map_err(mcap_err)?;
    out.write_metadata(&super::qos::rosbag2_metadata()).map_err(mcap_err)?;
    let mut channel_ids = Vec::new();
    for (name, text, topic, used) in [
        (joint_state::NAME, joint_state::schema(), JOINTS_TOPIC, true),
        (pose_stamped::NAME, pose_stamped::schema(), TRUTH_TOPIC, true),
        (twist::STAMPED_NAME, twist::stamped_schema(), COMMAND_TOPIC, run.command().is_some() && !recorded_command(w)),
        (odometry::NAME, odometry::schema(), ODOM_TOPIC, w.design_odometry.is_some()),
        (odometry::NAME, odometry::schema(), CALIBRATED_TOPIC, w.calibrated_odometry.is_some()),
        (laser_scan::NAME, laser_scan::schema(), SCAN_TOPIC, w.lidar.is_some()),
        (super::tf::NAME, laser_scan::tf_schema(), TF_STATIC_TOPIC, w.lidar.is_some() || writes_statics(w)),
        (imu::NAME, imu::schema(), IMU_TOPIC, w.imu.is_some()),
    ] {
        let id = if used {
            let schema = out.add_schema(name, "ros2msg", text.as_bytes()).map_err(mcap_err)?;
            out.add_channel(schema, topic, "cdr", &super::qos::channel_metadata(topic)).map_err(mcap_err)?
        } else {
            0
        };
        channel_ids.push(id);
    }
    for c in carried(w) {
        let schema = out.add_schema(&c.schema_name, "ros2msg", c.schema_text.as_bytes()).map_err(mcap_err)?;
        let metadata = super::qos::channel_metadata(&c.topic);
        channel_ids.push(out.add_channel(schema, &c.topic, "cdr", &metadata).map_err(mcap_err)?);
    }
    let mut sequence = vec![0u32; channel_ids.len()];
    for (log_time, slot, bytes) in pending {
        sequence[*slot] += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channel_ids[*slot],
            sequence: sequence[*slot],
            log_time: *log_time,
            publish_time: *log_time,
        };
        out.write_to_known_channel(&header, bytes).map_err(mcap_err)?;
    }
    out.finish().map_err(mcap_err)?;
    let file = out.into_inner().into_inner().map_err(|e| DatasetError::io(tmp, e.into_error()))?;
    file.sync_all().map_err(|e| DatasetError::io(tmp, e))
}
