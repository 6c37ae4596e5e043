//! The work budget of the similarity matrix (its own test process: the budget is
//! process-wide): maps × the occupied cells of all maps, refused one unit over, run at it.
#![allow(clippy::unwrap_used, clippy::panic)]

use haunts_occupancy::{Cell, GridGeometry, OCCUPIED, OccupancyError, OccupancyGrid, budget};
use haunts_similarity::{DifferenceParams, SimilarityError, similarity_matrix};

#[test]
fn the_similarity_matrix_is_refused_just_over_the_work_budget_and_computed_at_it() {
    let g = GridGeometry::new(0.05, nalgebra::Point2::origin(), 50, 50).unwrap();
    let wall_at = |col| {
        let mut m = OccupancyGrid::unknown(g);
        for row in 0..50 {
            m.set(Cell::new(col, row), OCCUPIED);
        }
        m
    };
    let maps = [wall_at(5), wall_at(7), wall_at(40)];
    // 3 maps × 150 occupied cells.
    budget::set_max_work(449).unwrap();
    match similarity_matrix(&maps, &DifferenceParams::default()) {
        Err(SimilarityError::Occupancy(OccupancyError::WorkTooLarge {
            what,
            factors,
            work,
            ..
        })) => {
            assert_eq!(what, "similarity matrix");
            assert_eq!(
                factors,
                [("maps", 3.0), ("occupied cells of all maps", 150.0)]
            );
            assert_eq!(work, 450.0);
        }
        other => panic!("{other:?}"),
    }
    budget::set_max_work(450).unwrap();
    let m = similarity_matrix(&maps, &DifferenceParams::default()).unwrap();
    assert_eq!(m.get(0, 2), Some(50.0 * 35.0));
    budget::set_max_work(budget::DEFAULT_MAX_WORK).unwrap();
}
