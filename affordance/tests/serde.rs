//! With the `serde` feature, parameters and models round-trip through JSON (loaded models give
//! the same densities), and deserialising checks the same rules as the constructors, naming
//! what is wrong.
#![cfg(feature = "serde")]
#![allow(clippy::unwrap_used)]

use approx::assert_relative_eq;
use haunts_affordance::density::{CumulativeDensity, DailyDensity, DensityParams, HitCounter};
use haunts_affordance::hypertime::{
    Background, Calibration, CalibrationReport, ClusterSearch, CycleValidation, DAY,
    DetectionColumns, FitReport, GivenPeriods, GkClustering, GkParams, HoldOut, HypertimeModel,
    HypertimeParams, Moments, PeriodSearch, PeriodStep, Projection, Regularisation, Selection,
    TimedPoint,
};
use haunts_affordance::layout::{Layout, LayoutLibrary, LayoutParams};
use haunts_affordance::ta::{ConfidenceMap, RegressionParams, TaMap, TaParams};
use haunts_affordance::{AffordanceError, DensityMap};
use haunts_gp::GridMode;
use haunts_occupancy::raycast::VisitRule;
use haunts_occupancy::{Cell, Grid, GridGeometry, MaxRangeRule};
use haunts_similarity::{ClusterParams, DifferenceParams, LayoutThreshold, Length, Symmetrisation};
use haunts_tracking::{Delimiter, Trajectory};
use nalgebra::Point2;
use serde_json::{Value, json};

use haunts_test_support::json;
use json::{Tally, corrupt, rejection, trip};

mod common;
use common::{room, walk, wall_at};

/// Asserts that `error` mentions every one of `words`.
fn assert_names(error: &str, words: &[&str]) {
    for w in words {
        assert!(error.contains(w), "`{error}` does not mention `{w}`");
    }
}

/// Both known and equal within 1e-12 (relative).
fn close(a: Option<f64>, b: Option<f64>) {
    let (a, b) = (a.unwrap(), b.unwrap());
    assert_relative_eq!(a, b, max_relative = 1e-12, epsilon = 1e-300);
}

/// Same geometry, values equal within 1e-12 (relative) or both NaN.
fn close_grids(a: &Grid<f64>, b: &Grid<f64>) {
    assert_eq!(a.geometry(), b.geometry());
    for (x, y) in a.data().iter().zip(b.data()) {
        assert!(
            (x.is_nan() && y.is_nan()) || (x - y).abs() <= 1e-12 * x.abs().max(1.0),
            "{x} != {y}"
        );
    }
}

#[test]
fn parameters_round_trip_through_json() {
    let density = DensityParams::default()
        .with_person_radius(0.3)
        .with_visit_rule(VisitRule { min_fraction: 0.25 })
        .with_max_range(MaxRangeRule::Ignore)
        .with_min_visits(2);
    assert_eq!(trip(&density), density);
    assert_eq!(trip(&DensityParams::default()), DensityParams::default());

    let layout = LayoutParams::default()
        .with_difference(DifferenceParams::default().with_cutoff(Length::Cells(7.0)))
        .with_cluster(
            ClusterParams::default()
                .with_threshold(LayoutThreshold::PerOccupiedCell(2.5))
                .with_symmetrisation(Symmetrisation::Mean),
        )
        .with_composite_min_fraction(0.75)
        .with_min_visits(3);
    assert_eq!(trip(&layout), layout);
    // The similarity types are written as serde's derive writes them.
    let text = serde_json::to_value(LayoutParams::default()).unwrap();
    assert_eq!(text["difference"], json!({"cutoff": {"Metres": 0.5}}));
    assert_eq!(text["cluster"]["symmetrisation"], json!("Max"));

    let gk = GkParams::default()
        .with_clusters(7)
        .with_fuzzifier(1.5)
        .with_tolerance(1e-5)
        .with_seed(42)
        .with_regularisation(Regularisation {
            identity_blend: 0.1,
            max_condition: 1e3,
            min_eigenvalue: 1e-7,
        });
    assert_eq!(trip(&gk), gk);
    let hypertime = HypertimeParams::default()
        .with_periods(vec![DAY, DAY / 2.0])
        .with_gk(gk)
        .with_time_radius(None)
        .with_space_smoothing(0.2)
        .with_require_convergence(true)
        .with_period_search(Some(PeriodSearch {
            candidates: vec![DAY / 3.0, DAY / 4.0, DAY / 8.0],
            max_periods: 2,
        }))
        .with_cluster_search(Some(ClusterSearch::default()))
        .with_spatial_floor(0.3)
        .with_background(Some(Background::default().with_dof(4.0)))
        .with_calibration(Some(Calibration {
            floors: vec![0.1, 0.2],
            weights: vec![0.0, 0.05],
            uniform_weights: vec![0.0, 0.3],
            later: Some(0.4),
            holdout: HoldOut {
                block: 300.0,
                every: 4,
            },
        }))
        .with_validation(
            CycleValidation::default()
                .with_margin(0.05)
                .with_given(GivenPeriods::Validate),
        )
        .with_moments(Moments::Membership);
    assert_eq!(trip(&hypertime), hypertime);
    assert_eq!(
        trip(&HypertimeParams::default()),
        HypertimeParams::default()
    );
    let columns = DetectionColumns::default()
        .with_columns(3, 1, 2)
        .with_delimiter(Delimiter::Char(';'))
        .with_header_lines(1);
    assert_eq!(trip(&columns), columns);
    assert_eq!(
        serde_json::to_value(columns).unwrap()["delimiter"],
        json!({"Char": ";"})
    );
    let point = TimedPoint::new(1.5e9, -2.25, 3.5);
    assert_eq!(trip(&point), point);
    let projection = Projection::new(vec![DAY, 7.0 * DAY]).unwrap();
    assert_eq!(trip(&projection), projection);

    let ta = TaParams::default()
        .with_cell_size(2.0)
        .with_fitted_lengthscale(0.5, 4.0)
        .with_regression(
            RegressionParams::default()
                .with_noise(0.5)
                .with_exact_limit(10)
                .with_grid_mode(GridMode::Exact),
        );
    assert_eq!(trip(&ta), ta);
    assert_eq!(trip(&TaParams::default()), TaParams::default());
    assert_eq!(
        serde_json::to_value(RegressionParams::default()).unwrap()["grid_mode"],
        json!({"Fast": {"tolerance": 1e-10, "check_points": 64}})
    );
}

