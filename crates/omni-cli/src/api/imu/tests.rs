//! Unit tests of the IMU fit: an IMU on another clock is refused, naming the file and the topic.

use super::*;
use crate::dataset::mcap::ImuRate;
use omni_kin::run::RunData;

/// An IMU stamped on the epoch while the wheels run from 0 s is refused naming the file, the topic and
/// both spans; one overlapping the wheels passes.
#[test]
fn an_imu_on_another_clock_is_refused_naming_the_file_and_topic() {
    let wheel_t_s: Vec<f64> = (0..101).map(|k| k as f64 * 0.1).collect();
    let truth = [0.0, 10.0].map(|t_s| omni_kin::StampedPose { t_s, pose: omni_kin::Pose2::IDENTITY }).to_vec();
    let data =
        RunData { name: "r".into(), wheel_rad_s: vec![0.0; 303], wheel_t_s, n_wheels: 3, truth, ..Default::default() };
    let run = Run::new(data).unwrap();
    let read = |origin_s: i64| GyroRead {
        rates: (0..50).map(|k| ImuRate { t_s: k as f64 * 0.2, imu_rad_s: [0.0; 3] }).collect(),
        origin_s,
        frame_id: "imu_link".into(),
        stated_mount: None,
    };
    assert!(check_overlap(Path::new("a.mcap"), "/imu", &run, &read(0)).is_ok());
    let mut epoch = read(1_700_000_000);
    epoch.rebase(0);
    let err = check_overlap(Path::new("a.mcap"), "/imu", &run, &epoch).unwrap_err().to_string();
    assert_eq!(
        err,
        "a.mcap: topic \"/imu\": its stamps (1700000000.000 to 1700000009.800 s) do not overlap the wheels' \
         (0.000 to 10.000 s): the IMU is stamped on another clock than the wheels' JointState; record both on one \
         clock (both ROS time, or both sim time)"
    );
}
