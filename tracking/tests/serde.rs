//! With the `serde` feature, parameters, detections, tracks, trajectories, reader records,
//! scores and models round-trip through JSON, and deserialising a model checks the same rules
//! as its constructor.
#![cfg(feature = "serde")]
#![allow(clippy::unwrap_used)]

use std::fmt::Debug;

use haunts_occupancy::mapping::MapperParams;
use haunts_occupancy::{LaserScan, Pose2};
use haunts_tracking::detect::recurring::{RecurringObjects, RecurringParams};
use haunts_tracking::detect::static_map::StaticMapParams;
use haunts_tracking::detect::{Detection, FixedDetector, Leg, LegDetector, LegDetectorParams};
use haunts_tracking::eval::mot::{ClearMot, ClearMotParams, Convention, Frame, ScanTruth};
use haunts_tracking::eval::sequence::{
    EvalFrames, EvalParams, EvalReport, Scoring, Sequence, TentativeSample, TrackingFrame,
    evaluate_sequence,
};
use haunts_tracking::io::frames::{OdomClock, PoseHistory};
use haunts_tracking::track::CombinationParams;
use haunts_tracking::track::Track;
use haunts_tracking::track::dummy::{
    DummyFilterParams, DummyReport, SpeedMeasure, TrajectoryStats, filter_dummies,
};
use haunts_tracking::track::kalman::{KalmanParams, KalmanTracker};
use haunts_tracking::track::particle::ParticleParams;
use haunts_tracking::{
    DelimitedOptions, Delimiter, EthOptions, OdomPose, PersonPosition, StampedScan,
    StaticTransform, TrackingError, Trajectory,
};
use nalgebra::{Isometry2, Matrix2, Point2, Vector2};
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::json;

use haunts_test_support::json;
use json::{corrupt, rejection, round_trip};

/// As [`round_trip`], for a value that must differ from its type's default (so that a field
/// lost on the way and filled in with its default would be noticed).
fn round_trip_non_default<T>(value: &T)
where
    T: Serialize + DeserializeOwned + PartialEq + Debug + Default,
{
    assert_ne!(value, &T::default());
    round_trip(value);
}

/// Every field differs from its default and the parameters pass their check.
fn leg_detector_params() -> LegDetectorParams {
    LegDetectorParams::default()
        .with_cluster_gap(0.12)
        .with_min_points(4)
        .with_max_cluster_length(0.35)
        .with_min_eigenvalue_ratio(0.01)
        .with_straight_length(0.15)
        .with_straight_eigenvalue_ratio(0.05)
        .with_min_background_gap(0.02)
        .with_max_leg_separation(0.8)
        .with_leg_radius(0.06)
        .with_max_range(12.0)
        .with_person_std(0.15)
        .with_single_legs(false)
        .with_single_leg_std(0.25)
        .with_single_leg_confidence(0.4)
}

fn combination_params() -> CombinationParams {
    CombinationParams::default()
        .with_horizon(0.6)
        .with_min_factor(0.1)
}

fn recurring_params() -> RecurringParams {
    {
        let mut p = RecurringParams::default();
        p.session_gap = 300.0;
        p.resolution = 0.05;
        p.min_scans = 3;
        p.min_sessions = 3;
        p.min_session_fraction = 0.5;
        p.query_radius = 0.05;
        p
    }
}

fn scan() -> LaserScan {
    LaserScan::new(10.125, -1.5, 0.25, 0.05, 20.0, vec![1.5, 2.25, 3.0], vec![]).unwrap()
}

fn person(bag_time: f64, id: u64, x: f64, y: f64) -> PersonPosition {
    PersonPosition {
        bag_time,
        id,
        position: Point2::new(x, y),
        line: 7,
    }
}

fn frame() -> Frame {
    Frame::new(
        2.5,
        vec![(1, Point2::new(1.5, -0.25)), (4, Point2::new(3.0, 2.0))],
    )
}

