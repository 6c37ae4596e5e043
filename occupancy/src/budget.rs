//! The budgets: the most cells a grid may have, and the most elementary operations a job
//! sized by data may take, both checked before anything is allocated or computed.
//!
//! # Cells
//!
//! Grids here are sized by data (the bounding box of poses, detections or map files), so one
//! far outlier or a tiny resolution could ask for billions of cells. Every
//! [`GridGeometry`](crate::GridGeometry) is checked against the budget when it is made
//! (`new`, `bounding`, `with_resolution`, deserialisation), so every grid, map, costmap or
//! raster laid on one is too; a geometry over the budget is
//! [`OccupancyError::GridTooLarge`], naming the extent asked for, the area it spans and the
//! resolution.
//!
//! The default is [`DEFAULT_MAX_CELLS`] = 2²⁸ cells (268 435 456): 1 GiB for one grid of
//! `f32`, 2 GiB of `f64`; an `OccupancyMapper` keeps 13 bytes per cell. It is one setting for
//! the whole process (like a thread pool), raised or lowered with [`set_max_cells`] up to
//! [`LIMIT_MAX_CELLS`] (`u32::MAX`, the widest index the algorithms here store).
//!
//! ```
//! use haunts_occupancy::{GridGeometry, OccupancyError, budget};
//! use nalgebra::Point2;
//! // One point a thousand kilometres away at 5 cm: 2·10⁷ × 41 cells, refused before allocating.
//! let far = [Point2::new(0.0, 0.0), Point2::new(1.0e6, 1.0)];
//! let err = GridGeometry::bounding(far, 0.05, 0.5).unwrap_err();
//! assert!(matches!(err, OccupancyError::GridTooLarge { .. }));
//! assert_eq!(budget::max_cells(), budget::DEFAULT_MAX_CELLS);
//! ```
//!
//! # Work
//!
//! A grid within the cell budget can still be the factor of a product that never returns:
//! hypertime scoring evaluates every cluster at every cell for every time step, a GP raster
//! costs cells × training points, a similarity matrix maps² × cells. Each such job states
//! its factors to [`check_work`] before it starts; a product over the work budget is
//! [`OccupancyError::WorkTooLarge`], naming the job and every factor (so the far outlier or the
//! tiny step that caused it shows), instead of hours of computing. A unit of work is about a
//! nanosecond of one core: one elementary operation of the job's inner loop (a multiply–add,
//! a look-up, a kernel value though it costs a few), times a cost factor where the operation is
//! much slower (a hypertime
//! density of one component at one cell: 64 units, measured at 50–70 ns).
//!
//! The default is [`DEFAULT_MAX_WORK`] = 2³⁶ ≈ 6.9·10¹⁰ units, about a minute of one core,
//! and 17 times the largest such job of the repository's real and simulated workloads (the
//! real people data's hypertime: the hourly strip, 6.4·10⁷ densities = 4.1·10⁹ units, its
//! scoring 3.7·10⁹; the ETH `seq_eth` confidence map's raster, 2.1·10⁸; the main job's
//! largest, 1.1·10⁸; `BENCHMARKS.md`, "Hostile inputs"). [`set_max_work`] raises or lowers it
//! for the whole process. Work bounded by parameters rather than by a product of data (a GP
//! fit: at most `exact_limit` samples, or linear in the samples) and work laid on one grid (a
//! costmap layer, an EDT, a planner: O(cells), bounded by the cell budget; a ray: clipped to
//! its grid) is not checked.
//!
//! ```
//! use haunts_occupancy::{OccupancyError, budget};
//! // Scoring every cell of a 4·10⁵ × 128 grid (one detection 100 km away) at 1440 steps.
//! let err = budget::check_work(
//!     "hypertime scoring",
//!     &[("time steps", 1440.0), ("cells", 4.0e5 * 128.0), ("components", 11.0), ("units per density", 64.0)],
//! )
//! .unwrap_err();
//! assert!(matches!(err, OccupancyError::WorkTooLarge { .. }));
//! assert!(err.to_string().contains("51200000 cells"));
//! assert!(budget::check_work("a day", &[("steps", 1440.0), ("cells", 6400.0)]).is_ok());
//! ```

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use nalgebra::Point2;

