//! [`TaMap`]: the GP posterior mean of the grid-cell activity (seed 002, §4.3).

use haunts_occupancy::{CellState, Grid, GridGeometry, OccupancyGrid};
use haunts_similarity::GlobalParams;
use haunts_tracking::Trajectory;
use nalgebra::Point2;

use super::cells::{GridCellActivity, TrainingSet, grid_cell_activity};
use super::params::TaParams;
use super::regression::{GpModel, MeanCheck, fit_lengthscale};
use super::sessions::{Session, register_session};
use crate::{AffordanceError, DensityMap, Result};
use haunts_similarity::GlobalMatch;

/// A target-activity map: the posterior mean of a GP fitted to the grid-cell activity of
/// trajectories (seed 002, §4.3), on the cells of a map.
///
/// Units: targets per grid cell of side k (per session when sessions are pooled). As a
/// [`DensityMap`] it gives the posterior mean anywhere on its geometry and `None` off it
/// (where samples were not counted). The mean reverts to 0 (the prior) far from every sample
/// and may dip slightly below 0 next to busy areas.
///
/// # Example
/// ```
/// use haunts_affordance::ta::{TaMap, TaParams};
/// use haunts_affordance::DensityMap;
/// use haunts_occupancy::GridGeometry;
/// use haunts_tracking::Trajectory;
/// use nalgebra::Point2;
///
/// // Ten people cross a 9 m × 9 m square diagonally; the map is at 0.1 m.
/// let geometry = GridGeometry::new(0.1, Point2::origin(), 90, 90)?;
/// let people: Vec<Trajectory> = (0..10)
///     .map(|id| Trajectory {
///         id,
///         samples: (0..60).map(|k| (k as f64 * 0.4, Point2::new(0.3 + 0.14 * k as f64, 0.2 + 0.14 * k as f64))).collect(),
///     })
///     .collect();
/// let ta = TaMap::fit(&people, geometry, &TaParams::default())?;
/// assert_eq!(ta.training().len(), 600);
/// assert!(!ta.model().is_sparse());
/// let on_path = ta.density_at(Point2::new(4.5, 4.4)).unwrap();
/// let corner = ta.density_at(Point2::new(8.5, 0.5)).unwrap();
/// assert!(on_path > 8.0 && corner.abs() < 1.0, "{on_path} {corner}");
/// // The raster on the map's cells is the same posterior mean (fast grid mode, 1e-6 here).
/// let cell = geometry.world_to_cell(Point2::new(4.55, 4.45)).unwrap();
/// approx::assert_abs_diff_eq!(ta.raster()[cell], ta.density_at(Point2::new(4.55, 4.45)).unwrap(), epsilon = 1e-6);
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
///
/// # Saving and loading
/// With the `serde` feature the map is saved as what defines it: its parameters, geometry,
/// Algorithm 2 outcome (counts and training set) and the length scale used (fitted or
/// given). Loading checks them (valid parameters; a length scale equal to
/// [`TaParams::lengthscale`], or within the fitting bounds when it was fitted; a non-empty
/// training set of finite points with finite levels ≥ 0; counts on the coarse cells of the
/// geometry; at least one session), then refits the GP (no search: the stored length scale)
/// and recomputes the raster, so a loaded map gives the same posterior mean. Loading costs a
/// fit, O(n³) for the exact GP.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "TaMapFields"))]
pub struct TaMap {
    params: TaParams,
    geometry: GridGeometry,
    activity: GridCellActivity,
    lengthscale: f64,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    model: GpModel,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    mean: Grid<f64>,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    check: Option<MeanCheck>,
}

impl TaMap {
    /// The TA map of one session of world-frame trajectories (those that passed the dummy
    /// filter, [`haunts_tracking::track::dummy::filter_dummies`]) on the cells of `geometry` (the
    /// occupancy map's): Algorithm 2 with cells of `params.cell_size`, then GP regression.
    ///
    /// # Errors
    /// - [`AffordanceError::InvalidParameter`] for bad parameters.
    /// - [`AffordanceError::UnorderedTimes`] when a trajectory's times go back.
    /// - [`AffordanceError::NoUsableData`] when no sample lies on the map (no trajectory, all
    ///   empty, outside or NaN; those are skipped and counted otherwise, see
    ///   [`GridCellActivity::skipped`]).
    /// - [`AffordanceError::Gp`] when the regression fails (e.g. a factorisation that stays
    ///   singular with the jitter policy).
    ///
    /// # Complexity
    /// Algorithm 2 is O(samples). The exact GP (n ≤ `exact_limit`) fits in O(n³); the sparse
    /// GP in O(n m²) with m ≤ `inducing` grid inducing points. The raster (fast mode) costs
    /// p² mean predictions (O(n) or O(m²) each, p ≈ 2.5 · extent / ℓ + 8 Chebyshev nodes per
    /// axis) and O(cells · p) interpolation. seq_eth (8555 samples, 252 × 206 cells at 0.1 m):
    /// ≈ 0.1 s, see `BENCHMARKS.md`.
    pub fn fit(
        trajectories: &[Trajectory],
        geometry: GridGeometry,
        params: &TaParams,
    ) -> Result<Self> {
        Self::fit_sessions(&[trajectories], geometry, params)
    }

