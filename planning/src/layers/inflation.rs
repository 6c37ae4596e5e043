//! The inflation layer: costs that fall off exponentially with the exact distance to the
//! nearest lethal cell.

use haunts_occupancy::distance_transform;

use super::for_row_chunks;
use crate::costmap::{
    INSCRIBED_INFLATED_OBSTACLE, LETHAL_OBSTACLE, MAX_NON_OBSTACLE, NO_INFORMATION,
};
use crate::error::rule;
use crate::{Costmap, Layer, Result};

/// Parameters of an [`InflationLayer`], in metres.
///
/// The defaults are those of `nav2_bringup`'s parameter file for a TurtleBot 3: inscribed
/// radius 0.22 m, inflation radius 0.55 m, cost scaling factor 3 per metre.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct InflationParams {
    /// Radius of the largest circle inside the robot's footprint: cells this close to a lethal
    /// cell are [`INSCRIBED_INFLATED_OBSTACLE`].
    pub inscribed_radius: f64,
    /// Cells farther than this from every lethal cell get no inflation cost.
    pub inflation_radius: f64,
    /// `k` in `252·exp(−k·(d − r_inscribed))`, per metre: larger values make costs fall off
    /// faster.
    pub cost_scaling_factor: f64,
}

impl Default for InflationParams {
    fn default() -> Self {
        Self {
            inscribed_radius: 0.22,
            inflation_radius: 0.55,
            cost_scaling_factor: 3.0,
        }
    }
}

impl InflationParams {
    /// Sets the inscribed radius (metres).
    pub fn with_inscribed_radius(mut self, metres: f64) -> Self {
        self.inscribed_radius = metres;
        self
    }
    /// Sets the inflation radius (metres).
    pub fn with_inflation_radius(mut self, metres: f64) -> Self {
        self.inflation_radius = metres;
        self
    }
    /// Sets the cost scaling factor (per metre).
    pub fn with_cost_scaling_factor(mut self, k: f64) -> Self {
        self.cost_scaling_factor = k;
        self
    }

    /// The parameters, after checking `0 <= inscribed_radius <= inflation_radius`, both finite,
    /// and a finite `cost_scaling_factor >= 0`.
    ///
    /// # Errors
    /// [`PlanningError::InvalidParameter`](crate::PlanningError::InvalidParameter) naming the
    /// first rule broken.
    pub fn check(self) -> Result<Self> {
        let r_i = self.inscribed_radius;
        rule(
            "inscribed_radius",
            r_i,
            r_i.is_finite() && r_i >= 0.0,
            "must be finite and >= 0",
        )?;
        let r = self.inflation_radius;
        rule(
            "inflation_radius",
            r,
            r.is_finite() && r >= r_i,
            "must be finite and >= inscribed_radius",
        )?;
        let k = self.cost_scaling_factor;
        rule(
            "cost_scaling_factor",
            k,
            k.is_finite() && k >= 0.0,
            "must be finite and >= 0",
        )?;
        Ok(self)
    }

    /// The inflation cost of a cell at `distance` metres from the nearest lethal cell, as Nav2
    /// computes it: [`LETHAL_OBSTACLE`] at 0, [`INSCRIBED_INFLATED_OBSTACLE`] up to the inscribed radius,
    /// `⌊252·exp(−k·(d − r_inscribed))⌋` up to the inflation radius (both inclusive), 0 beyond.
    ///
    /// ```
    /// use haunts_planning::InflationParams;
    /// let p = InflationParams::default();
    /// assert_eq!(p.cost_at(0.1), 253);
    /// assert_eq!(p.cost_at(0.32), (252.0 * (-3.0f64 * (0.32 - 0.22)).exp()) as u8);
    /// assert_eq!(p.cost_at(0.6), 0);
    /// ```
    pub fn cost_at(&self, distance: f64) -> u8 {
        if distance <= 0.0 {
            LETHAL_OBSTACLE
        } else if distance <= self.inscribed_radius {
            INSCRIBED_INFLATED_OBSTACLE
        } else if distance <= self.inflation_radius {
            let factor = (-self.cost_scaling_factor * (distance - self.inscribed_radius)).exp();
            // Truncation, as Nav2's `(unsigned char)` cast; the factor is in (0, 1].
            (f64::from(MAX_NON_OBSTACLE) * factor) as u8
        } else {
            0
        }
    }
}

/// Largest squared distance (cells²) tabulated; beyond it costs are computed cell by cell.
const TABLE_LIMIT: u64 = 1 << 22;

/// Inflation around lethal cells, as Nav2's inflation layer: every cell within the inflation
/// radius of a [`LETHAL_OBSTACLE`] cell gets [`InflationParams::cost_at`] its exact Euclidean distance
/// (cell centre to cell centre, from [`haunts_occupancy::distance_transform`]), combined
/// with the cost below by maximum. An [`NO_INFORMATION`] cell stays unknown unless it is within the
/// inscribed radius (Nav2's `inflate_unknown: false`).
///
/// # Complexity
/// O(cells): one exact distance transform and one sweep with a table indexed by the integer
/// squared distance.
///
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry};
/// use haunts_planning::{Costmap, InflationLayer, InflationParams, Layer, INSCRIBED_INFLATED_OBSTACLE, LETHAL_OBSTACLE};
/// let geometry = GridGeometry::new(0.1, nalgebra::Point2::origin(), 8, 1).unwrap();
/// let wall = Grid::from_fn(geometry, |c| if c.col == 0 { LETHAL_OBSTACLE } else { 0 });
/// let mut costmap = Costmap::new(wall);
/// let params = InflationParams::default(); // 0.22 m inscribed, 0.55 m inflated, k = 3
/// InflationLayer::new(params)?.apply(&mut costmap)?;
/// assert_eq!(costmap.cost(Cell::new(2, 0)), Some(INSCRIBED_INFLATED_OBSTACLE)); // 0.2 m away
/// assert_eq!(costmap.cost(Cell::new(3, 0)), Some(params.cost_at(0.3))); // 0.3 m away
/// assert_eq!(costmap.cost(Cell::new(6, 0)), Some(0)); // 0.6 m away
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InflationLayer {
    params: InflationParams,
}

