//! ROS 1 bags (format 2.0) through our own record reader (`ros1_records.rs`) over a
//! `BufReader<File>`: the index read once when the bag is opened (or, when it is missing or
//! unreadable, the chunks found by a linear scan, which the notes say), the topics from it,
//! and the chunks read one at a time for the log-time merge, so that memory stays O(chunk).

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::ros1_index::{Index, read_index, scan_chunks};
use super::ros1_records::{Inner, Ros1File, bag_header, chunk_records, read_chunk};
use super::topic::TopicInfo;
use crate::codec::Encoding;
use crate::merge::{ChunkLoader, ChunkRef, Stored};
use crate::{BagError, Result};

/// The bag at `path`, opened for reading records.
fn open_file(path: &Path) -> Result<Ros1File<BufReader<File>>> {
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    Ok(Ros1File::new(BufReader::with_capacity(1 << 16, file), len))
}

/// The index of the bag at `path`: its index section, or (when `index_pos` is 0, past the end,
/// or the section cannot be read) the chunks found by a linear scan, with notes saying so.
///
/// # Errors
/// [`BagError::Io`]; [`BagError::Ros1`] when the bag header is broken, or when the index is
/// unreadable and a linear scan finds no connection either.
pub(super) fn ros1_index(path: &Path) -> Result<Index> {
    let bad = |what: String| BagError::Ros1 {
        path: path.to_path_buf(),
        what,
    };
    let mut file = open_file(path)?;
    let header = bag_header(&mut file).map_err(bad)?;
    let len = file.len();
    let reason = match header.index_pos {
        None => "the bag header has no index_pos".to_owned(),
        Some(0) => "index_pos is 0: the bag was not closed (`rosbag reindex` rebuilds its index)"
            .to_owned(),
        Some(at) if at > len => {
            format!("index_pos {at} is past the end of the file of {len} bytes (cut short?)")
        }
        Some(at) => match read_index(&mut file, &header, at) {
            Ok(index) => return Ok(index),
            Err(e) => format!("the index section at byte {at}: {e}"),
        },
    };
    // Up to the end of the file: an index section met on the way is skipped record by record
    // (its connections are kept), and a cut record ends the scan.
    let mut index = scan_chunks(&mut file, &header, len);
    if index.connections.is_empty() {
        let mut what = vec![reason];
        what.append(&mut index.notes);
        return Err(bad(format!(
            "{}; a linear scan found no readable connection in {} chunks",
            what.join("; "),
            index.chunks.len()
        )));
    }
    let mut notes = vec![format!(
        "{}: summary unreadable ({reason}); {} chunks found by a linear scan of the file",
        path.display(),
        index.chunks.len()
    )];
    notes.extend(
        index
            .notes
            .drain(..)
            .map(|n| format!("{}: {n}", path.display())),
    );
    index.notes = notes;
    Ok(index)
}

/// The topics of a ROS 1 bag, from its index: types and MD5 sums from the connection records,
/// counts from the chunk infos (two connections of one topic count together).
pub(super) fn ros1_topics(index: &Index) -> Vec<TopicInfo> {
    let mut counts: BTreeMap<u32, u64> = BTreeMap::new();
    for chunk in &index.chunks {
        for &(id, n) in &chunk.counts {
            *counts.entry(id).or_insert(0) += u64::from(n);
        }
    }
    let mut by_name: BTreeMap<String, TopicInfo> = BTreeMap::new();
    for (id, c) in &index.connections {
        let count = counts.get(id).copied().unwrap_or(0);
        match by_name.get_mut(&c.topic) {
            Some(t) => t.count = t.count.map(|a| a + count),
            None => {
                by_name.insert(
                    c.topic.clone(),
                    TopicInfo {
                        name: c.topic.clone(),
                        type_name: c.type_name.clone(),
                        encoding: Encoding::Ros1,
                        md5: c.md5sum.clone(),
                        count: Some(count),
                    },
                );
            }
        }
    }
    by_name.into_values().collect()
}

/// The chunks of a ROS 1 bag, one read and decompressed at a time (positions and earliest log
/// times from the index).
pub(super) struct Ros1Chunks {
    path: PathBuf,
    file: Ros1File<BufReader<File>>,
    /// Topic of each connection id (from the index, and the chunks' own records).
    topics: BTreeMap<u32, Arc<str>>,
    /// The wanted topics, and the connections of them.
    wanted: Vec<String>,
    wanted_ids: BTreeSet<u32>,
    /// A chunk's compressed bytes and its records, kept between chunks.
    raw: Vec<u8>,
    records: Vec<u8>,
}

impl Ros1Chunks {
    /// The loader and the chunks that hold the `wanted` topics (by the index's counts per
    /// connection; a chunk whose counts are not known is read).
    pub(super) fn open(
        path: &Path,
        index: &Index,
        wanted: &[String],
    ) -> Result<(Self, Vec<ChunkRef>)> {
        let topics: BTreeMap<u32, Arc<str>> = index
            .connections
            .iter()
            .map(|(&id, c)| (id, Arc::<str>::from(c.topic.as_str())))
            .collect();
        let wanted_ids: BTreeSet<u32> = topics
            .iter()
            .filter(|(_, t)| wanted.iter().any(|w| **w == ***t))
            .map(|(&id, _)| id)
            .collect();
        let chunks = index
            .chunks
            .iter()
            .filter(|c| {
                c.counts.is_empty()
                    || c.counts
                        .iter()
                        .any(|(id, _)| wanted_ids.contains(id) || !topics.contains_key(id))
            })
            .map(|c| ChunkRef {
                start: c.start,
                at: c.at,
                length: 0,
            })
            .collect();
        let loader = Self {
            path: path.to_path_buf(),
            file: open_file(path)?,
            topics,
            wanted: wanted.to_vec(),
            wanted_ids,
            raw: Vec::new(),
            records: Vec::new(),
        };
        Ok((loader, chunks))
    }

    /// The wanted messages of the chunk at byte `at`, or what broke in it.
    fn read_chunk(&mut self, at: u64) -> Result<Vec<Stored>, String> {
        read_chunk(&mut self.file, at, &mut self.raw, &mut self.records)?;
        let (topics, wanted, wanted_ids) = (&mut self.topics, &self.wanted, &mut self.wanted_ids);
        let mut batch = Vec::new();
        chunk_records(&self.records, |record| {
            match record {
                Inner::Connection(c) => {
                    if let std::collections::btree_map::Entry::Vacant(slot) = topics.entry(c.id) {
                        if wanted.contains(&c.topic) {
                            wanted_ids.insert(c.id);
                        }
                        slot.insert(Arc::from(c.topic.as_str()));
                    }
                }
                Inner::Message { conn, time, data } => {
                    if wanted_ids.contains(&conn) {
                        if let Some(topic) = topics.get(&conn) {
                            batch.push((topic.clone(), time, data.to_vec()));
                        }
                    } else if !topics.contains_key(&conn) {
                        return Err(format!("message of unknown connection {conn}"));
                    }
                }
            }
            Ok(())
        })?;
        Ok(batch)
    }
}

impl ChunkLoader for Ros1Chunks {
    fn load(&mut self, chunk: &ChunkRef) -> Result<Vec<Stored>> {
        self.read_chunk(chunk.at)
            .map_err(|what| BagError::Ros1Chunk {
                path: self.path.clone(),
                offset: chunk.at,
                what,
            })
    }
}
