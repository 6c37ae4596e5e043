//! Both trackers on the real `leg_tracker` bag (`general_tracking_moving_1`: a moving robot,
//! 12 annotated people), scored as `leg_tracker_benchmarks` does. Skipped with a notice when
//! `../shared/data` is absent.
//!
//! The thresholds are the scores reached today minus a small margin, so that a regression
//! fails; they are well below the target of MOTA ≥ 0.70 — the geometric leg
//! detector cannot tell a single leg from a post or a table leg, so a new track must earn
//! its confirmation (two leg pairs, or 1.2 m walked) and every annotated person seen only
//! for a moment before that is a miss.
#![allow(clippy::unwrap_used)]

use haunts_tracking::detect::static_map::StaticMapParams;
use haunts_tracking::detect::{LegDetector, LegDetectorParams};
use haunts_tracking::eval::mot::ClearMot;
use haunts_tracking::eval::sequence::{
    EvalFrames, EvalParams, EvalReport, Scoring, Sequence, TrackingFrame, evaluate_sequence,
};
use haunts_tracking::track::Tracker;
use haunts_tracking::track::kalman::{KalmanParams, KalmanTracker};
use haunts_tracking::track::particle::{ParticleParams, ParticleTracker};

use data::shared_data;
use haunts_test_support::data;

fn sequence() -> Option<Sequence> {
    let dir = shared_data("leg_tracker/general_tracking_moving_1/scans.txt")?;
    Some(Sequence::read(dir.parent()?).unwrap())
}

fn run(sequence: &Sequence, tracker: &mut dyn Tracker, params: &EvalParams) -> EvalReport {
    let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
    evaluate_sequence(sequence, &detector, tracker, params).unwrap()
}

fn pf() -> ParticleTracker {
    ParticleTracker::new(ParticleParams::default()).unwrap()
}

fn kf() -> KalmanTracker {
    KalmanTracker::new(KalmanParams::default()).unwrap()
}

/// The benchmark's protocol, with the map of static objects (what `eval_tracking` runs).
fn with_static_map() -> EvalParams {
    EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()))
}

fn summary(name: &str, s: &ClearMot) {
    eprintln!(
        "{name}: MOTA {:.3} MOTP {:.3} m, {} switches, {} false positives, {} misses of {}",
        s.mota, s.motp, s.id_switches, s.false_positives, s.misses, s.ground_truth
    );
}

#[test]
fn both_trackers_reach_their_scores_on_the_moving_robot_bag() {
    let Some(sequence) = sequence() else { return };
    let params = with_static_map();
    let pf_report = run(&sequence, &mut pf(), &params);
    let kf_report = run(&sequence, &mut kf(), &params);
    let (p, k) = (&pf_report.scores, &kf_report.scores);
    summary("particle filter", p);
    summary("kalman", k);
    for report in [&pf_report, &kf_report] {
        assert_eq!(report.scans, 873);
        assert_eq!(report.skipped_scans, 0);
        assert_eq!(report.tracking_frame, TrackingFrame::Odometry);
        // 123 annotated scans; 133 of the 153 annotations are within −80°..12°.
        assert_eq!((report.frames, report.scores.ground_truth), (123, 133));
        assert_eq!(report.resets, 0);
    }
    // The better tracker: the Kalman tracker (0.504 / 0.130 m; the particle filter 0.459 /
    // 0.155 m, with fewer false positives but more misses).
    assert!(k.mota >= 0.47, "kalman MOTA {}", k.mota);
    assert!(k.motp <= 0.15, "kalman MOTP {}", k.motp);
    assert!(k.false_positives <= 20 && k.id_switches <= 2, "{k:?}");
    assert!(p.mota >= 0.42, "particle filter MOTA {}", p.mota);
    assert!(p.motp <= 0.17, "particle filter MOTP {}", p.motp);
    assert!(p.false_positives <= 8 && p.id_switches <= 2, "{p:?}");
    assert!(k.mota > p.mota);
}

#[test]
fn the_static_map_removes_clutter() {
    let Some(sequence) = sequence() else { return };
    // Without the map, posts and table legs seen before a person walks by them pair up
    // with anything and are confirmed: 47 false positives instead of 15 for the Kalman
    // tracker, for the same 83 matches.
    let with = run(&sequence, &mut kf(), &with_static_map()).scores;
    let without = run(&sequence, &mut kf(), &EvalParams::leg_tracker_benchmarks()).scores;
    summary("kalman, no static map", &without);
    assert!(
        without.false_positives >= with.false_positives + 20,
        "{without:?} vs {with:?}"
    );
    assert!(without.mota + 0.15 <= with.mota);
}

