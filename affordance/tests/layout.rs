//! The layout library's behaviour: matching, new layouts, affordance sums, histories and every
//! way a day can be refused without changing what is stored.

use approx::assert_relative_eq;
use haunts_affordance::density::DailyDensity;
use haunts_affordance::layout::{DayId, LayoutId, LayoutLibrary, LayoutParams};
use haunts_affordance::{AffordanceError, DensityMap};
use haunts_occupancy::{Cell, Grid, GridGeometry, OCCUPIED, OccupancyGrid};
use haunts_similarity::{ClusterParams, LayoutThreshold, SimilarityError, Symmetrisation};
use nalgebra::Point2;

mod common;
use common::{room, wall_at};

fn counts(hits: u32, visits: u32) -> DailyDensity {
    DailyDensity::new(Grid::filled(room(), hits), Grid::filled(room(), visits), 1).unwrap()
}

fn library() -> LayoutLibrary {
    LayoutLibrary::new(room(), LayoutParams::default()).unwrap()
}

#[test]
fn an_empty_library_matches_nothing() {
    let lib = library();
    let c = lib.classify(&wall_at(5)).unwrap();
    assert_eq!(c.layout, None);
    assert!(c.distances.is_empty());
    assert_eq!(c.distance(), None);
}

#[test]
fn a_small_move_joins_a_large_move_starts_a_new_layout() {
    let mut lib = library();
    let first = lib.ingest("d0", &wall_at(10), &counts(1, 2)).unwrap();
    assert!(first.created);
    assert_eq!((first.day, first.layout), (DayId(0), LayoutId(0)));
    // 9 cells (0.45 m) is within the cutoff ct = 0.5 m: a difference of zero.
    let near = lib.ingest("d1", &wall_at(19), &counts(1, 2)).unwrap();
    assert!(!near.created);
    assert_eq!(near.layout, LayoutId(0));
    assert_eq!(near.classification.distance(), Some(0.0));
    // The layout's composite map now holds both walls (each in half of its days). A wall at
    // column 50 lies 31 cells from the nearer one (60 · 31 cells²); the composite's walls lie
    // 40 and 31 cells from it (60 · 71 cells²): the larger, 4260 cells² = 10.65 m² > 3.25 m².
    let far = lib.ingest("d2", &wall_at(50), &counts(1, 2)).unwrap();
    assert!(far.created);
    assert_eq!(far.layout, LayoutId(1));
    let d = far.classification.distances[0];
    assert!(!d.matches);
    assert_relative_eq!(
        d.distance.unwrap(),
        4260.0 * 0.05 * 0.05,
        max_relative = 1e-12
    );
    assert_eq!(lib.layouts().len(), 2);
    assert_eq!(lib.day_count(), 3);
}

#[test]
fn the_threshold_is_strict_and_in_the_similarity_crates_units() {
    // 60 cells moved by 40 cells: 2400 cells². A threshold of exactly 2400 cells² does not
    // match (strictly below is required), 2401 does.
    for (threshold, joins) in [(2400.0, false), (2401.0, true)] {
        let params = LayoutParams::default().with_cluster(
            ClusterParams::default().with_threshold(LayoutThreshold::Cells(threshold)),
        );
        let mut lib = LayoutLibrary::new(room(), params).unwrap();
        lib.ingest("a", &wall_at(10), &counts(0, 1)).unwrap();
        let r = lib.ingest("b", &wall_at(50), &counts(0, 1)).unwrap();
        assert_eq!(!r.created, joins, "threshold {threshold}");
    }
}

