//! The hypertime model on synthetic data: Gustafson–Kessel against a plain reference, its
//! invariants and bad input; the mixture's conditional density; FreMEn and the choice of k.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use approx::assert_relative_eq;
use haunts_affordance::hypertime::{
    Background, ClusterSearch, CycleValidation, DAY, DetectionColumns, EvaluationParams,
    GivenPeriods, GkParams, HoldOut, HypertimeModel, HypertimeParams, PeriodSearch, Projection,
    Regularisation, TimedPoint, evaluate, grid_log_likelihood, kmeans_plus_plus, parse_detections,
    read_detections,
};
use haunts_affordance::{AffordanceError, DensityMap};
use haunts_occupancy::GridGeometry;
use haunts_tracking::{Delimiter, SkipReason};
use nalgebra::{DMatrix, DVector, Point2};
use proptest::prelude::*;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// Three elongated blobs in the plane, `per` points each, and their centres.
fn blobs(per: usize, seed: u64) -> (Vec<f64>, [[f64; 2]; 3]) {
    let centres = [[0.0, 0.0], [6.0, 1.0], [2.0, 7.0]];
    let mut rng = StdRng::seed_from_u64(seed);
    let mut data = Vec::new();
    for (i, c) in centres.iter().enumerate() {
        for _ in 0..per {
            let (a, b) = (gaussian(&mut rng), gaussian(&mut rng));
            // Each blob stretched along its own direction.
            let (sx, sy) = [(1.0, 0.2), (0.2, 1.0), (0.6, 0.6)][i];
            data.extend_from_slice(&[c[0] + sx * a, c[1] + sy * b]);
        }
    }
    (data, centres)
}

