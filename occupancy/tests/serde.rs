//! With the `serde` feature, grids, scans and parameters round-trip through JSON, and
//! deserialising checks the same rules as the constructors.
#![cfg(feature = "serde")]

use haunts_occupancy::distance_transform_with_nearest;
use haunts_occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts_occupancy::raycast::{Traversal, VisitCounter, VisitRule};
use haunts_occupancy::{
    Cell, Grid, GridGeometry, LaserScan, MapLoadOptions, MapSaveOptions, MaxRangeRule,
    OccupancyGrid, Pose2, load_map, save_map,
};
use nalgebra::{Point2, Vector2};

use haunts_test_support::json;
use json::corrupt;

#[test]
fn values_round_trip_through_json() {
    let g = GridGeometry::new(0.05, Point2::new(-1.5, 2.0), 3, 2).unwrap();
    let map = OccupancyGrid::from_values(g, vec![-1, 0, 100, 50, 0, 0]).unwrap();
    let back: OccupancyGrid = serde_json::from_str(&serde_json::to_string(&map).unwrap()).unwrap();
    assert_eq!(back, map);
    let scan = LaserScan::new(1.5, -1.0, 0.5, 0.1, 8.0, vec![1.0, 2.0], vec![]).unwrap();
    let back: LaserScan = serde_json::from_str(&serde_json::to_string(&scan).unwrap()).unwrap();
    assert_eq!(back, scan);
    let params = MapperParams::default();
    let back: MapperParams =
        serde_json::from_str(&serde_json::to_string(&params).unwrap()).unwrap();
    assert_eq!(back, params);
    let options = MapLoadOptions::default();
    let back: MapLoadOptions =
        serde_json::from_str(&serde_json::to_string(&options).unwrap()).unwrap();
    assert_eq!(back, options);
}

#[test]
fn deserialising_checks_the_rules() {
    let bad_geometry = r#"{"resolution":-0.1,"origin":[0.0,0.0],"width":2,"height":2}"#;
    let e = serde_json::from_str::<GridGeometry>(bad_geometry).unwrap_err();
    assert!(e.to_string().contains("resolution"), "{e}");
    let short =
        r#"{"geometry":{"resolution":0.1,"origin":[0.0,0.0],"width":2,"height":2},"data":[1,2,3]}"#;
    let e = serde_json::from_str::<Grid<u8>>(short).unwrap_err();
    assert!(e.to_string().contains("4"), "{e}");
    let bad_value = r#"{"values":{"geometry":{"resolution":0.1,"origin":[0.0,0.0],"width":1,"height":1},"data":[101]},"thresholds":{"occupied_min":65,"free_max":25}}"#;
    assert!(serde_json::from_str::<OccupancyGrid>(bad_value).is_err());
    let bad_scan = r#"{"stamp":0.0,"angle_min":0.0,"angle_increment":0.0,"range_min":0.0,"range_max":1.0,"ranges":[]}"#;
    let e = serde_json::from_str::<LaserScan>(bad_scan).unwrap_err();
    assert!(e.to_string().contains("angle_increment"), "{e}");
}

/// Lookups, world ↔ cell conversions, a traversal and a mapping step on a geometry.
fn use_geometry(g: &GridGeometry) {
    let o = g.origin();
    let corner = g.upper_corner();
    let r = g.resolution();
    for p in [
        o,
        corner,
        Point2::new(0.0, 0.0),
        Point2::new(o.x + 1.5 * r, o.y + 0.5 * r),
        Point2::new(f64::NAN, 1.0),
        Point2::new(1e300, -1e300),
    ] {
        if let Some(c) = g.world_to_cell(p) {
            assert!(g.contains(c));
            let i = g.index(c).unwrap();
            assert_eq!(g.cell_at(i), Some(c));
            let _ = g.cell_center(c);
        }
        let _ = g.world_to_grid(p);
    }
    let last = Cell::new(g.width() - 1, g.height() - 1);
    assert_eq!(g.index(last), Some(g.len() - 1));
    let _ = g.checked_cell(-1, i64::MAX);
    let _ = g.with_resolution(0.1);
    let _ = g.same_cells(g, 0.01);
    let _ = GridGeometry::bounding([o, corner], r, 0.0);
    let total: f64 = Traversal::new(g, o, corner).map(|(_, l)| l).sum();
    assert!(total >= 0.0);
    let mut mapper = OccupancyMapper::new(*g, MapperParams::default()).unwrap();
    let pose = Pose2::new(Vector2::new(o.x + 0.5 * r, o.y + 0.5 * r), 0.3);
    let _ = mapper.insert(&scan(), &pose);
    let map = mapper.occupancy_grid();
    assert_eq!(map.geometry(), g);
}

