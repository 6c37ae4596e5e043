//! haunts learns where and when people are around a mobile robot, and turns that into maps a
//! robot plans with. This facade re-exports every crate of the workspace; see the README and
//! `ARCHITECTURE.md` for the map of the code.
#![deny(missing_docs)]

#[cfg(feature = "serde")]
pub mod artifact;
#[cfg(feature = "figures")]
pub mod figure;
#[cfg(any(feature = "serde", feature = "figures"))]
pub mod json;
pub mod live;
pub mod pipeline;
#[cfg(feature = "train")]
pub mod training;

/// The `nalgebra` every crate's API is built on (points, poses, vectors): a program whose own
/// `Cargo.toml` pins another version names the exact types as `haunts::nalgebra::Point2`,
/// and needs no `nalgebra` of its own.
pub use nalgebra;

pub use haunts_affordance as affordance;
pub use haunts_bag as bag;
pub use haunts_core as core;
pub use haunts_gp as gp;
pub use haunts_occupancy as occupancy;
pub use haunts_planning as planning;
pub use haunts_sim as sim;
pub use haunts_similarity as similarity;
pub use haunts_tracking as tracking;

/// The README's Rust examples, run as doctests (its library path above all).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