#[test]
fn gk_recovers_blob_centres() {
    let (data, truth) = blobs(300, 1);
    let gk = GkParams::default().with_clusters(3).fit(&data, 2).unwrap();
    for c in truth {
        let nearest = (0..3)
            .map(|i| {
                let f = gk.centre(i).unwrap();
                ((f[0] - c[0]).powi(2) + (f[1] - c[1]).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(nearest < 0.15, "centre {c:?} missed by {nearest}");
    }
    // Every cluster's norm-inducing matrix has determinant ρ.
    for i in 0..3 {
        assert_relative_eq!(
            gk.norm_matrix(i, 1.0).unwrap().determinant(),
            1.0,
            epsilon = 1e-9
        );
    }
    // The elongated blobs' covariances are elongated the right way.
    let labels = gk.hard_labels();
    assert_eq!(labels.len(), 900);
    let first = labels[0];
    let f = gk.covariance(first).unwrap();
    assert!(f[(0, 0)] > 5.0 * f[(1, 1)], "{f}");
}

#[test]
fn gk_matches_the_plain_reference_on_blobs() {
    let (data, _) = blobs(60, 2);
    let params = GkParams::default()
        .with_clusters(3)
        .with_tolerance(1e-9)
        .with_max_iterations(500);
    let fast = params.fit(&data, 2).unwrap();
    let init = kmeans_plus_plus(&data, 2, 3, params.seed).unwrap();
    let slow = reference_gk(&data, 2, &init, &params, fast.iterations());
    for (a, b) in fast.centres().iter().zip(&slow.centres) {
        assert_relative_eq!(*a, *b, epsilon = 1e-8);
    }
    for (a, b) in fast.memberships().iter().zip(&slow.memberships) {
        assert_relative_eq!(*a, *b, epsilon = 1e-8);
    }
}

fn random_data(n: usize, dim: usize, seed: u64) -> Vec<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n * dim)
        .map(|i| {
            // A few groups so clusters have something to find.
            let group = (i / dim) % 3;
            group as f64 * 3.0 + gaussian(&mut rng)
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// A few iterations of the fast GK equal the plain one's, memberships and all.
    #[test]
    fn gk_equals_reference(n in 8usize..60, dim in 1usize..5, k in 1usize..5, seed in 0u64..1000,
                           iterations in 1usize..6) {
        let data = random_data(n, dim, seed);
        let params = GkParams::default().with_clusters(k).with_tolerance(0.0)
            .with_max_iterations(iterations).with_seed(seed);
        let fast = match params.fit(&data, dim) {
            Ok(c) => c,
            Err(AffordanceError::NotConverged { partial, iterations: it, .. }) => {
                prop_assert_eq!(it, iterations);
                *partial
            }
            Err(e) => panic!("{e}"),
        };
        let init = kmeans_plus_plus(&data, dim, k, seed).unwrap();
        let slow = reference_gk(&data, dim, &init, &params, fast.iterations());
        for (a, b) in fast.centres().iter().zip(&slow.centres) {
            prop_assert!((a - b).abs() <= 1e-7 * (1.0 + b.abs()), "{} vs {}", a, b);
        }
        for (a, b) in fast.memberships().iter().zip(&slow.memberships) {
            prop_assert!((a - b).abs() <= 1e-7, "{} vs {}", a, b);
        }
        for i in 0..k {
            let f = fast.covariance(i).unwrap();
            for (a, b) in f.iter().zip(slow.covariances[i].iter()) {
                prop_assert!((a - b).abs() <= 1e-7 * (1.0 + b.abs()), "{} vs {}", a, b);
            }
        }
    }

    /// Memberships are in [0, 1] and sum to 1 for every point.
    #[test]
    fn memberships_sum_to_one(n in 4usize..80, dim in 1usize..5, k in 1usize..5, seed in 0u64..1000,
                              m in 1.2f64..3.0) {
        prop_assume!(k <= n);
        let data = random_data(n, dim, seed);
        let params = GkParams::default().with_clusters(k).with_fuzzifier(m).with_seed(seed)
            .with_max_iterations(20);
        let gk = match params.fit(&data, dim) {
            Ok(c) => c,
            Err(AffordanceError::NotConverged { partial, .. }) => *partial,
            Err(e) => panic!("{e}"),
        };
        prop_assert_eq!(gk.len(), n);
        for j in 0..n {
            let u = gk.membership(j).unwrap();
            prop_assert!(u.iter().all(|v| (0.0..=1.0).contains(v)));
            prop_assert!((u.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn same_seed_same_clustering_on_any_number_of_threads() {
    // Several blocks of rows, so the parallel sums really split.
    let data = random_data(3 * 512 + 77, 4, 5);
    let params = GkParams::default()
        .with_clusters(6)
        .with_seed(9)
        .with_max_iterations(40);
    // Converged or not, the result must be the same.
    let fit = |params: GkParams| match params.fit(&data, 4) {
        Ok(c) => c,
        Err(AffordanceError::NotConverged { partial, .. }) => *partial,
        Err(e) => panic!("{e}"),
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| fit(params))
    };
    let one = run(1);
    assert_eq!(one, run(3));
    assert_eq!(one, fit(params));
    let other = fit(params.with_seed(10));
    assert_ne!(one.centres(), other.centres());
}

#[test]
fn identical_points_give_a_well_defined_clustering() {
    let data = [1.5, -2.0].repeat(40);
    let gk = GkParams::default().with_clusters(3).fit(&data, 2).unwrap();
    for i in 0..3 {
        assert_eq!(gk.centre(i).unwrap(), &[1.5, -2.0]);
        assert!(gk.covariance(i).unwrap().iter().all(|v| v.is_finite()));
    }
    for j in 0..40 {
        for u in gk.membership(j).unwrap() {
            assert_relative_eq!(*u, 1.0 / 3.0, epsilon = 1e-15);
        }
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let data = [0.0, 0.0, 1.0, 1.0];
    assert!(matches!(
        GkParams::default().with_clusters(3).fit(&data, 2),
        Err(AffordanceError::TooFewPoints {
            points: 2,
            clusters: 3
        })
    ));
    assert!(matches!(
        GkParams::default().with_clusters(1).fit(&data, 3),
        Err(AffordanceError::BadShape { len: 4, dim: 3 })
    ));
    assert!(matches!(
        GkParams::default().with_clusters(1).fit(&data, 0),
        Err(AffordanceError::BadShape { dim: 0, .. })
    ));
    assert!(matches!(
        GkParams::default()
            .with_clusters(1)
            .fit(&[0.0, 0.0, f64::NAN, 1.0], 2),
        Err(AffordanceError::NonFiniteInput { row: 1, column: 0 })
    ));
    assert!(matches!(
        GkParams::default().with_clusters(1).fit(&[], 2),
        Err(AffordanceError::TooFewPoints { points: 0, .. })
    ));
    let bad = [
        (GkParams::default().with_clusters(0), "clusters"),
        (GkParams::default().with_fuzzifier(1.0), "fuzzifier"),
        (GkParams::default().with_fuzzifier(f64::NAN), "fuzzifier"),
        (GkParams::default().with_volume(0.0), "volume"),
        (GkParams::default().with_tolerance(-1.0), "tolerance"),
        (GkParams::default().with_max_iterations(0), "max_iterations"),
        (
            GkParams::default().with_regularisation(Regularisation {
                identity_blend: 1.5,
                ..Regularisation::default()
            }),
            "identity_blend",
        ),
        (
            GkParams::default().with_regularisation(Regularisation {
                max_condition: 0.5,
                ..Regularisation::default()
            }),
            "max_condition",
        ),
        (
            GkParams::default().with_regularisation(Regularisation {
                min_eigenvalue: 0.0,
                ..Regularisation::default()
            }),
            "min_eigenvalue",
        ),
    ];
    for (params, field) in bad {
        match params.fit(&data, 2) {
            Err(AffordanceError::InvalidParameter(haunts_core::InvalidParameter {
                name, ..
            })) => assert_eq!(name, field),
            other => panic!("{field}: {other:?}"),
        }
    }
}

#[test]
fn the_iteration_cap_returns_the_partial_clustering() {
    let (data, _) = blobs(50, 3);
    let err = GkParams::default()
        .with_clusters(3)
        .with_tolerance(0.0)
        .with_max_iterations(2)
        .fit(&data, 2)
        .unwrap_err();
    let AffordanceError::NotConverged {
        iterations,
        change,
        partial,
    } = err
    else {
        panic!("{err:?}");
    };
    assert_eq!((iterations, partial.iterations()), (2, 2));
    assert!(change > 0.0 && change.is_finite());
    assert_eq!(partial.len(), 150);
}

#[test]
fn identity_blending_widens_flat_clusters() {
    // Points on a line: without blending the cross-line variance sits at the eigenvalue floor.
    let data: Vec<f64> = (0..100).flat_map(|i| [i as f64 * 0.1, 0.0]).collect();
    let plain = GkParams::default().with_clusters(1).fit(&data, 2).unwrap();
    let blended = GkParams::default()
        .with_clusters(1)
        .with_regularisation(Regularisation {
            identity_blend: 0.1,
            ..Regularisation::default()
        })
        .fit(&data, 2)
        .unwrap();
    let (p, b) = (plain.covariance(0).unwrap(), blended.covariance(0).unwrap());
    let beta = Regularisation::default().max_condition;
    assert_relative_eq!(p[(1, 1)], p[(0, 0)] / beta, max_relative = 1e-9);
    // One cluster: F is the data's covariance, singular, so det(F₀)^{1/d} falls back to the
    // mean variance var(x)/2, and blending adds γ·var(x)/2 across the line.
    let var_x = p[(0, 0)];
    assert_relative_eq!(b[(1, 1)], 0.1 * var_x / 2.0, max_relative = 1e-9);
    assert_relative_eq!(
        b[(0, 0)],
        0.9 * var_x + 0.1 * var_x / 2.0,
        max_relative = 1e-9
    );
}

#[test]
fn projection_rejects_bad_periods_and_keeps_precision() {
    for bad in [
        vec![0.0],
        vec![-1.0],
        vec![f64::NAN],
        vec![DAY, 3600.0, DAY],
    ] {
        assert!(matches!(
            Projection::new(bad),
            Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "periods",
                    ..
                }
            ))
        ));
    }
    let p = Projection::new(vec![DAY, 3600.0]).unwrap();
    assert_eq!(p.dim(), 6);
    // 1.5·10⁹ s is a whole number of days plus 6 h + 15 min: phase exact from t mod T.
    let t = 17_361.0 * DAY + 6.25 * 3600.0;
    let mut out = [0.0; 6];
    p.project_into(&TimedPoint::new(t, 3.0, 4.0), &mut out);
    let day = std::f64::consts::TAU * 6.25 / 24.0;
    let hour = std::f64::consts::TAU * 0.25;
    let expected = [3.0, 4.0, day.cos(), day.sin(), hour.cos(), hour.sin()];
    for (a, b) in out.iter().zip(expected) {
        assert_relative_eq!(*a, b, epsilon = 1e-12);
    }
}

/// People in a morning place A = (0, 0) from 8 to 11 h and an afternoon place B = (8, 3)
/// from 13 to 17 h, plus a few at C = (4, 8) all day, over `days` days.
fn two_places(days: usize, per_hour: usize, seed: u64) -> Vec<TimedPoint> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut points = Vec::new();
    for day in 0..days {
        for hour in 8..17 {
            for _ in 0..per_hour {
                let t = day as f64 * DAY + (hour as f64 + rng.random::<f64>()) * 3600.0;
                let (cx, cy) = match hour {
                    8..=10 => (0.0, 0.0),
                    11..=12 => (4.0, 8.0),
                    _ => (8.0, 3.0),
                };
                let (cx, cy) = if rng.random::<f64>() < 0.15 {
                    (4.0, 8.0)
                } else {
                    (cx, cy)
                };
                points.push(TimedPoint::new(
                    t,
                    cx + 0.5 * gaussian(&mut rng),
                    cy + 0.5 * gaussian(&mut rng),
                ));
            }
        }
    }
    points
}

fn small_params() -> HypertimeParams {
    HypertimeParams::default().with_clusters(6)
}

#[test]
fn snapshot_is_a_density_over_the_plane() {
    let model = HypertimeModel::fit(&two_places(2, 40, 1), &small_params()).unwrap();
    let g = GridGeometry::new(0.1, Point2::new(-8.0, -8.0), 240, 240).unwrap();
    for hour in [3.0, 9.5, 12.0, 15.0] {
        let raster = model.at(hour * 3600.0).rasterise(&g);
        let mass: f64 = raster.data().iter().sum::<f64>() * 0.01;
        assert_relative_eq!(mass, 1.0, epsilon = 2e-3);
    }
    let weights = model.at(9.5 * 3600.0).weights();
    assert_eq!(weights.len(), model.clusters());
    assert_relative_eq!(
        weights.iter().map(|w| w.0).sum::<f64>(),
        1.0,
        epsilon = 1e-12
    );
}

/// `p(s, τ(t))` of the full mixture, straight from its components.
fn joint(model: &HypertimeModel, s: Point2<f64>, t: f64) -> f64 {
    let p = model.projection();
    let mut x = vec![0.0; p.dim()];
    p.project_into(&TimedPoint::new(t, s.x, s.y), &mut x);
    let x = DVector::from_vec(x);
    model
        .components()
        .iter()
        .map(|c| {
            let d = &x - &c.mean;
            let inv: DMatrix<f64> = c.covariance.clone().try_inverse().unwrap();
            let q = (d.transpose() * inv * &d)[(0, 0)];
            let norm =
                ((std::f64::consts::TAU).powi(x.len() as i32) * c.covariance.determinant()).sqrt();
            c.weight * (-0.5 * q).exp() / norm
        })
        .sum()
}

#[test]
fn snapshot_is_the_joint_density_normalised_over_the_plane() {
    let model = HypertimeModel::fit(&two_places(2, 30, 2), &small_params()).unwrap();
    let g = GridGeometry::new(0.1, Point2::new(-8.0, -8.0), 240, 240).unwrap();
    for hour in [9.0, 14.5] {
        let t = hour * 3600.0;
        let mass: f64 = (0..g.len())
            .map(|i| joint(&model, g.cell_center(g.cell_at(i).unwrap()), t))
            .sum::<f64>()
            * 0.01;
        let snapshot = model.at(t);
        for s in [
            Point2::new(0.2, -0.1),
            Point2::new(8.0, 3.0),
            Point2::new(4.0, 7.5),
        ] {
            let expected = joint(&model, s, t) / mass;
            assert_relative_eq!(
                snapshot.density_at(s).unwrap(),
                expected,
                max_relative = 2e-3
            );
            assert_relative_eq!(
                snapshot.log_density_at(s).unwrap(),
                expected.ln(),
                epsilon = 2e-3
            );
        }
    }
}

#[test]
fn hypertime_beats_the_baseline_when_time_matters() {
    let train = two_places(3, 40, 3);
    let test = two_places(1, 40, 4)
        .into_iter()
        .map(|p| TimedPoint {
            time: p.time + 5.0 * DAY,
            ..p
        })
        .collect::<Vec<_>>();
    let params = small_params();
    let model = HypertimeModel::fit(&train, &params).unwrap();
    let baseline = HypertimeModel::fit(&train, &params.clone().without_time()).unwrap();
    assert!(baseline.periods().is_empty());
    let g = GridGeometry::bounding(train.iter().map(|p| p.position), 0.25, 1.0).unwrap();
    let ht = grid_log_likelihood(&model, &test, &g, 300.0).unwrap();
    let st = grid_log_likelihood(&baseline, &test, &g, 300.0).unwrap();
    assert_eq!(ht.used + ht.outside, test.len());
    assert!(
        ht.mean().unwrap() > st.mean().unwrap() + 0.3,
        "{ht:?} {st:?}"
    );
    // Mornings at A, afternoons at B.
    let (a, b) = (Point2::new(0.0, 0.0), Point2::new(8.0, 3.0));
    let morning = model.at(9.5 * 3600.0);
    let afternoon = model.at(15.0 * 3600.0);
    assert!(morning.density_at(a).unwrap() > 20.0 * morning.density_at(b).unwrap());
    assert!(afternoon.density_at(b).unwrap() > 20.0 * afternoon.density_at(a).unwrap());
    // The baseline does not depend on time.
    assert_eq!(
        baseline.at(9.5 * 3600.0).density_at(a),
        baseline.at(15.0 * 3600.0).density_at(a)
    );
}

/// Detections at (nearly) one time of day — a patrol at 12:30 every day — over places that
/// do not change with time: time says nothing, and with the seed's unit circle the
/// hypertime model is the time-independent one (same score to 0.05 nat). Scaling the circle
/// by the times' own spread (`time_radius: None`) lets a quarter of an hour weigh like the
/// plane and gives another model (here 0.13 nat apart, in either direction depending on the
/// data; on the simulated office it cost 0.5 nat).
#[test]
fn data_at_one_time_of_day_score_like_the_baseline() {
    let points = |days: usize, seed: u64| {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut out = Vec::new();
        for day in 0..days {
            for _ in 0..300 {
                let t = day as f64 * DAY + 12.5 * 3600.0 + 900.0 * rng.random::<f64>();
                let (cx, cy) = [(0.0, 0.0), (4.0, 8.0), (8.0, 3.0)][rng.random_range(0..3)];
                out.push(TimedPoint::new(
                    t,
                    cx + 0.7 * gaussian(&mut rng),
                    cy + 0.7 * gaussian(&mut rng),
                ));
            }
        }
        out
    };
    let (train, test) = (points(4, 5), points(2, 6));
    let g = GridGeometry::bounding(train.iter().map(|p| p.position), 0.25, 2.0).unwrap();
    let score = |params: &HypertimeParams| {
        let model = HypertimeModel::fit(&train, params).unwrap();
        grid_log_likelihood(&model, &test, &g, 300.0)
            .unwrap()
            .mean()
            .unwrap()
    };
    let params = HypertimeParams::default().with_clusters(15);
    let (seed, spread, baseline) = (
        score(&params),
        score(&params.clone().with_time_radius(None)),
        score(&params.clone().without_time()),
    );
    assert!((seed - baseline).abs() < 0.05, "{seed} vs {baseline}");
    assert!((spread - baseline).abs() > 0.05, "{spread} vs {baseline}");
}

#[test]
fn model_skips_non_finite_points_and_handles_degenerate_data() {
    let mut points = two_places(1, 20, 5);
    let n = points.len();
    points.push(TimedPoint::new(f64::NAN, 0.0, 0.0));
    points.push(TimedPoint::new(0.0, f64::NAN, 0.0));
    points.push(TimedPoint::new(0.0, 0.0, f64::NEG_INFINITY));
    let model = HypertimeModel::fit(&points, &small_params()).unwrap();
    assert_eq!((model.report().points, model.report().skipped), (n, 3));

    // One non-daily period.
    let hourly = HypertimeModel::fit(&points, &small_params().with_periods(vec![3600.0])).unwrap();
    assert_eq!(hourly.periods(), &[3600.0]);
    assert_eq!(hourly.components()[0].mean.len(), 4);

    // Every detection at one place and time: a well-defined density, as peaked as the
    // spatial floor allows (0.1 m: nothing to hold out, so not calibrated), 1 / (2π · 0.1²).
    let same = vec![TimedPoint::new(1000.0, 2.0, 3.0); 20];
    let model = HypertimeModel::fit(&same, &small_params()).unwrap();
    assert_eq!(model.report().spatial_floor, 0.1);
    let at = model.at(1000.0);
    let peak = at.density_at(Point2::new(2.0, 3.0)).unwrap();
    assert_relative_eq!(
        peak,
        1.0 / (std::f64::consts::TAU * 0.01),
        max_relative = 1e-6
    );
    assert!(at.density_at(Point2::new(3.0, 3.0)).unwrap() < peak);
    // Any time still gives a density.
    assert!(
        model
            .at(50_000.0)
            .density_at(Point2::new(2.0, 3.0))
            .unwrap()
            > 0.0
    );

    // Unknown at a non-finite time or point.
    assert_eq!(model.at(f64::NAN).density_at(Point2::new(2.0, 3.0)), None);
    assert_eq!(at.density_at(Point2::new(f64::NAN, 3.0)), None);

    // Too few finite points.
    let few = vec![TimedPoint::new(0.0, 0.0, 0.0); 3];
    assert!(matches!(
        HypertimeModel::fit(&few, &small_params()),
        Err(AffordanceError::TooFewPoints {
            points: 3,
            clusters: 6
        })
    ));
    let all_nan = vec![TimedPoint::new(f64::NAN, 0.0, 0.0); 10];
    assert!(matches!(
        HypertimeModel::fit(&all_nan, &small_params()),
        Err(AffordanceError::TooFewPoints { points: 0, .. })
    ));
    assert!(matches!(
        HypertimeModel::fit(&points, &small_params().with_periods(vec![-5.0])),
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "periods",
                ..
            }
        ))
    ));
}

#[test]
fn grid_scoring_counts_what_it_cannot_score() {
    let points = two_places(1, 20, 6);
    let model = HypertimeModel::fit(&points, &small_params()).unwrap();
    let g = GridGeometry::new(0.5, Point2::new(-3.0, -3.0), 30, 30).unwrap();
    let test = [
        TimedPoint::new(9.0 * 3600.0, 0.0, 0.0),
        TimedPoint::new(9.0 * 3600.0, 100.0, 0.0),
        TimedPoint::new(f64::NAN, 0.0, 0.0),
    ];
    let r = grid_log_likelihood(&model, &test, &g, 60.0).unwrap();
    assert_eq!((r.used, r.outside, r.skipped), (1, 1, 1));
    assert!(r.mean().unwrap().is_finite());
    assert_eq!(
        grid_log_likelihood(&model, &test[1..], &g, 60.0)
            .unwrap()
            .mean(),
        None
    );
    assert!(matches!(
        grid_log_likelihood(&model, &test, &g, 0.0),
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "time_step",
                ..
            }
        ))
    ));
}

