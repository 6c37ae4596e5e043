//! Exact EDT on a 4000×4000 grid made by tiling the Willow Garage map's obstacles, the input
//! `benches/peers/edt_scipy.py` builds for `scipy.ndimage.distance_transform_edt`.
//! Side-by-side ratio: `benches/peers/compare_edt.sh`.

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts::occupancy::{Grid, GridGeometry, MapLoadOptions, load_map};
use haunts::occupancy::{distance_transform, distance_transform_with_nearest};
use std::hint::black_box;

/// The willow obstacle mask (row 0 at the bottom) tiled to `n × n`, as `np.tile` does.
fn tiled_willow(n: usize) -> Grid<bool> {
    let path = common::shared_data("maps/willow-2010-02-18-0.10.yaml");
    let mask = load_map(path, &MapLoadOptions::default())
        .expect("willow loads")
        .grid
        .occupied_mask();
    let (w, h) = (mask.width(), mask.height());
    let g = GridGeometry::new(0.1, nalgebra::Point2::origin(), n, n).expect("geometry");
    Grid::from_fn(g, |c| mask.data()[(c.row % h) * w + c.col % w])
}

fn edt(c: &mut Criterion) {
    let mask = tiled_willow(4000);
    eprintln!("obstacles: {}", mask.data().iter().filter(|&&m| m).count());
    // The peers' check: `benches/peers/edt_scipy.py --check FILE` compares every tool's
    // result with these squared distances (u32 little-endian, row-major, row 0 at the bottom).
    if let Some(path) = std::env::var_os("HAUNTS_EDT_D2_OUT") {
        let field = distance_transform(&mask).expect("obstacles");
        let bytes: Vec<u8> = field
            .squared_cells()
            .iter()
            .flat_map(|d| d.to_le_bytes())
            .collect();
        std::fs::write(&path, bytes).expect("writes HAUNTS_EDT_D2_OUT");
        let with = distance_transform_with_nearest(&mask).expect("obstacles");
        assert_eq!(with.squared_cells(), field.squared_cells());
        eprintln!("squared distances written to {}", path.to_string_lossy());
    }
    let mut group = c.benchmark_group("edt");
    group.sample_size(15);
    group.bench_function("willow_tiled_4000", |b| {
        b.iter(|| distance_transform(black_box(&mask)))
    });
    let pool = common::one_thread();
    group.bench_function("willow_tiled_4000_1thread", |b| {
        b.iter(|| pool.install(|| distance_transform(black_box(&mask))))
    });
    group.bench_function("willow_tiled_4000_nearest", |b| {
        b.iter(|| distance_transform_with_nearest(black_box(&mask)))
    });
    group.bench_function("willow_tiled_4000_nearest_1thread", |b| {
        b.iter(|| pool.install(|| distance_transform_with_nearest(black_box(&mask))))
    });
    group.finish();
}

criterion_group!(benches, edt);
criterion_main!(benches);
