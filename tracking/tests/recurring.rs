//! Recurring objects: legs that come back at every patrol are furniture; legs seen at one
//! patrol only are people, however long they stood.

use haunts_occupancy::{LaserScan, Pose2};
use haunts_tracking::TrackingError;
use haunts_tracking::detect::recurring::{RecurringObjects, RecurringParams};
use haunts_tracking::detect::{LegDetector, LegDetectorParams};
use nalgebra::{Point2, Vector2};

/// 181 beams over ±0.9 rad against a far wall at 8 m, with a short bump (a leg-like
/// cluster) at `(first beam, range)` for each object present.
fn scan(stamp: f64, objects: &[(usize, f64)]) -> LaserScan {
    let mut ranges = vec![8.0; 181];
    for &(first, range) in objects {
        for r in &mut ranges[first..first + 5] {
            *r = range;
        }
    }
    LaserScan::new(stamp, -0.9, 0.01, 0.05, 20.0, ranges, vec![]).expect("valid scan")
}

const POST: (usize, f64) = (88, 2.0);
const PERSON: (usize, f64) = (40, 3.0);

/// Sessions starting an hour apart, ten scans at 10 Hz each; `person_in` says in which
/// sessions the person stands there too (the post always does).
fn day(sessions: usize, person_in: &[usize]) -> Vec<LaserScan> {
    (0..sessions)
        .flat_map(|s| {
            let person = person_in.contains(&s);
            (0..10).map(move |k| {
                let stamp = s as f64 * 3600.0 + k as f64 * 0.1;
                if person {
                    scan(stamp, &[POST, PERSON])
                } else {
                    scan(stamp, &[POST])
                }
            })
        })
        .collect()
}

fn build(scans: &[LaserScan], params: RecurringParams) -> RecurringObjects {
    let detector = LegDetector::new(LegDetectorParams::default()).expect("valid detector");
    let poses = vec![Pose2::identity(); scans.len()];
    RecurringObjects::build(&detector, scans.iter().zip(&poses), params).expect("builds")
}

/// Where the detector puts the leg of an object in the scans above (world = sensor frame).
fn leg_of(object: (usize, f64)) -> Point2<f64> {
    let detector = LegDetector::new(LegDetectorParams::default()).expect("valid detector");
    let legs = detector.legs(&scan(0.0, &[object]));
    assert_eq!(legs.len(), 1);
    legs[0].centre
}

#[test]
fn what_recurs_in_most_sessions_is_marked_and_a_long_stay_is_not() {
    let (post, person) = (leg_of(POST), leg_of(PERSON));
    // Five patrols; the person stood through the whole of two of them.
    let recurring = build(&day(5, &[1, 3]), RecurringParams::default());
    assert_eq!(recurring.sessions(), 5);
    assert!(recurring.contains(&post));
    assert!(!recurring.contains(&person));
    // Nothing else, and nothing 20 cm away.
    assert!(!recurring.contains(&(post + Vector2::new(0.2, 0.0))));
    assert!(recurring.len() <= 2, "{} cells", recurring.len());
    assert!(
        recurring
            .centres()
            .all(|c| (c - post).norm() <= 0.1 * std::f64::consts::SQRT_2)
    );
    // Present in four of five patrols: 80 %, marked by default; with 100 % required, not.
    let recurring = build(&day(5, &[0, 1, 2, 3]), RecurringParams::default());
    assert!(recurring.contains(&person));
    let strict = {
        let mut p = RecurringParams::default();
        p.min_session_fraction = 1.0;
        p
    };
    assert!(!build(&day(5, &[0, 1, 2, 3]), strict).contains(&person));
}

#[test]
fn one_session_or_too_few_scans_mark_nothing() {
    // One patrol cannot tell a long stay from furniture.
    let one = build(&day(1, &[0]), RecurringParams::default());
    assert_eq!(one.sessions(), 1);
    assert!(one.is_empty());
    // A session counts only with `min_scans` scans holding the candidate.
    let demanding = {
        let mut p = RecurringParams::default();
        p.min_scans = 11;
        p
    };
    assert!(build(&day(3, &[]), demanding).is_empty());
    // No scans at all.
    let none = build(&[], RecurringParams::default());
    assert_eq!(none.sessions(), 0);
    assert!(none.is_empty());
}

#[test]
fn scans_with_a_non_finite_pose_are_skipped() {
    let scans = day(2, &[]);
    let detector = LegDetector::new(LegDetectorParams::default()).expect("valid detector");
    // The second session's poses are NaN: only one session saw the post.
    let poses: Vec<Pose2> = (0..scans.len())
        .map(|i| {
            if i < 10 {
                Pose2::identity()
            } else {
                Pose2::new(Vector2::new(f64::NAN, 0.0), 0.0)
            }
        })
        .collect();
    let recurring = RecurringObjects::build(
        &detector,
        scans.iter().zip(&poses),
        RecurringParams::default(),
    )
    .expect("builds");
    assert_eq!(recurring.sessions(), 2);
    assert!(recurring.is_empty());
}

