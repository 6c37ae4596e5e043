//! Raycasting checked against plain references.

use super::*;
use approx::assert_relative_eq;
use proptest::prelude::*;
use std::collections::BTreeMap;

/// Brute-force reference: walk the segment in `n` tiny steps and add each step's length to
/// the cell holding its midpoint.
fn supersampled(g: &GridGeometry, a: Point2<f64>, b: Point2<f64>, n: usize) -> BTreeMap<Cell, f64> {
    let mut out = BTreeMap::new();
    let step = (b - a).norm() / n as f64;
    for i in 0..n {
        let t = (i as f64 + 0.5) / n as f64;
        if let Some(c) = g.world_to_cell(a + (b - a) * t) {
            *out.entry(c).or_insert(0.0) += step;
        }
    }
    out
}

fn geometry() -> impl Strategy<Value = GridGeometry> {
    (
        1usize..30,
        1usize..30,
        0.01f64..1.0,
        -5.0f64..5.0,
        -5.0f64..5.0,
    )
        .prop_map(|(w, h, r, x, y)| GridGeometry::new(r, Point2::new(x, y), w, h).unwrap())
}

/// The fast traversal's steps, its iterator and `add_ray` against the plain fixed-point
/// traversal of [`reference::steps`]: the same cells with positive length in the same
/// order, the same units and length bits, the same counts; the fast traversal's
/// zero-length corner cells lie in the grid. Lengths agree with the floating-point
/// traversal's ([`reference::float_steps`]) to 10⁻⁹ m per metre of segment. Returns how
/// many steps were compared.
fn assert_same_as_reference(g: &GridGeometry, a: Point2<f64>, b: Point2<f64>) -> usize {
    let (expected, metres_per_unit) = reference::steps(g, a, b);
    let mut steps = vec![];
    Traversal::new(g, a, b).for_each_index(|i, units| steps.push((i, units)));
    assert!(
        steps.iter().all(|&(i, _)| i < g.len()),
        "a step outside the grid: {a} → {b} on {g:?}"
    );
    let positive = |s: &[(usize, u64)]| s.iter().copied().filter(|s| s.1 > 0).collect::<Vec<_>>();
    let expected_steps: Vec<_> = expected
        .iter()
        .map(|&(c, r, units)| (r * g.width() + c, units))
        .collect();
    assert_eq!(
        positive(&steps),
        positive(&expected_steps),
        "steps of {a} → {b} on {g:?}"
    );
    let cells: Vec<_> = Traversal::new(g, a, b)
        .map(|(c, l)| (c, l.to_bits()))
        .collect();
    let expected_cells: Vec<_> = expected
        .iter()
        .filter(|s| s.2 > 0)
        .map(|&(c, r, units)| (Cell::new(c, r), (units as f64 * metres_per_unit).to_bits()))
        .collect();
    assert_eq!(cells, expected_cells, "cells of {a} → {b} on {g:?}");
    for min_fraction in [0.0, 0.5, 1.0] {
        let mut counter = VisitCounter::new(*g, VisitRule { min_fraction }).unwrap();
        let n = counter.add_ray(a, b);
        let mut counts = vec![0u32; g.len()];
        let min_units = units_for(min_fraction * g.resolution(), metres_per_unit);
        for &(c, r, units) in &expected {
            if units >= min_units {
                counts[r * g.width() + c] += 1;
            }
        }
        assert_eq!(
            counter.counts().data(),
            &counts[..],
            "counts of {a} → {b}, {min_fraction}"
        );
        assert_eq!(n, counts.iter().sum::<u32>() as usize);
    }
    // Against floating point: each cell's length (summed over its steps) to rounding.
    let tolerance = 1e-9 * (1.0 + (b - a).norm());
    let mut lengths: BTreeMap<Cell, (f64, f64)> = BTreeMap::new();
    for (c, l) in Traversal::new(g, a, b) {
        lengths.entry(c).or_default().0 += l;
    }
    for (c, r, l) in reference::float_steps(g, a, b) {
        lengths.entry(Cell::new(c, r)).or_default().1 += l;
    }
    for (cell, (fixed, float)) in &lengths {
        assert!(
            (fixed - float).abs() <= tolerance,
            "{cell:?}: {fixed} (fixed point) against {float} (floating point), {a} → {b} on {g:?}"
        );
    }
    expected.len()
}

