//! Exact GP regression against a plain nalgebra implementation of Rasmussen & Williams
//! Algorithm 2.1, gradients against finite differences, and bad or degenerate input.

use approx::assert_relative_eq;
use haunts_gp::{
    Constrained, GpError, GpRegression, JitterPolicy, Kernel, Matern52, Mean, OptimiseOptions, Rbf,
    RbfArd, Sum, White,
};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

mod common;
use common::uniform;

fn data(seed: u64, n: usize, dim: usize) -> (Vec<f64>, Vec<f64>) {
    let x: Vec<f64> = uniform(seed, n * dim).iter().map(|u| u * 10.0).collect();
    let e = uniform(seed + 1, n);
    let y = x
        .chunks_exact(dim)
        .zip(&e)
        .map(|(p, e)| (p[0] * 0.7).sin() + p.iter().sum::<f64>() * 0.1 + 0.1 * (e - 0.5))
        .collect();
    (x, y)
}

/// The textbook computation with nalgebra: (mean, variance, lml).
fn reference(
    kernel: &dyn Kernel,
    noise: f64,
    offset: f64,
    x: &[f64],
    dim: usize,
    y: &[f64],
    xs: &[f64],
) -> (Vec<f64>, Vec<f64>, f64) {
    let n = y.len();
    let pt = |a: &[f64], i: usize| a[i * dim..(i + 1) * dim].to_vec();
    let k = DMatrix::from_fn(n, n, |i, j| {
        kernel.value(&pt(x, i), &pt(x, j)) + if i == j { noise } else { 0.0 }
    });
    let chol = k.cholesky().unwrap();
    let r = DVector::from_iterator(n, y.iter().map(|v| v - offset));
    let alpha = chol.solve(&r);
    let l = chol.l();
    let lml = -0.5 * r.dot(&alpha)
        - l.diagonal().iter().map(|d| d.ln()).sum::<f64>()
        - 0.5 * n as f64 * (2.0 * std::f64::consts::PI).ln();
    let m = xs.len() / dim;
    let mut mean = Vec::new();
    let mut var = Vec::new();
    for j in 0..m {
        let p = pt(xs, j);
        let ks = DVector::from_fn(n, |i, _| kernel.value(&pt(x, i), &p));
        mean.push(offset + ks.dot(&alpha));
        let v = l.solve_lower_triangular(&ks).unwrap();
        var.push(kernel.value(&p, &p) - v.norm_squared());
    }
    (mean, var, lml)
}

#[test]
fn matches_the_textbook_algorithm() {
    let (x, y) = data(1, 120, 2);
    let xs: Vec<f64> = uniform(9, 2 * 300).iter().map(|u| u * 12.0 - 1.0).collect();
    let kernels: Vec<Box<dyn Kernel>> = vec![
        Box::new(Rbf::new(1.3, 1.7).unwrap()),
        Box::new(RbfArd::new(0.8, &[2.0, 0.9]).unwrap()),
        Box::new(
            Sum::new(
                Box::new(Matern52::new(0.5, 3.0).unwrap()),
                Box::new(Rbf::new(0.2, 0.5).unwrap()),
            )
            .unwrap(),
        ),
    ];
    for kernel in kernels {
        for (mean, offset) in [(Mean::Zero, 0.0), (Mean::Constant(0.4), 0.4)] {
            // A chunk of 7 test points exercises the blocked prediction.
            let gp = GpRegression::from_box(kernel.clone())
                .with_noise(0.05)
                .with_mean(mean)
                .with_chunk_size(7)
                .fit(&x, 2, &y)
                .unwrap();
            let (m, v, lml) = reference(kernel.as_ref(), 0.05, offset, &x, 2, &y, &xs);
            let p = gp.predict(&xs).unwrap();
            assert_eq!(gp.jitter(), 0.0);
            assert_relative_eq!(gp.log_marginal_likelihood(), lml, max_relative = 1e-10);
            for j in 0..m.len() {
                assert_relative_eq!(p.mean[j], m[j], epsilon = 1e-9, max_relative = 1e-9);
                assert_relative_eq!(
                    p.variance[j],
                    v[j].max(0.0),
                    epsilon = 1e-10,
                    max_relative = 1e-8
                );
            }
            assert_eq!(gp.predict_mean(&xs).unwrap(), p.mean);
            assert_eq!(gp.predict_variance(&xs).unwrap(), p.variance);
        }
    }
}

