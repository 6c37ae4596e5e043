//! One suite for every kernel: gradients against finite differences, symmetry, positive
//! semi-definiteness, hand-computed values, and typed errors on bad input.

use approx::assert_relative_eq;
use haunts_gp::{
    Constant, Constrained, GpError, Kernel, Matern32, Matern52, Periodic, Product, Rbf, RbfArd,
    Scaled, Sum, White, covariance, cross_covariance,
};
use nalgebra::{DMatrix, SymmetricEigen};
use proptest::prelude::*;

type Built = Result<Box<dyn Kernel>, GpError>;

/// Every built-in kernel (and some combinations) for points of dimension `d`, with the
/// hyperparameters of scikit-learn's defaults or near them.
fn all_kernels(d: usize) -> Vec<(&'static str, Box<dyn Kernel>)> {
    let list: Vec<(&'static str, Built)> = vec![
        ("rbf", Ok(Box::new(Rbf::new(1.0, 1.0).unwrap()))),
        (
            "rbf_ard",
            Ok(Box::new(RbfArd::new(1.0, &vec![1.0; d]).unwrap())),
        ),
        ("matern32", Ok(Box::new(Matern32::new(1.0, 1.0).unwrap()))),
        ("matern52", Ok(Box::new(Matern52::new(1.0, 1.0).unwrap()))),
        (
            "periodic",
            Ok(Box::new(Periodic::new(1.0, 1.0, 1.0).unwrap())),
        ),
        ("white", Ok(Box::new(White::new(1.0).unwrap()))),
        ("constant", Ok(Box::new(Constant::new(1.0).unwrap()))),
        (
            "scaled_matern52",
            Scaled::new(2.0, Box::new(Matern52::new(1.0, 1.0).unwrap()))
                .map(|k| Box::new(k) as Box<dyn Kernel>),
        ),
        (
            "sum_rbf_ard_white",
            Sum::new(
                Box::new(RbfArd::new(1.0, &vec![1.0; d]).unwrap()),
                Box::new(White::new(0.1).unwrap()),
            )
            .map(|k| Box::new(k) as Box<dyn Kernel>),
        ),
        (
            "product_matern32_rbf",
            Product::new(
                Box::new(Matern32::new(1.0, 1.0).unwrap()),
                Box::new(Rbf::new(1.0, 1.0).unwrap()),
            )
            .map(|k| Box::new(k) as Box<dyn Kernel>),
        ),
        (
            "product_periodic_sum",
            Sum::new(
                Box::new(Constant::new(0.5).unwrap()),
                Box::new(Matern52::new(1.0, 1.0).unwrap()),
            )
            .and_then(|s| {
                Product::new(Box::new(Periodic::new(1.0, 1.0, 2.0).unwrap()), Box::new(s))
            })
            .map(|k| Box::new(k) as Box<dyn Kernel>),
        ),
        (
            "fixed_periodic_length_scale",
            Constrained::new(Box::new(Periodic::new(1.0, 1.0, 2.0).unwrap()))
                .hold("length_scale")
                .and_then(|k| k.bound("periodicity", 0.5, 8.0))
                .map(|k| Box::new(k) as Box<dyn Kernel>),
        ),
        (
            "fixed_product_variance",
            Product::new(
                Box::new(Matern32::new(1.0, 1.0).unwrap()),
                Box::new(Rbf::new(1.0, 1.0).unwrap()),
            )
            .and_then(|p| Constrained::new(Box::new(p)).hold("k1__variance"))
            .map(|k| Box::new(k) as Box<dyn Kernel>),
        ),
    ];
    list.into_iter().map(|(n, k)| (n, k.unwrap())).collect()
}

/// Log hyperparameters from numbers in [0, 1]: uniform on the kernel's bounds intersected
/// with [−1.5, 1.5] (a range where central differences are well conditioned).
fn params_from(k: &dyn Kernel, u: &[f64]) -> Vec<f64> {
    k.log_bounds()
        .iter()
        .zip(u)
        .map(|(&(lo, hi), &t)| {
            let (lo, hi) = (lo.max(-1.5), hi.min(1.5));
            lo + t * (hi - lo)
        })
        .collect()
}