#[test]
fn parameters_are_checked_where_used_not_when_read() {
    // As when built by hand: a bad value loads, and the function using it refuses it.
    let params: TaParams = serde_json::from_value(json!({
        "cell_size": -1.0,
        "lengthscale": 2.0,
        "fit_lengthscale": null,
        "regression": serde_json::to_value(RegressionParams::default()).unwrap(),
    }))
    .unwrap();
    assert!(matches!(
        params.check(),
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "cell_size",
                ..
            }
        ))
    ));
    let e = rejection::<RegressionParams>(json!({
        "variance": 1.0, "noise": 1.0, "exact_limit": 10, "inducing": 5,
        "grid_mode": {"Approximate": {}},
    }));
    assert_names(&e, &["Approximate"]);
}

fn geometry(width: usize, height: usize) -> GridGeometry {
    GridGeometry::new(0.5, Point2::new(-1.0, 2.0), width, height).unwrap()
}

#[test]
fn densities_round_trip_and_give_the_same_densities() {
    let g = geometry(3, 2);
    let day = DailyDensity::new(
        Grid::from_vec(g, vec![2, 0, 5, 1, 7, 0]).unwrap(),
        Grid::from_vec(g, vec![4, 3, 0, 1, 2, 9]).unwrap(),
        2,
    )
    .unwrap();
    let back = trip(&day);
    assert_eq!(back, day);
    for cell in [
        Cell::new(0, 0),
        Cell::new(1, 0),
        Cell::new(2, 0),
        Cell::new(1, 1),
    ] {
        let p = g.cell_center(cell);
        assert_eq!(back.density_at(p), day.density_at(p));
    }
    assert_eq!(day.density_at(g.cell_center(Cell::new(0, 0))), Some(0.5));

    let mut all = CumulativeDensity::new(g, 1).unwrap();
    all.add(&day).unwrap();
    all.add(&day).unwrap();
    let back = trip(&all);
    assert_eq!(back, all);
    assert_eq!(back.days(), 2);
    assert_eq!(
        back.density_at(g.cell_center(Cell::new(1, 1))),
        Some(7.0 / 2.0)
    );

    let mut hits = HitCounter::new(g, 0.3).unwrap();
    hits.add(Point2::new(-0.75, 2.25));
    hits.add(Point2::new(f64::NAN, 0.0));
    let back = trip(&hits);
    assert_eq!(back, hits);
    assert_eq!(back.stats().non_finite, 1);
}

#[test]
fn bad_densities_are_rejected_naming_the_problem() {
    let grid = |w: usize, data: Value| {
        json!({
            "geometry": {"resolution": 0.5, "origin": [0.0, 0.0], "width": w, "height": 1},
            "data": data,
        })
    };
    let day = |hits: Value, visits: Value, min: u32| json!({"hits": hits, "visits": visits, "min_visits": min});
    let good = day(grid(2, json!([1, 2])), grid(2, json!([3, 4])), 1);
    assert!(serde_json::from_value::<DailyDensity>(good).is_ok());
    // Hits and visits on different cells.
    let e = rejection::<DailyDensity>(day(grid(2, json!([1, 2])), grid(3, json!([3, 4, 5])), 1));
    assert_names(&e, &["visits", "expected"]);
    // A grid whose data does not fill it.
    let e = rejection::<DailyDensity>(day(grid(2, json!([1])), grid(2, json!([3, 4])), 1));
    assert_names(&e, &["1 elements", "expected 2"]);
    // A negative count, and a count that is not a number.
    let e = rejection::<DailyDensity>(day(grid(2, json!([1, -2])), grid(2, json!([3, 4])), 1));
    assert_names(&e, &["-2", "u32"]);
    let e = rejection::<DailyDensity>(day(grid(2, json!([1, null])), grid(2, json!([3, 4])), 1));
    assert_names(&e, &["null"]);
    // min_visits = 0.
    let e = rejection::<DailyDensity>(day(grid(2, json!([1, 2])), grid(2, json!([3, 4])), 0));
    assert_names(&e, &["min_visits"]);
    let e = rejection::<CumulativeDensity>(json!({
        "hits": grid(2, json!([1, 2])), "visits": grid(1, json!([3])),
        "days": 1, "min_visits": 1,
    }));
    assert_names(&e, &["visits"]);
    let e = rejection::<HitCounter>(json!({
        "counts": grid(2, json!([1, 2])), "radius": -0.25,
        "stats": {"counted": 1, "non_finite": 0, "outside": 0, "cell_hits": 3},
    }));
    assert_names(&e, &["person_radius"]);
}

/// Hits growing along the rows, visits along the columns.
fn counts(scale: u32) -> DailyDensity {
    let g = room();
    DailyDensity::new(
        Grid::from_fn(g, |c| scale * (c.row % 7) as u32),
        Grid::from_fn(g, |c| (c.col % 5) as u32),
        1,
    )
    .unwrap()
}

fn library() -> LayoutLibrary {
    let mut library = LayoutLibrary::new(room(), LayoutParams::default()).unwrap();
    library.ingest("monday", &wall_at(10), &counts(1)).unwrap();
    library.ingest("tuesday", &wall_at(11), &counts(2)).unwrap();
    library
        .ingest("wednesday", &wall_at(50), &counts(3))
        .unwrap();
    library
        .ingest("thursday", &wall_at(49), &counts(1))
        .unwrap();
    library.ingest("friday", &wall_at(12), &counts(5)).unwrap();
    assert_eq!(library.layouts().len(), 2);
    library
}

