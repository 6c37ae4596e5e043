//! Scan-to-map ICP of a 360-beam scan in a 20 m × 20 m office map at 0.05 m, from a guess
//! 0.1 m and 2° off; and the preparation of the map as a target.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_occupancy::{Cell, GridGeometry, OCCUPIED, OccupancyGrid, Pose2};
use haunts_similarity::{IcpParams, IcpTarget, icp};
use nalgebra::{Point2, Vector2};
use std::hint::black_box;

fn office() -> OccupancyGrid {
    let n = 400;
    let g = GridGeometry::new(0.05, Point2::origin(), n, n).expect("geometry");
    let mut m = OccupancyGrid::unknown(g);
    for i in 0..n {
        for c in [
            Cell::new(i, 0),
            Cell::new(i, n - 1),
            Cell::new(0, i),
            Cell::new(n - 1, i),
        ] {
            m.set(c, OCCUPIED);
        }
        if i % 100 < 70 {
            m.set(Cell::new(i, 200), OCCUPIED);
            m.set(Cell::new(150, i), OCCUPIED);
        }
        if (40..90).contains(&i) {
            m.set(Cell::new(i, 120), OCCUPIED);
            m.set(Cell::new(260, i + 200), OCCUPIED);
        }
    }
    m
}

/// Endpoints (sensor frame) of 360 beams cast from `pose` until they hit an occupied cell.
fn scan(map: &OccupancyGrid, pose: &Pose2) -> Vec<Point2<f64>> {
    let g = map.geometry();
    (0..360)
        .filter_map(|k| {
            let a = (k as f64).to_radians();
            let dir = Vector2::new(a.cos(), a.sin());
            (1..3000).map(|s| s as f64 * 0.01).find_map(|r| {
                let p = Point2::from(dir * r);
                let c = g.world_to_cell(pose * p)?;
                (map.value(c) == Some(OCCUPIED)).then_some(p)
            })
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let map = office();
    let target = IcpTarget::new(&map).expect("target");
    let truth = Pose2::new(Vector2::new(5.0, 6.0), 0.3);
    let points = scan(&map, &truth);
    let guess = truth * Pose2::new(Vector2::new(0.08, -0.06), 2f64.to_radians());
    let params = IcpParams::default();
    let r = icp(&target, &points, &guess, &params).expect("converges");
    assert!((r.pose.translation.vector - truth.translation.vector).norm() < 0.05);
    let mut group = c.benchmark_group("icp");
    group.bench_function("scan_to_map_360_beams", |b| {
        b.iter(|| icp(black_box(&target), black_box(&points), &guess, &params))
    });
    group.sample_size(20);
    group.bench_function("prepare_target_400x400", |b| {
        b.iter(|| IcpTarget::new(black_box(&map)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