/// A geometry whose lattice is exact in world coordinates half of the time (a power-of-two
/// resolution, an origin on the lattice), so that rays can run exactly through corners and
/// along edges; otherwise any resolution and origin.
fn lattice_geometry() -> impl Strategy<Value = GridGeometry> {
    (
        1usize..25,
        1usize..25,
        prop_oneof![
            Just(1.0),
            Just(0.5),
            Just(0.125),
            Just(0.05),
            Just(0.1),
            0.01f64..1.0
        ],
        -20i32..20,
        -20i32..20,
        prop::bool::ANY,
    )
        .prop_map(|(w, h, r, x, y, on_lattice)| {
            let origin = if on_lattice {
                Point2::new(f64::from(x) * r, f64::from(y) * r)
            } else {
                Point2::new(f64::from(x) * 0.173, f64::from(y) * 0.291)
            };
            GridGeometry::new(r, origin, w, h).unwrap()
        })
}

/// A point in grid units around the grid, snapped to a column line, a row line or a corner
/// (0: free, 1: x snapped, 2: y snapped, 3: both).
fn grid_point() -> impl Strategy<Value = (f64, f64, u8)> {
    (-3.0f64..28.0, -3.0f64..28.0, 0u8..4)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn the_fast_traversal_steps_as_the_plain_one(
        g in lattice_geometry(),
        (u, v, snap) in grid_point(),
        // 0: any second point; 1: along the row; 2: along the column; 3, 4: at 45°.
        (du, dv, kind) in (-30.0f64..30.0, -30.0f64..30.0, 0u8..5),
    ) {
        let snap_to = |x: f64, yes: bool| if yes { x.round() } else { x };
        let (u, v) = (snap_to(u, snap & 1 == 1), snap_to(v, snap & 2 == 2));
        let (du, dv) = match kind {
            0 => (snap_to(du, snap & 1 == 1), snap_to(dv, snap & 2 == 2)),
            1 => (du, 0.0),
            2 => (0.0, dv),
            3 => (du.round(), du.round()),
            _ => (du.round(), -du.round()),
        };
        let world = |u: f64, v: f64| g.origin() + nalgebra::Vector2::new(u, v) * g.resolution();
        assert_same_as_reference(&g, world(u, v), world(u + du, v + dv));
    }
}

#[test]
fn every_ray_between_lattice_points_steps_as_the_plain_one() {
    // Corners to corners, along edges and at every slope a 9 × 8 lattice holds, on a grid
    // whose corners are exact in world coordinates and on one where they are not.
    for g in [
        GridGeometry::new(0.5, Point2::new(-1.0, 2.0), 6, 5).unwrap(),
        GridGeometry::new(0.05, Point2::new(-0.35, 0.15), 6, 5).unwrap(),
    ] {
        let points: Vec<_> = (-1..8)
            .flat_map(|u| (-1..7).map(move |v| (u, v)))
            .map(|(u, v)| {
                g.origin() + nalgebra::Vector2::new(f64::from(u), f64::from(v)) * g.resolution()
            })
            .collect();
        let mut steps = 0;
        for &a in &points {
            for &b in &points {
                steps += assert_same_as_reference(&g, a, b);
            }
        }
        assert!(steps > 10_000, "{steps}");
    }
}

proptest! {
    #[test]
    fn traversal_equals_a_supersampled_reference(
        g in geometry(),
        a in (-0.3f64..1.3, -0.3f64..1.3),
        b in (-0.3f64..1.3, -0.3f64..1.3),
    ) {
        // Endpoints anywhere in and around the grid, in fractions of its extent.
        let ext = g.upper_corner() - g.origin();
        let p = |(u, v): (f64, f64)| g.origin() + nalgebra::Vector2::new(u * ext.x, v * ext.y);
        let (a, b) = (p(a), p(b));
        let n = 20_000;
        let step = (b - a).norm() / n as f64;
        let exact: Vec<(Cell, f64)> = Traversal::new(&g, a, b).collect();
        let reference = supersampled(&g, a, b, n);
        // Cells are distinct and 4- or 8-connected in order.
        for w in exact.windows(2) {
            let (c0, c1) = (w[0].0, w[1].0);
            prop_assert!(c0 != c1);
            prop_assert!(c0.col.abs_diff(c1.col) <= 1 && c0.row.abs_diff(c1.row) <= 1);
        }
        let exact_map: BTreeMap<Cell, f64> = exact.iter().copied().collect();
        prop_assert_eq!(exact_map.len(), exact.len());
        for (cell, len) in &reference {
            let e = exact_map.get(cell).copied().unwrap_or(0.0);
            prop_assert!((e - len).abs() <= 2.0 * step + 1e-9, "{:?}: exact {} vs reference {}", cell, e, len);
        }
        for (cell, len) in &exact_map {
            if *len > 2.0 * step {
                prop_assert!(reference.contains_key(cell), "{:?} ({}) missing from the reference", cell, len);
            }
        }
        let total_exact: f64 = exact.iter().map(|c| c.1).sum();
        let total_ref: f64 = reference.values().sum();
        prop_assert!((total_exact - total_ref).abs() <= 2.0 * step + 1e-9);
    }

    #[test]
    fn bresenham_is_8_connected_and_ends_at_both_points(
        a in (-40i64..40, -40i64..40),
        b in (-40i64..40, -40i64..40),
    ) {
        let line: Vec<_> = bresenham(a, b).collect();
        prop_assert_eq!(line[0], a);
        prop_assert_eq!(*line.last().unwrap(), b);
        prop_assert_eq!(line.len() as i64, (b.0 - a.0).abs().max((b.1 - a.1).abs()) + 1);
        for w in line.windows(2) {
            prop_assert!((w[0].0 - w[1].0).abs() <= 1 && (w[0].1 - w[1].1).abs() <= 1);
        }
    }
}

