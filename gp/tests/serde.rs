//! With the `serde` feature, kernels, parameters and fitted models round-trip through JSON:
//! kernels with the same hyperparameters and covariances, models rebuilt by their fit and
//! predicting as before; deserialising refuses what the constructors and fits refuse.
#![cfg(feature = "serde")]
#![allow(clippy::unwrap_used)]

use haunts_gp::{
    Constant, Constrained, ExactGp, GpError, GpRegression, Grid2, GridCheck, GridMode,
    GridPrediction, Inducing, JitterPolicy, Kernel, Matern32, Matern52, Mean, OptimisationReport,
    OptimiseOptions, Periodic, Prediction, Product, Rbf, RbfArd, Scaled, SparseGp,
    SparseGpRegression, SparseMethod, SparseObjective, Sum, White, covariance,
};
use serde_json::{Value, json};

mod common;
use common::{uniform, wavy};

use haunts_test_support::json;
use json::{Tally, rejection, trip};

/// `|a − b| ≤ tol · max(1, |a|)` for every pair, and equal lengths.
fn assert_close(a: &[f64], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!((x - y).abs() <= tol * x.abs().max(1.0), "{i}: {x} vs {y}");
    }
}

/// Six points of R² on [0, 3]², with a repeated one (where `White` is not zero).
fn points() -> Vec<f64> {
    let mut x: Vec<f64> = uniform(7, 10).iter().map(|u| 3.0 * u).collect();
    x.extend_from_slice(&[x[2], x[3]]);
    x
}

/// A covered kernel of every type, and composites nesting them (all for points of R²).
fn kernels() -> Vec<Box<dyn Kernel>> {
    let rbf = Rbf::new(1.3, 0.7).unwrap();
    let ard = RbfArd::new(0.9, &[0.4, 2.5]).unwrap();
    vec![
        Box::new(rbf),
        Box::new(ard.clone()),
        Box::new(Matern32::new(2.0, 1.1).unwrap()),
        Box::new(Matern52::new(0.3, 0.9).unwrap()),
        Box::new(Periodic::new(1.5, 0.8, 2.2).unwrap()),
        Box::new(White::new(0.1).unwrap()),
        Box::new(Constant::new(0.7).unwrap()),
        Box::new(Scaled::new(3.0, Box::new(rbf)).unwrap()),
        Box::new(Sum::new(Box::new(rbf), Box::new(White::new(0.05).unwrap())).unwrap()),
        Box::new(
            Product::new(
                Box::new(Periodic::new(1.0, 1.2, 4.0).unwrap()),
                Box::new(ard.clone()),
            )
            .unwrap(),
        ),
        Box::new(
            Constrained::new(Box::new(rbf))
                .hold("variance")
                .unwrap()
                .bound("length_scale", 0.5, 20.0)
                .unwrap(),
        ),
        Box::new(
            Sum::new(
                Box::new(
                    Product::new(
                        Box::new(
                            Scaled::new(0.5, Box::new(Matern52::new(1.0, 2.0).unwrap())).unwrap(),
                        ),
                        Box::new(Constant::new(2.0).unwrap()),
                    )
                    .unwrap(),
                ),
                Box::new(
                    Constrained::new(Box::new(ard))
                        .hold("length_scale_1")
                        .unwrap(),
                ),
            )
            .unwrap(),
        ),
    ]
}

/// The same hyperparameters (names, values, bounds) and the same covariances and gradients,
/// to the bit.
fn assert_same_kernel(a: &dyn Kernel, b: &dyn Kernel) {
    let x = points();
    assert_eq!(a.as_any().type_id(), b.as_any().type_id(), "{a:?} vs {b:?}");
    assert_eq!(a.param_names(), b.param_names());
    assert_eq!(a.log_params(), b.log_params(), "{a:?}");
    assert_eq!(a.log_bounds(), b.log_bounds(), "{a:?}");
    assert_eq!(a.dim(), b.dim());
    assert_eq!(a.scale_param(), b.scale_param());
    assert_eq!(covariance(a, &x, 2).unwrap(), covariance(b, &x, 2).unwrap());
    let (mut ga, mut gb) = (vec![0.0; a.n_params()], vec![0.0; b.n_params()]);
    a.gradient(&x[0..2], &x[4..6], &mut ga);
    b.gradient(&x[0..2], &x[4..6], &mut gb);
    assert_eq!(ga, gb);
}

