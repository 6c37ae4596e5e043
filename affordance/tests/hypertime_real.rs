//! The hypertime model on two real days of people detections (`../shared/data/people/`,
//! skipped with a notice when absent), with the default settings: trained on one day, it
//! predicts the other at least as well as the time-independent baseline, both in both
//! directions and both above the uniform density over the training area. Every choice
//! (floor, background weight) is made on held-out hours of the training day.
#![allow(clippy::unwrap_used)]

use haunts_affordance::hypertime::{
    DAY, EvaluationParams, HypertimeModel, HypertimeParams, evaluate,
};
use haunts_occupancy::GridGeometry;

mod common;
use common::stroll_day;

#[test]
fn hypertime_beats_the_static_baseline_on_the_next_day() {
    let (Some(d25), Some(d26)) = (stroll_day("25"), stroll_day("26")) else {
        return;
    };
    // Counts taken with `wc -l` and `awk '{print NF}'`: every line has six fields.
    assert_eq!((d25.records.len(), d25.skipped), (34_429, 0));
    assert_eq!((d26.records.len(), d26.skipped), (22_449, 0));
    for (train, test) in [(&d25.records, &d26.records), (&d26.records, &d25.records)] {
        let params = HypertimeParams::default();
        let model = HypertimeModel::fit(train, &params).unwrap();
        let baseline = HypertimeModel::fit(train, &params.clone().without_time()).unwrap();
        assert_eq!((model.clusters(), baseline.clusters()), (30, 30));
        // One day cannot check the daily period: kept as given, and reported so.
        assert_eq!(model.periods(), &[DAY]);
        assert!(model.report().selection.no_period_validated());
        let grid = GridGeometry::bounding(train.iter().map(|p| p.position), 0.25, 1.0).unwrap();
        let eval = EvaluationParams::default();
        let ht = evaluate(&model, test, &grid, &eval).unwrap();
        let st = evaluate(&baseline, test, &grid, &eval).unwrap();
        assert_eq!(ht.loglik.used + ht.loglik.outside, test.len());
        let (h, s) = (ht.mean().unwrap(), st.mean().unwrap());
        eprintln!(
            "hypertime {h:.4}, static {s:.4}, uniform {:.4} nats per detection",
            ht.uniform_loglik
        );
        assert!(h >= s, "hypertime {h} < static {s}");
        assert!(s >= st.uniform_loglik);
    }
}