#[test]
fn axis_aligned_and_diagonal_rays() {
    let g = GridGeometry::new(0.5, Point2::new(-1.0, -1.0), 4, 4).unwrap();
    // Leftwards along a row, starting on a cell boundary.
    let cells: Vec<_> =
        Traversal::new(&g, Point2::new(0.0, 0.25), Point2::new(-1.0, 0.25)).collect();
    assert_eq!(
        cells.iter().map(|c| c.0).collect::<Vec<_>>(),
        [Cell::new(1, 2), Cell::new(0, 2)]
    );
    // Exactly through corners: only the diagonal cells, each with √2 · 0.5.
    let cells: Vec<_> =
        Traversal::new(&g, Point2::new(-1.0, -1.0), Point2::new(1.0, 1.0)).collect();
    assert_eq!(cells.len(), 4);
    for (i, (c, len)) in cells.iter().enumerate() {
        assert_eq!(*c, Cell::new(i, i));
        assert_relative_eq!(*len, 0.5 * 2f64.sqrt(), epsilon = 1e-12);
    }
    // Entirely outside, degenerate and non-finite segments.
    assert_eq!(
        Traversal::new(&g, Point2::new(5.0, 5.0), Point2::new(6.0, 5.0)).count(),
        0
    );
    assert_eq!(
        Traversal::new(&g, Point2::new(0.1, 0.1), Point2::new(0.1, 0.1)).count(),
        0
    );
    assert_eq!(
        Traversal::new(&g, Point2::new(f64::NAN, 0.1), Point2::new(0.1, 0.1)).count(),
        0
    );
    // From far outside: clipped, same cells as from the border.
    let far: Vec<_> = Traversal::new(&g, Point2::new(-1e9, 0.25), Point2::new(0.9, 0.25))
        .map(|c| c.0)
        .collect();
    assert_eq!(far, (0..4).map(|c| Cell::new(c, 2)).collect::<Vec<_>>());
}

#[test]
fn visits_follow_the_half_cell_rule() {
    let g = GridGeometry::new(0.05, Point2::origin(), 20, 20).unwrap();
    let mut v = VisitCounter::new(g, VisitRule::default()).unwrap();
    // A ray ending 0.024 m into cell 3: cells 0..=2 visited, cell 3 not (0.024 < 0.025).
    assert_eq!(
        v.add_ray(Point2::new(0.0, 0.01), Point2::new(0.174, 0.01)),
        3
    );
    assert_eq!(v.counts()[Cell::new(3, 0)], 0);
    v.add_ray(Point2::new(0.0, 0.01), Point2::new(0.176, 0.01));
    assert_eq!(v.counts()[Cell::new(3, 0)], 1);
    assert_eq!(v.counts()[Cell::new(0, 0)], 2);
    assert!(VisitRule { min_fraction: -1.0 }.check().is_err());
    assert!(
        VisitRule {
            min_fraction: f64::NAN
        }
        .check()
        .is_err()
    );

    let scan = LaserScan::new(0.0, 0.0, 0.1, 0.0, 5.0, vec![0.5, f64::NAN, 10.0], vec![]).unwrap();
    let pose = Pose2::new(nalgebra::Vector2::new(0.3, 0.3), 0.0);
    let stats = v.add_scan(&scan, &pose, MaxRangeRule::Ignore).unwrap();
    assert_eq!((stats.rays, stats.skipped_beams), (1, 2));
    let bad = Pose2::new(nalgebra::Vector2::new(f64::NAN, 0.3), 0.0);
    assert!(matches!(
        v.add_scan(&scan, &bad, MaxRangeRule::Ignore),
        Err(OccupancyError::NonFinitePose { .. })
    ));
}

