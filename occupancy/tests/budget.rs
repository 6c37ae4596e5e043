//! The cell budget raised and lowered (its own test process: the budget is process-wide).
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
