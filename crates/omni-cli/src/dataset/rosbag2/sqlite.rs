//! rosbag2's sqlite3 storage (`.db3`, the default recorder storage up to ROS 2 Iron): the `topics` table
//! (`id`, `name`, `type`, `serialization_format`) and the `messages` table (`topic_id`, `timestamp` in ns,
//! `data` = the CDR payload), read in `(timestamp, id)` order (as `ros2 bag play` does) into the same
//! message pipeline as MCAP ([`MessageSink`]).

use crate::dataset::DatasetError;
use crate::dataset::mcap::recording::MessageSink;
use rusqlite::{Connection, OpenFlags, types::ValueRef};
use std::io::Read;
use std::path::Path;

/// Feeds every message of the sqlite3 file at `path` into `sink`. `image`, when given, is the database's
/// bytes (a file-compressed recording, decompressed in memory); `path` then only names it.
pub(crate) fn feed(path: &Path, image: Option<Vec<u8>>, sink: &mut impl MessageSink) -> Result<(), DatasetError> {
    crate::dataset::count_message_pass();
    let empty = match &image {
        Some(bytes) => bytes.is_empty(),
        None => std::fs::metadata(path).map_err(|e| DatasetError::io(path, e))?.len() == 0,
    };
    if empty {
        return Err(DatasetError::file(
            path,
            "the sqlite3 file is empty (0 bytes): the recording holds no messages (was it interrupted before \
             anything was written?)",
        ));
    }
    let conn = open(path, image)?;
    let db_error = |e: rusqlite::Error| sqlite_error(path, &e);
    // The recording's channel of each topic id.
    let mut ids: Vec<(i64, usize)> = Vec::new();
    {
        let mut stmt =
            conn.prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id").map_err(db_error)?;
        let mut rows = stmt.query([]).map_err(db_error)?;
        while let Some(row) = rows.next().map_err(db_error)? {
            let id: i64 = row.get(0).map_err(db_error)?;
            let (name, msg_type, format): (String, String, String) =
                (row.get(1).map_err(db_error)?, row.get(2).map_err(db_error)?, row.get(3).map_err(db_error)?);
            // The sqlite3 storage has no schema records: the type names are ROS 2 message types.
            ids.push((id, sink.channel(&name, &msg_type, "ros2msg", &format)));
        }
    }
    let order = if in_time_order(&conn).map_err(db_error)? { "id" } else { "timestamp, id" };
    let mut stmt = conn
        .prepare(&format!("SELECT id, topic_id, timestamp, data FROM messages ORDER BY {order}"))
        .map_err(db_error)?;
    let mut rows = stmt.query([]).map_err(db_error)?;
    while let Some(row) = rows.next().map_err(db_error)? {
        let id: i64 = row.get(0).map_err(db_error)?;
        let topic_id: i64 = row.get(1).map_err(db_error)?;
        let t_ns: i64 = row.get(2).map_err(db_error)?;
        let at = || format!("table messages, id {id}");
        let Some(&(_, channel)) = ids.iter().find(|(t, _)| *t == topic_id) else {
            return Err(DatasetError::at(path, at(), format!("topic_id {topic_id} is not in the topics table")));
        };
        let data = match row.get_ref(3).map_err(db_error)? {
            ValueRef::Blob(b) => b,
            other => {
                return Err(DatasetError::at(
                    path,
                    at(),
                    format!("field data is {:?}, not a blob of CDR bytes", other.data_type()),
                ));
            }
        };
        sink.message(channel, data, u64::try_from(t_ns).unwrap_or(0));
    }
    Ok(())
}

/// Whether the rows' `id` order is their `(timestamp, id)` order (as the recorder writes them): the rows are
/// then read in table order, page after page, instead of one index lookup per row (a tenth of a `.db3`'s
/// loading time). Read from the ids alone (the `timestamp_idx` index rosbag2 creates covers them).
fn in_time_order(conn: &Connection) -> rusqlite::Result<bool> {
    let mut stmt = conn.prepare("SELECT id FROM messages ORDER BY timestamp, id")?;
    let mut rows = stmt.query([])?;
    let mut last = i64::MIN;
    while let Some(row) = rows.next()? {
        let id: i64 = row.get(0)?;
        if id <= last {
            return Ok(false);
        }
        last = id;
    }
    Ok(true)
}