#[test]
fn bad_input_is_a_typed_error() {
    let detector = LegDetector::new(LegDetectorParams::default()).expect("valid detector");
    let scans = [scan(10.0, &[POST]), scan(5.0, &[POST])];
    let poses = [Pose2::identity(); 2];
    assert!(matches!(
        RecurringObjects::build(
            &detector,
            scans.iter().zip(&poses),
            RecurringParams::default()
        ),
        Err(TrackingError::TimeWentBackwards { .. })
    ));
    for (params, name) in [
        (
            {
                let mut p = RecurringParams::default();
                p.session_gap = f64::NAN;
                p
            },
            "session_gap",
        ),
        (
            {
                let mut p = RecurringParams::default();
                p.resolution = 0.0;
                p
            },
            "resolution",
        ),
        (
            {
                let mut p = RecurringParams::default();
                p.min_scans = 0;
                p
            },
            "min_scans",
        ),
        (
            {
                let mut p = RecurringParams::default();
                p.min_sessions = 1;
                p
            },
            "min_sessions",
        ),
        (
            {
                let mut p = RecurringParams::default();
                p.min_session_fraction = 1.5;
                p
            },
            "min_session_fraction",
        ),
        (
            {
                let mut p = RecurringParams::default();
                p.query_radius = -0.1;
                p
            },
            "query_radius",
        ),
    ] {
        match params.check() {
            Err(TrackingError::InvalidParameter(haunts_core::InvalidParameter {
                name: got,
                ..
            })) => assert_eq!(got, name),
            other => panic!("{name}: {other:?}"),
        }
    }
}

#[test]
fn the_online_tracker_drops_legs_on_recurring_objects() {
    use haunts_tracking::detect::Detector;
    use haunts_tracking::track::kalman::{KalmanParams, KalmanTracker};
    use haunts_tracking::track::online::OnlineTracker;

    let detector = LegDetector::new(LegDetectorParams::default()).expect("valid detector");
    // The post recurs over five patrols; the person came at one.
    let recurring = build(&day(5, &[2]), RecurringParams::default());
    let scan = scan(5.0 * 3600.0, &[POST, PERSON]);
    assert_eq!(detector.detect(&scan).expect("detects").len(), 2);
    let (post, person) = (leg_of(POST), leg_of(PERSON));
    // Seen from a robot 1 m further along x: the cells are in the world frame.
    let sensor = Pose2::new(Vector2::new(1.0, 0.0), 0.0);
    let shifted = RecurringObjects::build(
        &detector,
        day(5, &[]).iter().zip(&vec![sensor; 50]),
        RecurringParams::default(),
    )
    .expect("builds");
    for (recurring, pose) in [(&recurring, Pose2::identity()), (&shifted, sensor)] {
        let mut tracker = KalmanTracker::new(KalmanParams::default()).expect("valid tracker");
        let mut online = OnlineTracker::new(&detector, &mut tracker, None)
            .expect("valid")
            .with_recurring(recurring.clone());
        let step = online.step(&scan, &pose).expect("steps");
        // Only the person's single leg is left (the mask is applied in the world frame).
        assert_eq!(step.detections, 1);
        assert!(recurring.contains(&(pose * post)));
        assert!(!recurring.contains(&(pose * person)));
    }
}

#[test]
fn a_far_point_is_answered_without_overflow() {
    // A day patrolled from 1e300 m away (a finite pose, as a corrupted or far-off odometry
    // file may give): the cells saturate at `i64::MAX`, and asking about a point there (or
    // anywhere, with a radius of many cells) must answer, not overflow the cell arithmetic.
    let scans = day(2, &[]);
    let detector = LegDetector::new(LegDetectorParams::default()).expect("valid detector");
    let far = Pose2::new(Vector2::new(1e300, -1e300), 0.0);
    let poses = vec![far; scans.len()];
    let recurring = RecurringObjects::build(
        &detector,
        scans.iter().zip(&poses),
        RecurringParams::default(),
    )
    .expect("builds");
    assert!(!recurring.is_empty());
    assert!(!recurring.contains(&(far * leg_of(POST))));
    assert!(!recurring.contains(&Point2::new(f64::MAX, f64::MIN)));
    let near = build(&day(2, &[]), RecurringParams::default());
    for p in [
        Point2::new(1e300, 0.0),
        Point2::new(-1e300, 1e300),
        Point2::new(f64::INFINITY, 0.0),
        Point2::new(f64::NAN, 0.0),
        Point2::new(leg_of(POST).x, f64::NAN),
    ] {
        assert!(!near.contains(&p), "{p}");
    }
    assert!(near.contains(&leg_of(POST)));
}
