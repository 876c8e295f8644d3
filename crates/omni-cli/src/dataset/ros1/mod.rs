//! ROS 1 bags (`.bag`, format 2.0 as `rosbag record` writes it; many labs' archives): the container read by
//! the `rosbag` crate (chunks: bz2, lz4 or none; connections), each message of a type omnical reads
//! transcoded to ROS 2 CDR (module `transcode`) and fed, in time order, to the same message pipeline as MCAP and
//! rosbag2 (`MessageSink`): the same topic choice, notes and errors. ROS 1 type names
//! (`sensor_msgs/JointState`) become ROS 2's (`sensor_msgs/msg/JointState`); `tf/tfMessage` is read as
//! `tf2_msgs/TFMessage`. Messages of other types are passed on untouched (and ignored, as in MCAP).

mod transcode;

use crate::dataset::DatasetError;
use crate::dataset::ground_truth::ExternalTruth;
use crate::dataset::mcap::assembly;
use crate::dataset::mcap::recording::{MessageSink, Recording};
use crate::dataset::mcap::{Inventory, InventorySink};
use crate::dataset::mcap::{McapOptions, McapRead};
use rosbag::{ChunkRecord, MessageRecord, RosBag};
use std::collections::BTreeMap;
use std::path::Path;

/// Reads the ROS 1 bag at `path` into runs, as [`crate::dataset::mcap::read_file_with_truth`] reads an MCAP
/// file.
pub fn read_bag(path: &Path, opts: &McapOptions, truth: Option<&ExternalTruth>) -> Result<McapRead, DatasetError> {
    let mut rec = Recording::for_read(opts);
    feed(path, &mut rec)?;
    let stem = path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned());
    assembly::runs(path, &stem, rec, opts, truth)
}

/// What `omnical init` needs of the bag at `path`: its topics, joints and ground-truth candidates.
pub fn inspect(path: &Path) -> Result<Inventory, DatasetError> {
    let mut inv = InventorySink::new(path);
    feed(path, &mut inv)?;
    inv.finish()
}

/// Feeds every message of the bag at `path` into `sink`, in time order (file order within a time).
pub(crate) fn feed(path: &Path, sink: &mut impl MessageSink) -> Result<(), DatasetError> {
    crate::dataset::count_message_pass();
    // rosbag 0.6.3 panics on some damaged files (a slice index past the end of a truncated bag): a damaged
    // file is an error, never a crash.
    let mut sink = std::panic::AssertUnwindSafe(sink);
    std::panic::catch_unwind(move || scan(path, &mut **sink))
        .unwrap_or_else(|_| Err(DatasetError::file(path, "the file is damaged: the ROS 1 bag reader panicked on it")))
}

