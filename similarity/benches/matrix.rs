//! The similarity matrix of 70 maps of 400×400 cells (the seed's 70 days), both directions,
//! distance fields included; and the pair sums alone on prepared maps.
//!
//! The maps come from a SplitMix64 generator written out here, so that
//! `benches/peers/similarity_numpy.py` builds the identical maps; before timing, the bench
//! prints to stderr a checksum of the matrix that the Python peer checks.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_occupancy::{Cell, GridGeometry, OCCUPIED, OccupancyGrid};
use haunts_similarity::{
    DifferenceParams, PreparedMap, similarity_matrix, similarity_matrix_prepared,
};
use nalgebra::Point2;
use std::hint::black_box;

/// SplitMix64 (Steele, Lea and Flood 2014), the state starting at the seed: a few lines that
/// any language reproduces bit for bit, unlike `rand`'s `StdRng`.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// `lo + next_u64() % (hi - lo)`: in `lo..hi`, with a modulo bias far too small to matter.
    fn range(&mut self, lo: usize, hi: usize) -> usize {
        lo + (self.next_u64() % (hi - lo) as u64) as usize
    }
}

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
    let mut layout = SplitMix64(index % 7);
    let mut jitter = SplitMix64(1000 + index);
    for _ in 0..10 {
        let c0 = layout.range(10, 360);
        let r0 = layout.range(10, 360);
        let dc = jitter.range(0, 3);
        let dr = jitter.range(0, 3);
        for k in 0..30 {
            m.set(Cell::new(c0 + dc + k, r0 + dr), OCCUPIED);
            m.set(Cell::new(c0 + dc, r0 + dr + k), OCCUPIED);
        }
    }
    m
}

/// Prints to stderr what the Python peer must reproduce: the sum of the off-diagonal entries
/// (row-major, in order, shortest exact decimal of the f64), the same sum of squared distances
/// `d²` (an exact integer) and its number of terms, and the occupied cells of all maps.
fn print_checksum(maps: &[OccupancyGrid], prepared: &[PreparedMap], params: &DifferenceParams) {
    let m = similarity_matrix(maps, params).expect("matrix");
    let n = m.len();
    let mut sum = 0.0;
    for x in 0..n {
        for y in (0..n).filter(|&y| y != x) {
            sum += m.values()[x * n + y];
        }
    }
    let ct = params.cutoff.cells(m.resolution());
    let (mut sum_d2, mut terms) = (0u64, 0u64);
    for (x, px) in prepared.iter().enumerate() {
        let sq = px.field().squared_cells();
        for (_, py) in prepared.iter().enumerate().filter(|(y, _)| *y != x) {
            for &i in py.occupied_indices() {
                let d2 = sq[i as usize];
                if f64::from(d2).sqrt() > ct {
                    sum_d2 += u64::from(d2);
                    terms += 1;
                }
            }
        }
    }
    let occupied: usize = m.occupied_counts().iter().sum();
    eprintln!(
        "similarity checksum: maps={n} sum_offdiag={sum} sum_offdiag_d2={sum_d2} terms={terms} \
         occupied={occupied}"
    );
}

fn matrix(c: &mut Criterion) {
    let maps: Vec<OccupancyGrid> = (0..70).map(day).collect();
    let prepared: Vec<PreparedMap> = maps
        .iter()
        .map(|m| PreparedMap::new(m).expect("map"))
        .collect();
    let params = DifferenceParams::default();
    print_checksum(&maps, &prepared, &params);
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
