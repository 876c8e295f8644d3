//! rosbag2's sqlite3 storage (`.db3`, the default recorder storage up to ROS 2 Iron): the `topics` table
//! (`id`, `name`, `type`, `serialization_format`) and the `messages` table (`topic_id`, `timestamp` in ns,
//! `data` = the CDR payload), read in `(timestamp, id)` order (as `ros2 bag play` does) into the same
//! message pipeline as MCAP ([`Recording`]).

use crate::dataset::DatasetError;
use crate::dataset::mcap::read::Recording;
use rusqlite::{Connection, OpenFlags, types::ValueRef};
use std::path::Path;

/// Feeds every message of the sqlite3 file at `path` into `rec`. `image`, when given, is the database's
/// bytes (a file-compressed recording, decompressed in memory); `path` then only names it.
pub(crate) fn feed(path: &Path, image: Option<Vec<u8>>, rec: &mut Recording) -> Result<(), DatasetError> {
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
            ids.push((id, rec.channel(&name, &msg_type, "ros2msg", &format)));
        }
    }
    let mut stmt =
        conn.prepare("SELECT id, topic_id, timestamp, data FROM messages ORDER BY timestamp, id").map_err(db_error)?;
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
        rec.message(channel, data, u64::try_from(t_ns).unwrap_or(0));
    }
    Ok(())
}

/// Opens the database read-only, from the file or from `image`.
fn open(path: &Path, image: Option<Vec<u8>>) -> Result<Connection, DatasetError> {
    let db_error = |e: rusqlite::Error| sqlite_error(path, &e);
    let conn = match image {
        None => Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX)
            .map_err(db_error)?,
        Some(bytes) => {
            let mut conn = Connection::open_in_memory().map_err(db_error)?;
            conn.deserialize_read_exact(rusqlite::MAIN_DB, &bytes[..], bytes.len(), true).map_err(db_error)?;
            conn
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
