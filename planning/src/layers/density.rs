//! The density layer: a raster of people's density (or any scalar) turned into costs, to avoid
//! people (positive weight) or to seek them (negative weight), as seed 000 uses its affordance
//! map in the ROS global costmap.

use haunts_occupancy::Grid;

use super::for_row_chunks;
use crate::costmap::{INSCRIBED_INFLATED_OBSTACLE, MAX_NON_OBSTACLE};
use crate::error::{rule, same_geometry};
use crate::{Costmap, Layer, Result};

/// How a [`DensityLayer`] combines its cost `v` with the cost `c` below it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Combine {
    /// `max(c, v)` (Nav2's `updateWithMax`): the layer only raises costs.
    #[default]
    Max,
    /// `v` (Nav2's `updateWithOverwrite`): the layer's cost replaces the one below.
    Overwrite,
    /// `c + v`, saturated to `0..=252` so that it never creates or removes an obstacle (Nav2's
    /// `updateWithAddition` saturates the same way). With a negative weight this lowers costs
    /// where people are.
    Additive,
}

/// Parameters of a [`DensityLayer`]: the layer's cost of a cell of density `x` is
/// `offset + weight · x`, rounded to the nearest integer and clamped to `0..=252`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct DensityLayerParams {
    /// Cost per unit of density. Positive to avoid people, negative to seek them (seed 000).
    pub weight: f64,
    /// Cost added to every cell the raster covers; with a negative weight, an offset makes
    /// empty places cost more than busy ones even in [`Combine::Max`] mode.
    pub offset: f64,
    /// How the layer's cost meets the cost below.
    pub combine: Combine,
}

impl Default for DensityLayerParams {
    /// Weight 252 (a density of 1 is the highest non-obstacle cost), offset 0, [`Combine::Max`].
    fn default() -> Self {
        Self {
            weight: f64::from(MAX_NON_OBSTACLE),
            offset: 0.0,
            combine: Combine::Max,
        }
    }
}

impl DensityLayerParams {
    /// Sets the weight (cost per unit of density; negative to seek people).
    pub fn with_weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }
    /// Sets the offset (cost added to every covered cell).
    pub fn with_offset(mut self, offset: f64) -> Self {
        self.offset = offset;
        self
    }
    /// Sets the combination mode.
    pub fn with_combine(mut self, combine: Combine) -> Self {
        self.combine = combine;
        self
    }

    /// The parameters, after checking that `weight` and `offset` are finite.
    ///
    /// # Errors
    /// [`PlanningError::InvalidParameter`](crate::PlanningError::InvalidParameter) naming the
    /// first rule broken.
    pub fn check(self) -> Result<Self> {
        rule(
            "weight",
            self.weight,
            self.weight.is_finite(),
            "must be finite",
        )?;
        rule(
            "offset",
            self.offset,
            self.offset.is_finite(),
            "must be finite",
        )?;
        Ok(self)
    }
}

/// A density raster as a costmap layer.
///
/// The raster must lie on the costmap's grid (rasterise a density map onto the costmap's
/// geometry). A NaN cell of the raster means "no information": the layer leaves that cell alone.
/// Obstacle cells ([`INSCRIBED_INFLATED_OBSTACLE`], [`LETHAL_OBSTACLE`](crate::LETHAL_OBSTACLE), [`NO_INFORMATION`](crate::NO_INFORMATION)) are
/// never changed, in any mode: people neither create walls nor remove them.
///
/// # Complexity
/// O(cells).
///
/// ```
/// use haunts_occupancy::{Grid, GridGeometry};
/// use haunts_planning::{Combine, Costmap, DensityLayer, DensityLayerParams, Layer, LETHAL_OBSTACLE};
/// let geometry = GridGeometry::new(0.5, nalgebra::Point2::origin(), 4, 1).unwrap();
/// let people = Grid::from_vec(geometry, vec![0.0, 1.0, f64::NAN, 1.0]).unwrap();
/// let below = Grid::from_vec(geometry, vec![100, 100, 100, LETHAL_OBSTACLE]).unwrap();
///
/// // Seek people: cost 200 where nobody is, 200 − 150 = 50 where density is 1.
/// let seek = DensityLayerParams::default().with_weight(-150.0).with_offset(200.0).with_combine(Combine::Overwrite);
/// let mut costmap = Costmap::new(below.clone());
/// DensityLayer::new(people.clone(), seek)?.apply(&mut costmap)?;
/// assert_eq!(costmap.data(), &[200, 50, 100, LETHAL_OBSTACLE]);
///
/// // Avoid people on top of what is there, saturating below lethal.
/// let avoid = DensityLayerParams::default().with_weight(200.0).with_combine(Combine::Additive);
/// let mut costmap = Costmap::new(below);
/// DensityLayer::new(people, avoid)?.apply(&mut costmap)?;
/// assert_eq!(costmap.data(), &[100, 252, 100, LETHAL_OBSTACLE]);
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct DensityLayer {
    raster: Grid<f64>,
    params: DensityLayerParams,
}