/// ∂k/∂(log θ_j) by Richardson-extrapolated central differences (error O(h⁴)).
fn finite_difference(k: &dyn Kernel, a: &[f64], b: &[f64], j: usize) -> f64 {
    let p = k.log_params();
    let at = |h: f64| {
        let mut q = p.clone();
        q[j] += h;
        let mut k2 = k.clone_box();
        k2.set_log_params(&q).unwrap();
        k2.value(a, b)
    };
    let d = |h: f64| (at(h) - at(-h)) / (2.0 * h);
    let h = 1e-4;
    (4.0 * d(h / 2.0) - d(h)) / 3.0
}

fn point(d: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-1.5..1.5f64, d)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn gradients_agree_with_finite_differences(
        d in 1usize..=3,
        u in prop::collection::vec(0.0..1.0f64, 16),
        a in point(3),
        b in point(3),
        same in prop::bool::weighted(0.2),
    ) {
        let a = &a[..d];
        let b = if same { a } else { &b[..d] };
        for (name, mut k) in all_kernels(d) {
            let p = params_from(k.as_ref(), &u);
            k.set_log_params(&p).unwrap();
            let mut g = vec![0.0; k.n_params()];
            k.gradient(a, b, &mut g);
            let v = k.value(a, b);
            for (j, &gj) in g.iter().enumerate() {
                let fd = finite_difference(k.as_ref(), a, b, j);
                let tol = 1e-6 * (gj.abs() + v.abs()) + 1e-300;
                prop_assert!(
                    (fd - gj).abs() <= tol,
                    "{name}: ∂k/∂{}: analytic {gj}, finite difference {fd}",
                    k.param_names()[j]
                );
            }
        }
    }

    #[test]
    fn kernels_are_symmetric(
        d in 1usize..=3,
        u in prop::collection::vec(0.0..1.0f64, 16),
        a in point(3),
        b in point(3),
    ) {
        for (name, mut k) in all_kernels(d) {
            k.set_log_params(&params_from(k.as_ref(), &u)).unwrap();
            let (a, b) = (&a[..d], &b[..d]);
            prop_assert_eq!(k.value(a, b), k.value(b, a), "{}", name);
            let (mut gab, mut gba) = (vec![0.0; k.n_params()], vec![0.0; k.n_params()]);
            k.gradient(a, b, &mut gab);
            k.gradient(b, a, &mut gba);
            prop_assert_eq!(gab, gba, "{}", name);
        }
    }

    #[test]
    fn covariances_are_positive_semi_definite(
        d in 1usize..=3,
        u in prop::collection::vec(0.0..1.0f64, 16),
        x in prop::collection::vec(-1.5..1.5f64, 3..=60),
        duplicate in prop::bool::ANY,
    ) {
        let n = x.len() / d;
        let mut x = x[..n * d].to_vec();
        if duplicate && n > 1 {
            // A repeated point (the white-noise and rank-deficient case).
            let first = x[..d].to_vec();
            x[(n - 1) * d..].copy_from_slice(&first);
        }
        for (name, mut k) in all_kernels(d) {
            // The exp-sine-squared kernel of the Euclidean distance (scikit-learn's form) is
            // positive semi-definite in one dimension only.
            if name.contains("periodic") && d > 1 {
                continue;
            }
            k.set_log_params(&params_from(k.as_ref(), &u)).unwrap();
            let m = DMatrix::from_row_slice(n, n, &covariance(k.as_ref(), &x, d).unwrap());
            let trace = m.trace();
            let min = SymmetricEigen::new(m).eigenvalues.min();
            prop_assert!(min >= -1e-9 * trace, "{name}: smallest eigenvalue {min}, trace {trace}");
        }
    }

    #[test]
    fn log_params_round_trip(d in 1usize..=3, u in prop::collection::vec(0.0..1.0f64, 16)) {
        for (name, mut k) in all_kernels(d) {
            let n = k.n_params();
            prop_assert_eq!(k.log_params().len(), n, "{}", name);
            prop_assert_eq!(k.log_bounds().len(), n, "{}", name);
            prop_assert_eq!(k.param_names().len(), n, "{}", name);
            let p = params_from(k.as_ref(), &u);
            k.set_log_params(&p).unwrap();
            prop_assert_eq!(k.log_params(), p, "{}", name);
        }
    }
}