#[test]
fn every_kernel_round_trips_with_its_hyperparameters() {
    for k in kernels() {
        let back: Box<dyn Kernel> = trip(&k);
        assert_same_kernel(k.as_ref(), back.as_ref());
    }
    // The kernels by their own types too.
    let rbf = Rbf::new(1.3, 0.7).unwrap();
    assert_eq!(trip(&rbf), rbf);
    let ard = RbfArd::new(0.9, &[0.4, 2.5]).unwrap();
    assert_eq!(trip(&ard), ard);
    let m32 = Matern32::new(2.0, 1.1).unwrap();
    assert_eq!(trip(&m32), m32);
    let m52 = Matern52::new(0.3, 0.9).unwrap();
    assert_eq!(trip(&m52), m52);
    let per = Periodic::new(1.5, 0.8, 2.2).unwrap();
    assert_eq!(trip(&per), per);
    let white = White::new(0.1).unwrap();
    assert_eq!(trip(&white), white);
    let constant = Constant::new(0.7).unwrap();
    assert_eq!(trip(&constant), constant);
    let scaled = Scaled::new(3.0, Box::new(rbf)).unwrap();
    assert_same_kernel(&scaled, &trip(&scaled));
    let sum = Sum::new(Box::new(rbf), Box::new(white)).unwrap();
    assert_same_kernel(&sum, &trip(&sum));
    let product = Product::new(Box::new(per), Box::new(ard)).unwrap();
    assert_same_kernel(&product, &trip(&product));
    let constrained = Constrained::new(Box::new(rbf)).hold("variance").unwrap();
    assert_same_kernel(&constrained, &trip(&constrained));
}

#[test]
fn kernels_set_in_log_space_evaluate_the_same_after_a_round_trip() {
    for mut k in kernels() {
        let p: Vec<f64> = (0..k.n_params()).map(|i| 0.1 + 0.37 * i as f64).collect();
        k.set_log_params(&p).unwrap();
        let back: Box<dyn Kernel> = trip(&k);
        // Kernels evaluate with the natural values written, so the covariances agree to the
        // bit; the logs are recomputed from them, to the last bit.
        let x = points();
        assert_eq!(
            covariance(k.as_ref(), &x, 2).unwrap(),
            covariance(back.as_ref(), &x, 2).unwrap(),
            "{k:?}"
        );
        assert_close(&k.log_params(), &back.log_params(), 1e-15);
    }
}

#[test]
fn a_boxed_kernel_is_written_as_its_type_and_hyperparameters() {
    let k: Box<dyn Kernel> = Box::new(
        Sum::new(
            Box::new(Rbf::new(2.0, 0.5).unwrap()),
            Box::new(White::new(0.25).unwrap()),
        )
        .unwrap(),
    );
    assert_eq!(
        serde_json::to_value(&k).unwrap(),
        json!({"Sum": {
            "k1": {"Rbf": {"variance": 2.0, "length_scale": 0.5}},
            "k2": {"White": {"noise_level": 0.25}},
        }})
    );
    // Only what was changed of a constrained kernel is written; omitted lists are empty.
    let c = Constrained::new(Box::new(RbfArd::new(1.0, &[1.0, 2.0]).unwrap()))
        .hold("length_scale_0")
        .unwrap()
        .bound("variance", 0.5, 4.0)
        .unwrap();
    assert_eq!(
        serde_json::to_value(&c).unwrap(),
        json!({
            "inner": {"RbfArd": {"variance": 1.0, "length_scales": [1.0, 2.0]}},
            "held": ["length_scale_0"],
            "bounds": {"variance": [0.5, 4.0]},
        })
    );
    let plain: Constrained =
        serde_json::from_value(json!({"inner": {"Rbf": {"variance": 1.0, "length_scale": 2.0}}}))
            .unwrap();
    assert_eq!(plain.param_names(), ["variance", "length_scale"]);
}

/// A kernel of the user's: cannot be written.
#[derive(Debug, Clone)]
struct Flat;

impl Kernel for Flat {
    fn value(&self, _a: &[f64], _b: &[f64]) -> f64 {
        1.0
    }
    fn log_params(&self) -> Vec<f64> {
        Vec::new()
    }
    fn set_log_params(&mut self, _p: &[f64]) -> Result<(), GpError> {
        Ok(())
    }
    fn log_bounds(&self) -> Vec<(f64, f64)> {
        Vec::new()
    }
    fn param_names(&self) -> Vec<String> {
        Vec::new()
    }
    fn gradient(&self, _a: &[f64], _b: &[f64], _out: &mut [f64]) {}
    fn dim(&self) -> Option<usize> {
        None
    }
}

#[test]
fn a_kernel_of_the_user_is_an_error_naming_it() {
    let k = Sum::new(Box::new(Rbf::new(1.0, 1.0).unwrap()), Box::new(Flat)).unwrap();
    let e = serde_json::to_string(&k).unwrap_err().to_string();
    assert!(
        e.contains("Flat") && e.contains("cannot be serialised"),
        "{e}"
    );
    let gp = GpRegression::new(Flat)
        .with_noise(0.1)
        .fit(&[0.0, 1.0], 1, &[1.0, 2.0])
        .unwrap();
    assert!(serde_json::to_string(&gp).is_err());
}

