//! The index of a ROS 1 bag: its index section (connection and chunk-info records at
//! `index_pos`), checked against the bag header's counts, or, for a bag whose index is missing
//! or unreadable, the same found by a linear scan of its chunk records.

use std::collections::BTreeMap;
use std::io::{Read, Seek};

use super::ros1_records::{
    BagHeader, Connection, Fields, Inner, OP_CHUNK, OP_CHUNK_INFO, OP_CONNECTION, OP_INDEX_DATA,
    Problem, Ros1File, chunk_data, chunk_records, connection, cut_record, time_of, u32_of, u64_of,
};

/// A chunk as the index (or the linear scan) has it: where, from when, and how many messages
/// of each connection.
#[derive(Debug, Clone)]
pub(crate) struct ChunkEntry {
    /// The byte of the chunk record.
    pub at: u64,
    /// The log time of its earliest message, ns.
    pub start: u64,
    /// (connection id, messages) of the connections it holds (empty: not known).
    pub counts: Vec<(u32, u32)>,
}

/// What the index of a bag lists.
#[derive(Debug, Clone, Default)]
pub(crate) struct Index {
    /// Connections by id.
    pub connections: BTreeMap<u32, Connection>,
    /// Chunks, in file order.
    pub chunks: Vec<ChunkEntry>,
    /// What the reader had to do (a linear scan, broken chunks).
    pub notes: Vec<String>,
}

/// The index section at `index_pos`: connection and chunk-info records up to the end of the
/// file, checked against the counts of the bag header. Any problem is an error (the caller
/// falls back to [`scan_chunks`]).
pub(crate) fn read_index<R: Read + Seek>(
    file: &mut Ros1File<R>,
    header: &BagHeader,
    index_pos: u64,
) -> Result<Index, Problem> {
    let mut index = Index::default();
    let mut data = Vec::new();
    let mut at = index_pos;
    while at < file.len() {
        let record = file.record(at)?;
        file.data(&record, &mut data)?;
        match record.op {
            OP_CONNECTION => {
                let c = connection(&record.header, &data)
                    .map_err(|e| format!("connection record at byte {at}: {e}"))?;
                index.connections.entry(c.id).or_insert(c);
            }
            OP_CHUNK_INFO => index.chunks.push(
                chunk_info(&record.header, &data)
                    .map_err(|e| format!("chunk info at byte {at}: {e}"))?,
            ),
            op => {
                return Err(format!(
                    "a record of op {op:#04x} at byte {at} in the index"
                ));
            }
        }
        at = record.end();
    }
    let missing = |what: &str, want: Option<u32>, got: usize| {
        want.filter(|&n| (n as usize) > got)
            .map(|n| format!("the index lists {got} {what} of the {n} the bag header announces"))
    };
    if let Some(problem) = missing("connections", header.conn_count, index.connections.len())
        .or_else(|| missing("chunks", header.chunk_count, index.chunks.len()))
    {
        return Err(problem);
    }
    Ok(index)
}

/// A chunk-info record: `ver` 1, `chunk_pos`, `start_time`, `count`; data: `count` × (connection
/// id, messages).
fn chunk_info(header: &[u8], data: &[u8]) -> Result<ChunkEntry, Problem> {
    let (mut ver, mut at, mut start, mut count) = (None, None, None, None);
    for field in Fields(header) {
        let (name, v) = field?;
        match name {
            b"ver" => ver = Some(u32_of(name, v)?),
            b"chunk_pos" => at = Some(u64_of(name, v)?),
            b"start_time" => start = Some(time_of(name, v)?),
            b"count" => count = Some(u32_of(name, v)?),
            _ => {}
        }
    }
    if ver != Some(1) {
        return Err(format!("version {ver:?}, not 1"));
    }
    let (Some(at), Some(start), Some(count)) = (at, start, count) else {
        return Err("`chunk_pos`, `start_time` or `count` missing".to_owned());
    };
    if data.len() as u64 != 8 * u64::from(count) {
        return Err(format!(
            "{} bytes of entries for a count of {count}",
            data.len()
        ));
    }
    let counts = data
        .chunks_exact(8)
        .map(|e| {
            (
                u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                u32::from_le_bytes([e[4], e[5], e[6], e[7]]),
            )
        })
        .collect();
    Ok(ChunkEntry { at, start, counts })
}

/// Finds the chunks by reading the file from the first chunk record to its end (or to `end`),
/// decompressing each one to take its connections, counts and earliest log time: for a bag
/// whose index is missing or unreadable. A chunk that cannot be read is listed still (with the
/// start of the chunk before it), so that reading it reports it; the scan stops where a record
/// cannot be read at all. What was skipped goes to the notes.
pub(crate) fn scan_chunks<R: Read + Seek>(
    file: &mut Ros1File<R>,
    header: &BagHeader,
    end: u64,
) -> Index {
    let mut index = Index::default();
    let (mut raw, mut out, mut data) = (Vec::new(), Vec::new(), Vec::new());
    let mut at = header.data_start;
    let mut last_start = 0;
    while at < end {
        let record = match file.record_head(at) {
            Ok(r) if r.end() <= file.len() => r,
            Ok(r) => {
                // A chunk cut short is listed, so that reading it says so.
                if r.op == OP_CHUNK {
                    index.chunks.push(ChunkEntry {
                        at,
                        start: last_start,
                        counts: Vec::new(),
                    });
                }
                let e = cut_record(&r, file.len());
                index.notes.push(format!("the linear scan stopped: {e}"));
                break;
            }
            Err(e) => {
                index.notes.push(format!("the linear scan stopped: {e}"));
                break;
            }
        };
        match record.op {
            OP_CHUNK => {
                let mut counts = BTreeMap::<u32, u32>::new();
                let mut start = u64::MAX;
                let read = chunk_data(file, &record, &mut raw, &mut out).and_then(|()| {
                    chunk_records(&out, |r| {
                        match r {
                            Inner::Connection(c) => {
                                index.connections.entry(c.id).or_insert(c);
                            }
                            Inner::Message { conn, time, .. } => {
                                *counts.entry(conn).or_insert(0) += 1;
                                start = start.min(time);
                            }
                        }
                        Ok(())
                    })
                });
                match read {
                    Ok(()) if counts.is_empty() => {}
                    Ok(()) => {
                        last_start = start;
                        index.chunks.push(ChunkEntry {
                            at,
                            start,
                            counts: counts.into_iter().collect(),
                        });
                    }
                    Err(e) => {
                        index.notes.push(format!(
                            "chunk at byte {at}: {e}; its messages are not counted"
                        ));
                        index.chunks.push(ChunkEntry {
                            at,
                            start: last_start,
                            counts: Vec::new(),
                        });
                    }
                }
            }
            OP_CONNECTION => {
                if let Ok(c) = file
                    .data(&record, &mut data)
                    .and_then(|()| connection(&record.header, &data))
                {
                    index.connections.entry(c.id).or_insert(c);
                }
            }
            // Index data (the times of a chunk's messages, known from the chunk itself), chunk
            // infos (an index section reached), any other record: skipped.
            OP_INDEX_DATA | OP_CHUNK_INFO => {}
            _ => {}
        }
        at = record.end();
    }
    index
}
