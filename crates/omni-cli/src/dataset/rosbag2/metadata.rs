//! rosbag2's `metadata.yaml`: which storage, which files (in order), which topics, what time span, which
//! compression. Written by `ros2 bag record` (and by Python rosbags) beside the storage files; versions 1–9
//! share the keys read here.
//!
//! ```yaml
//! rosbag2_bagfile_information:
//!   version: 9
//!   storage_identifier: sqlite3            # or mcap
//!   relative_file_paths: [rec_0.db3, rec_1.db3]
//!   duration: {nanoseconds: 12000000000}
//!   starting_time: {nanoseconds_since_epoch: 1700000000250000000}
//!   message_count: 1090
//!   topics_with_message_count:
//!     - topic_metadata: {name: /joint_states, type: sensor_msgs/msg/JointState, serialization_format: cdr}
//!       message_count: 1050
//!   compression_format: ''                 # or zstd
//!   compression_mode: ''                   # or FILE / MESSAGE (any case)
//! ```

use crate::dataset::DatasetError;
use std::path::{Path, PathBuf};
use yaml_rust2::{Yaml, YamlLoader};

/// The file name of a recording's metadata.
pub const FILE_NAME: &str = "metadata.yaml";

/// Where the messages are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// SQLite 3 files (`.db3`), rosbag2's default up to ROS 2 Iron.
    Sqlite3,
    /// MCAP files, the default from ROS 2 Jazzy.
    Mcap,
}

/// How the recording is compressed (rosbag2 `compression_mode` with `compression_format: zstd`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// Not compressed (or compressed inside the storage, as MCAP chunks are).
    None,
    /// Each storage file is one zstd stream (`rec_0.db3.zstd`).
    FileZstd,
    /// Each message payload is a zstd stream.
    MessageZstd,
}

/// One topic as the metadata lists it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicCount {
    /// The topic name.
    pub name: String,
    /// The message type, e.g. `sensor_msgs/msg/JointState`.
    pub msg_type: String,
    /// The payload encoding, `cdr` for ROS 2.
    pub serialization_format: String,
    /// Messages recorded on it.
    pub message_count: u64,
}

/// The contents of a `metadata.yaml` that matter for reading.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Metadata {
    /// The storage plugin.
    pub storage: Storage,
    /// The storage files, in recording order, as paths (the relative paths joined to the folder).
    pub files: Vec<PathBuf>,
    /// The topics with their message counts.
    pub topics: Vec<TopicCount>,
    /// The first message's time. ns since the epoch.
    pub starting_time_ns: i64,
    /// From the first to the last message. ns.
    pub duration_ns: i64,
    /// The compression.
    pub compression: Compression,
}

/// Reads `dir/metadata.yaml`. Every error names the file and the key.
pub fn read(dir: &Path) -> Result<Metadata, DatasetError> {
    let path = dir.join(FILE_NAME);
    let text = std::fs::read_to_string(&path).map_err(|e| DatasetError::io(&path, e))?;
    parse(&path, dir, &text)
}