#[test]
fn parameters_round_trip_through_json() {
    round_trip_non_default(&leg_detector_params());
    round_trip_non_default(&combination_params());
    round_trip_non_default(
        &KalmanParams::default()
            .with_acceleration_std(2.0)
            .with_initial_speed_std(0.8)
            .with_gate(5.99)
            .with_max_gate_distance(1.5)
            .with_confirm_hits(4)
            .with_tentative_missing_time(0.4)
            .with_confirm_confidence(0.9)
            .with_confirm_strong_hits(1)
            .with_min_travel(1.0)
            .with_confirm_mean_confidence(Some(0.625))
            .with_max_missing_time(2.0)
            .with_max_report_coast(0.25)
            .with_min_birth_confidence(1.0)
            .with_max_time_gap(3.0)
            .with_max_history(Some(50)),
    );
    round_trip_non_default(
        &ParticleParams::default()
            .with_particles(200)
            .with_seed(42)
            .with_speed_noise(0.25)
            .with_heading_noise(0.75)
            .with_max_speed(2.0)
            .with_initial_speed_std(0.4)
            .with_combination(combination_params())
            .with_birth_threshold(0.75)
            .with_min_track_distance(0.5)
            .with_merge_distance(0.25)
            .with_min_confidence(0.4)
            .with_max_missing_time(1.5)
            .with_tentative_missing_time(0.25)
            .with_confirm_hits(5)
            .with_confirm_confidence(0.8)
            .with_confirm_strong_hits(3)
            .with_min_travel(1.5)
            .with_confirm_mean_confidence(Some(0.625))
            .with_max_report_coast(0.75)
            .with_max_time_gap(4.0)
            .with_max_history(Some(100)),
    );
    round_trip_non_default(
        &StaticMapParams::default()
            .with_resolution(0.1)
            .with_range(6.0)
            .with_static_time(2.0)
            .with_query_radius(0.15)
            .with_person_clearance(0.5)
            .with_occupied(0.7)
            .with_mapper({
                let mut p = MapperParams::default();
                p.p_hit = 0.75;
                p
            }),
    );
    round_trip_non_default(
        &DummyFilterParams::default()
            .with_min_samples(8)
            .with_min_displacement(1.5)
            .with_min_mean_speed(0.25)
            .with_speed(SpeedMeasure::NetDisplacement),
    );
    round_trip_non_default(
        &ClearMotParams::default()
            .with_match_threshold(0.5)
            .with_convention(Convention::LegTrackerBenchmarks),
    );
    round_trip_non_default(&recurring_params());
    round_trip_non_default(&EthOptions::default().with_frame_rate(25.0));
    round_trip_non_default(&{
        let mut p = DelimitedOptions::default();
        p.time = 3;
        p.id = 0;
        p.x = 1;
        p.y = 2;
        p.delimiter = Delimiter::Char(';');
        p.header_lines = 1;
        p
    });
    // Every variant of the parameter enums.
    for speed in [SpeedMeasure::PathLength, SpeedMeasure::NetDisplacement] {
        round_trip(&speed);
    }
    for convention in [Convention::MotMetrics, Convention::LegTrackerBenchmarks] {
        round_trip(&convention);
    }
    for delimiter in [Delimiter::Whitespace, Delimiter::Char('\t')] {
        round_trip(&delimiter);
    }
    for clock in [OdomClock::HeaderStamp, OdomClock::BagTime] {
        round_trip(&clock);
    }
    for frames in [EvalFrames::Annotated, EvalFrames::EveryScan] {
        round_trip(&frames);
    }
    for scoring in [Scoring::Online, Scoring::Trajectories] {
        round_trip(&scoring);
    }
    // The evaluation's parameters, with a robot frame named at run time.
    let frame = String::from("base_footprint");
    round_trip_non_default(
        &EvalParams::leg_tracker_benchmarks()
            .with_frames(EvalFrames::EveryScan)
            .with_static_map(Some(StaticMapParams::default().with_static_time(2.0)))
            .with_scoring(Scoring::Trajectories)
            .with_record_tentative(true)
            .with_base_frame(frame),
    );
}

#[test]
fn parameters_are_checked_where_they_are_used() {
    // Plain data: a bad value deserialises, and the tracker built from it refuses it.
    let mut value = serde_json::to_value(KalmanParams::default()).unwrap();
    value["gate"] = json!(-1.0);
    let params: KalmanParams = serde_json::from_value(value).unwrap();
    assert_eq!(params.gate, -1.0);
    assert!(matches!(
        KalmanTracker::new(params),
        Err(TrackingError::InvalidParameter(
            haunts_core::InvalidParameter { name: "gate", .. }
        ))
    ));
}

