//! The [`DensityMap`] trait: the density of people at a world point.

use haunts_occupancy::{Grid, GridGeometry};
use nalgebra::Point2;

/// A map of how much people are at each world point (per-layout affordance, TA map, hypertime
/// model at a time t, …). Units are the implementation's (a ratio of hits to visits, a
/// probability density per m², an activity level); each implementation documents its own.
///
/// Object safe and `Send + Sync`; implemented for `&T`, `&mut T`, `Box<T>` and `Arc<T>` of any
/// density map, so an owner can hold a boxed one and lend a borrowed one alike.
#[auto_impl::auto_impl(&, &mut, Box, Arc)]
pub trait DensityMap: Send + Sync {
    /// The density at world point `p` (metres), or `None` where the map knows nothing (never
    /// seen, outside its extent).
    fn density_at(&self, p: Point2<f64>) -> Option<f64>;

    /// The density at every cell centre of `geometry`, `NaN` where unknown (a raster that
    /// `haunts_planning`'s density layer and the picture functions take directly).
    fn rasterise(&self, geometry: &GridGeometry) -> Grid<f64> {
        Grid::from_fn(*geometry, |cell| {
            self.density_at(geometry.cell_center(cell))
                .unwrap_or(f64::NAN)
        })
    }
}

/// The same density everywhere (or unknown everywhere): the trivial implementation for tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UniformDensity(pub Option<f64>);

impl DensityMap for UniformDensity {
    fn density_at(&self, _p: Point2<f64>) -> Option<f64> {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rasterise_marks_unknown_as_nan() {
        let g = GridGeometry::new(0.5, Point2::new(-1.0, 2.0), 3, 2).unwrap();
        let known = UniformDensity(Some(0.25)).rasterise(&g);
        assert!(known.data().iter().all(|v| *v == 0.25));
        let unknown = UniformDensity(None).rasterise(&g);
        assert!(unknown.data().iter().all(|v| v.is_nan()));
        assert_eq!(unknown.width(), 3);
    }
}