#[test]
fn data_mean_is_the_centred_fit_plus_the_mean() {
    let (x, y) = data(2, 60, 1);
    let shifted: Vec<f64> = y.iter().map(|v| v + 5.0).collect();
    let mean = shifted.iter().sum::<f64>() / 60.0;
    let xs = [0.5, 3.3, 9.9, 14.0];
    let k = Rbf::new(1.0, 1.2).unwrap();
    let a = GpRegression::new(k)
        .with_noise(0.01)
        .with_mean(Mean::Data)
        .fit(&x, 1, &shifted)
        .unwrap();
    let b = GpRegression::new(k)
        .with_noise(0.01)
        .with_mean(Mean::Constant(mean))
        .fit(&x, 1, &shifted)
        .unwrap();
    assert_relative_eq!(a.prior_mean(), mean, max_relative = 1e-14);
    assert_eq!(a.predict(&xs).unwrap(), b.predict(&xs).unwrap());
    // Far from the data the mean returns to the data mean, the variance to the prior.
    let far = a.predict(&[1e3]).unwrap();
    assert_relative_eq!(far.mean[0], mean, max_relative = 1e-12);
    assert_relative_eq!(far.variance[0], 1.0, max_relative = 1e-12);
}

/// Central differences of the log marginal likelihood in log space.
fn finite_difference(gp: &GpRegression, x: &[f64], dim: usize, y: &[f64]) -> Vec<f64> {
    let theta = gp.kernel().log_params();
    let h = 1e-5;
    let lml = |theta: &[f64], log_noise: f64| {
        let mut k = gp.kernel().clone_box();
        k.set_log_params(theta).unwrap();
        GpRegression::from_box(k)
            .with_noise(log_noise.exp())
            .fit(x, dim, y)
            .unwrap()
            .log_marginal_likelihood()
    };
    let ln = gp.noise_variance().ln();
    let mut out = Vec::new();
    for j in 0..theta.len() {
        let (mut up, mut down) = (theta.clone(), theta.clone());
        up[j] += h;
        down[j] -= h;
        out.push((lml(&up, ln) - lml(&down, ln)) / (2.0 * h));
    }
    out.push((lml(&theta, ln + h) - lml(&theta, ln - h)) / (2.0 * h));
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn gradient_matches_finite_differences(
        log_var in -1.0f64..1.0,
        log_l1 in -0.5f64..1.5,
        log_l2 in -0.5f64..1.5,
        log_noise in -4.0f64..-0.5,
        log_w in -3.0f64..-1.0,
        seed in 0u64..1000,
    ) {
        let (x, y) = data(seed, 40, 2);
        let kernel = Sum::new(
            Box::new(RbfArd::new(log_var.exp(), &[log_l1.exp(), log_l2.exp()]).unwrap()),
            Box::new(
                Sum::new(
                    Box::new(Matern52::new(0.3, log_l2.exp()).unwrap()),
                    Box::new(White::new(log_w.exp()).unwrap()),
                )
                .unwrap(),
            ),
        )
        .unwrap();
        let gp = GpRegression::new(kernel).with_noise(log_noise.exp());
        let fitted = gp.fit(&x, 2, &y).unwrap();
        let g = fitted.log_marginal_likelihood_gradient();
        let fd = finite_difference(&gp, &x, 2, &y);
        prop_assert_eq!(g.len(), fd.len());
        for (a, b) in g.iter().zip(&fd) {
            prop_assert!((a - b).abs() <= 1e-5 * (1.0 + b.abs()), "analytic {a} vs numeric {b}");
        }
    }
}

#[test]
fn optimisation_reaches_a_stationary_point_that_beats_the_start() {
    let (x, y) = data(3, 80, 2);
    let start = GpRegression::new(Rbf::new(0.5, 0.3).unwrap()).with_noise(0.5);
    let before = start.fit(&x, 2, &y).unwrap().log_marginal_likelihood();
    let options = {
        let mut p = OptimiseOptions::default();
        p.restarts = 2;
        p.seed = 7;
        p
    };
    let (gp, report) = start.fit_optimised(&x, 2, &y, &options).unwrap();
    assert!(
        report.log_marginal_likelihood > before + 10.0,
        "{before} -> {report:?}"
    );
    let g = gp.log_marginal_likelihood_gradient();
    assert!(
        g.iter().all(|v| v.abs() < 1e-3),
        "gradient at the optimum {g:?}"
    );
    // Deterministic for a seed.
    let (_, again) = start.fit_optimised(&x, 2, &y, &options).unwrap();
    assert_eq!(report, again);
}