#[test]
fn detections_tracks_and_trajectories_round_trip() {
    let detection = Detection {
        position: Point2::new(1.25, -0.5),
        covariance: Matrix2::new(0.04, 0.01, 0.01, 0.09),
        confidence: 0.5,
    };
    round_trip(&detection);
    round_trip_non_default(&FixedDetector {
        detections: vec![detection, Detection::isotropic(Point2::new(-2.0, 3.5), 0.2)],
    });
    round_trip(&Leg {
        centre: Point2::new(2.0, 0.25),
        points: 5,
        length: 0.125,
        eigenvalue_ratio: 0.375,
        background_gap: 0.75,
    });
    round_trip(&Track {
        id: 7,
        position: Point2::new(3.5, -1.25),
        velocity: Vector2::new(0.75, 0.5),
        covariance: Matrix2::new(0.02, -0.005, -0.005, 0.03),
        age: 1.5,
        hits: 9,
        confidence: 0.75,
        history: vec![
            (0.5, Point2::new(3.0, -1.5)),
            (0.625, Point2::new(3.25, -1.375)),
        ],
    });
    round_trip(&Trajectory {
        id: 3,
        samples: vec![(1.0, Point2::new(0.0, 0.5)), (1.5, Point2::new(0.25, 0.75))],
    });
}

#[test]
fn reader_records_and_sequences_round_trip() {
    let stamped = StampedScan {
        bag_time: 10.1875,
        frame: "left_laser".to_owned(),
        scan: scan(),
        line: 12,
    };
    round_trip(&stamped);
    let odom = OdomPose {
        bag_time: 10.25,
        stamp: 10.125,
        pose: Pose2::new(Vector2::new(1.5, -2.0), 0.5),
        line: 3,
    };
    round_trip(&odom);
    let tf = StaticTransform {
        parent: "base_link".to_owned(),
        child: "left_laser".to_owned(),
        transform: Pose2::new(Vector2::new(0.85, 0.235), 0.735),
        line: 1,
    };
    round_trip(&tf);
    let truth = person(10.25, 1004, 2.5, -0.75);
    round_trip(&truth);
    round_trip_non_default(&Sequence {
        scans: vec![stamped],
        odometry: vec![odom],
        static_transforms: vec![tf],
        ground_truth: vec![truth, person(10.25, 1005, 4.0, 1.0)],
        skipped_lines: 2,
    });
}

#[test]
fn a_stamped_scan_checks_its_scan() {
    let stamped = StampedScan {
        bag_time: 10.1875,
        frame: "left_laser".to_owned(),
        scan: scan(),
        line: 12,
    };
    let mut value = serde_json::to_value(&stamped).unwrap();
    value["scan"]["angle_increment"] = json!(0.0);
    assert!(rejection::<StampedScan>(&value).contains("angle_increment"));
}

#[test]
fn scores_and_reports_round_trip() {
    round_trip_non_default(&frame());
    let scores = ClearMot {
        mota: 0.625,
        motp: 0.125,
        id_switches: 1,
        false_positives: 2,
        misses: 3,
        matches: 13,
        ground_truth: 16,
        hypotheses: 15,
        frames: 4,
    };
    round_trip(&scores);
    round_trip(&ScanTruth {
        frames: vec![frame(), Frame::new(2.625, vec![])],
        unassigned: 2,
    });
    let sample = TentativeSample {
        scan: 41,
        time: 12.5,
        id: 17,
        position: Point2::new(2.25, -1.0),
        person: true,
        hits: 2,
        age: 0.375,
        travel: 0.5,
        speed: 0.875,
        position_std: 0.0625,
    };
    round_trip(&sample);
    for tracking_frame in [TrackingFrame::Odometry, TrackingFrame::Sensor] {
        round_trip(&tracking_frame);
    }
    round_trip(&EvalReport {
        scores,
        scans: 120,
        skipped_scans: 1,
        frames: 60,
        unassigned_truth: 2,
        detections: 345,
        resets: 1,
        tracking_frame: TrackingFrame::Sensor,
        mounts_assumed: vec!["left_laser".into()],
        followed_tentatively: 5,
        tentative: vec![sample],
    });

    // The dummy filter's report, with every drop reason.
    let walker = Trajectory {
        id: 1,
        samples: (0..=20)
            .map(|k| (k as f64 * 0.125, Point2::new(k as f64 * 0.125, 0.0)))
            .collect(),
    };
    let pillar = Trajectory {
        id: 2,
        samples: vec![(0.0, Point2::new(3.0, 0.0)), (0.5, Point2::new(3.0, 0.0))],
    };
    let report =
        filter_dummies(vec![walker.clone(), pillar], &DummyFilterParams::default()).unwrap();
    assert_eq!((report.kept.len(), report.dropped.len()), (1, 1));
    assert_eq!(report.dropped[0].reasons.len(), 3);
    round_trip_non_default::<DummyReport>(&report);
    round_trip(&TrajectoryStats::of(&walker).unwrap());
}

