//! A*: the optimal path under the costmap's cost model, guided by the octile distance.

use haunts_occupancy::Cell;

use crate::planner::endpoints;
use crate::search::{At, Queue, Radix, astar_with_extra, no_extra, octile};
use crate::{Costmap, Path, Planner, PlanningError, Result, SearchParams};

/// A* on the 8-connected grid of a costmap, with the cost model of [`SearchParams`] and the
/// octile distance as heuristic.
///
/// The heuristic is admissible and consistent (every step costs at least its length), so the
/// path is optimal: its [`Path::cost`] equals [`Dijkstra`](crate::Dijkstra)'s. The open list
/// is a radix heap (keys are monotone under a consistent heuristic); among cells of equal `f`
/// the one reached last is expanded first, so the same input always gives the same path. When
/// several paths are optimal, which one is returned depends on this rule.
///
/// # Errors
/// As [`Planner::plan`].
///
/// # Complexity
/// O(cells) memory (dense arrays of costs so far and parents, allocated zeroed per call) and
/// O(E · log C) time in the edges E the search relaxes (at worst every cell's) and the spread
/// C of the keys' bits.
///
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry};
/// use haunts_planning::{AStar, Costmap, Planner, SearchParams, LETHAL_OBSTACLE};
/// // A wall at x = 2 with a gap at the top row.
/// let geometry = GridGeometry::new(0.5, nalgebra::Point2::origin(), 5, 4).unwrap();
/// let wall = |c: Cell| c.col == 2 && c.row < 3;
/// let costmap = Costmap::new(Grid::from_fn(geometry, |c| if wall(c) { LETHAL_OBSTACLE } else { 0 }));
/// let planner = AStar::new(SearchParams::default())?;
/// let path = planner.plan(&costmap, Cell::new(0, 0), Cell::new(4, 0))?;
/// assert!(path.cells().contains(&Cell::new(2, 3)));
/// // Up to the gap, through it and down again, never cutting the wall's corners:
/// // six straight steps and two diagonal ones.
/// approx::assert_relative_eq!(path.length(), 0.5 * (6.0 + 2.0 * 2f64.sqrt()), epsilon = 1e-12);
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AStar {
    params: SearchParams,
}

impl AStar {
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
}

impl Planner for AStar {
    fn plan(&self, costmap: &Costmap, start: Cell, goal: Cell) -> Result<Path> {
        let factors = self.params.factors();
        let ends = endpoints(&factors, costmap, start, goal)?;
        let costs = costmap.data();
        run(
            costmap,
            (start, goal),
            ends,
            |i| factors.of(costs[i]),
            |at| octile(at.col, at.row, goal.col, goal.row),
            Radix::default(),
        )
    }
}

/// A* on `costmap` between checked endpoints (`ends` = their indices) with the given step
/// factor and heuristic (both in cells) and open list, as a [`Path`] in metres or
/// [`PlanningError::Unreachable`].
pub(crate) fn run(
    costmap: &Costmap,
    ends: (Cell, Cell),
    indices: (usize, usize),
    factor: impl Fn(usize) -> f64,
    heuristic: impl Fn(At) -> f64,
    queue: impl Queue,
) -> Result<Path> {
    run_with_extra(costmap, ends, indices, factor, no_extra, heuristic, queue)
}

/// [`run`] with an extra factor `extra(i, j)` on each step from cell index `i` to `j`
/// (`search::astar_with_extra`).
pub(crate) fn run_with_extra(
    costmap: &Costmap,
    (start, goal): (Cell, Cell),
    (s, t): (usize, usize),
    factor: impl Fn(usize) -> f64,
    extra: impl Fn(usize, usize) -> f64,
    heuristic: impl Fn(At) -> f64,
    queue: impl Queue,
) -> Result<Path> {
    let g = costmap.geometry();
    let found = astar_with_extra(
        g.width(),
        g.height(),
        factor,
        extra,
        heuristic,
        (s, t),
        queue,
    )
    .map_err(|explored| PlanningError::Unreachable {
        start,
        goal,
        explored,
    })?;
    Ok(Path::from_indices(
        *g,
        &found.cells,
        found.cost * g.resolution(),
    ))
}