#[test]
fn parameters_and_results_round_trip() {
    let jitter = JitterPolicy {
        initial: 1e-8,
        growth: 4.0,
        max_attempts: 3,
    };
    assert_eq!(trip(&jitter), jitter);
    assert_eq!(trip(&JitterPolicy::default()), JitterPolicy::default());
    for mean in [Mean::Zero, Mean::Constant(1.5), Mean::Data] {
        assert_eq!(trip(&mean), mean);
    }
    for method in [SparseMethod::Vfe, SparseMethod::Fitc] {
        assert_eq!(trip(&method), method);
    }
    for inducing in [
        Inducing::Given(vec![0.0, 1.0, 2.0, 3.0]),
        Inducing::KMeans {
            m: 7,
            lloyd: 3,
            sample: 100,
            seed: 42,
        },
        Inducing::Grid(vec![4, 5]),
    ] {
        assert_eq!(trip(&inducing), inducing);
    }
    let grid = Grid2 {
        origin: [-1.0, 2.5],
        step: [0.1, 0.2],
        shape: [30, 20],
    };
    assert_eq!(trip(&grid), grid);
    for mode in [
        GridMode::Exact,
        GridMode::fast(),
        GridMode::Fast {
            tolerance: 1e-6,
            check_points: 0,
        },
    ] {
        assert_eq!(trip(&mode), mode);
    }
    let options = {
        let mut p = OptimiseOptions::default();
        p.optimise_noise = false;
        p.noise_bounds = (1e-4, 10.0);
        p.restarts = 3;
        p.seed = 9;
        p.max_iters = 50;
        p.memory = 5;
        p.grad_tolerance = 1e-5;
        p.warm_start_subset = 0;
        p.warm_start_max = 1000;
        p.polish_evaluations = 2;
        p
    };
    assert_eq!(trip(&options), options);
    assert_eq!(
        trip(&OptimiseOptions::default()),
        OptimiseOptions::default()
    );
    let prediction = Prediction {
        mean: vec![1.0, -2.0],
        variance: vec![0.5, 0.0],
    };
    assert_eq!(trip(&prediction), prediction);
    let gp = GridPrediction {
        mean: vec![1.0],
        variance: vec![0.1],
        nodes: Some([8, 16]),
        checked: Some(GridCheck {
            points: 64,
            max_mean_error: 1e-12,
            max_relative_variance_error: 2e-11,
        }),
    };
    assert_eq!(trip(&gp), gp);
    let report = OptimisationReport {
        log_marginal_likelihood: -12.5,
        log_params: vec![0.1, -0.2],
        full_evaluations: 10,
        subset_evaluations: 30,
        runs: 2,
    };
    assert_eq!(trip(&report), report);
    let objective = SparseObjective {
        value: -3.0,
        gradient: vec![0.5],
        jitter: 0.0,
    };
    assert_eq!(trip(&objective), objective);
}

#[test]
fn configurations_round_trip_and_fit_the_same_model() {
    let (x, y) = wavy(21, 40);
    let xs: Vec<f64> = uniform(22, 20).iter().map(|u| 10.0 * u).collect();
    let exact = GpRegression::new(Matern52::new(1.0, 2.0).unwrap())
        .with_noise(0.02)
        .with_mean(Mean::Constant(0.25))
        .with_jitter(JitterPolicy::none())
        .with_chunk_size(3);
    let back: GpRegression = trip(&exact);
    assert_eq!(
        serde_json::to_value(&back).unwrap(),
        serde_json::to_value(&exact).unwrap()
    );
    let (a, b) = (exact.fit(&x, 2, &y).unwrap(), back.fit(&x, 2, &y).unwrap());
    assert_eq!(a.predict(&xs).unwrap(), b.predict(&xs).unwrap());
    let sparse = SparseGpRegression::new(Rbf::new(1.0, 2.0).unwrap(), Inducing::kmeans(8))
        .with_noise(0.05)
        .with_mean(Mean::Data)
        .with_method(SparseMethod::Fitc)
        .with_chunk_size(11);
    let back: SparseGpRegression = trip(&sparse);
    assert_eq!(
        serde_json::to_value(&back).unwrap(),
        serde_json::to_value(&sparse).unwrap()
    );
    let (a, b) = (sparse.fit(&x, 2, &y).unwrap(), back.fit(&x, 2, &y).unwrap());
    assert_eq!(a.predict(&xs).unwrap(), b.predict(&xs).unwrap());
}

