//! Daily density (seed 000 III-B: human hits / laser visits), issue 7's target "under 100 ms
//! for a day of the simulated office or the Intel log":
//! - a simulated office day (the default 15-minute patrol: 9000 scans of 541 beams, the true
//!   people at every scan as the tracked positions) at 0.1 m, every scan and every tenth scan
//!   (what the pipeline counts);
//! - the Intel lab log (910 scans of 180 beams, corrected poses) at 0.05 m, with a position
//!   beside every pose.

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts::affordance::{DailyDensity, DensityParams};
use haunts::sim::{SimParams, Simulator};
use nalgebra::{Point2, Vector2};
use std::hint::black_box;

fn density(c: &mut Criterion) {
    let params = DensityParams::default();
    let mut group = c.benchmark_group("daily_density");
    group.sample_size(20);

    let sim = Simulator::new(SimParams::default()).expect("default simulation");
    let day = sim.day(3).expect("day simulates");
    let geometry = sim.geometry().with_resolution(0.1).expect("geometry");
    let scans: Vec<usize> = (0..day.scans.len()).collect();
    let people: Vec<Point2<f64>> = day.people.iter().flatten().map(|p| p.position).collect();
    eprintln!(
        "sim day: {} scans, {} positions, {}×{} cells",
        scans.len(),
        people.len(),
        geometry.width(),
        geometry.height()
    );
    for (name, stride) in [
        ("sim_day_every_scan_0.1", 1),
        ("sim_day_every_10th_scan_0.1", 10),
    ] {
        let used: Vec<(&_, &_)> = scans
            .iter()
            .step_by(stride)
            .map(|&i| (&day.scans[i], &day.poses[i]))
            .collect();
        let positions: Vec<Point2<f64>> = scans
            .iter()
            .step_by(stride)
            .flat_map(|&i| day.people[i].iter().map(|p| p.position))
            .collect();
        group.bench_function(name, |b| {
            b.iter(|| {
                black_box(
                    DailyDensity::from_day(
                        geometry,
                        &used,
                        |&(s, p)| (s, p),
                        positions.iter().copied(),
                        &params,
                    )
                    .expect("density"),
                )
            })
        });
    }

    let (log, geometry) = common::intel(0.05);
    let positions: Vec<Point2<f64>> = log
        .scans
        .iter()
        .map(|s| s.laser_pose * Point2::from(Vector2::new(1.0, 0.0)))
        .collect();
    group.bench_function("intel_0.05", |b| {
        b.iter(|| {
            black_box(
                DailyDensity::from_day(
                    geometry,
                    &log.scans,
                    |s| (&s.scan, &s.laser_pose),
                    positions.iter().copied(),
                    &params,
                )
                .expect("density"),
            )
        })
    });
    group.finish();
}

criterion_group!(benches, density);
criterion_main!(benches);