#[test]
fn warm_start_on_a_subset_reaches_the_full_optimum() {
    let (x, y) = data(4, 500, 2);
    let start = GpRegression::new(Rbf::new(0.5, 1.0).unwrap()).with_noise(0.1);
    let direct = {
        let mut p = OptimiseOptions::default();
        p.warm_start_subset = 0;
        p
    };
    let warm = {
        let mut p = OptimiseOptions::default();
        p.warm_start_subset = 100;
        p
    };
    let (_, a) = start.fit_optimised(&x, 2, &y, &direct).unwrap();
    let (_, b) = start.fit_optimised(&x, 2, &y, &warm).unwrap();
    assert!(b.subset_evaluations > 0);
    assert!(
        b.log_marginal_likelihood >= a.log_marginal_likelihood - 1e-6,
        "{a:?} {b:?}"
    );
    assert!(b.full_evaluations < a.full_evaluations, "{a:?} {b:?}");
}

/// The default stages (L-BFGS on 400 points, Newton on 1000 with the Hessian extrapolated
/// from 160 and 400) and the Newton polish on all the data reach the optimum of L-BFGS on all
/// the data, for an ARD kernel, in fewer full-data fits; the model returned is a fit of the
/// polish (its likelihood is the report's).
#[test]
fn staged_newton_reaches_the_direct_optimum() {
    let (x, y) = data(21, 2000, 2);
    let start = GpRegression::new(RbfArd::new(0.5, &[1.0, 2.0]).unwrap()).with_noise(0.1);
    let direct = {
        let mut p = OptimiseOptions::default();
        p.warm_start_subset = 0;
        p
    };
    let (_, a) = start.fit_optimised(&x, 2, &y, &direct).unwrap();
    let (gp, b) = start
        .fit_optimised(&x, 2, &y, &OptimiseOptions::default())
        .unwrap();
    eprintln!("direct {a:?}\nstaged {b:?}");
    assert!(b.subset_evaluations > 0);
    assert!(
        b.log_marginal_likelihood >= a.log_marginal_likelihood - 1e-6,
        "{a:?} {b:?}"
    );
    assert!(b.full_evaluations < a.full_evaluations, "{a:?} {b:?}");
    assert_eq!(gp.log_marginal_likelihood(), b.log_marginal_likelihood);
    let g = gp.log_marginal_likelihood_gradient();
    assert!(g.iter().all(|v| v.abs() < 1e-3), "gradient {g:?}");
}

/// Warm starts with restarts: every start goes through the stages, and the result is the
/// same for the same seed.
#[test]
fn staged_optimisation_with_restarts_is_deterministic() {
    let (x, y) = data(22, 900, 2);
    let start = GpRegression::new(Rbf::new(0.5, 1.0).unwrap()).with_noise(0.1);
    let options = {
        let mut p = OptimiseOptions::default();
        p.restarts = 1;
        p.seed = 5;
        p
    };
    let (gp, a) = start.fit_optimised(&x, 2, &y, &options).unwrap();
    assert!(a.subset_evaluations > 0 && a.runs == 2, "{a:?}");
    assert_eq!(gp.log_marginal_likelihood(), a.log_marginal_likelihood);
    let (_, b) = start.fit_optimised(&x, 2, &y, &options).unwrap();
    assert_eq!(a, b);
}

#[test]
fn duplicate_points_without_noise_get_reported_jitter() {
    let x = [0.0, 1.0, 1.0, 2.0];
    let y = [0.0, 1.0, 1.0, 0.5];
    let gp = GpRegression::new(Rbf::new(1.0, 1.0).unwrap()).with_noise(0.0);
    let fitted = gp.fit(&x, 1, &y).unwrap();
    assert!(fitted.jitter() > 0.0 && fitted.jitter() <= 1e-5);
    let p = fitted.predict(&[1.0, 1.5]).unwrap();
    assert!((p.mean[0] - 1.0).abs() < 1e-4);
    assert!(p.variance.iter().all(|v| *v >= 0.0));
    // Without jitter it is a typed error, not a panic.
    let strict = gp.with_jitter(JitterPolicy::none()).fit(&x, 1, &y);
    assert!(
        matches!(strict, Err(GpError::NotPositiveDefinite { .. })),
        "{strict:?}"
    );
}

