//! Seed 002's grid-cell algorithm (Algorithm 2): distinct targets per coarse cell, assigned
//! to every trajectory sample: the training set of the TA map.

use haunts_occupancy::{Grid, GridGeometry};
use haunts_tracking::Trajectory;
use nalgebra::Point2;

use crate::{AffordanceError, Result};

/// The samples the GP learns from: positions and their level of activity.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TrainingSet {
    /// World positions of the trajectory samples kept, in input order (sessions, then
    /// trajectories, then samples).
    pub points: Vec<Point2<f64>>,
    /// The level of activity of each point: the distinct targets of its cell, divided by the
    /// number of sessions.
    pub activity: Vec<f64>,
}

impl TrainingSet {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.points.len()
    }
    /// Whether there is no sample.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
    /// The points as a flat row-major array `[x0, y0, x1, y1, …]` (the gp crate's layout).
    pub fn flat_points(&self) -> Vec<f64> {
        self.points.iter().flat_map(|p| [p.x, p.y]).collect()
    }
}

/// Samples left out of a count, by reason.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Skipped {
    /// Samples with a NaN or infinite time or coordinate.
    pub non_finite: usize,
    /// Samples outside the map.
    pub outside: usize,
    /// Trajectories without any sample (they count as no target).
    pub empty_trajectories: usize,
}

/// The outcome of Algorithm 2.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct GridCellActivity {
    /// Distinct targets per coarse cell (side k, anchored at the map origin; the last row
    /// and column may reach past the map), all sessions pooled.
    pub counts: Grid<u32>,
    /// Number of sessions pooled (the divisor of the levels).
    pub sessions: usize,
    /// The training set.
    pub training: TrainingSet,
    /// What was left out.
    pub skipped: Skipped,
}

impl GridCellActivity {
    /// The level of activity of each coarse cell: its count divided by the number of
    /// sessions.
    pub fn levels(&self) -> Grid<f64> {
        let n = self.sessions.max(1) as f64;
        self.counts.map(|&c| f64::from(c) / n)
    }
}

/// Cells of side `k` covering `geometry` from its origin: `⌈extent / k⌉` per axis (with a
/// tolerance of 1e-9 cells so that an extent of exactly n·k gives n cells).
pub(super) fn coarse_geometry(geometry: &GridGeometry, k: f64) -> Result<GridGeometry> {
    let r = geometry.resolution();
    let n = |cells: usize| ((cells as f64 * r / k) - 1e-9).ceil().max(1.0) as usize;
    Ok(GridGeometry::new(
        k,
        geometry.origin(),
        n(geometry.width()),
        n(geometry.height()),
    )?)
}

/// Seed 002's Algorithm 2 (grid-cell algorithm) over one or more sessions already in the
/// frame of `geometry`: the map is divided into cells of side `cell_size` (k) from its
/// origin; each cell's count is the number of distinct trajectories (targets) with at least
/// one sample in it (each `Trajectory` is one target; sessions are pooled, so the same id in
/// two sessions is two targets); each sample's level of activity is its cell's count divided
/// by the number of sessions (§4.4's `i_total / (n + 1)`).
///
/// Samples with a NaN or infinite time or coordinate, and samples outside `geometry`, are
/// skipped and counted; so are empty trajectories.
///
/// # Errors
/// - [`AffordanceError::InvalidParameter`] for a `cell_size` that is not finite and > 0.
/// - [`AffordanceError::UnorderedTimes`] when a trajectory's finite times go back.
/// - Occupancy errors when the coarse grid cannot be built (too many cells).
///
/// # Complexity
/// O(samples + coarse cells).
///
/// ```
/// use haunts_affordance::ta::grid_cell_activity;
/// use haunts_occupancy::GridGeometry;
/// use haunts_tracking::Trajectory;
/// use nalgebra::Point2;
///
/// let g = GridGeometry::new(0.5, Point2::origin(), 12, 6)?; // 6 m × 3 m: two 3 m cells
/// let t = |id, pts: &[(f64, f64)]| Trajectory {
///     id,
///     samples: pts.iter().enumerate().map(|(i, &(x, y))| (i as f64, Point2::new(x, y))).collect(),
/// };
/// let people = [
///     t(1, &[(0.5, 1.0), (1.0, 1.0), (4.0, 1.0)]), // both cells
///     t(2, &[(2.0, 2.0), (2.5, 2.5)]),             // left cell only, twice
///     t(3, &[(9.0, 1.0), (f64::NAN, 1.0)]),        // off the map, and a NaN
/// ];
/// let a = grid_cell_activity(&[&people[..]], &g, 3.0)?;
/// assert_eq!(a.counts.data(), &[2, 1]);
/// assert_eq!(a.training.activity, vec![2.0, 2.0, 1.0, 2.0, 2.0]);
/// assert_eq!((a.skipped.outside, a.skipped.non_finite), (1, 1));
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
pub fn grid_cell_activity(
    sessions: &[&[Trajectory]],
    geometry: &GridGeometry,
    cell_size: f64,
) -> Result<GridCellActivity> {
    haunts_core::positive("cell_size", cell_size)?;
    let coarse = coarse_geometry(geometry, cell_size)?;
    let (cw, ch) = (coarse.width(), coarse.height());
    let mut counts = vec![0u32; coarse.len()];
    // The last target (1-based) counted in each cell, so a target counts once per cell.
    let mut stamp = vec![0usize; coarse.len()];
    let mut skipped = Skipped::default();
    // Kept samples with their coarse cell index, assigned once all counts are known.
    let mut kept: Vec<(Point2<f64>, usize)> = Vec::new();
    let origin = geometry.origin();
    let mut target = 0usize;
    for (session, trajectories) in sessions.iter().enumerate() {
        for trajectory in trajectories.iter() {
            target += 1;
            if trajectory.samples.is_empty() {
                skipped.empty_trajectories += 1;
            }
            let mut last_time = f64::NEG_INFINITY;
            for (i, &(t, p)) in trajectory.samples.iter().enumerate() {
                if !(t.is_finite() && p.x.is_finite() && p.y.is_finite()) {
                    skipped.non_finite += 1;
                    continue;
                }
                if t < last_time {
                    return Err(AffordanceError::UnorderedTimes {
                        session,
                        id: trajectory.id,
                        sample: i,
                    });
                }
                last_time = t;
                if geometry.world_to_cell(p).is_none() {
                    skipped.outside += 1;
                    continue;
                }
                // Inside the map: the coarse index is within range up to rounding; clamp it.
                let col = (((p.x - origin.x) / cell_size).floor().max(0.0) as usize).min(cw - 1);
                let row = (((p.y - origin.y) / cell_size).floor().max(0.0) as usize).min(ch - 1);
                let index = row * cw + col;
                if stamp[index] != target {
                    stamp[index] = target;
                    counts[index] += 1;
                }
                kept.push((p, index));
            }
        }
    }
    let n = sessions.len().max(1) as f64;
    let training = TrainingSet {
        points: kept.iter().map(|(p, _)| *p).collect(),
        activity: kept
            .iter()
            .map(|&(_, i)| f64::from(counts[i]) / n)
            .collect(),
    };
    Ok(GridCellActivity {
        counts: Grid::from_vec(coarse, counts)?,
        sessions: sessions.len(),
        training,
        skipped,
    })
}