/// The keys of a JSON object, sorted.
fn keys(v: &Value) -> Vec<String> {
    let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    k.sort();
    k
}

/// Test points of [0, 10]² (some outside the data's hull).
fn test_points() -> Vec<f64> {
    let mut xs: Vec<f64> = uniform(31, 2 * 25).iter().map(|u| 12.0 * u - 1.0).collect();
    xs.extend_from_slice(&[5.0, 5.0, 0.0, 0.0]);
    xs
}

/// The grid 2-D models are compared on.
const GRID: Grid2 = Grid2 {
    origin: [0.0, 0.0],
    step: [0.5, 0.5],
    shape: [21, 21],
};

/// Means and variances equal to 1e-12 (the same bits in practice).
fn assert_same_prediction(a: (&[f64], &[f64]), b: (&[f64], &[f64])) {
    assert_close(a.0, b.0, 1e-12);
    assert_close(a.1, b.1, 1e-12);
}

/// The loaded exact GP is the saved one: same data, same factor and jitter, same predictions
/// on test points (read as points of the model's dimension) and, for 2-D models, on a grid.
fn assert_same_exact(a: &ExactGp, b: &ExactGp) {
    assert_eq!((a.n(), a.dim()), (b.n(), b.dim()));
    assert_eq!((a.points(), a.targets()), (b.points(), b.targets()));
    assert_eq!((a.noise(), a.prior_mean()), (b.noise(), b.prior_mean()));
    assert_eq!(
        (a.mean_rule(), a.jitter_policy()),
        (b.mean_rule(), b.jitter_policy())
    );
    assert_eq!(a.jitter(), b.jitter());
    assert_close(
        &[a.log_marginal_likelihood()],
        &[b.log_marginal_likelihood()],
        1e-12,
    );
    let xs = test_points();
    let (pa, pb) = (a.predict(&xs).unwrap(), b.predict(&xs).unwrap());
    assert_same_prediction((&pa.mean, &pa.variance), (&pb.mean, &pb.variance));
    assert_close(
        &a.predict_mean(&xs).unwrap(),
        &b.predict_mean(&xs).unwrap(),
        1e-12,
    );
    if a.dim() == 2 {
        let fast = GridMode::fast();
        assert_same_grid(&a.predict_grid(&GRID, fast), &b.predict_grid(&GRID, fast));
    }
}

/// Two fast grid predictions, equal (see [`assert_same_prediction`]).
fn assert_same_grid(a: &Result<GridPrediction, GpError>, b: &Result<GridPrediction, GpError>) {
    let (a, b) = (a.as_ref().unwrap(), b.as_ref().unwrap());
    assert_same_prediction((&a.mean, &a.variance), (&b.mean, &b.variance));
}

#[test]
fn an_exact_gp_round_trips_and_predicts_as_before() {
    let (x, y) = wavy(5, 60);
    let kernel = Sum::new(
        Box::new(Scaled::new(0.8, Box::new(RbfArd::new(1.0, &[2.0, 3.0]).unwrap())).unwrap()),
        Box::new(Matern32::new(0.1, 0.5).unwrap()),
    )
    .unwrap();
    let gp = GpRegression::new(kernel)
        .with_noise(0.01)
        .with_mean(Mean::Data)
        .with_chunk_size(7)
        .fit(&x, 2, &y)
        .unwrap();
    let written = serde_json::to_value(&gp).unwrap();
    // What defines the model, not its factor nor its weights.
    assert_eq!(
        keys(&written),
        [
            "chunk_size",
            "dim",
            "jitter",
            "kernel",
            "mean",
            "noise",
            "points",
            "targets"
        ]
    );
    assert_eq!(written["targets"], json!(y));
    assert_eq!(written["mean"], json!("Data"));
    let back: ExactGp = trip(&gp);
    assert_same_exact(&gp, &back);

    // An optimised model (hyperparameters set in log space).
    let start = GpRegression::new(Rbf::new(1.0, 1.0).unwrap()).with_noise(0.1);
    let options = {
        let mut p = OptimiseOptions::default();
        p.restarts = 1;
        p
    };
    let (gp, _) = start.fit_optimised(&x, 2, &y, &options).unwrap();
    assert_same_exact(&gp, &trip(&gp));
}

#[test]
fn an_exact_gp_that_needed_jitter_round_trips_with_it() {
    // Repeated points without noise: K is singular, the default policy adds jitter.
    let x = [0.0, 1.0, 1.0, 2.0, 3.0];
    let y = [0.0, 1.0, 1.0, 0.5, -0.5];
    let gp = GpRegression::new(Rbf::new(1.0, 1.0).unwrap())
        .with_noise(0.0)
        .fit(&x, 1, &y)
        .unwrap();
    assert!(gp.jitter() > 0.0);
    assert_same_exact(&gp, &trip(&gp));
}

