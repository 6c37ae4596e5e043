//! Opening a robot log and streaming its messages: ROS 1 bags (format 2.0: uncompressed, bz2
//! and lz4 chunks, through the `rosbag` crate) and MCAP files (chunked or not, zstd or lz4,
//! with or without a summary, through the `mcap` crate).
//!
//! Messages come in log-time order: the chunks listed by the file's index (a ROS 1 bag's
//! chunk infos, an MCAP summary's chunk indexes) are merged by log time (`merge.rs`), holding
//! only the chunks that overlap in time, one chunk when none do. An MCAP file without a
//! summary or without chunk indexes (written unchunked, or cut short) is read in file order,
//! the order its recorder wrote (receive order), and [`Bag::notes`] says so. The list of
//! topics comes from the same index; an MCAP file without a summary is scanned once to list
//! them.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Read, Seek};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::codec::{Encoding, decode};
use crate::mcap_check;
use crate::merge::{ChunkLoader, ChunkRef, Merge, Stored};
use crate::msg::{Message, names_type};
use crate::{BagError, Result};

/// The two file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// A ROS 1 bag, format 2.0.
    Ros1,
    /// An MCAP file (ROS 2 bags, Foxglove recordings).
    Mcap,
}

/// One topic of a log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    /// Its name (e.g. `/scan`).
    pub name: String,
    /// The recorded type name (`sensor_msgs/LaserScan` in ROS 1, `sensor_msgs/msg/LaserScan`
    /// in ROS 2).
    pub type_name: String,
    /// How its messages are serialised.
    pub encoding: Encoding,
    /// The ROS 1 MD5 sum of its definition, when the file records one.
    pub md5: Option<String>,
    /// How many messages it has, when the index says.
    pub count: Option<u64>,
}

/// One message as stored: its topic, when it was logged, and its bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct RawMessage {
    /// The topic.
    pub topic: Arc<str>,
    /// When it was recorded, nanoseconds since the UNIX epoch (a bag's receive time).
    pub log_time: u64,
    /// Its index within its topic, from 0, in the order read (log-time order, or file order
    /// where the file has no index: see [`Bag::notes`]).
    pub index: u64,
    /// Its serialised bytes.
    pub data: Vec<u8>,
}

impl RawMessage {
    /// The log time in seconds.
    pub fn log_seconds(&self) -> f64 {
        self.log_time as f64 * 1e-9
    }
}

/// An opened robot log: its format, topics and notes. Messages are read from the file anew by
/// each call of [`Bag::messages`] or [`Bag::read`].
///
/// # Example
/// ```no_run
/// use haunts_bag::{Bag, msg::LaserScan};
///
/// let bag = Bag::open("robot.mcap")?;
/// for topic in bag.topics() {
///     println!("{} {} {:?}", topic.name, topic.type_name, topic.count);
/// }
/// for scan in bag.read::<LaserScan>("/scan")? {
///     let (raw_time, scan) = scan?;
///     println!("{raw_time} {} beams", scan.ranges.len());
/// }
/// # Ok::<(), haunts_bag::BagError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Bag {
    path: PathBuf,
    format: Format,
    topics: Vec<TopicInfo>,
    notes: Vec<String>,
}

impl Bag {
    /// Opens the log at `path`, telling the format by its first bytes, and reads its index.
    ///
    /// # Errors
    /// [`BagError::Io`], [`BagError::UnknownFormat`], and [`BagError::Ros1`] /
    /// [`BagError::Mcap`] when the file's structure is broken.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref().to_path_buf();
        let io = |source| BagError::Io {
            path: path.clone(),
            source,
        };
        let mut file = File::open(&path).map_err(io)?;
        let mut magic = Vec::with_capacity(13);
        (&mut file).take(13).read_to_end(&mut magic).map_err(io)?;
        if magic.starts_with(mcap::MAGIC) {
            let (topics, notes) = mcap_topics(&path)?;
            Ok(Self {
                path,
                format: Format::Mcap,
                topics,
                notes,
            })
        } else if magic == b"#ROSBAG V2.0\n" {
            let topics = ros1_topics(&path)?;
            Ok(Self {
                path,
                format: Format::Ros1,
                topics,
                notes: Vec::new(),
            })
        } else {
            Err(BagError::UnknownFormat { path, found: magic })
        }
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Its format.
    pub fn format(&self) -> Format {
        self.format
    }