/// Cell lookups of a grid: by cell, by world point, by row, every cell.
fn use_grid<T: std::fmt::Debug>(grid: &Grid<T>) {
    use_geometry(grid.geometry());
    for row in 0..grid.height() {
        assert_eq!(grid.row(row).len(), grid.width());
    }
    assert_eq!(grid.rows().count(), grid.height());
    for (cell, v) in grid.cells() {
        let _ = format!("{v:?}");
        assert!(grid.get(cell).is_some());
        let _ = &grid[cell];
        let _ = grid.at_world(grid.geometry().cell_center(cell));
    }
    assert!(grid.get(Cell::new(grid.width(), 0)).is_none());
}

/// Lookups, masks, a distance field and saving (then loading) the map.
fn use_map(map: &OccupancyGrid, dir: &std::path::Path) {
    use_grid(map.values());
    for (cell, _) in map.values().cells() {
        let _ = (map.state(cell), map.probability(cell), map.value(cell));
    }
    let (f, o, u) = map.counts();
    assert_eq!(f + o + u, map.geometry().len());
    let _ = map.free_mask();
    match distance_transform_with_nearest(&map.occupied_mask()) {
        Ok(field) => {
            let _ = (field.metres_grid(), field.nearest(Cell::new(0, 0)));
        }
        Err(e) => assert!(o == 0, "{e}"),
    }
    let yaml = dir.join("map.yaml");
    save_map(&yaml, map, &MapSaveOptions::default()).unwrap();
    let back = load_map(&yaml, &MapLoadOptions::default()).unwrap();
    assert_eq!(back.grid.geometry().width(), map.geometry().width());
}

/// A scan of 30 beams over 90°, some hitting, some at max range, some invalid (all finite:
/// JSON has no infinity, serde_json writes it as `null`).
fn scan() -> LaserScan {
    let ranges = (0..30)
        .map(|i| match i % 5 {
            0 => 4.0,
            1 => 0.0,
            _ => 0.3 + 0.05 * f64::from(i),
        })
        .collect();
    LaserScan::new(12.5, -0.8, 0.054, 0.05, 4.0, ranges, vec![]).unwrap()
}

#[test]
fn corrupted_files_are_refused_or_usable_never_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let g = GridGeometry::new(0.1, Point2::new(-0.4, -0.3), 7, 5).unwrap();
    let geometry = corrupt(&g, 1000, |g: &GridGeometry| use_geometry(g));
    let floats = Grid::from_fn(g, |c| c.col as f64 - 0.5 * c.row as f64);
    let grid = corrupt(&floats, 1000, |grid: &Grid<f64>| use_grid(grid));
    let map = OccupancyGrid::from_grid(Grid::from_fn(g, |c| match (c.col + 3 * c.row) % 4 {
        0 => -1,
        1 => 0,
        2 => 100,
        _ => 40,
    }))
    .unwrap();
    let maps = corrupt(&map, 1000, |map: &OccupancyGrid| use_map(map, dir.path()));
    // A mapper over a room, and the scan in it.
    let room = GridGeometry::new(0.05, Point2::new(-2.0, -2.0), 80, 80).unwrap();
    let mut mapper = OccupancyMapper::new(room, MapperParams::default()).unwrap();
    let mut visits = VisitCounter::new(room, VisitRule::default()).unwrap();
    let scans = corrupt(&scan(), 1000, |scan: &LaserScan| {
        let pose = Pose2::new(Vector2::new(0.1, -0.2), 0.7);
        let _ = (scan.len(), scan.is_empty(), scan.beams().count());
        let _ = scan.endpoints_world(&pose).count();
        let _ = scan.rays(&pose, MaxRangeRule::Clear(3.0)).count();
        let stats = mapper.insert(scan, &pose).unwrap();
        assert_eq!(stats.rays + stats.skipped_beams, scan.len());
        visits
            .add_scan(scan, &pose, MaxRangeRule::default())
            .unwrap();
        let _ = mapper.occupancy_grid();
    });
    for (name, tally) in [
        ("GridGeometry", geometry),
        ("Grid<f64>", grid),
        ("OccupancyGrid", maps),
        ("LaserScan", scans),
    ] {
        eprintln!("{name}: {tally:?}");
        assert!(tally.refused > 0 && tally.accepted > 0, "{name}: {tally:?}");
    }
}