#[test]
fn models_round_trip_through_json() {
    let detector = LegDetector::new(leg_detector_params()).unwrap();
    round_trip(&detector);

    let pose = |x: f64, yaw: f64| Isometry2::new(Vector2::new(x, 0.5), yaw);
    let history = PoseHistory::new([
        (0.0, pose(0.0, 0.0)),
        (1.0, pose(1.0, 0.5)),
        (1.0, pose(9.0, 0.0)),
        (f64::NAN, pose(0.0, 0.0)),
        (2.0, pose(2.5, 1.0)),
    ])
    .unwrap()
    .with_tolerance(0.05)
    .unwrap();
    assert_eq!(
        (history.skipped_non_finite(), history.dropped_duplicates()),
        (1, 1)
    );
    let back = round_trip(&history);
    assert_eq!(back.pose_at(1.5).unwrap(), history.pose_at(1.5).unwrap());

    let recurring = recurring_objects();
    assert_eq!(recurring.sessions(), 2);
    assert!(!recurring.is_empty());
    let back = round_trip(&recurring);
    assert!(back.contains(&Point2::new(2.04, 0.0)));
}

/// Two posts seen in two patrols an hour apart (after the example of `RecurringObjects`).
fn recurring_objects() -> RecurringObjects {
    let ranges: Vec<f64> = (0..181)
        .map(|i| match i {
            40..=44 => 3.0,
            88..=92 => 2.0,
            _ => 8.0,
        })
        .collect();
    let scan = |t: f64| LaserScan::new(t, -0.9, 0.01, 0.05, 20.0, ranges.clone(), vec![]).unwrap();
    let scans = [0.0, 0.1, 0.2, 3600.0, 3600.1, 3600.2].map(scan);
    let poses = vec![Pose2::identity(); scans.len()];
    let params = {
        let mut p = RecurringParams::default();
        p.min_scans = 3;
        p.query_radius = 0.04;
        p
    };
    let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
    RecurringObjects::build(&detector, scans.iter().zip(&poses), params).unwrap()
}

#[test]
fn a_leg_detector_checks_its_parameters() {
    let detector = LegDetector::new(leg_detector_params()).unwrap();
    let good = serde_json::to_value(detector).unwrap();
    for (field, bad) in [
        ("cluster_gap", json!(-0.1)),
        ("min_points", json!(1)),
        ("single_leg_confidence", json!(1.5)),
    ] {
        let mut value = good.clone();
        value["params"][field] = bad;
        let e = rejection::<LegDetector>(&value);
        assert!(e.contains(field), "{field}: {e}");
    }
}

#[test]
fn a_pose_history_rejects_what_its_constructor_would_repair() {
    let history = PoseHistory::new([
        (0.0, Isometry2::new(Vector2::new(0.0, 0.0), 0.0)),
        (1.0, Isometry2::new(Vector2::new(1.0, 0.5), 0.5)),
    ])
    .unwrap();
    let good = serde_json::to_value(&history).unwrap();
    let bad = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut value = good.clone();
        edit(&mut value);
        rejection::<PoseHistory>(&value)
    };
    // Times out of order (the constructor would sort them).
    let e = bad(&|v| v["times"] = json!([1.0, 0.0]));
    assert!(e.contains("times") && e.contains("increasing"), "{e}");
    // A repeated time (the constructor would drop the second sample).
    let e = bad(&|v| v["times"] = json!([1.0, 1.0]));
    assert!(e.contains("times"), "{e}");
    // No sample.
    let e = bad(&|v| {
        v["times"] = json!([]);
        v["poses"] = json!([]);
    });
    assert!(e.contains("times"), "{e}");
    // One time per pose.
    let e = bad(&|v| v["times"] = json!([0.0, 1.0, 2.0]));
    assert!(e.contains("times") && e.contains("poses"), "{e}");
    // A rotation that is not a unit complex number (nalgebra does not normalise it).
    let e = bad(&|v| v["poses"][1]["rotation"] = json!([2.0, 0.0]));
    assert!(e.contains("poses"), "{e}");
    // A negative tolerance.
    let e = bad(&|v| v["tolerance"] = json!(-0.5));
    assert!(e.contains("tolerance"), "{e}");
    // The tolerance and the counts of repaired samples may be left out.
    let mut minimal = good.clone();
    for key in ["tolerance", "skipped_non_finite", "dropped_duplicates"] {
        minimal.as_object_mut().unwrap().remove(key);
    }
    let back: PoseHistory = serde_json::from_value(minimal).unwrap();
    assert_eq!(back, history);
}