#[test]
fn every_scan_and_no_odometry_are_scored_too() {
    let Some(sequence) = sequence() else { return };
    // clear_mot.py's way: every scan is scored, so tracks between annotations count too.
    let every = with_static_map().with_frames(EvalFrames::EveryScan);
    let report = run(&sequence, &mut pf(), &every);
    assert_eq!(report.frames, 873);
    assert_eq!(report.scores.ground_truth, 133);
    let annotated = run(&sequence, &mut pf(), &with_static_map());
    assert!(report.scores.false_positives >= annotated.scores.false_positives);
    // Without odometry the tracker works in the laser frame (where a map of static objects
    // means nothing on a moving robot) and still finds people.
    let blind = Sequence {
        odometry: Vec::new(),
        static_transforms: Vec::new(),
        ..sequence
    };
    let report = run(&blind, &mut kf(), &EvalParams::leg_tracker_benchmarks());
    assert_eq!(report.tracking_frame, TrackingFrame::Sensor);
    assert!(report.scores.matches >= 40, "{:?}", report.scores);
}

#[test]
fn trajectories_count_people_from_before_their_confirmation() {
    let Some(sequence) = sequence() else { return };
    let online = run(&sequence, &mut kf(), &with_static_map()).scores;
    let params = with_static_map().with_scoring(Scoring::Trajectories);
    let whole = run(&sequence, &mut kf(), &params).scores;
    summary("kalman, trajectories", &whole);
    // The people missed online are nearly all seen by a track that was not yet confirmed:
    // the trajectories find them (49 → 8 misses today), at the price of the false positives
    // of those tentative stretches (11 → 33; many are people the annotators skipped in
    // that scan).
    assert!(whole.misses <= 12, "{whole:?}");
    assert!(
        online.misses >= whole.misses + 30,
        "{online:?} vs {whole:?}"
    );
    assert!(
        whole.false_positives <= 40 && whole.id_switches <= 2,
        "{whole:?}"
    );
    assert!(whole.mota >= 0.65 && whole.motp <= 0.15, "{whole:?}");
    // Every online match is a trajectory sample too: the trajectories only add.
    assert!(whole.matches >= online.matches);
}

#[test]
fn nearly_every_online_miss_is_a_person_followed_tentatively() {
    let Some(sequence) = sequence() else { return };
    let params = with_static_map().with_record_tentative(true);
    let report = run(&sequence, &mut kf(), &params);
    let s = &report.scores;
    // 47 of the 49 misses today: the detector found them and a tentative track followed
    // them, but it had not yet shown it was a person (see `benches/peers/confirmation_oracle.py`
    // for why no confirmation rule gets them for free).
    assert!(
        report.followed_tentatively <= s.misses && report.followed_tentatively + 6 >= s.misses,
        "{} of {s:?}",
        report.followed_tentatively
    );
    // Clutter outnumbers people among the tentative tracks (305 to 55 samples today).
    let people = report.tentative.iter().filter(|u| u.person).count();
    let clutter = report.tentative.len() - people;
    assert!(people >= report.followed_tentatively, "{people}");
    assert!(clutter >= 4 * people, "{clutter} vs {people}");
}

#[test]
fn the_forest_detector_transfers_poorly_to_the_moving_robot_bag() {
    use haunts_tracking::detect::ForestDetector;
    let Some(sequence) = sequence() else { return };
    // The shipped forest (trained on leg_tracker's training set only), with the trackers'
    // births and confirmation at its cross-validated operating point (the running average
    // of a track's leg probabilities must reach it).
    let detector = ForestDetector::shipped().unwrap();
    let p = detector.min_probability();
    let params = KalmanParams::default()
        .with_min_birth_confidence(p)
        .with_confirm_mean_confidence(Some(p));
    let score = |frames| {
        let mut kf = KalmanTracker::new(params).unwrap();
        let eval = with_static_map().with_frames(frames);
        evaluate_sequence(&sequence, &detector, &mut kf, &eval).unwrap()
    };
    let (every, annotated) = (score(EvalFrames::EveryScan), score(EvalFrames::Annotated));
    summary("kalman + forest, every scan", &every.scores);
    summary("kalman + forest, annotated", &annotated.scores);
    assert_eq!((every.frames, annotated.frames), (873, 123));
    // Today 0.263 annotated / −0.075 every scan, against 0.541 / 0.256 with the geometric
    // detector: at its operating point the forest keeps 30 % of the clusters within 0.25 m
    // of a person on this bag (examples/cluster_quality.rs), so most people are missed.
    assert!(annotated.scores.mota >= 0.15, "{:?}", annotated.scores);
    assert!(every.scores.mota >= -0.15, "{:?}", every.scores);
    assert!(every.scores.false_positives >= annotated.scores.false_positives);
    assert_eq!(every.scores.misses, annotated.scores.misses);
}