/// The loaded sparse GP is the saved one.
fn assert_same_sparse(a: &SparseGp, b: &SparseGp) {
    assert_eq!(a.inducing_points(), b.inducing_points());
    assert_eq!((a.n(), a.method()), (b.n(), b.method()));
    assert_eq!((a.noise(), a.jitter()), (b.noise(), b.jitter()));
    assert_eq!(a.jitter_policy(), b.jitter_policy());
    assert_eq!(a.objective(), b.objective());
    let xs = test_points();
    let (pa, pb) = (a.predict(&xs).unwrap(), b.predict(&xs).unwrap());
    assert_same_prediction((&pa.mean, &pa.variance), (&pb.mean, &pb.variance));
    let fast = GridMode::fast();
    assert_same_grid(&a.predict_grid(&GRID, fast), &b.predict_grid(&GRID, fast));
}

#[test]
fn a_sparse_gp_round_trips_and_predicts_as_before() {
    let (x, y) = wavy(9, 300);
    let kernel = Sum::new(
        Box::new(Rbf::new(1.0, 2.0).unwrap()),
        Box::new(Constant::new(0.1).unwrap()),
    )
    .unwrap();
    for (method, inducing) in [
        (SparseMethod::Vfe, Inducing::kmeans(25)),
        (SparseMethod::Fitc, Inducing::Grid(vec![5, 4])),
    ] {
        let gp = SparseGpRegression::from_box(Box::new(kernel.clone()), inducing)
            .with_noise(0.01)
            .with_mean(Mean::Data)
            .with_method(method)
            .with_chunk_size(64)
            .fit(&x, 2, &y)
            .unwrap();
        let written = serde_json::to_value(&gp).unwrap();
        // O(m²) numbers: no training data, no factor.
        assert_eq!(
            keys(&written),
            [
                "dim",
                "inducing_points",
                "jitter",
                "kernel",
                "method",
                "n",
                "noise",
                "objective",
                "prior_mean",
                "whitened_precision",
                "whitened_projection"
            ]
        );
        let m = gp.inducing_points().len() / 2;
        assert_eq!(
            written["whitened_precision"].as_array().unwrap().len(),
            m * (m + 1) / 2
        );
        assert_eq!(written["whitened_projection"].as_array().unwrap().len(), m);
        assert_same_sparse(&gp, &trip(&gp));
    }
    // A model of the optimiser (its factors come from the bound's gradient pass).
    let start = SparseGpRegression::new(Rbf::new(0.5, 3.0).unwrap(), Inducing::Grid(vec![5, 5]))
        .with_noise(0.1);
    let (gp, _) = start
        .fit_optimised(&x, 2, &y, &OptimiseOptions::default())
        .unwrap();
    assert_same_sparse(&gp, &trip(&gp));
}

#[test]
fn invalid_kernels_are_refused_with_the_reason() {
    let cases = [
        (
            json!({"Rbf": {"variance": 1.0, "length_scale": -2.0}}),
            "hyperparameter `length_scale` = -2",
        ),
        (
            json!({"Matern32": {"variance": 0.0, "length_scale": 1.0}}),
            "hyperparameter `variance` = 0",
        ),
        (
            json!({"Periodic": {"variance": 1.0, "length_scale": 1.0, "periodicity": -1.0}}),
            "`periodicity`",
        ),
        (
            json!({"RbfArd": {"variance": 1.0, "length_scales": [1.0, -0.5]}}),
            "`length_scale_1`",
        ),
        (
            json!({"RbfArd": {"variance": 1.0, "length_scales": []}}),
            "dimension mismatch",
        ),
        (json!({"White": {"noise_level": null}}), "null"),
        (
            json!({"Matern52": {"variance": 1.0}}),
            "missing field `length_scale`",
        ),
        (
            json!({"Cosine": {"variance": 1.0}}),
            "unknown variant `Cosine`",
        ),
        (
            json!({"Scaled": {"constant_value": -1.0, "inner": {"Constant": {"constant_value": 1.0}}}}),
            "`constant_value`",
        ),
        (
            json!({"Sum": {
                "k1": {"RbfArd": {"variance": 1.0, "length_scales": [1.0, 1.0]}},
                "k2": {"RbfArd": {"variance": 1.0, "length_scales": [1.0, 1.0, 1.0]}},
            }}),
            "dimension mismatch: expected 2, found 3",
        ),
        (
            json!({"Product": {"k1": {"Rbf": {"variance": 1.0, "length_scale": 1.0}}}}),
            "missing field `k2`",
        ),
        (
            json!({"Constrained": {
                "inner": {"Rbf": {"variance": 1.0, "length_scale": 1.0}},
                "held": ["lengthscale"],
            }}),
            "no hyperparameter `lengthscale`",
        ),
        (
            json!({"Constrained": {
                "inner": {"Rbf": {"variance": 1.0, "length_scale": 1.0}},
                "bounds": {"length_scale": [2.0, 1.0]},
            }}),
            "upper bound",
        ),
    ];
    for (v, reason) in cases {
        let e = rejection::<Box<dyn Kernel>>(&v);
        assert!(e.contains(reason), "{v}: {e}");
    }
    // By type too.
    let e = rejection::<Rbf>(&json!({"variance": 1.0, "length_scale": -2.0}));
    assert!(e.contains("`length_scale` = -2"), "{e}");
    let e = rejection::<Periodic>(&json!({"variance": 1.0, "length_scale": 1.0}));
    assert!(e.contains("missing field `periodicity`"), "{e}");
}

