//! Simulating 70 days of the default 15-minute patrol (9000 scans of 541 beams a day, the
//! issue's target: under 10 s), and one day alone.
//!
//! Measured on the 2-core development machine (load ≈ 1.9, 2026-12-01): 70 days in 4.10 s
//! (criterion median), one day in 72 ms.

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_sim::{SimParams, Simulator};
use std::hint::black_box;

fn sim(c: &mut Criterion) {
    let sim = Simulator::new(SimParams::default()).expect("default parameters are valid");
    let mut group = c.benchmark_group("sim");
    group.sample_size(10);
    group.bench_function("one_day_15min_patrol", |b| {
        b.iter(|| black_box(sim.day(black_box(3)).expect("day simulates")))
    });
    group.bench_function("70_days_15min_patrol", |b| {
        b.iter(|| {
            // Day by day in parallel chunks, dropping each day: what a pipeline does, and
            // it keeps memory at a few days' worth.
            let mut scans = 0;
            for chunk in 0..35 {
                let days = sim.days(chunk * 2..chunk * 2 + 2).expect("days simulate");
                scans += days.iter().map(|d| d.scans.len()).sum::<usize>();
            }
            black_box(scans)
        })
    });
    group.finish();
}

criterion_group!(benches, sim);
criterion_main!(benches);