fn scan(path: &Path, sink: &mut impl MessageSink) -> Result<(), DatasetError> {
    check_index(path)?;
    let bag = RosBag::new(path).map_err(|e| DatasetError::file(path, format!("not a ROS 1 bag: {e}")))?;
    let bad = |e: rosbag::Error| DatasetError::file(path, format!("the bag is damaged: {e}"));
    // Connection id → (sink channel, the layout to transcode with).
    let mut channels: BTreeMap<u32, (usize, String, Option<&'static [transcode::Field]>)> = BTreeMap::new();
    // Owned: a compressed chunk holds its messages in its own buffer.
    let mut messages: Vec<(u64, u32, Vec<u8>)> = Vec::new();
    for record in bag.chunk_records() {
        let ChunkRecord::Chunk(chunk) = record.map_err(bad)? else { continue };
        for m in chunk.messages() {
            match m.map_err(bad)? {
                MessageRecord::Connection(c) => {
                    let (name, layout) = match transcode::layout(c.tp) {
                        Some((ros2, fields)) => (ros2.to_string(), Some(fields)),
                        None => (c.tp.to_string(), None),
                    };
                    let i = sink.channel(c.topic, &name, "ros2msg", "cdr");
                    channels.insert(c.id, (i, c.topic.to_string(), layout));
                }
                MessageRecord::MessageData(m) => messages.push((m.time, m.conn_id, m.data.to_vec())),
            }
        }
    }
    messages.sort_by_key(|&(t, _, _)| t);
    for (k, (t, conn, data)) in messages.into_iter().enumerate() {
        let Some((i, topic, layout)) = channels.get(&conn) else {
            return Err(DatasetError::file(
                path,
                format!("message {k} is on connection {conn}, which the bag never declares"),
            ));
        };
        match layout {
            Some(fields) => {
                let cdr = transcode::to_cdr(&data, fields).map_err(|e| {
                    DatasetError::at(path, format!("topic {topic:?}"), format!("a message does not decode: {e}"))
                })?;
                sink.message(*i, &cdr, t);
            }
            None => sink.message(*i, &data, t),
        }
    }
    Ok(())
}

/// The bag header's promise that the file holds its index (at `index_pos`), which the reader needs: a bag
/// whose recording was interrupted has none (`index_pos` 0) or ends before it (truncated copy).
fn check_index(path: &Path) -> Result<(), DatasetError> {
    const MAGIC: &[u8] = b"#ROSBAG V2.0\n";
    use std::io::Read;
    let cannot = |e: std::io::Error| DatasetError::file(path, format!("cannot read it: {e}"));
    let file = std::fs::File::open(path).map_err(cannot)?;
    let len = file.metadata().map_err(cannot)?.len();
    // The bag header record is padded to 4096 bytes by `rosbag record`; its fields come first.
    let mut bytes = Vec::with_capacity(4096);
    file.take(4096).read_to_end(&mut bytes).map_err(cannot)?;
    let Some(rest) = bytes.strip_prefix(MAGIC) else {
        return Err(DatasetError::file(path, not_version_2(&bytes)));
    };
    let index_pos = bag_header_field(rest, b"index_pos").and_then(|v| <[u8; 8]>::try_from(v).ok());
    let Some(index_pos) = index_pos.map(u64::from_le_bytes) else {
        return Err(DatasetError::file(
            path,
            "the bag is damaged: its first record is not a bag header with index_pos",
        ));
    };
    let reindex = format!("run `rosbag reindex {}` (ROS 1) and read the reindexed bag", path.display());
    if index_pos == 0 {
        return Err(DatasetError::file(
            path,
            format!("the bag has no index (was its recording interrupted?): {reindex}"),
        ));
    }
    if index_pos >= len {
        return Err(DatasetError::file(
            path,
            format!(
                "the file is truncated: its index should start at byte {index_pos} but the file has {} bytes; if \
                 the recording was interrupted, {reindex}",
                len
            ),
        ));
    }
    Ok(())
}

/// Why a file that does not start as a bag of format 2.0 is refused: another format version of a ROS 1 bag
/// (`#ROSBAG V1.2`, written by ROS before 2010) named with the way to rewrite it, or no bag at all.
fn not_version_2(head: &[u8]) -> String {
    let line = head.split(|&c| c == b'\n').next().unwrap_or_default();
    match line.strip_prefix(b"#ROSBAG V") {
        Some(version) if !version.is_empty() && version.len() <= 8 => format!(
            "a ROS 1 bag of format version {}, which omnical does not read: it reads version 2.0 (as `rosbag record` \
             writes it); rewrite the bag as version 2.0 with ROS 1's `rosbag filter OLD.bag NEW.bag True` (rosbag \
             reads version {0} and writes 2.0), then read the new bag",
            String::from_utf8_lossy(version)
        ),
        _ => "not a ROS 1 bag: it does not start with \"#ROSBAG V2.0\"".to_string(),
    }
}

/// The value of field `name` in the header of the record at the start of `rest` (ROS 1 bag record: header
/// length, then `length name=value` fields, all lengths u32 little-endian).
fn bag_header_field<'a>(rest: &'a [u8], name: &[u8]) -> Option<&'a [u8]> {
    let u32_at = |b: &[u8], at: usize| Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?) as usize);
    let header = rest.get(4..4 + u32_at(rest, 0)?)?;
    let mut at = 0;
    while at < header.len() {
        let field = header.get(at + 4..at + 4 + u32_at(header, at)?)?;
        at += 4 + field.len();
        let eq = field.iter().position(|&c| c == b'=')?;
        if &field[..eq] == name {
            return Some(&field[eq + 1..]);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bag_of_format_1_2_is_named_with_the_version_read_and_the_one_found() {
        let dir = tempfile::tempdir().unwrap();
        let read = |name: &str, bytes: &[u8]| {
            let p = dir.path().join(name);
            std::fs::write(&p, bytes).unwrap();
            check_index(&p).unwrap_err().to_string().replace(&p.display().to_string(), name)
        };
        assert_eq!(
            read("old.bag", b"#ROSBAG V1.2\n\x00\x00\x00\x00"),
            "old.bag: a ROS 1 bag of format version 1.2, which omnical does not read: it reads version 2.0 (as \
             `rosbag record` writes it); rewrite the bag as version 2.0 with ROS 1's `rosbag filter OLD.bag NEW.bag \
             True` (rosbag reads version 1.2 and writes 2.0), then read the new bag"
        );
        assert_eq!(read("text.bag", b"hello"), "text.bag: not a ROS 1 bag: it does not start with \"#ROSBAG V2.0\"");
    }
}