#[test]
fn invalid_exact_models_are_refused_with_the_reason() {
    let (x, y) = wavy(3, 12);
    let gp = GpRegression::new(Rbf::new(1.0, 2.0).unwrap())
        .with_noise(0.01)
        .fit(&x, 2, &y)
        .unwrap();
    let good = serde_json::to_value(&gp).unwrap();
    let with = |edit: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        edit(&mut v);
        rejection::<ExactGp>(&v)
    };
    let e = with(&|v| {
        v["targets"].as_array_mut().unwrap().pop();
    });
    assert!(e.contains("12 points but 11 targets"), "{e}");
    let e = with(&|v| v["points"][3] = Value::Null);
    assert!(e.contains("invalid type: null, expected f64"), "{e}");
    let e = with(&|v| v["targets"][0] = Value::Null);
    assert!(e.contains("null"), "{e}");
    let e = with(&|v| {
        v.as_object_mut().unwrap().remove("targets");
    });
    assert!(e.contains("missing field `targets`"), "{e}");
    let e = with(&|v| v["noise"] = json!(-1.0));
    assert!(e.contains("`noise` = -1"), "{e}");
    let e = with(&|v| v["kernel"]["Rbf"]["length_scale"] = json!(-2.0));
    assert!(e.contains("`length_scale` = -2"), "{e}");
    let e = with(&|v| v["dim"] = json!(5));
    assert!(e.contains("cannot hold points of dimension 5"), "{e}");
    let e = with(&|v| v["chunk_size"] = json!(0));
    assert!(e.contains("chunk_size"), "{e}");
    // Repeated points, no noise and no jitter allowed: K is not positive definite.
    let e = with(&|v| {
        v["noise"] = json!(0.0);
        v["jitter"]["max_attempts"] = json!(1);
        v["points"][2] = v["points"][0].clone();
        v["points"][3] = v["points"][1].clone();
    });
    assert!(e.contains("not positive definite"), "{e}");
}

#[test]
fn invalid_sparse_models_are_refused_with_the_reason() {
    let (x, y) = wavy(4, 80);
    let gp = SparseGpRegression::new(Rbf::new(1.0, 2.0).unwrap(), Inducing::Grid(vec![3, 3]))
        .with_noise(0.01)
        .fit(&x, 2, &y)
        .unwrap();
    let good = serde_json::to_value(&gp).unwrap();
    let with = |edit: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        edit(&mut v);
        rejection::<SparseGp>(&v)
    };
    let e = with(&|v| {
        v["whitened_projection"].as_array_mut().unwrap().pop();
    });
    assert!(
        e.contains("`whitened_projection` has 8 numbers, 9 expected"),
        "{e}"
    );
    let e = with(&|v| {
        v["whitened_precision"]
            .as_array_mut()
            .unwrap()
            .push(json!(1.0));
    });
    assert!(
        e.contains("`whitened_precision` has 46 numbers, 45 expected"),
        "{e}"
    );
    let e = with(&|v| {
        v["inducing_points"].as_array_mut().unwrap().pop();
    });
    assert!(e.contains("cannot hold points of dimension 2"), "{e}");
    let e = with(&|v| v["inducing_points"][0] = Value::Null);
    assert!(e.contains("invalid type: null, expected f64"), "{e}");
    let e = with(&|v| v["whitened_precision"][4] = Value::Null);
    assert!(e.contains("null"), "{e}");
    let e = with(&|v| {
        v.as_object_mut().unwrap().remove("objective");
    });
    assert!(e.contains("missing field `objective`"), "{e}");
    let e = with(&|v| v["noise"] = json!(0.0));
    assert!(e.contains("`noise` = 0"), "{e}");
    let e = with(&|v| v["n"] = json!(0));
    assert!(e.contains("no training points"), "{e}");
    let e = with(&|v| v["method"] = json!("Exact"));
    assert!(e.contains("unknown variant `Exact`"), "{e}");
    // B = −I: not positive definite.
    let e = with(&|v| {
        let mut b = Vec::new();
        for i in 0..9 {
            b.extend((0..=i).map(|j| if i == j { -1.0 } else { 0.0 }));
        }
        v["whitened_precision"] = json!(b);
    });
    assert!(e.contains("not positive definite"), "{e}");
}

