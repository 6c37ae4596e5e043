//! Helpers shared by the integration tests.

/// Deterministic pseudo-random numbers in [0, 1) (SplitMix64).
pub fn uniform(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        })
        .collect()
}

/// `n` points uniform on [0, 10]² (stream `seed`) and a smooth surface with noise of width 0.1
/// (stream `seed + 1`): `sin(x/2)·cos(y/3) + 0.1·(u − 0.5)`.
#[allow(dead_code)]
pub fn wavy(seed: u64, n: usize) -> (Vec<f64>, Vec<f64>) {
    let x: Vec<f64> = uniform(seed, 2 * n).iter().map(|u| u * 10.0).collect();
    let e = uniform(seed + 1, n);
    let y = x
        .chunks_exact(2)
        .zip(&e)
        .map(|(p, e)| (p[0] / 2.0).sin() * (p[1] / 3.0).cos() + 0.1 * (e - 0.5))
        .collect();
    (x, y)
}
