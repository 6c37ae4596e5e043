//! `frames` on the `leg_tracker` bag of `../shared/data` (skipped with a notice when absent):
//! the static chain, odometry coverage of the scans, and the chain laser → base_link → odom
//! that puts the ground truth into a fixed frame.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::PathBuf;

use approx::assert_relative_eq;
use haunts_tracking::eval::mot::truth_frames_for_scans;
use haunts_tracking::io::frames::{OdomClock, odometry_history, static_chain};
use haunts_tracking::{
    TrackingError, read_ground_truth, read_odometry, read_scans, read_static_transforms,
};
use nalgebra::{Isometry2, Point2};

use data::shared_data;
use haunts_test_support::data;

const BAG: &str = "leg_tracker/general_tracking_moving_1";

/// A file of the bag in `../shared/data/`, or `None` with a printed notice.
fn bag_file(name: &str) -> Option<PathBuf> {
    shared_data(&format!("{BAG}/{name}"))
}

#[test]
fn the_laser_is_mounted_ahead_left_and_turned_left() {
    let Some(path) = bag_file("static_tf.txt") else {
        return;
    };
    let tfs = read_static_transforms(path).unwrap().records;
    let laser_to_base = static_chain(&tfs, "left_laser", "base_link").unwrap();
    assert_relative_eq!(laser_to_base.translation.x, 0.850326, epsilon = 1e-9);
    assert_relative_eq!(laser_to_base.translation.y, 0.235214, epsilon = 1e-9);
    assert_relative_eq!(laser_to_base.rotation.angle(), 0.734808, epsilon = 1e-9);
    // A point 1 m straight ahead of the laser is ahead and to the left of the robot.
    let p = laser_to_base * Point2::new(1.0, 0.0);
    assert!(p.x > 1.5 && p.y > 0.8, "{p}");
    let base_to_laser = static_chain(&tfs, "base_link", "left_laser").unwrap();
    assert_relative_eq!(base_to_laser * p, Point2::new(1.0, 0.0), epsilon = 1e-12);
    // odom is not a static frame: it comes from odom.txt.
    assert!(matches!(
        static_chain(&tfs, "left_laser", "odom"),
        Err(TrackingError::NoTransformChain { .. })
    ));
}

#[test]
fn odometry_covers_every_scan_and_moves_smoothly_between_them() {
    let (Some(odom), Some(scans)) = (bag_file("odom.txt"), bag_file("scans.txt")) else {
        return;
    };
    let odom = read_odometry(odom).unwrap();
    let history = odometry_history(&odom.records, OdomClock::HeaderStamp).unwrap();
    assert_eq!(history.len(), odom.records.len());
    assert_eq!(
        (history.skipped_non_finite(), history.dropped_duplicates()),
        (0, 0)
    );
    let scans = read_scans(scans).unwrap().records;
    let poses: Vec<Isometry2<f64>> = scans
        .iter()
        .map(|s| history.pose_at(s.scan.stamp).unwrap())
        .collect();
    // Between consecutive scans (≈ 0.13 s) the robot moves < 0.25 m and turns < 0.5 rad,
    // also where its heading crosses ±π.
    let mut crossings = 0;
    for w in poses.windows(2) {
        let step = w[0].inverse() * w[1];
        assert!(step.translation.vector.norm() < 0.25, "{step}");
        assert!(step.rotation.angle().abs() < 0.5, "{step}");
        if (w[0].rotation.angle() - w[1].rotation.angle()).abs() > std::f64::consts::PI {
            crossings += 1;
        }
    }
    assert!(
        crossings > 0,
        "the heading never crosses ±π: the wrap is untested"
    );
    // The robot travels: more than 50 m of path over the bag.
    let path: f64 = poses
        .windows(2)
        .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
        .sum();
    assert!(path > 50.0, "path {path} m");
}

#[test]
fn standing_people_stand_still_in_odom_but_not_in_the_laser_frame() {
    let (Some(odom), Some(scans), Some(tfs), Some(truth)) = (
        bag_file("odom.txt"),
        bag_file("scans.txt"),
        bag_file("static_tf.txt"),
        bag_file("ground_truth_people.txt"),
    ) else {
        return;
    };
    let history = odometry_history(
        &read_odometry(odom).unwrap().records,
        OdomClock::HeaderStamp,
    )
    .unwrap();
    let scans = read_scans(scans).unwrap().records;
    let tfs = read_static_transforms(tfs).unwrap().records;
    let laser_to_base = static_chain(&tfs, "left_laser", "base_link").unwrap();
    let bag_times: Vec<f64> = scans.iter().map(|s| s.bag_time).collect();
    let assigned =
        truth_frames_for_scans(&bag_times, &read_ground_truth(truth).unwrap().records).unwrap();
    assert_eq!(assigned.unassigned, 0);

    // Positions per person (ids ≥ 1000 are the people who stand in the bag) in three ways.
    let mut odom_frame: BTreeMap<u64, Vec<Point2<f64>>> = BTreeMap::new();
    let mut laser_frame: BTreeMap<u64, Vec<Point2<f64>>> = BTreeMap::new();
    let mut no_mount: BTreeMap<u64, Vec<Point2<f64>>> = BTreeMap::new();
    for (scan, frame) in scans.iter().zip(&assigned.frames) {
        for &(id, p) in &frame.objects {
            let t = scan.scan.stamp;
            odom_frame
                .entry(id)
                .or_default()
                .push(history.to_world(t, &p, &laser_to_base).unwrap());
            laser_frame.entry(id).or_default().push(p);
            no_mount
                .entry(id)
                .or_default()
                .push(history.to_world(t, &p, &Isometry2::identity()).unwrap());
        }
    }
    let spread = |points: &[Point2<f64>]| {
        let mean = points
            .iter()
            .map(|p| p.coords)
            .sum::<nalgebra::Vector2<f64>>()
            / points.len() as f64;
        points
            .iter()
            .map(|p| (p.coords - mean).norm())
            .fold(0.0, f64::max)
    };
    let standing: Vec<u64> = odom_frame
        .iter()
        .filter(|(id, points)| **id >= 1000 && points.len() >= 5)
        .map(|(id, _)| *id)
        .collect();
    assert_eq!(standing, vec![1000, 1001, 1004, 1005, 1006]);
    for id in &standing {
        let s = spread(&odom_frame[id]);
        assert!(s < 0.45, "person {id} spreads {s} m in odom");
    }
    // The same people move in the laser frame, and without the mounting transform.
    let max_laser = standing
        .iter()
        .map(|id| spread(&laser_frame[id]))
        .fold(0.0, f64::max);
    let max_no_mount = standing
        .iter()
        .map(|id| spread(&no_mount[id]))
        .fold(0.0, f64::max);
    assert!(max_laser > 2.0, "laser-frame spread {max_laser} m");
    assert!(
        max_no_mount > 1.0,
        "spread without the mount {max_no_mount} m"
    );
}