#[test]
fn the_layout_library_round_trips_with_its_composites() {
    let library = library();
    let back = trip(&library);
    assert_eq!(back, library);
    for (a, b) in back.layouts().iter().zip(library.layouts()) {
        assert_eq!(a.composite().maps(), b.composite().maps());
        assert_eq!(
            a.composite().occupied_counts(),
            b.composite().occupied_counts()
        );
        assert_eq!(a.composite().free_counts(), b.composite().free_counts());
        assert_eq!(
            a.composite_mask(0.5).unwrap(),
            b.composite_mask(0.5).unwrap()
        );
        for p in [
            Point2::new(0.12, 0.33),
            Point2::new(2.9, 1.1),
            Point2::new(1.5, 2.95),
        ] {
            assert_eq!(a.affordance().density_at(p), b.affordance().density_at(p));
        }
    }
    assert!(
        library.layouts()[0]
            .affordance()
            .density_at(Point2::new(0.12, 0.33))
            .is_some()
    );
    // The loaded library classifies and ingests as the saved one.
    for col in [13, 48, 30] {
        assert_eq!(
            back.classify(&wall_at(col)).unwrap(),
            library.classify(&wall_at(col)).unwrap()
        );
    }
    let (mut a, mut b) = (library.clone(), back);
    assert_eq!(
        a.ingest("saturday", &wall_at(48), &counts(2)).unwrap(),
        b.ingest("saturday", &wall_at(48), &counts(2)).unwrap()
    );
    assert_eq!(a, b);
    // One layout on its own, and an empty library.
    let layout: &Layout = &library.layouts()[1];
    assert_eq!(&trip(layout), layout);
    let empty = LayoutLibrary::new(room(), LayoutParams::default()).unwrap();
    assert_eq!(trip(&empty), empty);
}

#[test]
fn a_bad_layout_library_is_rejected_naming_the_problem() {
    let good = serde_json::to_value(library()).unwrap();
    assert!(serde_json::from_value::<LayoutLibrary>(good.clone()).is_ok());
    let broken = |edit: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        edit(&mut v);
        rejection::<LayoutLibrary>(v)
    };
    let e = broken(&|v| v["next_day"] = json!(6));
    assert_names(&e, &["layout library", "5 of the 6 ingested days"]);
    let e = broken(&|v| v["next_day"] = json!(4));
    assert_names(&e, &["day id 4", "not below the day count 4"]);
    let e = broken(&|v| v["layouts"][1]["days"][0]["label"] = json!("monday"));
    assert_names(&e, &["label `monday` repeated"]);
    let e = broken(&|v| v["layouts"][1]["id"] = json!(0));
    assert_names(&e, &["layout 0 stored at position 1"]);
    let e = broken(&|v| v["params"]["composite_min_fraction"] = json!(0.0));
    assert_names(&e, &["composite_min_fraction"]);
    let e = broken(&|v| v["layouts"][0]["affordance"]["min_visits"] = json!(2));
    assert_names(&e, &["min_visits 2"]);
    let e = broken(&|v| v["layouts"][0]["affordance"]["days"] = json!(2));
    assert_names(&e, &["layout 0", "holds 2 days, the layout 3"]);
    let e = broken(&|v| v["layouts"][0]["composite"]["occupied"]["data"][10] = json!(4));
    assert_names(&e, &["occupied + free counts exceed"]);
    let e = broken(&|v| v["layouts"][0]["composite"]["free"]["data"][11] = json!(-1));
    assert_names(&e, &["-1"]);
    let e = broken(&|v| v["layouts"][0]["days"] = json!([]));
    assert_names(&e, &["no day"]);
    let e = broken(&|v| v["layouts"][0]["days"][1]["distance"] = json!(-1.0));
    assert_names(&e, &["distance -1"]);
    let e = broken(&|v| v["layouts"][0]["days"][1]["distance"] = json!("far"));
    assert_names(&e, &["far"]);
    let e = broken(&|v| {
        v["layouts"][1]["affordance"]["hits"]["geometry"]["width"] = json!(30);
        v["layouts"][1]["affordance"]["hits"]["data"] = json!(vec![0; 30 * 60]);
    });
    assert_names(&e, &["visits"]);
    let e = broken(&|v| {
        let g = json!({"resolution": 0.1, "origin": [0.0, 0.0], "width": 30, "height": 30});
        for key in ["hits", "visits"] {
            v["layouts"][1]["affordance"][key]["geometry"] = g.clone();
            v["layouts"][1]["affordance"][key]["data"] = json!(vec![0; 900]);
        }
        for key in ["occupied", "free"] {
            v["layouts"][1]["composite"][key]["geometry"] = g.clone();
            v["layouts"][1]["composite"][key]["data"] = json!(vec![0; 900]);
        }
    });
    assert_names(&e, &["layout lies on"]);
}

/// Three days: a queue at (1, 1) at ten, a crowd at (6, 2) at four.
fn detections() -> Vec<TimedPoint> {
    let mut points = vec![TimedPoint::new(0.0, f64::NAN, 0.0)];
    for day in 0..3 {
        for i in 0..40 {
            let t = day as f64 * DAY + i as f64 * 45.0;
            let wobble = 0.05 * (i % 5) as f64;
            let jitter = 0.03 * (i % 3) as f64;
            points.push(TimedPoint::new(
                t + 10.0 * 3600.0,
                1.0 + wobble,
                1.0 - wobble + jitter,
            ));
            points.push(TimedPoint::new(
                t + 16.0 * 3600.0,
                6.0 - wobble + jitter,
                2.0 + wobble,
            ));
        }
    }
    points
}

