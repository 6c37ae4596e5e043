//! Daily and cumulative densities: hand-computed cases, a brute-force reference for the human
//! hits, skips of bad input, and one suite over every `DensityMap`.

use approx::assert_relative_eq;
use haunts_affordance::density::{
    CumulativeDensity, DailyDensity, DensityParams, HitCounter, HitStats,
};
use haunts_affordance::{AffordanceError, DensityMap};
use haunts_occupancy::raycast::VisitRule;
use haunts_occupancy::{Cell, Grid, GridGeometry, LaserScan, MaxRangeRule, Pose2};
use haunts_tracking::Trajectory;
use nalgebra::{Point2, Vector2};
use proptest::prelude::*;

/// The plain reference: every cell of the grid, tested against the disc.
fn reference_hits(geometry: GridGeometry, radius: f64, positions: &[Point2<f64>]) -> Grid<u32> {
    let mut out = Grid::filled(geometry, 0u32);
    for p in positions {
        if !(p.x.is_finite() && p.y.is_finite()) {
            continue;
        }
        for row in 0..geometry.height() {
            for col in 0..geometry.width() {
                let cell = Cell::new(col, row);
                let c = geometry.cell_center(cell);
                let (dx, dy) = (c.x - p.x, c.y - p.y);
                if dx * dx + dy * dy < radius * radius {
                    out[cell] += 1;
                }
            }
        }
    }
    out
}

fn geom(res: f64, w: usize, h: usize) -> GridGeometry {
    GridGeometry::new(res, Point2::origin(), w, h).unwrap()
}

#[test]
fn disc_at_a_cell_centre_excludes_cells_exactly_on_the_radius() {
    // 0.125 m cells and a 0.25 m radius: every coordinate is exact in binary, so the four
    // cells exactly two cells away are excluded by the strict "closer than" of seed 000.
    let g = geom(0.125, 9, 9);
    let p = g.cell_center(Cell::new(4, 4));
    let mut hits = HitCounter::new(g, 0.25).unwrap();
    assert_eq!(hits.add(p), 9);
    assert_eq!(hits.counts()[Cell::new(6, 4)], 0);
    assert_eq!(hits.counts()[Cell::new(5, 5)], 1);
    let mut wider = HitCounter::new(g, 0.250001).unwrap();
    assert_eq!(wider.add(p), 13);
    assert_eq!(wider.counts()[Cell::new(6, 4)], 1);
}

#[test]
fn disc_at_a_cell_corner_hits_twelve_cells() {
    // Centres at (±0.5, ±0.5), (±0.5, ±1.5), (±1.5, ±0.5) cells from the corner are inside a
    // radius of 2 cells; (±1.5, ±1.5) is 2.12 away.
    let g = geom(0.125, 9, 9);
    let mut hits = HitCounter::new(g, 0.25).unwrap();
    assert_eq!(hits.add(Point2::new(0.5, 0.5)), 12);
    assert_eq!(hits.counts().data().iter().sum::<u32>(), 12);
    assert_eq!(hits.counts()[Cell::new(2, 2)], 0); // (-1.5, -1.5)
    assert_eq!(hits.counts()[Cell::new(2, 3)], 1); // (-1.5, -0.5)
}

#[test]
fn the_seed_disc_at_five_centimetres() {
    // Seed 000: 0.25 m discs on 0.05 m cells. Half a cell off the lattice (never on a
    // boundary), the disc holds the cells with (i + ½)² + j² < 25: 78 of them.
    let g = geom(0.05, 40, 40);
    let p = g.cell_center(Cell::new(20, 20)) + Vector2::new(0.025, 0.0);
    let mut hits = HitCounter::new(g, 0.25).unwrap();
    let expected = (-8i32..8)
        .flat_map(|i| (-8i32..8).map(move |j| (i, j)))
        .filter(|(i, j)| (f64::from(*i) - 0.5).powi(2) + f64::from(j * j) < 25.0)
        .count();
    assert_eq!(expected, 78);
    assert_eq!(hits.add(p), expected);
}

#[test]
fn positions_are_counted_once_each_and_accumulate() {
    let g = geom(0.1, 10, 10);
    let mut hits = HitCounter::new(g, 0.06).unwrap();
    let p = Point2::new(0.55, 0.55);
    let trajectory = Trajectory {
        id: 7,
        samples: vec![(0.0, p), (0.1, p), (0.2, Point2::new(0.15, 0.15))],
    };
    assert_eq!(hits.add_trajectory(&trajectory), 3);
    assert_eq!(hits.counts()[Cell::new(5, 5)], 2);
    assert_eq!(hits.counts()[Cell::new(1, 1)], 1);
    assert_eq!(hits.stats().counted, 3);
    assert_eq!(hits.stats().cell_hits, 3);
}

