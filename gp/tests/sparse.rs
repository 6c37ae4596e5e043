//! Sparse GPs against the exact GP: identical with Z = X, a bounded error with fewer inducing
//! points, and bad input.

use haunts_gp::{GpError, GpRegression, Inducing, Mean, Rbf, SparseGpRegression, SparseMethod};

mod common;
use common::uniform;

fn data(n: usize) -> (Vec<f64>, Vec<f64>) {
    common::wavy(11, n)
}

#[test]
fn inducing_points_at_the_data_reproduce_the_exact_gp() {
    let (x, y) = data(150);
    // ℓ = 1 keeps the noiseless Kuu = K(X, X) well enough conditioned for a fair comparison.
    let kernel = Rbf::new(1.0, 1.0).unwrap();
    let exact = GpRegression::new(kernel)
        .with_noise(0.01)
        .with_mean(Mean::Data)
        .fit(&x, 2, &y)
        .unwrap();
    let xs: Vec<f64> = uniform(13, 2 * 100).iter().map(|u| u * 10.0).collect();
    let e = exact.predict(&xs).unwrap();
    for method in [SparseMethod::Vfe, SparseMethod::Fitc] {
        let sparse = SparseGpRegression::new(kernel, Inducing::Given(x.clone()))
            .with_noise(0.01)
            .with_mean(Mean::Data)
            .with_method(method)
            .with_chunk_size(37)
            .fit(&x, 2, &y)
            .unwrap();
        let lml = exact.log_marginal_likelihood();
        // Kuu gets jitter (it is the noiseless K, badly conditioned): allow for it.
        assert!(
            (sparse.objective() - lml).abs() < 1e-4 * lml.abs(),
            "{method:?}: {} vs {lml}",
            sparse.objective()
        );
        let s = sparse.predict(&xs).unwrap();
        for j in 0..100 {
            assert!(
                (s.mean[j] - e.mean[j]).abs() < 1e-4,
                "{method:?} mean {j}: {} vs {}",
                s.mean[j],
                e.mean[j]
            );
            assert!(
                (s.variance[j] - e.variance[j]).abs() < 1e-4,
                "{method:?} var {j}"
            );
        }
    }
}

#[test]
fn fewer_inducing_points_give_a_bounded_error_and_a_lower_bound() {
    let (x, y) = data(2000);
    let kernel = Rbf::new(1.0, 2.0).unwrap();
    let exact = GpRegression::new(kernel)
        .with_noise(0.01)
        .fit(&x, 2, &y)
        .unwrap();
    let xs: Vec<f64> = uniform(14, 2 * 400).iter().map(|u| 0.5 + u * 9.0).collect();
    let e = exact.predict(&xs).unwrap();
    let mut previous = f64::NEG_INFINITY;
    for m in [25, 64, 144] {
        let sparse = SparseGpRegression::new(kernel, Inducing::kmeans(m))
            .with_noise(0.01)
            .fit(&x, 2, &y)
            .unwrap();
        // VFE is a lower bound of the exact log likelihood that tightens with m.
        assert!(sparse.objective() <= exact.log_marginal_likelihood() + 1e-6);
        assert!(sparse.objective() > previous);
        previous = sparse.objective();
        let s = sparse.predict(&xs).unwrap();
        let mean_err = s
            .mean
            .iter()
            .zip(&e.mean)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let var_err = s
            .variance
            .iter()
            .zip(&e.variance)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "m = {m}: max |mean error| {mean_err:.2e}, max |variance error| {var_err:.2e}, bound gap {:.3e}",
            exact.log_marginal_likelihood() - sparse.objective()
        );
        if m == 144 {
            assert!(
                mean_err < 2e-3 && var_err < 2e-3,
                "m = {m}: {mean_err} {var_err}"
            );
        }
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let (x, y) = data(50);
    let gp = SparseGpRegression::new(
        Rbf::new(1.0, 1.0).unwrap(),
        Inducing::Given(vec![0.0, 0.0, 1.0]),
    );
    assert!(matches!(
        gp.fit(&x, 2, &y),
        Err(GpError::BadPointArray { .. })
    ));
    let gp =
        SparseGpRegression::new(Rbf::new(1.0, 1.0).unwrap(), Inducing::kmeans(10)).with_noise(0.0);
    assert!(matches!(
        gp.fit(&x, 2, &y),
        Err(GpError::InvalidParameter(haunts_core::InvalidParameter {
            name: "noise",
            ..
        }))
    ));
    let mut bad = x.clone();
    bad[7] = f64::NAN;
    let gp = SparseGpRegression::new(Rbf::new(1.0, 1.0).unwrap(), Inducing::kmeans(10));
    assert!(matches!(
        gp.fit(&bad, 2, &y),
        Err(GpError::NonFiniteInput { index: 3 })
    ));
    // Duplicate inducing points are handled by the jitter.
    let z = vec![1.0, 1.0, 1.0, 1.0, 5.0, 5.0];
    let fitted = SparseGpRegression::new(Rbf::new(1.0, 1.0).unwrap(), Inducing::Given(z))
        .fit(&x, 2, &y)
        .unwrap();
    assert!(fitted.jitter() > 0.0);
    assert!(fitted.predict(&[1.0, 1.0]).unwrap().variance[0] >= 0.0);
}
