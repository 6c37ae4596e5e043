//! Reading tracking data: the `leg_tracker` benchmark's text export ([`leg_tracker`]) and its
//! frames ([`frames`]), pedestrian trajectories ([`trajectory`]: ETH `obsmat`, delimited
//! columns), OpenTraj's `map.xml` scene obstacles ([`parse_scene_map`]), the line loop every
//! text reader shares ([`parse_lines`], [`Fields`]), and the bridge between that export and a
//! [`Recording`](haunts_occupancy::recording::Recording) ([`crate::Sequence::to_recording`],
//! [`crate::Sequence::from_recording`]).

pub mod frames;
pub mod leg_tracker;
pub(crate) mod lines;
mod recording;
mod scene_map;
pub mod trajectory;

pub use frames::{OdomClock, odometry_history, static_chain};
pub use leg_tracker::{
    OdomPose, PersonPosition, StampedScan, StaticTransform, parse_ground_truth, parse_odometry,
    parse_scans, parse_static_transforms, read_ground_truth, read_odometry, read_scans,
    read_static_transforms,
};
pub use lines::{Fields, KEEP_SKIPPED, Parsed, SkipReason, SkippedLine, parse_lines};
pub use scene_map::{SceneMap, parse_scene_map};
pub use trajectory::{
    DelimitedOptions, Delimiter, EthOptions, Trajectory, keep_near, parse_delimited, parse_eth,
    read_delimited, read_eth,
};
