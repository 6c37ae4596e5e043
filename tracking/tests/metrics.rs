//! CLEAR MOT on the ground truth of the `leg_tracker` bag in `../shared/data` (skipped with a
//! notice when absent): grouping per scan, and scores of perturbed copies of the truth whose
//! values are known in advance.
#![allow(clippy::unwrap_used)]

use approx::assert_relative_eq;
use haunts_tracking::eval::mot::{
    ClearMotParams, Convention, Frame, clear_mot, group_by_time, truth_frames_for_scans,
};
use haunts_tracking::{PersonPosition, read_ground_truth, read_scans};
use nalgebra::Vector2;

use data::shared_data;
use haunts_test_support::data;

const BAG: &str = "leg_tracker/general_tracking_moving_1";

/// The bag's scan bag times and ground truth, or `None` with a printed notice.
fn bag() -> Option<(Vec<f64>, Vec<PersonPosition>)> {
    let dir = shared_data(BAG)?;
    let scans = read_scans(dir.join("scans.txt")).unwrap().records;
    let truth = read_ground_truth(dir.join("ground_truth_people.txt"))
        .unwrap()
        .records;
    Some((scans.iter().map(|s| s.bag_time).collect(), truth))
}

#[test]
fn every_annotation_belongs_to_the_scan_just_before_it() {
    let Some((scan_times, truth)) = bag() else {
        return;
    };
    let assigned = truth_frames_for_scans(&scan_times, &truth).unwrap();
    assert_eq!(assigned.frames.len(), 873);
    assert_eq!(assigned.unassigned, 0);
    let objects: usize = assigned.frames.iter().map(|f| f.objects.len()).sum();
    assert_eq!(objects, 153);
    let annotated = assigned
        .frames
        .iter()
        .filter(|f| !f.objects.is_empty())
        .count();
    // One annotated scan per distinct annotation time.
    assert_eq!(annotated, group_by_time(&truth).len());
    assert_eq!(annotated, 123);
    // Each annotation is stamped halfway to the next scan: 62–72 ms after its own.
    for (k, frame) in assigned.frames.iter().enumerate() {
        for &(id, _) in &frame.objects {
            let record = truth
                .iter()
                .find(|r| {
                    r.id == id && r.bag_time > scan_times[k] && r.bag_time - scan_times[k] < 0.1
                })
                .unwrap();
            let mid = (scan_times[k] + scan_times[k + 1]) / 2.0;
            assert!((record.bag_time - mid).abs() < 1e-3);
        }
    }
}

/// The truth frames of every scan, with ids shifted and positions moved by `offset`, minus
/// person `drop`.
fn perturbed(frames: &[Frame], offset: Vector2<f64>, drop: Option<u64>) -> Vec<Frame> {
    frames
        .iter()
        .map(|f| {
            let objects = f
                .objects
                .iter()
                .filter(|o| Some(o.0) != drop)
                .map(|&(id, p)| (id + 50_000, p + offset))
                .collect();
            Frame::new(f.time, objects)
        })
        .collect()
}

#[test]
fn perturbed_truth_scores_as_predicted() {
    let Some((scan_times, truth)) = bag() else {
        return;
    };
    let frames = truth_frames_for_scans(&scan_times, &truth).unwrap().frames;
    let person_four = truth.iter().filter(|r| r.id == 4).count();
    assert_eq!(person_four, 17);
    for convention in [Convention::MotMetrics, Convention::LegTrackerBenchmarks] {
        let params = ClearMotParams::default().with_convention(convention);
        // 0.5 m off and one person never tracked.
        let hyps = perturbed(&frames, Vector2::new(0.3, 0.4), Some(4));
        let s = clear_mot(&frames, &hyps, &params).unwrap();
        assert_eq!((s.ground_truth, s.frames), (153, 873));
        assert_eq!((s.matches, s.misses), (153 - 17, 17));
        assert_eq!((s.false_positives, s.id_switches), (0, 0));
        assert_relative_eq!(s.motp, 0.5, epsilon = 1e-9);
        assert_relative_eq!(s.mota, 1.0 - 17.0 / 153.0, epsilon = 1e-12);
        // 20 m off: nothing matches, everything is missed and false.
        let hyps = perturbed(&frames, Vector2::new(0.0, 20.0), None);
        let s = clear_mot(&frames, &hyps, &params).unwrap();
        assert_eq!((s.matches, s.misses, s.false_positives), (0, 153, 153));
        assert_relative_eq!(s.mota, -1.0);
        assert_relative_eq!(s.motp, 0.0);
    }
}