#[test]
fn a_jitter_policy_makes_between_one_and_a_hundred_attempts() {
    // Regression: any count was accepted, so a policy read from a file could ask for billions
    // of factorisations of a matrix that never becomes positive definite.
    let x = [0.0, 1.0, 1.0, 2.0];
    let y = [0.0, 1.0, 1.0, 0.5];
    let gp = GpRegression::new(Rbf::new(1.0, 1.0).unwrap()).with_noise(0.0);
    for attempts in [0, JitterPolicy::MAX_ATTEMPTS + 1, u32::MAX] {
        let policy = JitterPolicy {
            max_attempts: attempts,
            ..JitterPolicy::default()
        };
        let e = gp.clone().with_jitter(policy).fit(&x, 1, &y);
        assert!(
            matches!(e, Err(GpError::InvalidParameter(haunts_core::InvalidParameter { name, .. })) if name == "jitter.max_attempts"),
            "{attempts}: {e:?}"
        );
    }
    let most = JitterPolicy {
        max_attempts: JitterPolicy::MAX_ATTEMPTS,
        ..JitterPolicy::default()
    };
    assert!(gp.with_jitter(most).fit(&x, 1, &y).is_ok());
}

#[test]
fn degenerate_but_valid_inputs_have_well_defined_results() {
    // n = 1.
    let gp = GpRegression::new(Rbf::new(2.0, 1.0).unwrap())
        .with_noise(0.0)
        .fit(&[3.0], 1, &[7.0])
        .unwrap();
    let p = gp.predict(&[3.0, 100.0]).unwrap();
    assert_relative_eq!(p.mean[0], 7.0, max_relative = 1e-12);
    assert_eq!(p.mean[1], 0.0);
    assert!(p.variance[0] >= 0.0 && p.variance[0] < 1e-9);
    // Constant targets with the data mean: the mean is the constant everywhere.
    let x: Vec<f64> = (0..20).map(f64::from).collect();
    let gp = GpRegression::new(Rbf::new(1.0, 2.0).unwrap())
        .with_noise(1e-4)
        .with_mean(Mean::Data)
        .fit(&x, 1, &[4.2; 20])
        .unwrap();
    assert!(
        gp.predict_mean(&[3.5, -50.0])
            .unwrap()
            .iter()
            .all(|m| (m - 4.2).abs() < 1e-12)
    );
    // Huge and tiny length scales: finite, non-negative, no panic.
    for l in [1e-8, 1e8] {
        let gp = GpRegression::new(Rbf::new(1.0, l).unwrap())
            .with_noise(1e-6)
            .fit(&x, 1, &x)
            .unwrap();
        let p = gp.predict(&[0.5, 7.0]).unwrap();
        assert!(p.mean.iter().all(|m| m.is_finite()), "l = {l}: {p:?}");
        assert!(
            p.variance.iter().all(|v| (0.0..=1.0 + 1e-9).contains(v)),
            "l = {l}: {p:?}"
        );
        assert!(gp.log_marginal_likelihood().is_finite());
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let gp = GpRegression::new(Rbf::new(1.0, 1.0).unwrap());
    assert!(matches!(
        gp.fit(&[0.0, f64::NAN], 1, &[1.0, 2.0]),
        Err(GpError::NonFiniteInput { index: 1 })
    ));
    assert!(matches!(
        gp.fit(&[0.0, 1.0], 1, &[1.0, f64::INFINITY]),
        Err(GpError::NonFiniteTarget { index: 1 })
    ));
    assert!(matches!(
        gp.fit(&[0.0, 1.0], 1, &[1.0]),
        Err(GpError::LengthMismatch {
            points: 2,
            targets: 1
        })
    ));
    assert!(matches!(gp.fit(&[], 1, &[]), Err(GpError::NoData)));
    assert!(matches!(
        gp.fit(&[0.0, 1.0, 2.0], 2, &[1.0]),
        Err(GpError::BadPointArray { .. })
    ));
    assert!(matches!(
        gp.clone().with_noise(-1.0).fit(&[0.0], 1, &[1.0]),
        Err(GpError::InvalidParameter(haunts_core::InvalidParameter {
            name: "noise",
            ..
        }))
    ));
    let fitted = gp.fit(&[0.0, 1.0], 1, &[1.0, 2.0]).unwrap();
    assert!(matches!(
        fitted.predict(&[f64::NAN]),
        Err(GpError::NonFiniteInput { index: 0 })
    ));
    let ard = GpRegression::new(RbfArd::new(1.0, &[1.0, 1.0]).unwrap());
    assert!(matches!(
        ard.fit(&[0.0, 1.0], 1, &[1.0, 2.0]),
        Err(GpError::DimensionMismatch { .. })
    ));
}

#[test]
fn fast_grid_prediction_matches_the_exact_one() {
    use haunts_gp::{Grid2, GridMode};
    let (x, y) = data(5, 300, 2);
    let grid = Grid2 {
        origin: [0.05, -0.5],
        step: [0.1, 0.15],
        shape: [110, 80],
    };
    for kernel in [
        Box::new(Rbf::new(1.0, 2.0).unwrap()) as Box<dyn Kernel>,
        Box::new(RbfArd::new(0.7, &[1.5, 3.0]).unwrap()),
    ] {
        let gp = GpRegression::from_box(kernel)
            .with_noise(0.01)
            .fit(&x, 2, &y)
            .unwrap();
        let exact = gp.predict_grid(&grid, GridMode::Exact).unwrap();
        assert_eq!(exact.mean, gp.predict_mean(&grid.points()).unwrap());
        let fast = gp.predict_grid(&grid, GridMode::fast()).unwrap();
        let nodes = fast.nodes.unwrap();
        assert!(nodes[0] < 110 && nodes[1] < 80, "{nodes:?}");
        let (mut dm, mut dv) = (0.0f64, 0.0f64);
        for q in 0..grid.len() {
            dm = dm.max((fast.mean[q] - exact.mean[q]).abs());
            dv = dv.max((fast.variance[q] - exact.variance[q]).abs());
            assert!(fast.variance[q] >= 0.0);
        }
        assert!(
            dm < 1e-7 && dv < 1e-8,
            "mean error {dm}, variance error {dv}, nodes {nodes:?}"
        );
        let check = fast.checked.unwrap();
        assert!(
            check.max_mean_error <= dm && check.max_relative_variance_error <= dv / 0.7 + 1e-15
        );
    }
}

/// With σ² held by [`Constrained`], the optimiser fits ℓ (and σn²) alone: the variance comes back
/// unchanged, and ℓ matches a plain grid search of the log marginal likelihood.
#[test]
fn a_fixed_variance_is_not_optimised() {
    let (x, y) = data(8, 120, 2);
    let kernel = Constrained::new(Box::new(Rbf::new(1.0, 0.7).unwrap()))
        .hold("variance")
        .and_then(|k| k.bound("length_scale", 0.1, 10.0))
        .unwrap();
    let options = {
        let mut p = OptimiseOptions::default();
        p.optimise_noise = false;
        p
    };
    let (gp, report) = GpRegression::new(kernel)
        .with_noise(0.05)
        .fit_optimised(&x, 2, &y, &options)
        .unwrap();
    assert_eq!(report.log_params.len(), 1);
    let fitted = report.log_params[0].exp();
    let lml = |l: f64| {
        GpRegression::new(Rbf::new(1.0, l).unwrap())
            .with_noise(0.05)
            .fit(&x, 2, &y)
            .unwrap()
            .log_marginal_likelihood()
    };
    // Grid over log ℓ in [ln 0.1, ln 10], then refined around the best node.
    let (mut lo, mut hi) = (0.1f64.ln(), 10f64.ln());
    let mut best = lo;
    for _ in 0..4 {
        let nodes: Vec<f64> = (0..=40).map(|k| lo + (hi - lo) * k as f64 / 40.0).collect();
        best = nodes
            .iter()
            .copied()
            .max_by(|a, b| lml(a.exp()).total_cmp(&lml(b.exp())))
            .unwrap();
        let step = (hi - lo) / 40.0;
        (lo, hi) = (best - step, best + step);
    }
    assert_relative_eq!(fitted, best.exp(), max_relative = 1e-3);
    assert!(report.log_marginal_likelihood >= lml(best.exp()) - 1e-7);
    assert_relative_eq!(
        gp.log_marginal_likelihood(),
        report.log_marginal_likelihood,
        max_relative = 1e-12
    );
}

#[test]
fn a_grid_over_the_point_budget_is_refused_before_allocating() {
    use haunts_gp::{Grid2, GridMode};
    let (x, y) = data(5, 50, 2);
    let gp = GpRegression::new(Rbf::new(1.0, 2.0).unwrap())
        .with_noise(0.01)
        .fit(&x, 2, &y)
        .unwrap();
    // 2^40 points (16 TiB of means): refused at once, not allocated.
    let huge = Grid2 {
        origin: [0.0, 0.0],
        step: [1e-6, 1e-6],
        shape: [1 << 20, 1 << 20],
    };
    for mode in [GridMode::Exact, GridMode::fast()] {
        assert!(matches!(
            gp.predict_grid(&huge, mode),
            Err(GpError::InvalidParameter(haunts_core::InvalidParameter { name: "grid.shape", value, .. })) if value == (1u64 << 40) as f64
        ));
    }
    // usize::MAX × 2 does not wrap into a small grid either.
    let wrapping = Grid2 {
        shape: [usize::MAX, 2],
        ..huge
    };
    assert!(wrapping.check().is_err());
    let fine = Grid2 {
        shape: [1 << 14, 1 << 14],
        ..huge
    };
    assert!(fine.check().is_ok());
}