/// People alternate between two places with a period of 3 h (a day / 8), over four days.
fn three_hour_rhythm(seed: u64) -> Vec<TimedPoint> {
    let mut rng = StdRng::seed_from_u64(seed);
    let period = DAY / 8.0;
    let mut points = Vec::new();
    for day in 0..4 {
        for i in 0..900 {
            let t = day as f64 * DAY + 8.0 * 3600.0 + i as f64 * 40.0;
            let phase = (t % period) / period;
            let (cx, cy) = if phase < 0.5 { (0.0, 0.0) } else { (6.0, 0.0) };
            points.push(TimedPoint::new(
                t,
                cx + 0.4 * gaussian(&mut rng),
                cy + 0.4 * gaussian(&mut rng),
            ));
        }
    }
    points
}

#[test]
fn fremen_finds_the_rhythm_of_the_data() {
    let points = three_hour_rhythm(7);
    let params = HypertimeParams::default()
        .with_periods(Vec::new())
        .with_clusters(4)
        .with_period_search(Some(PeriodSearch {
            max_periods: 2,
            ..PeriodSearch::default()
        }));
    let model = HypertimeModel::fit(&points, &params).unwrap();
    let selection = &model.report().selection;
    let first = selection.period_steps[0];
    assert_relative_eq!(first.period, DAY / 8.0);
    assert!(first.accepted);
    // Validated on left-out cycles: four days hold data in 16 of its cycles.
    assert!(first.cycles > 8);
    assert!(first.heldout_loglik.unwrap() > first.without_loglik.unwrap() + 0.1);
    assert_eq!(model.periods()[0], DAY / 8.0);
    // Periods are kept only while they pass the validation.
    assert!(!selection.no_period_validated());
    let kept: Vec<f64> = selection
        .period_steps
        .iter()
        .filter(|s| s.kept)
        .map(|s| s.period)
        .collect();
    assert_eq!(model.periods(), &kept[..]);
}

