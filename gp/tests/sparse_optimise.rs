//! Optimisation of the sparse (VFE) bound: its analytic gradient against central finite
//! differences, the optimised bound with Z = X against the exact GP's optimised likelihood,
//! GPy's optimised bound, and bad input.

use std::path::Path;

use haunts_gp::{
    GpError, GpRegression, Inducing, Mean, OptimiseOptions, Rbf, SparseGpRegression, SparseMethod,
};
use proptest::prelude::*;
use serde_json::Value;

mod common;
use common::uniform;

use common::wavy as data;

/// The bound and gradient at log parameters `theta` = [log σ², log ℓ, log σn²].
fn at(
    theta: &[f64],
    z: &[f64],
    x: &[f64],
    y: &[f64],
    chunk: usize,
    mean: Mean,
) -> Result<haunts_gp::SparseObjective, GpError> {
    SparseGpRegression::new(
        Rbf::new(theta[0].exp(), theta[1].exp())?,
        Inducing::Given(z.to_vec()),
    )
    .with_noise(theta[2].exp())
    .with_mean(mean)
    .with_chunk_size(chunk)
    .objective_gradient(x, 2, y)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Over variances 0.1–10, length scales 0.3–30 (K(Z, Z) of 25 points on 10 × 10 is
    /// numerically singular at the long end and may take jitter) and noise variances 1e-6–1,
    /// the analytic gradient equals central differences (Richardson-extrapolated from steps
    /// h and 2h in log space, so truncation is O(h⁴)) at h = 1e-3 or at h = 5e-3 (the small
    /// step where the bound is smooth to rounding, the large one where its rounding noise
    /// dominates). Tolerance: 1e-7 of the gradient's
    /// scale while K(Z, Z) is well conditioned (ℓ ≤ 1), 1e-5 beyond (the bound itself then
    /// carries rounding of order ε·cond(Kuu)), plus 3× the bound's own rounding noise over the
    /// step, measured at θ, plus (at h = 1e-3) twice the truncation error estimated from the
    /// two steps.
    #[test]
    fn gradient_matches_central_differences(
        log_var in (0.1f64).ln()..(10.0f64).ln(),
        log_len in (0.3f64).ln()..(30.0f64).ln(),
        log_noise in prop_oneof![Just((1e-6f64).ln()), (1e-6f64).ln()..0.0],
        seed in 0u64..1000,
    ) {
        let (x, y) = data(100 + 2 * seed, 90);
        let z: Vec<f64> = uniform(7 + seed, 2 * 25).iter().map(|u| u * 10.0).collect();
        let theta = [log_var, log_len, log_noise];
        let centre = at(&theta, &z, &x, &y, 23, Mean::Data).unwrap();
        // The bound's rounding noise as a function of θ: its departure from the tangent over
        // steps of 1e-7, where the curvature's share is below 1e-9.
        let mut noise = 0.0f64;
        for (i, u) in uniform(seed, 12).chunks_exact(3).enumerate() {
            let delta: Vec<f64> = u.iter().map(|v| 1e-7 * (v - 0.5)).collect();
            let moved: Vec<f64> = theta.iter().zip(&delta).map(|(t, d)| t + d).collect();
            let f = at(&moved, &z, &x, &y, 23 + i, Mean::Data).unwrap().value;
            let tangent: f64 = centre.gradient.iter().zip(&delta).map(|(g, d)| g * d).sum();
            noise = noise.max((f - centre.value - tangent).abs());
        }
        let attempt = |j: f64, log_var: f64| j / log_var.exp();
        let c = attempt(centre.jitter, theta[0]);
        let relative = if log_len <= 0.0 { 1e-7 } else { 1e-5 };
        for k in 0..3 {
            let g = centre.gradient[k];
            let mut fds = Vec::new();
            for h in [1e-3, 5e-3] {
                let mut d = [0.0; 2];
                for (s, step) in [h, 2.0 * h].into_iter().enumerate() {
                    let mut up = theta;
                    let mut down = theta;
                    up[k] += step;
                    down[k] -= step;
                    let (u, dn) = (at(&up, &z, &x, &y, 23, Mean::Data).unwrap(), at(&down, &z, &x, &y, 23, Mean::Data).unwrap());
                    // Another jitter attempt on either side is a jump of the function, not a
                    // slope (the jitter is relative to σ², so compare jitter / σ²).
                    prop_assume!((attempt(u.jitter, up[0]) - c).abs() <= 1e-9 * c);
                    prop_assume!((attempt(dn.jitter, down[0]) - c).abs() <= 1e-9 * c);
                    d[s] = (u.value - dn.value) / (2.0 * step);
                }
                fds.push((h, (4.0 * d[0] - d[1]) / 3.0));
            }
            // The extrapolated differences still carry a truncation error ∝ h⁴, whose constant
            // is large where the bound is stiff (noise variances near 1e-6: the two steps'
            // estimates then differ by 1e-3 of the gradient). Estimated from the two steps,
            // the error at h = 1e-3 is |fd(1e-3) − fd(5e-3)| / (5⁴ − 1); twice that joins
            // its tolerance.
            let truncation = 2.0 * (fds[0].1 - fds[1].1).abs() / 624.0;
            let mut report = Vec::new();
            for (i, &(h, fd)) in fds.iter().enumerate() {
                let estimated = if i == 0 { truncation } else { 0.0 };
                let tolerance = relative * g.abs().max(1.0) + 3.0 * noise / h + estimated;
                report.push((h, fd, tolerance, (fd - g).abs() <= tolerance));
            }
            prop_assert!(
                report.iter().any(|r| r.3),
                "θ = {theta:?}, k = {k}: analytic {g}, (step, differences, tolerance, ok) {report:?}, noise {noise:e}, jitter {}",
                centre.jitter
            );
        }
    }
}

#[test]
fn objective_gradient_value_is_the_fitted_bound() {
    let (x, y) = data(3, 300);
    let gp = SparseGpRegression::new(Rbf::new(1.3, 1.7).unwrap(), Inducing::kmeans(30))
        .with_noise(0.02)
        .with_mean(Mean::Data);
    let at = gp.objective_gradient(&x, 2, &y).unwrap();
    let fitted = gp.fit(&x, 2, &y).unwrap();
    assert!(
        (at.value - fitted.objective()).abs() < 1e-10 * fitted.objective().abs(),
        "{} vs {}",
        at.value,
        fitted.objective()
    );
    assert_eq!(at.jitter, fitted.jitter());
}

#[test]
fn with_inducing_points_at_the_data_the_optimised_bound_is_the_exact_optimum() {
    let (x, y) = data(5, 60);
    let options = {
        let mut p = OptimiseOptions::default();
        p.warm_start_subset = 0;
        p
    };
    let (_, exact) = GpRegression::new(Rbf::new(0.5, 1.0).unwrap())
        .with_noise(0.1)
        .with_mean(Mean::Data)
        .fit_optimised(&x, 2, &y, &options)
        .unwrap();
    let (sparse, report) =
        SparseGpRegression::new(Rbf::new(0.5, 1.0).unwrap(), Inducing::Given(x.clone()))
            .with_noise(0.1)
            .with_mean(Mean::Data)
            .fit_optimised(&x, 2, &y, &options)
            .unwrap();
    eprintln!(
        "Z = X: exact {:.10} {:?}, VFE {:.10} {:?} (jitter {})",
        exact.log_marginal_likelihood,
        exact.log_params,
        report.log_marginal_likelihood,
        report.log_params,
        sparse.jitter()
    );
    // With Z = X, Qff = Kff and the bound is the exact likelihood (up to Kuu's jitter).
    assert!(
        (report.log_marginal_likelihood - exact.log_marginal_likelihood).abs()
            < 1e-6 * exact.log_marginal_likelihood.abs(),
        "{} vs {}",
        report.log_marginal_likelihood,
        exact.log_marginal_likelihood
    );
    for (a, b) in report.log_params.iter().zip(&exact.log_params) {
        assert!(
            (a - b).abs() < 1e-3,
            "{:?} vs {:?}",
            report.log_params,
            exact.log_params
        );
    }
}

fn load(name: &str) -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn flat(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .flat_map(|row| match row.as_array() {
            Some(r) => r.iter().map(|v| v.as_f64().unwrap()).collect(),
            None => vec![row.as_f64().unwrap()],
        })
        .collect()
}

#[test]
fn optimised_bound_reaches_gpys() {
    let d = load("gpy_vfe_opt_2d_300.json");
    let (x, y, z) = (flat(&d["x_train"]), flat(&d["y_train"]), flat(&d["z"]));
    let s = &d["start"];
    let f = |v: &Value| v.as_f64().unwrap();
    let start = SparseGpRegression::new(
        Rbf::new(f(&s["variance"]), f(&s["lengthscale"])).unwrap(),
        Inducing::Given(z.clone()),
    )
    .with_noise(f(&s["noise"]));
    let (gp, report) = start
        .fit_optimised(&x, 2, &y, &OptimiseOptions::default())
        .unwrap();
    let gpy = f(&d["bound_opt"]);
    let theta_gpy = flat(&d["theta_opt"]);
    // Our bound at GPy's optimum (GPy adds 1e-8 to K(Z, Z); we add the policy's jitter).
    let ours_at_gpy = at(&theta_gpy, &z, &x, &y, 0, Mean::Zero).unwrap();
    eprintln!(
        "GPy fixture: ours {:.10} at {:?} (jitter {}), GPy {gpy:.10} at {theta_gpy:?}; ours at GPy's optimum {:?}",
        report.log_marginal_likelihood,
        report.log_params,
        gp.jitter(),
        ours_at_gpy.value
    );
    // The same function: at GPy's optimum our bound (no jitter needed) is GPy's plus the
    // small loss GPy's 1e-8 jitter on K(Z, Z) causes (cond ≈ 1e15 there), and flat.
    assert_eq!(ours_at_gpy.jitter, 0.0);
    assert!(
        ours_at_gpy.value >= gpy && ours_at_gpy.value < gpy + 2e-3,
        "{} vs {gpy}",
        ours_at_gpy.value
    );
    assert!(ours_at_gpy.gradient.iter().all(|g| g.abs() < 1e-2));
    assert!(
        report.log_marginal_likelihood >= gpy - 1e-6,
        "ours {} < GPy {gpy}",
        report.log_marginal_likelihood
    );
    for (a, b) in report.log_params.iter().zip(&theta_gpy) {
        assert!(
            (a - b).abs() < 1e-3,
            "{:?} vs {theta_gpy:?}",
            report.log_params
        );
    }
}

#[test]
fn bad_input_to_the_optimiser_is_a_typed_error() {
    let (x, y) = data(9, 40);
    let gp = SparseGpRegression::new(Rbf::new(1.0, 1.0).unwrap(), Inducing::kmeans(10));
    let o = OptimiseOptions::default();
    let mut bad = x.clone();
    bad[5] = f64::NAN;
    assert!(matches!(
        gp.fit_optimised(&bad, 2, &y, &o),
        Err(GpError::NonFiniteInput { index: 2 })
    ));
    let mut bad_y = y.clone();
    bad_y[3] = f64::INFINITY;
    assert!(matches!(
        gp.fit_optimised(&x, 2, &bad_y, &o),
        Err(GpError::NonFiniteTarget { index: 3 })
    ));
    assert!(matches!(
        gp.fit_optimised(&x[..2], 2, &y[..1], &o),
        Err(GpError::TooFewPoints {
            found: 1,
            required: 2
        })
    ));
    assert!(matches!(
        gp.fit_optimised(&[], 2, &[], &o),
        Err(GpError::NoData)
    ));
    let same = vec![3.0; 2 * 40];
    assert!(matches!(
        gp.fit_optimised(&same, 2, &y, &o),
        Err(GpError::IdenticalInputs { n: 40 })
    ));
    assert!(matches!(
        gp.clone()
            .with_method(SparseMethod::Fitc)
            .fit_optimised(&x, 2, &y, &o),
        Err(GpError::Unsupported { .. })
    ));
    assert!(matches!(
        gp.clone()
            .with_method(SparseMethod::Fitc)
            .objective_gradient(&x, 2, &y),
        Err(GpError::Unsupported { .. })
    ));
    assert!(matches!(
        gp.clone().with_noise(1e-7).fit_optimised(&x, 2, &y, &o),
        Err(GpError::InvalidParameter(haunts_core::InvalidParameter {
            name: "noise",
            ..
        }))
    ));
    assert!(matches!(
        gp.fit_optimised(&x, 2, &y[..39], &o),
        Err(GpError::LengthMismatch { .. })
    ));
}

#[test]
fn staged_optimisation_with_a_capped_polish_stays_near_the_direct_optimum() {
    let (x, y) = data(13, 4000);
    let start =
        SparseGpRegression::new(Rbf::new(0.5, 1.0).unwrap(), Inducing::kmeans(40)).with_noise(0.1);
    let direct = {
        let mut p = OptimiseOptions::default();
        p.warm_start_subset = 0;
        p
    };
    let staged = {
        let mut p = OptimiseOptions::default();
        p.warm_start_subset = 300;
        p.polish_evaluations = 3;
        p
    };
    let (_, a) = start.fit_optimised(&x, 2, &y, &direct).unwrap();
    let (gp, b) = start.fit_optimised(&x, 2, &y, &staged).unwrap();
    eprintln!(
        "direct {:.8} ({} full evaluations), staged {:.8} ({} full, {} subset)",
        a.log_marginal_likelihood,
        a.full_evaluations,
        b.log_marginal_likelihood,
        b.full_evaluations,
        b.subset_evaluations
    );
    // The cap holds, and the best full pass's model is returned without another fit.
    assert!(b.full_evaluations <= 3 && b.subset_evaluations > 0);
    assert_eq!(gp.objective(), b.log_marginal_likelihood);
    assert!(a.log_marginal_likelihood >= b.log_marginal_likelihood - 1e-6);
    // Three full passes give up a little of the optimum: 1.2e-6 of the bound here (the
    // bound is flat in σ²), 6e-8 at n = 10⁵ (BENCHMARKS.md).
    assert!(
        b.log_marginal_likelihood
            >= a.log_marginal_likelihood - 3e-6 * a.log_marginal_likelihood.abs(),
        "staged {} vs direct {}",
        b.log_marginal_likelihood,
        a.log_marginal_likelihood
    );
}

/// Regression: with 25 inducing points on 10 × 10 and ℓ = 22, K(Z, Z) factored without jitter
/// (no negative pivot) and the bound was rounding noise (±2 over steps of 1e-7); a pivot
/// below 1e-11 of the variance now takes the next jitter, and the gradient is the slope again.
#[test]
fn nearly_singular_kuu_takes_jitter_and_the_bound_stays_smooth() {
    let seed = 365;
    let (x, y) = data(100 + 2 * seed, 90);
    let z: Vec<f64> = uniform(7 + seed, 2 * 25).iter().map(|u| u * 10.0).collect();
    let theta = [-2.0545405035017006, 3.0921521129365503, (1e-6f64).ln()];
    let centre = at(&theta, &z, &x, &y, 23, Mean::Data).unwrap();
    assert!(centre.jitter > 0.0);
    let h = 1e-3;
    for k in 0..3 {
        let mut d = [0.0; 2];
        for (s, step) in [h, 2.0 * h].into_iter().enumerate() {
            let mut up = theta;
            let mut down = theta;
            up[k] += step;
            down[k] -= step;
            let u = at(&up, &z, &x, &y, 23, Mean::Data).unwrap();
            let dn = at(&down, &z, &x, &y, 23, Mean::Data).unwrap();
            d[s] = (u.value - dn.value) / (2.0 * step);
        }
        let fd = (4.0 * d[0] - d[1]) / 3.0;
        let g = centre.gradient[k];
        assert!(
            (fd - g).abs() <= 1e-5 * g.abs().max(1.0),
            "k = {k}: analytic {g}, differences {fd}"
        );
    }
}