    /// The TA map of several sessions already in the frame of `geometry` (e.g. registered
    /// with [`register_session`]): the trajectories are pooled into one Algorithm 2 count and
    /// each level is divided by the number of sessions (seed 002, §4.4: `i_total / (n + 1)`
    /// for a reference and `n` sources).
    ///
    /// # Errors
    /// As [`TaMap::fit`].
    pub fn fit_sessions(
        sessions: &[&[Trajectory]],
        geometry: GridGeometry,
        params: &TaParams,
    ) -> Result<Self> {
        let params = params.check()?;
        let activity = grid_cell_activity(sessions, &geometry, params.cell_size)?;
        if activity.training.is_empty() {
            let given = sessions
                .iter()
                .flat_map(|s| s.iter())
                .map(|t| t.samples.len())
                .sum();
            return Err(AffordanceError::NoUsableData {
                what: "trajectory samples",
                given,
                non_finite: activity.skipped.non_finite,
                outside: activity.skipped.outside,
            });
        }
        Self::from_activity(activity, geometry, params)
    }

    /// The TA map of a reference session and source sessions: each source's map is registered
    /// onto the reference map (global registration, [`register_session`]), its trajectories
    /// are moved into the reference frame, and all are pooled as in
    /// [`TaMap::fit_sessions`] on the reference map's geometry. Returns the map and each
    /// source's registration.
    ///
    /// # Errors
    /// [`AffordanceError::SessionRegistration`] naming the first source that cannot be
    /// registered; otherwise as [`TaMap::fit`].
    pub fn fit_registered(
        reference: &Session,
        sources: &[Session],
        registration: &GlobalParams,
        params: &TaParams,
    ) -> Result<(Self, Vec<GlobalMatch>)> {
        let mut registered = Vec::with_capacity(sources.len());
        for (i, source) in sources.iter().enumerate() {
            registered.push(
                register_session(&reference.map, source, registration).map_err(|e| match e {
                    AffordanceError::Similarity(source) => AffordanceError::SessionRegistration {
                        session: i,
                        source: Box::new(source),
                    },
                    other => other,
                })?,
            );
        }
        let mut sessions: Vec<&[Trajectory]> = vec![&reference.trajectories];
        sessions.extend(registered.iter().map(|r| r.trajectories.as_slice()));
        let map = Self::fit_sessions(&sessions, *reference.map.geometry(), params)?;
        Ok((
            map,
            registered.into_iter().map(|r| r.registration).collect(),
        ))
    }

    /// Regression on a computed Algorithm 2 outcome (non-empty training set).
    fn from_activity(
        activity: GridCellActivity,
        geometry: GridGeometry,
        params: TaParams,
    ) -> Result<Self> {
        let lengthscale = match params.fit_lengthscale {
            Some(bounds) => fit_lengthscale(
                &activity.training.flat_points(),
                &activity.training.activity,
                params.lengthscale,
                bounds,
                &params.regression,
            )?,
            None => params.lengthscale,
        };
        Self::build(activity, geometry, params, lengthscale)
    }

    /// The GP with length scale `lengthscale` on the training set, and its raster.
    fn build(
        activity: GridCellActivity,
        geometry: GridGeometry,
        params: TaParams,
        lengthscale: f64,
    ) -> Result<Self> {
        let x = activity.training.flat_points();
        let model = GpModel::fit(
            &x,
            &activity.training.activity,
            lengthscale,
            &params.regression,
        )?;
        let (mean, check) =
            model.mean_raster(&geometry, lengthscale, params.regression.grid_mode)?;
        Ok(Self {
            params,
            geometry,
            activity,
            lengthscale,
            model,
            mean,
            check,
        })
    }

    /// The posterior mean on every cell of the map: the TA map.
    pub fn raster(&self) -> &Grid<f64> {
        &self.mean
    }