use crate::{OccupancyError, Result};

/// The default cell budget: 2²⁸ cells (1 GiB of `f32`).
pub const DEFAULT_MAX_CELLS: usize = 1 << 28;

/// The largest budget [`set_max_cells`] accepts: `u32::MAX` cells, the widest index the
/// algorithms here store.
pub const LIMIT_MAX_CELLS: usize = u32::MAX as usize;

static MAX_CELLS: AtomicUsize = AtomicUsize::new(DEFAULT_MAX_CELLS);

/// The cell budget in force: the most cells a [`GridGeometry`](crate::GridGeometry) may have.
pub fn max_cells() -> usize {
    MAX_CELLS.load(Ordering::Relaxed)
}

/// Sets the cell budget of the process and returns the previous one. Geometries already made
/// are not checked again.
///
/// # Errors
/// [`OccupancyError::InvalidParameter`] for 0 or more than [`LIMIT_MAX_CELLS`].
///
/// ```
/// use haunts_occupancy::budget;
/// assert!(budget::set_max_cells(0).is_err());
/// assert!(budget::set_max_cells(usize::MAX).is_err());
/// ```
pub fn set_max_cells(cells: usize) -> Result<usize> {
    if cells == 0 || cells > LIMIT_MAX_CELLS {
        return Err(OccupancyError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "max_cells",
                value: cells as f64,
                rule: "must be in 1..=u32::MAX",
            },
        ));
    }
    Ok(MAX_CELLS.swap(cells, Ordering::Relaxed))
}

/// Checks an extent of `width × height` cells of side `resolution` over the area from `from`
/// to `to` against the budget, before any integer conversion: the sides come back as `usize`
/// only when they are finite, whole and within the budget (a side of 0 is left to the caller).
///
/// # Errors
/// [`OccupancyError::GridTooLarge`] when `width · height` exceeds [`max_cells`] or a side is
/// not finite.
pub fn check_extent(
    width: f64,
    height: f64,
    resolution: f64,
    from: Point2<f64>,
    to: Point2<f64>,
) -> Result<(usize, usize)> {
    let budget = max_cells();
    // The product in f64 is exact enough: the budget is far below 2^53.
    let cap = budget as f64;
    if !(width.is_finite()
        && height.is_finite()
        && width <= cap
        && height <= cap
        && width * height <= cap)
    {
        return Err(OccupancyError::GridTooLarge {
            width,
            height,
            resolution,
            from: [from.x, from.y],
            to: [to.x, to.y],
            budget,
        });
    }
    // Both sides are now at most the budget (or one is 0), so the casts are exact.
    Ok((width.max(0.0) as usize, height.max(0.0) as usize))
}

/// The default work budget: 2³⁶ ≈ 6.9·10¹⁰ units of about a nanosecond of one core (see the
/// module's docs).
pub const DEFAULT_MAX_WORK: u64 = 1 << 36;

static MAX_WORK: AtomicU64 = AtomicU64::new(DEFAULT_MAX_WORK);

/// The work budget in force: the most elementary operations a job sized by data may take.
pub fn max_work() -> u64 {
    MAX_WORK.load(Ordering::Relaxed)
}

/// Sets the work budget of the process and returns the previous one.
///
/// # Errors
/// [`OccupancyError::InvalidParameter`] for 0.
///
/// ```
/// use haunts_occupancy::budget;
/// assert!(budget::set_max_work(0).is_err());
/// ```
pub fn set_max_work(work: u64) -> Result<u64> {
    if work == 0 {
        return Err(OccupancyError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "max_work",
                value: 0.0,
                rule: "must be at least 1",
            },
        ));
    }
    Ok(MAX_WORK.swap(work, Ordering::Relaxed))
}

