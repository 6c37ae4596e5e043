//! Path metrics of seed 002's Table 2: length, and mean, variance and maximum of the activity
//! along the path.

use haunts_occupancy::Grid;

use crate::error::same_geometry;
use crate::{Path, PlanningError, Result};

/// How long a path is and how much activity it meets (seed 002, Table 2).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PathMetrics {
    /// Length in metres ([`Path::length`]).
    pub length: f64,
    /// Mean activity over the path's cells.
    pub activity_mean: f64,
    /// Population variance (divided by the number of cells) of the activity over the cells.
    pub activity_variance: f64,
    /// Largest activity of a cell of the path.
    pub activity_max: f64,
}

impl Path {
    /// The path's length and the statistics of `activity` over its cells, start and goal
    /// included (each cell counts once, as the seed evaluates "each point along the path").
    ///
    /// # Errors
    /// [`PlanningError::GeometryMismatch`] when `activity` does not lie on the path's grid;
    /// [`PlanningError::NonFiniteActivity`] when a cell of the path has a NaN or infinite
    /// activity.
    ///
    /// ```
    /// use haunts_occupancy::{Cell, Grid, GridGeometry};
    /// use haunts_planning::{Costmap, Planner, StraightLine};
    /// let geometry = GridGeometry::new(0.5, nalgebra::Point2::origin(), 4, 1).unwrap();
    /// let activity = Grid::from_vec(geometry, vec![1.0, 3.0, 1.0, 3.0]).unwrap();
    /// let costmap = Costmap::filled(geometry, 0);
    /// let path = StraightLine::default().plan(&costmap, Cell::new(0, 0), Cell::new(3, 0))?;
    /// let m = path.metrics(&activity)?;
    /// assert_eq!((m.length, m.activity_mean), (1.5, 2.0));
    /// assert_eq!((m.activity_variance, m.activity_max), (1.0, 3.0));
    /// # Ok::<(), haunts_planning::PlanningError>(())
    /// ```
    pub fn metrics(&self, activity: &Grid<f64>) -> Result<PathMetrics> {
        same_geometry("activity raster", self.geometry(), activity.geometry())?;
        let mut values = Vec::with_capacity(self.cells().len());
        for &cell in self.cells() {
            let value = activity[cell];
            if !value.is_finite() {
                return Err(PlanningError::NonFiniteActivity { cell, value });
            }
            values.push(value);
        }
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Ok(PathMetrics {
            length: self.length(),
            activity_mean: mean,
            activity_variance: variance,
            activity_max: max,
        })
    }
}
