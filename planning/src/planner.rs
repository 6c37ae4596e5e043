//! The `Planner` trait, the `Path` it returns, and `StraightLine`, the trivial planner.

use haunts_occupancy::raycast::bresenham;
use haunts_occupancy::{Cell, GridGeometry};
use nalgebra::Point2;

use crate::cost_model::Factors;
use crate::search::octile;
use crate::{Costmap, Endpoint, PlanningError, Result, SearchParams};

/// A planner on a costmap: from a start cell to a goal cell, a path or a typed error.
///
/// Object safe and `Send + Sync`, so planners can be chosen at run time
/// (`Box<dyn Planner>`) and shared between threads.
///
/// ```
/// use haunts_occupancy::{Cell, GridGeometry};
/// use haunts_planning::{AStar, Costmap, Dijkstra, Planner, StraightLine};
/// let geometry = GridGeometry::new(0.1, nalgebra::Point2::origin(), 10, 10).unwrap();
/// let costmap = Costmap::filled(geometry, 0);
/// let planners: Vec<Box<dyn Planner>> = vec![
///     Box::new(AStar::default()),
///     Box::new(Dijkstra::default()),
///     Box::new(StraightLine::default()),
/// ];
/// for planner in &planners {
///     let path = planner.plan(&costmap, Cell::new(0, 0), Cell::new(9, 9))?;
///     approx::assert_relative_eq!(path.length(), 0.9 * 2f64.sqrt(), epsilon = 1e-12);
/// }
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
///
/// Implemented for `&T`, `&mut T`, `Box<T>` and `Arc<T>` of any planner.
#[auto_impl::auto_impl(&, &mut, Box, Arc)]
pub trait Planner: Send + Sync {
    /// A path on `costmap` from `start` to `goal`.
    ///
    /// # Errors
    /// [`PlanningError::CellOutsideMap`], [`PlanningError::InObstacle`] or
    /// [`PlanningError::InUnknown`] for a bad endpoint; [`PlanningError::Unreachable`] when the
    /// planner finds no path; a planner's own errors (e.g. a raster on another grid).
    fn plan(&self, costmap: &Costmap, start: Cell, goal: Cell) -> Result<Path>;

    /// [`Planner::plan`] between the cells holding two world points (metres).
    ///
    /// # Errors
    /// [`PlanningError::PointOutsideMap`] for a point outside the costmap or not finite; as
    /// [`Planner::plan`] otherwise.
    fn plan_world(&self, costmap: &Costmap, start: Point2<f64>, goal: Point2<f64>) -> Result<Path> {
        let cell = |endpoint, point| {
            costmap
                .geometry()
                .world_to_cell(point)
                .ok_or(PlanningError::PointOutsideMap { endpoint, point })
        };
        self.plan(
            costmap,
            cell(Endpoint::Start, start)?,
            cell(Endpoint::Goal, goal)?,
        )
    }
}

/// A path on a grid: 8-connected cells from start to goal, and its cost under the planner's
/// cost model (metres, weighted).
///
/// With the `serde` feature a path (de)serialises as its `geometry`, `cells` and `cost`;
/// deserialising checks what the planners guarantee: at least one cell, every cell on the
/// grid, each cell an 8-neighbour of the one before it, and a finite cost `>= 0`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "PathFields"))]
pub struct Path {
    geometry: GridGeometry,
    cells: Vec<Cell>,
    cost: f64,
}

impl Path {
    /// A path from row-major indices (never empty: planners always include the start).
    pub(crate) fn from_indices(geometry: GridGeometry, indices: &[u32], cost: f64) -> Self {
        let w = geometry.width();
        let cells = indices
            .iter()
            .map(|&i| Cell::new(i as usize % w, i as usize / w))
            .collect();
        Self {
            geometry,
            cells,
            cost,
        }
    }

    /// The grid the path lies on.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// The cells, start first and goal last (one cell when start and goal are the same).
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }
    /// The world positions of the cells' centres, start first.
    pub fn points(&self) -> Vec<Point2<f64>> {
        self.cells
            .iter()
            .map(|&c| self.geometry.cell_center(c))
            .collect()
    }
    /// The first cell.
    pub fn start(&self) -> Cell {
        self.cells[0]
    }
    /// The last cell.
    pub fn goal(&self) -> Cell {
        self.cells[self.cells.len() - 1]
    }
    /// The length in metres: the sum of the distances between consecutive cell centres.
    pub fn length(&self) -> f64 {
        let steps: f64 = self
            .cells
            .windows(2)
            .map(|p| {
                let dx = p[0].col.abs_diff(p[1].col) as f64;
                let dy = p[0].row.abs_diff(p[1].row) as f64;
                dx.hypot(dy)
            })
            .sum();
        steps * self.geometry.resolution()
    }
    /// The cost the planner minimised: the sum over steps of the step's length (metres) times
    /// the factor of the cell entered (see [`SearchParams`]); equal to the length on a free
    /// costmap.
    pub fn cost(&self) -> f64 {
        self.cost
    }
}

