//! `tracker::eval` on a made-up sequence whose answer is known: what it counts of the people
//! a tracker follows without reporting them.
#![allow(clippy::unwrap_used, clippy::panic)]

use haunts_occupancy::LaserScan;
use haunts_tracking::detect::{Detection, FixedDetector};
use haunts_tracking::eval::sequence::{EvalParams, Sequence, TrackingFrame, evaluate_sequence};
use haunts_tracking::track::kalman::{KalmanParams, KalmanTracker};
use haunts_tracking::{OdomPose, PersonPosition, StampedScan, StaticTransform, TrackingError};
use nalgebra::{Isometry2, Point2};

/// Eight scans at 7.5 Hz in the laser frame (no odometry), with person 1 annotated at
/// (2, 0) after scans 2..=6 and person 2 at (0, 5) after scans 4..=6.
fn sequence() -> Sequence {
    let scans: Vec<StampedScan> = (0..8)
        .map(|k| {
            let t = 100.0 + k as f64 / 7.5;
            StampedScan {
                bag_time: t,
                frame: "laser".into(),
                scan: LaserScan::new(t, -1.0, 0.5, 0.05, 20.0, vec![3.0; 5], vec![]).unwrap(),
                line: k + 2,
            }
        })
        .collect();
    let mut ground_truth = Vec::new();
    for (k, scan) in scans.iter().enumerate().take(7).skip(2) {
        let t = scan.bag_time + 0.05;
        ground_truth.push(PersonPosition {
            bag_time: t,
            id: 1,
            position: Point2::new(2.0, 0.0),
            line: 0,
        });
        if k >= 4 {
            ground_truth.push(PersonPosition {
                bag_time: t,
                id: 2,
                position: Point2::new(0.0, 5.0),
                line: 0,
            });
        }
    }
    Sequence {
        scans,
        ground_truth,
        ..Sequence::default()
    }
}

#[test]
fn people_followed_only_by_tentative_tracks_are_counted_and_recorded() {
    // A single leg on person 1 and another on unannotated clutter, in every scan: single
    // legs that never move are never confirmed, so the tracker follows both tentatively.
    let leg = |x: f64, y: f64| Detection {
        confidence: 0.5,
        ..Detection::isotropic(Point2::new(x, y), 0.2)
    };
    let detector = FixedDetector {
        detections: vec![leg(2.05, 0.0), leg(-2.0, 1.0)],
    };
    let sequence = sequence();
    let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
    let params = EvalParams::default().with_record_tentative(true);
    let report = evaluate_sequence(&sequence, &detector, &mut kf, &params).unwrap();
    let s = &report.scores;
    assert_eq!((report.frames, s.ground_truth, s.misses), (5, 8, 8));
    assert_eq!(s.false_positives, 0);
    // Person 1 at each of the five scored scans; person 2 is followed by nothing.
    assert_eq!(report.followed_tentatively, 5);
    // Two tentative tracks at each scored scan, one of them on person 1.
    assert_eq!(report.tentative.len(), 10);
    let mut on_person: Vec<_> = report.tentative.iter().filter(|u| u.person).collect();
    assert_eq!(on_person.len(), 5);
    on_person.sort_by_key(|u| u.scan);
    for (u, k) in on_person.iter().zip(2..=6) {
        assert_eq!(u.scan, k);
        assert_eq!(u.hits, k + 1);
        assert!((u.age - k as f64 / 7.5).abs() < 1e-9, "{u:?}");
        assert!((u.position - Point2::new(2.05, 0.0)).norm() < 1e-6, "{u:?}");
        assert!(u.travel < 1e-6 && u.speed < 1e-6, "{u:?}");
        assert!(u.position_std > 0.0 && u.position_std < 0.2, "{u:?}");
    }
    assert!(
        report
            .tentative
            .iter()
            .filter(|u| !u.person)
            .all(|u| (u.position - Point2::new(-2.0, 1.0)).norm() < 1e-6)
    );
    assert!(on_person.iter().all(|u| u.id == on_person[0].id));

    // Not recorded unless asked; the count is kept either way. Outside a bearing window
    // that holds only person 2, nobody is followed.
    let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
    let params = EvalParams::default().with_bearing_window(Some((1.0, 2.0)));
    let report = evaluate_sequence(&sequence, &detector, &mut kf, &params).unwrap();
    assert!(report.tentative.is_empty());
    assert_eq!(
        (report.scores.ground_truth, report.followed_tentatively),
        (3, 0)
    );
}