    /// The TA map on the free cells of `map` (seed 002 §4.3 colours only free space): the
    /// posterior mean there, NaN on occupied and unknown cells.
    ///
    /// # Errors
    /// [`AffordanceError::GeometryMismatch`] when `map` does not lie on the TA map's cells.
    pub fn on_free_cells(&self, map: &OccupancyGrid) -> Result<Grid<f64>> {
        if !self
            .geometry
            .same_cells(map.geometry(), GridGeometry::SAME_CELLS_TOLERANCE)
        {
            return Err(AffordanceError::GeometryMismatch {
                what: "occupancy map",
                expected: Box::new(self.geometry),
                found: Box::new(*map.geometry()),
            });
        }
        let states = map.states();
        let data = self
            .mean
            .data()
            .iter()
            .zip(states.data())
            .map(|(&m, s)| if *s == CellState::Free { m } else { f64::NAN })
            .collect();
        Ok(Grid::from_vec(self.geometry, data)?)
    }

    /// The geometry of the map's cells.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The training set (samples and their levels of activity).
    pub fn training(&self) -> &TrainingSet {
        &self.activity.training
    }

    /// Algorithm 2's outcome: counts per coarse cell, sessions, skipped samples.
    pub fn cells(&self) -> &GridCellActivity {
        &self.activity
    }

    /// The length scale used, metres (fitted when asked).
    pub fn lengthscale(&self) -> f64 {
        self.lengthscale
    }

    /// The fitted GP.
    pub fn model(&self) -> &GpModel {
        &self.model
    }

    /// The parameters (checked).
    pub fn params(&self) -> &TaParams {
        &self.params
    }

    /// The measured error of the fast raster against exact predictions at a sample of
    /// cells, and the nodes it used (`None` in the exact mode).
    pub fn grid_check(&self) -> Option<MeanCheck> {
        self.check
    }
}

impl DensityMap for TaMap {
    /// The posterior mean at `p`, or `None` off the map (or for a non-finite `p`).
    fn density_at(&self, p: Point2<f64>) -> Option<f64> {
        self.geometry.world_to_cell(p)?;
        self.model.predict(&[p]).ok()?.mean.first().copied()
    }

    /// The posterior mean on the cells of `geometry` by the model's grid prediction (the
    /// stored raster when `geometry` is the map's); NaN off the map's extent, and everywhere
    /// if the grid prediction fails.
    fn rasterise(&self, geometry: &GridGeometry) -> Grid<f64> {
        if self
            .geometry
            .same_cells(geometry, GridGeometry::SAME_CELLS_TOLERANCE)
        {
            return self.mean.clone();
        }
        let mode = self.params.regression.grid_mode;
        match self.model.mean_raster(geometry, self.lengthscale, mode) {
            Ok((mean, _)) => Grid::from_fn(*geometry, |cell| {
                let on_map = self
                    .geometry
                    .world_to_cell(geometry.cell_center(cell))
                    .is_some();
                match mean.get(cell) {
                    Some(v) if on_map => *v,
                    _ => f64::NAN,
                }
            }),
            Err(_) => Grid::filled(*geometry, f64::NAN),
        }
    }
}

/// The fields of a [`TaMap`] as deserialised: what defines it, before it is checked and the GP
/// refitted.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct TaMapFields {
    params: TaParams,
    geometry: GridGeometry,
    activity: GridCellActivity,
    lengthscale: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<TaMapFields> for TaMap {
    type Error = AffordanceError;
    fn try_from(f: TaMapFields) -> Result<Self> {
        let bad = |problem: String| AffordanceError::InvalidModel {
            model: "TA map",
            problem,
        };
        let params = f.params.check()?;
        let l = f.lengthscale;
        haunts_core::positive("lengthscale", l)?;
        match params.fit_lengthscale {
            Some((low, high)) if !(low..=high).contains(&l) => {
                return Err(bad(format!(
                    "fitted length scale {l} outside its bounds [{low}, {high}]"
                )));
            }
            None if l != params.lengthscale => {
                return Err(bad(format!(
                    "length scale {l} differs from the parameters' {} (it is not fitted)",
                    params.lengthscale
                )));
            }
            _ => {}
        }
        let activity = f.activity;
        let training = &activity.training;
        if training.is_empty() {
            return Err(bad("an empty training set".into()));
        }
        if training.points.len() != training.activity.len() {
            return Err(bad(format!(
                "{} training points for {} levels of activity",
                training.points.len(),
                training.activity.len()
            )));
        }
        if let Some(i) = training
            .points
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(bad(format!("training point {i} is not finite")));
        }
        if let Some(i) = training
            .activity
            .iter()
            .position(|a| !(a.is_finite() && *a >= 0.0))
        {
            return Err(bad(format!(
                "level of activity {i} is {} (must be finite and >= 0)",
                training.activity[i]
            )));
        }
        if activity.sessions == 0 {
            return Err(bad(
                "0 sessions (the levels are divided by their number)".into()
            ));
        }
        let coarse = super::cells::coarse_geometry(&f.geometry, params.cell_size)?;
        crate::density::check_geometry("activity counts", &coarse, activity.counts.geometry())?;
        Self::build(activity, f.geometry, params, l)
    }
}
