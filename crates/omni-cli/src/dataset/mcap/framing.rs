//! The MCAP container: its records and chunks checked before the mcap crate reads them, its errors in
//! words, and the pass that feeds an MCAP file's messages, in file order, into a [`MessageSink`].

use super::recording::MessageSink;
use crate::dataset::DatasetError;
use mcap::records::op;
use mcap::sans_io::LinearReaderOptions;
use std::path::Path;

/// The smallest and largest cap on one record's length (the cap is 64 × the file size between them).
const MIN_RECORD_LIMIT: usize = 64 << 20;
const MAX_RECORD_LIMIT: usize = 4 << 30;

/// The name of an MCAP record opcode (MCAP specification, "Records").
fn record_kind(opcode: u8) -> &'static str {
    match opcode {
        op::HEADER => "Header",
        op::FOOTER => "Footer",
        op::SCHEMA => "Schema",
        op::CHANNEL => "Channel",
        op::MESSAGE => "Message",
        op::CHUNK => "Chunk",
        op::MESSAGE_INDEX => "Message Index",
        op::CHUNK_INDEX => "Chunk Index",
        op::ATTACHMENT => "Attachment",
        op::ATTACHMENT_INDEX => "Attachment Index",
        op::STATISTICS => "Statistics",
        op::METADATA => "Metadata",
        op::METADATA_INDEX => "Metadata Index",
        op::SUMMARY_OFFSET => "Summary Offset",
        op::DATA_END => "Data End",
        _ => "unknown",
    }
}

/// An MCAP reading error, in words.
fn mcap_error(path: &Path, e: mcap::McapError) -> DatasetError {
    use mcap::McapError as E;
    let what = match e {
        E::UnexpectedEof | E::BadMagic | E::BadFooter => {
            "the file is truncated: it ends in the middle of a record, before the MCAP end marker (was the \
             recording interrupted?)"
                .to_string()
        }
        E::BadChunkCrc { saved, calculated } => {
            format!("the file is corrupted: a chunk's CRC is {calculated:08x}, but {saved:08x} was recorded")
        }
        E::RecordTooLarge { opcode, len } => format!(
            "the file is corrupted: a {} record (opcode 0x{opcode:02x}) claims {len} bytes, more than the file \
             holds",
            record_kind(opcode)
        ),
        E::ChunkTooLarge(len) => {
            format!("the file is corrupted: a chunk claims {len} bytes of records, more than the file holds")
        }
        E::Parse(_) => "the file is corrupted: the fields inside a record do not parse (a length or string in \
                        it is damaged)"
            .to_string(),
        e => format!("the file is damaged: {e}"),
    };
    DatasetError::file(path, what)
}

/// The top-level record at `pos`: opcode, body (cut at the end of the file: the mcap reader streams a
/// chunk's records before it has the whole chunk) and whether the body is whole.
fn record_at(buf: &[u8], pos: usize) -> Option<(u8, &[u8], bool)> {
    let opcode = *buf.get(pos)?;
    let len = u64::from_le_bytes(buf.get(pos + 1..pos + 9)?.try_into().ok()?);
    let start = pos + 9;
    let end = usize::try_from(len).ok().and_then(|n| start.checked_add(n)).filter(|&e| e <= buf.len());
    Some((opcode, &buf[start.min(buf.len())..end.unwrap_or(buf.len())], end.is_some()))
}