#[test]
fn recurring_objects_check_parameters_and_sort_cells() {
    let recurring = recurring_objects();
    let good = serde_json::to_value(&recurring).unwrap();
    for (field, bad) in [
        ("resolution", json!(0.0)),
        ("min_sessions", json!(1)),
        ("min_session_fraction", json!(2.0)),
    ] {
        let mut value = good.clone();
        value["params"][field] = bad;
        let e = rejection::<RecurringObjects>(&value);
        assert!(e.contains(field), "{field}: {e}");
    }
    // Cells out of order and repeated are put in order (a lookup needs them sorted).
    let mut value = good.clone();
    let cells = value["cells"].as_array_mut().unwrap();
    assert!(cells.len() >= 2, "{cells:?}");
    let doubled: Vec<_> = cells.iter().rev().chain(cells.iter()).cloned().collect();
    *cells = doubled;
    let back: RecurringObjects = serde_json::from_value(value).unwrap();
    assert_eq!(back, recurring);
}

/// A 181-beam scan at `t` of a far wall (8 m), a post at (2, −1) and a person's two legs
/// around (`x`, 0.5); all ranges finite (JSON has no infinity).
fn room_scan(t: f64, x: f64) -> LaserScan {
    beams_of_room(t, x, -0.9, 181)
}

/// `beams` beams of [`room_scan`] from `angle_min`, 0.01 rad apart.
fn beams_of_room(t: f64, x: f64, angle_min: f64, beams: usize) -> LaserScan {
    let circles = [
        (Point2::new(2.0, -1.0), 0.05),
        (Point2::new(x, 0.38), 0.06),
        (Point2::new(x + 0.05, 0.62), 0.06),
    ];
    let ranges = (0..beams)
        .map(|i| {
            let a = angle_min + 0.01 * i as f64;
            let d = Vector2::new(a.cos(), a.sin());
            circles.iter().fold(8.0f64, |r, (c, radius)| {
                let b = d.dot(&c.coords);
                let disc = b * b - c.coords.norm_squared() + radius * radius;
                if disc >= 0.0 && b - disc.sqrt() > 0.0 {
                    r.min(b - disc.sqrt())
                } else {
                    r
                }
            })
        })
        .collect();
    LaserScan::new(t, angle_min, 0.01, 0.05, 20.0, ranges, vec![]).unwrap()
}

/// The robot driving slowly along x: `k` scans at 10 Hz.
fn drive(k: usize) -> Vec<(LaserScan, Pose2)> {
    (0..k)
        .map(|i| {
            let t = 100.0 + 0.1 * i as f64;
            (
                room_scan(t, 1.5 + 0.05 * i as f64),
                Pose2::new(Vector2::new(0.02 * i as f64, 0.0), 0.0),
            )
        })
        .collect()
}

/// Detection with `detector` and a Kalman tracker, with and without a static map and
/// `recurring` objects, over `scans`; then the dummy filter on the trajectories.
fn track_with(
    detector: &dyn haunts_tracking::detect::Detector,
    recurring: Option<&RecurringObjects>,
    scans: &[(LaserScan, Pose2)],
) {
    for statics in [None, Some(StaticMapParams::default())] {
        let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
        let mut online =
            haunts_tracking::track::online::OnlineTracker::new(detector, &mut kf, statics).unwrap();
        if let Some(r) = recurring {
            online = online.with_recurring(r.clone());
        }
        for (scan, pose) in scans {
            let _ = online.step(scan, pose);
        }
        let trajectories = online.lists().trajectories();
        let _ = filter_dummies(trajectories, &DummyFilterParams::default());
    }
}

