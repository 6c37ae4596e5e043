//! End to end on synthetic days: a room whose two tables stand in one of two places (layout A
//! on the left, layout B on the right), a robot that scans it from fixed waypoints, and people
//! who sit around the tables. The library must find the two layouts, assign every day to the
//! right one, and concentrate each layout's affordance near its own tables.

use haunts_affordance::DensityMap;
use haunts_affordance::density::{DailyDensity, DensityParams};
use haunts_affordance::layout::{LayoutId, LayoutLibrary, LayoutParams};
use haunts_occupancy::{Cell, FREE, GridGeometry, LaserScan, OCCUPIED, OccupancyGrid, Pose2};
use nalgebra::{Point2, Vector2};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

const RES: f64 = 0.05;
/// Half sizes of a table, metres.
const HALF: (f64, f64) = (0.5, 0.3);

/// Table centres of each layout.
const TABLES: [[(f64, f64); 2]; 2] = [[(1.5, 1.5), (1.5, 3.5)], [(4.5, 1.5), (4.5, 3.5)]];

/// Which layout each day shows.
const TRUTH: [usize; 10] = [0, 0, 1, 0, 1, 1, 0, 1, 0, 1];

/// Where the robot stops to scan (never inside a table).
const WAYPOINTS: [(f64, f64); 7] = [
    (3.0, 1.0),
    (3.0, 4.0),
    (3.0, 2.5),
    (0.5, 2.5),
    (5.5, 2.5),
    (1.5, 2.5),
    (4.5, 2.5),
];

/// A 6 m × 5 m room at 0.05 m.
fn room() -> GridGeometry {
    GridGeometry::new(RES, Point2::origin(), 120, 100).unwrap()
}

/// Distance from `p` to the (filled) table rectangle centred at `c`.
fn to_table(p: Point2<f64>, c: (f64, f64)) -> f64 {
    let dx = ((p.x - c.0).abs() - HALF.0).max(0.0);
    let dy = ((p.y - c.1).abs() - HALF.1).max(0.0);
    dx.hypot(dy)
}

/// The day's map: walls two cells thick, the layout's tables (each shifted by up to one cell,
/// as an aligned map of another day would be), everything else free.
fn day_map(layout: usize, rng: &mut StdRng) -> OccupancyGrid {
    let g = room();
    let shifts: Vec<(f64, f64)> = (0..2)
        .map(|_| {
            (
                rng.random_range(-1i32..=1) as f64 * RES,
                rng.random_range(-1i32..=1) as f64 * RES,
            )
        })
        .collect();
    let mut map = OccupancyGrid::unknown(g);
    for row in 0..g.height() {
        for col in 0..g.width() {
            let cell = Cell::new(col, row);
            let p = g.cell_center(cell);
            let wall = col < 2 || row < 2 || col >= g.width() - 2 || row >= g.height() - 2;
            let table = TABLES[layout]
                .iter()
                .zip(&shifts)
                .any(|(c, s)| to_table(p, (c.0 + s.0, c.1 + s.1)) == 0.0);
            map.set(cell, if wall || table { OCCUPIED } else { FREE });
        }
    }
    map
}

/// A 360° scan from `at`, marched through the map in 2 cm steps.
fn scan_from(map: &OccupancyGrid, at: Point2<f64>) -> LaserScan {
    let beams = 720;
    let increment = std::f64::consts::TAU / beams as f64;
    let ranges = (0..beams)
        .map(|i| {
            let a = -std::f64::consts::PI + i as f64 * increment;
            let d = Vector2::new(a.cos(), a.sin());
            let mut r = 0.0;
            loop {
                r += 0.02;
                match map.geometry().world_to_cell(at + d * r) {
                    Some(c) if map.value(c) == Some(OCCUPIED) => break r,
                    Some(_) if r < 9.0 => {}
                    _ => break f64::INFINITY,
                }
            }
        })
        .collect();
    LaserScan::new(
        0.0,
        -std::f64::consts::PI,
        increment,
        0.05,
        10.0,
        ranges,
        vec![],
    )
    .unwrap()
}

/// People sitting around the layout's tables (0.25–0.45 m from an edge), and a few walkers.
fn people(layout: usize, rng: &mut StdRng) -> Vec<Point2<f64>> {
    let mut out = Vec::new();
    for c in TABLES[layout] {
        for _ in 0..80 {
            let off = rng.random_range(0.25..0.45);
            let along = rng.random_range(-1.0..1.0);
            let p = match rng.random_range(0..4) {
                0 => (c.0 + along * HALF.0, c.1 + HALF.1 + off),
                1 => (c.0 + along * HALF.0, c.1 - HALF.1 - off),
                2 => (c.0 + HALF.0 + off, c.1 + along * HALF.1),
                _ => (c.0 - HALF.0 - off, c.1 + along * HALF.1),
            };
            out.push(Point2::new(p.0, p.1));
        }
    }
    for _ in 0..15 {
        out.push(Point2::new(
            rng.random_range(0.3..5.7),
            rng.random_range(0.3..4.7),
        ));
    }
    out
}

