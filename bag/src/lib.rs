#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

pub mod codec;
pub mod convert;
mod error;
mod mcap_check;
mod merge;
pub mod msg;
mod read;
mod recording;
mod write;

pub use codec::Encoding;
pub use error::{BagError, Result};
pub use read::{Bag, Format, MAX_MCAP_RECORD, MAX_ROS1_CHUNK, Messages, RawMessage, TopicInfo};
pub use recording::{BagScans, RecordingOptions};
pub use write::McapWriter;