    /// Its topics, sorted by name.
    pub fn topics(&self) -> &[TopicInfo] {
        &self.topics
    }

    /// What the reader had to do to open the file (e.g. scan an MCAP file without a summary).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The topic named `name`.
    ///
    /// # Errors
    /// [`BagError::NoSuchTopic`].
    pub fn topic(&self, name: &str) -> Result<&TopicInfo> {
        self.topics
            .iter()
            .find(|t| t.name == name)
            .ok_or_else(|| BagError::NoSuchTopic {
                path: self.path.clone(),
                topic: name.to_owned(),
                available: self.topics.iter().map(|t| t.name.clone()).collect(),
            })
    }

    /// The topics whose recorded type is `T`'s.
    pub fn topics_of<T: Message>(&self) -> Vec<&TopicInfo> {
        self.topics
            .iter()
            .filter(|t| names_type::<T>(&t.type_name))
            .collect()
    }

    /// The raw messages of `topics`, in log-time order (ties in file order), or in file order
    /// when an MCAP file has no chunk index ([`Bag::notes`] says so).
    ///
    /// # Errors
    /// [`BagError::NoSuchTopic`] for a topic the file does not have, [`BagError::Io`] when it
    /// cannot be opened again; the items are the messages or the errors of the file's
    /// structure met while reading (after which the iterator ends).
    pub fn messages(&self, topics: &[&str]) -> Result<Messages> {
        for topic in topics {
            self.topic(topic)?;
        }
        let wanted: Vec<String> = topics.iter().map(|t| (*t).to_owned()).collect();
        let inner = match self.format {
            Format::Mcap => match McapChunks::open(&self.path, &wanted)? {
                Some((loader, chunks)) => Inner::Merged(Merge::new(chunks), Box::new(loader)),
                None => Inner::Mcap(Box::new(mcap_check::LinearMessages::open(&self.path)?)),
            },
            Format::Ros1 => {
                let (loader, chunks) = Ros1Chunks::open(&self.path, &wanted)?;
                Inner::Merged(Merge::new(chunks), Box::new(loader))
            }
        };
        Ok(Messages {
            path: self.path.clone(),
            wanted,
            counts: BTreeMap::new(),
            inner,
            done: false,
        })
    }

    /// The messages of `topic` decoded as `T`, each with its log time in seconds, in the order
    /// of [`Bag::messages`]. The topic's recorded type (and its MD5 sum, where a ROS 1 bag records one) is
    /// checked before anything is decoded.
    ///
    /// # Errors
    /// [`BagError::NoSuchTopic`], [`BagError::TypeMismatch`], [`BagError::Md5Mismatch`];
    /// each item is the message, a [`BagError::Decode`] naming the topic and message index
    /// (a caller that wants to go on skips it and counts it), or an error of the file.
    pub fn read<T: Message>(
        &self,
        topic: &str,
    ) -> Result<impl Iterator<Item = Result<(f64, T)>> + use<T>> {
        let info = self.topic(topic)?;
        check_type::<T>(info)?;
        let encoding = info.encoding;
        Ok(self.messages(&[topic])?.map(move |m| {
            let m = m?;
            let value = decode::<T>(encoding, &m.data).map_err(|what| BagError::Decode {
                topic: m.topic.to_string(),
                index: m.index,
                what,
            })?;
            Ok((m.log_seconds(), value))
        }))
    }
}

/// Checks that `info` records `T`'s type (and its MD5 where one is recorded).
///
/// # Errors
/// [`BagError::TypeMismatch`], [`BagError::Md5Mismatch`].
pub fn check_type<T: Message>(info: &TopicInfo) -> Result<()> {
    if !names_type::<T>(&info.type_name) {
        return Err(BagError::TypeMismatch {
            topic: info.name.clone(),
            recorded: info.type_name.clone(),
            expected: T::ROS2_TYPE.to_owned(),
        });
    }
    if let (Some(recorded), Some(expected)) = (&info.md5, T::ROS1_MD5)
        && recorded != expected
        && recorded != "*"
        && !T::ROS1_OTHER_MD5S.contains(&recorded.as_str())
    {
        return Err(BagError::Md5Mismatch {
            topic: info.name.clone(),
            type_name: info.type_name.clone(),
            recorded: recorded.clone(),
            expected: expected.to_owned(),
        });
    }
    Ok(())
}

