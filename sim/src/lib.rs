#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// The `nalgebra` this crate's API is built on (points, poses, vectors), so that a caller
/// whose own `Cargo.toml` pins another version can name the exact types:
/// `use haunts_sim::nalgebra::Point2`.
pub use nalgebra;

mod error;
mod laser;
mod office;
mod people;
mod rng;
mod robot;
mod schedule;
mod shapes;
mod sim;

pub use error::{Result, SimError};
pub use laser::{LaserParams, MaxRangeReturn};
pub use office::{Door, Furniture, FurnitureKind, Layout, Office};
pub use people::{Activity, PeopleParams, PersonTruth, RatePeak, Visit};
pub use robot::{OdometryParams, PatrolParams};
pub use schedule::{MAX_DAY, ScheduleParams};
pub use shapes::Shape;
pub use sim::{Day, FurnitureNoise, START_CLEARANCE, SimParams, Simulator};