#[test]
fn known_values() {
    let e = std::f64::consts::E;
    let (a, b) = ([0.0, 0.0], [3.0, 4.0]); // r = 5, r² = 25
    let rbf = Rbf::new(2.0, 5.0).unwrap(); // 2 exp(−25/50)
    assert_relative_eq!(rbf.value(&a, &b), 2.0 / e.sqrt(), max_relative = 1e-15);
    let ard = RbfArd::new(1.5, &[3.0, 2.0]).unwrap(); // 1.5 exp(−½(1 + 4))
    assert_relative_eq!(
        ard.value(&a, &b),
        1.5 * (-2.5f64).exp(),
        max_relative = 1e-15
    );
    // ℓ = 5√3: u = √3·5/ℓ = 1 → (1 + 1)/e.
    let m32 = Matern32::new(3.0, 5.0 * 3f64.sqrt()).unwrap();
    assert_relative_eq!(m32.value(&a, &b), 3.0 * 2.0 / e, max_relative = 1e-14);
    // ℓ = 5√5 / 2: u = 2 → (1 + 2 + 4/3) e^{−2}.
    let m52 = Matern52::new(1.0, 5.0 * 5f64.sqrt() / 2.0).unwrap();
    assert_relative_eq!(
        m52.value(&a, &b),
        13.0 / 3.0 / (e * e),
        max_relative = 1e-14
    );
    // p = 30: sin(π/6) = ½ → exp(−2·¼/ℓ²), ℓ = 0.5 → e^{−2}.
    let per = Periodic::new(4.0, 0.5, 30.0).unwrap();
    assert_relative_eq!(per.value(&a, &b), 4.0 / (e * e), max_relative = 1e-14);
    // A whole period apart: k = σ².
    let per1 = Periodic::new(4.0, 0.5, 5.0).unwrap();
    assert_relative_eq!(per1.value(&a, &b), 4.0, max_relative = 1e-14);
    let white = White::new(0.3).unwrap();
    assert_relative_eq!(white.value(&b, &[3.0, 4.0]), 0.3, max_relative = 1e-15);
    assert_eq!(white.value(&a, &[0.0, 1e-300]), 0.0);
    assert_relative_eq!(white.value(&[-0.0], &[0.0]), 0.3, max_relative = 1e-15);
    let c = Constant::new(0.7).unwrap();
    assert_relative_eq!(c.value(&a, &b), 0.7, max_relative = 1e-15);
    let scaled = Scaled::new(3.0, Box::new(rbf)).unwrap();
    assert_relative_eq!(scaled.value(&a, &b), 6.0 / e.sqrt(), max_relative = 1e-15);
    let sum = Sum::new(Box::new(rbf), Box::new(c)).unwrap();
    assert_relative_eq!(
        sum.value(&a, &b),
        2.0 / e.sqrt() + 0.7,
        max_relative = 1e-15
    );
    let prod = Product::new(Box::new(rbf), Box::new(per)).unwrap();
    assert_relative_eq!(prod.value(&a, &b), 8.0 / e.powf(2.5), max_relative = 1e-14);
}

