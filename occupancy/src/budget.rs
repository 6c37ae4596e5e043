//! The cell budget: the most cells a grid may have, checked before anything is allocated.
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

use std::sync::atomic::{AtomicUsize, Ordering};

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
        return Err(OccupancyError::InvalidParameter {
            name: "max_cells",
            value: cells as f64,
            rule: "must be in 1..=u32::MAX",
        });
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

/// Formats a cell count that may not fit an integer: whole below 10¹⁵, scientific above.
pub(crate) fn count(n: f64) -> String {
    if n.abs() < 1e15 {
        format!("{n}")
    } else {
        format!("{n:e}")
    }
}