#[test]
fn k_is_chosen_by_held_out_likelihood() {
    let points = two_places(2, 30, 8);
    let params = small_params().with_cluster_search(Some(ClusterSearch {
        candidates: vec![1, 3, 6],
        holdout: HoldOut::default(),
    }));
    let model = HypertimeModel::fit(&points, &params).unwrap();
    let scores = &model.report().selection.cluster_scores;
    assert_eq!(
        scores.iter().map(|s| s.0).collect::<Vec<_>>(),
        vec![1, 3, 6]
    );
    let best = scores
        .iter()
        .fold(scores[0], |b, s| if s.1 > b.1 { *s } else { b });
    assert_eq!(model.clusters(), best.0);
    assert!(scores[0].1 < best.1);

    let bad = small_params().with_cluster_search(Some(ClusterSearch {
        candidates: vec![],
        holdout: HoldOut::default(),
    }));
    assert!(matches!(
        HypertimeModel::fit(&points, &bad),
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter { .. }
        ))
    ));
    // All detections in one ten-minute block: nothing to hold out.
    let burst: Vec<TimedPoint> = (0..50)
        .map(|i| TimedPoint::new(1.0 + i as f64, i as f64 * 0.1, 0.0))
        .collect();
    assert!(matches!(
        HypertimeModel::fit(&burst, &params),
        Err(AffordanceError::EmptyHoldOut { points: 50 })
    ));
}

