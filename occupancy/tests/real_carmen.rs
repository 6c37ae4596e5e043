//! The real CARMEN logs of `../shared/data/carmen/` read completely, and the maps built from
//! them show the buildings: the robot's own path is free, walls are where the beams end, and
//! the Intel lab has its known size.

mod common;

use haunts_occupancy::carmen::{CarmenOptions, LaserKind, read_carmen};
use haunts_occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts_occupancy::{CellState, GridGeometry, OccupancyGrid};
use nalgebra::Point2;

fn build(log: &haunts_occupancy::carmen::CarmenLog, every: usize) -> OccupancyGrid {
    let points = log.scans.iter().flat_map(|s| {
        let pose = s.laser_pose;
        s.scan.endpoints().map(move |p| pose * p)
    });
    let geometry = GridGeometry::bounding(points, 0.05, 1.0).unwrap();
    let mut mapper = OccupancyMapper::new(geometry, MapperParams::default()).unwrap();
    for s in log.scans.iter().step_by(every) {
        mapper.insert(&s.scan, &s.laser_pose).unwrap();
    }
    mapper.occupancy_grid()
}

/// Fraction of `points` whose cell, or one of its 8 neighbours, has `state`.
fn fraction_near(map: &OccupancyGrid, points: &[Point2<f64>], state: CellState) -> f64 {
    let g = map.geometry();
    let near = |p: &Point2<f64>| {
        let Some(c) = g.world_to_cell(*p) else {
            return false;
        };
        (-1..=1).any(|dc| {
            (-1..=1).any(|dr| {
                g.checked_cell(c.col as i64 + dc, c.row as i64 + dr)
                    .and_then(|n| map.state(n))
                    == Some(state)
            })
        })
    };
    points.iter().filter(|p| near(p)).count() as f64 / points.len() as f64
}

#[test]
fn logs_read_completely() {
    for (file, scans, beams) in [
        ("intel-corrected.log.gz", 910, 180),
        ("csail-corrected.log.gz", 406, 361),
    ] {
        let Some(path) = common::shared_data(&format!("carmen/{file}")) else {
            return;
        };
        let log = read_carmen(&path, &CarmenOptions::default()).unwrap();
        assert_eq!(log.scans.len(), scans, "{file}");
        assert_eq!(log.skipped, 0, "{file}: {:?}", log.first_skipped);
        assert!(
            log.scans
                .iter()
                .all(|s| s.kind == LaserKind::Front && s.scan.len() == beams)
        );
        assert!(
            log.odometry.len() > scans,
            "{file}: {} odometry lines",
            log.odometry.len()
        );
        // Real logs are messy: Intel's clock steps back by ~0.1 s four times; we keep file order.
        // The other lines are PARAM, NEFF and comments, counted not lost.
        assert_eq!(log.other_messages.get("NEFF"), Some(&scans));
    }
}

#[test]
fn maps_from_the_logs_show_the_buildings() {
    // CSAIL's long corridors have beams ending 30 m away on walls other scans barely see.
    for (file, min_walls) in [
        ("intel-corrected.log.gz", 0.9),
        ("csail-corrected.log.gz", 0.8),
    ] {
        let Some(path) = common::shared_data(&format!("carmen/{file}")) else {
            return;
        };
        let log = read_carmen(&path, &CarmenOptions::default()).unwrap();
        // Map from the even scans; check against the odd ones (held out).
        let map = build(&log, 2);
        let held_out = log.scans.iter().skip(1).step_by(2);
        let poses: Vec<Point2<f64>> = held_out
            .clone()
            .map(|s| s.laser_pose * Point2::origin())
            .collect();
        let ends: Vec<Point2<f64>> = held_out
            .flat_map(|s| {
                s.scan
                    .endpoints()
                    .map(move |p| s.laser_pose * p)
                    .collect::<Vec<_>>()
            })
            .collect();
        let free_path = fraction_near(&map, &poses, CellState::Free);
        let walls = fraction_near(&map, &ends, CellState::Occupied);
        assert!(
            free_path > 0.99,
            "{file}: only {free_path:.3} of the robot's path is free"
        );
        assert!(
            walls > min_walls,
            "{file}: only {walls:.3} of held-out beam ends hit walls"
        );
        eprintln!("{file}: path free {free_path:.3}, beam ends on walls {walls:.3}");
        let (free, occupied, _) = map.counts();
        assert!(
            free > 10 * occupied,
            "{file}: {free} free vs {occupied} occupied cells"
        );
    }
    // The Intel lab is a square building about 29 m on a side.
    let Some(path) = common::shared_data("carmen/intel-corrected.log.gz") else {
        return;
    };
    let map = build(&read_carmen(&path, &CarmenOptions::default()).unwrap(), 1);
    let occupied: Vec<_> = map
        .values()
        .cells()
        .filter(|(_, v)| **v >= 65)
        .map(|(c, _)| c)
        .collect();
    let percentile = |mut v: Vec<usize>, q: f64| {
        v.sort_unstable();
        v[((v.len() - 1) as f64 * q) as usize]
    };
    let cols: Vec<usize> = occupied.iter().map(|c| c.col).collect();
    let rows: Vec<usize> = occupied.iter().map(|c| c.row).collect();
    let width = (percentile(cols.clone(), 0.995) - percentile(cols, 0.005)) as f64 * 0.05;
    let height = (percentile(rows.clone(), 0.995) - percentile(rows, 0.005)) as f64 * 0.05;
    assert!(
        (25.0..33.0).contains(&width) && (25.0..33.0).contains(&height),
        "Intel lab walls span {width:.1} × {height:.1} m"
    );
}

#[test]
fn a_log_as_a_recording_places_each_scan_at_its_logged_laser_pose() {
    let Some(path) = common::shared_data("carmen/intel-corrected.log.gz") else {
        return;
    };
    let log = read_carmen(&path, &CarmenOptions::default()).unwrap();
    let recording = log.to_recording().unwrap();
    let scans: Vec<_> = recording.scans().unwrap().map(Result::unwrap).collect();
    assert_eq!(scans.len(), log.scans.len());
    let history = recording.odometry().unwrap();
    let mut checked = 0;
    for (r, s) in scans.iter().zip(&log.scans) {
        assert_eq!(r.scan.ranges, s.scan.ranges);
        let pose = recording.sensor_pose_at(&r.frame, r.scan.stamp).unwrap();
        // Scans sharing a stamp take the first one's pose.
        let first = log
            .scans
            .iter()
            .find(|o| o.scan.stamp == s.scan.stamp)
            .unwrap();
        assert!((pose.translation.vector - first.laser_pose.translation.vector).norm() < 1e-9);
        checked += 1;
    }
    assert_eq!(checked, 910);
    assert_eq!(history.len() + history.dropped_duplicates(), 910);
}