#[test]
fn known_gradients() {
    // RBF with σ² = 2, ℓ = 5 at r² = 25: ∂/∂log σ² = k, ∂/∂log ℓ = k r²/ℓ² = k.
    let rbf = Rbf::new(2.0, 5.0).unwrap();
    let mut g = [0.0; 2];
    rbf.gradient(&[0.0, 0.0], &[3.0, 4.0], &mut g);
    let k = 2.0 / std::f64::consts::E.sqrt();
    assert_relative_eq!(g[0], k, max_relative = 1e-15);
    assert_relative_eq!(g[1], k, max_relative = 1e-15);
    // Product order: k1's gradient first, scaled by k2.
    let prod = Product::new(Box::new(rbf), Box::new(Constant::new(3.0).unwrap())).unwrap();
    let mut g = [0.0; 3];
    prod.gradient(&[0.0, 0.0], &[3.0, 4.0], &mut g);
    for gi in g {
        assert_relative_eq!(gi, 3.0 * k, max_relative = 1e-15);
    }
}

#[test]
fn names_follow_scikit_learn_prefixes() {
    let k = Sum::new(
        Box::new(Scaled::new(1.0, Box::new(Periodic::new(1.0, 1.0, 1.0).unwrap())).unwrap()),
        Box::new(RbfArd::new(1.0, &[1.0, 2.0]).unwrap()),
    )
    .unwrap();
    assert_eq!(
        k.param_names(),
        [
            "k1__constant_value",
            "k1__k__variance",
            "k1__k__length_scale",
            "k1__k__periodicity",
            "k2__variance",
            "k2__length_scale_0",
            "k2__length_scale_1",
        ]
    );
    assert_eq!(k.dim(), Some(2));
    assert_relative_eq!(k.log_params()[6], 2f64.ln(), max_relative = 1e-15);
}

#[test]
fn bad_hyperparameters_are_typed_errors() {
    for (name, mut k) in all_kernels(2) {
        let before = k.log_params();
        let n = k.n_params();
        assert_eq!(
            k.set_log_params(&vec![0.0; n + 1]),
            Err(GpError::WrongParameterCount {
                expected: n,
                found: n + 1
            }),
            "{name}"
        );
        assert!(
            matches!(
                k.set_log_params(&[]),
                Err(GpError::WrongParameterCount { .. })
            ),
            "{name}"
        );
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1000.0, -1000.0] {
            // The last parameter bad: all-or-nothing means the earlier ones are not set.
            let mut p = vec![0.25; n];
            p[n - 1] = bad;
            match k.set_log_params(&p) {
                Err(GpError::InvalidHyperparameter { name: pname, .. }) => {
                    assert_eq!(pname, k.param_names()[n - 1].rsplit("__").next().unwrap());
                }
                other => panic!("{name}: {bad} gave {other:?}"),
            }
            assert_eq!(k.log_params(), before, "{name} changed on error");
        }
    }
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(Rbf::new(bad, 1.0).is_err());
        assert!(Rbf::new(1.0, bad).is_err());
        assert!(Matern32::new(1.0, bad).is_err());
        assert!(Matern52::new(bad, 1.0).is_err());
        assert!(Periodic::new(1.0, 1.0, bad).is_err());
        assert!(RbfArd::new(1.0, &[1.0, bad]).is_err());
        assert!(White::new(bad).is_err());
        assert!(Constant::new(bad).is_err());
        assert!(Scaled::new(bad, Box::new(Constant::new(1.0).unwrap())).is_err());
    }
    assert_eq!(
        RbfArd::new(1.0, &[]).unwrap_err(),
        GpError::DimensionMismatch {
            expected: 1,
            found: 0
        }
    );
}

