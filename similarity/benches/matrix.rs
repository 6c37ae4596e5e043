//! The similarity matrix of 70 maps of 400×400 cells (the seed's 70 days), both directions,
//! distance fields included; and the pair sums alone on prepared maps.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_occupancy::{Cell, GridGeometry, OCCUPIED, OccupancyGrid};
use haunts_similarity::{
    DifferenceParams, PreparedMap, similarity_matrix, similarity_matrix_prepared,
};
use nalgebra::Point2;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use std::hint::black_box;

/// A 20 m room with two inner walls and ten pieces of furniture whose places depend on the
/// day's layout (7 layouts) plus a little per-day jitter.
fn day(index: u64) -> OccupancyGrid {
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
    }
    let mut layout = StdRng::seed_from_u64(index % 7);
    let mut jitter = StdRng::seed_from_u64(1000 + index);
    for _ in 0..10 {
        let (c0, r0) = (layout.random_range(10..360), layout.random_range(10..360));
        let (dc, dr) = (jitter.random_range(0..3), jitter.random_range(0..3));
        for k in 0..30 {
            m.set(Cell::new(c0 + dc + k, r0 + dr), OCCUPIED);
            m.set(Cell::new(c0 + dc, r0 + dr + k), OCCUPIED);
        }
    }
    m
}

fn matrix(c: &mut Criterion) {
    let maps: Vec<OccupancyGrid> = (0..70).map(day).collect();
    let prepared: Vec<PreparedMap> = maps
        .iter()
        .map(|m| PreparedMap::new(m).expect("map"))
        .collect();
    let params = DifferenceParams::default();
    let mut group = c.benchmark_group("similarity_matrix");
    group.sample_size(10);
    group.bench_function("70_maps_400x400", |b| {
        b.iter(|| similarity_matrix(black_box(&maps), &params))
    });
    group.bench_function("70_maps_400x400_prepared", |b| {
        b.iter(|| similarity_matrix_prepared(black_box(&prepared), &params))
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    group.bench_function("70_maps_400x400_1thread", |b| {
        b.iter(|| pool.install(|| similarity_matrix(black_box(&maps), &params)))
    });
    group.finish();
}

criterion_group!(benches, matrix);
criterion_main!(benches);
