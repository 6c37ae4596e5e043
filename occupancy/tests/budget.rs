//! The cell and work budgets raised and lowered (its own test process: the budget is process-wide).
#![allow(clippy::unwrap_used, clippy::panic)]

use haunts_occupancy::{GridGeometry, OccupancyError, budget};
use nalgebra::Point2;

#[test]
fn the_budget_can_be_lowered_and_raised_and_is_checked_at_every_construction() {
    assert_eq!(budget::max_cells(), budget::DEFAULT_MAX_CELLS);
    let o = Point2::origin();
    // Lowered to 100 cells: 10 × 10 passes, 10 × 11 does not, by every constructor.
    assert_eq!(
        budget::set_max_cells(100).unwrap(),
        budget::DEFAULT_MAX_CELLS
    );
    let g = GridGeometry::new(0.1, o, 10, 10).unwrap();
    match GridGeometry::new(0.1, o, 10, 11) {
        Err(OccupancyError::GridTooLarge {
            width,
            height,
            budget,
            ..
        }) => assert_eq!((width, height, budget), (10.0, 11.0, 100)),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        g.with_resolution(0.05),
        Err(OccupancyError::GridTooLarge { .. })
    ));
    let corners = [Point2::new(0.0, 0.0), Point2::new(0.95, 1.05)];
    assert!(matches!(
        GridGeometry::bounding(corners, 0.1, 0.0),
        Err(OccupancyError::GridTooLarge { .. })
    ));
    // Raised past the default: a 2^15 × 2^14 geometry (2^29 cells) is accepted (nothing is
    // allocated by a geometry).
    budget::set_max_cells(1 << 30).unwrap();
    assert_eq!(
        GridGeometry::new(0.1, o, 1 << 15, 1 << 14).unwrap().len(),
        1 << 29
    );
    // Never beyond u32 indices, never 0; a refused setting changes nothing.
    assert!(budget::set_max_cells(budget::LIMIT_MAX_CELLS + 1).is_err());
    assert!(budget::set_max_cells(0).is_err());
    assert_eq!(budget::max_cells(), 1 << 30);
    budget::set_max_cells(budget::DEFAULT_MAX_CELLS).unwrap();
    assert!(GridGeometry::new(0.1, o, 1 << 15, 1 << 14).is_err());
}

#[test]
fn the_work_budget_refuses_a_product_just_over_it_and_names_every_factor() {
    assert_eq!(budget::max_work(), budget::DEFAULT_MAX_WORK);
    let job = [("time steps", 10.0), ("cells", 100.0), ("components", 3.0)];
    assert_eq!(budget::check_work("scoring", &job).unwrap(), 3000.0);
    // Lowered to one unit under the job, which is then refused naming it.
    assert_eq!(
        budget::set_max_work(2999).unwrap(),
        budget::DEFAULT_MAX_WORK
    );
    match budget::check_work("scoring", &job) {
        Err(e @ OccupancyError::WorkTooLarge { .. }) => {
            assert_eq!(
                e.to_string(),
                "scoring: 10 time steps × 100 cells × 3 components = 3000 units exceeds \
                 the work budget of 2999 units (haunts_occupancy::budget::set_max_work raises it)"
            );
            let OccupancyError::WorkTooLarge {
                what,
                factors,
                work,
                budget,
            } = e
            else {
                unreachable!()
            };
            assert_eq!(
                (what, factors, work, budget),
                ("scoring", job.to_vec(), 3000.0, 2999)
            );
        }
        other => panic!("{other:?}"),
    }
    budget::set_max_work(3000).unwrap();
    assert!(budget::check_work("scoring", &job).is_ok());
    // Factors past any integer, infinite or NaN are refused, not wrapped.
    for absurd in [1e300, f64::INFINITY, f64::NAN] {
        assert!(matches!(
            budget::check_work("x", &[("a", absurd), ("b", 1e300)]),
            Err(OccupancyError::WorkTooLarge { .. })
        ));
    }
    assert!(budget::set_max_work(0).is_err());
    assert_eq!(budget::max_work(), 3000);
    budget::set_max_work(budget::DEFAULT_MAX_WORK).unwrap();
}
