//! `BagError`: what went wrong reading or writing a robot log.

use std::path::PathBuf;

/// Errors of this crate. Each names the file, and the topic and message index or byte offset
/// where it can.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BagError {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file starts with neither a ROS 1 bag's nor an MCAP file's magic bytes.
    #[error(
        "{}: neither a ROS 1 bag (#ROSBAG V2.0) nor an MCAP file; it starts with {found:?} \
         (ROS 2 .db3 bags: convert once with `rosbags-convert --dst-storage mcap`)",
        path.display()
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// Its first bytes (at most 13).
        found: Vec<u8>,
    },
    /// A ROS 1 bag's structure is broken (truncated, a bad record, a bad chunk).
    #[error("{}: ROS 1 bag: {what}", path.display())]
    Ros1 {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the byte offset where known.
        what: String,
    },
    /// A chunk of a ROS 1 bag cannot be read (cut short, unknown compression, bad compressed
    /// data, a size over 1 GiB, a record running past its end); the chunks
    /// after it are still read.
    #[error("{}: ROS 1 chunk at byte {offset}: {what}", path.display())]
    Ros1Chunk {
        /// The file.
        path: PathBuf,
        /// The byte offset of the chunk record.
        offset: u64,
        /// What is wrong (with the byte within the decompressed chunk where it is a record).
        what: String,
    },
    /// An MCAP file's structure is broken (truncated, bad CRC, bad record, a record over
    /// 1 GiB, unknown compression).
    #[error("{}: MCAP: {source}", path.display())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// The `mcap` crate's error.
        source: mcap::McapError,
    },
    /// A chunk of an MCAP file is broken (bad CRC, bad compression, a record past its end);
    /// the chunks after it are still read.
    #[error("{}: MCAP chunk at byte {offset}: {source}", path.display())]
    McapChunk {
        /// The file.
        path: PathBuf,
        /// The byte offset of the chunk record.
        offset: u64,
        /// The `mcap` crate's error.
        source: mcap::McapError,
    },
    /// An MCAP record holds a string, byte array or map whose length runs past the record's
    /// end (refused before the `mcap` crate allocates that length).
    #[error(
        "{}: MCAP record of opcode {opcode:#04x} and {length} bytes: a field's length runs past \
         its end",
        path.display()
    )]
    McapRecord {
        /// The file.
        path: PathBuf,
        /// The record's opcode.
        opcode: u8,
        /// The record's length.
        length: u64,
    },
    /// A requested topic is not in the file.
    #[error("{}: no topic `{topic}` (topics: {})", path.display(), available.join(", "))]
    NoSuchTopic {
        /// The file.
        path: PathBuf,
        /// The topic asked for.
        topic: String,
        /// The topics the file has.
        available: Vec<String>,
    },
    /// A topic's recorded type is not the type it is decoded as.
    #[error("topic `{topic}` holds `{recorded}`, not `{expected}`")]
    TypeMismatch {
        /// The topic.
        topic: String,
        /// The type the file records.
        recorded: String,
        /// The type asked for.
        expected: String,
    },
    /// A ROS 1 topic's MD5 sum is not the one of the definition it is decoded with.
    #[error("topic `{topic}` ({type_name}) has MD5 {recorded}, expected {expected}")]
    Md5Mismatch {
        /// The topic.
        topic: String,
        /// Its type.
        type_name: String,
        /// The MD5 sum the file records.
        recorded: String,
        /// The MD5 sum of the definition used.
        expected: String,
    },
    /// A channel's message encoding is one this crate does not decode (only `ros1` and `cdr`).
    #[error("topic `{topic}` is encoded as `{encoding}`; only ros1 and cdr are decoded")]
    UnsupportedEncoding {
        /// The topic.
        topic: String,
        /// Its encoding.
        encoding: String,
    },
    /// A message's bytes do not decode as its type (a schema that does not match the data,
    /// or a truncated message).
    #[error("topic `{topic}`, message {index}: {what}")]
    Decode {
        /// The topic.
        topic: String,
        /// The message's index within its topic, from 0.
        index: u64,
        /// What the decoder said.
        what: String,
    },
    /// No topic of the type needed, or several where one must be chosen.
    #[error("{}: {what}", path.display())]
    TopicChoice {
        /// The file.
        path: PathBuf,
        /// What was looked for and found (e.g. `two LaserScan topics: /left, /right; name one`).
        what: String,
    },
    /// A message is well-formed but unusable (e.g. a scan with no beams, a pose that is not
    /// finite).
    #[error("topic `{topic}`, message {index}: {what}")]
    InvalidMessage {
        /// The topic.
        topic: String,
        /// The message's index within its topic.
        index: u64,
        /// What is wrong.
        what: String,
    },
    /// The map frame named ([`crate::MapFrame::Named`]) is not linked to the odometry frame
    /// by the recording's transforms (it is not above the odometry frame in the tf tree).
    #[error(
        "{}: no transform from map frame `{frame}` to odometry frame `{odom_frame}` (frames \
         seen: {})",
        path.display(),
        if seen.is_empty() { "none".to_owned() } else { seen.join(", ") }
    )]
    NoMapFrame {
        /// The file.
        path: PathBuf,
        /// The map frame asked for.
        frame: String,
        /// The odometry frame (the odometry's header frame, else `odom`).
        odom_frame: String,
        /// The frames of the recording's transforms, sorted.
        seen: Vec<String>,
    },
    /// A message could not be encoded for writing.
    #[error("encoding a `{type_name}` message: {what}")]
    Encode {
        /// Its type.
        type_name: &'static str,
        /// What the encoder said.
        what: String,
    },
    /// The occupancy crate rejected what a message was converted into.
    #[error("{source}")]
    Occupancy {
        /// Its error.
        #[from]
        source: haunts_occupancy::OccupancyError,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = BagError> = std::result::Result<T, E>;
