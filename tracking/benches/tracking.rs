//! One scan's leg detection (geometric; learned: leg_tracker's clustering, every cluster's
//! features and the shipped forest's vote, then pairing), one Kalman step and one particle-filter step (500 particles per
//! person). Inputs are built outside the timed loops.
#![allow(clippy::unwrap_used, missing_docs)]

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use haunts_occupancy::LaserScan;
use haunts_tracking::detect::features::cluster_features;
use haunts_tracking::detect::forest::LegForest;
use haunts_tracking::detect::{ClusterParams, clusters};
use haunts_tracking::detect::{
    Detection, Detector, ForestDetector, LegDetector, LegDetectorParams,
};
use haunts_tracking::read_scans;
use haunts_tracking::track::Tracker;
use haunts_tracking::track::kalman::{KalmanParams, KalmanTracker};
use haunts_tracking::track::particle::{ParticleParams, ParticleTracker};
use nalgebra::Point2;

/// A real scan (the one with most detections among the first 200 of the `leg_tracker` bag)
/// or, without the data, a synthetic 768-beam scan with five pairs of legs.
fn scan() -> LaserScan {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/leg_tracker/general_tracking_moving_1/scans.txt");
    if path.exists() {
        let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
        let scans = read_scans(&path).unwrap().records;
        if let Some(s) = scans
            .into_iter()
            .take(200)
            .max_by_key(|s| detector.detect(&s.scan).map_or(0, |d| d.len()))
        {
            return s.scan;
        }
    }
    eprintln!("no real scan: benching a synthetic one");
    let inc = 270f64.to_radians() / 768.0;
    let min = -135f64.to_radians();
    let ranges = (0..768)
        .map(|i| {
            let a = min + i as f64 * inc;
            let mut r = 6.0 / a.cos().abs().max(0.3);
            for k in 0..5 {
                for side in [-0.15, 0.15] {
                    let c = nalgebra::Vector2::new(2.0 + k as f64 * 0.4, -2.0 + k as f64 + side);
                    let b = a.cos() * c.x + a.sin() * c.y;
                    let disc = b * b - c.norm_squared() + 0.0036;
                    if disc >= 0.0 {
                        r = r.min(b - disc.sqrt());
                    }
                }
            }
            r
        })
        .collect();
    LaserScan::new(0.0, min, inc, 0.02, 11.0, ranges, vec![]).unwrap()
}

/// `people` walkers seen at 7.5 Hz, at step `k`.
fn people(people: usize, k: usize) -> Vec<Detection> {
    let t = k as f64 / 7.5;
    (0..people)
        .map(|p| Detection::isotropic(Point2::new(-3.0 + 1.2 * t, p as f64 * 1.5), 0.1))
        .collect()
}

/// A tracker warmed up on `n` people for 3 s, and the next time and detections.
fn warmed<T: Tracker>(mut tracker: T, n: usize) -> (T, f64, Vec<Detection>) {
    for k in 0..23 {
        tracker.update(k as f64 / 7.5, &people(n, k)).unwrap();
    }
    assert_eq!(tracker.tracks().len(), n);
    (tracker, 23.0 / 7.5, people(n, 23))
}

fn benches(c: &mut Criterion) {
    let scan = scan();
    let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
    c.bench_function("leg detection, one scan", |b| {
        b.iter(|| detector.detect(black_box(&scan)).unwrap())
    });

    let forest = LegForest::shipped().unwrap();
    let found = clusters(&scan, &ClusterParams::default()).unwrap();
    eprintln!("{} clusters in the benched scan", found.len());
    c.bench_function("features + forest of every cluster, one scan", |b| {
        b.iter(|| {
            black_box(&found)
                .iter()
                .map(|c| forest.probability(&cluster_features(&scan, c)))
                .sum::<f64>()
        })
    });
    let learned = ForestDetector::shipped().unwrap();
    c.bench_function("learned leg detection, one scan", |b| {
        b.iter(|| learned.detect(black_box(&scan)).unwrap())
    });

    let (kf, t, dets) = warmed(KalmanTracker::new(KalmanParams::default()).unwrap(), 5);
    c.bench_function("kalman step, 5 people", |b| {
        b.iter_batched(
            || kf.clone(),
            |mut kf| {
                kf.update(t, black_box(&dets)).unwrap();
                kf
            },
            BatchSize::SmallInput,
        )
    });

    let (pf, t, dets) = warmed(ParticleTracker::new(ParticleParams::default()).unwrap(), 5);
    c.bench_function("particle step, 5 people x 500 particles", |b| {
        b.iter_batched(
            || pf.clone(),
            |mut pf| {
                pf.update(t, black_box(&dets)).unwrap();
                pf
            },
            BatchSize::SmallInput,
        )
    });
}

criterion_group!(tracking, benches);
criterion_main!(tracking);
