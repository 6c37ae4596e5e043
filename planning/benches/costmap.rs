//! Building a full layered costmap (static + inflation + density) of 4000 × 4000 cells: the
//! Willow Garage map's cells tiled as the occupancy crate's EDT bench does, read at 0.05 m
//! (so Nav2's default 0.55 m inflation reaches 11 cells), and a smooth density raster.
//! Needs `../shared/data` beside the project (exits with a notice when absent).

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_occupancy::{Grid, GridGeometry, MapLoadOptions, OccupancyGrid, load_map};
use haunts_planning::{
    Costmap, DensityLayer, DensityLayerParams, InflationLayer, InflationParams, LayeredCostmap,
    StaticLayer,
};
use std::hint::black_box;
use std::path::PathBuf;

const SIDE: usize = 4000;

fn tiled_willow() -> Option<OccupancyGrid> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/maps/willow-2010-02-18-0.10.yaml");
    if !path.exists() {
        eprintln!(
            "{} is absent: this bench needs ../shared/data",
            path.display()
        );
        return None;
    }
    let map = load_map(path, &MapLoadOptions::default())
        .expect("willow loads")
        .grid;
    let (w, h) = (map.geometry().width(), map.geometry().height());
    let values = map.values().data();
    let g = GridGeometry::new(0.05, nalgebra::Point2::origin(), SIDE, SIDE).expect("geometry");
    let tiled = Grid::from_fn(g, |c| values[(c.row % h) * w + c.col % w]);
    Some(OccupancyGrid::from_grid(tiled).expect("valid values"))
}

fn costmap(c: &mut Criterion) {
    let Some(map) = tiled_willow() else { return };
    let g = *map.geometry();
    let (free, occupied, unknown) = map.counts();
    eprintln!("cells: {free} free, {occupied} occupied, {unknown} unknown");
    let density = Grid::from_fn(g, |c| {
        let (x, y) = (c.col as f64 * 0.05, c.row as f64 * 0.05);
        0.5 + 0.5 * (x / 7.0).sin() * (y / 5.0).cos()
    });
    let stack = LayeredCostmap::new(g)
        .with_layer(StaticLayer::new(&map, true))
        .with_layer(InflationLayer::new(InflationParams::default()).expect("params"))
        .with_layer(
            DensityLayer::new(density, DensityLayerParams::default().with_weight(100.0))
                .expect("params"),
        );
    let built = stack.build().expect("builds");
    let inflated = built
        .data()
        .iter()
        .filter(|&&c| (1..=253).contains(&c))
        .count();
    eprintln!("cells with a cost in 1..=253: {inflated}");

    let mut group = c.benchmark_group("costmap_4000");
    group.sample_size(15);
    group.bench_function("static_inflation_density", |b| {
        b.iter(|| black_box(&stack).build())
    });
    let mut out = Costmap::filled(g, 0);
    group.bench_function("static_inflation_density_reused", |b| {
        b.iter(|| black_box(&stack).build_into(&mut out))
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a rayon pool");
    group.bench_function("static_inflation_density_1thread", |b| {
        b.iter(|| pool.install(|| black_box(&stack).build()))
    });
    group.finish();
}

criterion_group!(benches, costmap);
criterion_main!(benches);
