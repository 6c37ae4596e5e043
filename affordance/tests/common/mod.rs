//! Helpers shared by the integration tests (not every test file uses every helper).
#![allow(dead_code)]

use haunts_occupancy::{Cell, FREE, GridGeometry, OCCUPIED, OccupancyGrid};
use nalgebra::Point2;

#[allow(unused_imports)] // not every test file reads the real data
pub use data::shared_data;
use haunts_test_support::data;

/// 3 m × 3 m at 0.05 m: the room of the layout tests.
pub fn room() -> GridGeometry {
    GridGeometry::new(0.05, Point2::origin(), 60, 60).expect("a valid geometry")
}

/// A day's map of [`room`]: a wall along column `col` (all 60 rows), the rest of the room
/// seen free (the day observed the whole room, as seed 000's days do: its days and layouts
/// compare as whole maps whether or not `LayoutParams::observed_only` is on).
pub fn wall_at(col: usize) -> OccupancyGrid {
    wall_seen_in(col, 0..60)
}

/// A day's map of [`room`] that saw only the columns `seen`: a wall along column `col` in
/// it, the rest of `seen` free, everything else unknown.
pub fn wall_seen_in(col: usize, seen: std::ops::Range<usize>) -> OccupancyGrid {
    let mut m = OccupancyGrid::unknown(room());
    for c in seen {
        for row in 0..60 {
            m.set(Cell::new(c, row), if c == col { OCCUPIED } else { FREE });
        }
    }
    m
}

/// A straight walk from `a` to `b` in `n` samples, 0.4 s apart.
pub fn walk(id: u64, a: (f64, f64), b: (f64, f64), n: usize) -> haunts_tracking::Trajectory {
    haunts_tracking::Trajectory {
        id,
        samples: (0..n)
            .map(|k| {
                let t = k as f64 / (n - 1) as f64;
                (
                    k as f64 * 0.4,
                    Point2::new(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)),
                )
            })
            .collect(),
    }
}

/// The people detections of a shared stroll day (`"25"` or `"26"`, `t x y …` columns), read
/// whole, or `None` with a notice when the shared data are absent.
pub fn stroll_day(
    day: &str,
) -> Option<haunts_tracking::Parsed<haunts_affordance::hypertime::TimedPoint>> {
    use haunts_affordance::hypertime::{DetectionColumns, read_detections};
    let path = shared_data(&format!("people/2017_05_{day}.txt"))?;
    let columns = DetectionColumns::default().with_columns(0, 1, 2);
    Some(read_detections(path, &columns).expect("the shared stroll day reads"))
}
