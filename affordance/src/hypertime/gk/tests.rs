//! The fused, lane-wise iteration against a plain one written from the textbook formulas.

use nalgebra::{DMatrix, DVector};

use super::{GkParams, Regularisation};

/// SplitMix64 uniforms in [0, 1).
struct SplitMix64(u64);

impl SplitMix64 {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 * 2f64.powi(-53)
    }
}

/// `n` points in `dim` dimensions around a few stretched groups.
fn groups(n: usize, dim: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .flat_map(|j| (0..dim).map(move |a| (j, a)))
        .map(|(j, a)| {
            let group = (j % 5) as f64;
            group * (1.0 + a as f64) + (1.0 + (j % 3) as f64 * a as f64) * (rng.uniform() - 0.5)
        })
        .collect()
}

/// The state of the plain iteration.
struct Plain {
    centres: Vec<DVector<f64>>,
    covariances: Vec<DMatrix<f64>>,
    memberships: Vec<Vec<f64>>,
    objective: f64,
}

/// One textbook iteration, point by point and cluster by cluster.
fn plain_step(state: &mut Plain, x: &[DVector<f64>], params: &GkParams, nu: f64) {
    let (k, m, dim) = (params.clusters, params.fuzzifier, x[0].len());
    let reg = params.regularisation;
    let a: Vec<DMatrix<f64>> = state
        .covariances
        .iter()
        .map(|f| {
            let inverse = f
                .clone()
                .try_inverse()
                .expect("regularised covariances invert");
            inverse * (params.volume * f.determinant()).powf(1.0 / dim as f64)
        })
        .collect();
    state.objective = 0.0;
    for (xj, u) in x.iter().zip(&mut state.memberships) {
        let d2: Vec<f64> = (0..k)
            .map(|i| {
                let d = xj - &state.centres[i];
                (d.transpose() * &a[i] * &d)[(0, 0)].max(0.0)
            })
            .collect();
        let zeros = d2.iter().filter(|d| **d == 0.0).count();
        for i in 0..k {
            u[i] = if zeros > 0 {
                if d2[i] == 0.0 {
                    1.0 / zeros as f64
                } else {
                    0.0
                }
            } else {
                1.0 / (0..k)
                    .map(|l| (d2[i] / d2[l]).powf(1.0 / (m - 1.0)))
                    .sum::<f64>()
            };
            state.objective += u[i].powf(m) * d2[i];
        }
    }
    for i in 0..k {
        let w: Vec<f64> = state.memberships.iter().map(|u| u[i].powf(m)).collect();
        let total: f64 = w.iter().sum();
        let centre = x
            .iter()
            .zip(&w)
            .fold(DVector::zeros(dim), |s, (xj, w)| s + xj * *w)
            / total;
        let f = x
            .iter()
            .zip(&w)
            .fold(DMatrix::zeros(dim, dim), |s, (xj, w)| {
                s + (xj - &centre) * (xj - &centre).transpose() * *w
            })
            / total;
        let f = f * (1.0 - reg.identity_blend)
            + DMatrix::identity(dim, dim) * (reg.identity_blend * nu);
        let eig = f.symmetric_eigen();
        let floor = (eig.eigenvalues.max() / reg.max_condition).max(reg.min_eigenvalue);
        let values = eig.eigenvalues.map(|l| l.max(floor));
        state.centres[i] = centre;
        state.covariances[i] =
            &eig.eigenvectors * DMatrix::from_diagonal(&values) * eig.eigenvectors.transpose();
    }
}

/// `det(F₀)^{1/d}` of the whole data set, plainly.
fn plain_nu(x: &[DVector<f64>]) -> f64 {
    let dim = x[0].len();
    let mean = x.iter().fold(DVector::zeros(dim), |a, b| a + b) / x.len() as f64;
    let f0 = x.iter().fold(DMatrix::zeros(dim, dim), |a, b| {
        a + (b - &mean) * (b - &mean).transpose()
    }) / x.len() as f64;
    f0.determinant().powf(1.0 / dim as f64)
}

/// Runs both iterations side by side from the same centres (data rows, so the first
/// iteration meets points on prototypes) and compares them after every iteration.
fn check_against_plain(n: usize, dim: usize, params: GkParams, iterations: usize) {
    let data = groups(n, dim, 7 + dim as u64);
    let k = params.clusters;
    let centres: Vec<f64> = (0..k)
        .flat_map(|i| data[i * (n / k) * dim..][..dim].to_vec())
        .collect();
    let mut fast = params
        .start_from(&data, dim, &centres)
        .expect("valid input");
    let x: Vec<DVector<f64>> = data.chunks(dim).map(DVector::from_column_slice).collect();
    let nu = plain_nu(&x);
    let mut plain = Plain {
        centres: centres
            .chunks(dim)
            .map(DVector::from_column_slice)
            .collect(),
        covariances: vec![DMatrix::identity(dim, dim); k],
        memberships: vec![vec![0.0; k]; n],
        objective: f64::NAN,
    };
    let close = |a: f64, b: f64, what: &str, it: usize| {
        assert!(
            (a - b).abs() <= 1e-10 * (1.0 + b.abs()),
            "{what} after {it} iterations: {a} vs {b} (dim {dim}, {k} clusters)"
        );
    };
    for it in 1..=iterations {
        fast.step().expect("no degenerate covariance");
        plain_step(&mut plain, &x, &params, nu);
        close(fast.objective(), plain.objective, "objective", it);
        for (j, u) in plain.memberships.iter().enumerate() {
            for (i, u) in u.iter().enumerate() {
                close(fast.memberships[j * k + i], *u, "membership", it);
            }
        }
        for i in 0..k {
            for a in 0..dim {
                close(fast.centres[i * dim + a], plain.centres[i][a], "centre", it);
            }
            for (f, g) in fast.covariances[i].iter().zip(plain.covariances[i].iter()) {
                close(*f, *g, "covariance", it);
            }
        }
    }
}

#[test]
fn four_dimensions_m2_equals_the_plain_iteration() {
    // Several blocks, and a number of clusters that leaves lanes unused.
    let params = GkParams::default().with_clusters(7);
    check_against_plain(3 * super::BLOCK + 77, 4, params, 6);
}

#[test]
fn any_dimension_fuzzifier_and_blending_equal_the_plain_iteration() {
    let params = GkParams::default()
        .with_clusters(5)
        .with_fuzzifier(1.6)
        .with_volume(2.0)
        .with_regularisation(Regularisation {
            identity_blend: 0.1,
            ..Regularisation::default()
        });
    check_against_plain(700, 3, params, 5);
    check_against_plain(300, 6, params.with_clusters(9), 4);
}
