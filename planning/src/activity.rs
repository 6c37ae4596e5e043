//! Planners that avoid people's activity (seed 002, section 5.4): A* with the seed's
//! activity-scaled heuristic, and A* with activity in the step cost, which stays optimal.

use haunts_occupancy::{Cell, Grid};

use crate::astar::run;
use crate::error::{rule, same_geometry};
use crate::planner::endpoints;
use crate::search::{At, Heap, Radix, octile};
use crate::{
    Costmap, INSCRIBED_INFLATED_OBSTACLE, Path, Planner, PlanningError, Result, SearchParams,
};

/// The activity threshold θ of seed 002: below it the heuristic is left alone.
pub const SEED_THRESHOLD: f64 = 5.5;

/// An activity raster (e.g. a target-activity map rasterised onto the costmap's grid) with
/// every value finite, and its maximum.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Activity {
    grid: Grid<f64>,
    max: f64,
}

impl Activity {
    pub(crate) fn new(grid: Grid<f64>) -> Result<Self> {
        if let Some((cell, &value)) = grid.cells().find(|(_, a)| !a.is_finite()) {
            return Err(PlanningError::NonFiniteActivity { cell, value });
        }
        let max = grid
            .data()
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        Ok(Self { grid, max })
    }

    /// The values, after checking they lie on the costmap's grid.
    pub(crate) fn on(&self, costmap: &Costmap) -> Result<&[f64]> {
        same_geometry("activity raster", costmap.geometry(), self.grid.geometry())?;
        Ok(self.grid.data())
    }
}

/// Parameters of [`ActivityAwareAStar`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ActivityAwareParams {
    /// The cost model of `g` (seed 002 used distance alone: `cost_weight` 0 on a costmap of
    /// free and lethal cells).
    pub search: SearchParams,
    /// θ: cells of activity above it scale the heuristic ([`SEED_THRESHOLD`] = 5.5 by default).
    pub threshold: f64,
}

impl Default for ActivityAwareParams {
    fn default() -> Self {
        Self {
            search: SearchParams::default(),
            threshold: SEED_THRESHOLD,
        }
    }
}

impl ActivityAwareParams {
    /// Sets the cost model.
    pub fn with_search(mut self, search: SearchParams) -> Self {
        self.search = search;
        self
    }
    /// Sets θ.
    pub fn with_threshold(mut self, threshold: f64) -> Self {
        self.threshold = threshold;
        self
    }
    /// The parameters, after checking the cost model and a finite `threshold >= 0`.
    ///
    /// # Errors
    /// [`PlanningError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        self.search.check()?;
        let t = self.threshold;
        rule(
            "threshold",
            t,
            t.is_finite() && t >= 0.0,
            "must be finite and >= 0",
        )?;
        Ok(self)
    }
}

/// The activity-aware A* of seed 002 (section 5.4): A* whose heuristic grows with the activity
/// `a_n` of the cell it is evaluated at,
///
/// `h'(n) = h(n) · (1 + a_n / a_max)` when `a_n > θ`, `h(n)` otherwise,
///
/// where `h` is the octile distance to the goal (the seed used the Euclidean distance on its
/// grid), `a_max` the largest activity of the raster and θ the threshold (5.5 in the seed).
///
/// **This heuristic is inadmissible**: it can overestimate the remaining cost by up to a factor
/// of 2. A* then no longer guarantees an optimal path under its own cost `g`: it avoids busy
/// cells because they *look* far from the goal, not because they cost more, so how much it
/// avoids them depends on how far from the goal they are (near the goal `h` is small and the
/// activity hardly matters, which is why the seed's case 2 can still reach a busy goal).
/// Cells are re-opened when reached more cheaply, so the path is always valid. For a path that
/// is optimal for an explicit trade-off between length and activity, use [`ActivityCostAStar`].
///
/// The keys are not monotone under this heuristic, so the open list is a binary heap: among
/// cells of equal `f`, the one with the larger `g`, then the smaller row-major index, first.
///
/// # Errors
/// As [`Planner::plan`]; [`PlanningError::GeometryMismatch`] when the activity raster does not
/// lie on the costmap's grid.
///
/// # Complexity
/// As [`AStar`](crate::AStar), with possibly more expansions (re-opened cells).
///
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry};
/// use haunts_planning::{ActivityAwareAStar, ActivityAwareParams, AStar, Costmap, Planner};
/// let geometry = GridGeometry::new(1.0, nalgebra::Point2::origin(), 21, 11).unwrap();
/// // A busy spot in the middle of the straight line from (0, 5) to (20, 5).
/// let activity = Grid::from_fn(geometry, |c| {
///     let d2 = (c.col as f64 - 10.0).powi(2) + (c.row as f64 - 5.0).powi(2);
///     8.0 * (-d2 / 8.0).exp()
/// });
/// let costmap = Costmap::filled(geometry, 0);
/// let (start, goal) = (Cell::new(0, 5), Cell::new(20, 5));
/// let plain = AStar::default().plan(&costmap, start, goal)?;
/// let aware = ActivityAwareAStar::new(activity.clone(), ActivityAwareParams::default())?
///     .plan(&costmap, start, goal)?;
/// let busiest = |p: &haunts_planning::Path| p.metrics(&activity).unwrap().activity_max;
/// assert!(busiest(&aware) < 5.5 && busiest(&plain) > 7.9);
/// assert!(aware.length() > plain.length());
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ActivityAwareAStar {
    activity: Activity,
    params: ActivityAwareParams,
}