/// The fields of a [`Path`] as deserialised, before they are checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct PathFields {
    geometry: GridGeometry,
    cells: Vec<Cell>,
    cost: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<PathFields> for Path {
    type Error = PlanningError;
    fn try_from(f: PathFields) -> Result<Self> {
        let invalid = |name, value, rule| {
            Err(PlanningError::InvalidParameter(
                haunts_core::InvalidParameter { name, value, rule },
            ))
        };
        if f.cells.is_empty() {
            return invalid("cells", 0.0, "a path holds at least its start cell");
        }
        if let Some(i) = f.cells.iter().position(|c| !f.geometry.contains(*c)) {
            return invalid(
                "cells",
                i as f64,
                "the cell at this index lies outside the path's grid",
            );
        }
        if let Some(i) = f
            .cells
            .windows(2)
            .position(|w| w[0].col.abs_diff(w[1].col).max(w[0].row.abs_diff(w[1].row)) != 1)
        {
            return invalid(
                "cells",
                (i + 1) as f64,
                "the cell at this index is not an 8-neighbour of the one before it",
            );
        }
        if !(f.cost.is_finite() && f.cost >= 0.0) {
            return invalid("cost", f.cost, "must be finite and >= 0");
        }
        Ok(Self {
            geometry: f.geometry,
            cells: f.cells,
            cost: f.cost,
        })
    }
}

/// The trivial planner: the Bresenham line from start to goal when every cell on it can be
/// entered (and no step cuts a corner), [`PlanningError::Unreachable`] otherwise. Useful in
/// tests and as a cheap first try before a search.
///
/// # Complexity
/// O(length of the line).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StraightLine {
    params: SearchParams,
}

impl StraightLine {
    /// The planner with checked cost-model parameters.
    ///
    /// # Errors
    /// As [`SearchParams::check`].
    pub fn new(params: SearchParams) -> Result<Self> {
        Ok(Self {
            params: params.check()?,
        })
    }
}

impl Planner for StraightLine {
    fn plan(&self, costmap: &Costmap, start: Cell, goal: Cell) -> Result<Path> {
        let factors = self.params.factors();
        let s = factors.endpoint(costmap, Endpoint::Start, start)?;
        let t = factors.endpoint(costmap, Endpoint::Goal, goal)?;
        let g = costmap.geometry();
        let w = g.width();
        let costs = costmap.data();
        let enterable = |col: usize, row: usize| factors.of(costs[row * w + col]).is_finite();
        let signed = |c: Cell| (c.col as i64, c.row as i64);
        let mut indices = vec![s as u32];
        let mut cost = 0.0;
        let mut previous = start;
        for (col, row) in bresenham(signed(start), signed(goal)).skip(1) {
            // The line stays in the bounding box of two cells of the grid.
            let cell = Cell::new(col as usize, row as usize);
            let corner_free =
                enterable(cell.col, previous.row) && enterable(previous.col, cell.row);
            if !enterable(cell.col, cell.row) || !corner_free {
                return Err(PlanningError::Unreachable {
                    start,
                    goal,
                    explored: indices.len(),
                });
            }
            let i = cell.row * w + cell.col;
            let length = octile(previous.col, previous.row, cell.col, cell.row);
            cost += length * factors.of(costs[i]);
            indices.push(i as u32);
            previous = cell;
        }
        debug_assert_eq!(indices.last().map(|&i| i as usize), Some(t));
        Ok(Path::from_indices(*g, &indices, cost * g.resolution()))
    }
}

/// Shared checks for a path request: both endpoints inside `costmap` and enterable under
/// `factors`; their row-major indices.
pub(crate) fn endpoints(
    factors: &Factors,
    costmap: &Costmap,
    start: Cell,
    goal: Cell,
) -> Result<(usize, usize)> {
    Ok((
        factors.endpoint(costmap, Endpoint::Start, start)?,
        factors.endpoint(costmap, Endpoint::Goal, goal)?,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LETHAL_OBSTACLE;
    use haunts_occupancy::Grid;

    #[test]
    fn straight_line_stops_at_obstacles_and_corners() {
        let g = GridGeometry::new(1.0, Point2::origin(), 5, 5).unwrap();
        let wall = Costmap::new(Grid::from_fn(g, |c| {
            if c == Cell::new(2, 2) {
                LETHAL_OBSTACLE
            } else {
                0
            }
        }));
        let planner = StraightLine::default();
        assert!(matches!(
            planner.plan(&wall, Cell::new(0, 0), Cell::new(4, 4)),
            Err(PlanningError::Unreachable { .. })
        ));
        // The diagonal step (1,2) → (2,3) passes between (2,2) and (1,3).
        assert!(matches!(
            planner.plan(&wall, Cell::new(1, 2), Cell::new(2, 3)),
            Err(PlanningError::Unreachable { .. })
        ));
        let path = planner
            .plan(&wall, Cell::new(0, 4), Cell::new(4, 4))
            .unwrap();
        assert_eq!(path.cells().len(), 5);
        assert_eq!(path.length(), 4.0);
        assert_eq!(path.cost(), 4.0);
    }

    #[test]
    fn world_points_outside_are_typed_errors() {
        let g = GridGeometry::new(1.0, Point2::origin(), 5, 5).unwrap();
        let costmap = Costmap::filled(g, 0);
        let planner = StraightLine::default();
        assert!(matches!(
            planner.plan_world(&costmap, Point2::new(f64::NAN, 1.0), Point2::new(1.0, 1.0)),
            Err(PlanningError::PointOutsideMap {
                endpoint: Endpoint::Start,
                ..
            })
        ));
        assert!(matches!(
            planner.plan_world(&costmap, Point2::new(1.0, 1.0), Point2::new(5.0, 1.0)),
            Err(PlanningError::PointOutsideMap {
                endpoint: Endpoint::Goal,
                ..
            })
        ));
        let path = planner
            .plan_world(&costmap, Point2::new(0.2, 0.2), Point2::new(3.9, 0.1))
            .unwrap();
        assert_eq!(path.points()[3], Point2::new(3.5, 0.5));
    }
}
