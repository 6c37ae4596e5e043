#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// The `nalgebra` this crate's API is built on (points, poses, vectors), so that a caller
/// whose own `Cargo.toml` pins another version can name the exact types:
/// `use haunts_bag::nalgebra::Point2`.
pub use nalgebra;

pub mod codec;
pub mod convert;
mod error;
mod limits;
mod map_frame;
mod mcap_check;
mod merge;
pub mod msg;
mod read;
mod recording;
mod write;

pub use codec::Encoding;
pub use error::{BagError, Result};
pub use map_frame::MapFrame;
pub use read::{Bag, Format, Messages, RawMessage, TopicInfo};
pub use recording::{RecordingOptions, RecordingTopics};
pub use write::McapWriter;
