//! The work budget at every site of this crate whose work is a product of data-sized factors:
//! hypertime scoring and count evaluation, the TA map's GP raster (cells × training or
//! inducing points) and the confidence map's (cells × their square). Each job is refused with `WorkTooLarge` when the budget is one
//! unit under its work, before it starts, and passes when the budget equals it. One test (the
//! budget is process-wide, so this binary holds nothing else).
#![allow(clippy::unwrap_used, clippy::panic)]

use haunts_affordance::AffordanceError;
use haunts_affordance::hypertime::{
    EvaluationParams, HypertimeModel, HypertimeParams, TimedPoint, evaluate,
};
use haunts_affordance::ta::{ConfidenceMap, GpModel, RegressionParams, TaMap, TaParams};
use haunts_gp::GridMode;
use haunts_occupancy::{GridGeometry, OccupancyError, budget};
use haunts_tracking::Trajectory;
use nalgebra::Point2;

mod common;
use common::walk;

/// Runs `job` with the budget raised, one refusal at a time, from 1 unit to what each check
/// asks: every refusal must name a job over the budget in force (so one unit less than its
/// work is refused) and the job must pass once the budget equals that work. Returns the jobs
/// refused, in order, with their work.
fn ladder<T>(mut job: impl FnMut() -> Result<T, AffordanceError>) -> (T, Vec<(&'static str, f64)>) {
    let mut refused = Vec::new();
    budget::set_max_work(1).unwrap();
    loop {
        match job() {
            Ok(value) => {
                budget::set_max_work(budget::DEFAULT_MAX_WORK).unwrap();
                return (value, refused);
            }
            Err(AffordanceError::Occupancy(OccupancyError::WorkTooLarge {
                what,
                work,
                budget,
                ..
            })) => {
                assert!(work > budget as f64, "{what}: {work} within {budget}");
                assert_eq!(budget, budget::max_work());
                refused.push((what, work));
                budget::set_max_work(work as u64).unwrap();
            }
            Err(other) => panic!("{other:?}"),
        }
    }
}

#[test]
fn every_data_sized_job_is_refused_just_over_the_work_budget_and_runs_at_it() {
    assert_eq!(budget::max_work(), budget::DEFAULT_MAX_WORK);

    // Hypertime: 300 detections over 5 hours, scored on a 16 × 16 grid at 60 s steps.
    let points: Vec<TimedPoint> = (0..300)
        .map(|i| {
            TimedPoint::new(
                i as f64 * 60.0,
                0.1 + (i % 9) as f64 * 0.1,
                0.1 + (i % 8) as f64 * 0.1,
            )
        })
        .collect();
    let model = HypertimeModel::fit(&points, &HypertimeParams::default().with_clusters(3)).unwrap();
    let grid = GridGeometry::new(0.25, Point2::origin(), 16, 16).unwrap();
    let components = model.components().len() as f64 + 1.0;
    let (e, refused) = ladder(|| evaluate(&model, &points, &grid, &EvaluationParams::default()));
    assert_eq!(
        refused,
        [("hypertime scoring", 300.0 * 256.0 * components * 64.0)]
    );
    assert_eq!(e.loglik.used, 300);
    // One normalisation step for the whole span: the counts over 30 intervals are the larger.
    let one_step = EvaluationParams::default().with_time_step(1.0e6);
    let (_, refused) = ladder(|| evaluate(&model, &points, &grid, &one_step));
    assert_eq!(
        refused,
        [
            ("hypertime scoring", 256.0 * components * 64.0),
            (
                "hypertime count evaluation",
                30.0 * 256.0 * components * 64.0
            ),
        ]
    );
    // The same scoring with one far detection among the test points: its grid is the
    // caller's, so it is only counted outside; a grid stretched to it is refused at once.
    let far = GridGeometry::bounding(
        points
            .iter()
            .map(|p| p.position)
            .chain([Point2::new(2.0e6, 0.0)]),
        0.25,
        1.0,
    )
    .unwrap();
    match evaluate(&model, &points, &far, &EvaluationParams::default()) {
        Err(AffordanceError::Occupancy(e @ OccupancyError::WorkTooLarge { .. })) => {
            let text = e.to_string();
            assert!(
                text.starts_with("hypertime scoring: 300 time steps × "),
                "{text}"
            );
        }
        other => panic!("{other:?}"),
    }

    // TA map: 6 walkers of 5 samples across a 12 m × 8 m map of 5 cm cells. Exact GP
    // (n ≤ 2000) and the fast raster.
    let g = GridGeometry::new(0.05, Point2::origin(), 240, 160).unwrap();
    let cells = 240.0 * 160.0;
    let people: Vec<Trajectory> = (0..6)
        .map(|i| {
            walk(
                i,
                (0.5, 0.5 + 1.2 * i as f64),
                (11.5, 7.5 - 1.1 * i as f64),
                5,
            )
        })
        .collect();
    let (ta, refused) = ladder(|| TaMap::fit(&people, g, &TaParams::default()));
    let n = ta.training().len() as f64;
    assert_eq!(
        refused,
        [
            ("GP mean raster", 128.0 * 128.0 * n),
            ("GP mean raster", cells * 128.0),
        ]
    );
    // The exact raster: every cell over every training point.
    let exact = TaParams::default()
        .with_regression(RegressionParams::default().with_grid_mode(GridMode::Exact));
    let (_, refused) = ladder(|| TaMap::fit(&people, g, &exact));
    assert_eq!(refused, [("GP mean raster", cells * n)]);
    // The sparse GP: over its inducing points.
    let sparse = TaParams::default().with_regression(
        RegressionParams::default()
            .with_exact_limit(0)
            .with_grid_mode(GridMode::Exact),
    );
    let (ta, refused) = ladder(|| TaMap::fit(&people, g, &sparse));
    let GpModel::Sparse(gp) = ta.model() else {
        panic!("sparse")
    };
    let m = (gp.inducing_points().len() / 2) as f64;
    assert_eq!(refused, [("GP mean raster", cells * m)]);

    // Confidence: the variance of every cell, basis² each.
    let robot: Vec<Point2<f64>> = (0..50).map(|i| Point2::new(0.2 * i as f64, 4.0)).collect();
    let (_, refused) = ladder(|| ConfidenceMap::fit(&robot, g, 3.0, &RegressionParams::default()));
    assert_eq!(
        refused,
        vec![
            ("GP mean and variance raster", 64.0 * 64.0 * 2500.0),
            ("GP mean and variance raster", cells * 64.0 * 64.0),
        ]
    );
    assert_eq!(budget::max_work(), budget::DEFAULT_MAX_WORK);
}