#[test]
fn the_day_joins_the_closest_matching_layout() {
    // Two layouts, each a wall; a permissive threshold lets a day match both, and it joins the
    // closer one.
    let params = LayoutParams::default().with_cluster(
        ClusterParams::default()
            .with_threshold(LayoutThreshold::Cells(5000.0))
            .with_symmetrisation(Symmetrisation::Max),
    );
    let mut lib = LayoutLibrary::new(room(), params).unwrap();
    lib.ingest("a", &wall_at(5), &counts(0, 1)).unwrap();
    // Walls at 5, 40 and 55: 60 · 35 + 60 · 50 = 5100 cells² from layout 0, a new layout.
    let mut three_walls = wall_at(5);
    for row in 0..60 {
        three_walls.set(Cell::new(55, row), OCCUPIED);
        three_walls.set(Cell::new(40, row), OCCUPIED);
    }
    let b = lib.ingest("b", &three_walls, &counts(0, 1)).unwrap();
    assert!(b.created, "{:?}", b.classification);
    // Walls at 5, 38 and 55: 60 · 33 + 60 · 50 = 4980 cells² from layout 0 (a match, barely)
    // and 0 from layout 1 (38 is within ct of 40).
    let mut day = wall_at(5);
    for row in 0..60 {
        day.set(Cell::new(38, row), OCCUPIED);
        day.set(Cell::new(55, row), OCCUPIED);
    }
    let c = lib.classify(&day).unwrap();
    assert!(c.distances.iter().all(|d| d.matches), "{c:?}");
    assert_eq!(c.layout, Some(LayoutId(1)));
    assert_eq!(c.distances[1].distance, Some(0.0));
    assert_eq!(c.distances[0].distance, Some(4980.0));
}

#[test]
fn a_layouts_affordance_is_the_sum_of_its_days() {
    let mut lib = library();
    lib.ingest("a", &wall_at(10), &counts(1, 4)).unwrap();
    lib.ingest("b", &wall_at(50), &counts(7, 7)).unwrap();
    lib.ingest("c", &wall_at(11), &counts(3, 4)).unwrap();
    let first = lib.layout(LayoutId(0)).unwrap();
    let p = Point2::new(1.0, 1.0);
    assert_relative_eq!(first.affordance().density_at(p).unwrap(), 0.5); // (1 + 3) / (4 + 4)
    assert_eq!(first.affordance().days(), 2);
    let second = lib.layout(LayoutId(1)).unwrap();
    assert_relative_eq!(second.affordance().density_at(p).unwrap(), 1.0);
    // The composite counts both days of layout 0: column 10 occupied once, 11 once.
    assert_eq!(first.composite().maps(), 2);
    assert_eq!(first.composite().occupied_counts()[Cell::new(10, 3)], 1);
    assert_eq!(first.composite().occupied_counts()[Cell::new(11, 3)], 1);
    assert_eq!(first.composite().occupied_counts()[Cell::new(50, 3)], 0);
    let mask = first.composite_mask(0.5).unwrap();
    assert!(mask[Cell::new(10, 3)] && mask[Cell::new(11, 3)]);
    assert!(!first.composite_mask(1.0).unwrap()[Cell::new(10, 3)]);
    assert!(first.composite_mask(0.0).is_err());
    assert!(lib.layout(LayoutId(2)).is_none());
}

#[test]
fn histories_keep_labels_ids_and_distances() {
    let mut lib = library();
    for (label, col) in [("mon", 10), ("tue", 50), ("wed", 12), ("thu", 49)] {
        lib.ingest(label, &wall_at(col), &counts(0, 1)).unwrap();
    }
    let labels = |id: usize| -> Vec<&str> {
        lib.layout(LayoutId(id))
            .unwrap()
            .days()
            .iter()
            .map(|d| d.label.as_str())
            .collect()
    };
    assert_eq!(labels(0), ["mon", "wed"]);
    assert_eq!(labels(1), ["tue", "thu"]);
    let (layout, record) = lib.find_day("wed").unwrap();
    assert_eq!(layout, LayoutId(0));
    assert_eq!(record.id, DayId(2));
    assert_eq!(record.distance, Some(0.0));
    assert_eq!(lib.find_day("mon").unwrap().1.distance, None);
    assert!(lib.find_day("fri").is_none());
}

