//! The leg detector on synthetic scans (legs as circles, walls as lines) and on arbitrary
//! ranges.
#![allow(clippy::unwrap_used)]

use approx::assert_abs_diff_eq;
use haunts_occupancy::LaserScan;
use haunts_tracking::detect::{Detection, Detector, FixedDetector, LegDetector, LegDetectorParams};
use nalgebra::{Point2, Vector2};
use proptest::prelude::*;

/// A 270° scan at 0.25° resolution (1081 beams), 30 m range.
fn empty_scan() -> LaserScan {
    let inc = 0.25f64.to_radians();
    LaserScan::new(
        1.0,
        -135f64.to_radians(),
        inc,
        0.02,
        30.0,
        vec![f64::INFINITY; 1081],
        vec![],
    )
    .unwrap()
}

fn beam(scan: &LaserScan, i: usize) -> Vector2<f64> {
    let a = scan.angle_min + i as f64 * scan.angle_increment;
    Vector2::new(a.cos(), a.sin())
}

/// Adds a circle (a leg) of `radius` at `centre`: each beam keeps its nearest hit.
fn add_circle(scan: &mut LaserScan, centre: Point2<f64>, radius: f64) {
    for i in 0..scan.len() {
        let d = beam(scan, i);
        let b = d.dot(&centre.coords);
        let disc = b * b - centre.coords.norm_squared() + radius * radius;
        if disc >= 0.0 && b - disc.sqrt() > 0.0 {
            scan.ranges[i] = scan.ranges[i].min(b - disc.sqrt());
        }
    }
}

/// Adds the segment from `a` to `b` (a wall).
fn add_segment(scan: &mut LaserScan, a: Point2<f64>, b: Point2<f64>) {
    for i in 0..scan.len() {
        let d = beam(scan, i);
        let e = b - a;
        // Solve t·d = a + s·e.
        let det = d.x * (-e.y) - d.y * (-e.x);
        if det.abs() < 1e-12 {
            continue;
        }
        let t = (a.x * (-e.y) - a.y * (-e.x)) / det;
        let s = (d.x * a.y - d.y * a.x) / det;
        if t > 0.0 && (0.0..=1.0).contains(&s) {
            scan.ranges[i] = scan.ranges[i].min(t);
        }
    }
}

fn detector() -> LegDetector {
    LegDetector::new(LegDetectorParams::default()).unwrap()
}

#[test]
fn two_leg_arcs_make_one_person_at_their_midpoint() {
    for (x, y) in [(1.5, 0.0), (3.0, -1.0), (2.0, 2.5)] {
        let mut scan = empty_scan();
        let centre = Point2::new(x, y);
        // Legs 0.3 m apart, across the line of sight.
        let across = Vector2::new(-y, x).normalize() * 0.15;
        add_circle(&mut scan, centre + across, 0.06);
        add_circle(&mut scan, centre - across, 0.06);
        let people = detector().detect(&scan).unwrap();
        assert_eq!(people.len(), 1, "at ({x}, {y}): {people:?}");
        let p = &people[0];
        assert_abs_diff_eq!(p.position, centre, epsilon = 0.03);
        assert_abs_diff_eq!(p.confidence, 1.0);
        assert_abs_diff_eq!(p.covariance[(0, 0)], 0.01, epsilon = 1e-12);
    }
}

#[test]
fn a_single_leg_is_a_weaker_candidate_or_nothing() {
    let mut scan = empty_scan();
    add_circle(&mut scan, Point2::new(2.0, 0.5), 0.06);
    let people = detector().detect(&scan).unwrap();
    assert_eq!(people.len(), 1);
    assert_abs_diff_eq!(people[0].confidence, 0.5);
    assert!(people[0].covariance[(0, 0)] > 0.01);
    let pairs_only =
        LegDetector::new(LegDetectorParams::default().with_single_legs(false)).unwrap();
    assert!(pairs_only.detect(&scan).unwrap().is_empty());
}

#[test]
fn legs_too_far_apart_are_not_paired() {
    let mut scan = empty_scan();
    add_circle(&mut scan, Point2::new(2.0, 0.6), 0.06);
    add_circle(&mut scan, Point2::new(2.0, -0.6), 0.06);
    let people = detector().detect(&scan).unwrap();
    assert_eq!(people.len(), 2);
    assert!(people.iter().all(|p| p.confidence < 1.0));
}

#[test]
fn legs_on_static_objects_are_removed_before_pairing() {
    // Two legs 0.3 m apart make one pair; with the leg at y < 0 on a static object (a table
    // leg beside a person's leg), only the person's leg is left, a single-leg candidate.
    let mut scan = empty_scan();
    add_circle(&mut scan, Point2::new(2.0, 0.15), 0.06);
    add_circle(&mut scan, Point2::new(2.0, -0.15), 0.06);
    let d = detector();
    let all = d.detect_where(&scan, &|_| true).unwrap();
    assert_eq!(all, d.detect(&scan).unwrap());
    assert_eq!(all.len(), 1);
    assert_abs_diff_eq!(all[0].confidence, 1.0);
    let kept = d.detect_where(&scan, &|p| p.y > 0.05).unwrap();
    assert_eq!(kept.len(), 1);
    assert_abs_diff_eq!(kept[0].confidence, 0.5);
    assert!(kept[0].position.y > 0.1);
    // The trait's default filters finished detections instead: the pair's midpoint.
    let fixed = FixedDetector {
        detections: all.clone(),
    };
    assert_eq!(fixed.detect_where(&scan, &|p| p.y > 0.05).unwrap().len(), 0);
    assert_eq!(fixed.detect_where(&scan, &|p| p.x > 1.0).unwrap(), all);
}

