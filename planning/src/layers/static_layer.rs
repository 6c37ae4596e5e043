//! The static layer: an occupancy map read as free, lethal and unknown costs.

use haunts_occupancy::{CellState, Grid, OccupancyGrid};

use crate::costmap::{FREE_SPACE, LETHAL_OBSTACLE, NO_INFORMATION};
use crate::error::same_geometry;
use crate::{Costmap, Layer, Result};

/// The costs of an occupancy map, as Nav2's static layer with `use_maximum: false`: occupied
/// cells are [`LETHAL_OBSTACLE`], free cells [`FREE_SPACE`], unknown cells [`NO_INFORMATION`] when unknown space is
/// tracked and [`FREE_SPACE`] otherwise. States come from the map's own
/// [`StateThresholds`](haunts_occupancy::StateThresholds).
///
/// The layer overwrites every cell, so it belongs at the bottom of a stack.
///
/// ```
/// use haunts_occupancy::{GridGeometry, OccupancyGrid};
/// use haunts_planning::{LayeredCostmap, StaticLayer, LETHAL_OBSTACLE, NO_INFORMATION};
/// let geometry = GridGeometry::new(0.1, nalgebra::Point2::origin(), 3, 1).unwrap();
/// let map = OccupancyGrid::from_values(geometry, vec![0, 100, -1]).unwrap();
/// let tracked = LayeredCostmap::new(geometry).with_layer(StaticLayer::new(&map, true));
/// assert_eq!(tracked.build()?.data(), &[0, LETHAL_OBSTACLE, NO_INFORMATION]);
/// let untracked = LayeredCostmap::new(geometry).with_layer(StaticLayer::new(&map, false));
/// assert_eq!(untracked.build()?.data(), &[0, LETHAL_OBSTACLE, 0]);
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct StaticLayer {
    costs: Grid<u8>,
}

impl StaticLayer {
    /// The layer of `map`; `track_unknown` says whether unknown cells cost [`NO_INFORMATION`] (Nav2's
    /// `track_unknown_space: true`) or [`FREE_SPACE`].
    pub fn new(map: &OccupancyGrid, track_unknown: bool) -> Self {
        let unknown = if track_unknown {
            NO_INFORMATION
        } else {
            FREE_SPACE
        };
        let thresholds = map.thresholds();
        let costs = map.values().map(|&v| match thresholds.state(v) {
            CellState::Free => FREE_SPACE,
            CellState::Occupied => LETHAL_OBSTACLE,
            CellState::Unknown => unknown,
        });
        Self { costs }
    }

    /// The costs this layer writes.
    pub fn costs(&self) -> &Grid<u8> {
        &self.costs
    }
}

impl Layer for StaticLayer {
    /// Overwrites every cell with the map's cost.
    ///
    /// # Errors
    /// [`PlanningError::GeometryMismatch`](crate::PlanningError::GeometryMismatch) when the map
    /// lies on another grid than `costs`.
    fn apply(&self, costs: &mut Costmap) -> Result<()> {
        same_geometry("static layer", costs.geometry(), self.costs.geometry())?;
        costs
            .grid_mut()
            .data_mut()
            .copy_from_slice(self.costs.data());
        Ok(())
    }
}
