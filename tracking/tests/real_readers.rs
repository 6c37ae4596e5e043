//! The readers on the real data of `../shared/data` (skipped with a notice when absent).
//! Expected counts were taken independently with `awk` over the same files.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeSet;

use haunts_tracking::{
    EthOptions, read_eth, read_ground_truth, read_odometry, read_scans, read_static_transforms,
};

use data::shared_data;
use haunts_test_support::data;

const BAG: &str = "leg_tracker/general_tracking_moving_1";

#[test]
fn scans_of_the_moving_bag() {
    let Some(path) = shared_data(&format!("{BAG}/scans.txt")) else {
        return;
    };
    let scans = read_scans(path).unwrap();
    assert_eq!((scans.records.len(), scans.skipped), (873, 0));
    assert!(scans.records.iter().all(|s| s.scan.len() == 768));
    assert!(scans.records.iter().all(|s| s.frame == "left_laser"));
    assert!(
        scans
            .records
            .windows(2)
            .all(|w| w[0].bag_time <= w[1].bag_time)
    );
    let span = scans.records[872].scan.stamp - scans.records[0].scan.stamp;
    assert!((110.0..120.0).contains(&span), "span {span} s");
}

#[test]
fn ground_truth_of_the_moving_bag() {
    let Some(path) = shared_data(&format!("{BAG}/ground_truth_people.txt")) else {
        return;
    };
    let truth = read_ground_truth(path).unwrap();
    assert_eq!((truth.records.len(), truth.skipped), (153, 0));
    let people: BTreeSet<u64> = truth.records.iter().map(|p| p.id).collect();
    assert_eq!(people.len(), 12);
}

#[test]
fn odometry_and_static_transforms_of_the_moving_bag() {
    let (Some(odom), Some(tf)) = (
        shared_data(&format!("{BAG}/odom.txt")),
        shared_data(&format!("{BAG}/static_tf.txt")),
    ) else {
        return;
    };
    let odom = read_odometry(odom).unwrap();
    assert_eq!((odom.records.len(), odom.skipped), (11561, 0));
    let tf = read_static_transforms(tf).unwrap();
    assert_eq!((tf.records.len(), tf.skipped), (1, 0));
    assert_eq!(tf.records[0].parent, "base_link");
    assert_eq!(tf.records[0].child, "left_laser");
}

/// (sequence, rows, distinct ids, inferred frame rate in Hz).
const ETH: [(&str, usize, usize, f64); 2] =
    [("seq_eth", 8908, 360, 15.0), ("seq_hotel", 6544, 390, 25.0)];

#[test]
fn eth_sequences() {
    for (sequence, rows, ids, rate) in ETH {
        let Some(path) = shared_data(&format!("trajectories/eth/{sequence}/obsmat.txt")) else {
            return;
        };
        let inferred = read_eth(&path, &EthOptions::default()).unwrap();
        assert_eq!(inferred.skipped, 0, "{sequence}");
        assert_eq!(inferred.records.len(), ids, "{sequence}");
        let samples: usize = inferred.records.iter().map(|t| t.samples.len()).sum();
        assert_eq!(samples, rows, "{sequence}");
        let fixed = read_eth(&path, &EthOptions::default().with_frame_rate(rate)).unwrap();
        assert_eq!(inferred, fixed, "{sequence}");
        // Consecutive samples of one person are mostly one annotation step (0.4 s) apart.
        let steps: Vec<f64> = inferred
            .records
            .iter()
            .flat_map(|t| t.samples.windows(2).map(|w| w[1].0 - w[0].0))
            .collect();
        let regular = steps.iter().filter(|&&d| (d - 0.4).abs() < 1e-6).count();
        assert!(
            regular * 10 > steps.len() * 9,
            "{sequence}: {regular}/{}",
            steps.len()
        );
    }
}