/// Its statistics and the dummy filter (two ways of measuring speed).
fn use_trajectory(trajectory: &Trajectory) {
    let _ = TrajectoryStats::of(trajectory).map(|s| {
        (
            s.mean_speed(SpeedMeasure::PathLength),
            s.mean_speed(SpeedMeasure::NetDisplacement),
        )
    });
    for speed in [SpeedMeasure::PathLength, SpeedMeasure::NetDisplacement] {
        let params = DummyFilterParams::default().with_speed(speed);
        let _ = filter_dummies(vec![trajectory.clone(), trajectory.clone()], &params);
    }
}

/// A sequence of the robot driving with odometry and a laser mounted on `base_link`, a
/// person walking in front of it, annotated in the laser frame; the scans keep only the 51
/// beams around the person, so that the corruptions sampled from the document are not all
/// in ranges.
fn drive_sequence() -> Sequence {
    let scans: Vec<_> = drive(8)
        .into_iter()
        .enumerate()
        .map(|(k, (scan, pose))| {
            let x = 1.5 + 0.05 * k as f64;
            (beams_of_room(scan.stamp, x, 0.05, 51), pose)
        })
        .collect();
    let laser = Pose2::new(Vector2::new(0.2, 0.0), 0.0);
    let mut sequence = Sequence {
        static_transforms: vec![StaticTransform {
            parent: "base_link".into(),
            child: "laser".into(),
            transform: laser,
            line: 1,
        }],
        ..Sequence::default()
    };
    for (k, (scan, pose)) in scans.into_iter().enumerate() {
        let t = scan.stamp;
        sequence.odometry.push(OdomPose {
            bag_time: t - 0.01,
            stamp: t - 0.01,
            pose: pose * laser.inverse(),
            line: k + 1,
        });
        if k % 3 == 1 {
            sequence
                .ground_truth
                .push(person(t + 0.01, 1, 1.5 + 0.05 * k as f64, 0.5));
        }
        sequence.scans.push(StampedScan {
            bag_time: t,
            frame: "laser".into(),
            scan,
            line: k + 1,
        });
    }
    sequence
}