impl ActivityAwareAStar {
    /// The planner over an activity raster, with checked parameters.
    ///
    /// # Errors
    /// As [`ActivityAwareParams::check`]; [`PlanningError::NonFiniteActivity`] for a NaN or
    /// infinite activity.
    pub fn new(activity: Grid<f64>, params: ActivityAwareParams) -> Result<Self> {
        Ok(Self {
            params: params.check()?,
            activity: Activity::new(activity)?,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &ActivityAwareParams {
        &self.params
    }
    /// The activity raster.
    pub fn activity(&self) -> &Grid<f64> {
        &self.activity.grid
    }
}

impl Planner for ActivityAwareAStar {
    fn plan(&self, costmap: &Costmap, start: Cell, goal: Cell) -> Result<Path> {
        let activity = self.activity.on(costmap)?;
        let factors = self.params.search.factors();
        let ends = endpoints(&factors, costmap, start, goal)?;
        let costs = costmap.data();
        // a > θ >= 0 implies a_max >= a > 0, so the scale lies in (1, 2].
        let (theta, a_max) = (self.params.threshold, self.activity.max);
        let heuristic = |at: At| {
            let a = activity[at.index];
            let h = octile(at.col, at.row, goal.col, goal.row);
            if a > theta { h * (1.0 + a / a_max) } else { h }
        };
        run(
            costmap,
            (start, goal),
            ends,
            |i| factors.of(costs[i]),
            heuristic,
            // The heuristic is inconsistent: keys are not monotone, so a general heap.
            Heap::default(),
        )
    }
}

/// Parameters of [`ActivityCostAStar`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ActivityCostParams {
    /// The cost model the activity term is added to.
    pub search: SearchParams,
    /// `w`: extra cost per metre per unit of activity.
    pub activity_weight: f64,
}

impl Default for ActivityCostParams {
    /// The default cost model and `w = 1`.
    fn default() -> Self {
        Self {
            search: SearchParams::default(),
            activity_weight: 1.0,
        }
    }
}

impl ActivityCostParams {
    /// Sets the cost model.
    pub fn with_search(mut self, search: SearchParams) -> Self {
        self.search = search;
        self
    }
    /// Sets `w`, the extra cost per metre per unit of activity.
    pub fn with_activity_weight(mut self, weight: f64) -> Self {
        self.activity_weight = weight;
        self
    }
    /// The parameters, after checking the cost model and a finite `activity_weight >= 0`.
    ///
    /// # Errors
    /// [`PlanningError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        self.search.check()?;
        let w = self.activity_weight;
        rule(
            "activity_weight",
            w,
            w.is_finite() && w >= 0.0,
            "must be finite and >= 0",
        )?;
        Ok(self)
    }
}

/// A* that pays for activity in the step cost: entering a cell of cost `c` and activity `a`
/// with a step of length `L` costs
///
/// `L · (1 + cost_weight · c / 252 + w · max(a, 0))`,
///
/// the principled alternative to [`ActivityAwareAStar`]. Every step still costs at least its
/// length, so the octile heuristic stays admissible and consistent and the path is
/// **optimal** for this trade-off: `w` says how many metres of detour one unit of activity per
/// metre is worth. (Negative activities, which a regression can produce, count as 0.)
///
/// # Errors
/// As [`Planner::plan`]; [`PlanningError::GeometryMismatch`] when the activity raster does not
/// lie on the costmap's grid.
///
/// # Complexity
/// As [`AStar`](crate::AStar).
///
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry};
/// use haunts_planning::{ActivityCostAStar, ActivityCostParams, Costmap, Dijkstra, Planner};
/// let geometry = GridGeometry::new(1.0, nalgebra::Point2::origin(), 3, 1).unwrap();
/// let activity = Grid::from_vec(geometry, vec![0.0, 2.0, -1.0]).unwrap();
/// let params = ActivityCostParams::default().with_activity_weight(0.5);
/// let planner = ActivityCostAStar::new(activity, params)?;
/// let path = planner.plan(&Costmap::filled(geometry, 0), Cell::new(0, 0), Cell::new(2, 0))?;
/// // (1 + 0.5·2) + (1 + 0.5·0) metres.
/// approx::assert_relative_eq!(path.cost(), 3.0, epsilon = 1e-12);
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ActivityCostAStar {
    activity: Activity,
    params: ActivityCostParams,
}