#[test]
fn dimension_mismatches_are_typed_errors() {
    let ard = RbfArd::new(1.0, &[1.0, 2.0]).unwrap();
    let err = GpError::DimensionMismatch {
        expected: 2,
        found: 3,
    };
    let mismatch = Err(err.clone());
    assert_eq!(ard.try_value(&[0.0, 0.0, 0.0], &[0.0, 0.0, 0.0]), mismatch);
    assert_eq!(ard.try_value(&[0.0, 0.0], &[0.0, 0.0, 0.0]), mismatch);
    assert_eq!(covariance(&ard, &[0.0; 6], 3), Err(err.clone()));
    assert_eq!(
        cross_covariance(&ard, &[0.0; 6], &[0.0; 6], 3),
        Err(err.clone())
    );
    // Isotropic kernels take any dimension, but both points must share it.
    let rbf = Rbf::new(1.0, 1.0).unwrap();
    assert_eq!(
        rbf.try_value(&[0.0, 0.0], &[0.0]),
        Err(GpError::DimensionMismatch {
            expected: 2,
            found: 1
        })
    );
    assert_relative_eq!(rbf.try_value(&[0.0; 3], &[0.0; 3]).unwrap(), 1.0);
    // Two ARD kernels of different dimensions cannot be combined.
    let ard3 = RbfArd::new(1.0, &[1.0; 3]).unwrap();
    assert_eq!(
        Sum::new(Box::new(ard.clone()), Box::new(ard3.clone())).unwrap_err(),
        err
    );
    assert!(Product::new(Box::new(ard3), Box::new(ard)).is_err());
}

#[test]
fn bad_points_are_typed_errors() {
    let rbf = Rbf::new(1.0, 1.0).unwrap();
    assert_eq!(
        covariance(&rbf, &[0.0; 5], 2),
        Err(GpError::BadPointArray { len: 5, dim: 2 })
    );
    assert_eq!(
        covariance(&rbf, &[0.0; 4], 0),
        Err(GpError::BadPointArray { len: 4, dim: 0 })
    );
    assert_eq!(
        covariance(&rbf, &[0.0, 0.0, 1.0, f64::NAN], 2),
        Err(GpError::NonFiniteInput { index: 1 })
    );
    assert_eq!(
        cross_covariance(&rbf, &[0.0, 0.0], &[f64::INFINITY, 0.0], 2),
        Err(GpError::NonFiniteInput { index: 0 })
    );
    assert_eq!(
        rbf.try_value(&[0.0], &[f64::NAN]),
        Err(GpError::NonFiniteInput { index: 1 })
    );
    // No points: an empty matrix.
    assert_eq!(covariance(&rbf, &[], 2), Ok(vec![]));
}

#[test]
fn cross_covariance_matches_covariance() {
    let k = Sum::new(
        Box::new(Matern52::new(1.3, 0.7).unwrap()),
        Box::new(White::new(0.2).unwrap()),
    )
    .unwrap();
    let x = [0.0, 1.0, -0.5, 2.0, 0.25, 0.0];
    let full = covariance(&k, &x, 2).unwrap();
    let cross = cross_covariance(&k, &x, &x, 2).unwrap();
    assert_eq!(full, cross);
    // 3 × 1 block.
    let col = cross_covariance(&k, &x, &x[2..4], 2).unwrap();
    assert_eq!(col, [full[1], full[4], full[7]]);
}

#[test]
fn boxed_kernels_clone_independently() {
    let k: Box<dyn Kernel> = Box::new(Rbf::new(1.0, 1.0).unwrap());
    let mut c = k.clone();
    c.set_log_params(&[1.0, 1.0]).unwrap();
    assert_eq!(k.log_params(), [0.0, 0.0]);
    assert_eq!(c.log_params(), [1.0, 1.0]);
}

