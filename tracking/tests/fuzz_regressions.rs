//! The `leg_tracker`, `trajectory` and `scene_map` fuzzers' inputs as tests: the seed corpora
//! of `fuzz/seeds/leg_tracker/`, `fuzz/seeds/trajectory/` and `fuzz/seeds/scene_map/` (each
//! with its expected outcome) and every crash input saved under `tests/fuzz_regressions/`
//! (named `<target>-<what broke>`), run through `fuzz/common/text_check.rs` and
//! `fuzz/common/scene_check.rs`, the very code the fuzz targets run (byte 0 of a text input
//! picks the reader and its options).

#[path = "../../fuzz/common/scene_check.rs"]
mod scene_check;
#[path = "../../fuzz/common/text_check.rs"]
mod text_check;

use std::collections::BTreeMap;

use haunts_test_support::data::assert_same_names;
use haunts_test_support::{crate_files as files, fuzz_seeds as seeds};

#[test]
fn leg_tracker_seeds_read_as_expected() {
    // (records, skipped lines)
    let expected = BTreeMap::from([
        ("bad-ground-truth-nan.txt", (0, 2)),
        ("bad-scans-count.txt", (0, 1)),
        ("ok-ground-truth.txt", (5, 0)),
        ("ok-odom.txt", (5, 0)),
        ("ok-scans.txt", (3, 0)),
        ("ok-static-tf.txt", (1, 0)),
    ]);
    let seeds = seeds!("leg_tracker");
    assert_same_names(&seeds, &expected);
    for (name, data) in &seeds {
        assert_eq!(
            text_check::leg_tracker(data),
            expected[name.as_str()],
            "{name}"
        );
    }
}

#[test]
fn trajectory_seeds_read_as_expected() {
    // (trajectories, samples, skipped lines)
    let expected = BTreeMap::from([
        ("bad-delimited-columns.txt", (0, 0, 2)),
        ("ok-delimited.csv", (2, 3, 0)),
        ("ok-eth-obsmat-25hz.txt", (5, 8, 0)),
        ("ok-eth-obsmat.txt", (2, 8, 0)),
    ]);
    let seeds = seeds!("trajectory");
    assert_same_names(&seeds, &expected);
    for (name, data) in &seeds {
        assert_eq!(
            text_check::trajectory(data),
            expected[name.as_str()],
            "{name}"
        );
    }
}

#[test]
fn scene_map_seeds_read_as_expected() {
    // (walls, poles, cells marked on the check's 40 × 30 grid), or refused.
    let expected = BTreeMap::from([
        ("bad-nan.xml", None),
        ("bad-no-radius.xml", None),
        // The wall from the origin to 1e300 crosses 28 cells; the pole fills all 1200.
        ("ok-absurd.xml", Some((1, 1, 1200))),
        ("ok-seq-eth.xml", Some((4, 0, 36))),
        ("ok-seq-hotel.xml", Some((4, 3, 10))),
    ]);
    let seeds = seeds!("scene_map");
    assert_same_names(&seeds, &expected);
    for (name, data) in &seeds {
        let got = scene_check::scene_map(data).expect("UTF-8 seeds");
        match expected[name.as_str()] {
            Some(want) => assert_eq!(got.ok(), Some(want), "{name}"),
            None => assert!(
                matches!(got, Err(haunts_tracking::TrackingError::SceneMap { .. })),
                "{name}: {got:?}"
            ),
        }
    }
}

/// Every saved crash input of the three targets replays without a panic.
#[test]
fn saved_crash_inputs_replay() {
    for (name, data) in files!("tests/fuzz_regressions") {
        if name.starts_with("leg_tracker-") {
            text_check::leg_tracker(&data);
        } else if name.starts_with("trajectory-") {
            text_check::trajectory(&data);
        } else if name.starts_with("scene_map-") {
            let _ = scene_check::scene_map(&data);
        } else {
            panic!("{name}: not named after a target");
        }
    }
}