#[test]
fn bresenham_cells_clip_to_the_grid() {
    let g = GridGeometry::new(1.0, Point2::origin(), 5, 5).unwrap();
    let cells: Vec<_> =
        bresenham_cells(&g, Point2::new(-1e12, 2.5), Point2::new(2.5, 2.5)).collect();
    assert_eq!(cells, (0..3).map(|c| Cell::new(c, 2)).collect::<Vec<_>>());
    assert_eq!(
        bresenham_cells(&g, Point2::new(-3.0, -3.0), Point2::new(-1.0, -2.0)).count(),
        0
    );
}

#[test]
fn many_scans_in_parallel_count_as_one_by_one() {
    let g = GridGeometry::new(0.05, Point2::new(-5.0, -5.0), 200, 200).unwrap();
    let scans: Vec<(LaserScan, Pose2)> = (0..40)
        .map(|i| {
            let ranges = (0..90)
                .map(|b| {
                    if b % 17 == 0 {
                        f64::NAN
                    } else {
                        1.0 + 0.05 * f64::from((b * 7 + i) % 60)
                    }
                })
                .collect();
            let scan = LaserScan::new(f64::from(i), -1.5, 0.035, 0.1, 4.0, ranges, vec![]).unwrap();
            (
                scan,
                Pose2::new(
                    nalgebra::Vector2::new(0.1 * f64::from(i % 7), -0.2),
                    0.3 * f64::from(i),
                ),
            )
        })
        .collect();
    let mut one_by_one = VisitCounter::new(g, VisitRule::default()).unwrap();
    let mut expected = ScanStats::default();
    for (s, p) in &scans {
        let st = one_by_one.add_scan(s, p, MaxRangeRule::default()).unwrap();
        expected.rays += st.rays;
        expected.skipped_beams += st.skipped_beams;
        expected.cell_visits += st.cell_visits;
    }
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut batch = VisitCounter::new(g, VisitRule::default()).unwrap();
        let stats = pool
            .install(|| batch.add_scans(&scans, |(s, p)| (s, p), MaxRangeRule::default()))
            .unwrap();
        assert_eq!(stats, expected);
        assert_eq!(batch.counts(), one_by_one.counts(), "{threads} threads");
        // On top of counts already there (the calling thread counts into the counter itself).
        pool.install(|| batch.add_scans(&scans, |(s, p)| (s, p), MaxRangeRule::default()))
            .unwrap();
        let doubled: Vec<u32> = one_by_one.counts().data().iter().map(|c| 2 * c).collect();
        assert_eq!(
            batch.counts().data(),
            &doubled[..],
            "{threads} threads, twice"
        );
    }
    let mut bad = scans.clone();
    bad[3].1 = Pose2::new(nalgebra::Vector2::new(f64::NAN, 0.0), 0.0);
    let mut untouched = VisitCounter::new(g, VisitRule::default()).unwrap();
    assert!(
        untouched
            .add_scans(&bad, |(s, p)| (s, p), MaxRangeRule::default())
            .is_err()
    );
    assert!(untouched.counts().data().iter().all(|&c| c == 0));
}

/// A start whose first column crossing rounds to a hair before the clipped segment's entry
/// (what floating point can give a segment entering the grid through a row edge right at a
/// column line): the traversal never steps back, every step's units are at most the
/// segment's, and the cells are the entry cell and the one after the crossing.
#[test]
fn a_first_crossing_rounded_before_the_entry_steps_no_negative_length() {
    let g = GridGeometry::new(1.0, Point2::origin(), 4, 4).unwrap();
    let t0 = 0.25;
    let start = Start {
        t0,
        t1: 1.0,
        col: 1,
        row: 0,
        // Crossing x = 2 at t just below t0, then every half of the parameter.
        col_axis: (1, t0 - 1e-16, 0.5),
        row_axis: (0, f64::INFINITY, f64::INFINITY),
        metres_per_t: 2.0,
    };
    let mut steps = vec![];
    Traversal::from_start(&g, &start).for_each_index(|i, units| steps.push((i, units)));
    let total = fixed(1.0, 0) - fixed(t0, 0);
    assert!(steps.iter().all(|&(_, units)| units <= total), "{steps:?}");
    assert_eq!(steps.iter().map(|s| s.1).sum::<u64>(), total, "{steps:?}");
    let cells: Vec<usize> = steps.iter().filter(|s| s.1 > 0).map(|s| s.0).collect();
    assert_eq!(cells, [2, 3], "{steps:?}");
}
