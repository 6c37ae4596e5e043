//! The data of the GP benchmarks: exactly what `benches/peers/gp_peer_bench.py` generates
//! (SplitMix64, seed 3, four draws per point; see that script's header).

/// SplitMix64 stream.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * 2f64.powi(-53)
    }
}

/// n points uniform in [0, 20]², y = sin(x0/2)·cos(x1/3) + 0.1·N(0, 1) (Box–Muller, cosine).
pub fn dataset(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut rng = SplitMix64(3);
    let mut x = Vec::with_capacity(2 * n);
    let mut y = Vec::with_capacity(n);
    for _ in 0..n {
        let x0 = 20.0 * rng.uniform();
        let x1 = 20.0 * rng.uniform();
        let u1 = rng.uniform();
        let u2 = rng.uniform();
        let z = (-2.0 * (1.0 - u1).ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
        x.extend([x0, x1]);
        y.push((x0 / 2.0).sin() * (x1 / 3.0).cos() + 0.1 * z);
    }
    (x, y)
}

/// The 200 × 200 grid of cell centres over [0, 20]², i fastest.
pub fn grid() -> haunts_gp::Grid2 {
    haunts_gp::Grid2 {
        origin: [0.05, 0.05],
        step: [0.1, 0.1],
        shape: [200, 200],
    }
}
