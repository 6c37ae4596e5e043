//! The `day_artifact` fuzzer's inputs as tests: the seed corpus of `fuzz/seeds/day_artifact/`
//! (each with its expected outcome) and every crash input saved under
//! `tests/fuzz_regressions/` (named `day_artifact-<what broke>`), run through
//! `fuzz/common/artifact_check.rs`, the very code the target runs.
#![cfg(feature = "serde")]
#![allow(clippy::unwrap_used, clippy::panic)]

#[path = "../fuzz/common/artifact_check.rs"]
mod artifact_check;

use haunts::affordance::{DailyDensity, TimedPoint};
use haunts::artifact::{ArtifactError, Counts, DayArtifact};
use haunts::occupancy::{Grid, GridGeometry, OccupancyGrid};
use haunts::tracking::Trajectory;
use haunts_test_support::crate_files as files;
use nalgebra::Point2;

/// The artifact of the `ok-*` seeds: a 3 × 2-cell day with one track.
fn tiny() -> DayArtifact {
    let g = GridGeometry::new(0.5, Point2::new(-1.0, 0.0), 3, 2).unwrap();
    let map = OccupancyGrid::from_values(g, vec![0, 100, -1, 0, 0, 50]).unwrap();
    let density = DailyDensity::new(
        Grid::from_vec(g, vec![0, 1, 0, 0, 2, 0]).unwrap(),
        Grid::from_vec(g, vec![3, 4, 0, 1, 5, 0]).unwrap(),
        1,
    )
    .unwrap();
    DayArtifact {
        label: "tiny".into(),
        source: "tiny.mcap".into(),
        span: (100.0, 160.5),
        map,
        density,
        trajectories: vec![Trajectory {
            id: 7,
            samples: vec![
                (100.0, Point2::new(-0.5, 0.25)),
                (100.4, Point2::new(-0.25, 0.5)),
            ],
        }],
        tracked: vec![TimedPoint::new(100.0, -0.5, 0.25)],
        robot: vec![Point2::new(0.0, 0.5)],
        counts: Counts {
            scans: 10,
            skipped: 1,
            keyframes: 2,
            refused_matches: 0,
        },
        notes: vec!["a note".into()],
        alignment: None,
    }
}

/// `fuzz/seeds/day_artifact/` with the tiny artifact: `ok-file.bin` (byte 0 = 0, the whole
/// file), `ok-payload.bin` (byte 0 = 1, the JSON payload), `bad-checksum.bin`,
/// `bad-truncated.bin` and `bad-payload-nan.bin` (a map value the grid refuses, behind a valid
/// checksum). Run with `HAUNTS_WRITE_SEEDS=1` to write them again.
fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    let file = tiny().to_bytes();
    let payload = file[20..file.len() - 32].to_vec();
    let mut checksum = file.clone();
    let last = checksum.len() - 1;
    checksum[last] ^= 1;
    let text = String::from_utf8(payload.clone()).unwrap();
    let bad = text.replacen("\"resolution\":0.5", "\"resolution\":\"NaN\"", 1);
    assert_ne!(bad, text);
    [
        ("ok-file.bin", [vec![0], file.clone()].concat()),
        ("ok-payload.bin", [vec![1], payload].concat()),
        ("bad-checksum.bin", [vec![0], checksum].concat()),
        (
            "bad-truncated.bin",
            [vec![0], file[..file.len() - 40].to_vec()].concat(),
        ),
        ("bad-payload-nan.bin", [vec![1], bad.into_bytes()].concat()),
    ]
    .into()
}

#[test]
fn day_artifact_seeds_are_current_and_read_as_expected() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/day_artifact");
    let want = seeds();
    if std::env::var_os("HAUNTS_WRITE_SEEDS").is_some() {
        for (name, bytes) in &want {
            std::fs::write(dir.join(name), bytes).unwrap();
        }
    }
    let got = files!("fuzz/seeds/day_artifact");
    assert_eq!(got.keys().map(String::as_str).collect::<Vec<_>>(), {
        let mut names: Vec<&str> = want.iter().map(|(n, _)| *n).collect();
        names.sort_unstable();
        names
    });
    for (name, bytes) in &want {
        assert_eq!(
            &got[*name], bytes,
            "{name} is not current (HAUNTS_WRITE_SEEDS=1)"
        );
        let outcome = artifact_check::day_artifact(bytes);
        match *name {
            "ok-file.bin" | "ok-payload.bin" => assert_eq!(outcome.unwrap(), 1, "{name}"),
            "bad-checksum.bin" => assert!(matches!(outcome, Err(ArtifactError::Checksum { .. }))),
            "bad-truncated.bin" => assert!(matches!(outcome, Err(ArtifactError::Length { .. }))),
            _ => assert!(
                matches!(outcome, Err(ArtifactError::Payload { .. })),
                "{name}"
            ),
        }
    }
    // The whole file decodes to the artifact it was made from.
    let file = tiny().to_bytes();
    assert_eq!(
        DayArtifact::from_bytes(&file, std::path::Path::new("tiny")).unwrap(),
        tiny()
    );
}

/// Every saved crash input of the target replays without a panic.
#[test]
fn saved_crash_inputs_replay() {
    for (name, data) in files!("tests/fuzz_regressions") {
        if name.starts_with("day_artifact-") {
            let _ = artifact_check::day_artifact(&data);
        } else {
            panic!("{name}: not named after a target");
        }
    }
}
