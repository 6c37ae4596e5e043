//! The TA map of ETH `seq_eth` end to end (issue 7, item 4: target under 1 s): read
//! `obsmat.txt`, seed 002's dummy filter (α = 5 samples, β = 1 m, γ = 0.3 m/s, as
//! `examples/ta_map.rs`), a map bounding the kept samples with 2 m to spare, Algorithm 2
//! (3 m cells) and the GP (σ² = 1, ℓ = 2 m, σn² = 1; 8555 samples, so the sparse VFE GP on
//! 359 grid inducing points) with the posterior mean on every cell (fast grid mode).
//!
//! Timed: `end_to_end/0.1 m` and `end_to_end/0.2 m` (file to raster, at the two map
//! resolutions), and `fit_only/0.1 m` (`TaMap::fit` on trajectories already read and
//! filtered). Skipped with a notice when `../shared/data` is absent.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_affordance::ta::{TaMap, TaParams};
use haunts_occupancy::GridGeometry;
use haunts_tracking::track::dummy::{DummyFilterParams, filter_dummies};
use haunts_tracking::{EthOptions, Trajectory, read_eth};
use nalgebra::Point2;

fn data() -> Option<PathBuf> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/trajectories/eth/seq_eth/obsmat.txt");
    if path.exists() {
        Some(path)
    } else {
        eprintln!("skipping the ta_map bench: {} is absent", path.display());
        None
    }
}

/// Read, filter, bound: the kept trajectories and their map.
fn prepare(path: &Path, resolution: f64) -> (Vec<Trajectory>, GridGeometry) {
    let parsed = read_eth(path, &EthOptions::default()).expect("readable obsmat.txt");
    let filter = DummyFilterParams::default().with_min_samples(5);
    let kept = filter_dummies(parsed.records, &filter)
        .expect("valid trajectories")
        .kept;
    let points = kept
        .iter()
        .flat_map(|t| t.samples.iter().map(|s| s.1))
        .collect::<Vec<Point2<f64>>>();
    let geometry = GridGeometry::bounding(points, resolution, 2.0).expect("a map");
    (kept, geometry)
}

fn end_to_end(path: &Path, resolution: f64) -> TaMap {
    let (kept, geometry) = prepare(path, resolution);
    TaMap::fit(&kept, geometry, &TaParams::default()).expect("a TA map")
}

fn bench(c: &mut Criterion) {
    let Some(path) = data() else {
        return;
    };
    let ta = end_to_end(&path, 0.1);
    eprintln!(
        "ta_map: {} samples, sparse {}, {}×{} cells, fast-grid error {:?}",
        ta.training().len(),
        ta.model().is_sparse(),
        ta.geometry().width(),
        ta.geometry().height(),
        ta.grid_check()
    );
    let mut group = c.benchmark_group("ta_map_seq_eth");
    group.sample_size(10);
    for resolution in [0.1, 0.2] {
        group.bench_function(format!("end_to_end/{resolution} m"), |b| {
            b.iter(|| black_box(end_to_end(&path, resolution)))
        });
    }
    let (kept, geometry) = prepare(&path, 0.1);
    group.bench_function("fit_only/0.1 m", |b| {
        b.iter(|| black_box(TaMap::fit(&kept, geometry, &TaParams::default())))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
