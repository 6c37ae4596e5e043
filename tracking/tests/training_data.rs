//! The clustering on `leg_tracker`'s own training set (`../shared/data/leg_tracker/training`):
//! every labelled leg's beam indices (found by `lp.py`, `leg_tracker`'s clustering in numpy)
//! are one of our clusters, and each file holds the number of clusters `counts.json` says.
//! Skipped with a notice when the data is absent; needs the `train` feature (the labels are
//! training input).
#![cfg(feature = "train")]
#![allow(clippy::unwrap_used)]

use haunts_tracking::detect::training::read_leg_labels;
use haunts_tracking::detect::{ClusterParams, clusters};
use haunts_tracking::read_scans;

use data::shared_data;
use haunts_test_support::data;

/// `(file stem, clusters at 0.13 m / 3 points)` from `counts.json`.
const COUNTS: [(&str, usize); 9] = [
    ("positive_1", 5368),
    ("positive_2", 2230),
    ("positive_3", 4908),
    ("positive_4", 7630),
    ("positive_6", 5458),
    ("positive_7", 7707),
    ("negative_2_left_scan", 13293),
    ("negative_2_rear_scan", 13001),
    ("negative_2_right_scan", 14158),
];

#[test]
fn our_clusters_are_leg_trackers_on_every_training_file() {
    let Some(dir) = shared_data("leg_tracker/training/text") else {
        return;
    };
    let params = ClusterParams::default();
    let (mut labels_checked, mut unmatched) = (0, 0);
    for (stem, count) in COUNTS {
        let scans = read_scans(dir.join(format!("{stem}.scans.txt.gz"))).unwrap();
        assert_eq!(scans.skipped, 0, "{stem}");
        let found: Vec<_> = scans
            .records
            .iter()
            .map(|s| clusters(&s.scan, &params).unwrap())
            .collect();
        let total: usize = found.iter().map(Vec::len).sum();
        assert_eq!(total, count, "{stem}: clusters");
        let legs = dir.join(format!("{stem}.legs.txt"));
        if !legs.exists() {
            continue;
        }
        let labels = read_leg_labels(&legs).unwrap();
        assert_eq!(labels.skipped, 0);
        for label in &labels.records {
            if label.indices.is_empty() {
                unmatched += 1;
                continue;
            }
            let scan = &found[label.scan_line];
            let cluster = scan
                .iter()
                .find(|c| c.indices == label.indices)
                .unwrap_or_else(|| {
                    panic!(
                        "{stem} line {}: no cluster {:?}",
                        label.scan_line, label.indices
                    )
                });
            assert!(
                (cluster.centroid() - label.position).norm() < 1e-4,
                "{stem}"
            );
            labels_checked += 1;
        }
    }
    // 1,852 labelled legs; one of them (positive_6) matched no cluster in the conversion.
    assert_eq!((labels_checked, unmatched), (1851, 1));
}