#[test]
fn non_finite_and_outside_positions_are_skipped_and_counted() {
    let g = geom(0.1, 10, 10);
    let mut hits = HitCounter::new(g, 0.25).unwrap();
    let bad = [
        Point2::new(f64::NAN, 0.5),
        Point2::new(0.5, f64::INFINITY),
        Point2::new(f64::NEG_INFINITY, f64::NAN),
    ];
    let far = [
        Point2::new(-3.0, 0.5),
        Point2::new(1e300, -1e300),
        Point2::new(0.5, 1.3),
    ];
    assert_eq!(hits.add_all(bad.into_iter().chain(far)), 0);
    assert_eq!(
        hits.stats(),
        HitStats {
            counted: 0,
            non_finite: 3,
            outside: 3,
            cell_hits: 0
        }
    );
    assert_eq!(hits.stats().positions(), 6);
    assert!(hits.counts().data().iter().all(|v| *v == 0));
    // Just outside the top edge, the disc still reaches the top row.
    assert!(hits.add(Point2::new(0.5, 1.1)) > 0);
    assert_eq!(hits.stats().counted, 1);
}

#[test]
fn bad_parameters_are_typed_errors() {
    let g = geom(0.1, 4, 4);
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            HitCounter::new(g, r),
            Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "person_radius",
                    ..
                }
            ))
        ));
    }
    let cases = [
        (
            DensityParams::default().with_person_radius(0.0),
            "person_radius",
        ),
        (
            DensityParams::default().with_visit_rule(VisitRule { min_fraction: 2.0 }),
            "visit_rule.min_fraction",
        ),
        (
            DensityParams::default().with_max_range(MaxRangeRule::Clear(f64::NAN)),
            "max_range",
        ),
        (DensityParams::default().with_min_visits(0), "min_visits"),
    ];
    for (params, rule) in cases {
        match params.check() {
            Err(AffordanceError::InvalidParameter(haunts_core::InvalidParameter {
                name, ..
            })) => assert_eq!(name, rule),
            other => panic!("{rule}: {other:?}"),
        }
    }
    assert!(DensityParams::default().check().is_ok());
    assert!(CumulativeDensity::new(g, 0).is_err());
    assert!(DailyDensity::new(Grid::filled(g, 0), Grid::filled(g, 0), 0).is_err());
}

/// One beam along row 1 of a 0.1 m grid: it crosses columns 0–4 fully and 0.02 m of column 5.
fn one_beam_day(
    poses: &[Pose2],
    positions: &[Point2<f64>],
) -> (DailyDensity, haunts_affordance::density::DayStats) {
    let g = geom(0.1, 10, 3);
    let scan = LaserScan::new(0.0, 0.0, 0.01, 0.0, 10.0, vec![0.52], vec![]).unwrap();
    let scans: Vec<(LaserScan, Pose2)> = poses.iter().map(|p| (scan.clone(), *p)).collect();
    let params = DensityParams::default().with_person_radius(0.06);
    DailyDensity::from_day(
        g,
        &scans,
        |(s, p)| (s, p),
        positions.iter().copied(),
        &params,
    )
    .unwrap()
}

#[test]
fn daily_density_is_hits_over_half_cell_visits() {
    let pose = Pose2::new(Vector2::new(0.0, 0.15), 0.0);
    let nan_pose = Pose2::new(Vector2::new(f64::NAN, 0.15), 0.0);
    let person = Point2::new(0.25, 0.15);
    let (day, stats) = one_beam_day(
        &[pose, pose, nan_pose],
        &[person, Point2::new(f64::NAN, 0.0)],
    );
    assert_eq!(stats.non_finite_poses, 1);
    assert_eq!(stats.scans.rays, 2);
    assert_eq!(stats.hits.counted, 1);
    assert_eq!(stats.hits.non_finite, 1);
    let at = |x: f64, y: f64| day.density_at(Point2::new(x, y));
    assert_eq!(day.visits()[Cell::new(4, 1)], 2);
    assert_eq!(day.visits()[Cell::new(5, 1)], 0); // 0.02 m < half of 0.1 m
    assert_eq!(at(0.25, 0.15), Some(0.5)); // 1 hit / 2 visits
    assert_eq!(at(0.35, 0.15), Some(0.0));
    assert_eq!(at(0.55, 0.15), None); // never visited
    assert_eq!(at(0.25, 0.05), None); // row 0 is never visited
    assert_eq!(at(-0.05, 0.15), None); // outside
    assert_eq!(day.known_cells(), 5);
    // A stricter minimum makes every cell unknown.
    let strict = DailyDensity::new(day.hits().clone(), day.visits().clone(), 3).unwrap();
    assert_eq!(strict.known_cells(), 0);
    assert_eq!(strict.density_at(Point2::new(0.25, 0.15)), None);
}