#[test]
fn the_robot_frame_is_a_parameter_read_at_run_time() {
    // Odometry of a robot standing still, a laser mounted 0.5 m ahead of `base_footprint`.
    let mut sequence = sequence();
    sequence.odometry = (0..10)
        .map(|k| OdomPose {
            bag_time: 99.9 + k as f64 * 0.2,
            stamp: 99.9 + k as f64 * 0.2,
            pose: Isometry2::identity(),
            line: k + 2,
        })
        .collect();
    sequence.static_transforms = vec![StaticTransform {
        parent: "base_footprint".into(),
        child: "laser".into(),
        transform: Isometry2::translation(0.5, 0.0),
        line: 2,
    }];
    let detector = FixedDetector {
        detections: vec![Detection::isotropic(Point2::new(2.0, 0.0), 0.1)],
    };
    let run = |params: &EvalParams| {
        let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
        evaluate_sequence(&sequence, &detector, &mut kf, params)
    };
    // The default `base_link` is not in this robot's tree: a typed error naming both ends.
    match run(&EvalParams::default()) {
        Err(TrackingError::NoTransformChain { from, to }) => {
            assert_eq!((from.as_str(), to.as_str()), ("laser", "base_link"));
        }
        other => panic!("expected NoTransformChain, got {other:?}"),
    }
    // Named at run time (from a configuration file, say), the chain is found and the person
    // at (2, 0) in the laser frame is tracked there.
    let frame: String = "base_footprint".to_owned();
    let report = run(&EvalParams::default().with_base_frame(frame)).unwrap();
    assert_eq!(report.tracking_frame, TrackingFrame::Odometry);
    assert_eq!(report.scores.ground_truth, 8);
    assert!(report.scores.matches >= 1, "{:?}", report.scores);
}

#[test]
fn nothing_to_score_is_an_error_not_a_perfect_mota() {
    let detector = FixedDetector {
        detections: vec![Detection::isotropic(Point2::new(2.0, 0.0), 0.2)],
    };
    let params = EvalParams::default();
    let run = |sequence: &Sequence| {
        let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
        evaluate_sequence(sequence, &detector, &mut kf, &params)
    };
    // No ground truth: every track would be judged against nothing (MOTA 1 before).
    let no_truth = Sequence {
        ground_truth: Vec::new(),
        ..sequence()
    };
    let message = run(&no_truth).unwrap_err().to_string();
    assert!(
        message.contains("nothing to score") && message.contains("(8 scans read, 0 annotations,"),
        "{message}"
    );
    assert!(matches!(
        run(&no_truth),
        Err(TrackingError::NothingScored {
            scans: 8,
            annotations: 0,
            ..
        })
    ));
    // No scans (an empty or garbage scans.txt): the annotations belong to no scan.
    let no_scans = Sequence {
        scans: Vec::new(),
        skipped_lines: 8,
        ..sequence()
    };
    match run(&no_scans) {
        Err(TrackingError::NothingScored {
            scans,
            frames,
            annotations,
            unassigned,
        }) => assert_eq!((scans, frames, annotations, unassigned), (0, 0, 8, 8)),
        other => panic!("expected NothingScored, got {other:?}"),
    }
    // The same sequence with its people scores.
    assert_eq!(run(&sequence()).unwrap().scores.ground_truth, 8);
}