/// Same periods, components and report, and the same densities at several places and times
/// (the conditionals are recomputed on loading).
fn assert_same_model(a: &HypertimeModel, b: &HypertimeModel) {
    assert_eq!(a.projection(), b.projection());
    assert_eq!(a.report(), b.report());
    assert_eq!(a.components(), b.components());
    for hour in [0.0, 10.25, 13.0, 16.25, 23.9] {
        let (x, y) = (a.at(hour * 3600.0), b.at(hour * 3600.0));
        for p in [
            Point2::new(1.1, 0.9),
            Point2::new(5.9, 2.1),
            Point2::new(3.0, 1.5),
            Point2::new(-2.0, 7.0),
        ] {
            close(x.density_at(p), y.density_at(p));
            close(x.log_density_at(p), y.log_density_at(p));
        }
    }
}

#[test]
fn hypertime_models_round_trip_and_give_the_same_densities() {
    let points = detections();
    let params = HypertimeParams::default().with_clusters(4);
    let model = HypertimeModel::fit(&points, &params).unwrap();
    assert_eq!(model.report().skipped, 1);
    let back = trip(&model);
    assert_same_model(&model, &back);
    // Bit for bit, the recomputed conditionals included.
    assert_eq!(back, model);
    // The mean log-likelihood, which goes through every conditional.
    let (a, n) = model.mean_log_likelihood(&points).unwrap();
    let (b, m) = back.mean_log_likelihood(&points).unwrap();
    assert_eq!(n, m);
    assert_relative_eq!(a, b, max_relative = 1e-12);

    // The time-independent baseline, and two periods.
    let baseline = HypertimeModel::fit(&points, &params.clone().without_time()).unwrap();
    assert_same_model(&baseline, &trip(&baseline));
    let two = HypertimeModel::fit(&points, &params.with_periods(vec![DAY, DAY / 3.0])).unwrap();
    assert_same_model(&two, &trip(&two));
}

#[test]
fn an_infinite_report_value_survives_json() {
    // One iteration: the membership change is ∞, which JSON numbers cannot hold.
    let params = HypertimeParams::default()
        .with_gk(GkParams::default().with_clusters(3).with_max_iterations(1));
    let model = HypertimeModel::fit(&detections(), &params).unwrap();
    assert!(!model.report().converged);
    assert_eq!(model.report().change, f64::INFINITY);
    let text = serde_json::to_value(&model).unwrap();
    assert_eq!(text["report"]["change"], json!("inf"));
    let back = trip(&model);
    assert_eq!(back.report().change, f64::INFINITY);
    assert_same_model(&model, &back);

    let report = FitReport {
        points: 10,
        skipped: 0,
        iterations: 3,
        converged: true,
        change: 1e-4,
        objective: f64::NAN,
        spatial_floor: 0.1,
        background_weight: 0.01,
        uniform_weight: 0.2,
        selection: Selection {
            calibration: Some(CalibrationReport {
                floor: 0.1,
                weight: 0.01,
                uniform_weight: 0.2,
                heldout_loglik: Some(f64::NEG_INFINITY),
                heldout: 3,
                uniform_heldout_loglik: Some(-4.5),
                uniform_heldout: 2,
            }),
            period_steps: vec![PeriodStep {
                period: DAY,
                amplitude: None,
                cycles: 1,
                blocks: 1,
                without_loglik: Some(f64::NAN),
                heldout_loglik: Some(f64::NEG_INFINITY),
                accepted: false,
                kept: true,
            }],
            cluster_scores: vec![(2, -1.5), (3, f64::INFINITY)],
        },
    };
    let back = trip(&report);
    assert!(back.objective.is_nan());
    assert_eq!(back.selection.calibration, report.selection.calibration);
    let (a, b) = (
        back.selection.period_steps[0],
        report.selection.period_steps[0],
    );
    assert!(a.amplitude.is_none() && a.without_loglik.unwrap().is_nan());
    assert_eq!(
        (a.period, a.cycles, a.heldout_loglik, a.kept),
        (b.period, b.cycles, b.heldout_loglik, b.kept)
    );
    assert_eq!(
        back.selection.cluster_scores,
        report.selection.cluster_scores
    );
    let none = Selection::default();
    assert_eq!(trip(&none), none);
    // `null` is not a value, and other strings are refused.
    let mut v = serde_json::to_value(&report).unwrap();
    v["change"] = Value::Null;
    assert_names(&rejection::<FitReport>(v.clone()), &["null"]);
    v["change"] = json!("infinity");
    assert_names(&rejection::<FitReport>(v), &["infinity"]);
}

#[test]
fn a_bad_hypertime_model_is_rejected_naming_the_problem() {
    let model =
        HypertimeModel::fit(&detections(), &HypertimeParams::default().with_clusters(2)).unwrap();
    let good = serde_json::to_value(&model).unwrap();
    assert!(serde_json::from_value::<HypertimeModel>(good.clone()).is_ok());
    let broken = |edit: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        edit(&mut v);
        rejection::<HypertimeModel>(v)
    };
    let e = broken(&|v| v["components"] = json!([]));
    assert_names(&e, &["hypertime model", "no component"]);
    let e = broken(&|v| v["components"][1]["mean"] = json!([1.0, 2.0, 0.5]));
    assert_names(&e, &["component 1", "mean of 3 values", "4 dimensions"]);
    let e = broken(&|v| v["components"][0]["mean"][2] = Value::Null);
    assert_names(&e, &["null"]);
    let e = broken(&|v| v["components"][0]["covariance"][1][1] = Value::Null);
    assert_names(&e, &["null"]);
    let e = broken(&|v| v["components"][0]["covariance"][2] = json!([0.0, 0.0, 1.0]));
    assert_names(&e, &["row 2 has 3 values for 4 rows"]);
    let e = broken(&|v| {
        v["components"][0]["covariance"] = json!([[1.0, 0.0], [0.0, 1.0]]);
    });
    assert_names(&e, &["component 0", "covariance of 2 × 2, expected 4 × 4"]);
    let e = broken(&|v| v["components"][0]["weight"] = json!(1.5));
    assert_names(&e, &["weight 1.5"]);
    let e = broken(&|v| {
        let w = v["components"][0]["weight"].as_f64().unwrap();
        v["components"][0]["weight"] = json!(w * 0.5);
    });
    assert_names(&e, &["weights sum to"]);
    let e = broken(&|v| v["components"][1]["covariance"][0][1] = json!(0.123));
    assert_names(&e, &["component 1", "not symmetric at (1, 0)"]);
    let e = broken(&|v| {
        let mut rows = vec![vec![0.0; 4]; 4];
        rows[0][0] = 1.0;
        rows[1][1] = 1.0;
        v["components"][1]["covariance"] = json!(rows);
    });
    assert_names(&e, &["covariance of cluster 1 is degenerate"]);
    let e = broken(&|v| v["projection"]["periods"] = json!([-3600.0]));
    assert_names(&e, &["periods", "-3600"]);
    let e = broken(&|v| v["report"]["points"] = json!(1));
    assert_names(&e, &["2 components for 1 points"]);
}

