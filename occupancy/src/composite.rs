//! Composite geometric maps (seed 000 III-A): many aligned occupancy grids accumulated into
//! per-cell counts, from which static structure is extracted.

use crate::{CellState, Grid, GridGeometry, OccupancyError, OccupancyGrid, Result};

/// Per-cell counts over many aligned maps of the same geometry.
///
/// ```
/// use haunts_occupancy::{Cell, GeometricComposite, GridGeometry, OccupancyGrid};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(0.05, Point2::origin(), 2, 1).unwrap();
/// let mut c = GeometricComposite::new(g);
/// c.add(&OccupancyGrid::from_values(g, vec![100, 100]).unwrap()).unwrap(); // wall, chair
/// c.add(&OccupancyGrid::from_values(g, vec![100, 0]).unwrap()).unwrap();   // wall, no chair
/// c.add(&OccupancyGrid::from_values(g, vec![100, -1]).unwrap()).unwrap();
/// assert_eq!(c.occupancy_frequency().data(), &[1.0, 1.0 / 3.0]);
/// assert_eq!(c.static_structure(0.9).unwrap().data(), &[true, false]);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct GeometricComposite {
    occupied: Grid<u32>,
    free: Grid<u32>,
    maps: u32,
}

impl GeometricComposite {
    /// An empty composite over `geometry`.
    pub fn new(geometry: GridGeometry) -> Self {
        Self {
            occupied: Grid::filled(geometry, 0),
            free: Grid::filled(geometry, 0),
            maps: 0,
        }
    }

    /// Adds one map (states read with the map's own thresholds).
    ///
    /// # Errors
    /// [`OccupancyError::GeometryMismatch`] unless the map lies on the same cells (origins
    /// may differ by 1e-6 of a cell for decimal round-off in map files); nothing is added.
    pub fn add(&mut self, map: &OccupancyGrid) -> Result<()> {
        if !self
            .geometry()
            .same_cells(map.geometry(), GridGeometry::SAME_CELLS_TOLERANCE)
        {
            return Err(OccupancyError::GeometryMismatch {
                expected: Box::new(*self.geometry()),
                found: Box::new(*map.geometry()),
            });
        }
        let t = map.thresholds();
        let cells = self
            .occupied
            .data_mut()
            .iter_mut()
            .zip(self.free.data_mut());
        for ((o, f), &v) in cells.zip(map.values().data()) {
            match t.state(v) {
                CellState::Occupied => *o += 1,
                CellState::Free => *f += 1,
                CellState::Unknown => {}
            }
        }
        self.maps += 1;
        Ok(())
    }

    /// Where the composite lies.
    pub fn geometry(&self) -> &GridGeometry {
        self.occupied.geometry()
    }
    /// Number of maps added.
    pub fn maps(&self) -> u32 {
        self.maps
    }
    /// How many maps saw each cell occupied.
    pub fn occupied_counts(&self) -> &Grid<u32> {
        &self.occupied
    }
    /// How many maps saw each cell free.
    pub fn free_counts(&self) -> &Grid<u32> {
        &self.free
    }
    /// Fraction of all maps in which each cell was occupied (seed 000 Fig. 3); zeros for an
    /// empty composite.
    pub fn occupancy_frequency(&self) -> Grid<f64> {
        let n = f64::from(self.maps.max(1));
        self.occupied.map(|&o| f64::from(o) / n)
    }
    /// Fraction of the maps that observed a cell in which it was occupied; NaN where no map
    /// observed it.
    pub fn observed_frequency(&self) -> Grid<f64> {
        let data = self.occupied.data().iter().zip(self.free.data());
        let values = data
            .map(|(&o, &f)| {
                if o + f == 0 {
                    f64::NAN
                } else {
                    f64::from(o) / f64::from(o + f)
                }
            })
            .collect();
        Grid::from_vec(*self.geometry(), values)
            .unwrap_or_else(|_| Grid::filled(*self.geometry(), f64::NAN))
    }
    /// Static structure: cells occupied in at least `min_fraction` of the maps (walls, as
    /// opposed to furniture that moves).
    ///
    /// # Errors
    /// [`OccupancyError::EmptyComposite`] before any map is added;
    /// [`OccupancyError::InvalidParameter`] unless `0 < min_fraction <= 1`.
    pub fn static_structure(&self, min_fraction: f64) -> Result<Grid<bool>> {
        if self.maps == 0 {
            return Err(OccupancyError::EmptyComposite);
        }
        haunts_core::fraction("min_fraction", min_fraction)?;
        let need = min_fraction * f64::from(self.maps);
        Ok(self.occupied.map(|&o| f64::from(o) >= need - 1e-9))
    }

    /// The static structure at `min_fraction` as an occupancy grid a planner or `map_server`
    /// reads: 100 where [`GeometricComposite::static_structure`] holds, 0 where some map
    /// observed the cell, −1 (unknown) where none did.
    ///
    /// # Errors
    /// As [`GeometricComposite::static_structure`].
    ///
    /// # Example
    /// ```
    /// use haunts_occupancy::{GeometricComposite, GridGeometry, OccupancyGrid};
    /// use nalgebra::Point2;
    /// let g = GridGeometry::new(1.0, Point2::origin(), 3, 1)?;
    /// let mut composite = GeometricComposite::new(g);
    /// composite.add(&OccupancyGrid::from_values(g, vec![100, 0, -1])?)?;
    /// composite.add(&OccupancyGrid::from_values(g, vec![100, 100, -1])?)?;
    /// // Occupied on both days: static; on one of two: free at a fraction above one half.
    /// assert_eq!(composite.static_map(0.6)?.values().data(), &[100, 0, -1]);
    /// assert_eq!(composite.static_map(0.5)?.values().data(), &[100, 100, -1]);
    /// # Ok::<(), haunts_occupancy::OccupancyError>(())
    /// ```
    pub fn static_map(&self, min_fraction: f64) -> Result<OccupancyGrid> {
        let occupied = self.static_structure(min_fraction)?;
        let observed = self.observed_frequency();
        let values = occupied
            .data()
            .iter()
            .zip(observed.data())
            .map(|(&o, seen)| match (o, seen.is_finite()) {
                (true, _) => 100,
                (false, true) => 0,
                (false, false) => -1,
            })
            .collect();
        OccupancyGrid::from_values(*self.geometry(), values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    #[test]
    fn mismatched_maps_and_bad_fractions_are_rejected() {
        let g = GridGeometry::new(0.05, Point2::origin(), 2, 2).unwrap();
        let mut c = GeometricComposite::new(g);
        assert!(matches!(
            c.static_structure(0.5),
            Err(OccupancyError::EmptyComposite)
        ));
        let other = GridGeometry::new(0.05, Point2::new(0.05, 0.0), 2, 2).unwrap();
        assert!(c.add(&OccupancyGrid::unknown(other)).is_err());
        assert_eq!(c.maps(), 0);
        c.add(&OccupancyGrid::unknown(g)).unwrap();
        assert!(c.static_structure(0.0).is_err());
        assert!(c.static_structure(f64::NAN).is_err());
        assert!(c.observed_frequency().data().iter().all(|v| v.is_nan()));
    }
}
