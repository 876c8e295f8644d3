//! A 2D lidar as a reference (issue 28): its `sensor_msgs/msg/LaserScan` messages read from a recording
//! ([`read_scans`]: MCAP, rosbag2 (sqlite3 or MCAP storage), ROS 1 bags, through the same storage readers
//! as the runs), matched scan to scan into the sensor's own path ([`sensor_path`], the pure
//! [`omni_kin::lidar`] code), and the rooms the simulator casts rays in ([`room_from_arg`]).
//!
//! Room files (`omnical simulate --lidar FILE`) are TOML, in metres, the robot starting every run at the
//! origin heading +x:
//! ```toml
//! [[polygon]]   # the first polygon: the outer wall (the robot stays inside it)
//! vertices_m = [[-5, -4], [5, -4], [5, 4], [-5, 4]]
//! [[polygon]]   # every further one: an obstacle (the robot stays outside it)
//! vertices_m = [[3, 2], [4, 2], [4, 3], [3, 3]]
//! ```

use crate::dataset::{self, DatasetError};
use serde::Deserialize;
use std::path::Path;

pub use crate::dataset::mcap::ScanRead;
pub use crate::dataset::returns_text;
pub use omni_kin::lidar::room::BUILTIN_ROOMS;
pub use omni_kin::lidar::{
    CLEARANCE_M, LidarModel, MatchQuality, MatchSettings, Rejection, Room, Scan, ScanSettings, SensorPath,
    first_collision, sensor_path, simulate_scans,
};

/// The default LaserScan topic.
pub const DEFAULT_SCAN_TOPIC: &str = "/scan";

/// Reads the LaserScan messages on `topic` of the ROS recording at `path` (a `.mcap`, `.db3` or `.bag`
/// file, or a rosbag2 folder). Ranges are kept as recorded (inf, NaN, 0 and out-of-range values are no
/// returns, see [`Scan::is_return`]). The lidar's mount is read from the static transforms (`…tf_static`
/// topics, and pairs republished unchanged on `/tf`) from `base_link`, else `base_footprint`, down to the
/// scans' `header.frame_id` ([`ScanRead::chain`]). Errors name the file, the topic and, for a bad message, its index
/// (0-based within the topic) and field; a recording without the topic lists its topics.
///
/// ```no_run
/// let read = omni_cli::lidar::read_scans("run.mcap".as_ref(), "/scan")?;
/// let path = omni_cli::lidar::sensor_path(&read.scans, &Default::default())?;
/// println!("{} matches accepted, {} rejected", path.matched, path.rejected);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_scans(path: &Path, topic: &str) -> Result<ScanRead, DatasetError> {
    read_scans_from(path, topic, None)
}

/// [`read_scans`] with the lidar's mount looked up from `base_frame` (a robot description's `[frames]
/// base`) instead of `base_link`, else `base_footprint`.
pub fn read_scans_from(path: &Path, topic: &str, base_frame: Option<&str>) -> Result<ScanRead, DatasetError> {
    read_scans_within(path, topic, base_frame, dataset::DEFAULT_MAX_FILE_BYTES)
}

/// [`read_scans_from`] refusing a storage file larger than `max_file_bytes` (`--max-file-mb`).
pub fn read_scans_within(
    path: &Path,
    topic: &str,
    base_frame: Option<&str>,
    max_file_bytes: u64,
) -> Result<ScanRead, DatasetError> {
    let sink = dataset::feed_ros(path, max_file_bytes, |zstd| {
        dataset::mcap::ScanSink::new(topic, zstd).with_base_frame(base_frame)
    })?;
    sink.finish(path)
}

/// A room file (see the module docs).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RoomFile {
    polygon: Vec<PolygonEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PolygonEntry {
    vertices_m: Vec<[f64; 2]>,
}

/// Reads a room file (see the module docs); errors name the file and the polygon.
pub fn read_room(path: &Path) -> Result<Room, DatasetError> {
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError::io(path, e))?;
    let file: RoomFile = toml::from_str(&text).map_err(|e| {
        let at = crate::toml_error::locate(&text, &e);
        DatasetError::file(path, format!("not a room file ([[polygon]] tables with vertices_m = [[x, y], …]): {at}"))
    })?;
    Room::new(file.polygon.into_iter().map(|p| p.vertices_m).collect())
        .map_err(|e| DatasetError::file(path, format!("{e} (polygon 0 is the outer wall, then the obstacles)")))
}

/// The room `arg` names: a built-in one ([`BUILTIN_ROOMS`]) or a room file.
pub fn room_from_arg(arg: &str) -> Result<Room, DatasetError> {
    match Room::builtin(arg) {
        Some(room) => Ok(room),
        None if Path::new(arg).is_file() => read_room(Path::new(arg)),
        // An I/O error of kind NotFound, so that Python raises FileNotFoundError.
        None => Err(DatasetError::io(
            Path::new(arg),
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("no such room file, and not a built-in room ({})", BUILTIN_ROOMS.join(", ")),
            ),
        )),
    }
}
