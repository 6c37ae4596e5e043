//! The live session against the offline evaluation: the shared `leg_tracker` recording
//! streamed message by message through `haunts::live` scores exactly as `evaluate_sequence`
//! scores the same file with `eval_tracking`'s defaults (ROS 1 bag and MCAP); and the hostile
//! stream cases are dropped and counted by reason.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use haunts::bag::{Bag, RecordingOptions};
use haunts::live::replay::{Replay, ground_truth};
use haunts::live::{LiveParams, LiveSession};
use haunts::occupancy::{LaserScan, Pose2};
use haunts::tracking::detect::static_map::StaticMapParams;
use haunts::tracking::detect::{LegDetector, LegDetectorParams};
use haunts::tracking::eval::mot::ClearMot;
use haunts::tracking::eval::sequence::{EvalFrames, EvalParams, Sequence, evaluate_sequence};
use haunts::tracking::track::particle::{ParticleParams, ParticleTracker};
use haunts_test_support::bag;
use nalgebra::{Isometry2, Vector2};

/// `eval_tracking`'s protocol with its defaults.
fn protocol() -> EvalParams {
    EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()))
}

/// `evaluate_sequence` on the recording at `path` with `eval_tracking`'s defaults (particle
/// tracker, geometric detector, static map): every-scan and annotated scores.
fn offline(path: &std::path::Path) -> (ClearMot, ClearMot) {
    let bag = Bag::open(path).unwrap();
    let recording = bag.recording(&RecordingOptions::new()).unwrap();
    let truth = ground_truth(&bag, "/ground_truth_people_tracks").unwrap();
    let sequence = Sequence::from_recording(&recording, truth).unwrap();
    let run = |frames| {
        let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
        let mut tracker = ParticleTracker::new(ParticleParams::default()).unwrap();
        evaluate_sequence(
            &sequence,
            &detector,
            &mut tracker,
            &protocol().with_frames(frames),
        )
        .unwrap()
        .scores
    };
    (run(EvalFrames::EveryScan), run(EvalFrames::Annotated))
}

fn live(path: &std::path::Path) -> (ClearMot, ClearMot, haunts::live::Dropped) {
    let replay = Replay::new(Bag::open(path).unwrap(), &RecordingOptions::new(), None).unwrap();
    let mut session = LiveSession::with_defaults(replay.params(LiveParams::default())).unwrap();
    let replayed = replay.run(&mut session, |_| Ok(())).unwrap();
    assert_eq!(session.pending(), 0);
    let (every, annotated) = replayed.scores(&protocol()).unwrap().unwrap();
    (every.scores, annotated.scores, *session.dropped())
}

#[test]
fn replaying_the_recording_scores_as_the_offline_evaluation() {
    let (Some(ros1), Some(mcap)) = (bag::moving_bag(), bag::moving_mcap()) else {
        eprintln!("skipped: the shared leg_tracker recording is not there");
        return;
    };
    for path in [mcap, ros1] {
        let (every, annotated) = offline(&path);
        let (live_every, live_annotated, dropped) = live(&path);
        // Every count and both MOTAs, to the last bit.
        assert_eq!(live_every, every, "{}", path.display());
        assert_eq!(live_annotated, annotated, "{}", path.display());
        assert!(every.ground_truth > 0 && every.mota > 0.0);
        // No scan was out of order or refused by the tracker.
        assert_eq!(dropped.tracker_refused + dropped.stamp_backwards, 0);
    }
}

fn pose(x: f64, y: f64) -> Pose2 {
    Isometry2::new(Vector2::new(x, y), 0.0)
}

fn scan(stamp: f64, ranges: Vec<f64>) -> LaserScan {
    LaserScan::new(stamp, -1.5, 0.01, 0.05, 20.0, ranges, vec![]).unwrap()
}

/// A session whose odometry and mount are there from the start.
fn ready_session() -> LiveSession {
    let mut s = LiveSession::with_defaults(LiveParams::default()).unwrap();
    s.push_tf(0.0, ("base_link", "laser"), 0.0, &pose(0.1, 0.0), true);
    s.push_odom(0.0, 0.0, &pose(0.0, 0.0));
    s.push_odom(0.0, 100.0, &pose(10.0, 0.0));
    s
}