impl DensityLayer {
    /// The layer of `raster` with checked parameters.
    ///
    /// # Errors
    /// As [`DensityLayerParams::check`].
    pub fn new(raster: Grid<f64>, params: DensityLayerParams) -> Result<Self> {
        Ok(Self {
            raster,
            params: params.check()?,
        })
    }

    /// The raster.
    pub fn raster(&self) -> &Grid<f64> {
        &self.raster
    }
    /// The parameters.
    pub fn params(&self) -> &DensityLayerParams {
        &self.params
    }
}

impl Layer for DensityLayer {
    /// Combines the raster's costs with the non-obstacle cells of `costs`.
    ///
    /// # Errors
    /// [`PlanningError::GeometryMismatch`](crate::PlanningError::GeometryMismatch) when the
    /// raster lies on another grid than `costs`.
    fn apply(&self, costs: &mut Costmap) -> Result<()> {
        same_geometry("density layer", costs.geometry(), self.raster.geometry())?;
        let DensityLayerParams {
            weight,
            offset,
            combine,
        } = self.params;
        let raster = self.raster.data();
        let width = costs.geometry().width();
        for_row_chunks(costs.grid_mut().data_mut(), width, |first, chunk| {
            let raster = &raster[first..first + chunk.len()];
            for (cost, &x) in chunk.iter_mut().zip(raster) {
                if *cost >= INSCRIBED_INFLATED_OBSTACLE || x.is_nan() {
                    continue;
                }
                let v = offset + weight * x;
                let combined = match combine {
                    Combine::Max => f64::from(*cost).max(v),
                    Combine::Overwrite => v,
                    Combine::Additive => f64::from(*cost) + v,
                };
                if !combined.is_nan() {
                    *cost = combined.round().clamp(0.0, f64::from(MAX_NON_OBSTACLE)) as u8;
                }
            }
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PlanningError;
    use haunts_occupancy::GridGeometry;

    fn geometry() -> GridGeometry {
        GridGeometry::new(1.0, nalgebra::Point2::origin(), 3, 1).unwrap()
    }

    #[test]
    fn non_finite_parameters_are_rejected() {
        let raster = Grid::filled(geometry(), 0.0);
        for (params, name) in [
            (
                DensityLayerParams::default().with_weight(f64::NAN),
                "weight",
            ),
            (
                DensityLayerParams::default().with_weight(f64::NEG_INFINITY),
                "weight",
            ),
            (
                DensityLayerParams::default().with_offset(f64::NAN),
                "offset",
            ),
        ] {
            match DensityLayer::new(raster.clone(), params) {
                Err(PlanningError::InvalidParameter(haunts_core::InvalidParameter {
                    name: n,
                    ..
                })) => assert_eq!(n, name),
                other => panic!("{params:?} gave {other:?}"),
            }
        }
    }

    #[test]
    fn infinite_densities_saturate_and_max_mode_ignores_negative_costs() {
        let raster = Grid::from_vec(geometry(), vec![f64::INFINITY, -5.0, 0.25]).unwrap();
        let mut costmap = Costmap::filled(geometry(), 10);
        DensityLayer::new(raster, DensityLayerParams::default().with_weight(100.0))
            .unwrap()
            .apply(&mut costmap)
            .unwrap();
        assert_eq!(costmap.data(), &[MAX_NON_OBSTACLE, 10, 25]);
    }

    #[test]
    fn other_grids_are_rejected() {
        let other = GridGeometry::new(1.0, nalgebra::Point2::origin(), 4, 1).unwrap();
        let layer =
            DensityLayer::new(Grid::filled(other, 1.0), DensityLayerParams::default()).unwrap();
        let mut costmap = Costmap::filled(geometry(), 0);
        assert!(matches!(
            layer.apply(&mut costmap),
            Err(PlanningError::GeometryMismatch {
                what: "density layer",
                ..
            })
        ));
    }
}
