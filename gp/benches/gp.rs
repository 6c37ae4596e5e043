//! The GP benchmarks of issue 3: RBF (σ² = 1, ℓ = 2), σn² = 0.01, 2-D inputs, n = 5000,
//! predictions on a 200 × 200 grid; the peer side (scikit-learn, GPy) is
//! `benches/peers/gp_peer_bench.py` on the same data (`benches/peers/compare_gp.sh` runs both).
//!
//! Each benchmark prints to stderr what it computed (log likelihood, checksums, errors) so
//! that the comparison checks both sides answer the same question.

use std::sync::Once;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_gp::{GpRegression, GridMode, Inducing, OptimiseOptions, Rbf, SparseGpRegression};

#[allow(dead_code)]
mod common;

fn fit(c: &mut Criterion) {
    let (x, y) = common::dataset(5000);
    let gp = GpRegression::new(Rbf::new(1.0, 2.0).unwrap()).with_noise(0.01);
    let fitted = gp.fit(&x, 2, &y).unwrap();
    eprintln!(
        "gp fit: n=5000 lml={:.10} jitter={}",
        fitted.log_marginal_likelihood(),
        fitted.jitter()
    );
    let mut group = c.benchmark_group("gp_fit");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    group.bench_function("n5000_fixed", |b| b.iter(|| gp.fit(&x, 2, &y).unwrap()));
    group.finish();
}

fn optimise(c: &mut Criterion) {
    let (x, y) = common::dataset(5000);
    let start = GpRegression::new(Rbf::new(0.5, 1.0).unwrap()).with_noise(0.1);
    let options = OptimiseOptions::default();
    let mut group = c.benchmark_group("gp_fit");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(60));
    let once = Once::new();
    group.bench_function("n5000_optimised", |b| {
        once.call_once(|| {
            let t = std::time::Instant::now();
            let (_, report) = start.fit_optimised(&x, 2, &y, &options).unwrap();
            eprintln!(
                "gp opt: n=5000 lml={:.10} theta={:?} full_evaluations={} subset_evaluations={} seconds={:.2}",
                report.log_marginal_likelihood,
                report.log_params,
                report.full_evaluations,
                report.subset_evaluations,
                t.elapsed().as_secs_f64()
            );
        });
        b.iter(|| start.fit_optimised(&x, 2, &y, &options).unwrap())
    });
    group.finish();
}

fn predict(c: &mut Criterion) {
    let (x, y) = common::dataset(5000);
    let gp = GpRegression::new(Rbf::new(1.0, 2.0).unwrap())
        .with_noise(0.01)
        .fit(&x, 2, &y)
        .unwrap();
    let grid = common::grid();
    let once = Once::new();
    let report = || {
        once.call_once(|| {
            let exact = gp.predict_grid(&grid, GridMode::Exact).unwrap();
            let fast = gp.predict_grid(&grid, GridMode::Fast { tolerance: 1e-10, check_points: 0 }).unwrap();
            let max_mean = exact.mean.iter().zip(&fast.mean).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            let max_var = exact.variance.iter().zip(&fast.variance).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            // Peak resident memory of this process so far (Linux), an upper bound of the
            // prediction's.
            let peak_mb = std::fs::read_to_string("/proc/self/status")
                .ok()
                .and_then(|s| s.lines().find(|l| l.starts_with("VmHWM:")).map(str::to_owned))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse::<f64>().ok()))
                .map_or(f64::NAN, |kb| kb / 1024.0);
            eprintln!(
                "gp predict: sum_mean={:.12e} sum_var={:.12e} fast_nodes={} fast_max_mean_error={max_mean:.3e} fast_max_variance_error={max_var:.3e} peak_rss_mb={peak_mb:.0} (prior variance 1)",
                exact.mean.iter().sum::<f64>(),
                exact.variance.iter().sum::<f64>(),
                fast.nodes.map_or("-".to_owned(), |n| format!("{}x{}", n[0], n[1]))
            );
        })
    };
    let mut group = c.benchmark_group("gp_predict");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(30));
    group.bench_function("grid200_exact", |b| {
        report();
        b.iter(|| gp.predict_grid(&grid, GridMode::Exact).unwrap())
    });
    group.bench_function("grid200_fast", |b| {
        report();
        b.iter(|| {
            gp.predict_grid(
                &grid,
                GridMode::Fast {
                    tolerance: 1e-10,
                    check_points: 0,
                },
            )
            .unwrap()
        })
    });
    group.finish();
}

