//! One Gustafson–Kessel iteration of issue 7's workload: k = 30 clusters, m = 2, 50 000
//! hypertime points in 4-D. The peer is `benches/peers/gk_numpy.py` (same data, same initial
//! centres, same maths); `benches/peers/compare_gk.sh` runs both side by side.
//!
//! Data (SplitMix64, seed 7; the same bits in `gk_numpy.py`, whose docstring is the spec):
//! 12 places `(40·u, 20·u)` m, each with an hour of day `24·u`; then per point a place
//! `next_u64() mod 12` and four uniforms `u1..u4`: `r = √(−2 ln(1 − u1))`,
//! `x = px + 1.5·r·cos(τ·u2)`, `y = py + r·sin(τ·u2)`,
//! `t = hour + 1.5·√(−2 ln(1 − u3))·cos(τ·u4)` hours, point `(x, y, cos(τt/24), sin(τt/24))`.
//! Initial centres: rows `i·⌊n/k⌋`, `i = 0..k`; covariances start at the identity.
//!
//! Before timing, the bench runs 10 iterations from those centres and prints one line to
//! stderr, `gk check: {json}` (data sha256, objective and centres), which `compare_gk.sh`
//! compares with the peer's. Timed: one `GkRun::step` (memberships, prototypes, covariances)
//! on a run already 3 iterations in, with all cores and in a one-thread pool.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_affordance::hypertime::GkParams;
use sha2::{Digest, Sha256};

const N: usize = 50_000;
const DIM: usize = 4;
const K: usize = 30;
const SEED: u64 = 7;
const PLACES: usize = 12;
const CHECK_ITERATIONS: usize = 10;

/// SplitMix64 stream.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * 2f64.powi(-53)
    }
}

/// The `N × 4` points, flat and row-major (see the module docs).
fn dataset() -> Vec<f64> {
    use std::f64::consts::TAU;
    let mut rng = SplitMix64(SEED);
    let places: Vec<[f64; 3]> = (0..PLACES)
        .map(|_| {
            let px = 40.0 * rng.uniform();
            let py = 20.0 * rng.uniform();
            let hour = 24.0 * rng.uniform();
            [px, py, hour]
        })
        .collect();
    let mut data = Vec::with_capacity(N * DIM);
    for _ in 0..N {
        let [px, py, hour] = places[(rng.next_u64() % PLACES as u64) as usize];
        let (u1, u2, u3, u4) = (rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform());
        let r = (-2.0 * (1.0 - u1).ln()).sqrt();
        let x = px + 1.5 * r * (TAU * u2).cos();
        let y = py + r * (TAU * u2).sin();
        let t = hour + 1.5 * (-2.0 * (1.0 - u3).ln()).sqrt() * (TAU * u4).cos();
        let phase = TAU * t / 24.0;
        data.extend([x, y, phase.cos(), phase.sin()]);
    }
    data
}

/// Rows `i·⌊n/k⌋` of the data.
fn initial_centres(data: &[f64]) -> Vec<f64> {
    (0..K)
        .flat_map(|i| data[i * (N / K) * DIM..][..DIM].iter().copied())
        .collect()
}

fn sha256_le(values: &[f64]) -> String {
    let mut hash = Sha256::new();
    for v in values {
        hash.update(v.to_le_bytes());
    }
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

fn params() -> GkParams {
    GkParams::default().with_clusters(K).with_fuzzifier(2.0)
}

fn gk(c: &mut Criterion) {
    let data = dataset();
    let centres = initial_centres(&data);

    // The agreement check: CHECK_ITERATIONS iterations from the initial centres.
    let mut run = params()
        .start_from(&data, DIM, &centres)
        .expect("valid input");
    let mut objectives = Vec::new();
    for _ in 0..CHECK_ITERATIONS {
        run.step().expect("no degenerate covariance");
        objectives.push(run.objective());
    }
    let change = run.change();
    let clustering = run.into_clustering();
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:e}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    eprintln!(
        "gk check: {{\"n\":{N},\"dim\":{DIM},\"k\":{K},\"m\":2,\"seed\":{SEED},\
         \"data_sha256\":\"{}\",\"first_point\":[{}],\"iterations\":{CHECK_ITERATIONS},\
         \"objectives\":[{}],\"change\":{change:e},\"centres\":[{}],\"threads\":{}}}",
        sha256_le(&data),
        join(&data[..DIM]),
        join(&objectives),
        join(clustering.centres()),
        rayon::current_num_threads(),
    );

    let mut group = c.benchmark_group("gk");
    // A run 3 iterations in: covariances no longer the identity. Each timed step goes on
    // from the last (the cost of an iteration does not depend on where it starts).
    let started = || {
        let mut run = params()
            .start_from(&data, DIM, &centres)
            .expect("valid input");
        for _ in 0..3 {
            run.step().expect("no degenerate covariance");
        }
        run
    };
    let mut run = started();
    group.bench_function("iteration_k30_m2_n50000_d4", |b| {
        b.iter(|| black_box(run.step().expect("no degenerate covariance")))
    });
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let mut run = started();
    group.bench_function("iteration_k30_m2_n50000_d4_one_thread", |b| {
        one.install(|| b.iter(|| black_box(run.step().expect("no degenerate covariance"))))
    });
    group.finish();
}

criterion_group!(benches, gk);
criterion_main!(benches);
