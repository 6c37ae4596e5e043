//! Writing ROS 2 MCAP files: CDR messages with `ros2msg` schemas, zstd-compressed chunks and a
//! summary, so that Foxglove, Lichtblick and `ros2 bag play` open them.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

use crate::codec::encode_cdr;
use crate::msg::Message;
use crate::{BagError, Result};

/// A ROS 2 MCAP file being written. Topics are added as they are first written to; every
/// message of a topic must be of the type it started with.
///
/// # Example
/// ```
/// use haunts_bag::{Bag, McapWriter, msg::{PoseArray, Pose}};
///
/// let path = std::env::temp_dir().join(format!("haunts-doc-{}.mcap", std::process::id()));
/// let mut writer = McapWriter::create(&path)?;
/// let mut poses = PoseArray::default();
/// poses.poses.push(Pose::default());
/// writer.write("/people", 1.5, &poses)?;
/// writer.finish()?;
///
/// let bag = Bag::open(&path)?;
/// let (time, back) = bag.read::<PoseArray>("/people")?.next().unwrap()?;
/// assert_eq!((time, back), (1.5, poses));
/// # std::fs::remove_file(&path).ok();
/// # Ok::<(), haunts_bag::BagError>(())
/// ```
pub struct McapWriter<W: Write + Seek = BufWriter<File>> {
    path: PathBuf,
    writer: mcap::Writer<W>,
    /// topic → (channel id, ROS 2 type).
    channels: BTreeMap<String, (u16, &'static str)>,
    /// ROS 2 type → schema id.
    schemas: BTreeMap<&'static str, u16>,
    sequence: u32,
}

impl<W: Write + Seek> std::fmt::Debug for McapWriter<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("McapWriter")
            .field("path", &self.path)
            .field("channels", &self.channels)
            .finish_non_exhaustive()
    }
}

impl McapWriter {
    /// Creates (or truncates) the file at `path`.
    ///
    /// # Errors
    /// [`BagError::Io`], [`BagError::Mcap`].
    pub fn create(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref().to_path_buf();
        let file = File::create(&path).map_err(|source| BagError::Io {
            path: path.clone(),
            source,
        })?;
        Self::new(BufWriter::new(file), path)
    }
}

impl<W: Write + Seek> McapWriter<W> {
    /// Writes to `sink`; `path` only names it in errors.
    ///
    /// # Errors
    /// [`BagError::Mcap`].
    pub fn new(sink: W, path: PathBuf) -> Result<Self> {
        let writer = mcap::WriteOptions::new()
            .profile("ros2")
            .compression(Some(mcap::Compression::Zstd))
            .create(sink)
            .map_err(|source| BagError::Mcap {
                path: path.clone(),
                source,
            })?;
        Ok(Self {
            path,
            writer,
            channels: BTreeMap::new(),
            schemas: BTreeMap::new(),
            sequence: 0,
        })
    }

    /// Writes `message` on `topic`, logged (and published) at `seconds` since the UNIX epoch.
    ///
    /// # Errors
    /// [`BagError::TypeMismatch`] when the topic already holds another type;
    /// [`BagError::Encode`], [`BagError::Mcap`]; a negative or non-finite time is a
    /// [`BagError::Encode`].
    pub fn write<T: Message>(&mut self, topic: &str, seconds: f64, message: &T) -> Result<()> {
        let mcap_error = |path: &PathBuf| {
            let path = path.clone();
            move |source| BagError::Mcap { path, source }
        };
        let time = seconds * 1e9;
        if !(time.is_finite() && time >= 0.0 && time < u64::MAX as f64) {
            return Err(BagError::Encode {
                type_name: T::ROS2_TYPE,
                what: format!("log time {seconds} s is not a time MCAP can hold"),
            });
        }
        let channel = match self.channels.get(topic) {
            Some(&(id, kind)) if kind == T::ROS2_TYPE => id,
            Some(&(_, kind)) => {
                return Err(BagError::TypeMismatch {
                    topic: topic.to_owned(),
                    recorded: kind.to_owned(),
                    expected: T::ROS2_TYPE.to_owned(),
                });
            }
            None => {
                let schema = match self.schemas.get(T::ROS2_TYPE) {
                    Some(&id) => id,
                    None => {
                        let id = self
                            .writer
                            .add_schema(T::ROS2_TYPE, "ros2msg", T::ROS2_DEFINITION.as_bytes())
                            .map_err(mcap_error(&self.path))?;
                        self.schemas.insert(T::ROS2_TYPE, id);
                        id
                    }
                };
                let id = self
                    .writer
                    .add_channel(schema, topic, "cdr", &BTreeMap::new())
                    .map_err(mcap_error(&self.path))?;
                self.channels.insert(topic.to_owned(), (id, T::ROS2_TYPE));
                id
            }
        };
        let data = encode_cdr(message).map_err(|what| BagError::Encode {
            type_name: T::ROS2_TYPE,
            what,
        })?;
        let time = time.round() as u64;
        self.writer
            .write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: channel,
                    sequence: self.sequence,
                    log_time: time,
                    publish_time: time,
                },
                &data,
            )
            .map_err(mcap_error(&self.path))?;
        self.sequence = self.sequence.wrapping_add(1);
        Ok(())
    }

    /// Writes the summary and the end of the file, and flushes it.
    ///
    /// # Errors
    /// [`BagError::Mcap`].
    pub fn finish(mut self) -> Result<()> {
        self.writer.finish().map_err(|source| BagError::Mcap {
            path: self.path.clone(),
            source,
        })?;
        Ok(())
    }
}