/// `n` test points of dimension `dim` on [−1, 11], from `seed`.
fn points_of(dim: usize, n: usize, seed: u64) -> Vec<f64> {
    uniform(seed, dim * n)
        .iter()
        .map(|u| 12.0 * u - 1.0)
        .collect()
}

/// Everything a loaded kernel offers: its hyperparameters, values, gradients and covariance
/// matrices, setting its own log parameters back, and writing it again.
fn exercise_kernel(k: &dyn Kernel) {
    let p = k.n_params();
    assert_eq!(k.log_params().len(), p);
    assert_eq!(k.log_bounds().len(), p);
    assert_eq!(k.param_names().len(), p);
    let _ = k.scale_param();
    let dim = k.dim().unwrap_or(2);
    assert!(dim <= 8, "{k:?}");
    let x = points_of(dim, 6, 40);
    let _ = k.try_value(&x[..dim], &x[dim..2 * dim]);
    let _ = k.value(&x[..dim], &x[..dim]);
    let mut g = vec![0.0; p];
    k.gradient(&x[..dim], &x[dim..2 * dim], &mut g);
    covariance(k, &x, dim).unwrap();
    haunts_gp::cross_covariance(k, &x[..2 * dim], &x, dim).unwrap();
    // Other dimensions are typed errors, not panics.
    let _ = covariance(k, &x[..3], 3);
    let mut copy = k.clone_box();
    let _ = copy.set_log_params(&k.log_params());
    let _ = copy.set_log_params(&vec![1e300; p]);
    let again = serde_json::to_value(k).unwrap();
    serde_json::from_value::<Box<dyn Kernel>>(again).unwrap();
}

/// Everything a loaded exact GP offers.
fn exercise_exact(gp: &ExactGp) {
    let (n, dim) = (gp.n(), gp.dim());
    assert_eq!(gp.points().len(), n * dim);
    assert_eq!(gp.targets().len(), n);
    let _ = (gp.noise(), gp.prior_mean(), gp.mean_rule(), gp.jitter());
    let _ = (gp.jitter_policy(), gp.log_marginal_likelihood());
    exercise_kernel(gp.kernel());
    assert_eq!(
        gp.log_marginal_likelihood_gradient().len(),
        gp.kernel().n_params() + 1
    );
    let xs = points_of(dim, 7, 41);
    let p = gp.predict(&xs).unwrap();
    assert_eq!((p.mean.len(), p.variance.len()), (7, 7));
    assert_eq!(gp.predict_mean(&xs).unwrap().len(), 7);
    assert_eq!(gp.predict_variance(&xs).unwrap().len(), 7);
    assert!(gp.predict(&[]).unwrap().mean.is_empty());
    on_a_small_grid(dim, |grid, mode| gp.predict_grid(grid, mode));
}

/// Predictions of a loaded model on a 12 × 9 grid in both modes: the full grid for a 2-D
/// model, an error otherwise.
fn on_a_small_grid(
    dim: usize,
    predict: impl Fn(&Grid2, GridMode) -> Result<GridPrediction, GpError>,
) {
    let small = Grid2 {
        origin: [-1.0, 0.5],
        step: [0.7, 0.4],
        shape: [12, 9],
    };
    for mode in [GridMode::Exact, GridMode::fast()] {
        match predict(&small, mode) {
            Ok(g) => assert_eq!((g.mean.len(), g.variance.len()), (12 * 9, 12 * 9)),
            Err(e) => assert!(dim != 2, "{e}"),
        }
    }
}

/// Everything a loaded sparse GP offers.
fn exercise_sparse(gp: &SparseGp) {
    let _ = (gp.n(), gp.method(), gp.noise(), gp.jitter());
    let _ = (gp.jitter_policy(), gp.objective());
    let dim = serde_json::to_value(gp).unwrap()["dim"].as_u64().unwrap() as usize;
    assert_eq!(gp.inducing_points().len() % dim, 0);
    let xs = points_of(dim, 7, 42);
    let p = gp.predict(&xs).unwrap();
    assert_eq!((p.mean.len(), p.variance.len()), (7, 7));
    assert!(gp.predict(&xs[..1]).is_err() || dim == 1);
    on_a_small_grid(dim, |grid, mode| gp.predict_grid(grid, mode));
}

