//! What the `scene_map` fuzz target does with an input, shared with
//! `tracking/tests/fuzz_regressions.rs` so that saved inputs replay exactly as fuzzed: the
//! input (non-UTF-8 skipped) is read by `parse_scene_map`; an accepted map has finite
//! coordinates and radii `>= 0`, and is drawn into a free 40 × 30 grid of 0.25 m cells from
//! (−2, −3): at most every cell is marked, never one outside.
#![allow(dead_code)]

use haunts_occupancy::{FREE, GridGeometry, OCCUPIED, OccupancyGrid};
use haunts_tracking::{TrackingError, parse_scene_map};
use nalgebra::Point2;

/// Runs the `scene_map` target on an input: `None` for non-UTF-8 input, else
/// `Ok((lines, circles, cells marked))` or the typed error.
pub fn scene_map(data: &[u8]) -> Option<Result<(usize, usize, usize), TrackingError>> {
    let text = std::str::from_utf8(data).ok()?;
    Some(parse_scene_map(text).and_then(|scene| {
        for [a, b] in &scene.lines {
            assert!(a.x.is_finite() && a.y.is_finite() && b.x.is_finite() && b.y.is_finite());
        }
        for (c, r) in &scene.circles {
            assert!(c.x.is_finite() && c.y.is_finite() && r.is_finite() && *r >= 0.0);
        }
        let g = GridGeometry::new(0.25, Point2::new(-2.0, -3.0), 40, 30).expect("a small grid");
        let mut map = OccupancyGrid::from_values(g, vec![FREE; g.len()]).expect("free values");
        let marked = scene.draw(&mut map)?;
        let occupied = map
            .values()
            .data()
            .iter()
            .filter(|v| **v == OCCUPIED)
            .count();
        assert_eq!(marked, occupied, "every marked cell counted once");
        assert!(marked <= g.len());
        Ok((scene.lines.len(), scene.circles.len(), marked))
    }))
}
