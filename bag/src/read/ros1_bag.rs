//! ROS 1 bags (format 2.0) through the `rosbag` crate: the bag header checked by hand before
//! the crate maps the file, the topics from the index section, and the chunks read one at a
//! time for the log-time merge.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Read, Seek};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::TopicInfo;
use crate::codec::Encoding;
use crate::merge::{ChunkLoader, ChunkRef, Stored};
use crate::{BagError, Result};

/// The header of a ROS 1 bag: where the index starts. Read by hand before the `rosbag` crate
/// maps the file, because that crate slices the file at `index_pos` unchecked.
fn ros1_index_pos(path: &Path) -> Result<u64> {
    let bad = |what: String| BagError::Ros1 {
        path: path.to_path_buf(),
        what,
    };
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut head = Vec::new();
    (&mut file)
        .take(4096 + 13)
        .read_to_end(&mut head)
        .map_err(io)?;
    let body = head.get(13..).unwrap_or(&[]);
    let header_len = body
        .get(..4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        .ok_or_else(|| bad(format!("file of {len} bytes ends inside its header")))?;
    let header = body.get(4..4 + header_len).ok_or_else(|| {
        bad(format!(
            "bag header of {header_len} bytes runs past the file"
        ))
    })?;
    let mut fields = header;
    let mut index_pos = None;
    while fields.len() >= 4 {
        let n = u32::from_le_bytes([fields[0], fields[1], fields[2], fields[3]]) as usize;
        let Some(field) = fields.get(4..4 + n) else {
            return Err(bad("bag header field runs past the header".to_owned()));
        };
        if let Some(value) = field.strip_prefix(b"index_pos=")
            && let Ok(v) = <[u8; 8]>::try_from(value)
        {
            index_pos = Some(u64::from_le_bytes(v));
        }
        fields = &fields[4 + n..];
    }
    let index_pos = index_pos.ok_or_else(|| bad("bag header has no index_pos".to_owned()))?;
    // The header record's data (padding) follows its header: the chunk section starts after
    // it, and the `rosbag` crate slices the file from there to `index_pos` unchecked (found
    // by `bag_ros1`: a padding length past `index_pos` panicked in `chunk_records`).
    let padding = body
        .get(4 + header_len..8 + header_len)
        .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
        .ok_or_else(|| bad("bag header record ends before its data length".to_owned()))?;
    let data_start = 13 + 4 + header_len as u64 + 4 + padding;
    if index_pos == 0 {
        return Err(bad(
            "index_pos is 0: the bag was not closed (reindex it with `rosbag reindex`)".to_owned(),
        ));
    }
    if index_pos > len {
        return Err(bad(format!(
            "index_pos {index_pos} is outside the file of {len} bytes (truncated?)"
        )));
    }
    if index_pos < data_start {
        return Err(bad(format!(
            "index_pos {index_pos} is before the chunk section, which starts at byte \
             {data_start} (after the bag header and its {padding} bytes of data)"
        )));
    }
    Ok(index_pos)
}

/// The largest decompressed ROS 1 chunk read: 1 GiB. `rosbag record` writes chunks of 768 KB;
/// a larger `size` is a corrupt header, refused before the `rosbag` crate allocates it (it
/// reserves the announced size, up to 4 GiB, before decompressing; found by `bag_ros1`).
pub const MAX_ROS1_CHUNK: u64 = 1 << 30;

/// Checks the `size` field of the chunk record at byte `at` against [`MAX_ROS1_CHUNK`].
fn ros1_chunk_size_ok(path: &Path, at: u64) -> Result<(), String> {
    let mut file = File::open(path).map_err(|e| e.to_string())?;
    file.seek(std::io::SeekFrom::Start(at))
        .map_err(|e| e.to_string())?;
    let mut len = [0u8; 4];
    file.read_exact(&mut len)
        .map_err(|_| "record header runs past the file".to_owned())?;
    let len = u64::from(u32::from_le_bytes(len));
    let mut header = Vec::new();
    (&mut file)
        .take(len.min(1 << 20))
        .read_to_end(&mut header)
        .map_err(|e| e.to_string())?;
    let mut fields = header.as_slice();
    while fields.len() >= 4 {
        let n = u32::from_le_bytes([fields[0], fields[1], fields[2], fields[3]]) as usize;
        let Some(field) = fields.get(4..4 + n) else {
            break;
        };
        if let Some(value) = field.strip_prefix(b"size=")
            && let Ok(v) = <[u8; 4]>::try_from(value)
        {
            let size = u64::from(u32::from_le_bytes(v));
            if size > MAX_ROS1_CHUNK {
                return Err(format!(
                    "announces {size} decompressed bytes, over the limit of {MAX_ROS1_CHUNK}"
                ));
            }
        }
        fields = &fields[4 + n..];
    }
    Ok(())
}

/// The topics of a ROS 1 bag, from its connection records and chunk infos.
pub(super) fn ros1_topics(path: &Path) -> Result<Vec<TopicInfo>> {
    ros1_index_pos(path)?;
    let bag = rosbag::RosBag::new(path).map_err(|e| BagError::Ros1 {
        path: path.to_path_buf(),
        what: e.to_string(),
    })?;
    let mut connections: BTreeMap<u32, TopicInfo> = BTreeMap::new();
    let mut counts: BTreeMap<u32, u64> = BTreeMap::new();
    for record in bag.index_records() {
        let record = record.map_err(|e| BagError::Ros1 {
            path: path.to_path_buf(),
            what: format!("index section: {}", e),
        })?;
        match record {
            rosbag::IndexRecord::Connection(c) => {
                connections.insert(
                    c.id,
                    TopicInfo {
                        name: c.topic.to_owned(),
                        type_name: c.tp.to_owned(),
                        encoding: Encoding::Ros1,
                        md5: Some(c.md5sum.iter().map(|b| format!("{b:02x}")).collect()),
                        count: None,
                    },
                );
            }
            rosbag::IndexRecord::ChunkInfo(info) => {
                for entry in info.entries() {
                    *counts.entry(entry.conn_id).or_insert(0) += u64::from(entry.count);
                }
            }
            rosbag::IndexRecord::IndexData(_) => {}
        }
    }
    let mut by_name: BTreeMap<String, TopicInfo> = BTreeMap::new();
    for (id, mut info) in connections {
        info.count = Some(counts.get(&id).copied().unwrap_or(0));
        match by_name.get_mut(&info.name) {
            Some(t) => t.count = t.count.zip(info.count).map(|(a, b)| a + b),
            None => {
                by_name.insert(info.name.clone(), info);
            }
        }
    }
    Ok(by_name.into_values().collect())
}

/// The chunks of a ROS 1 bag, one decompressed at a time (their positions and earliest log
/// times come from the index's chunk infos).
pub(super) struct Ros1Chunks {
    path: PathBuf,
    bag: rosbag::RosBag,
    /// Topic of each connection id (from the index section and the chunks' own records).
    topics: BTreeMap<u32, Arc<str>>,
    /// The wanted topics.
    wanted: Vec<String>,
}

impl Ros1Chunks {
    /// The loader and the chunks that hold the `wanted` topics (by the chunk infos' counts per
    /// connection).
    pub(super) fn open(path: &Path, wanted: &[String]) -> Result<(Self, Vec<ChunkRef>)> {
        let bad = |what: String| BagError::Ros1 {
            path: path.to_path_buf(),
            what,
        };
        ros1_index_pos(path)?;
        let bag = rosbag::RosBag::new(path).map_err(|e| bad(e.to_string()))?;
        let mut topics = BTreeMap::new();
        let mut infos = Vec::new();
        for record in bag.index_records() {
            match record.map_err(|e| bad(format!("index section: {}", e)))? {
                rosbag::IndexRecord::Connection(c) => {
                    topics.insert(c.id, Arc::<str>::from(c.topic));
                }
                rosbag::IndexRecord::ChunkInfo(info) => {
                    let connections: Vec<u32> = info.entries().map(|e| e.conn_id).collect();
                    let chunk = ChunkRef {
                        start: info.start_time,
                        at: info.chunk_pos,
                        length: 0,
                    };
                    infos.push((chunk, connections));
                }
                rosbag::IndexRecord::IndexData(_) => {}
            }
        }
        // Chunks whose infos list connections, none of a wanted topic, are not read.
        let chunks = infos
            .into_iter()
            .filter(|(_, connections)| {
                connections.is_empty()
                    || connections.iter().any(|id| {
                        topics
                            .get(id)
                            .is_none_or(|t| wanted.iter().any(|w| **w == **t))
                    })
            })
            .map(|(chunk, _)| chunk)
            .collect();
        let loader = Self {
            path: path.to_path_buf(),
            bag,
            topics,
            wanted: wanted.to_vec(),
        };
        Ok((loader, chunks))
    }

    /// The wanted messages of the chunk at byte `at`, or what broke in it.
    fn read_chunk(&mut self, at: u64) -> Result<Vec<Stored>, String> {
        ros1_chunk_size_ok(&self.path, at)?;
        let mut records = self.bag.chunk_records();
        let record = match records.seek(at) {
            Ok(()) => records.next(),
            Err(e) => Some(Err(e)),
        };
        let chunk = match record {
            None => return Err("past the chunk section".to_owned()),
            Some(Err(e)) => return Err(e.to_string()),
            Some(Ok(rosbag::ChunkRecord::IndexData(_))) => {
                return Err("an index record where a chunk should be".to_owned());
            }
            Some(Ok(rosbag::ChunkRecord::Chunk(chunk))) => chunk,
        };
        let mut batch = Vec::new();
        for m in chunk.messages() {
            match m.map_err(|e| e.to_string())? {
                rosbag::MessageRecord::Connection(c) => {
                    self.topics.insert(c.id, Arc::<str>::from(c.topic));
                }
                rosbag::MessageRecord::MessageData(d) => {
                    let Some(topic) = self.topics.get(&d.conn_id) else {
                        return Err(format!("message of unknown connection {}", d.conn_id));
                    };
                    if self.wanted.iter().any(|w| **w == **topic) {
                        batch.push((topic.clone(), d.time, d.data.to_vec()));
                    }
                }
            }
        }
        Ok(batch)
    }
}

impl ChunkLoader for Ros1Chunks {
    fn load(&mut self, chunk: &ChunkRef) -> Result<Vec<Stored>> {
        self.read_chunk(chunk.at).map_err(|what| BagError::Ros1 {
            path: self.path.clone(),
            what: format!("chunk at byte {}: {what}", chunk.at),
        })
    }
}
