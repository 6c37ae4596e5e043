//! Visit counting (seed 000's half-cell rule) and log-odds mapping for all 910 scans of the
//! Intel lab log at 0.05 m.

mod common;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use haunts::occupancy::MaxRangeRule;
use haunts::occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts::occupancy::raycast::{Traversal, VisitCounter, VisitRule};
use std::hint::black_box;

fn raycast(c: &mut Criterion) {
    let (log, geometry) = common::intel(0.05);
    let rule = MaxRangeRule::default();
    let steps: u64 = log
        .scans
        .iter()
        .flat_map(|s| s.scan.rays(&s.laser_pose, rule).collect::<Vec<_>>())
        .map(|r| Traversal::new(&geometry, r.from, r.to).count() as u64)
        .sum();
    eprintln!(
        "{} scans, {steps} cell steps on {}×{} cells",
        log.scans.len(),
        geometry.width(),
        geometry.height()
    );

    let mut group = c.benchmark_group("raycast");
    group.throughput(Throughput::Elements(steps));
    group.bench_function("intel_visits_0.05", |b| {
        b.iter(|| {
            let mut visits = VisitCounter::new(geometry, VisitRule::default()).expect("rule");
            visits
                .add_scans(&log.scans, |s| (&s.scan, &s.laser_pose), rule)
                .expect("finite poses");
            black_box(visits)
        })
    });
    let pool = common::one_thread();
    group.bench_function("intel_visits_0.05_1thread", |b| {
        b.iter(|| {
            let mut visits = VisitCounter::new(geometry, VisitRule::default()).expect("rule");
            pool.install(|| visits.add_scans(&log.scans, |s| (&s.scan, &s.laser_pose), rule))
                .expect("finite poses");
            black_box(visits)
        })
    });
    group.bench_function("intel_mapping_0.05", |b| {
        b.iter(|| {
            let mut mapper =
                OccupancyMapper::new(geometry, MapperParams::default()).expect("params");
            for s in &log.scans {
                mapper.insert(&s.scan, &s.laser_pose).expect("finite pose");
            }
            black_box(mapper)
        })
    });
    group.finish();
}

criterion_group!(benches, raycast);
criterion_main!(benches);
