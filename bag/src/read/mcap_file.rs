//! MCAP files through the `mcap` crate: the summary (checked first, see `mcap_check`), the
//! topics from it or from one linear scan, and the chunks of an indexed file read one at a
//! time for the log-time merge.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Read, Seek};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::topic::TopicInfo;
use crate::codec::Encoding;
use crate::mcap_check::{self, MAX_MCAP_RECORD, mcap_options};
use crate::merge::{ChunkLoader, ChunkRef, Stored};
use crate::{BagError, Result};

/// The summary of an MCAP file, or why it has none that can be read (`Ok((None, None))`: the
/// file has no summary).
fn mcap_summary(path: &Path) -> Result<(Option<mcap::Summary>, Option<String>)> {
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    // Every field of every summary record must lie within its record (see `mcap_check`).
    if let Err(problem) = mcap_check::check_summary(&mut file, size).map_err(io)? {
        return Ok((None, Some(problem)));
    }
    file.seek(std::io::SeekFrom::Start(0)).map_err(io)?;
    // Records in the summary are capped too (a corrupt length must not allocate gigabytes).
    let mut reader = mcap::sans_io::SummaryReader::new_with_options(
        mcap::sans_io::SummaryReaderOptions::default()
            .with_file_size(size)
            .with_record_length_limit(MAX_MCAP_RECORD),
    );
    // A summary that cannot be read (a file cut short by a recorder that was killed has no
    // footer) is not fatal: the topics come from a linear scan instead.
    let mut summary_problem = None;
    while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(event) => event,
            Err(e) => {
                summary_problem = Some(e.to_string());
                break;
            }
        };
        match event {
            mcap::sans_io::SummaryReadEvent::ReadRequest(need) => {
                let n = file.read(reader.insert(need)).map_err(io)?;
                reader.notify_read(n);
            }
            mcap::sans_io::SummaryReadEvent::SeekRequest(to) => {
                let at = file.seek(to).map_err(io)?;
                reader.notify_seeked(at);
            }
        }
    }
    if summary_problem.is_some() {
        return Ok((None, summary_problem));
    }
    Ok((reader.finish(), None))
}

/// The topics of an MCAP file: from its summary, or by one linear scan when it has none.
pub(super) fn mcap_topics(path: &Path) -> Result<(Vec<TopicInfo>, Vec<String>)> {
    let (summary, summary_problem) = mcap_summary(path)?;
    let topic = |c: &mcap::Channel<'_>, count| -> Result<TopicInfo> {
        let encoding = match c.message_encoding.as_str() {
            "cdr" => Encoding::Cdr,
            "ros1" => Encoding::Ros1,
            other => {
                return Err(BagError::UnsupportedEncoding {
                    topic: c.topic.clone(),
                    encoding: other.to_owned(),
                });
            }
        };
        Ok(TopicInfo {
            name: c.topic.clone(),
            type_name: c.schema.as_ref().map_or(String::new(), |s| s.name.clone()),
            encoding,
            md5: c.metadata.get("md5sum").cloned(),
            count,
        })
    };
    let mut by_name: BTreeMap<String, TopicInfo> = BTreeMap::new();
    let mut notes = Vec::new();
    let add = |info: TopicInfo, by_name: &mut BTreeMap<String, TopicInfo>| {
        // Two channels of one topic (two publishers) count together.
        match by_name.get_mut(&info.name) {
            Some(t) => t.count = t.count.zip(info.count).map(|(a, b)| a + b),
            None => {
                by_name.insert(info.name.clone(), info);
            }
        }
    };
    match summary {
        Some(summary) if !summary.channels.is_empty() => {
            if summary.chunk_indexes.is_empty() {
                notes.push(format!(
                    "{}: no chunk index; messages come in file order, not sorted by log time",
                    path.display()
                ));
            }
            let counts = summary.stats.as_ref().map(|s| &s.channel_message_counts);
            let mut channels: Vec<_> = summary.channels.values().collect();
            channels.sort_by_key(|c| c.id);
            for c in channels {
                let count = counts.map(|m| m.get(&c.id).copied().unwrap_or(0));
                add(topic(c, count)?, &mut by_name);
            }
        }
        _ => {
            notes.push(match &summary_problem {
                None => format!(
                    "{}: no summary; topics found by a linear scan of the file, messages come \
                     in file order, not sorted by log time",
                    path.display()
                ),
                Some(e) => format!(
                    "{}: summary unreadable ({e}); topics found by a linear scan of the file, \
                     messages come in file order, not sorted by log time",
                    path.display()
                ),
            });
            let reader = mcap_check::LinearMessages::open(path)?;
            let stop = reader.stop_error();
            notes.extend(stop.as_ref().map(|e| format!("{e}; reading stops there")));
            let mut counts: BTreeMap<u16, (TopicInfo, u64)> = BTreeMap::new();
            for m in reader {
                let m = match m {
                    Ok(m) => m,
                    // A file cut short: what was read before the cut is kept and said.
                    Err(e) if !counts.is_empty() => {
                        let n: u64 = counts.values().map(|c| c.1).sum();
                        notes.push(format!(
                            "{}: the linear scan stopped after {n} messages: {e}",
                            path.display()
                        ));
                        break;
                    }
                    Err(e) => {
                        return Err(stop.unwrap_or(e));
                    }
                };
                if let Some(entry) = counts.get_mut(&m.channel.id) {
                    entry.1 += 1;
                } else {
                    counts.insert(m.channel.id, (topic(&m.channel, None)?, 1));
                }
            }
            for (_, (mut info, n)) in counts {
                info.count = Some(n);
                add(info, &mut by_name);
            }
        }
    }
    Ok((by_name.into_values().collect(), notes))
}