#[test]
fn detections_are_read_with_skips_counted() {
    let text = "t,x,y\n1,2,3\n4, 5 ,6\n7,8\n9,x,1\n10,inf,1\n\n# note\n11,12,13,14\n";
    let columns = DetectionColumns::default()
        .with_delimiter(Delimiter::Char(','))
        .with_header_lines(1);
    let parsed = parse_detections(text.as_bytes(), &columns).unwrap();
    assert_eq!(
        parsed.records,
        vec![
            TimedPoint::new(1.0, 2.0, 3.0),
            TimedPoint::new(4.0, 5.0, 6.0),
            TimedPoint::new(11.0, 12.0, 13.0)
        ]
    );
    assert_eq!(parsed.skipped, 3);
    let reasons: Vec<(usize, SkipReason)> = parsed
        .first_skipped
        .iter()
        .map(|s| (s.line, s.reason.clone()))
        .collect();
    assert_eq!(
        reasons,
        vec![
            (
                4,
                SkipReason::TooFewFields {
                    expected: 3,
                    found: 2
                }
            ),
            (5, SkipReason::BadNumber { field: 1 }),
            (6, SkipReason::NonFinite { field: 1 }),
        ]
    );
    // Other columns, whitespace.
    let parsed = parse_detections(
        "a 1 2 3\n".as_bytes(),
        &DetectionColumns::default().with_columns(3, 1, 2),
    )
    .unwrap();
    assert_eq!(parsed.records, vec![TimedPoint::new(3.0, 1.0, 2.0)]);
    assert!(matches!(
        parse_detections(
            "".as_bytes(),
            &DetectionColumns::default().with_columns(0, 0, 1)
        ),
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "columns",
                ..
            }
        ))
    ));
    assert!(matches!(
        read_detections("/nonexistent/detections.txt", &DetectionColumns::default()),
        Err(AffordanceError::Io { .. })
    ));
}

