//! The `leg_tracker` and `trajectory` fuzzers' inputs as tests: the seed corpora of
//! `fuzz/seeds/leg_tracker/` and `fuzz/seeds/trajectory/` (each with its expected outcome)
//! and every crash input saved under `tests/fuzz_regressions/` (named `<target>-<what
//! broke>`), run through `fuzz/common/text_check.rs`, the very code the fuzz targets run
//! (byte 0 of an input picks the reader and its options).

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

/// Every saved crash input of the two targets replays without a panic.
#[test]
fn saved_crash_inputs_replay() {
    for (name, data) in files!("tests/fuzz_regressions") {
        if name.starts_with("leg_tracker-") {
            text_check::leg_tracker(&data);
        } else if name.starts_with("trajectory-") {
            text_check::trajectory(&data);
        } else {
            panic!("{name}: not named after a target");
        }
    }
}
