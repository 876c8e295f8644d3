//! rosbag2 recordings as `ros2 bag record` leaves them: a folder with a `metadata.yaml` ([`metadata`]) and
//! one or more storage files (split by size or duration), in either storage:
//!
//! | storage | files | how it is read |
//! |---|---|---|
//! | `sqlite3` (default up to ROS 2 Iron) | `rec_0.db3`, `rec_1.db3`, … | tables `topics` and `messages` (`sqlite.rs`) |
//! | `mcap` (default from ROS 2 Jazzy) | `rec_0.mcap`, `rec_1.mcap`, … | as a bare `.mcap` ([`crate::dataset::mcap`]) |
//!
//! All files of a recording are read, in the order `relative_file_paths` lists them, into **one** recording
//! (topics matched by name), which is then one run named after the folder, or cut into runs at standstills
//! with `--split` exactly as a single MCAP file is. Both storages feed the same message pipeline and CDR
//! decoders, so the same messages give the same runs, bit for bit, whatever the storage.
//!
//! Compression: rosbag2's `zstd` in mode `FILE` (each storage file is one zstd stream, `rec_0.db3.zstd`,
//! decompressed in memory) and in mode `MESSAGE` (each payload is a zstd stream); any other format is
//! refused with the key and value. MCAP's own chunk compression (zstd, lz4) is read as for a bare `.mcap`.
//!
//! A bare `.db3` file (a split file on its own, or a recording whose `metadata.yaml` was lost) is read as
//! a recording of that one file, named after its stem.
//!
//! Errors name the file (the `metadata.yaml` and its key, or the storage file) and what is wrong; message
//! problems name the recording, topic and message index (0-based within its topic over the whole
//! recording).

pub mod metadata;
mod sqlite;

use crate::dataset::ground_truth::ExternalTruth;
use crate::dataset::mcap::McapOptions;
use crate::dataset::mcap::McapRead;
use crate::dataset::mcap::recording::{MessageSink, Recording};
use crate::dataset::mcap::{Inventory, InventorySink};
use crate::dataset::mcap::{assembly, framing};
use crate::dataset::{DatasetError, Note, check_size};
use metadata::{Compression, Storage};
use std::io::Read;
use std::path::Path;

/// Whether `dir` is a rosbag2 recording (it holds a `metadata.yaml`).
pub fn is_recording(dir: &Path) -> bool {
    dir.join(metadata::FILE_NAME).is_file()
}

/// Reads the recording in folder `dir` (see the module docs). Each storage file (decompressed, for `FILE`
/// compression) may be at most `max_file_bytes` long.
///
/// With `truth`, the ground truth comes from that file instead of a topic (see
/// [`crate::dataset::mcap::read_file_with_truth`]).
pub fn read_recording(
    dir: &Path,
    opts: &McapOptions,
    max_file_bytes: u64,
    truth: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    let meta = metadata::read(dir)?;
    let mut rec = Recording::for_read(opts);
    rec.zstd_messages = meta.compression == Compression::MessageZstd;
    feed_files(dir, &meta, max_file_bytes, &mut rec)?;
    let mut notes = Vec::new();
    for t in &meta.topics {
        let held = rec.messages_on(&t.name).unwrap_or(0);
        if held as u64 != t.message_count {
            notes.push(Note::about(
                dir,
                format!("topic {:?}: metadata.yaml lists {} messages, the files hold {held}", t.name, t.message_count),
            ));
        }
        // Topics the metadata lists but no file declares are still listed in messages.
        rec.channel(&t.name, &t.msg_type, "ros2msg", &t.serialization_format);
    }
    let name = dir.file_name().map_or_else(|| dir.display().to_string(), |s| s.to_string_lossy().into_owned());
    let mut out = assembly::runs(dir, &name, rec, opts, truth)?;
    out.notes.splice(0..0, notes);
    Ok(out)
}

