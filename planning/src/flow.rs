//! A cost for moving against people's flow: the robot keeps to the side people walk on
//! instead of meeting them head-on.
//!
//! A [`DirectionalCost`] gives, for every cell and each of the grid's eight moves, an extra
//! cost per metre of entering that cell with that move (a flow map's opposing traffic, say:
//! `haunts_affordance::flow::FlowMap::against`). [`FlowCostAStar`] adds it to the cost model's
//! step cost, beside the activity cost of [`ActivityCostAStar`](crate::ActivityCostAStar):
//!
//! `L · (1 + cost_weight · c / 252 + w_a · max(a, 0) + w_f · f_k(v))`
//!
//! for a step of length `L` (metres) into cell `v` of cost `c`, activity `a`, by move `k`.
//! Every extra term is ≥ 0, so every step costs at least its length: the octile distance
//! stays an admissible and consistent heuristic, and the path is **optimal** for this cost
//! (`planning/tests/flow_cost.rs` checks it against a plain Dijkstra on random maps).

use haunts_occupancy::{Cell, Grid, GridGeometry};

use crate::activity::Activity;
use crate::astar::run_with_extra;
use crate::error::{rule, same_geometry};
use crate::planner::endpoints;
use crate::search::{Radix, octile};
use crate::{Costmap, Path, Planner, PlanningError, Result, SearchParams};

/// The grid's eight moves by heading: move `k` heads `k · 45°` (0 east, +x, to the next
/// column; 2 north, +y, to the next row; 4 west; 6 south), as `(columns, rows)`.
pub const MOVES: [(i8, i8); 8] = [
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
];

/// The heading of move `k` ([`MOVES`]), radians: `k · π/4`.
pub fn move_heading(k: usize) -> f64 {
    k as f64 * std::f64::consts::FRAC_PI_4
}

/// The move ([`MOVES`] index) from cell `from` to the neighbouring cell `to`; `None` when
/// they are not neighbours.
pub fn move_between(from: Cell, to: Cell) -> Option<usize> {
    let dc = to.col as i64 - from.col as i64;
    let dr = to.row as i64 - from.row as i64;
    MOVES
        .iter()
        .position(|&(c, r)| i64::from(c) == dc && i64::from(r) == dr)
}

/// Per cell, per move ([`MOVES`]), an extra cost per metre of entering the cell by that move:
/// finite and ≥ 0.
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionalCost {
    geometry: GridGeometry,
    values: Vec<[f64; 8]>,
}

impl DirectionalCost {
    /// The costs `values` (row-major, one array of eight per cell) on `geometry`.
    ///
    /// # Errors
    /// [`PlanningError::InvalidDirectionalCost`] for a value that is not finite and ≥ 0, or
    /// for a number of cells other than the geometry's (reported at the first missing cell,
    /// or at cell (0, 0) when there are more, with the number given as the value).
    pub fn new(geometry: GridGeometry, values: Vec<[f64; 8]>) -> Result<Self> {
        if values.len() != geometry.len() {
            return Err(PlanningError::InvalidDirectionalCost {
                cell: geometry
                    .cell_at(values.len().min(geometry.len()))
                    .unwrap_or(Cell::new(0, 0)),
                value: values.len() as f64,
                what: "a cell count other than the grid's",
            });
        }
        for (i, v) in values.iter().enumerate() {
            if let Some(&value) = v.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                return Err(PlanningError::InvalidDirectionalCost {
                    cell: geometry.cell_at(i).unwrap_or(Cell::new(0, 0)),
                    value,
                    what: "not finite and >= 0",
                });
            }
        }
        Ok(Self { geometry, values })
    }

    /// The costs `f(cell, heading)` for every cell and each move's heading
    /// ([`move_heading`]).
    ///
    /// # Errors
    /// As [`DirectionalCost::new`].
    pub fn from_fn(geometry: GridGeometry, mut f: impl FnMut(Cell, f64) -> f64) -> Result<Self> {
        let values = (0..geometry.len())
            .filter_map(|i| geometry.cell_at(i))
            .map(|cell| std::array::from_fn(|k| f(cell, move_heading(k))))
            .collect();
        Self::new(geometry, values)
    }

    /// The grid.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The extra cost per metre of entering `cell` by move `k`; `None` outside the grid or
    /// for `k ≥ 8`.
    pub fn at(&self, cell: Cell, k: usize) -> Option<f64> {
        self.values.get(self.geometry.index(cell)?)?.get(k).copied()
    }

    /// The values on `costmap`'s grid.
    fn on(&self, costmap: &Costmap) -> Result<&[[f64; 8]]> {
        same_geometry("directional cost", costmap.geometry(), &self.geometry)?;
        Ok(&self.values)
    }
}