/// Checks the work of the job `what`, the product of `factors` (each a name and a count),
/// against the work budget before the job starts. The product is taken in `f64`, so factors
/// that would overflow any integer are refused, not wrapped; the product is returned.
///
/// # Errors
/// [`OccupancyError::WorkTooLarge`] when the product exceeds [`max_work`] or is not finite
/// (a NaN or infinite factor).
pub fn check_work(what: &'static str, factors: &[(&'static str, f64)]) -> Result<f64> {
    let work: f64 = factors.iter().map(|(_, n)| n.max(0.0)).product();
    let budget = max_work();
    let finite = factors.iter().all(|(_, n)| !n.is_nan()) && work.is_finite();
    if finite && work <= budget as f64 {
        Ok(work)
    } else {
        Err(OccupancyError::WorkTooLarge {
            what,
            factors: factors.to_vec(),
            work,
            budget,
        })
    }
}

/// `12 cells × 3 steps`: the factors of a [`OccupancyError::WorkTooLarge`].
pub(crate) fn factors(factors: &[(&'static str, f64)]) -> String {
    factors
        .iter()
        .map(|(name, n)| format!("{} {name}", count(*n)))
        .collect::<Vec<_>>()
        .join(" × ")
}

/// Formats a cell count that may not fit an integer: whole below 10¹⁵, scientific above.
pub(crate) fn count(n: f64) -> String {
    if n.abs() < 1e15 {
        format!("{n}")
    } else {
        format!("{n:e}")
    }
}

/// The grid for an *optional* output (a figure, a strip): [`GridGeometry::bounding`](crate::GridGeometry::bounding) of
/// `points` at `resolution` with `margin`, or, when that grid is over the cell budget or its
/// job over the work budget, at the finest `resolution · 2ᵏ` that fits both. The job's
/// factors other than the cells are `factors` (the cells are put in by this function); the
/// caller tells a coarsened grid by its resolution. An optional output is drawn coarser, so
/// it never fails the job whose numbers are computed anyway.
///
/// # Errors
/// [`OccupancyError::InvalidGeometry`] for a bad resolution or margin, or
/// [`OccupancyError::BadGridSize`] when no point is finite (as `bounding`);
/// [`OccupancyError::WorkTooLarge`] when even a grid of one cell is over the work budget.
///
/// ```
/// use haunts_occupancy::budget;
/// use nalgebra::Point2;
/// // Two detections 3 km apart: at 0.1 m, 9·10⁸ cells, over the cell budget.
/// let points = [Point2::new(0.0, 0.0), Point2::new(3000.0, 3000.0)];
/// let grid = budget::fit_grid(&points, 0.1, 1.0, "strip", &[("frames", 49.0)])?;
/// assert!(grid.resolution() > 0.1 && grid.len() <= budget::max_cells());
/// let near = [Point2::new(0.0, 0.0), Point2::new(30.0, 30.0)];
/// assert_eq!(budget::fit_grid(&near, 0.1, 1.0, "strip", &[("frames", 49.0)])?.resolution(), 0.1);
/// # Ok::<(), haunts_occupancy::OccupancyError>(())
/// ```
pub fn fit_grid(
    points: &[Point2<f64>],
    resolution: f64,
    margin: f64,
    what: &'static str,
    factors: &[(&'static str, f64)],
) -> Result<crate::GridGeometry> {
    let mut r = resolution;
    let mut last = None;
    // 2¹²⁸ times coarser than any real cell covers any finite extent in one cell.
    for _ in 0..128 {
        match crate::GridGeometry::bounding(points.iter().copied(), r, margin) {
            Ok(grid) => {
                let mut all = factors.to_vec();
                all.push(("cells", grid.len() as f64));
                match check_work(what, &all) {
                    Ok(_) => return Ok(grid),
                    Err(e) if grid.len() == 1 => return Err(e),
                    Err(e) => last = Some(e),
                }
            }
            Err(e @ OccupancyError::GridTooLarge { .. }) => last = Some(e),
            Err(e) => return Err(e),
        }
        r *= 2.0;
    }
    Err(last.unwrap_or(OccupancyError::BadGridSize {
        width: 0,
        height: 0,
    }))
}
