//! The shipped leg forest is what `train_leg_detector` makes from `leg_tracker`'s training
//! set with the default parameters, byte for byte (feature `train`; skipped with a notice
//! when `../shared/data` is absent). About 40 s: five cross-validation trainings and the
//! final one, on 41,892 rows.
#![cfg(feature = "train")]
#![allow(clippy::unwrap_used)]

use haunts_tracking::detect::forest::LegForest;
use haunts_tracking::detect::forest::train::{ForestParams, train_from_dir};
use haunts_tracking::detect::training::SampleParams;

use data::shared_data;
use haunts_test_support::data;

#[test]
fn retraining_reproduces_the_shipped_model_bit_for_bit() {
    let Some(dir) = shared_data("leg_tracker/training/text") else {
        return;
    };
    let trained = train_from_dir(&dir, &SampleParams::default(), &ForestParams::default()).unwrap();
    assert_eq!(trained.recordings.len(), 9);
    assert_eq!(trained.skipped_lines, 0);
    // Every one of the 1,852 labels finds its cluster within 0.1 m (the converter's 1e-4 m
    // missed one); 40,040 clusters of the rooms without people lie within 10 m.
    assert_eq!(trained.samples.legs.iter().filter(|&&l| l).count(), 1852);
    assert_eq!(trained.samples.len(), 41892);
    let cv = &trained.cross_validation;
    assert!(cv.auc > 0.9, "cross-validated AUC {}", cv.auc);
    let shipped = LegForest::shipped().unwrap();
    assert_eq!(trained.forest.threshold(), shipped.threshold());
    assert!(
        trained.forest.to_bytes() == include_bytes!("../models/leg_forest.bin"),
        "retrained model differs from tracking/models/leg_forest.bin"
    );
}
