//! [`ConfidenceMap`]: how much the TA map can be trusted where, from the robot's positions
//! alone (seed 002, §5.2).

use haunts_gp::GridCheck;
use haunts_occupancy::{Grid, GridGeometry};
use nalgebra::Point2;

use super::params::RegressionParams;
use super::regression::GpModel;
use crate::{AffordanceError, Result};

/// The confidence map of seed 002 (§5.2): a GP on the robot's trajectory "without applying a
/// grid cell algorithm", with the RBF length scale set to the sensor's tracking range. Only
/// its posterior variance matters (it does not depend on the targets); the confidence is
/// `1 − posterior variance / prior variance`, in `[0, 1]`: near 1 where the robot spent time
/// within a length scale, 0 far from every position.
///
/// # Example
/// ```
/// use haunts_affordance::ta::{ConfidenceMap, RegressionParams};
/// use haunts_occupancy::GridGeometry;
/// use nalgebra::Point2;
///
/// let geometry = GridGeometry::new(0.5, Point2::new(-20.0, -20.0), 80, 80)?;
/// // The robot drove 20 m along the x axis (one pose every 10 cm); its tracker sees 10 m.
/// let poses: Vec<Point2<f64>> = (0..=200).map(|k| Point2::new(-10.0 + 0.1 * k as f64, 0.0)).collect();
/// let c = ConfidenceMap::fit(&poses, geometry, 10.0, &RegressionParams::default())?;
/// assert!(c.confidence_at(Point2::new(0.0, 0.0)).unwrap() > 0.98);
/// assert!(c.confidence_at(Point2::new(-19.0, 19.5)).unwrap() < 0.5);
/// assert!(c.raster().data().iter().all(|v| (0.0..=1.0).contains(v)));
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
///
/// # Saving and loading
/// With the `serde` feature the map is saved as what defines it: its geometry, the sensor
/// range, the (checked) regression parameters, the finite robot positions used and the
/// number skipped. Loading checks them as [`ConfidenceMap::fit`] does (and that there is at
/// least one position, each finite), then refits the GP and recomputes the raster, so a
/// loaded map gives the same confidence. Loading costs a fit, O(n³) for the exact GP.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "ConfidenceMapFields"))]
pub struct ConfidenceMap {
    geometry: GridGeometry,
    sensor_range: f64,
    params: RegressionParams,
    positions: Vec<Point2<f64>>,
    skipped: usize,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    model: GpModel,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    raster: Grid<f64>,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    check: Option<GridCheck>,
}

impl ConfidenceMap {
    /// The confidence on the cells of `geometry` given the robot's world positions and the
    /// range of its people tracker (the length scale, metres). Positions off the map count
    /// (the robot sees into the map from there); NaN or infinite positions are skipped and
    /// counted ([`ConfidenceMap::skipped`]). Exact GP up to `params.exact_limit` positions,
    /// the sparse GP on all of them above.
    ///
    /// # Errors
    /// - [`AffordanceError::InvalidParameter`] for a `sensor_range` not finite and > 0, or
    ///   bad `params`.
    /// - [`AffordanceError::NoUsableData`] when no position is finite.
    /// - [`AffordanceError::Gp`] when the regression fails.
    ///
    /// # Complexity
    /// As [`TaMap::fit`](super::TaMap::fit) with n = the number of positions.
    pub fn fit(
        robot_positions: &[Point2<f64>],
        geometry: GridGeometry,
        sensor_range: f64,
        params: &RegressionParams,
    ) -> Result<Self> {
        haunts_core::positive("sensor_range", sensor_range)?;
        let params = params.check()?;
        let positions: Vec<Point2<f64>> = robot_positions
            .iter()
            .copied()
            .filter(|p| p.x.is_finite() && p.y.is_finite())
            .collect();
        let skipped = robot_positions.len() - positions.len();
        if positions.is_empty() {
            return Err(AffordanceError::NoUsableData {
                what: "robot positions",
                given: robot_positions.len(),
                non_finite: skipped,
                outside: 0,
            });
        }
        Self::build(geometry, sensor_range, params, positions, skipped)
    }

    /// The GP on the (finite, non-empty) `positions` and its raster; `params` checked.
    fn build(
        geometry: GridGeometry,
        sensor_range: f64,
        params: RegressionParams,
        positions: Vec<Point2<f64>>,
        skipped: usize,
    ) -> Result<Self> {
        let x: Vec<f64> = positions.iter().flat_map(|p| [p.x, p.y]).collect();
        let model = GpModel::fit(&x, &vec![0.0; positions.len()], sensor_range, &params)?;
        let (_, variance, check) = model.rasters(&geometry, &params)?;
        let raster = variance.map(|v| confidence(*v, params.variance));
        Ok(Self {
            geometry,
            sensor_range,
            params,
            positions,
            skipped,
            model,
            raster,
            check,
        })
    }

    /// The confidence on every cell, in `[0, 1]`.
    pub fn raster(&self) -> &Grid<f64> {
        &self.raster
    }

    /// The confidence at world point `p`, or `None` off the map (or for a non-finite `p`).
    pub fn confidence_at(&self, p: Point2<f64>) -> Option<f64> {
        self.geometry.world_to_cell(p)?;
        let v = self.model.predict(&[p]).ok()?.variance.first().copied()?;
        Some(confidence(v, self.params.variance))
    }

    /// The geometry of the map's cells.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The sensor range used as the length scale, metres.
    pub fn sensor_range(&self) -> f64 {
        self.sensor_range
    }

    /// Robot positions used.
    pub fn observers(&self) -> usize {
        self.positions.len()
    }

    /// The robot positions used (the finite ones given, in order).
    pub fn positions(&self) -> &[Point2<f64>] {
        &self.positions
    }

    /// The regression parameters (checked).
    pub fn params(&self) -> &RegressionParams {
        &self.params
    }

    /// Robot positions skipped because a coordinate was NaN or infinite.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// The fitted GP.
    pub fn model(&self) -> &GpModel {
        &self.model
    }

    /// The measured error of the fast grid mode (`None` in the exact mode).
    pub fn grid_check(&self) -> Option<GridCheck> {
        self.check
    }
}

/// `1 − variance / prior`, clamped to `[0, 1]` (NaN stays NaN).
fn confidence(variance: f64, prior: f64) -> f64 {
    (1.0 - variance / prior).clamp(0.0, 1.0)
}

/// The fields of a [`ConfidenceMap`] as deserialised: what defines it, before it is checked
/// and the GP refitted.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct ConfidenceMapFields {
    geometry: GridGeometry,
    sensor_range: f64,
    params: RegressionParams,
    positions: Vec<Point2<f64>>,
    skipped: usize,
}

#[cfg(feature = "serde")]
impl TryFrom<ConfidenceMapFields> for ConfidenceMap {
    type Error = AffordanceError;
    fn try_from(f: ConfidenceMapFields) -> Result<Self> {
        let bad = |problem: String| AffordanceError::InvalidModel {
            model: "confidence map",
            problem,
        };
        haunts_core::positive("sensor_range", f.sensor_range)?;
        let params = f.params.check()?;
        if f.positions.is_empty() {
            return Err(bad("no robot position".into()));
        }
        if let Some(i) = f
            .positions
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(bad(format!("robot position {i} is not finite")));
        }
        Self::build(f.geometry, f.sensor_range, params, f.positions, f.skipped)
    }
}
