#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// The `nalgebra` this crate's API is built on (points, poses, vectors), so that a caller
/// whose own `Cargo.toml` pins another version can name the exact types:
/// `use haunts_occupancy::nalgebra::Point2`.
pub use nalgebra;

mod error;
mod geometry;
mod grid;
mod occupancy_grid;
mod scan;

pub mod atomic;
pub mod bounds;
pub mod budget;
pub mod carmen;
mod composite;
mod edt;
mod frames;
mod map_io;
pub mod mapping;
#[cfg(feature = "png")]
pub mod picture;
pub mod raycast;
pub mod recording;
#[cfg(feature = "serde")]
pub mod serde_float;
pub mod text;

pub use carmen::{CarmenLog, CarmenOptions, read_carmen};
pub use composite::GeometricComposite;
pub use edt::{DistanceField, distance_transform, distance_transform_with_nearest};
pub use error::{OccupancyError, PgmProblem, Result};
pub use frames::{Link, PoseHistory, TransformTree, frame_name};
pub use geometry::{Cell, GridGeometry, Pose2};
pub use grid::Grid;
pub use map_io::{
    Interpretation, LoadNote, LoadedMap, MapLoadOptions, MapMetadata, MapMode, MapSaveOptions,
    decode_map_image, load_map, load_map_image, parse_map_yaml, save_map,
};
pub use mapping::{MapperParams, OccupancyMapper};
pub use occupancy_grid::{CellState, FREE, OCCUPIED, OccupancyGrid, StateThresholds, UNKNOWN};
#[cfg(feature = "png")]
pub use picture::{ColorMap, Picture};
pub use raycast::{VisitCounter, VisitRule};
pub use recording::{RecordedScan, Recording, ScanSource};
pub use scan::{Beam, LaserScan, MaxRangeRule, Ray, Reading, pose_is_finite};