#[test]
fn gk_clusterings_round_trip_and_are_checked() {
    let data = [
        0.0, 0.0, 0.1, 0.0, 0.0, 0.1, 0.1, 0.1, 5.0, 5.0, 5.1, 5.0, 5.0, 5.1, 5.2, 5.2,
    ];
    let gk = GkParams::default().with_clusters(2).fit(&data, 2).unwrap();
    let back: GkClustering = trip(&gk);
    assert_eq!(back, gk);
    assert_eq!((back.dim(), back.clusters(), back.len()), (2, 2, 8));
    assert_eq!(back.hard_labels(), gk.hard_labels());
    for i in 0..2 {
        assert_eq!(back.norm_matrix(i, 1.0), gk.norm_matrix(i, 1.0));
    }
    // A partial clustering after one iteration: its change is ∞.
    let Err(AffordanceError::NotConverged { partial, .. }) = GkParams::default()
        .with_clusters(2)
        .with_max_iterations(1)
        .fit(&data, 2)
    else {
        panic!("one iteration cannot converge");
    };
    assert_eq!(trip(&*partial).change(), f64::INFINITY);

    let good = serde_json::to_value(&gk).unwrap();
    let broken = |edit: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        edit(&mut v);
        rejection::<GkClustering>(v)
    };
    let e = broken(&|v| v["clusters"] = json!(0));
    assert_names(&e, &["GK clustering", "clusters = 0"]);
    let e = broken(&|v| v["centres"] = json!([0.0, 0.0, 5.0]));
    assert_names(&e, &["3 centre values for 2 clusters of dimension 2"]);
    let e = broken(&|v| v["covariances"] = json!([[[1.0, 0.0], [0.0, 1.0]]]));
    assert_names(&e, &["1 covariances for 2 clusters"]);
    let e = broken(&|v| v["covariances"][1] = json!([[1.0]]));
    assert_names(&e, &["covariance 1 is 1 × 1, expected 2 × 2"]);
    let e = broken(&|v| v["memberships"][3] = json!(0.9));
    assert_names(&e, &["memberships of point 1"]);
    let e = broken(&|v| v["memberships"] = json!([1.0, 0.0, 1.0]));
    assert_names(&e, &["3 memberships are not rows of 2"]);
    let e = broken(&|v| v["centres"][1] = Value::Null);
    assert_names(&e, &["null"]);
}

/// An 8 m × 6 m hall at 0.25 m: five people along y = 1, two along x = 6.
fn hall() -> (GridGeometry, Vec<Trajectory>) {
    let g = GridGeometry::new(0.25, Point2::new(-0.5, -0.5), 32, 24).unwrap();
    let mut people: Vec<Trajectory> = (0..5)
        .map(|id| walk(id, (0.0, 1.0 + 0.1 * id as f64), (7.0, 1.0), 30))
        .collect();
    people.push(walk(10, (6.0, 0.0), (6.0, 5.0), 20));
    people.push(walk(11, (6.2, 5.0), (6.2, 0.5), 20));
    (g, people)
}

fn assert_same_ta(a: &TaMap, b: &TaMap) {
    assert_eq!(a.params(), b.params());
    assert_eq!(a.geometry(), b.geometry());
    assert_eq!(a.cells(), b.cells());
    assert_eq!(a.lengthscale(), b.lengthscale());
    assert_eq!(a.model().is_sparse(), b.model().is_sparse());
    close_grids(a.raster(), b.raster());
    for p in [
        Point2::new(3.0, 1.0),
        Point2::new(6.1, 3.0),
        Point2::new(0.1, 5.0),
        Point2::new(7.2, 5.3),
    ] {
        close(a.density_at(p), b.density_at(p));
    }
    assert_eq!(b.density_at(Point2::new(-3.0, 1.0)), None);
    let other = GridGeometry::new(0.5, Point2::new(-1.0, -1.0), 20, 16).unwrap();
    close_grids(&a.rasterise(&other), &b.rasterise(&other));
}

#[test]
fn ta_maps_round_trip_and_give_the_same_mean() {
    let (g, people) = hall();
    let exact = TaMap::fit(&people, g, &TaParams::default()).unwrap();
    assert!(exact.density_at(Point2::new(3.0, 1.0)).unwrap() > 2.0);
    assert_same_ta(&exact, &trip(&exact));
    // A fitted length scale is stored, not searched again; the sparse GP is refitted too.
    let fitted = TaParams::default()
        .with_fitted_lengthscale(0.5, 5.0)
        .with_regression(RegressionParams::default().with_exact_limit(50));
    let map = TaMap::fit(&people, g, &fitted).unwrap();
    assert!(map.model().is_sparse());
    assert_ne!(map.lengthscale(), 2.0);
    assert_same_ta(&map, &trip(&map));
    // The exact grid mode.
    let exact_grid = TaParams::default()
        .with_regression(RegressionParams::default().with_grid_mode(GridMode::Exact));
    let map = TaMap::fit(&people, g, &exact_grid).unwrap();
    assert_same_ta(&map, &trip(&map));
}

