//! The hypertime model on two real days of people detections (`../shared/data/people/`,
//! skipped with a notice when absent), with the default settings: trained on one day, it
//! predicts the other at least as well as the time-independent baseline, both in both
//! directions and both above the uniform density over the training area; the uniform weight
//! it fits is smaller than on the drifting synthetic site of `hypertime_drift.rs`. Every choice
//! (floor, background weight) is made on held-out hours of the training day.
#![allow(clippy::unwrap_used)]

use haunts_affordance::hypertime::{
    DAY, EvaluationParams, HypertimeModel, HypertimeParams, evaluate,
};
use haunts_occupancy::GridGeometry;

mod common;
use common::{drifting_day, stroll_day};

#[test]
fn hypertime_beats_the_static_baseline_on_the_next_day() {
    let (Some(d25), Some(d26)) = (stroll_day("25"), stroll_day("26")) else {
        return;
    };
    // Counts taken with `wc -l` and `awk '{print NF}'`: every line has six fields.
    assert_eq!((d25.records.len(), d25.skipped), (34_429, 0));
    assert_eq!((d26.records.len(), d26.skipped), (22_449, 0));
    // The uniform weights fitted here, for the comparison with the drifting site below.
    let mut shared_u: Vec<f64> = Vec::new();
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
        shared_u.extend([
            model.report().uniform_weight,
            baseline.report().uniform_weight,
        ]);
    }
    // Issue 45: where the training day's last part differs from its first (people drifting
    // from room to room, `tests/hypertime_drift.rs`), the fitted uniform weight is larger than
    // on these days, for both models.
    let train = drifting_day(17_000, &[0, 1, 2, 3], 400, 1);
    for params in [
        HypertimeParams::default(),
        HypertimeParams::default().without_time(),
    ] {
        let u = HypertimeModel::fit(&train, &params)
            .unwrap()
            .report()
            .uniform_weight;
        eprintln!("uniform weight: drifting site {u}, shared days {shared_u:?}");
        assert!(shared_u.iter().all(|&s| u > s), "{u} vs {shared_u:?}");
    }
}