/// `scale_param` is a promise that ∂k/∂(log θ_i) = k everywhere (the sparse bound's gradient
/// relies on it): checked at random point pairs for every kernel that makes it, and the
/// kernels that must make it do.
#[test]
fn scale_params_are_what_they_claim() {
    for d in [1, 2] {
        for (name, k) in all_kernels(d) {
            let expected = match name {
                "sum_rbf_ard_white" => None,
                // k1's variance is held: k2's, the product's other scale, is free but
                // `Product` names the first factor's, so none is claimed.
                "fixed_product_variance" => None,
                _ => Some(0),
            };
            assert_eq!(k.scale_param(), expected, "{name}");
            let Some(i) = k.scale_param() else { continue };
            let mut g = vec![0.0; k.n_params()];
            let pts: Vec<f64> = (0..40).map(|j| ((j * 7919) % 101) as f64 / 17.0).collect();
            for (a, b) in pts.chunks_exact(d).zip(pts.chunks_exact(d).skip(3)) {
                k.gradient(a, b, &mut g);
                assert_relative_eq!(g[i], k.value(a, b), max_relative = 1e-14, epsilon = 1e-300);
            }
            k.gradient(&pts[..d], &pts[..d], &mut g);
            assert_relative_eq!(g[i], k.value(&pts[..d], &pts[..d]), max_relative = 1e-14);
        }
    }
    // A product takes its second factor's scale when the first has none.
    let sum = Sum::new(
        Box::new(Constant::new(0.5).unwrap()),
        Box::new(Rbf::new(1.0, 1.0).unwrap()),
    )
    .unwrap();
    let p = Product::new(Box::new(sum), Box::new(Matern32::new(2.0, 1.0).unwrap())).unwrap();
    assert_eq!(p.scale_param(), Some(3));
}

/// A held hyperparameter keeps its value whatever the optimiser sets; the free ones keep the
/// inner kernel's order, names, bounds and gradient entries.
#[test]
fn fixed_hyperparameters_stay_where_they_are() {
    let inner = Periodic::new(2.0, 0.5, 3.0).unwrap();
    let mut k = Constrained::new(Box::new(inner))
        .hold("length_scale")
        .and_then(|k| k.bound("periodicity", 1.0, 10.0))
        .unwrap();
    assert_eq!(k.param_names(), ["variance", "periodicity"]);
    assert_eq!(k.n_params(), 2);
    let b = inner.log_bounds();
    assert_eq!(k.log_bounds(), [b[0], (0.0, 10f64.ln())]);
    k.set_log_params(&[1.0, 0.2]).unwrap();
    let all = k.inner().log_params();
    assert_relative_eq!(all[0], 1.0);
    assert_relative_eq!(all[1], 0.5f64.ln());
    assert_relative_eq!(all[2], 0.2);
    let mut full = inner;
    full.set_log_params(&all).unwrap();
    let (a, c) = ([0.3], [1.7]);
    assert_relative_eq!(k.value(&a, &c), full.value(&a, &c), max_relative = 1e-15);
    let (mut g, mut g_full) = (vec![0.0; 2], vec![0.0; 3]);
    k.gradient(&a, &c, &mut g);
    full.gradient(&a, &c, &mut g_full);
    assert_eq!(g, [g_full[0], g_full[2]]);
    // Wrong counts and unknown names are typed errors; a refused set changes nothing.
    assert!(matches!(
        k.set_log_params(&[1.0]),
        Err(GpError::WrongParameterCount {
            expected: 2,
            found: 1
        })
    ));
    assert!(k.set_log_params(&[f64::NAN, 0.0]).is_err());
    assert_eq!(k.inner().log_params(), all);
    let rbf = || Constrained::new(Box::new(Rbf::new(1.0, 1.0).unwrap()));
    let err = rbf().hold("sigma").unwrap_err();
    assert!(matches!(err, GpError::UnknownHyperparameter { ref name, .. } if name == "sigma"));
    assert!(rbf().bound("length_scale", 2.0, 1.0).is_err());
    assert!(rbf().bound("length_scale", 0.0, 1.0).is_err());
    assert!(rbf().bound("length_scale", 1.0, f64::INFINITY).is_err());
    // Everything held: nothing left to optimise, the kernel itself unchanged.
    let none = rbf()
        .hold("variance")
        .and_then(|k| k.hold("length_scale"))
        .unwrap();
    assert_eq!(none.n_params(), 0);
    assert_eq!(none.scale_param(), None);
}