#[test]
fn a_bad_ta_map_is_rejected_naming_the_problem() {
    let (g, people) = hall();
    let good = serde_json::to_value(TaMap::fit(&people, g, &TaParams::default()).unwrap()).unwrap();
    assert!(serde_json::from_value::<TaMap>(good.clone()).is_ok());
    let broken = |edit: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        edit(&mut v);
        rejection::<TaMap>(v)
    };
    let e = broken(&|v| v["activity"]["training"]["activity"] = json!([1.0, 2.0]));
    assert_names(&e, &["TA map", "190 training points for 2 levels"]);
    let e = broken(&|v| {
        v["activity"]["training"]["points"] = json!([]);
        v["activity"]["training"]["activity"] = json!([]);
    });
    assert_names(&e, &["empty training set"]);
    let e = broken(&|v| v["activity"]["training"]["points"][3] = json!([null, 1.0]));
    assert_names(&e, &["null"]);
    let e = broken(&|v| v["activity"]["training"]["activity"][7] = json!(-1.0));
    assert_names(&e, &["level of activity 7 is -1"]);
    let e = broken(&|v| v["lengthscale"] = json!(2.5));
    assert_names(&e, &["length scale 2.5 differs"]);
    let e = broken(&|v| {
        v["params"]["fit_lengthscale"] = json!([0.5, 1.5]);
    });
    assert_names(&e, &["fitted length scale 2 outside its bounds [0.5, 1.5]"]);
    let e = broken(&|v| v["params"]["cell_size"] = json!(0.0));
    assert_names(&e, &["cell_size"]);
    let e = broken(&|v| v["params"]["cell_size"] = json!(2.0));
    assert_names(&e, &["activity counts lies on"]);
    let e = broken(&|v| v["activity"]["sessions"] = json!(0));
    assert_names(&e, &["0 sessions"]);
    let e = broken(&|v| v["params"]["regression"]["noise"] = json!(-1.0));
    assert_names(&e, &["noise"]);
}

#[test]
fn confidence_maps_round_trip_and_are_checked() {
    let g = GridGeometry::new(0.5, Point2::new(-5.0, -5.0), 20, 20).unwrap();
    let mut robot: Vec<Point2<f64>> = (0..60)
        .map(|k| Point2::new(-4.0 + 0.1 * k as f64, 0.3))
        .collect();
    robot.push(Point2::new(f64::NAN, 0.0));
    for params in [
        RegressionParams::default(),
        RegressionParams::default()
            .with_exact_limit(20)
            .with_inducing(30),
    ] {
        let map = ConfidenceMap::fit(&robot, g, 3.0, &params).unwrap();
        let back = trip(&map);
        assert_eq!(back.geometry(), map.geometry());
        assert_eq!(back.sensor_range(), 3.0);
        assert_eq!(back.params(), map.params());
        assert_eq!((back.observers(), back.skipped()), (60, 1));
        assert_eq!(back.positions(), map.positions());
        assert_eq!(back.model().is_sparse(), map.model().is_sparse());
        close_grids(back.raster(), map.raster());
        for p in [
            Point2::new(0.0, 0.3),
            Point2::new(-4.9, 4.9),
            Point2::new(4.0, -2.0),
        ] {
            close(back.confidence_at(p), map.confidence_at(p));
        }
        assert!(back.confidence_at(Point2::new(-2.0, 0.3)).unwrap() > 0.9);
    }

    let map = ConfidenceMap::fit(&robot, g, 3.0, &RegressionParams::default()).unwrap();
    let good = serde_json::to_value(&map).unwrap();
    let broken = |edit: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        edit(&mut v);
        rejection::<ConfidenceMap>(v)
    };
    let e = broken(&|v| v["positions"] = json!([]));
    assert_names(&e, &["confidence map", "no robot position"]);
    let e = broken(&|v| v["positions"][4] = json!([0.0, null]));
    assert_names(&e, &["null"]);
    let e = broken(&|v| v["positions"][4] = json!([0.0]));
    assert_names(&e, &["invalid length 1"]);
    let e = broken(&|v| v["sensor_range"] = json!(-3.0));
    assert_names(&e, &["sensor_range"]);
    let e = broken(&|v| v["params"]["inducing"] = json!(0));
    assert_names(&e, &["inducing"]);
    let e = broken(&|v| v["geometry"]["resolution"] = json!(0.0));
    assert_names(&e, &["resolution"]);
}

/// A few points in and around `g`, one not finite.
fn probes(g: &GridGeometry) -> Vec<Point2<f64>> {
    let o = g.origin();
    let (w, h) = (
        g.width() as f64 * g.resolution(),
        g.height() as f64 * g.resolution(),
    );
    vec![
        Point2::new(o.x + 0.3 * w, o.y + 0.6 * h),
        Point2::new(o.x + 0.9 * w, o.y + 0.1 * h),
        Point2::new(o.x - 1.0, o.y + 0.5 * h),
        Point2::new(f64::NAN, o.y),
    ]
}

/// A small raster geometry (7 × 5 cells) over the same area as `g`.
fn small_over(g: &GridGeometry) -> GridGeometry {
    let r = (g.width() as f64 * g.resolution() / 7.0).max(1e-3);
    GridGeometry::new(r, g.origin(), 7, 5).unwrap()
}

/// Density at the probes and a small raster.
fn exercise_density(d: &dyn DensityMap, g: &GridGeometry) {
    for p in probes(g) {
        let _ = d.density_at(p);
    }
    let small = small_over(g);
    assert_eq!(d.rasterise(&small).geometry(), &small);
}