/// Parameters of [`FlowCostAStar`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct FlowCostParams {
    /// The cost model the extra terms are added to.
    pub search: SearchParams,
    /// `w_f`: weight of the directional cost (1: a metre against a cost of 1 costs a metre
    /// more).
    pub flow_weight: f64,
    /// `w_a`: extra cost per metre per unit of activity, when an activity raster is given
    /// ([`FlowCostAStar::with_activity`]); as [`ActivityCostParams`](crate::ActivityCostParams).
    pub activity_weight: f64,
}

impl Default for FlowCostParams {
    /// The default cost model, `w_f = 1`, `w_a = 1`.
    fn default() -> Self {
        Self {
            search: SearchParams::default(),
            flow_weight: 1.0,
            activity_weight: 1.0,
        }
    }
}

impl FlowCostParams {
    /// Sets the cost model.
    pub fn with_search(mut self, search: SearchParams) -> Self {
        self.search = search;
        self
    }
    /// Sets `w_f`.
    pub fn with_flow_weight(mut self, weight: f64) -> Self {
        self.flow_weight = weight;
        self
    }
    /// Sets `w_a`.
    pub fn with_activity_weight(mut self, weight: f64) -> Self {
        self.activity_weight = weight;
        self
    }
    /// The parameters, after checking the cost model and both weights finite and ≥ 0.
    ///
    /// # Errors
    /// [`PlanningError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        self.search.check()?;
        for (name, w) in [
            ("flow_weight", self.flow_weight),
            ("activity_weight", self.activity_weight),
        ] {
            rule(
                name,
                w,
                w.is_finite() && w >= 0.0,
                "must be finite and >= 0",
            )?;
        }
        Ok(self)
    }
}

/// A* that pays for moving against people's flow (and, optionally, for their activity) in
/// the step cost: `L · (1 + cost_weight · c / 252 + w_a · max(a, 0) + w_f · f_k(v))` for a
/// step of length `L` into cell `v` of cost `c` and activity `a` by move `k` (see
/// [`DirectionalCost`]). Optimal for its cost, as [`AStar`](crate::AStar) is for the cost
/// model's.
///
/// # Errors
/// As [`Planner::plan`]; [`PlanningError::GeometryMismatch`] when the directional cost or the
/// activity raster does not lie on the costmap's grid.
///
/// # Complexity
/// As [`AStar`](crate::AStar), with a look-up of the move per step.
///
/// ```
/// use haunts_occupancy::{Cell, GridGeometry};
/// use haunts_planning::{AStar, Costmap, DirectionalCost, FlowCostAStar, FlowCostParams, Planner};
/// // A corridor 3 cells wide; people walk west in its upper lane (row 2).
/// let geometry = GridGeometry::new(1.0, nalgebra::Point2::origin(), 12, 3).unwrap();
/// let against_west = DirectionalCost::from_fn(geometry, |cell, heading| {
///     // Moving east (heading 0) in row 2 meets them head-on.
///     if cell.row == 2 { (-(heading - std::f64::consts::PI).cos()).max(0.0) } else { 0.0 }
/// })?;
/// let costmap = Costmap::filled(geometry, 0);
/// let (start, goal) = (Cell::new(0, 2), Cell::new(11, 2));
/// let plain = AStar::default().plan(&costmap, start, goal)?;
/// let aware = FlowCostAStar::new(against_west, FlowCostParams::default())?
///     .plan(&costmap, start, goal)?;
/// assert!(plain.cells().iter().all(|c| c.row == 2));
/// // It drops to the lane people walk east in, and comes back up at the end.
/// assert!(aware.cells().iter().filter(|c| c.row == 2).count() <= 2);
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct FlowCostAStar {
    flow: DirectionalCost,
    activity: Option<Activity>,
    params: FlowCostParams,
}