/// Feeds the messages of every storage file of the recording in folder `dir` (metadata `meta`) into `sink`,
/// file after file in the order `relative_file_paths` lists them. `sink` must already decompress messages
/// for `MESSAGE` compression; `FILE` compression is undone here.
fn feed_files(
    dir: &Path,
    meta: &metadata::Metadata,
    max_file_bytes: u64,
    sink: &mut impl MessageSink,
) -> Result<(), DatasetError> {
    let meta_path = dir.join(metadata::FILE_NAME);
    let file_zstd = meta.compression == Compression::FileZstd;
    for file in &meta.files {
        if !file.is_file() {
            return Err(DatasetError::at(
                &meta_path,
                "key relative_file_paths",
                format!("lists {}, which does not exist", file.display()),
            ));
        }
        match meta.storage {
            Storage::Mcap => {
                let buf = read_file(file, file_zstd, max_file_bytes)?;
                framing::feed_mcap(file, &buf, sink)?;
            }
            Storage::Sqlite3 if file_zstd => {
                let image = read_file(file, true, max_file_bytes)?;
                sqlite::feed(file, Some(image), sink)?;
            }
            Storage::Sqlite3 => {
                check_size(file, max_file_bytes)?;
                sqlite::feed(file, None, sink)?;
            }
        }
    }
    Ok(())
}

/// Feeds every message of the recording in folder `dir` into the sink `make(zstd_messages)` makes
/// (`zstd_messages`: each payload is zstd-compressed on its own, which the sink undoes).
pub(crate) fn feed_recording<S: MessageSink>(
    dir: &Path,
    max_file_bytes: u64,
    make: impl FnOnce(bool) -> S,
) -> Result<S, DatasetError> {
    let meta = metadata::read(dir)?;
    let mut sink = make(meta.compression == Compression::MessageZstd);
    feed_files(dir, &meta, max_file_bytes, &mut sink)?;
    Ok(sink)
}

/// Feeds every message of a bare rosbag2 sqlite3 file (`.db3`) into `sink`.
pub(crate) fn feed_db3(path: &Path, max_file_bytes: u64, sink: &mut impl MessageSink) -> Result<(), DatasetError> {
    check_size(path, max_file_bytes)?;
    sqlite::feed(path, None, sink)
}

/// What the recording in folder `dir` holds (topics, types, counts, joint names, URDF), for `omnical init`;
/// all its files are read as [`read_recording`] reads them.
pub fn inspect_recording(dir: &Path, max_file_bytes: u64) -> Result<Inventory, DatasetError> {
    let meta = metadata::read(dir)?;
    let mut inv = InventorySink::new(dir);
    inv.zstd_messages = meta.compression == Compression::MessageZstd;
    feed_files(dir, &meta, max_file_bytes, &mut inv)?;
    inv.finish()
}

/// What a bare rosbag2 sqlite3 file (`.db3`) holds, for `omnical init`.
pub fn inspect_db3(path: &Path, max_file_bytes: u64) -> Result<Inventory, DatasetError> {
    check_size(path, max_file_bytes)?;
    let mut inv = InventorySink::new(path);
    sqlite::feed(path, None, &mut inv)?;
    inv.finish()
}

/// Reads a bare rosbag2 sqlite3 file (`.db3`) as a recording of that one file, named after its stem.
pub fn read_db3(
    path: &Path,
    opts: &McapOptions,
    max_file_bytes: u64,
    truth: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    check_size(path, max_file_bytes)?;
    let mut rec = Recording::for_read(opts);
    sqlite::feed(path, None, &mut rec)?;
    let stem = path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned());
    assembly::runs(path, &stem, rec, opts, truth)
}

/// The bytes of a storage file, zstd-decompressed when `zstd` (at most `max_file_bytes` either way).
fn read_file(path: &Path, zstd: bool, max_file_bytes: u64) -> Result<Vec<u8>, DatasetError> {
    check_size(path, max_file_bytes)?;
    let file = std::fs::File::open(path).map_err(|e| DatasetError::io(path, e))?;
    if !zstd {
        let mut buf = Vec::new();
        std::io::BufReader::new(file).read_to_end(&mut buf).map_err(|e| DatasetError::io(path, e))?;
        return Ok(buf);
    }
    let not_zstd = |e: std::io::Error| {
        DatasetError::file(path, format!("the file does not decompress as zstd (metadata.yaml says FILE zstd): {e}"))
    };
    let mut buf = Vec::new();
    zstd::stream::read::Decoder::new(file)
        .map_err(not_zstd)?
        .take(max_file_bytes.saturating_add(1))
        .read_to_end(&mut buf)
        .map_err(not_zstd)?;
    if buf.len() as u64 > max_file_bytes {
        return Err(crate::dataset::too_large(path, buf.len() as u64, max_file_bytes));
    }
    Ok(buf)
}
