//! The exact and sparse GPs against scikit-learn's `GaussianProcessRegressor` and GPy's
//! sparse GPs, on the fixtures written by `benches/peers/gp_fixtures.py`.

use std::path::Path;

use haunts_gp::{
    GpRegression, Inducing, Kernel, Matern32, Matern52, Mean, OptimiseOptions, Periodic, Rbf,
    RbfArd, SparseGpRegression, SparseMethod, Sum,
};
use serde_json::Value;

fn load(name: &str) -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

fn flat(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .flat_map(|row| match row.as_array() {
            Some(r) => r.iter().map(f).collect(),
            None => vec![f(row)],
        })
        .collect()
}

/// A kernel from the fixtures' `spec` tree; `C * stationary` becomes our stationary kernel
/// with its own variance (same hyperparameter order as scikit-learn).
fn kernel(spec: &Value) -> Box<dyn Kernel> {
    match spec["type"].as_str().unwrap() {
        "sum" => Box::new(Sum::new(kernel(&spec["k1"]), kernel(&spec["k2"])).unwrap()),
        "product" => {
            assert_eq!(spec["k1"]["type"], "constant");
            let c = f(&spec["k1"]["constant_value"]);
            let k = &spec["k2"];
            match k["type"].as_str().unwrap() {
                "rbf" if k["ard"].as_bool().unwrap() => {
                    Box::new(RbfArd::new(c, &flat(&k["length_scale"])).unwrap())
                }
                "rbf" => Box::new(Rbf::new(c, flat(&k["length_scale"])[0]).unwrap()),
                "matern" => {
                    let l = flat(&k["length_scale"])[0];
                    if f(&k["nu"]) == 1.5 {
                        Box::new(Matern32::new(c, l).unwrap())
                    } else {
                        Box::new(Matern52::new(c, l).unwrap())
                    }
                }
                "exp_sine_squared" => {
                    Box::new(Periodic::new(c, f(&k["length_scale"]), f(&k["periodicity"])).unwrap())
                }
                other => panic!("unexpected kernel {other}"),
            }
        }
        other => panic!("unexpected kernel {other}"),
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300) || (a - b).abs() <= 1e-13
}

#[test]
fn exact_gp_equals_scikit_learn_with_fixed_hyperparameters() {
    for name in [
        "sklearn_rbf_2d_200.json",
        "sklearn_ard_2d_500.json",
        "sklearn_matern52_1d_50.json",
        "sklearn_matern32_2d_300.json",
        "sklearn_periodic_1d_100.json",
        "sklearn_sum_2d_200.json",
        "sklearn_datamean_rbf_2d_150.json",
    ] {
        let d = load(name);
        let dim = d["dim"].as_u64().unwrap() as usize;
        let k = kernel(&d["kernel"]["spec"]);
        assert_eq!(
            k.log_params().len(),
            d["kernel"]["theta"].as_array().unwrap().len(),
            "{name}"
        );
        for (a, b) in k.log_params().iter().zip(flat(&d["kernel"]["theta"])) {
            assert!((a - b).abs() < 1e-14, "{name}: theta {a} vs {b}");
        }
        let mean = if d["prior_mean"]["type"] == "zero" {
            Mean::Zero
        } else {
            Mean::Data
        };
        let gp = GpRegression::from_box(k)
            .with_noise(f(&d["noise"]))
            .with_mean(mean)
            .fit(&flat(&d["x_train"]), dim, &flat(&d["y_train"]))
            .unwrap();
        assert_eq!(gp.jitter(), 0.0, "{name}");
        assert!(
            (gp.prior_mean() - f(&d["mean_offset"])).abs() < 1e-12,
            "{name}"
        );
        let p = gp.predict(&flat(&d["x_test"])).unwrap();
        for (j, (m, v)) in flat(&d["mean"]).iter().zip(flat(&d["var"])).enumerate() {
            assert!(
                close(p.mean[j], *m, 1e-8),
                "{name} mean {j}: {} vs {m}",
                p.mean[j]
            );
            assert!(
                close(p.variance[j], v, 1e-8),
                "{name} var {j}: {} vs {v}",
                p.variance[j]
            );
        }
        let lml = f(&d["lml"]);
        assert!(
            close(gp.log_marginal_likelihood(), lml, 1e-8),
            "{name}: {} vs {lml}",
            gp.log_marginal_likelihood()
        );
        // scikit-learn's gradient is over the kernel's log hyperparameters (ours also has
        // log σn² last, which alpha does not have).
        let g = gp.log_marginal_likelihood_gradient();
        for (a, b) in g.iter().zip(flat(&d["lml_gradient"])) {
            assert!(
                (a - b).abs() <= 1e-7 * (1.0 + b.abs()),
                "{name}: gradient {a} vs {b}"
            );
        }
    }
}

