//! The dummy-target filter on the ground truth of the `leg_tracker` bag, put into the odometry
//! frame (skipped with a notice when `../shared/data` is absent): the people who stand are
//! dropped, the walkers with long enough tracks are kept.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;

use haunts_tracking::Trajectory;
use haunts_tracking::eval::mot::truth_frames_for_scans;
use haunts_tracking::io::frames::{OdomClock, odometry_history, static_chain};
use haunts_tracking::track::dummy::{DropReason, DummyFilterParams, filter_dummies};
use haunts_tracking::{read_ground_truth, read_odometry, read_scans, read_static_transforms};
use nalgebra::Point2;

use data::shared_data;
use haunts_test_support::data;

/// The bag's ground truth as trajectories in `odom`, or `None` with a printed notice.
fn world_trajectories() -> Option<Vec<Trajectory>> {
    let dir = shared_data("leg_tracker/general_tracking_moving_1")?;
    let odom = read_odometry(dir.join("odom.txt")).unwrap().records;
    let history = odometry_history(&odom, OdomClock::HeaderStamp).unwrap();
    let tfs = read_static_transforms(dir.join("static_tf.txt"))
        .unwrap()
        .records;
    let mount = static_chain(&tfs, "left_laser", "base_link").unwrap();
    let scans = read_scans(dir.join("scans.txt")).unwrap().records;
    let truth = read_ground_truth(dir.join("ground_truth_people.txt"))
        .unwrap()
        .records;
    let bag_times: Vec<f64> = scans.iter().map(|s| s.bag_time).collect();
    let frames = truth_frames_for_scans(&bag_times, &truth).unwrap().frames;
    let mut by_id: BTreeMap<u64, Vec<(f64, Point2<f64>)>> = BTreeMap::new();
    for (scan, frame) in scans.iter().zip(&frames) {
        for &(id, p) in &frame.objects {
            let t = scan.scan.stamp;
            by_id
                .entry(id)
                .or_default()
                .push((t, history.to_world(t, &p, &mount).unwrap()));
        }
    }
    Some(
        by_id
            .into_iter()
            .map(|(id, samples)| Trajectory { id, samples })
            .collect(),
    )
}

#[test]
fn standing_people_are_dummies_and_walkers_are_kept() {
    let Some(trajectories) = world_trajectories() else {
        return;
    };
    assert_eq!(trajectories.len(), 12);
    // The annotations are sparse (123 of 873 scans), so ask for 5 samples.
    let params = DummyFilterParams::default().with_min_samples(5);
    let report = filter_dummies(trajectories, &params).unwrap();
    let kept: Vec<u64> = report.kept.iter().map(|t| t.id).collect();
    assert_eq!(kept, vec![1, 2, 4, 5, 6]);
    for dropped in &report.dropped {
        let id = dropped.trajectory.id;
        if id >= 1000 {
            // Every standing person moved less than 0.5 m from first to last annotation.
            assert!(
                dropped.reasons.iter().any(
                    |r| matches!(r, DropReason::TooLittleDisplacement { metres } if *metres < 0.5)
                ),
                "{id}: {:?}",
                dropped.reasons
            );
        }
    }
    let dropped: Vec<u64> = report.dropped.iter().map(|d| d.trajectory.id).collect();
    assert_eq!(dropped, vec![3, 1000, 1001, 1003, 1004, 1005, 1006]);
}
