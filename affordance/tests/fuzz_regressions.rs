//! The `detections` and `layout_library` fuzzers' inputs as tests: the seed corpora of
//! `fuzz/seeds/detections/` and `fuzz/seeds/layout_library/` (each with its expected outcome)
//! and every crash input saved under `tests/fuzz_regressions/` (named `<target>-<what
//! broke>`), run through `fuzz/common/affordance_check.rs`, the very code the targets run.

#[path = "../../fuzz/common/affordance_check.rs"]
mod affordance_check;

use std::collections::BTreeMap;

use haunts_affordance::AffordanceError;
use haunts_affordance::layout::file::LibraryFileProblem;
use haunts_test_support::data::assert_same_names;
use haunts_test_support::{crate_files as files, fuzz_seeds as seeds};

#[test]
fn detections_seeds_read_as_expected() {
    // (records, skipped lines)
    let expected = BTreeMap::from([
        ("bad-people-nan-inf.txt", (0, 3)),
        ("ok-people-semicolon.txt", (4, 0)),
        ("ok-people.txt", (8, 0)),
    ]);
    let seeds = seeds!("detections");
    assert_same_names(&seeds, &expected);
    for (name, data) in &seeds {
        assert_eq!(
            affordance_check::detections(data),
            expected[name.as_str()],
            "{name}"
        );
    }
}

#[test]
fn layout_library_seeds_read_as_expected() {
    let seeds = seeds!("layout_library");
    let expected: BTreeMap<&str, ()> = [
        "bad-checksum.bin",
        // Issue 49: an origin at 1e300 (beyond GridGeometry::MAX_ORIGIN) behind a valid checksum.
        "bad-payload-origin-1e300.bin",
        // Issue 49: a resolution of 1e308 behind a valid checksum (it once looped `haunts maps`).
        "bad-payload-resolution-1e308.bin",
        "bad-truncated.bin",
        "ok-file.bin",
        "ok-payload.bin",
    ]
    .into_iter()
    .map(|n| (n, ()))
    .collect();
    assert_same_names(&seeds, &expected);
    for (name, data) in &seeds {
        let got = affordance_check::layout_library(data);
        if name.starts_with("ok-") {
            assert_eq!(got.as_ref().ok(), Some(&1), "{name}: {got:?}");
        } else {
            assert!(
                matches!(got, Err(AffordanceError::CorruptLibrary { path: None, .. })),
                "{name}: {got:?}"
            );
        }
    }
    let far = affordance_check::layout_library(&seeds["bad-payload-origin-1e300.bin"]);
    let far = format!("{:?}", far.unwrap_err());
    assert!(far.contains("MAX_ORIGIN"), "{far}");
    let checksum = affordance_check::layout_library(&seeds["bad-checksum.bin"]);
    assert!(
        matches!(
            checksum,
            Err(AffordanceError::CorruptLibrary {
                problem: LibraryFileProblem::ChecksumMismatch,
                ..
            })
        ),
        "{checksum:?}"
    );
}

/// Every saved crash input of the two targets replays without a panic.
#[test]
fn saved_crash_inputs_replay() {
    for (name, data) in files!("tests/fuzz_regressions") {
        if name.starts_with("detections-") {
            affordance_check::detections(&data);
        } else if name.starts_with("layout_library-") {
            let _ = affordance_check::layout_library(&data);
        } else {
            panic!("{name}: not named after a target");
        }
    }
}