#[test]
fn optimised_likelihood_is_at_least_scikit_learns() {
    for name in ["sklearn_opt_rbf_2d_300.json", "sklearn_opt_ard_2d_200.json"] {
        let d = load(name);
        let dim = d["dim"].as_u64().unwrap() as usize;
        let spec = &d["start_kernel"]["spec"];
        // scikit-learn optimises C * RBF + WhiteKernel with alpha = 0; our noise is σn².
        assert_eq!(spec["k2"]["type"], "white");
        let k = kernel(&spec["k1"]);
        let start = GpRegression::from_box(k).with_noise(f(&spec["k2"]["noise_level"]));
        let (x, y) = (flat(&d["x_train"]), flat(&d["y_train"]));
        let start_lml = start.fit(&x, dim, &y).unwrap().log_marginal_likelihood();
        assert!(
            close(start_lml, f(&d["lml_start"]), 1e-9),
            "{name}: start {start_lml}"
        );
        let (gp, report) = start
            .fit_optimised(&x, dim, &y, &OptimiseOptions::default())
            .unwrap();
        let theirs = f(&d["lml"]);
        assert!(
            report.log_marginal_likelihood >= theirs - 1e-6,
            "{name}: ours {} < scikit-learn {theirs}",
            report.log_marginal_likelihood
        );
        assert_eq!(gp.log_marginal_likelihood(), report.log_marginal_likelihood);
        eprintln!(
            "{name}: ours {:.9} scikit-learn {theirs:.9} ({} evaluations)",
            report.log_marginal_likelihood, report.full_evaluations
        );
    }
}

#[test]
fn sparse_gps_equal_gpy() {
    for (name, method) in [
        ("gpy_vfe_2d_300.json", SparseMethod::Vfe),
        ("gpy_fitc_2d_300.json", SparseMethod::Fitc),
    ] {
        let d = load(name);
        let k = Rbf::new(f(&d["kernel"]["variance"]), f(&d["kernel"]["lengthscale"])).unwrap();
        let gp = SparseGpRegression::new(k, Inducing::Given(flat(&d["z"])))
            .with_noise(f(&d["noise"]))
            .with_method(method)
            .fit(&flat(&d["x_train"]), 2, &flat(&d["y_train"]))
            .unwrap();
        assert_eq!(gp.jitter(), 0.0);
        // GPy's values without its 1e-8 jitter on Kuu.
        let reference = &d["no_jitter"];
        let lml = f(&reference["log_likelihood"]);
        assert!(
            close(gp.objective(), lml, 1e-8),
            "{name}: {} vs {lml}",
            gp.objective()
        );
        assert!(
            gp.objective() < f(&d["exact_lml"]),
            "{name}: a bound below the exact likelihood"
        );
        let p = gp.predict(&flat(&d["x_test"])).unwrap();
        for (j, (m, v)) in flat(&reference["mean"])
            .iter()
            .zip(flat(&reference["var"]))
            .enumerate()
        {
            assert!(
                (p.mean[j] - m).abs() < 1e-8 * (1.0 + m.abs()),
                "{name} mean {j}: {} vs {m}",
                p.mean[j]
            );
            assert!(
                (p.variance[j] - v).abs() < 1e-8,
                "{name} var {j}: {} vs {v}",
                p.variance[j]
            );
        }
    }
}