#[test]
fn refused_days_leave_the_library_unchanged() {
    let mut lib = library();
    lib.ingest("a", &wall_at(10), &counts(1, 2)).unwrap();
    let before = lib.clone();
    let other = GridGeometry::new(0.05, Point2::new(0.05, 0.0), 60, 60).unwrap();
    let mut shifted = OccupancyGrid::unknown(other);
    shifted.set(Cell::new(3, 3), OCCUPIED);
    assert!(matches!(
        lib.ingest("b", &shifted, &counts(1, 2)),
        Err(AffordanceError::GeometryMismatch {
            what: "day map",
            ..
        })
    ));
    assert!(matches!(
        lib.classify(&shifted),
        Err(AffordanceError::GeometryMismatch {
            what: "day map",
            ..
        })
    ));
    let wrong_counts =
        DailyDensity::new(Grid::filled(other, 1), Grid::filled(other, 1), 1).unwrap();
    assert!(matches!(
        lib.ingest("b", &wall_at(10), &wrong_counts),
        Err(AffordanceError::GeometryMismatch {
            what: "day hits",
            ..
        })
    ));
    assert!(matches!(
        lib.ingest("b", &OccupancyGrid::unknown(room()), &counts(1, 2)),
        Err(AffordanceError::EmptyDayMap)
    ));
    match lib.ingest("a", &wall_at(10), &counts(1, 2)) {
        Err(AffordanceError::DuplicateDay { label }) => assert_eq!(label, "a"),
        other => panic!("{other:?}"),
    }
    assert_eq!(lib, before);
    // And the library still works.
    assert!(
        !lib.ingest("b", &wall_at(10), &counts(1, 2))
            .unwrap()
            .created
    );
}

#[test]
fn a_layout_whose_days_disagree_everywhere_matches_nothing() {
    // Three days of one layout (permissive threshold) with walls in different places: no cell
    // is occupied in half of them, so the composite map is empty and cannot be matched.
    let params = LayoutParams::default()
        .with_cluster(ClusterParams::default().with_threshold(LayoutThreshold::Cells(1e9)));
    let mut lib = LayoutLibrary::new(room(), params).unwrap();
    for (i, col) in [5, 30, 55].into_iter().enumerate() {
        lib.ingest(format!("d{i}"), &wall_at(col), &counts(0, 1))
            .unwrap();
    }
    assert_eq!(lib.layouts().len(), 1);
    let c = lib.classify(&wall_at(30)).unwrap();
    assert_eq!(c.layout, None);
    assert_eq!(c.distances[0].distance, None);
    assert!(!c.distances[0].matches);
}

#[test]
fn bad_parameters_are_typed_errors() {
    let bad_fraction = LayoutParams::default().with_composite_min_fraction(1.5);
    assert!(matches!(
        LayoutLibrary::new(room(), bad_fraction),
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "composite_min_fraction",
                ..
            }
        ))
    ));
    assert!(matches!(
        LayoutParams::default().with_min_visits(0).check(),
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "min_visits",
                ..
            }
        ))
    ));
    let bad_threshold = LayoutParams::default().with_cluster(
        ClusterParams::default().with_threshold(LayoutThreshold::SquareMetres(f64::NAN)),
    );
    assert!(matches!(
        bad_threshold.check(),
        Err(AffordanceError::Similarity(
            SimilarityError::InvalidParameter(haunts_core::InvalidParameter { .. })
        ))
    ));
}

/// `LayoutParams::observed_only` (the default): structure counts against a day only where
/// the day observed. A layout with walls at columns 10 and 50, and a day that saw only
/// columns 0..30 with the wall at 10: the wall at 50 is no evidence that anything moved, so
/// the day joins the layout; compared as whole maps (seed 000's measure, `false`), the wall
/// it never looked at makes it a new layout.
#[test]
fn a_day_that_saw_part_of_the_room_is_compared_where_it_looked() {
    let mut both = wall_at(10);
    for row in 0..60 {
        both.set(Cell::new(50, row), OCCUPIED);
    }
    let part = common::wall_seen_in(10, 0..30);
    for observed_only in [true, false] {
        let params = LayoutParams::default().with_observed_only(observed_only);
        let mut lib = LayoutLibrary::new(room(), params).unwrap();
        lib.ingest("both walls", &both, &counts(1, 2)).unwrap();
        let c = lib.classify(&part).unwrap();
        if observed_only {
            assert_eq!(c.layout, Some(LayoutId(0)), "{c:?}");
            assert_eq!(c.distance(), Some(0.0));
        } else {
            assert_eq!(c.layout, None, "{c:?}");
        }
    }
    assert!(LayoutParams::default().observed_only);
}
