#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// The `nalgebra` this crate's API is built on (points, poses, vectors), so that a caller
/// whose own `Cargo.toml` pins another version can name the exact types:
/// `use haunts_planning::nalgebra::Point2`.
pub use nalgebra;

mod activity;
mod astar;
mod cost_model;
mod costmap;
mod dijkstra;
mod error;
mod flow;
mod layers;
mod metrics;
mod planner;
mod search;

pub use activity::{
    ActivityAwareAStar, ActivityAwareParams, ActivityCostAStar, ActivityCostParams, SEED_THRESHOLD,
    crossings, max_activity_cell,
};
pub use astar::AStar;
pub use cost_model::{SearchParams, UnknownPolicy};
pub use costmap::{
    Costmap, FREE_SPACE, INSCRIBED_INFLATED_OBSTACLE, LETHAL_OBSTACLE, Layer, LayerId,
    LayeredCostmap, MAX_NON_OBSTACLE, NO_INFORMATION,
};
pub use dijkstra::{CostToGo, Dijkstra};
pub use error::{Endpoint, PlanningError, Result};
pub use flow::{
    DirectionalCost, FlowCostAStar, FlowCostParams, MOVES, against_flow_share, move_between,
    move_heading,
};
pub use layers::{
    Combine, DensityLayer, DensityLayerParams, InflationLayer, InflationParams, StaticLayer,
};
pub use metrics::PathMetrics;
pub use planner::{Path, Planner, StraightLine};