#[test]
fn walls_give_nothing() {
    // A long wall, a short straight piece of wall (a line, not a leg), and a corner.
    let mut scan = empty_scan();
    add_segment(&mut scan, Point2::new(3.0, -4.0), Point2::new(3.0, 4.0));
    assert!(detector().detect(&scan).unwrap().is_empty());
    // A 20 cm straight piece is wider than a leg and straight: dropped by default, kept
    // with the straight test off.
    let mut scan = empty_scan();
    add_segment(&mut scan, Point2::new(2.0, -0.1), Point2::new(2.0, 0.1));
    assert!(detector().legs(&scan).is_empty());
    let no_straight_test =
        LegDetector::new(LegDetectorParams::default().with_straight_eigenvalue_ratio(0.0)).unwrap();
    assert_eq!(no_straight_test.legs(&scan).len(), 1);
    // A 10 cm straight piece is as wide as a leg: by default there is no line test for it
    // (a far leg's few hits look as straight), so it is a leg; the line test drops it when
    // enabled.
    let mut scan = empty_scan();
    add_segment(&mut scan, Point2::new(2.0, -0.05), Point2::new(2.0, 0.05));
    assert_eq!(detector().legs(&scan).len(), 1);
    let line_test =
        LegDetector::new(LegDetectorParams::default().with_min_eigenvalue_ratio(0.01)).unwrap();
    assert!(line_test.legs(&scan).is_empty());
    let mut scan = empty_scan();
    add_segment(&mut scan, Point2::new(2.0, -2.0), Point2::new(2.0, 2.0));
    add_segment(&mut scan, Point2::new(2.0, 2.0), Point2::new(-2.0, 2.0));
    assert!(detector().detect(&scan).unwrap().is_empty());
}

#[test]
fn a_leg_in_front_of_a_wall_is_still_found() {
    let mut scan = empty_scan();
    add_segment(&mut scan, Point2::new(4.0, -4.0), Point2::new(4.0, 4.0));
    add_circle(&mut scan, Point2::new(2.0, 0.15), 0.06);
    add_circle(&mut scan, Point2::new(2.0, -0.15), 0.06);
    let people = detector().detect(&scan).unwrap();
    assert_eq!(people.len(), 1);
    assert_abs_diff_eq!(people[0].position, Point2::new(2.0, 0.0), epsilon = 0.03);
}

#[test]
fn empty_and_invalid_scans_give_nothing() {
    let d = detector();
    let none = LaserScan::new(0.0, 0.0, 0.01, 0.0, 10.0, vec![], vec![]).unwrap();
    assert!(d.detect(&none).unwrap().is_empty());
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.0, -1.0] {
        let mut scan = empty_scan();
        scan.ranges.iter_mut().for_each(|r| *r = bad);
        assert!(d.detect(&scan).unwrap().is_empty(), "{bad}");
    }
}

#[test]
fn detectors_are_usable_as_trait_objects() {
    let fixed = FixedDetector {
        detections: vec![Detection::isotropic(Point2::new(1.0, 2.0), 0.1)],
    };
    let detectors: Vec<Box<dyn Detector>> = vec![Box::new(fixed), Box::new(detector())];
    let scan = empty_scan();
    let counts: Vec<usize> = detectors
        .iter()
        .map(|d| d.detect(&scan).unwrap().len())
        .collect();
    assert_eq!(counts, vec![1, 0]);
}

fn range() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => 0.0..12.0f64,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(0.0),
        1 => -5.0..0.0f64,
        1 => 1e6..1e300f64,
    ]
}

proptest! {
    #[test]
    fn arbitrary_ranges_never_panic_and_give_finite_detections(
        ranges in prop::collection::vec(range(), 0..400),
        angle_min in -3.2..3.2f64,
        increment in prop_oneof![0.001..0.05f64, -0.05..-0.001f64],
    ) {
        let scan = LaserScan::new(0.0, angle_min, increment, 0.02, 11.0, ranges, vec![]).unwrap();
        let d = detector();
        let legs = d.legs(&scan);
        for leg in &legs {
            prop_assert!(leg.points >= 3);
            prop_assert!(leg.length < 0.3);
            prop_assert!(leg.centre.coords.iter().all(|v| v.is_finite()));
            prop_assert!(leg.centre.coords.norm() <= 10.0 + 0.05 + 1e-9);
        }
        let people = d.detect(&scan).unwrap();
        prop_assert!(people.len() <= legs.len());
        for (i, p) in people.iter().enumerate() {
            prop_assert!(p.checked_covariance(i).is_ok());
        }
    }
}