#[test]
fn zero_visits_everywhere_leaves_every_cell_unknown() {
    let (day, stats) = one_beam_day(&[], &[Point2::new(0.25, 0.15)]);
    assert_eq!(stats.scans.rays, 0);
    assert_eq!(day.known_cells(), 0);
    assert!(day.density_grid().data().iter().all(|v| v.is_nan()));
    assert_eq!(day.hits().data().iter().sum::<u32>(), 1);
}

#[test]
fn cumulative_density_is_the_ratio_of_sums_not_the_mean_of_ratios() {
    let g = geom(1.0, 2, 1);
    let day = |h: Vec<u32>, v: Vec<u32>| {
        DailyDensity::new(
            Grid::from_vec(g, h).unwrap(),
            Grid::from_vec(g, v).unwrap(),
            1,
        )
        .unwrap()
    };
    let mut all = CumulativeDensity::new(g, 1).unwrap();
    assert_eq!(all.density_at(Point2::new(0.5, 0.5)), None);
    all.add(&day(vec![1, 0], vec![1, 0])).unwrap();
    all.add(&day(vec![1, 2], vec![9, 4])).unwrap();
    // (1 + 1) / (1 + 9) = 0.2, whereas the mean of the daily ratios would be 0.556.
    assert_relative_eq!(all.density_at(Point2::new(0.5, 0.5)).unwrap(), 0.2);
    assert_relative_eq!(all.density_at(Point2::new(1.5, 0.5)).unwrap(), 0.5);
    assert_eq!(all.days(), 2);
    assert_eq!(all.hits().data(), &[2, 2]);
    assert_eq!(all.visits().data(), &[10, 4]);
}

#[test]
fn a_day_on_other_cells_is_refused_and_adds_nothing() {
    let g = geom(0.5, 4, 4);
    let mut all = CumulativeDensity::new(g, 1).unwrap();
    all.add(&DailyDensity::new(Grid::filled(g, 1), Grid::filled(g, 2), 1).unwrap())
        .unwrap();
    let before = all.clone();
    let shifted = GridGeometry::new(0.5, Point2::new(0.25, 0.0), 4, 4).unwrap();
    let other = DailyDensity::new(Grid::filled(shifted, 5), Grid::filled(shifted, 5), 1).unwrap();
    assert!(matches!(
        all.add(&other),
        Err(AffordanceError::GeometryMismatch {
            what: "day hits",
            ..
        })
    ));
    assert!(matches!(
        all.add_counts(&Grid::filled(g, 1), &Grid::filled(geom(0.5, 4, 5), 1)),
        Err(AffordanceError::GeometryMismatch {
            what: "day visits",
            ..
        })
    ));
    assert_eq!(all, before);
    // Hits and visits of one day must agree too.
    assert!(matches!(
        DailyDensity::new(Grid::filled(g, 0), Grid::filled(shifted, 0), 1),
        Err(AffordanceError::GeometryMismatch { what: "visits", .. })
    ));
    // Round-off in an origin (a map file's decimals) is not a different geometry.
    let rounded = GridGeometry::new(0.5, Point2::new(1e-9, 0.0), 4, 4).unwrap();
    all.add(&DailyDensity::new(Grid::filled(rounded, 1), Grid::filled(rounded, 1), 1).unwrap())
        .unwrap();
    assert_eq!(all.days(), 2);
}

