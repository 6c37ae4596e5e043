//! Seed 002's target-activity (TA) map: where people move, learnt by Gaussian-process
//! regression on a grid-cell count of trajectories, with its confidence map and the
//! registration of several sessions onto a reference map.
//!
//! The pipeline (seed 002, §4.3–4.4):
//!
//! 1. **Grid cells** ([`grid_cell_activity`], Algorithm 2): the map is divided into square
//!    cells of side `k` (3 m) anchored at its origin; each cell's level of activity is the
//!    number of distinct trajectories (targets) with a sample in it, and every trajectory
//!    sample gets its cell's level. The samples with their levels are the training set. With
//!    several sessions the levels are divided by the number of sessions (§4.4: `i_total /
//!    (n + 1)`).
//! 2. **Regression** ([`TaMap::fit`]): zero-mean GP with the RBF kernel `σ² exp(−r²/2ℓ²)`
//!    (σ² = 1, ℓ = 2 m by default, ℓ optionally fitted by maximum likelihood), observation
//!    noise σn² = 1 (GPy's default, the framework the seed used). Up to
//!    [`RegressionParams::exact_limit`] samples the GP is exact; above it a VFE sparse GP on
//!    a grid of inducing points (spacing ℓ/2 where there are samples) takes all the samples
//!    (no downsampling). The TA map is the
//!    posterior mean on the cells of a [`GridGeometry`], shown on free cells
//!    ([`TaMap::on_free_cells`]).
//! 3. **Confidence** ([`ConfidenceMap::fit`]): the same GP on the robot's positions alone with
//!    the length scale set to the sensor range; the confidence is `1 − posterior variance /
//!    prior variance`, in `[0, 1]`.
//! 4. **Sessions** ([`register_session`], [`TaMap::fit_sessions`], [`TaMap::fit_registered`]):
//!    each session's map is registered onto the reference map by the similarity crate's
//!    global registration (features, RANSAC + Umeyama, ICP), its trajectories are moved into
//!    the reference frame (seed Eq. 12), and the pooled trajectories go through steps 1–2 with
//!    the activity normalised by the number of sessions.
//!
//! ```
//! use haunts_affordance::ta::{ConfidenceMap, RegressionParams, TaMap, TaParams};
//! use haunts_affordance::DensityMap;
//! use haunts_occupancy::GridGeometry;
//! use haunts_tracking::Trajectory;
//! use nalgebra::Point2;
//!
//! // A 12 m × 9 m hall at 0.25 m. Twelve people walk along y = 1.5 (through the cells of the
//! // bottom row), one along y = 7.5.
//! let geometry = GridGeometry::new(0.25, Point2::origin(), 48, 36)?;
//! let walk = |id: u64, y: f64| Trajectory {
//!     id,
//!     samples: (0..=40).map(|k| (k as f64 * 0.3, Point2::new(0.25 + k as f64 * 0.28, y))).collect(),
//! };
//! let mut people: Vec<Trajectory> = (0..12).map(|id| walk(id, 1.5)).collect();
//! people.push(walk(99, 7.5));
//! let ta = TaMap::fit(&people, geometry, &TaParams::default())?;
//! // Algorithm 2: 12 targets in each bottom cell the corridor crosses, 1 in the top row.
//! assert_eq!(ta.training().activity[0], 12.0);
//! let busy = ta.density_at(Point2::new(6.0, 1.5)).unwrap();
//! let quiet = ta.density_at(Point2::new(6.0, 7.5)).unwrap();
//! assert!(busy > 10.0 && quiet < 2.0, "{busy} {quiet}");
//! assert_eq!(ta.density_at(Point2::new(13.0, 1.5)), None); // off the map
//!
//! // The robot drove along the bottom wall; its sensor sees 5 m.
//! let robot: Vec<Point2<f64>> = (0..100).map(|k| Point2::new(k as f64 * 0.12, 0.5)).collect();
//! let confidence = ConfidenceMap::fit(&robot, geometry, 5.0, &RegressionParams::default())?;
//! assert!(confidence.confidence_at(Point2::new(6.0, 0.5)).unwrap() > 0.95);
//! assert!(confidence.confidence_at(Point2::new(6.0, 8.9)).unwrap() < 0.7);
//! # Ok::<(), haunts_affordance::AffordanceError>(())
//! ```

mod cells;
mod confidence;
mod map;
mod params;
mod regression;
mod sessions;

pub use cells::{GridCellActivity, Skipped, TrainingSet, grid_cell_activity};
pub use confidence::ConfidenceMap;
pub use map::TaMap;
pub use params::{RegressionParams, TaParams};
pub use regression::{GpModel, MeanCheck};
pub use sessions::{RegisteredSession, Session, register_session};

use haunts_gp::Grid2;
use haunts_occupancy::{Cell, GridGeometry};

/// The cell centres of `geometry` as a gp-crate grid (same order: column fastest, row 0 at
/// the bottom).
pub(crate) fn grid2(geometry: &GridGeometry) -> Grid2 {
    let c = geometry.cell_center(Cell::new(0, 0));
    let r = geometry.resolution();
    Grid2 {
        origin: [c.x, c.y],
        step: [r, r],
        shape: [geometry.width(), geometry.height()],
    }
}