fn parse(path: &Path, dir: &Path, text: &str) -> Result<Metadata, DatasetError> {
    let docs = YamlLoader::load_from_str(text).map_err(|e| DatasetError::file(path, format!("not valid YAML: {e}")))?;
    let info = docs.first().map(|d| &d["rosbag2_bagfile_information"]).unwrap_or(&Yaml::BadValue);
    if info.is_badvalue() {
        return Err(DatasetError::file(path, "no rosbag2_bagfile_information: not a rosbag2 metadata file"));
    }
    let key = |k: &str, what: &str| DatasetError::at(path, format!("key {k}"), what.to_string());
    let storage = match info["storage_identifier"].as_str() {
        Some("sqlite3") => Storage::Sqlite3,
        Some("mcap") => Storage::Mcap,
        Some(other) => {
            return Err(key(
                "storage_identifier",
                &format!("storage {other:?} is not supported (omnical reads rosbag2's \"sqlite3\" and \"mcap\")"),
            ));
        }
        None => return Err(key("storage_identifier", "is missing")),
    };
    let names = info["relative_file_paths"].as_vec().ok_or_else(|| key("relative_file_paths", "is missing"))?;
    let mut files = Vec::with_capacity(names.len());
    for n in names {
        let name = n.as_str().ok_or_else(|| key("relative_file_paths", "holds an entry that is not a string"))?;
        files.push(dir.join(name));
    }
    if files.is_empty() {
        return Err(key("relative_file_paths", "lists no files"));
    }
    let mut topics = Vec::new();
    for t in info["topics_with_message_count"].as_vec().map_or(&[][..], Vec::as_slice) {
        let m = &t["topic_metadata"];
        let text = |k: &str| m[k].as_str().unwrap_or_default().to_string();
        topics.push(TopicCount {
            name: text("name"),
            msg_type: text("type"),
            serialization_format: text("serialization_format"),
            message_count: t["message_count"].as_i64().and_then(|c| u64::try_from(c).ok()).unwrap_or(0),
        });
    }
    let format = info["compression_format"].as_str().unwrap_or_default();
    let mode = info["compression_mode"].as_str().unwrap_or_default().to_ascii_uppercase();
    let compression = match (format, mode.as_str()) {
        (_, "" | "NONE") | ("", _) => Compression::None,
        ("zstd", "FILE") => Compression::FileZstd,
        ("zstd", "MESSAGE") => Compression::MessageZstd,
        (f, m) => {
            return Err(key(
                "compression_format",
                &format!("compression {f:?} in mode {m:?} is not supported (omnical reads zstd, FILE or MESSAGE)"),
            ));
        }
    };
    Ok(Metadata {
        storage,
        files,
        topics,
        starting_time_ns: info["starting_time"]["nanoseconds_since_epoch"].as_i64().unwrap_or(0),
        duration_ns: info["duration"]["nanoseconds"].as_i64().unwrap_or(0),
        compression,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROSBAGS: &str = "rosbag2_bagfile_information:
  compression_format: zstd
  compression_mode: message
  duration:
    nanoseconds: 3000000000
  files:
  - duration:
      nanoseconds: 3000000000
    message_count: 5
    path: rec.db3
    starting_time:
      nanoseconds_since_epoch: 1700000000250000000
  message_count: 5
  relative_file_paths:
  - rec.db3
  - rec_1.db3
  starting_time:
    nanoseconds_since_epoch: 1700000000250000000
  storage_identifier: sqlite3
  topics_with_message_count:
  - message_count: 3
    topic_metadata:
      name: /joint_states
      offered_qos_profiles: ''
      serialization_format: cdr
      type: sensor_msgs/msg/JointState
      type_description_hash: RIHS01_abc
  version: 9
";

    #[test]
    fn reads_what_rosbags_writes() {
        let m = parse(Path::new("r/metadata.yaml"), Path::new("r"), ROSBAGS).unwrap();
        assert_eq!(m.storage, Storage::Sqlite3);
        assert_eq!(m.files, [Path::new("r/rec.db3"), Path::new("r/rec_1.db3")]);
        assert_eq!(m.compression, Compression::MessageZstd);
        assert_eq!((m.starting_time_ns, m.duration_ns), (1_700_000_000_250_000_000, 3_000_000_000));
        assert_eq!(
            m.topics,
            [TopicCount {
                name: "/joint_states".into(),
                msg_type: "sensor_msgs/msg/JointState".into(),
                serialization_format: "cdr".into(),
                message_count: 3
            }]
        );
    }

    #[test]
    fn refuses_what_it_cannot_read() {
        let err = |text: &str| parse(Path::new("r/metadata.yaml"), Path::new("r"), text).unwrap_err().to_string();
        assert_eq!(
            err(&ROSBAGS.replace("storage_identifier: sqlite3", "storage_identifier: cassette")),
            "r/metadata.yaml: key storage_identifier: storage \"cassette\" is not supported (omnical reads \
             rosbag2's \"sqlite3\" and \"mcap\")"
        );
        assert_eq!(
            err(&ROSBAGS.replace("compression_format: zstd", "compression_format: lz4")),
            "r/metadata.yaml: key compression_format: compression \"lz4\" in mode \"MESSAGE\" is not supported \
             (omnical reads zstd, FILE or MESSAGE)"
        );
        assert_eq!(err("a: 1"), "r/metadata.yaml: no rosbag2_bagfile_information: not a rosbag2 metadata file");
    }
}
