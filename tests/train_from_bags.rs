//! The learned leg detector's training data read from robot logs (feature `train`):
//! `leg_tracker`'s training bags, read through `haunts-bag`, train the shipped forest byte for
//! byte, and hold the same rows as their text copies up to the copies' rounding; labels pair
//! with the scan that follows them, in a log written here.
//!
//! `cargo test --features train --test train_from_bags` (`.ci/run` runs it; about 40 s of
//! training in the dev profile; the real-data tests skip with a notice when `../shared/data`
//! is absent).
#![cfg(feature = "train")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use haunts::bag::McapWriter;
use haunts::bag::convert::laser_scan_msg;
use haunts::bag::msg::{Pose, PoseArray};
use haunts::occupancy::LaserScan;
use haunts::pipeline::PipelineError;
use haunts::tracking::detect::LegForest;
use haunts::tracking::detect::forest::train::{ForestParams, train_from_recordings};
use haunts::tracking::detect::training::{
    Recording, SampleParams, Samples, ScanLabels, read_training_dir,
};
use haunts::training::labelled_scans;
use haunts_test_support::data::shared_data;

/// The recordings of the shared training bags, in file-name order, with the messages
/// skipped and the scans without labels.
fn bag_recordings() -> Option<(Vec<Recording>, usize, usize)> {
    let dir = shared_data("leg_tracker/training/bags")?;
    let mut bags: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "bag"))
        .collect();
    bags.sort();
    let (mut recordings, mut skipped, mut unlabelled) = (Vec::new(), 0, 0);
    for bag in &bags {
        let log = labelled_scans(bag, None).unwrap();
        let positive = bag.to_string_lossy().contains("positive");
        assert_eq!(log.labels_topic.is_some(), positive, "{}", bag.display());
        skipped += log.skipped;
        unlabelled += log.unlabelled_scans;
        recordings.extend(log.recordings);
    }
    Some((recordings, skipped, unlabelled))
}

fn samples(recordings: &[Recording]) -> Samples {
    let mut s = Samples::default();
    for (k, (_, scans)) in recordings.iter().enumerate() {
        s.add(k, scans, &SampleParams::default()).unwrap();
    }
    s
}

#[test]
fn the_training_bags_train_the_shipped_model_bit_for_bit() {
    let Some((recordings, skipped, unlabelled)) = bag_recordings() else {
        return;
    };
    let names: Vec<&str> = recordings.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(
        names,
        [
            "negative_2_left_scan",
            "negative_2_rear_scan",
            "negative_2_right_scan",
            "positive_1_extracted",
            "positive_2_extracted",
            "positive_3_extracted",
            "positive_4_extracted",
            "positive_6_extracted",
            "positive_7_extracted",
        ]
    );
    // Every scan of a positive bag follows its labels; nothing is undecodable.
    assert_eq!((skipped, unlabelled), (0, 0));
    let trained = train_from_recordings(
        recordings,
        skipped,
        &SampleParams::default(),
        &ForestParams::default(),
    )
    .unwrap();
    // Every one of the 1,852 labels finds its cluster within 0.1 m; 40,040 clusters of the
    // rooms without people lie within 10 m.
    assert_eq!(trained.samples.legs.iter().filter(|&&l| l).count(), 1852);
    assert_eq!(trained.samples.len(), 41892);
    assert_eq!(trained.samples.unmatched_labels, 0);
    let cv = &trained.cross_validation;
    assert!(cv.auc > 0.9, "cross-validated AUC {}", cv.auc);
    let shipped = LegForest::shipped().unwrap();
    assert_eq!(trained.forest.threshold(), shipped.threshold());
    assert!(
        trained.forest.to_bytes() == include_bytes!("../tracking/models/leg_forest.bin"),
        "the model trained from the bags differs from tracking/models/leg_forest.bin"
    );
}

