#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

pub mod assign;
pub mod cluster;
pub mod combination;
pub mod detector;
pub mod dummy;
pub mod error;
pub mod features;
pub mod forest;
pub mod frames;
pub mod kalman;
pub mod leg_tracker;
pub mod lines;
pub mod metrics;
pub mod particle;
pub mod recording;
pub mod scene_map;
pub mod tracker;
pub mod training;
pub mod trajectory;

pub use error::{Result, TrackingError};
pub use leg_tracker::{
    OdomPose, PersonPosition, StampedScan, StaticTransform, parse_ground_truth, parse_odometry,
    parse_scans, parse_static_transforms, read_ground_truth, read_odometry, read_scans,
    read_static_transforms,
};
pub use lines::{KEEP_SKIPPED, Parsed, SkipReason, SkippedLine};
pub use scene_map::{SceneMap, parse_scene_map};
pub use trajectory::{
    DelimitedOptions, Delimiter, ETH_ANNOTATION_RATE, EthOptions, Trajectory, parse_delimited,
    parse_eth, read_delimited, read_eth,
};