impl ActivityCostAStar {
    /// The planner over an activity raster, with checked parameters.
    ///
    /// # Errors
    /// As [`ActivityCostParams::check`]; [`PlanningError::NonFiniteActivity`] for a NaN or
    /// infinite activity.
    pub fn new(activity: Grid<f64>, params: ActivityCostParams) -> Result<Self> {
        Ok(Self {
            params: params.check()?,
            activity: Activity::new(activity)?,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &ActivityCostParams {
        &self.params
    }
    /// The activity raster.
    pub fn activity(&self) -> &Grid<f64> {
        &self.activity.grid
    }
}

impl Planner for ActivityCostAStar {
    fn plan(&self, costmap: &Costmap, start: Cell, goal: Cell) -> Result<Path> {
        let activity = self.activity.on(costmap)?;
        let factors = self.params.search.factors();
        let ends = endpoints(&factors, costmap, start, goal)?;
        let costs = costmap.data();
        let weight = self.params.activity_weight;
        run(
            costmap,
            (start, goal),
            ends,
            |i| factors.of(costs[i]) + weight * activity[i].max(0.0),
            |at| octile(at.col, at.row, goal.col, goal.row),
            Radix::default(),
        )
    }
}

/// The cell of maximum activity among the cells a path may end in (cost below
/// [`INSCRIBED_INFLATED_OBSTACLE`]; unknown cells excluded): the goal of seed 002's case 2. Ties go to the
/// smallest row-major index; NaN activities are ignored.
///
/// # Errors
/// [`PlanningError::GeometryMismatch`] when `activity` does not lie on the costmap's grid;
/// [`PlanningError::NoActivity`] when no such cell has a finite activity.
///
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry};
/// use haunts_planning::{max_activity_cell, Costmap, LETHAL_OBSTACLE};
/// let geometry = GridGeometry::new(1.0, nalgebra::Point2::origin(), 3, 1).unwrap();
/// let activity = Grid::from_vec(geometry, vec![1.0, 9.0, 4.0]).unwrap();
/// let costmap = Costmap::new(Grid::from_vec(geometry, vec![0, LETHAL_OBSTACLE, 0]).unwrap());
/// assert_eq!(max_activity_cell(&activity, &costmap)?, Cell::new(2, 0));
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
pub fn max_activity_cell(activity: &Grid<f64>, costmap: &Costmap) -> Result<Cell> {
    same_geometry("activity raster", costmap.geometry(), activity.geometry())?;
    let mut best: Option<(Cell, f64)> = None;
    for ((cell, &a), &cost) in activity.cells().zip(costmap.data()) {
        if cost < INSCRIBED_INFLATED_OBSTACLE && a.is_finite() && best.is_none_or(|(_, b)| a > b) {
            best = Some((cell, a));
        }
    }
    best.map(|(cell, _)| cell).ok_or(PlanningError::NoActivity)
}
/// Most directions [`crossings`] takes.
const MAX_DIRECTIONS: usize = 3600;

/// Start–goal pairs across `through`, for comparing planners on trips that cross a busy
/// place from every side (seed 002's case 1, "a start and a goal with a high-activity area
/// between them", without choosing one side): for each of `directions` bearings evenly
/// spaced over half a turn, the cells free to end a path in (cost below [`INSCRIBED_INFLATED_OBSTACLE`])
/// nearest to the two points `radius` metres either side of `through`'s centre. A side with
/// no such cell within `radius / 2` (a wall, the map's edge) drops its direction.
///
/// # Errors
/// [`PlanningError::InvalidParameter`] unless `radius` is finite and > 0 and `directions`
/// lies in `1..=3600` (a tenth of a degree apart at most).
///
/// ```
/// use haunts_occupancy::{Cell, GridGeometry};
/// use haunts_planning::{Costmap, crossings};
/// let geometry = GridGeometry::new(0.5, nalgebra::Point2::origin(), 21, 21).unwrap();
/// let trips = crossings(&Costmap::filled(geometry, 0), Cell::new(10, 10), 4.0, 4)?;
/// // 0°, 45°, 90° and 135°, each 8 cells either side.
/// assert_eq!(trips.len(), 4);
/// assert_eq!(trips[0], (Cell::new(2, 10), Cell::new(18, 10)));
/// assert_eq!(trips[2], (Cell::new(10, 2), Cell::new(10, 18)));
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
pub fn crossings(
    costmap: &Costmap,
    through: Cell,
    radius: f64,
    directions: usize,
) -> Result<Vec<(Cell, Cell)>> {
    rule(
        "radius",
        radius,
        radius.is_finite() && radius > 0.0,
        "must be finite and > 0",
    )?;
    rule(
        "directions",
        directions as f64,
        (1..=MAX_DIRECTIONS).contains(&directions),
        "must be between 1 and 3600",
    )?;
    let centre = costmap.geometry().cell_center(through);
    let within = 0.5 * radius;
    Ok((0..directions)
        .filter_map(|k| {
            let angle = std::f64::consts::PI * k as f64 / directions as f64;
            let step = nalgebra::Vector2::new(angle.cos(), angle.sin()) * radius;
            Some((
                costmap.nearest_free(centre - step, within)?,
                costmap.nearest_free(centre + step, within)?,
            ))
        })
        .collect())
}