/// A standard normal draw (Box–Muller).
fn gaussian(rng: &mut StdRng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The plain reference's result.
struct Reference {
    centres: Vec<f64>,
    covariances: Vec<DMatrix<f64>>,
    memberships: Vec<f64>,
}

/// Textbook Gustafson–Kessel, one point and one cluster at a time with nalgebra: `iterations`
/// rounds of (memberships from prototypes and `Aᵢ = (ρ det Fᵢ)^{1/d} Fᵢ⁻¹`; prototypes and
/// two-pass fuzzy covariances from `uᵐ`; blending and eigenvalue floors), from `init`.
fn reference_gk(
    data: &[f64],
    dim: usize,
    init: &[f64],
    params: &GkParams,
    iterations: usize,
) -> Reference {
    let (k, m, rho) = (params.clusters, params.fuzzifier, params.volume);
    let reg = params.regularisation;
    let x: Vec<DVector<f64>> = data.chunks(dim).map(DVector::from_column_slice).collect();
    let n = x.len();
    let mean = x.iter().fold(DVector::zeros(dim), |a, b| a + b) / n as f64;
    let f0 = x.iter().fold(DMatrix::zeros(dim, dim), |a, b| {
        a + (b - &mean) * (b - &mean).transpose()
    }) / n as f64;
    let eig0 = f0.clone().symmetric_eigen();
    let nu = if eig0.eigenvalues.iter().all(|l| *l > 0.0) {
        f0.determinant().powf(1.0 / dim as f64)
    } else {
        f0.trace() / dim as f64
    };
    let mut v: Vec<DVector<f64>> = init.chunks(dim).map(DVector::from_column_slice).collect();
    let mut f = vec![DMatrix::<f64>::identity(dim, dim); k];
    let mut u = vec![vec![0.0; k]; n];
    for _ in 0..iterations {
        let a: Vec<DMatrix<f64>> = f
            .iter()
            .map(|fi| {
                fi.clone().try_inverse().unwrap() * (rho * fi.determinant()).powf(1.0 / dim as f64)
            })
            .collect();
        for j in 0..n {
            let d2: Vec<f64> = (0..k)
                .map(|i| {
                    let d = &x[j] - &v[i];
                    (d.transpose() * &a[i] * &d)[(0, 0)].max(0.0)
                })
                .collect();
            let zeros = d2.iter().filter(|d| **d == 0.0).count();
            for i in 0..k {
                u[j][i] = if zeros > 0 {
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
            }
        }
        for i in 0..k {
            let w: Vec<f64> = (0..n).map(|j| u[j][i].powf(m)).collect();
            let total: f64 = w.iter().sum();
            if total <= 0.0 {
                continue;
            }
            v[i] = (0..n).fold(DVector::zeros(dim), |s, j| s + &x[j] * w[j]) / total;
            let fi = (0..n).fold(DMatrix::zeros(dim, dim), |s, j| {
                s + (&x[j] - &v[i]) * (&x[j] - &v[i]).transpose() * w[j]
            }) / total;
            let fi = fi * (1.0 - reg.identity_blend)
                + DMatrix::identity(dim, dim) * (reg.identity_blend * nu);
            let eig = fi.symmetric_eigen();
            let floor = (eig.eigenvalues.max() / reg.max_condition).max(reg.min_eigenvalue);
            let values = eig.eigenvalues.map(|l| l.max(floor));
            f[i] =
                &eig.eigenvectors * DMatrix::from_diagonal(&values) * eig.eigenvectors.transpose();
        }
    }
    Reference {
        centres: v.iter().flat_map(|c| c.iter().copied()).collect(),
        covariances: f,
        memberships: u.concat(),
    }
}

/// `n` detections a day for `days` days, uniform over `[0, width] × [0, 5]` m at uniform
/// times between 08:00 and 18:00: no daily rhythm.
fn no_rhythm(days: std::ops::Range<usize>, n: usize, width: f64, seed: u64) -> Vec<TimedPoint> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut points = Vec::new();
    for day in days {
        let mut times: Vec<f64> = (0..n)
            .map(|_| day as f64 * DAY + 8.0 * 3600.0 + rng.random::<f64>() * 10.0 * 3600.0)
            .collect();
        times.sort_by(f64::total_cmp);
        for t in times {
            points.push(TimedPoint::new(
                t,
                rng.random::<f64>() * width,
                rng.random::<f64>() * 5.0,
            ));
        }
    }
    points
}

#[test]
fn a_test_day_on_twice_the_ground_without_rhythm_scores_above_uniform() {
    // Three training days over 10 m × 5 m; the test day covers 20 m × 5 m, no daily rhythm.
    let train = no_rhythm(0..3, 1200, 10.0, 21);
    let test = no_rhythm(3..4, 1200, 20.0, 22);
    let params = HypertimeParams::default();
    let model = HypertimeModel::fit(&train, &params).unwrap();
    let baseline = HypertimeModel::fit(&train, &params.clone().without_time()).unwrap();
    // The daily period was checked on left-out days and rejected: the static model.
    let selection = &model.report().selection;
    assert!(selection.no_period_validated());
    let step = selection.period_steps[0];
    assert!(step.cycles == 3 && !step.accepted && !step.kept, "{step:?}");
    assert!(model.periods().is_empty());
    // The known area is the training data's; half the test day lies outside it.
    let grid = GridGeometry::bounding(train.iter().map(|p| p.position), 0.25, 1.0).unwrap();
    let eval = EvaluationParams::default();
    let (h, s) = (
        evaluate(&model, &test, &grid, &eval).unwrap(),
        evaluate(&baseline, &test, &grid, &eval).unwrap(),
    );
    let outside = h.loglik.outside as f64 / test.len() as f64;
    assert!((0.4..0.5).contains(&outside), "{outside}");
    let (hm, sm) = (h.mean().unwrap(), s.mean().unwrap());
    eprintln!(
        "hypertime {hm:.4}, static {sm:.4}, uniform {:.4}",
        h.uniform_loglik
    );
    assert!(hm >= h.uniform_loglik && sm >= s.uniform_loglik);
    assert!((hm - sm).abs() <= 0.1);
    assert_eq!(h.share_low, 0.0);
}

/// People alternate between (0, 0) and (6, 0) every half of `period`, 8:00–16:00 on each of
/// `days`, the alternation shifted by `shift(day)` of a period.
fn alternating(days: usize, period: f64, shift: impl Fn(usize) -> f64) -> Vec<TimedPoint> {
    let mut rng = StdRng::seed_from_u64(11);
    let mut points = Vec::new();
    for day in 0..days {
        for i in 0..720 {
            let t = day as f64 * DAY + 8.0 * 3600.0 + i as f64 * 40.0;
            let phase = ((t / period) + shift(day)).rem_euclid(1.0);
            let x = if phase < 0.5 { 0.0 } else { 6.0 };
            points.push(TimedPoint::new(
                t,
                x + 0.3 * gaussian(&mut rng),
                0.3 * gaussian(&mut rng),
            ));
        }
    }
    points
}

/// Regression: on the real people data `--periods auto` trained on one day accepted a 1.6 h
/// period (five cycles of that day passed leave-one-cycle-out) that did not recur the next
/// day. Periods are now validated on held-out whole days.
#[test]
fn a_period_of_one_day_only_is_not_validated() {
    let period = DAY / 15.0; // 1.6 h
    let search = |validation: CycleValidation| {
        small_params()
            .with_periods(Vec::new())
            .with_period_search(Some(PeriodSearch::default()))
            .with_validation(validation)
    };
    // One day: every candidate lies in one block, so none is tried.
    let one_day = alternating(1, period, |_| 0.0);
    let model = HypertimeModel::fit(&one_day, &search(CycleValidation::default())).unwrap();
    let selection = &model.report().selection;
    assert!(selection.period_steps.is_empty(), "{selection:?}");
    assert!(model.periods().is_empty() && selection.no_period_validated());
    // The old reading (folds of the period's own cycles: blocks no longer than it) accepts
    // the pattern of that day, as it did on the real data.
    let cycles = CycleValidation::default().with_block(60.0);
    let model = HypertimeModel::fit(&one_day, &search(cycles)).unwrap();
    let first = model.report().selection.period_steps[0];
    assert!(
        first.accepted && (first.period - period).abs() < 1.0,
        "{first:?}"
    );
    // Two days on which the pattern does not recur (the second day half a period later):
    // held out, each day is predicted worse with the period; nothing is validated.
    let shifted = alternating(2, period, |d| 0.5 * d as f64);
    let model = HypertimeModel::fit(&shifted, &search(CycleValidation::default())).unwrap();
    let selection = &model.report().selection;
    assert!(!selection.period_steps.is_empty(), "{selection:?}");
    assert!(
        selection.period_steps.iter().all(|s| s.blocks == 2),
        "{selection:?}"
    );
    assert!(model.periods().is_empty() && selection.no_period_validated());
    // The same pattern recurring on the second day is validated on the held-out day.
    let recurring = alternating(2, period, |_| 0.0);
    let model = HypertimeModel::fit(&recurring, &search(CycleValidation::default())).unwrap();
    let first = model.report().selection.period_steps[0];
    assert!(
        first.accepted && (first.period - period).abs() < 1.0 && first.blocks == 2,
        "{first:?}"
    );
    assert!(model.periods().contains(&first.period));
}

/// The facade's studies reuse a model that kept no period as its static baseline.
#[test]
fn a_model_without_a_validated_period_is_its_baseline() {
    // The daily period is rejected on the held-out day (the second day is the first shifted
    // by half a day's pattern), so the fit ends on the baseline's calibration and fit.
    let points = alternating(2, DAY / 4.0, |d| 0.5 * d as f64);
    let model = HypertimeModel::fit(&points, &small_params()).unwrap();
    assert!(model.periods().is_empty(), "{:?}", model.report().selection);
    let baseline = HypertimeModel::fit(&points, &small_params().without_time()).unwrap();
    assert_eq!(
        (
            model.report().spatial_floor,
            model.report().background_weight
        ),
        (
            baseline.report().spatial_floor,
            baseline.report().background_weight
        )
    );
    for (i, p) in points.iter().enumerate().step_by(37) {
        let q = Point2::new(p.position.x + 0.1 * (i % 7) as f64, p.position.y);
        assert_eq!(
            model.at(p.time).density_at(q),
            baseline.at(p.time).density_at(q)
        );
    }
}

#[test]
fn bad_validation_blocks_are_typed_errors() {
    for block in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let params = small_params().with_validation(CycleValidation::default().with_block(block));
        assert!(
            matches!(
                HypertimeModel::fit(&alternating(1, 3600.0, |_| 0.0), &params),
                Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter { name: "block", .. }
                ))
            ),
            "{block}"
        );
    }
}

