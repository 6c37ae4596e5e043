//! The hypertime model on two real days of people detections (`../shared/data/people/`,
//! skipped with a notice when absent): trained on 25 May 2017, it predicts 26 May better than
//! the time-independent baseline. Every third detection is used so the test stays quick in the
//! debug profile; the example runs on all of them.
#![allow(clippy::unwrap_used)]

use haunts_affordance::hypertime::{
    DetectionColumns, HypertimeModel, HypertimeParams, TimedPoint, grid_log_likelihood,
    read_detections,
};
use haunts_occupancy::GridGeometry;

mod common;
use common::shared_data;

fn every_third(points: Vec<TimedPoint>) -> Vec<TimedPoint> {
    points.into_iter().step_by(3).collect()
}

#[test]
fn hypertime_beats_the_static_baseline_on_the_next_day() {
    let (Some(train), Some(test)) = (
        shared_data("people/2017_05_25.txt"),
        shared_data("people/2017_05_26.txt"),
    ) else {
        return;
    };
    let columns = DetectionColumns::default().with_columns(0, 1, 2);
    let train = read_detections(train, &columns).unwrap();
    let test = read_detections(test, &columns).unwrap();
    // Counts taken with `wc -l` and `awk '{print NF}'`: every line has six fields.
    assert_eq!((train.records.len(), train.skipped), (34_429, 0));
    assert_eq!((test.records.len(), test.skipped), (22_449, 0));
    let (train, test) = (every_third(train.records), every_third(test.records));

    let params = HypertimeParams::default();
    let model = HypertimeModel::fit(&train, &params).unwrap();
    let baseline = HypertimeModel::fit(&train, &params.clone().without_time()).unwrap();
    assert_eq!((model.clusters(), baseline.clusters()), (30, 30));
    let grid =
        GridGeometry::bounding(train.iter().chain(&test).map(|p| p.position), 0.25, 1.0).unwrap();
    let ht = grid_log_likelihood(&model, &test, &grid, 300.0).unwrap();
    let st = grid_log_likelihood(&baseline, &test, &grid, 300.0).unwrap();
    assert_eq!((ht.used, ht.outside, ht.skipped), (test.len(), 0, 0));
    let (ht, st) = (ht.mean().unwrap(), st.mean().unwrap());
    eprintln!("hypertime {ht:.4}, static {st:.4} nats per detection");
    assert!(ht > st, "hypertime {ht} <= static {st}");
}