#[test]
fn corrupted_files_are_refused_or_usable_never_a_panic() {
    let scans = drive(8);
    let default_detector = LegDetector::new(LegDetectorParams::default()).unwrap();
    let recurring = recurring_objects();

    let detectors = corrupt(
        &LegDetector::new(leg_detector_params()).unwrap(),
        1000,
        |detector: &LegDetector| {
            let scan = &scans[0].0;
            let legs = detector.legs(scan);
            let _ = detector.pair(&legs);
            use haunts_tracking::detect::Detector;
            let _ = detector.detect(scan).unwrap();
            let _ = detector.detect_where(scan, &|p| p.y > 0.0).unwrap();
            let _ = detector.candidates(scan).unwrap();
            let params = {
                let mut p = RecurringParams::default();
                p.min_scans = 2;
                p
            };
            let _ = RecurringObjects::build(detector, scans.iter().map(|(s, p)| (s, p)), params)
                .unwrap();
            track_with(detector, None, &scans);
        },
    );

    let history = PoseHistory::new(scans.iter().map(|(s, p)| (s.stamp, *p)))
        .unwrap()
        .with_tolerance(0.05)
        .unwrap();
    let laser = Pose2::new(Vector2::new(0.2, 0.0), 0.1);
    let histories = corrupt(&history, 1000, |history: &PoseHistory| {
        let (start, end) = history.span();
        assert!(start <= end && !history.is_empty());
        let _ = history.samples().count();
        let mid = 0.5 * (start + end);
        let mut sensed = Vec::new();
        for t in [
            start,
            end,
            mid,
            start - 1.0,
            end + 1.0,
            start + 0.25,
            f64::NAN,
        ] {
            assert_eq!(history.pose_at(t).is_ok(), history.covers(t), "{t}");
            if let Ok(sensor) = history.sensor_pose_at(t, &laser) {
                let p = Point2::new(1.0, 0.5);
                let w = history.to_world(t, &p, &laser).unwrap();
                let _ = history.to_sensor(t, &w, &laser).unwrap();
                let _ = recurring.contains(&w);
                sensed.push((room_scan(t, 1.5), sensor));
            }
        }
        track_with(&default_detector, Some(&recurring), &sensed);
    });

    let recurrings = corrupt(&recurring, 1000, |recurring: &RecurringObjects| {
        let _ = (recurring.sessions(), recurring.len(), recurring.is_empty());
        let centres: Vec<_> = recurring.centres().collect();
        for c in &centres {
            assert!(recurring.contains(c) || !c.x.is_finite() || !c.y.is_finite());
        }
        for p in [
            Point2::new(2.04, 0.0),
            Point2::new(0.0, 0.0),
            Point2::new(1e300, -1e300),
            Point2::new(f64::NAN, 1.0),
        ] {
            let _ = recurring.contains(&p);
        }
        track_with(&default_detector, Some(recurring), &scans);
    });

    let sequence = drive_sequence();
    let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
    let report = evaluate_sequence(
        &sequence,
        &default_detector,
        &mut kf,
        &EvalParams::default(),
    )
    .unwrap();
    assert!(
        report.scores.ground_truth > 0 && report.scores.matches > 0,
        "{report:?}"
    );
    let sequences = corrupt(&sequence, 800, |sequence: &Sequence| {
        for params in [
            EvalParams::default(),
            EvalParams::leg_tracker_benchmarks()
                .with_frames(EvalFrames::EveryScan)
                .with_scoring(Scoring::Trajectories)
                .with_static_map(Some(StaticMapParams::default()))
                .with_record_tentative(true),
        ] {
            let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
            let _ = evaluate_sequence(sequence, &default_detector, &mut kf, &params);
        }
    });

    let track = {
        let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
        let mut online =
            haunts_tracking::track::online::OnlineTracker::new(&default_detector, &mut kf, None)
                .unwrap();
        for (scan, pose) in &drive(20) {
            online.step(scan, pose).unwrap();
        }
        online.lists().reported()[0].clone()
    };
    assert!(track.history.len() > 5, "{track:?}");
    let tracks = corrupt(&track, 1000, |track: &Track| {
        use_trajectory(&track.trajectory())
    });
    let trajectories = corrupt(&track.trajectory(), 1000, use_trajectory);

    for (name, tally) in [
        ("LegDetector", detectors),
        ("PoseHistory", histories),
        ("RecurringObjects", recurrings),
        ("Sequence", sequences),
        ("Track", tracks),
        ("Trajectory", trajectories),
    ] {
        eprintln!("{name}: {tally:?}");
        assert!(tally.refused > 0 && tally.accepted > 0, "{name}: {tally:?}");
    }
}

/// A hand-written recurring-objects file: one marked cell near (2.05, 0.05) and one at the
/// saturated far end; `query_radius` as given.
fn recurring_file(query_radius: &str) -> RecurringObjects {
    serde_json::from_str(&format!(
        r#"{{"params":{{"session_gap":600.0,"resolution":0.1,"min_scans":5,"min_sessions":2,
            "min_session_fraction":0.8,"query_radius":{query_radius}}},"sessions":2,
            "cells":[[20,0],[9223372036854775807,0]]}}"#
    ))
    .unwrap()
}

#[test]
fn recurring_objects_answer_a_far_point_without_overflow() {
    // `contains` added the query reach to the saturated cell index of a far point:
    // "attempt to add with overflow".
    let recurring = recurring_file("0.03");
    assert!(recurring.contains(&Point2::new(2.05, 0.05)));
    assert!(!recurring.contains(&Point2::new(2.5, 0.05)));
    assert!(!recurring.contains(&Point2::new(1e300, 0.0)));
    assert!(!recurring.contains(&Point2::new(-1e300, 1e300)));
}

#[test]
fn recurring_objects_answer_a_query_radius_of_many_cells() {
    // A valid but huge radius (1e300 m, `i64::MAX` cells) overflowed; a radius of a few
    // thousand cells would have visited millions of cells per query.
    let recurring = recurring_file("1e300");
    assert!(recurring.contains(&Point2::new(-5e299, 3e299)));
    assert!(recurring.contains(&Point2::new(9e299, 0.0)));
    assert!(!recurring.contains(&Point2::new(1e300, -1e300)));
    assert!(!recurring.contains(&Point2::new(f64::NAN, 0.0)));
    let wide = recurring_file("300.0");
    let start = std::time::Instant::now();
    for k in 0..100 {
        assert!(wide.contains(&Point2::new(100.0 + f64::from(k), -100.0)));
    }
    assert!(start.elapsed().as_secs_f64() < 1.0, "{:?}", start.elapsed());
}