#[test]
fn a_rhythm_seen_once_is_not_validated() {
    // Day 0: mornings at (0, 0), afternoons at (8, 0); day 1 the other way round.
    let mut rng = StdRng::seed_from_u64(5);
    let mut points = Vec::new();
    for day in 0..2 {
        for i in 0..600 {
            let t = day as f64 * DAY + 8.0 * 3600.0 + i as f64 * 60.0;
            let morning = i < 300;
            let x = if morning == (day == 0) { 0.0 } else { 8.0 };
            points.push(TimedPoint::new(
                t,
                x + 0.3 * gaussian(&mut rng),
                0.3 * gaussian(&mut rng),
            ));
        }
    }
    let params = small_params();
    let model = HypertimeModel::fit(&points, &params).unwrap();
    let step = model.report().selection.period_steps[0];
    assert!(
        step.heldout_loglik.unwrap() < step.without_loglik.unwrap(),
        "{step:?}"
    );
    assert!(model.periods().is_empty() && model.report().selection.no_period_validated());
    // Trusted, the daily period is kept unchecked; on one day it cannot be checked and is
    // kept as given, unless it must be validated.
    let trusted = params
        .clone()
        .with_validation(CycleValidation::default().with_given(GivenPeriods::Trust));
    assert_eq!(
        HypertimeModel::fit(&points, &trusted).unwrap().periods(),
        &[DAY]
    );
    let one_day: Vec<TimedPoint> = points[..600].to_vec();
    let model = HypertimeModel::fit(&one_day, &params).unwrap();
    assert_eq!(model.periods(), &[DAY]);
    assert!(model.report().selection.no_period_validated());
    let strict =
        params.with_validation(CycleValidation::default().with_given(GivenPeriods::Validate));
    assert!(
        HypertimeModel::fit(&one_day, &strict)
            .unwrap()
            .periods()
            .is_empty()
    );
}