impl InflationLayer {
    /// The layer with checked parameters.
    ///
    /// # Errors
    /// As [`InflationParams::check`].
    pub fn new(params: InflationParams) -> Result<Self> {
        Ok(Self {
            params: params.check()?,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &InflationParams {
        &self.params
    }
}

impl Layer for InflationLayer {
    /// Raises the cost of every cell near a lethal cell of `costs`.
    ///
    /// # Errors
    /// [`PlanningError::Occupancy`](crate::PlanningError::Occupancy) when the grid is too large
    /// for the distance transform (sides beyond ≈ 46 000 cells).
    fn apply(&self, costs: &mut Costmap) -> Result<()> {
        let geometry = *costs.geometry();
        let mask = costs.grid().map(|&c| c == LETHAL_OBSTACLE);
        if !mask.data().contains(&true) {
            return Ok(());
        }
        let field = distance_transform(&mask)?;
        let resolution = geometry.resolution();
        let cost_of = |d2: u32| self.params.cost_at(f64::from(d2).sqrt() * resolution);
        // Every squared distance within the inflation radius is below `reach` (`cost_of` is 0
        // for the few tabulated ones past the radius).
        let radius_cells = self.params.inflation_radius / resolution;
        let diagonal = (geometry.width() as u64 - 1).pow(2) + (geometry.height() as u64 - 1).pow(2);
        let reach = ((radius_cells * radius_cells).ceil() as u64 + 1).min(diagonal);
        let table: Vec<u8> = (0..=reach.min(TABLE_LIMIT) as u32).map(cost_of).collect();
        let squared = field.squared_cells();
        for_row_chunks(
            costs.grid_mut().data_mut(),
            geometry.width(),
            |first, chunk| {
                let squared = &squared[first..first + chunk.len()];
                for (cost, &d2) in chunk.iter_mut().zip(squared) {
                    let inflated = match table.get(d2 as usize) {
                        Some(&c) => c,
                        None if u64::from(d2) <= reach => cost_of(d2),
                        None => continue,
                    };
                    *cost = combine(*cost, inflated);
                }
            },
        );
        Ok(())
    }
}

/// Nav2's update rule: unknown cells take only inscribed or lethal costs, others the maximum.
fn combine(old: u8, inflated: u8) -> u8 {
    if old == NO_INFORMATION {
        if inflated >= INSCRIBED_INFLATED_OBSTACLE {
            inflated
        } else {
            old
        }
    } else {
        old.max(inflated)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PlanningError;

    #[test]
    fn parameters_are_checked() {
        for (params, name) in [
            (
                InflationParams::default().with_inscribed_radius(f64::NAN),
                "inscribed_radius",
            ),
            (
                InflationParams::default().with_inscribed_radius(-0.1),
                "inscribed_radius",
            ),
            (
                InflationParams::default().with_inflation_radius(0.1),
                "inflation_radius",
            ),
            (
                InflationParams::default().with_inflation_radius(f64::INFINITY),
                "inflation_radius",
            ),
            (
                InflationParams::default().with_cost_scaling_factor(f64::NAN),
                "cost_scaling_factor",
            ),
            (
                InflationParams::default().with_cost_scaling_factor(-1.0),
                "cost_scaling_factor",
            ),
        ] {
            match InflationLayer::new(params) {
                Err(PlanningError::InvalidParameter(haunts_core::InvalidParameter {
                    name: n,
                    ..
                })) => assert_eq!(n, name),
                other => panic!("{params:?} gave {other:?}"),
            }
        }
    }

    #[test]
    fn unknown_cells_take_only_obstacle_costs() {
        assert_eq!(combine(NO_INFORMATION, 200), NO_INFORMATION);
        assert_eq!(
            combine(NO_INFORMATION, INSCRIBED_INFLATED_OBSTACLE),
            INSCRIBED_INFLATED_OBSTACLE
        );
        assert_eq!(combine(10, 200), 200);
        assert_eq!(
            combine(LETHAL_OBSTACLE, INSCRIBED_INFLATED_OBSTACLE),
            LETHAL_OBSTACLE
        );
    }

    #[test]
    fn radius_boundaries_are_inclusive() {
        let p = InflationParams::default()
            .with_inscribed_radius(0.2)
            .with_inflation_radius(0.5)
            .with_cost_scaling_factor(0.0);
        assert_eq!(p.cost_at(0.2), INSCRIBED_INFLATED_OBSTACLE);
        assert_eq!(p.cost_at(0.5), MAX_NON_OBSTACLE);
        assert_eq!(p.cost_at(0.5000001), 0);
    }
}
