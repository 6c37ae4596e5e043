//! Fitting a flow map (issue 48, item 4: 10⁵ observations on a 400 × 400 grid in at most
//! 100 ms, the histogram): `histogram/1e5 obs, 400x400` fits the histogram alone
//! (`FlowParams::with_mixture(false)`), `both/1e5 obs, 400x400` the histogram and the
//! semi-wrapped mixture of every cell (the default), reported beside it.
//!
//! The observations: seeded, 60 % along four lanes crossing the 40 m × 40 m map (0.1 m
//! cells) at 1.2 m/s, the rest anywhere with any heading, so that some cells stand alone,
//! most pool their rings and some stay uniform, as on a real site.

use std::f64::consts::{PI, TAU};
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_affordance::flow::{FlowMap, FlowObservation, FlowParams};
use haunts_occupancy::GridGeometry;
use nalgebra::Point2;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

fn observations(n: usize) -> Vec<FlowObservation> {
    let mut rng = StdRng::seed_from_u64(48);
    (0..n)
        .map(|i| {
            let (u, v) = (rng.random::<f64>(), rng.random::<f64>());
            let (p, heading) = match i % 5 {
                0 => (Point2::new(40.0 * u, 10.0 + v), 0.0),
                1 => (Point2::new(40.0 * u, 30.0 + v), PI),
                2 => (Point2::new(20.0 + v, 40.0 * u), 0.5 * PI),
                _ => (Point2::new(40.0 * u, 40.0 * v), TAU * rng.random::<f64>()),
            };
            let heading = heading + 0.2 * (rng.random::<f64>() - 0.5);
            FlowObservation::new(i as f64, p, heading, 1.2)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let seen = observations(100_000);
    let grid = GridGeometry::new(0.1, Point2::new(0.0, 0.0), 400, 400).expect("a grid");
    let mut group = c.benchmark_group("flow_fit");
    group.sample_size(10);
    let histogram = FlowParams::default().with_mixture(false);
    group.bench_function("histogram/1e5 obs, 400x400", |b| {
        b.iter(|| FlowMap::fit(black_box(&seen), grid, &histogram).expect("a flow map"))
    });
    let both = FlowParams::default();
    group.bench_function("both/1e5 obs, 400x400", |b| {
        b.iter(|| FlowMap::fit(black_box(&seen), grid, &both).expect("a flow map"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