fn sparse(c: &mut Criterion) {
    let (x, y) = common::dataset(1_000_000);
    let grid = common::grid();
    let run = |inducing: &[f64]| {
        let gp = SparseGpRegression::new(
            Rbf::new(1.0, 2.0).unwrap(),
            Inducing::Given(inducing.to_vec()),
        )
        .with_noise(0.01);
        let fitted = gp.fit(&x, 2, &y).unwrap();
        let p = fitted.predict_grid(&grid, GridMode::Exact).unwrap();
        (fitted, p)
    };
    let mut group = c.benchmark_group("gp_sparse");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(60));
    group.bench_function("n1M_m500_fit_and_grid200", |b| {
        let inducing = Inducing::kmeans(500).points(&x, 2).unwrap();
        let (fitted, p) = run(&inducing);
        eprintln!(
            "gp sparse: n=1000000 m=500 vfe_bound={:.6} sum_mean={:.6e} jitter={}",
            fitted.objective(),
            p.mean.iter().sum::<f64>(),
            fitted.jitter()
        );
        b.iter(|| run(&inducing))
    });
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    group.bench_function("kmeans_m500_of_1M", |b| {
        b.iter(|| Inducing::kmeans(500).points(&x, 2).unwrap())
    });
    group.finish();
}

/// Options of the sparse optimisation bench: warm starts on subsets of 2000, 5000, 12 500 and
/// 31 250 points, then the Newton polish on all 10⁶ points, capped at 3 full passes.
fn sparse_options() -> OptimiseOptions {
    {
        let mut p = OptimiseOptions::default();
        p.warm_start_subset = 2000;
        p.warm_start_max = 40_000;
        p.polish_evaluations = 3;
        p
    }
}

/// Optimising the VFE bound's hyperparameters (σ², ℓ, σn²) on 10⁶ points with 500 k-means++
/// inducing points held fixed, from σ² = 0.5, ℓ = 1, σn² = 0.1 (the exact bench's start).
/// With `HAUNTS_GP_SPARSE_DIRECT=1` it first prints, once, the bound reached by L-BFGS on
/// all the data from the start (no warm starts), the reference for the staged shortcut (slow:
/// it took 140 full passes at n = 10⁵; at 10⁶ a pass costs ≈ 10 s, so half an hour or more).
fn sparse_optimise(c: &mut Criterion) {
    let (x, y) = common::dataset(1_000_000);
    let inducing = Inducing::kmeans(500).points(&x, 2).unwrap();
    let start = SparseGpRegression::new(Rbf::new(0.5, 1.0).unwrap(), Inducing::Given(inducing))
        .with_noise(0.1);
    let options = sparse_options();
    let once = Once::new();
    let mut group = c.benchmark_group("gp_sparse");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(60));
    group.bench_function("n1M_m500_optimise", |b| {
        once.call_once(|| {
            if std::env::var_os("HAUNTS_GP_SPARSE_DIRECT").is_some() {
                let direct = { let mut p = OptimiseOptions::default(); p.warm_start_subset = 0; p };
                let t = std::time::Instant::now();
                let (_, report) = start.fit_optimised(&x, 2, &y, &direct).unwrap();
                eprintln!(
                    "gp sparse opt direct: n=1000000 m=500 bound={:.6} theta={:?} full_evaluations={} seconds={:.1}",
                    report.log_marginal_likelihood,
                    report.log_params,
                    report.full_evaluations,
                    t.elapsed().as_secs_f64()
                );
            }
            let t = std::time::Instant::now();
            let (gp, report) = start.fit_optimised(&x, 2, &y, &options).unwrap();
            eprintln!(
                "gp sparse opt: n=1000000 m=500 bound={:.6} theta={:?} full_evaluations={} subset_evaluations={} jitter={} seconds={:.1}",
                report.log_marginal_likelihood,
                report.log_params,
                report.full_evaluations,
                report.subset_evaluations,
                gp.jitter(),
                t.elapsed().as_secs_f64()
            );
        });
        b.iter(|| start.fit_optimised(&x, 2, &y, &options).unwrap())
    });
    group.finish();
}

criterion_group!(benches, fit, optimise, predict, sparse, sparse_optimise);
criterion_main!(benches);