#[test]
fn hostile_scans_are_dropped_and_counted_by_reason() {
    let mut s = ready_session();
    let mut tracked = 0;
    // NaN ranges: kept, read as no return, counted.
    tracked += s
        .push_scan(1.0, "laser", scan(1.0, vec![f64::NAN; 300]))
        .len();
    assert_eq!(s.dropped().non_finite_ranges, 300);
    // No beams; a million beams.
    tracked += s.push_scan(1.1, "laser", scan(1.1, vec![])).len();
    tracked += s
        .push_scan(1.2, "laser", scan(1.2, vec![3.0; 1_000_000]))
        .len();
    // A description that does not check (fields are public: a caller can break them).
    let mut bad = scan(1.3, vec![3.0; 300]);
    bad.angle_increment = 0.0;
    tracked += s.push_scan(1.3, "laser", bad).len();
    let mut nan_stamp = scan(1.35, vec![3.0; 300]);
    nan_stamp.stamp = f64::NAN;
    tracked += s.push_scan(1.35, "laser", nan_stamp).len();
    // Time going backwards.
    tracked += s.push_scan(1.4, "laser", scan(2.0, vec![3.0; 300])).len();
    tracked += s.push_scan(1.5, "laser", scan(1.9, vec![3.0; 300])).len();
    // A frame no transform links to the base: it waits its window, then is dropped; the
    // scan behind it waits for it.
    tracked += s.push_scan(1.6, "camera", scan(2.1, vec![3.0; 300])).len();
    tracked += s.push_scan(1.7, "laser", scan(2.2, vec![3.0; 300])).len();
    assert_eq!(s.pending(), 2);
    tracked += s.push_scan(2.2, "laser", scan(2.3, vec![3.0; 300])).len();
    assert_eq!(s.pending(), 0);
    // Bad odometry and transforms.
    s.push_odom(2.3, f64::NAN, &pose(0.0, 0.0));
    s.push_odom(2.3, 50.0, &pose(f64::INFINITY, 0.0));
    s.push_odom(2.3, 100.0, &pose(1.0, 0.0));
    s.push_tf(2.3, ("base_link", ""), 0.0, &pose(0.0, 0.0), true);
    s.push_tf(
        2.3,
        ("base_link", "camera"),
        0.0,
        &pose(f64::NAN, 0.0),
        false,
    );
    let d = *s.dropped();
    assert_eq!(
        (
            d.empty_scan,
            d.too_many_beams,
            d.invalid_scan,
            d.stamp_backwards
        ),
        (1, 1, 2, 1)
    );
    assert_eq!((d.missing_tf, d.no_odometry, d.tracker_refused), (1, 0, 0));
    assert_eq!((d.bad_odometry, d.duplicate_odometry, d.bad_tf), (2, 1, 2));
    assert_eq!(d.scans(), 6);
    assert_eq!(d.messages(), 11);
    // Tracked: the NaN scan, 2.0, 2.2 and 2.3.
    assert_eq!(tracked, 4);
    assert_eq!((s.scans(), s.tracked()), (10, 4));
}

#[test]
fn late_odometry_and_transforms_within_the_window_are_used() {
    let mut s = LiveSession::with_defaults(LiveParams::default()).unwrap();
    // The scan comes first; its mount and odometry 0.3 s later.
    assert!(
        s.push_scan(10.0, "laser", scan(10.0, vec![3.0; 300]))
            .is_empty()
    );
    assert!(s.push_odom(10.1, 9.9, &pose(1.0, 0.0)).is_empty());
    assert!(
        s.push_tf(10.2, ("/base_link", "/laser"), 0.0, &pose(0.5, 0.0), true)
            .is_empty()
    );
    let out = s.push_odom(10.3, 10.1, &pose(3.0, 0.0));
    assert_eq!(out.len(), 1);
    // Halfway between the two samples, plus the mount.
    approx::assert_relative_eq!(out[0].sensor.translation.x, 2.5, epsilon = 1e-12);
    // Without odometry after its stamp, a scan is dropped once its window has passed.
    assert!(
        s.push_scan(10.4, "laser", scan(10.4, vec![3.0; 300]))
            .is_empty()
    );
    assert!(s.push_odom(10.8, 10.2, &pose(3.5, 0.0)).is_empty());
    assert_eq!(s.pending(), 1);
    assert!(s.push_odom(10.95, 10.25, &pose(3.6, 0.0)).is_empty());
    assert_eq!((s.pending(), s.dropped().no_odometry), (0, 1));
    // The end of the stream resolves what waits.
    assert!(
        s.push_scan(11.0, "laser", scan(11.0, vec![3.0; 300]))
            .is_empty()
    );
    assert!(s.finish().is_empty());
    assert_eq!((s.pending(), s.dropped().no_odometry), (0, 2));
}

#[test]
fn waiting_scans_are_bounded() {
    let mut s = LiveSession::with_defaults(LiveParams::default().with_window(1e9)).unwrap();
    for k in 0..100 {
        let t = f64::from(k) * 0.1;
        s.push_scan(t, "laser", scan(t, vec![3.0; 300]));
    }
    assert_eq!(s.pending(), 64);
    assert_eq!(s.dropped().pending_overflow, 36);
}
