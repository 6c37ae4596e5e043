//! Loading the real ROS maps (YAML + PGM) into occupancy grids.

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts::occupancy::{MapLoadOptions, load_map};
use std::hint::black_box;

fn map_io(c: &mut Criterion) {
    let mut group = c.benchmark_group("map_io");
    for (id, file) in [
        ("load_y4_aaf_3MB", "maps/y4_aaf-cropped.yaml"),
        ("load_willow", "maps/willow-2010-02-18-0.10.yaml"),
    ] {
        let path = common::shared_data(file);
        let options = MapLoadOptions::default();
        group.bench_function(id, |b| {
            b.iter(|| load_map(black_box(&path), &options).expect("map loads"))
        });
    }
    group.finish();
}

criterion_group!(benches, map_io);
criterion_main!(benches);
