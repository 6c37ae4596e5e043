//! `clear_mot` against the `motmetrics` package and a port of `clear_mot.py`, on the seeded
//! synthetic scenario of `tests/fixtures/clear_mot_motmetrics.json` (written by
//! `benches/peers/motmetrics_fixture.py`).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use haunts_tracking::eval::mot::{ClearMot, ClearMotParams, Convention, Frame, clear_mot};
use nalgebra::Point2;
use serde_json::Value;

fn fixture() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/clear_mot_motmetrics.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn objects(list: &Value) -> Vec<(u64, Point2<f64>)> {
    list.as_array()
        .unwrap()
        .iter()
        .map(|o| {
            let o = o.as_array().unwrap();
            let id = o[0].as_u64().unwrap();
            (
                id,
                Point2::new(o[1].as_f64().unwrap(), o[2].as_f64().unwrap()),
            )
        })
        .collect()
}

fn frames(fixture: &Value) -> (Vec<Frame>, Vec<Frame>) {
    fixture["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let time = f["time"].as_f64().unwrap();
            (
                Frame::new(time, objects(&f["truth"])),
                Frame::new(time, objects(&f["hypotheses"])),
            )
        })
        .unzip()
}

fn count(v: &Value, key: &str) -> usize {
    usize::try_from(v[key].as_u64().expect(key)).unwrap()
}

fn assert_same(ours: &ClearMot, theirs: &Value) {
    assert_eq!(ours.frames, count(theirs, "num_frames"));
    assert_eq!(ours.ground_truth, count(theirs, "num_objects"));
    assert_eq!(ours.hypotheses, count(theirs, "num_predictions"));
    assert_eq!(ours.matches, count(theirs, "num_detections"));
    assert_eq!(
        ours.matches - ours.id_switches,
        count(theirs, "num_matches")
    );
    assert_eq!(ours.id_switches, count(theirs, "num_switches"));
    assert_eq!(ours.false_positives, count(theirs, "num_false_positives"));
    assert_eq!(ours.misses, count(theirs, "num_misses"));
    approx::assert_abs_diff_eq!(ours.mota, theirs["mota"].as_f64().unwrap(), epsilon = 1e-9);
    approx::assert_abs_diff_eq!(ours.motp, theirs["motp"].as_f64().unwrap(), epsilon = 1e-9);
}

#[test]
fn clear_mot_equals_motmetrics() {
    let fixture = fixture();
    let (truth, hyps) = frames(&fixture);
    assert_eq!(truth.len(), 200);
    let params = ClearMotParams::default()
        .with_match_threshold(fixture["match_threshold"].as_f64().unwrap());
    let ours = clear_mot(&truth, &hyps, &params).unwrap();
    assert_same(&ours, &fixture["motmetrics"]);
    // The scenario exercises every kind of error.
    assert!(ours.id_switches > 10 && ours.misses > 10 && ours.false_positives > 10);
}

#[test]
fn leg_tracker_convention_equals_clear_mot_py() {
    let fixture = fixture();
    let (truth, hyps) = frames(&fixture);
    let params = ClearMotParams::default()
        .with_match_threshold(fixture["match_threshold"].as_f64().unwrap())
        .with_convention(Convention::LegTrackerBenchmarks);
    let ours = clear_mot(&truth, &hyps, &params).unwrap();
    assert_same(&ours, &fixture["clear_mot_py"]);
    // The two conventions count switches differently on this scenario.
    assert_ne!(
        count(&fixture["clear_mot_py"], "num_switches"),
        count(&fixture["motmetrics"], "num_switches")
    );
}
