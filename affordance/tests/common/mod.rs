//! Helpers shared by the integration tests (not every test file uses every helper).
#![allow(dead_code)]

use std::path::PathBuf;

use haunts_occupancy::{Cell, FREE, GridGeometry, OCCUPIED, OccupancyGrid};
use nalgebra::Point2;

/// A file of `../shared/data/` (beside the project root), or `None` with a printed notice.
pub fn shared_data(relative: &str) -> Option<PathBuf> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(relative);
    if path.exists() {
        Some(path)
    } else {
        eprintln!("skipping: {} is absent", path.display());
        None
    }
}

/// 3 m × 3 m at 0.05 m: the room of the layout tests.
pub fn room() -> GridGeometry {
    GridGeometry::new(0.05, Point2::origin(), 60, 60).expect("a valid geometry")
}

/// A day's map of [`room`]: a wall along column `col` (all 60 rows), the column right of it
/// seen free, the rest unknown.
pub fn wall_at(col: usize) -> OccupancyGrid {
    let mut m = OccupancyGrid::unknown(room());
    for row in 0..60 {
        m.set(Cell::new(col, row), OCCUPIED);
        m.set(Cell::new(col + 1, row), FREE);
    }
    m
}