#[test]
fn the_background_bounds_the_cost_of_a_detection_where_nobody_was_seen() {
    let points = two_places(2, 30, 9);
    let far = TimedPoint::new(10.0 * 3600.0, 40.0, 30.0);
    let bare = HypertimeModel::fit(&points, &small_params().with_background(None)).unwrap();
    assert!(bare.background().is_none());
    assert!(bare.log_density(&far).unwrap() < -100.0);
    let fixed = small_params()
        .with_calibration(None)
        .with_background(Some(Background::default().with_weight(0.01)));
    let model = HypertimeModel::fit(&points, &fixed).unwrap();
    let b = *model.background().unwrap();
    assert_eq!((b.weight, model.report().background_weight), (0.01, 0.01));
    // There, the density is the background's: β t_ν, with the 2-D Student-t by its formula.
    let v = nalgebra::Vector2::new(far.position.x - b.mean[0], far.position.y - b.mean[1]);
    let s = nalgebra::Matrix2::new(b.scale[0][0], b.scale[0][1], b.scale[1][0], b.scale[1][1]);
    let d2 = v.dot(&(s.try_inverse().unwrap() * v));
    let t = (1.0 + d2 / b.dof).powf(-(b.dof / 2.0 + 1.0))
        / (std::f64::consts::TAU * s.determinant().sqrt());
    assert_relative_eq!(
        model.log_density(&far).unwrap(),
        (0.01 * t).ln(),
        max_relative = 1e-6
    );
    assert!(model.log_density(&far).unwrap() > -20.0);
    // The two shares: far away the background's dominates (the model knows nothing there),
    // at a place seen in training the mixture's; their log-sum is the density.
    let snapshot = model.at(far.time);
    let (mixture, background) = snapshot.log_parts_at(far.position).unwrap();
    assert!(background > mixture + 10.0);
    assert_relative_eq!(background, (0.01 * t).ln(), max_relative = 1e-6);
    let seen = points[0].position;
    let (mixture, background) = snapshot.log_parts_at(seen).unwrap();
    assert!(mixture > background);
    let sum = mixture.max(background) + (-(mixture - background).abs()).exp().ln_1p();
    assert_relative_eq!(
        sum,
        snapshot.log_density_at(seen).unwrap(),
        max_relative = 1e-12
    );
    // Without a background its share is −∞.
    let (_, none) = bare.at(far.time).log_parts_at(seen).unwrap();
    assert_eq!(none, f64::NEG_INFINITY);
    // Calibrated: the floor and weight come from the candidates.
    let calibrated = HypertimeModel::fit(&points, &small_params()).unwrap();
    let report = calibrated.report();
    let c = report.selection.calibration.clone().unwrap();
    assert!([0.05, 0.1, 0.2, 0.3, 0.5].contains(&report.spatial_floor));
    assert_eq!(
        (c.floor, c.weight),
        (report.spatial_floor, report.background_weight)
    );
    // Still a density over the plane.
    let g = GridGeometry::new(0.5, Point2::new(-300.0, -300.0), 1200, 1200).unwrap();
    let mass: f64 = calibrated
        .at(10.0 * 3600.0)
        .rasterise(&g)
        .data()
        .iter()
        .sum::<f64>()
        * 0.25;
    assert!((mass - 1.0).abs() < 0.01, "{mass}");
}

#[test]
fn one_far_detection_or_tiny_count_cells_are_refused_not_hours_of_work() {
    use haunts_occupancy::OccupancyError;
    // 3 000 detections in a 6 m room and one at x = 10⁷ m: the scoring grid bounding them at
    // 0.25 m would be 4·10⁷ × 30 cells, and scoring never returned. Refused, naming it.
    let mut train: Vec<TimedPoint> = (0..3000)
        .map(|i| {
            TimedPoint::new(
                i as f64 * 30.0,
                (i % 20) as f64 * 0.3,
                (i % 17) as f64 * 0.3,
            )
        })
        .collect();
    train.push(TimedPoint::new(90_000.0, 1.0e7, 2.0));
    match GridGeometry::bounding(train.iter().map(|p| p.position), 0.25, 1.0) {
        Err(OccupancyError::GridTooLarge { width, to, .. }) => {
            assert!(width > 4.0e7, "{width}");
            assert_eq!(to[0], 1.0e7 + 1.0);
        }
        other => panic!("expected GridTooLarge, got {other:?}"),
    }
    // Count cells of a micrometre over a normal grid: 4·10¹² cells, refused.
    let model =
        HypertimeModel::fit(&train[..3000], &HypertimeParams::default().with_clusters(2)).unwrap();
    let grid = GridGeometry::bounding(train[..3000].iter().map(|p| p.position), 0.25, 1.0).unwrap();
    let tiny = EvaluationParams::default().with_counts(1e-6, 600.0);
    assert!(matches!(
        evaluate(&model, &train[..3000], &grid, &tiny),
        Err(AffordanceError::Occupancy(OccupancyError::GridTooLarge { resolution, .. })) if resolution == 1e-6
    ));
    let e = evaluate(&model, &train[..3000], &grid, &EvaluationParams::default()).unwrap();
    assert_eq!(e.loglik.used, 3000);
}

#[test]
fn a_detection_column_of_usize_max_is_an_error_not_a_wrapped_panic() {
    // `1 + max` wrapped to 0 fields needed, then indexing panicked.
    let columns = DetectionColumns {
        y: usize::MAX,
        ..DetectionColumns::default()
    };
    assert!(matches!(
        parse_detections("1 2 3\n".as_bytes(), &columns),
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter { name: "y", .. }
        ))
    ));
    let columns = DetectionColumns {
        y: usize::MAX - 1,
        ..DetectionColumns::default()
    };
    let parsed = parse_detections("1 2 3\n".as_bytes(), &columns).unwrap();
    assert_eq!((parsed.records.len(), parsed.skipped), (0, 1));
}
