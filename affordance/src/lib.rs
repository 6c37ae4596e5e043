#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// The `nalgebra` this crate's API is built on (points, poses, vectors), so that a caller
/// whose own `Cargo.toml` pins another version can name the exact types:
/// `use haunts_affordance::nalgebra::Point2`.
pub use nalgebra;

pub mod activity_at;
pub mod density;
mod density_map;
mod error;
pub mod flow;
pub mod hypertime;
pub mod layout;
mod parallel;
#[cfg(feature = "serde")]
mod serde_support;
pub mod ta;

pub use activity_at::{ActivityAt, ActivityAtParams};
pub use density::{CumulativeDensity, DailyDensity, DayStats, DensityParams, HitCounter, HitStats};
pub use density_map::{DensityMap, UniformDensity};
pub use error::{AffordanceError, Result};
pub use hypertime::{
    Evaluation, EvaluationParams, GkParams, HypertimeModel, HypertimeParams, HypertimeSnapshot,
    Projection, TimedPoint, evaluate, read_detections,
};
pub use layout::register::{MovedDay, Refusal, RegisterParams, Registration, move_day};
pub use layout::{Classification, DayId, Layout, LayoutId, LayoutLibrary, LayoutParams};
pub use ta::{ConfidenceMap, RegressionParams, TaMap, TaParams, TrainingSet, register_session};
