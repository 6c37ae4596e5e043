//! Opening a robot log and streaming its messages: ROS 1 bags (format 2.0: uncompressed, bz2
//! and lz4 chunks, through our own record reader, `read/ros1_records.rs`) and MCAP files
//! (chunked or not, zstd or lz4, with or without a summary, through the `mcap` crate).
//!
//! Messages come in log-time order: the chunks listed by the file's index (a ROS 1 bag's
//! chunk infos, an MCAP summary's chunk indexes) are merged by log time (`merge.rs`), holding
//! only the chunks that overlap in time, one chunk when none do. An MCAP file without a
//! summary or without chunk indexes (written unchunked, or cut short) is read in file order,
//! the order its recorder wrote (receive order), and [`Bag::notes`] says so. A ROS 1 bag
//! without a readable index (not closed, cut short) has its chunks found by a linear scan when
//! it is opened (each chunk decompressed once to list its connections and earliest log time),
//! and is then merged by log time as well; the notes say so. The list of topics comes from the
//! same index; an MCAP file without a summary is scanned once to list them.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::codec::decode;
use crate::mcap_check;
use crate::merge::{ChunkLoader, Merge};
use crate::msg::{Message, names_type};
use crate::{BagError, Result};

mod mcap_file;
mod ros1_bag;
mod ros1_index;
mod ros1_records;
mod topic;

pub use self::topic::TopicInfo;

use self::mcap_file::{McapChunks, mcap_topics};
use self::ros1_bag::{Ros1Chunks, ros1_index, ros1_topics};

/// The two file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// A ROS 1 bag, format 2.0.
    Ros1,
    /// An MCAP file (ROS 2 bags, Foxglove recordings).
    Mcap,
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
    /// A ROS 1 bag's index, read once by [`Bag::open`].
    ros1: Option<Arc<ros1_index::Index>>,
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
                ros1: None,
            })
        } else if magic == b"#ROSBAG V2.0\n" {
            let index = ros1_index(&path)?;
            Ok(Self {
                path,
                format: Format::Ros1,
                topics: ros1_topics(&index),
                notes: index.notes.clone(),
                ros1: Some(Arc::new(index)),
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

    /// What the reader had to do to open the file (e.g. scan an MCAP file without a summary,
    /// or a ROS 1 bag whose index is missing or unreadable).
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
    /// structure met while reading: a broken chunk of an indexed file (or of a ROS 1 bag found
    /// by a linear scan) is one [`BagError::Ros1Chunk`] / [`BagError::McapChunk`] item and the
    /// next chunks are still read; an MCAP file read in file order ends at its first error.
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
                let empty = ros1_index::Index::default();
                let index = self.ros1.as_deref().unwrap_or(&empty);
                let (loader, chunks) = Ros1Chunks::open(&self.path, index, &wanted)?;
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

impl Bag {
    /// `message` (read from this bag by [`Bag::messages`]) decoded as `T`, its topic's type
    /// checked first: for a reader of several topics at once, in log-time order.
    ///
    /// # Errors
    /// [`BagError::NoSuchTopic`], [`BagError::TypeMismatch`], [`BagError::Md5Mismatch`],
    /// [`BagError::Decode`] naming the topic and message index.
    pub fn decode<T: Message>(&self, message: &RawMessage) -> Result<T> {
        let info = self.topic(&message.topic)?;
        check_type::<T>(info)?;
        decode::<T>(info.encoding, &message.data).map_err(|what| BagError::Decode {
            topic: message.topic.to_string(),
            index: message.index,
            what,
        })
    }
}

/// Checks that `info` records `T`'s type (and its MD5 where one is recorded).
///
/// # Errors
/// [`BagError::TypeMismatch`], [`BagError::Md5Mismatch`].
pub(crate) fn check_type<T: Message>(info: &TopicInfo) -> Result<()> {
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