/// Opens the database read-only, from `image` or from the file.
///
/// The file is read whole into an in-memory database (one read, as an MCAP file is) rather than opened in
/// place: SQLite then reads no page through a system call (`pread` per 4 KiB page was ~15 % of a `.db3`
/// recording's loading time), and loading many recordings in parallel scales like MCAP. A file whose
/// write-ahead log (`-wal`) is not empty (a recording still being written, or interrupted in WAL mode) is
/// opened in place, so that SQLite reads the log too.
fn open(path: &Path, image: Option<Vec<u8>>) -> Result<Connection, DatasetError> {
    let db_error = |e: rusqlite::Error| sqlite_error(path, &e);
    let conn = match image {
        Some(bytes) => in_memory(path, &bytes[..], bytes.len())?,
        None if has_wal(path) => {
            Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX)
                .map_err(db_error)?
        }
        None => {
            let file = std::fs::File::open(path).map_err(|e| DatasetError::io(path, e))?;
            let len = file.metadata().map_err(|e| DatasetError::io(path, e))?.len();
            let len = usize::try_from(len).map_err(|_| DatasetError::file(path, "the file is too large to read"))?;
            in_memory(path, file, len)?
        }
    };
    // Both tables must be there before any row is read (an empty or foreign SQLite file fails here).
    for table in ["topics", "messages"] {
        let found: i64 = conn
            .query_row("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = ?1", [table], |r| r.get(0))
            .map_err(db_error)?;
        if found == 0 {
            return Err(DatasetError::file(
                path,
                format!(
                    "not a rosbag2 sqlite3 file: it has no {table:?} table (rosbag2 writes \"topics\" and \"messages\")"
                ),
            ));
        }
    }
    Ok(conn)
}

/// A read-only in-memory database of the `len` bytes that `bytes` gives (a database file's image).
fn in_memory(path: &Path, bytes: impl Read, len: usize) -> Result<Connection, DatasetError> {
    let db_error = |e: rusqlite::Error| sqlite_error(path, &e);
    let mut conn = Connection::open_in_memory().map_err(db_error)?;
    conn.deserialize_read_exact(rusqlite::MAIN_DB, LegacyHeader { inner: bytes, at: 0 }, len, true)
        .map_err(db_error)?;
    // Pages are read where they lie in the image, not copied into the page cache: its allocations take
    // SQLite's global memory mutex, on which two loading threads waited for each other (1.4× the CPU time of
    // one thread on the 180-run set).
    conn.pragma_update(None, "mmap_size", i64::try_from(len).unwrap_or(i64::MAX)).map_err(db_error)?;
    Ok(conn)
}

/// Whether the database at `path` has a non-empty write-ahead log beside it (`<path>-wal`).
fn has_wal(path: &Path) -> bool {
    let mut wal = path.as_os_str().to_owned();
    wal.push("-wal");
    std::fs::metadata(wal).is_ok_and(|m| m.len() > 0)
}

/// A database image read with its header's file format bytes (offsets 18 and 19: 2 = WAL) set to 1
/// (rollback journal): an in-memory database cannot be in WAL mode, and without a log file beside it a WAL
/// database's pages are all in the file (SQLite's advice for `sqlite3_deserialize`).
struct LegacyHeader<R> {
    inner: R,
    /// Bytes read so far.
    at: usize,
}

impl<R: Read> Read for LegacyHeader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        for offset in [18_usize, 19] {
            if let Some(b) = offset.checked_sub(self.at).filter(|&i| i < n).map(|i| &mut buf[i])
                && *b == 2
            {
                *b = 1;
            }
        }
        self.at += n;
        Ok(n)
    }
}

/// An SQLite error, in words.
fn sqlite_error(path: &Path, e: &rusqlite::Error) -> DatasetError {
    use rusqlite::ErrorCode as C;
    let what = match e.sqlite_error_code() {
        Some(C::NotADatabase) => {
            "not an SQLite database (not a rosbag2 .db3 file, or its first page is damaged)".into()
        }
        Some(C::DatabaseCorrupt) => {
            format!("the sqlite3 file is corrupted or truncated ({e}); was the recording interrupted?")
        }
        _ => format!("cannot read the sqlite3 file: {e}"),
    };
    DatasetError::file(path, what)
}