impl FlowCostAStar {
    /// The planner over a directional cost, with checked parameters and no activity term.
    ///
    /// # Errors
    /// As [`FlowCostParams::check`].
    pub fn new(flow: DirectionalCost, params: FlowCostParams) -> Result<Self> {
        Ok(Self {
            flow,
            activity: None,
            params: params.check()?,
        })
    }

    /// The same planner with an activity raster, paid for as
    /// [`ActivityCostAStar`](crate::ActivityCostAStar) does (weight
    /// [`FlowCostParams::activity_weight`]).
    ///
    /// # Errors
    /// [`PlanningError::NonFiniteActivity`] for a NaN or infinite activity;
    /// [`PlanningError::GeometryMismatch`] when it does not lie on the directional cost's grid.
    pub fn with_activity(mut self, activity: Grid<f64>) -> Result<Self> {
        same_geometry("activity raster", &self.flow.geometry, activity.geometry())?;
        self.activity = Some(Activity::new(activity)?);
        Ok(self)
    }

    /// The parameters.
    pub fn params(&self) -> &FlowCostParams {
        &self.params
    }
    /// The directional cost.
    pub fn flow(&self) -> &DirectionalCost {
        &self.flow
    }
}

impl Planner for FlowCostAStar {
    fn plan(&self, costmap: &Costmap, start: Cell, goal: Cell) -> Result<Path> {
        let flow = self.flow.on(costmap)?;
        let activity = match &self.activity {
            Some(a) => Some(a.on(costmap)?),
            None => None,
        };
        let factors = self.params.search.factors();
        let ends = endpoints(&factors, costmap, start, goal)?;
        let costs = costmap.data();
        let (wf, wa) = (self.params.flow_weight, self.params.activity_weight);
        let w = costmap.geometry().width();
        // The move from index `i` to its neighbour `j`, by their columns and rows (not by the
        // index difference alone: on a grid one or two cells wide, moves share differences).
        let move_of = |i: usize, j: usize| {
            let dc = (j % w) as isize - (i % w) as isize;
            let dr = (j / w) as isize - (i / w) as isize;
            MOVES
                .iter()
                .position(|&(c, r)| isize::from(c) == dc && isize::from(r) == dr)
        };
        run_with_extra(
            costmap,
            (start, goal),
            ends,
            |j| {
                let a = activity.map_or(0.0, |a| wa * a[j].max(0.0));
                factors.of(costs[j]) + a
            },
            |i, j| move_of(i, j).map_or(0.0, |k| wf * flow[j][k]),
            |at| octile(at.col, at.row, goal.col, goal.row),
            Radix::default(),
        )
    }
}

/// The share of `path`'s length that moves at more than 90° from the dominant flow of the
/// cell it enters (`dominant(cell)`, a heading in radians; `None`: no dominant flow, never
/// against): the `against_flow_share` of a plan. 0 for a path of one cell.
pub fn against_flow_share(path: &Path, mut dominant: impl FnMut(Cell) -> Option<f64>) -> f64 {
    let (mut against, mut total) = (0.0, 0.0);
    for pair in path.cells().windows(2) {
        let Some(k) = move_between(pair[0], pair[1]) else {
            continue;
        };
        let length = if k % 2 == 0 {
            1.0
        } else {
            std::f64::consts::SQRT_2
        };
        total += length;
        if let Some(flow) = dominant(pair[1]) {
            // cos < 0: more than 90° apart.
            if (move_heading(k) - flow).cos() < -1e-12 {
                against += length;
            }
        }
    }
    if total > 0.0 { against / total } else { 0.0 }
}