/// The raw messages of some topics of a [`Bag`], in log-time order (see [`Bag::messages`]).
pub struct Messages {
    path: PathBuf,
    wanted: Vec<String>,
    counts: BTreeMap<Arc<str>, u64>,
    inner: Inner,
    done: bool,
}

impl std::fmt::Debug for Messages {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Messages")
            .field("path", &self.path)
            .field("wanted", &self.wanted)
            .finish_non_exhaustive()
    }
}

enum Inner {
    /// An MCAP file without chunk indexes, in file order.
    Mcap(Box<mcap_check::LinearMessages>),
    /// The chunks of an indexed file, merged by log time.
    Merged(Merge, Box<dyn ChunkLoader>),
}

impl Messages {
    /// The most chunks this iterator has held in memory at once (0 when it reads an MCAP
    /// file in file order, one chunk at a time): 1 for a file whose chunks do not overlap in
    /// log time, the number of overlapping chunks otherwise.
    pub fn most_chunks_held(&self) -> usize {
        match &self.inner {
            Inner::Mcap(_) => 0,
            Inner::Merged(merge, _) => merge.most_held(),
        }
    }
}

impl Iterator for Messages {
    type Item = Result<RawMessage>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        loop {
            let next = match &mut self.inner {
                Inner::Mcap(reader) => match reader.next()? {
                    Ok(m) => {
                        if !self.wanted.iter().any(|w| *w == m.channel.topic) {
                            continue;
                        }
                        Ok((
                            Arc::<str>::from(m.channel.topic.as_str()),
                            m.log_time,
                            m.data.into_owned(),
                        ))
                    }
                    Err(e) => Err(e),
                },
                Inner::Merged(merge, loader) => merge.next(loader.as_mut())?,
            };
            return Some(match next {
                Ok((topic, log_time, data)) => {
                    let count = self.counts.entry(topic.clone()).or_insert(0);
                    let index = *count;
                    *count += 1;
                    Ok(RawMessage {
                        topic,
                        log_time,
                        index,
                        data,
                    })
                }
                Err(e) => {
                    // A broken chunk of an indexed file is skipped (the next call reads the
                    // next chunk); a stream read in file order cannot go on after an error.
                    self.done = matches!(self.inner, Inner::Mcap(_));
                    Err(e)
                }
            });
        }
    }
}

// ---------------------------------------------------------------------------------------------
// MCAP

/// The longest MCAP record (a chunk, compressed or not) read: 1 GiB. Recorders write chunks of
/// a few MB; a length beyond this is a corrupt file, refused before anything is allocated.
pub const MAX_MCAP_RECORD: usize = 1 << 30;

/// How MCAP files are read: chunk CRCs checked (where the writer stored one), records capped
/// at [`MAX_MCAP_RECORD`].
pub(crate) fn mcap_options() -> mcap::sans_io::LinearReaderOptions {
    mcap::sans_io::LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_record_length_limit(MAX_MCAP_RECORD)
}

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
fn mcap_topics(path: &Path) -> Result<(Vec<TopicInfo>, Vec<String>)> {
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
            let stop = reader.stop();
            notes.extend(stop.map(|at| {
                format!(
                    "{}: the uncompressed chunk at byte {at} holds a record running past its \
                     end; reading stops there",
                    path.display()
                )
            }));
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
                        return Err(match stop {
                            Some(at) => mcap_check::bad_chunk(path, at),
                            None => e,
                        });
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
struct McapChunks {
    path: PathBuf,
    file: File,
    /// Topic of each wanted channel.
    channels: BTreeMap<u16, Arc<str>>,
}

impl McapChunks {
    /// The loader and the chunks that may hold the `wanted` topics, or `None` when the file
    /// has no summary with chunk indexes (it is then read in file order).
    fn open(path: &Path, wanted: &[String]) -> Result<Option<(Self, Vec<ChunkRef>)>> {
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

// ---------------------------------------------------------------------------------------------
// ROS 1

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
fn ros1_topics(path: &Path) -> Result<Vec<TopicInfo>> {
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
struct Ros1Chunks {
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
    fn open(path: &Path, wanted: &[String]) -> Result<(Self, Vec<ChunkRef>)> {
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