/// The chunks of an indexed MCAP file, read one at a time (CRC checked, records capped).
pub(super) struct McapChunks {
    path: PathBuf,
    file: File,
    /// Topic of each wanted channel.
    channels: BTreeMap<u16, Arc<str>>,
    /// This pass's chunks against the whole-file allowance of inflation.
    inflation: crate::limits::Inflation,
}

impl McapChunks {
    /// The loader and the chunks that may hold the `wanted` topics, or `None` when the file
    /// has no summary with chunk indexes (it is then read in file order).
    pub(super) fn open(path: &Path, wanted: &[String]) -> Result<Option<(Self, Vec<ChunkRef>)>> {
        let Some(summary) = mcap_summary(path)?.0 else {
            return Ok(None);
        };
        if summary.chunk_indexes.is_empty() || summary.channels.is_empty() {
            return Ok(None);
        }
        let channels: BTreeMap<u16, Arc<str>> = summary
            .channels
            .values()
            .filter(|c| wanted.contains(&c.topic))
            .map(|c| (c.id, Arc::from(c.topic.as_str())))
            .collect();
        // A chunk whose message indexes name none of the wanted channels is not read (a
        // writer without message indexes leaves the map empty: such chunks are all read).
        let chunks = summary
            .chunk_indexes
            .iter()
            .filter(|c| {
                c.message_index_offsets.is_empty()
                    || c.message_index_offsets
                        .keys()
                        .any(|id| channels.contains_key(id))
            })
            .map(|c| ChunkRef {
                start: c.message_start_time,
                at: c.chunk_start_offset,
                length: c.chunk_length,
            })
            .collect();
        let file = File::open(path).map_err(|source| BagError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let loader = Self {
            path: path.to_path_buf(),
            file,
            channels,
            inflation: crate::limits::Inflation::default(),
        };
        Ok(Some((loader, chunks)))
    }
}

impl ChunkLoader for McapChunks {
    fn load(&mut self, chunk: &ChunkRef) -> Result<Vec<Stored>> {
        let at = chunk.at;
        let bad = |source| BagError::McapChunk {
            path: self.path.clone(),
            offset: at,
            source,
        };
        // The record: opcode, length, body (the chunk's header and its compressed records).
        let length = usize::try_from(chunk.length)
            .ok()
            .filter(|&n| n <= MAX_MCAP_RECORD)
            .ok_or_else(|| bad(mcap::McapError::ChunkTooLarge(chunk.length)))?;
        let mut record = Vec::new();
        self.file
            .seek(std::io::SeekFrom::Start(at))
            .and_then(|_| {
                (&mut self.file)
                    .take(length as u64)
                    .read_to_end(&mut record)
            })
            .map_err(|source| BagError::Io {
                path: self.path.clone(),
                source,
            })?;
        if record.len() < length || record.first() != Some(&mcap::records::op::CHUNK) {
            return Err(bad(mcap::McapError::UnexpectedEoc));
        }
        // What `mcap` does not check (see `mcap_check`): an uncompressed chunk's records fit.
        let fits = record
            .get(9..)
            .and_then(mcap_check::chunk_parts)
            .is_some_and(|(name, records, declared)| {
                !name.is_empty() || mcap_check::plain_records_fit(records, declared)
            });
        if !fits {
            return Err(mcap_check::bad_chunk(&self.path, at));
        }
        if let Some(why) = record.get(9..).and_then(mcap_check::chunk_bomb) {
            return Err(mcap_check::bomb_chunk(&self.path, at, &why));
        }
        if let Some((uncompressed, compressed)) = record.get(9..).and_then(mcap_check::chunk_sizes)
        {
            self.inflation
                .charge(compressed, uncompressed)
                .map_err(|why| mcap_check::bomb_chunk(&self.path, at, &why))?;
        }
        let mut reader = mcap::sans_io::LinearReader::new_with_options(
            mcap_options()
                .with_skip_start_magic(true)
                .with_skip_end_magic(true),
        );
        let mut rest = record.as_slice();
        let mut messages = Vec::new();
        while let Some(event) = reader.next_event() {
            match event.map_err(bad)? {
                mcap::sans_io::LinearReadEvent::ReadRequest(need) => {
                    let n = need.min(rest.len());
                    reader.insert(n).copy_from_slice(&rest[..n]);
                    reader.notify_read(n);
                    rest = &rest[n..];
                }
                mcap::sans_io::LinearReadEvent::Record { opcode, data } => {
                    if opcode != mcap::records::op::MESSAGE {
                        continue;
                    }
                    if let mcap::records::Record::Message { header, data } =
                        mcap::parse_record(opcode, data).map_err(bad)?
                        && let Some(topic) = self.channels.get(&header.channel_id)
                    {
                        messages.push((topic.clone(), header.log_time, data.into_owned()));
                    }
                }
            }
        }
        Ok(messages)
    }
}
