//! The error type of the planning crate: every way a costmap or a plan request can be rejected.

use haunts_occupancy::{Cell, GridGeometry, OccupancyError};
use nalgebra::Point2;

/// Which end of a path a request was about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Endpoint {
    /// Where the path begins.
    Start,
    /// Where the path ends.
    Goal,
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Start => "start",
            Self::Goal => "goal",
        })
    }
}

/// Errors of `haunts-planning`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlanningError {
    /// A start or goal cell lies outside the costmap.
    #[error("{endpoint} cell ({}, {}) is outside the {width}×{height} costmap", cell.col, cell.row)]
    CellOutsideMap {
        /// Which endpoint.
        endpoint: Endpoint,
        /// The cell given.
        cell: Cell,
        /// Width of the costmap in cells.
        width: usize,
        /// Height of the costmap in cells.
        height: usize,
    },
    /// A start or goal world point lies outside the costmap, or is not finite.
    #[error("{endpoint} point ({}, {}) is outside the costmap or not finite", point.x, point.y)]
    PointOutsideMap {
        /// Which endpoint.
        endpoint: Endpoint,
        /// The point given, in metres.
        point: Point2<f64>,
    },
    /// A start or goal cell is an obstacle: inscribed (253) or lethal (254).
    #[error("{endpoint} cell ({}, {}) is an obstacle (cost {cost})", cell.col, cell.row)]
    InObstacle {
        /// Which endpoint.
        endpoint: Endpoint,
        /// The cell.
        cell: Cell,
        /// Its cost.
        cost: u8,
    },
    /// A start or goal cell is unknown (255) and the unknown-cell policy forbids entering it.
    #[error("{endpoint} cell ({}, {}) is unknown and the policy forbids unknown cells", cell.col, cell.row)]
    InUnknown {
        /// Which endpoint.
        endpoint: Endpoint,
        /// The cell.
        cell: Cell,
    },
    /// The planner found no path. For the complete planners (A*, Dijkstra and the activity
    /// variants) none exists under their rules; `StraightLine` only tries the straight line.
    #[error(
        "no path from ({}, {}) to ({}, {}) ({explored} cells reached from the start)",
        start.col, start.row, goal.col, goal.row
    )]
    Unreachable {
        /// The start cell.
        start: Cell,
        /// The goal cell.
        goal: Cell,
        /// Cells the search reached before it ran out of cells to expand.
        explored: usize,
    },
    /// Two grids that must describe the same cells do not.
    #[error("{what}: grid geometry {found:?} differs from the costmap's {expected:?}")]
    GeometryMismatch {
        /// Which input had the wrong geometry (e.g. `density layer`, `activity raster`).
        what: &'static str,
        /// The geometry required (the costmap's).
        expected: Box<GridGeometry>,
        /// The geometry given.
        found: Box<GridGeometry>,
    },
    /// A parameter breaks its rule.
    #[error(transparent)]
    InvalidParameter(#[from] haunts_core::InvalidParameter),
    /// An activity raster holds a NaN or infinite value where a value is needed.
    #[error("activity at cell ({}, {}) is {value}, not a finite number", cell.col, cell.row)]
    NonFiniteActivity {
        /// The first such cell.
        cell: Cell,
        /// Its value.
        value: f64,
    },
    /// A directional cost that cannot be used: a value not finite and ≥ 0, or the wrong
    /// number of cells.
    #[error("directional cost at cell ({}, {}): {value} is {what}", cell.col, cell.row)]
    InvalidDirectionalCost {
        /// The cell.
        cell: Cell,
        /// The value (or the number of cells given).
        value: f64,
        /// What is wrong.
        what: &'static str,
    },
    /// No traversable cell has a finite activity, so there is no cell of maximum activity.
    #[error("no traversable cell has a finite activity value")]
    NoActivity,
    /// A layer index does not name a layer of the costmap.
    #[error("layer {index} does not exist (the costmap has {layers} layers)")]
    NoSuchLayer {
        /// The index given.
        index: usize,
        /// Number of layers.
        layers: usize,
    },
    /// The occupancy crate rejected a grid (e.g. one too large for its distance transform).
    #[error(transparent)]
    Occupancy(#[from] OccupancyError),
}

/// Shorthand for results of this crate.
pub type Result<T, E = PlanningError> = std::result::Result<T, E>;

/// `Ok(())` when `found` describes the same cells as `expected`, else
/// [`PlanningError::GeometryMismatch`] naming `what`.
pub(crate) fn same_geometry(
    what: &'static str,
    expected: &GridGeometry,
    found: &GridGeometry,
) -> Result<()> {
    if expected.same_cells(found, GridGeometry::SAME_CELLS_TOLERANCE) {
        Ok(())
    } else {
        Err(PlanningError::GeometryMismatch {
            what,
            expected: Box::new(*expected),
            found: Box::new(*found),
        })
    }
}

/// `Ok(value)` when `ok`, else [`PlanningError::InvalidParameter`].
pub(crate) fn rule(name: &'static str, value: f64, ok: bool, rule: &'static str) -> Result<f64> {
    if ok {
        Ok(value)
    } else {
        Err(PlanningError::InvalidParameter(
            haunts_core::InvalidParameter { name, value, rule },
        ))
    }
}
