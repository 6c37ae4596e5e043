#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod error;
mod geometry;
mod grid;
mod occupancy_grid;
mod scan;

pub mod atomic;
pub mod budget;
pub mod carmen;
pub mod composite;
pub mod edt;
pub mod frames;
pub mod map_io;
pub mod mapping;
#[cfg(feature = "png")]
pub mod picture;
pub mod raycast;
pub mod recording;
#[cfg(feature = "serde")]
pub mod serde_float;
pub mod text;

pub use error::{OccupancyError, PgmProblem, Result};
pub use geometry::{Cell, GridGeometry, Pose2};
pub use grid::Grid;
pub use map_io::{
    Interpretation, LoadNote, LoadedMap, MapLoadOptions, MapMetadata, MapMode, MapSaveOptions,
    decode_map_image, load_map, load_map_image, parse_map_yaml, save_map,
};
pub use occupancy_grid::{CellState, FREE, OCCUPIED, OccupancyGrid, StateThresholds, UNKNOWN};
pub use scan::{Beam, LaserScan, MaxRangeRule, Ray, Reading, pose_is_finite};