#[test]
fn the_text_copies_hold_the_bags_rows_up_to_their_rounding() {
    let (Some((bags, _, _)), Some(dir)) =
        (bag_recordings(), shared_data("leg_tracker/training/text"))
    else {
        return;
    };
    let (text, skipped) = read_training_dir(dir).unwrap();
    assert_eq!(skipped, 0);
    assert_eq!(text.len(), bags.len());
    for ((t, _), (b, _)) in text.iter().zip(&bags) {
        assert_eq!(*t, b.replace("_extracted", ""));
    }
    let (t, b) = (samples(&text), samples(&bags));
    assert_eq!(
        (t.len(), t.legs.clone(), t.origin.clone()),
        (b.len(), b.legs, b.origin)
    );
    // Ranges written to the millimetre (the laser's own resolution: the same numbers as the
    // bag's f32s to 1e-7 relative) and angles to 1e-9 rad: the features agree closely, and
    // exactly where they only count points. Per feature, the largest difference relative to
    // 1 + |value|: today 3.6e-4 for the circularity (a circle fitted to a nearly straight
    // cluster is ill-conditioned), 4.4e-5 for the radius, under 4e-6 for the others.
    let mut worst = [0.0_f64; haunts::tracking::detect::features::FEATURES];
    for (x, y) in t.features.iter().zip(&b.features) {
        assert_eq!(x[0], y[0], "number of points");
        for (w, (u, v)) in worst.iter_mut().zip(x.iter().zip(y)) {
            *w = w.max((u - v).abs() / (1.0 + u.abs()));
        }
    }
    let largest = worst.iter().copied().fold(0.0, f64::max);
    let shown: Vec<String> = worst.iter().map(|w| format!("{w:.1e}")).collect();
    eprintln!("largest differences per feature: {}", shown.join(" "));
    assert!(largest < 1e-3, "largest differences per feature: {worst:?}");
    assert!(
        largest > 0.0,
        "the copies are rounded: some feature should differ"
    );
}

/// A labelled log written here: labels, scan, scan with no labels before it, labels, scan.
#[test]
fn labels_go_to_the_scan_that_follows_them() {
    let dir = std::env::temp_dir().join(format!("haunts-train-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("walkers.mcap");
    let scan = |t: f64| {
        let ranges = vec![2.0, 2.0, 2.0, 0.0, 3.0, 3.0, 3.0, 3.0];
        laser_scan_msg(
            &LaserScan::new(t, 0.0, 0.01, 0.03, 11.0, ranges, vec![]).unwrap(),
            "laser",
        )
    };
    let legs = |xs: &[f64]| PoseArray {
        poses: xs
            .iter()
            .map(|&x| {
                let mut p = Pose::default();
                p.position.x = x;
                p
            })
            .collect(),
        ..PoseArray::default()
    };
    let mut w = McapWriter::create(&path).unwrap();
    w.write("/legs", 1.0, &legs(&[2.0])).unwrap();
    w.write("/scan", 1.0, &scan(1.0)).unwrap();
    w.write("/scan", 2.0, &scan(2.0)).unwrap();
    w.write("/legs", 3.0, &legs(&[3.0, f64::NAN])).unwrap();
    w.write("/scan", 3.1, &scan(3.1)).unwrap();
    w.finish().unwrap();

    let log = labelled_scans(&path, None).unwrap();
    assert_eq!(log.labels_topic.as_deref(), Some("/legs"));
    assert_eq!((log.skipped, log.unlabelled_scans), (0, 1));
    let [(name, scans)] = log.recordings.as_slice() else {
        panic!("one scan topic, one recording");
    };
    assert_eq!(name, "walkers");
    let xs: Vec<Vec<f64>> = scans
        .iter()
        .map(|s| match &s.labels {
            ScanLabels::Legs(l) => l.iter().map(|p| p.x).collect(),
            ScanLabels::NoPeople => panic!("a labelled log"),
        })
        .collect();
    // The NaN label is dropped; the scan at 2 s has no labels of its own.
    assert_eq!(xs, vec![vec![2.0], vec![], vec![3.0]]);
    assert!((scans[2].scan.stamp - 3.1).abs() < 1e-6);

    // Named as a label topic, a scan topic is refused for its type; two PoseArray topics
    // and none named is refused, naming both.
    assert!(matches!(
        labelled_scans(&path, Some("/scan")),
        Err(PipelineError::Bag(_))
    ));
    let two = dir.join("two.mcap");
    let mut w = McapWriter::create(&two).unwrap();
    w.write("/legs", 1.0, &legs(&[2.0])).unwrap();
    w.write("/more_legs", 1.0, &legs(&[2.0])).unwrap();
    w.write("/scan", 1.0, &scan(1.0)).unwrap();
    w.finish().unwrap();
    match labelled_scans(&two, None) {
        Err(PipelineError::LabelTopics { topics, .. }) => {
            assert_eq!(topics.len(), 2);
        }
        other => panic!("expected LabelTopics, got {other:?}"),
    }
    // Naming one of them reads it.
    let log = labelled_scans(&two, Some("/more_legs")).unwrap();
    assert_eq!(log.recordings[0].1.len(), 1);
    std::fs::remove_dir_all(&dir).ok();
}