#[test]
fn corrupted_files_are_refused_or_usable_never_a_panic() {
    // Every kernel through `Box<dyn Kernel>`: all of their variants (a few dozen each).
    let mut kernel_tally = Tally::default();
    for k in kernels() {
        let value = serde_json::to_value(&k).unwrap();
        kernel_tally.read::<Box<dyn Kernel>>(json::mutations(&value, 400), |k, _| {
            exercise_kernel(k.as_ref());
            true
        });
    }
    // An exact GP of 12 points of R² (a refit on every load).
    let (x, y) = wavy(3, 12);
    let kernel = Sum::new(
        Box::new(Scaled::new(0.8, Box::new(RbfArd::new(1.0, &[2.0, 3.0]).unwrap())).unwrap()),
        Box::new(White::new(0.01).unwrap()),
    )
    .unwrap();
    let exact = GpRegression::new(kernel)
        .with_noise(0.01)
        .with_mean(Mean::Data)
        .with_chunk_size(5)
        .fit(&x, 2, &y)
        .unwrap();
    let mut exact_tally = Tally::default();
    exact_tally.read::<ExactGp>(
        json::mutations(&serde_json::to_value(&exact).unwrap(), 300),
        |gp, _| {
            exercise_exact(gp);
            true
        },
    );
    // Sparse GPs of both methods with 9 inducing points.
    let (x, y) = wavy(4, 80);
    let mut sparse_tally = Tally::default();
    for (method, inducing) in [
        (SparseMethod::Vfe, Inducing::Grid(vec![3, 3])),
        (SparseMethod::Fitc, Inducing::kmeans(9)),
    ] {
        let gp = SparseGpRegression::new(Rbf::new(1.0, 2.0).unwrap(), inducing)
            .with_noise(0.01)
            .with_mean(Mean::Data)
            .with_method(method)
            .fit(&x, 2, &y)
            .unwrap();
        sparse_tally.read::<SparseGp>(
            json::mutations(&serde_json::to_value(&gp).unwrap(), 600),
            |gp, _| {
                exercise_sparse(gp);
                true
            },
        );
    }
    eprintln!("kernels {kernel_tally:?}, exact {exact_tally:?}, sparse {sparse_tally:?}");
    for t in [&kernel_tally, &exact_tally, &sparse_tally] {
        assert!(t.refused > 0 && t.accepted > 0, "{t:?}");
    }
}

#[test]
fn an_exact_gp_with_the_largest_chunk_size_predicts_in_one_block() {
    // `chunk_size · dim` overflowed in the prediction (a panic) for a chunk size of 2⁶³ read
    // from a file; it is one block of every test point instead.
    let gp: ExactGp = serde_json::from_value(json!({
        "kernel": {"Rbf": {"variance": 1.0, "length_scale": 1.0}},
        "noise": 0.01, "mean": "Zero",
        "jitter": {"initial": 1e-10, "growth": 10.0, "max_attempts": 7},
        "chunk_size": 1u64 << 63, "dim": 2,
        "points": [0.0, 0.0, 1.0, 1.0], "targets": [1.0, -1.0],
    }))
    .unwrap();
    let p = gp.predict(&[0.0, 0.0, 1.0, 1.0, 5.0, 5.0]).unwrap();
    assert_eq!(p.mean.len(), 3);
    assert!((p.mean[0] - 1.0).abs() < 0.05 && p.mean[2].abs() < 1e-6);
}

#[test]
fn a_sparse_configuration_with_the_largest_chunk_size_fits_in_one_block() {
    // The same overflow in the sparse fit's and its optimiser's blocks.
    let (x, y) = wavy(4, 40);
    let config: SparseGpRegression = serde_json::from_value(json!({
        "kernel": {"Rbf": {"variance": 1.0, "length_scale": 2.0}},
        "inducing": {"Grid": [3, 3]}, "noise": 0.01, "mean": "Zero", "method": "Vfe",
        "jitter": {"initial": 1e-10, "growth": 10.0, "max_attempts": 7},
        "chunk_size": 1u64 << 63,
    }))
    .unwrap();
    let gp = config.fit(&x, 2, &y).unwrap();
    let one_block = config.clone().with_chunk_size(40).fit(&x, 2, &y).unwrap();
    assert_eq!(gp.objective(), one_block.objective());
    let options = {
        let mut p = OptimiseOptions::default();
        p.restarts = 0;
        p.max_iters = 3;
        p
    };
    config.fit_optimised(&x, 2, &y, &options).unwrap();
}