/// Every implementation of `DensityMap` in this file: rasterising onto its own geometry gives
/// `density_grid` (or `density_at` at each centre), unknown is NaN, and rasterising onto a
/// finer, shifted geometry samples `density_at` at the new centres.
#[test]
fn every_density_map_rasterises_its_point_densities() {
    let g = geom(0.5, 6, 4);
    let hits = Grid::from_fn(g, |c| (c.col + 2 * c.row) as u32);
    let visits = Grid::from_fn(g, |c| if c.col == 0 { 0 } else { (c.row + 1) as u32 });
    let day = DailyDensity::new(hits.clone(), visits.clone(), 1).unwrap();
    let mut cumulative = CumulativeDensity::new(g, 2).unwrap();
    cumulative.add_counts(&hits, &visits).unwrap();
    cumulative.add(&day).unwrap();
    /// A map, and its directly computed density grid where it has one.
    type Case = (Box<dyn DensityMap>, Option<Grid<f64>>);
    let maps: Vec<Case> = vec![
        (Box::new(day.clone()), Some(day.density_grid())),
        (
            Box::new(cumulative.clone()),
            Some(cumulative.density_grid()),
        ),
        (Box::new(haunts_affordance::UniformDensity(Some(0.5))), None),
    ];
    let finer = GridGeometry::new(0.2, Point2::new(-0.3, -0.1), 20, 12).unwrap();
    for (i, (map, direct)) in maps.iter().enumerate() {
        let own = map.rasterise(&g);
        for (cell, v) in own.cells() {
            let expected = map.density_at(g.cell_center(cell));
            assert_eq!(v.is_nan(), expected.is_none(), "map {i} {cell:?}");
            if let Some(e) = expected {
                assert_eq!(*v, e);
            }
            if let Some(direct) = direct {
                let d = direct[cell];
                assert!(d == *v || (d.is_nan() && v.is_nan()), "map {i} {cell:?}");
            }
        }
        let fine = map.rasterise(&finer);
        for (cell, v) in fine.cells() {
            let expected = map.density_at(finer.cell_center(cell));
            assert!(expected == Some(*v) || (expected.is_none() && v.is_nan()));
        }
    }
    // Unknown where never visited (column 0) and outside.
    assert_eq!(day.density_at(Point2::new(0.25, 0.25)), None);
    assert_eq!(day.density_at(Point2::new(-0.25, 0.25)), None);
    assert_eq!(day.density_at(Point2::new(0.75, 0.25)), Some(1.0));
    // The cumulative one needs two visits: row 0 has 1 + 1.
    assert_eq!(cumulative.density_at(Point2::new(0.75, 0.25)), Some(1.0));
    assert_eq!(
        CumulativeDensity::new(g, 3)
            .unwrap()
            .density_at(Point2::new(0.75, 0.25)),
        None
    );
}

fn special() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -3.0..6.0f64,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(1e300),
        1 => Just(-1e300),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn hits_equal_the_brute_force_reference(
        res in 0.03..0.4f64,
        ox in -2.0..2.0f64,
        oy in -2.0..2.0f64,
        w in 1usize..25,
        h in 1usize..25,
        radius in 0.01..1.2f64,
        xs in prop::collection::vec((special(), special()), 0..30),
    ) {
        let g = GridGeometry::new(res, Point2::new(ox, oy), w, h).unwrap();
        let positions: Vec<Point2<f64>> = xs.iter().map(|(x, y)| Point2::new(*x, *y)).collect();
        let mut hits = HitCounter::new(g, radius).unwrap();
        let added = hits.add_all(positions.iter().copied());
        let reference = reference_hits(g, radius, &positions);
        prop_assert_eq!(hits.counts(), &reference);
        let stats = hits.stats();
        prop_assert_eq!(stats.positions(), positions.len());
        prop_assert_eq!(stats.cell_hits, added);
        prop_assert_eq!(added as u64, reference.data().iter().map(|v| u64::from(*v)).sum::<u64>());
        let non_finite = positions.iter().filter(|p| !(p.x.is_finite() && p.y.is_finite())).count();
        prop_assert_eq!(stats.non_finite, non_finite);
    }

    #[test]
    fn a_day_from_any_input_never_panics(
        ranges in prop::collection::vec(prop_oneof![
            4 => 0.0..8.0f64,
            1 => Just(f64::NAN),
            1 => Just(f64::INFINITY),
            1 => Just(f64::NEG_INFINITY),
        ], 1..40),
        poses in prop::collection::vec((special(), special(), special()), 0..5),
        xs in prop::collection::vec((special(), special()), 0..20),
        radius in 0.01..1.0f64,
    ) {
        let g = GridGeometry::new(0.1, Point2::new(-1.0, -1.0), 30, 20).unwrap();
        let scan = LaserScan::new(0.0, -1.0, 0.05, 0.02, 6.0, ranges, vec![]).unwrap();
        let scans: Vec<(LaserScan, Pose2)> = poses
            .iter()
            .map(|(x, y, a)| (scan.clone(), Pose2::new(Vector2::new(*x, *y), *a)))
            .collect();
        let positions: Vec<Point2<f64>> = xs.iter().map(|(x, y)| Point2::new(*x, *y)).collect();
        let params = DensityParams::default().with_person_radius(radius);
        let (day, stats) = DailyDensity::from_day(
            g, &scans, |(s, p)| (s, p), positions.iter().copied(), &params,
        ).unwrap();
        prop_assert_eq!(stats.hits.positions(), positions.len());
        prop_assert_eq!(stats.scans.cell_visits as u64,
            day.visits().data().iter().map(|v| u64::from(*v)).sum::<u64>());
        prop_assert!(stats.non_finite_poses <= scans.len());
        for v in day.density_grid().data() {
            prop_assert!(v.is_nan() || (v.is_finite() && *v >= 0.0));
        }
    }
}