fn exercise_daily(d: &DailyDensity) {
    let g = *d.geometry();
    assert!(d.visits().geometry().same_cells(&g, 1e-9));
    assert!(d.min_visits() >= 1);
    assert_eq!(d.density_grid().geometry(), &g);
    assert!(d.known_cells() <= g.width() * g.height());
    exercise_density(d, &g);
    let mut sum = CumulativeDensity::new(g, d.min_visits()).unwrap();
    sum.add(d).unwrap();
    sum.add(d).unwrap();
}

fn exercise_cumulative(c: &CumulativeDensity) {
    let g = *c.geometry();
    assert!(c.visits().geometry().same_cells(&g, 1e-9));
    let _ = (c.days(), c.min_visits());
    assert_eq!(c.density_grid().geometry(), &g);
    exercise_density(c, &g);
    let mut more = c.clone();
    more.add_counts(&Grid::filled(g, 1), &Grid::filled(g, 2))
        .unwrap();
}

fn exercise_hits(h: &HitCounter) {
    let g = *h.counts().geometry();
    let _ = (h.radius(), h.stats(), h.stats().positions());
    let mut more = h.clone();
    for p in probes(&g) {
        more.add(p);
    }
    more.add_all(probes(&g));
    let _ = more.into_counts();
}

fn exercise_projection(p: &Projection) {
    let d = p.dim();
    assert_eq!(d, 2 + 2 * p.periods().len());
    let mut out = vec![0.0; d];
    p.project_into(&TimedPoint::new(1.7e9, 1.0, 2.0), &mut out);
}

/// An 8 × 8 room at 0.25 m (a small layout library).
fn small_room() -> GridGeometry {
    GridGeometry::new(0.25, Point2::origin(), 8, 8).unwrap()
}

/// A day's map of [`small_room`]: a wall along column `col`, the column right of it free.
fn small_wall(col: usize) -> haunts_occupancy::OccupancyGrid {
    let mut m = haunts_occupancy::OccupancyGrid::unknown(small_room());
    for row in 0..8 {
        m.set(Cell::new(col, row), haunts_occupancy::OCCUPIED);
        m.set(Cell::new(col + 1, row), haunts_occupancy::FREE);
    }
    m
}

fn small_counts(scale: u32) -> DailyDensity {
    let g = small_room();
    DailyDensity::new(
        Grid::from_fn(g, |c| scale * (c.row % 3) as u32),
        Grid::from_fn(g, |c| 1 + (c.col % 4) as u32),
        1,
    )
    .unwrap()
}

fn small_library() -> LayoutLibrary {
    let mut library = LayoutLibrary::new(small_room(), LayoutParams::default()).unwrap();
    library
        .ingest("mon", &small_wall(1), &small_counts(1))
        .unwrap();
    library
        .ingest("tue", &small_wall(1), &small_counts(2))
        .unwrap();
    library
        .ingest("wed", &small_wall(6), &small_counts(3))
        .unwrap();
    library
}

fn exercise_layout(l: &Layout) {
    let _ = (l.id(), l.days().len(), l.composite().maps());
    let _ = (l.composite().occupied_counts(), l.composite().free_counts());
    let _ = l.composite_mask(0.5);
    let a = l.affordance();
    exercise_cumulative(a);
}

/// Classifies and ingests a room's maps (`wall` builds them) with its counts.
fn exercise_library(
    library: &LayoutLibrary,
    wall: fn(usize) -> haunts_occupancy::OccupancyGrid,
    counts: fn(u32) -> DailyDensity,
) {
    let _ = (library.geometry(), library.params(), library.day_count());
    for l in library.layouts() {
        assert_eq!(library.layout(l.id()).unwrap().id(), l.id());
        exercise_layout(l);
        for d in l.days() {
            assert!(library.find_day(&d.label).is_some());
        }
    }
    let _ = library.find_day("nobody");
    let mut more = library.clone();
    for (k, col) in [1, 5, 3].into_iter().enumerate() {
        let _ = library.classify(&wall(col));
        let _ = more.ingest(format!("extra {k}"), &wall(col), &counts(2));
    }
}

fn exercise_hypertime(model: &HypertimeModel) {
    let _ = (model.projection(), model.periods(), model.report());
    assert_eq!(model.components().len(), model.clusters());
    let g = GridGeometry::new(0.5, Point2::new(-1.0, -1.0), 16, 8).unwrap();
    for hour in [0.0, 10.25, 16.0] {
        let snapshot = model.at(hour * 3600.0);
        let _ = (snapshot.time(), snapshot.weights());
        for p in probes(&g) {
            let _ = snapshot.log_density_at(p);
        }
        exercise_density(&snapshot, &g);
    }
    let _ = model.at(f64::NAN).weights();
    let points = detections();
    let _ = model.log_density(&points[3]);
    let _ = model.mean_log_likelihood(&points);
}

fn exercise_gk(gk: &GkClustering) {
    let (d, c, n) = (gk.dim(), gk.clusters(), gk.len());
    assert_eq!(gk.centres().len(), d * c);
    assert_eq!(gk.memberships().len(), n * c);
    let _ = (gk.is_empty(), gk.iterations(), gk.objective(), gk.change());
    for i in 0..=c {
        let _ = (gk.centre(i), gk.covariance(i), gk.norm_matrix(i, 1.0));
    }
    for j in [0, n / 2, n] {
        let _ = gk.membership(j);
    }
    assert_eq!(gk.hard_labels().len(), n);
}

fn exercise_ta(map: &TaMap) {
    let g = *map.geometry();
    assert_eq!(map.raster().geometry(), &g);
    let _ = (
        map.training().len(),
        map.cells().levels(),
        map.lengthscale(),
    );
    let _ = (map.params(), map.grid_check(), map.model().is_sparse());
    let _ = map.model().predict(&probes(&g)[..3]).unwrap();
    exercise_density(map, &g);
    let free = haunts_occupancy::OccupancyGrid::unknown(g);
    let _ = map.on_free_cells(&free);
}

