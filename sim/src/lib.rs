#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

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
