//! Registering a day recorded from another start pose onto a layout library (issue 46, item
//! 6: a 400 × 400-cell day into a library of 5 layouts, target ≤ 200 ms).
//!
//! The library: the simulated office's five layouts (`haunts-sim`, seed 0), each its
//! ground-truth map of walls, fixed and movable furniture (0.05 m cells), one day each. The
//! day: layout 2's map seen from a frame moved by (3.2 m, −1.7 m, 30°), drawn onto its own
//! 400 × 400 cells (20 m × 20 m) by nearest neighbour. Timed: `LayoutLibrary::register`
//! (one global registration per layout: corners, descriptors, RANSAC + Umeyama, ICP, the
//! fit), and `register_and_move` (the same, then `move_day` onto the library's cells: what
//! `haunts day --like` adds to a day). The check before timing prints the transform found
//! and its error against the truth.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_affordance::{DailyDensity, LayoutLibrary, LayoutParams, RegisterParams, move_day};
use haunts_occupancy::{Grid, GridGeometry, OccupancyGrid, Pose2};
use haunts_sim::{SimParams, Simulator};
use haunts_similarity::resample_posed;
use nalgebra::{Point2, Vector2};

/// The library of the office's five layouts, and the day (its map and an empty density).
fn setup() -> (LayoutLibrary, OccupancyGrid, DailyDensity, Pose2) {
    let sim = Simulator::new(SimParams::default()).expect("the default office");
    let g = sim.geometry();
    let mut library = LayoutLibrary::new(g, LayoutParams::default()).expect("a library");
    let zeros = Grid::filled(g, 0u32);
    let empty = DailyDensity::new(zeros.clone(), zeros, 1).expect("a density");
    let mut maps = Vec::new();
    for layout in 0..sim.office().layouts.len() {
        let furniture = sim.furniture(0, layout).expect("a layout");
        let map = sim
            .truth_grid(&sim.static_shapes(&furniture))
            .expect("a map");
        library
            .ingest(format!("layout {layout}"), &map, &empty)
            .expect("ingested");
        maps.push(map);
    }
    // The day's frame at `truth` in the library's: its cells see layout 2 from there.
    let truth = Pose2::new(Vector2::new(3.2, -1.7), 30f64.to_radians());
    let centre = Point2::from((g.origin().coords + g.upper_corner().coords) / 2.0);
    let own = GridGeometry::new(
        g.resolution(),
        truth.inverse() * centre - Vector2::new(10.0, 10.0),
        400,
        400,
    )
    .expect("the day's grid");
    let day = resample_posed(&maps[2], &own, &truth.inverse()).expect("the day's map");
    let zeros = Grid::filled(own, 0u32);
    let density = DailyDensity::new(zeros.clone(), zeros, 1).expect("a density");
    (library, day, density, truth)
}

fn bench(c: &mut Criterion) {
    let (library, day, density, truth) = setup();
    let params = RegisterParams::default();
    let r = library.register(&day, &params).expect("registered");
    let t = (r.pose().translation.vector - truth.translation.vector).norm();
    let deg = r
        .pose()
        .rotation
        .angle_to(&truth.rotation)
        .abs()
        .to_degrees();
    eprintln!(
        "register check: {} layouts, day {}x{} cells, {r:?}, off by {t:.3} m, {deg:.3} deg",
        library.layouts().len(),
        day.geometry().width(),
        day.geometry().height(),
    );
    let mut group = c.benchmark_group("register");
    group.sample_size(20);
    group.bench_function("400x400_into_5_layouts", |b| {
        b.iter(|| {
            library
                .register(black_box(&day), &params)
                .expect("registered")
        })
    });
    group.bench_function("register_and_move", |b| {
        b.iter(|| {
            let r = library
                .register(black_box(&day), &params)
                .expect("registered");
            move_day(&day, &density, &r.pose(), library.geometry()).expect("moved")
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