fn day(layout: usize, rng: &mut StdRng) -> (OccupancyGrid, DailyDensity) {
    let map = day_map(layout, rng);
    let scans: Vec<(LaserScan, Pose2)> = WAYPOINTS
        .iter()
        .map(|&(x, y)| {
            let pose = Pose2::new(Vector2::new(x, y), 0.0);
            (scan_from(&map, Point2::new(x, y)), pose)
        })
        .collect();
    let (density, stats) = DailyDensity::from_day(
        room(),
        &scans,
        |(s, p)| (s, p),
        people(layout, rng),
        &DensityParams::default(),
    )
    .unwrap();
    assert_eq!(stats.hits.non_finite + stats.hits.outside, 0);
    assert_eq!(stats.scans.rays, 7 * 720);
    (map, density)
}

#[test]
fn two_furniture_layouts_are_found_and_their_affordances_follow_the_tables() {
    let mut rng = StdRng::seed_from_u64(7);
    // Cells the laser saw fewer than 5 times over a layout's days have no density: a single
    // passer-by in a barely seen corner would otherwise look like a crowd.
    let params = LayoutParams::default().with_min_visits(5);
    let mut library = LayoutLibrary::new(room(), params).unwrap();
    let mut layout_of_truth: [Option<LayoutId>; 2] = [None, None];
    for (i, &truth) in TRUTH.iter().enumerate() {
        let (map, density) = day(truth, &mut rng);
        let r = library
            .ingest(format!("day {i:02}"), &map, &density)
            .unwrap();
        match layout_of_truth[truth] {
            None => {
                assert!(r.created, "day {i} should start layout {truth}");
                layout_of_truth[truth] = Some(r.layout);
            }
            Some(expected) => {
                assert!(!r.created, "day {i}: {:?}", r.classification);
                assert_eq!(r.layout, expected, "day {i}");
                // Tables that moved by at most two cells are within the cutoff.
                assert_eq!(r.classification.distance(), Some(0.0), "day {i}");
            }
        }
    }
    assert_eq!(library.layouts().len(), 2);
    let ids = layout_of_truth.map(|l| l.unwrap());
    assert_ne!(ids[0], ids[1]);

    // Each layout's history is exactly its days.
    for (truth, id) in ids.iter().enumerate() {
        let labels: Vec<String> = library
            .layout(*id)
            .unwrap()
            .days()
            .iter()
            .map(|d| d.label.clone())
            .collect();
        let expected: Vec<String> = TRUTH
            .iter()
            .enumerate()
            .filter(|(_, t)| **t == truth)
            .map(|(i, _)| format!("day {i:02}"))
            .collect();
        assert_eq!(labels, expected);
    }

    // Each layout's affordance mass lies near its own tables, not near the other layout's.
    let g = room();
    for (truth, id) in ids.iter().enumerate() {
        let affordance = library.layout(*id).unwrap().affordance();
        let grid = affordance.density_grid();
        let (mut own, mut other, mut total) = (0.0, 0.0, 0.0);
        for (cell, v) in grid.cells().filter(|(_, v)| !v.is_nan()) {
            let p = g.cell_center(cell);
            let near = |l: usize| TABLES[l].iter().any(|c| to_table(p, *c) <= 0.7);
            total += v;
            if near(truth) {
                own += v;
            }
            if near(1 - truth) {
                other += v;
            }
        }
        assert!(
            own > 0.9 * total,
            "layout {truth}: {own} of {total} near its tables"
        );
        assert!(
            other < 0.05 * own,
            "layout {truth}: {other} near the other tables vs {own}"
        );

        // Rasterised onto 0.25 m cells (what a costmap layer takes), the busiest cell is
        // beside one of the layout's own tables.
        let coarse = GridGeometry::new(0.25, Point2::origin(), 24, 20).unwrap();
        let raster = affordance.rasterise(&coarse);
        let (best, _) = raster
            .cells()
            .filter(|(_, v)| !v.is_nan())
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        let p = coarse.cell_center(best);
        assert!(
            TABLES[truth].iter().any(|c| to_table(p, *c) <= 0.6),
            "layout {truth}: busiest at {p}"
        );
    }

    // A new day of either layout is recognised without being stored.
    for truth in [1, 0] {
        let (map, _) = day(truth, &mut rng);
        let c = library.classify(&map).unwrap();
        assert_eq!(c.layout, Some(ids[truth]));
    }
    assert_eq!(library.day_count(), TRUTH.len() as u64);

    // And the whole library survives a save and a load.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("office.hlib");
    library.save(&path).unwrap();
    let back = LayoutLibrary::load(&path).unwrap();
    assert_eq!(back, library);
    let (map, _) = day(0, &mut rng);
    assert_eq!(back.classify(&map).unwrap().layout, Some(ids[0]));
}