/// Checks that the records inside each uncompressed chunk fit in it. mcap 0.26 subtracts an inner record's
/// length from the chunk's remaining bytes unchecked (`sans_io/linear_reader.rs`): a corrupted length
/// panics with overflow checks and reads past the chunk without them. Found by fuzzing
/// (`tests/data/bad/fuzz/chunk_record_overrun.mcap`). Other damage is left to the mcap reader.
fn check_chunks(buf: &[u8]) -> Result<(), String> {
    let u64_at = |b: &[u8], at: usize| -> Option<u64> { Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?)) };
    let mut pos = mcap::MAGIC.len();
    while let Some((opcode, body, whole)) = record_at(buf, pos) {
        if opcode == op::FOOTER {
            break;
        }
        if opcode == op::CHUNK {
            // start time, end time, uncompressed size (u64 each), uncompressed CRC (u32), compression (string),
            // records (u64 length + bytes).
            let Some(name_len) = body.get(28..32).and_then(|b| b.try_into().ok()).map(u32::from_le_bytes) else {
                return Ok(());
            };
            let name_end = 32 + name_len as usize;
            if name_len == 0
                && let Some(records_len) = u64_at(body, name_end)
            {
                // Checked against the declared length, which the mcap reader counts down; bytes missing at
                // the end of a cut file are left to it (it reports the truncation).
                let records = body.get(name_end + 8..).unwrap_or_default();
                if whole && records_len > records.len() as u64 {
                    return Err(format!(
                        "the chunk at byte {pos} claims {records_len} bytes of records but holds {}",
                        records.len()
                    ));
                }
                let mut at: u64 = 0;
                while at < records_len {
                    let left = records_len - at;
                    if left < 9 {
                        return Err(format!(
                            "the chunk at byte {pos} ends inside the header of a record ({left} bytes left)"
                        ));
                    }
                    let Some(len) = usize::try_from(at).ok().and_then(|a| u64_at(records, a + 1)) else {
                        break;
                    };
                    if len > left - 9 {
                        return Err(format!(
                            "a record in the chunk at byte {pos} claims {len} bytes but the chunk has {} left",
                            left - 9
                        ));
                    }
                    at += 9 + len;
                }
            }
        }
        if !whole {
            break;
        }
        pos += 9 + body.len();
    }
    Ok(())
}

/// Feeds every message of an MCAP file, in file order, into `rec`.
pub(crate) fn feed_mcap(path: &Path, buf: &[u8], rec: &mut impl MessageSink) -> Result<(), DatasetError> {
    crate::dataset::count_message_pass();
    // mcap 0.26 can still panic on some damaged files (an integer overflow on a record longer than its
    // uncompressed chunk, in builds with overflow checks): a damaged file is an error, never a crash.
    let mut rec = std::panic::AssertUnwindSafe(rec);
    std::panic::catch_unwind(move || scan(path, buf, &mut **rec))
        .unwrap_or_else(|_| Err(DatasetError::file(path, "the file is damaged: the MCAP reader panicked on it")))
}

fn scan<S: MessageSink>(path: &Path, buf: &[u8], rec: &mut S) -> Result<(), DatasetError> {
    if !buf.starts_with(mcap::MAGIC) {
        return Err(DatasetError::file(path, "not an MCAP file (it does not start with the MCAP magic bytes)"));
    }
    check_chunks(buf).map_err(|what| DatasetError::file(path, format!("the file is corrupted: {what}")))?;
    // This file's channel ids and the recording's channels they feed.
    let mut ids: Vec<(u16, usize)> = Vec::new();
    let declare = |rec: &mut S, ids: &mut Vec<(u16, usize)>, ch: &mcap::Channel<'_>| {
        let (schema, encoding) = ch.schema.as_ref().map_or(("", ""), |s| (s.name.as_str(), s.encoding.as_str()));
        let i = rec.channel(&ch.topic, schema, encoding, &ch.message_encoding);
        ids.push((ch.id, i));
        i
    };
    // The summary lists every channel, also those without messages. A damaged summary is ignored here: the
    // pass over the messages below reports what is wrong with the file.
    if let Ok(Some(summary)) = mcap::Summary::read(buf) {
        let mut all: Vec<_> = summary.channels.values().collect();
        all.sort_by_key(|c| c.id);
        for c in all {
            declare(rec, &mut ids, c);
        }
    }
    // A cap on record lengths: a corrupted length then fails cleanly instead of overflowing inside the
    // mcap crate (its default is no limit).
    let limit = buf.len().saturating_mul(64).clamp(MIN_RECORD_LIMIT, MAX_RECORD_LIMIT);
    let options = LinearReaderOptions::default().with_validate_chunk_crcs(true).with_record_length_limit(limit);
    for m in mcap::io::MessageReader::new_with_options(std::io::Cursor::new(buf), options) {
        let m = m.map_err(|e| mcap_error(path, e))?;
        let i = match ids.iter().find(|(id, _)| *id == m.channel.id) {
            Some(&(_, i)) => i,
            None => declare(rec, &mut ids, &m.channel),
        };
        rec.message(i, &m.data, m.log_time);
    }
    Ok(())
}