fn exercise_confidence(map: &ConfidenceMap) {
    let g = *map.geometry();
    assert_eq!(map.raster().geometry(), &g);
    let _ = (map.sensor_range(), map.observers(), map.positions().len());
    let _ = (map.params(), map.skipped(), map.grid_check());
    let _ = map.model().predict(&probes(&g)[..3]).unwrap();
    for p in probes(&g) {
        let _ = map.confidence_at(p);
    }
}

#[test]
fn corrupted_files_are_refused_or_usable_never_a_panic() {
    let mut tallies: Vec<(&str, Tally)> = Vec::new();
    // Densities on 3 × 2 cells: every variant.
    let g = geometry(3, 2);
    let day = DailyDensity::new(
        Grid::from_vec(g, vec![2, 0, 5, 1, 7, 0]).unwrap(),
        Grid::from_vec(g, vec![4, 3, 0, 1, 2, 9]).unwrap(),
        2,
    )
    .unwrap();
    tallies.push(("DailyDensity", corrupt(&day, 400, exercise_daily)));
    let mut all = CumulativeDensity::new(g, 1).unwrap();
    all.add(&day).unwrap();
    all.add(&day).unwrap();
    tallies.push(("CumulativeDensity", corrupt(&all, 400, exercise_cumulative)));
    let mut hits = HitCounter::new(g, 0.3).unwrap();
    hits.add(Point2::new(-0.75, 2.25));
    hits.add(Point2::new(f64::NAN, 0.0));
    tallies.push(("HitCounter", corrupt(&hits, 400, exercise_hits)));
    let projection = Projection::new(vec![DAY, 7.0 * DAY]).unwrap();
    tallies.push(("Projection", corrupt(&projection, 100, exercise_projection)));
    // Layouts: the small library whole, and 60 × 60 ones spread out.
    let small = small_library();
    let layout = small.layouts()[0].clone();
    tallies.push(("Layout", corrupt(&layout, 2000, exercise_layout)));
    tallies.push((
        "LayoutLibrary (8 × 8)",
        corrupt(&small, 3000, |l| {
            exercise_library(l, small_wall, small_counts)
        }),
    ));
    tallies.push((
        "LayoutLibrary (60 × 60)",
        corrupt(&library(), 100, |l| exercise_library(l, wall_at, counts)),
    ));
    // Hypertime: a model of 2 clusters (conditionals recomputed on load) and a clustering.
    let model =
        HypertimeModel::fit(&detections(), &HypertimeParams::default().with_clusters(2)).unwrap();
    tallies.push(("HypertimeModel", corrupt(&model, 400, exercise_hypertime)));
    let data = [
        0.0, 0.0, 0.1, 0.0, 0.0, 0.1, 0.1, 0.1, 5.0, 5.0, 5.1, 5.0, 5.0, 5.1, 5.2, 5.2,
    ];
    let gk = GkParams::default().with_clusters(2).fit(&data, 2).unwrap();
    tallies.push(("GkClustering", corrupt(&gk, 400, exercise_gk)));
    // TA maps (a GP refit and a raster per load): exact and sparse.
    let (hall, people) = hall();
    let exact = TaMap::fit(&people, hall, &TaParams::default()).unwrap();
    tallies.push(("TaMap (exact)", corrupt(&exact, 300, exercise_ta)));
    let fitted = TaParams::default()
        .with_fitted_lengthscale(0.5, 5.0)
        .with_regression(RegressionParams::default().with_exact_limit(50));
    let sparse = TaMap::fit(&people, hall, &fitted).unwrap();
    tallies.push(("TaMap (sparse)", corrupt(&sparse, 300, exercise_ta)));
    // Confidence maps, exact and sparse.
    let cg = GridGeometry::new(0.5, Point2::new(-5.0, -5.0), 20, 20).unwrap();
    let robot: Vec<Point2<f64>> = (0..30)
        .map(|k| Point2::new(-4.0 + 0.2 * k as f64, 0.3))
        .collect();
    for params in [
        RegressionParams::default(),
        RegressionParams::default()
            .with_exact_limit(10)
            .with_inducing(20),
    ] {
        let map = ConfidenceMap::fit(&robot, cg, 3.0, &params).unwrap();
        tallies.push(("ConfidenceMap", corrupt(&map, 300, exercise_confidence)));
    }
    eprintln!("{tallies:#?}");
    for (name, t) in &tallies {
        assert!(t.refused > 0, "{name}: nothing refused ({t:?})");
    }
}

#[test]
fn a_library_with_a_huge_cutoff_classifies_without_overflow() {
    // A finite cutoff of 1e300 m is valid, but haunts-similarity's `directed_difference`
    // overflowed an integer on it (a panic in classify and ingest; fixed in its
    // `min_squared_above`); no distance exceeds it, so every difference is 0 and every day
    // matches the first layout.
    let mut v = serde_json::to_value(small_library()).unwrap();
    v["params"]["difference"] = json!({"cutoff": {"Metres": 1e300}});
    let mut loaded: LayoutLibrary = serde_json::from_value(v).unwrap();
    let mut by_hand = LayoutLibrary::new(
        small_room(),
        LayoutParams::default()
            .with_difference(DifferenceParams::default().with_cutoff(Length::Cells(1e300))),
    )
    .unwrap();
    by_hand
        .ingest("mon", &small_wall(1), &small_counts(1))
        .unwrap();
    for col in [1, 6] {
        let c = loaded.classify(&small_wall(col)).unwrap();
        assert_eq!(c.distances.first().and_then(|d| d.distance), Some(0.0));
        assert!(c.distances.iter().all(|d| d.matches));
        let c = by_hand.classify(&small_wall(col)).unwrap();
        assert_eq!(c.layout.map(|l| l.0), Some(0));
    }
    loaded
        .ingest("thu", &small_wall(6), &small_counts(1))
        .unwrap();
    assert_eq!(loaded.day_count(), 4);
}
