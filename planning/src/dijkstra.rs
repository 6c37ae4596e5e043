//! Dijkstra: the cost-to-go field of a goal, from which the optimal path of every start follows.

use haunts_occupancy::{Cell, Grid, GridGeometry};

use crate::planner::endpoints;
use crate::search::{Field, cost_to_go};
use crate::{Costmap, Endpoint, Path, Planner, PlanningError, Result, SearchParams};

/// Dijkstra's algorithm on the 8-connected grid of a costmap, with the cost model of
/// [`SearchParams`], run backwards from the goal.
///
/// [`Dijkstra::cost_to_go`] computes the whole field once; [`CostToGo::path_from`] then gives
/// the optimal path of any start in O(path length), which suits many robots (or many candidate
/// starts) heading for one goal. As a [`Planner`], it stops as soon as the start is settled.
///
/// # Complexity
/// O(cells) memory and O(E · log C) time in the edges E relaxed (all of them for a full
/// field) and the spread C of the keys' bits (the open list is a radix heap). Among cells of
/// equal cost the one reached last is settled first, deterministically.
///
/// ```
/// use haunts_occupancy::{Cell, GridGeometry};
/// use haunts_planning::{Costmap, Dijkstra, SearchParams};
/// let geometry = GridGeometry::new(1.0, nalgebra::Point2::origin(), 4, 3).unwrap();
/// let dijkstra = Dijkstra::new(SearchParams::default())?;
/// let field = dijkstra.cost_to_go(&Costmap::filled(geometry, 0), Cell::new(0, 0))?;
/// let expected = 1.0 + 2.0 * 2f64.sqrt(); // one straight step, two diagonal ones
/// approx::assert_relative_eq!(field.cost(Cell::new(3, 2)).unwrap(), expected, epsilon = 1e-12);
/// let path = field.path_from(Cell::new(3, 0))?;
/// assert_eq!(path.cells().len(), 4);
/// assert_eq!(path.goal(), Cell::new(0, 0));
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Dijkstra {
    params: SearchParams,
}

impl Dijkstra {
    /// The planner with checked parameters.
    ///
    /// # Errors
    /// As [`SearchParams::check`].
    pub fn new(params: SearchParams) -> Result<Self> {
        Ok(Self {
            params: params.check()?,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &SearchParams {
        &self.params
    }

    /// The cost from every cell of `costmap` to `goal`, with the next step of each cell's
    /// optimal path.
    ///
    /// # Errors
    /// [`PlanningError::CellOutsideMap`], [`PlanningError::InObstacle`] or
    /// [`PlanningError::InUnknown`] when the goal is not a cell a path may end in.
    pub fn cost_to_go(&self, costmap: &Costmap, goal: Cell) -> Result<CostToGo> {
        let factors = self.params.factors();
        let t = factors.endpoint(costmap, Endpoint::Goal, goal)?;
        let g = *costmap.geometry();
        let costs = costmap.data();
        let field = cost_to_go(g.width(), g.height(), |i| factors.of(costs[i]), t, None);
        Ok(CostToGo {
            geometry: g,
            goal,
            field,
        })
    }
}

impl Planner for Dijkstra {
    fn plan(&self, costmap: &Costmap, start: Cell, goal: Cell) -> Result<Path> {
        let factors = self.params.factors();
        let (s, t) = endpoints(&factors, costmap, start, goal)?;
        let g = *costmap.geometry();
        let costs = costmap.data();
        let field = cost_to_go(g.width(), g.height(), |i| factors.of(costs[i]), t, Some(s));
        CostToGo {
            geometry: g,
            goal,
            field,
        }
        .path_from(start)
    }
}

/// The cost-to-go field of one goal: for every cell, the cost of its optimal path to the goal
/// (metres, weighted as in [`SearchParams`]) and the path itself.
#[derive(Debug, Clone, PartialEq)]
pub struct CostToGo {
    geometry: GridGeometry,
    goal: Cell,
    /// Costs in cells.
    field: Field,
}

impl CostToGo {
    /// The goal.
    pub fn goal(&self) -> Cell {
        self.goal
    }
    /// Where the field lies.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// The cost from `cell` to the goal, or `None` outside the grid or when no path joins them.
    pub fn cost(&self, cell: Cell) -> Option<f64> {
        let i = self.geometry.index(cell)?;
        self.field.cost(i).map(|c| c * self.geometry.resolution())
    }
    /// The whole field (metres, weighted; `INFINITY` where the goal cannot be reached).
    pub fn grid(&self) -> Grid<f64> {
        let r = self.geometry.resolution();
        let mut i = 0;
        Grid::from_fn(self.geometry, |_| {
            let c = self.field.cost(i).map_or(f64::INFINITY, |c| c * r);
            i += 1;
            c
        })
    }
    /// The optimal path from `start` to the goal.
    ///
    /// # Errors
    /// [`PlanningError::CellOutsideMap`] when `start` is outside the grid;
    /// [`PlanningError::Unreachable`] when no path joins it to the goal (which includes a start
    /// in an obstacle).
    pub fn path_from(&self, start: Cell) -> Result<Path> {
        let g = &self.geometry;
        let s = g.index(start).ok_or(PlanningError::CellOutsideMap {
            endpoint: Endpoint::Start,
            cell: start,
            width: g.width(),
            height: g.height(),
        })?;
        match (self.field.path(s), self.field.cost(s)) {
            (Some(cells), Some(cost)) => Ok(Path::from_indices(*g, &cells, cost * g.resolution())),
            _ => Err(PlanningError::Unreachable {
                start,
                goal: self.goal,
                explored: self.field.reached(),
            }),
        }
    }
}
