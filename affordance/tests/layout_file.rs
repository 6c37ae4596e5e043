//! Saving and loading the layout library: round trips, corrupt and newer files refused with
//! the right problem, and saves that a crash cannot spoil.

use haunts_affordance::AffordanceError;
use haunts_affordance::density::DailyDensity;
use haunts_affordance::layout::file::{FORMAT_VERSION, LibraryFileProblem, MAGIC};
use haunts_affordance::layout::{LayoutLibrary, LayoutParams};
use haunts_occupancy::{Cell, FREE, Grid, GridGeometry, OCCUPIED, OccupancyGrid};
use haunts_similarity::{ClusterParams, DifferenceParams, LayoutThreshold, Length, Symmetrisation};
use nalgebra::Point2;
use proptest::prelude::*;
use sha2::{Digest, Sha256};

/// Bytes before the payload (magic, version, payload length), as the module docs lay out.
const HEADER_LEN: usize = 20;
/// Bytes of the SHA-256 checksum after the payload.
const CHECKSUM_LEN: usize = 32;

/// A small library with two layouts and three days.
fn small_library() -> LayoutLibrary {
    let g = GridGeometry::new(0.1, Point2::new(-0.35, 1.25), 16, 9).unwrap();
    // 9 rows moved by 13 cells make 117 cells²: a new layout above 50.
    let params = LayoutParams::default()
        .with_cluster(ClusterParams::default().with_threshold(LayoutThreshold::Cells(50.0)));
    let mut lib = LayoutLibrary::new(g, params).unwrap();
    // The room seen whole (free), a wall along column `col`.
    let wall = |col: usize| {
        let mut m = OccupancyGrid::from_grid(Grid::filled(g, FREE)).unwrap();
        for row in 0..9 {
            m.set(Cell::new(col, row), OCCUPIED);
        }
        m
    };
    let day = |k: u32| {
        DailyDensity::new(
            Grid::from_fn(g, |c| (c.col as u32 * k) % 5),
            Grid::from_fn(g, |c| c.row as u32 + k),
            1,
        )
        .unwrap()
    };
    lib.ingest("2015-01-13", &wall(1), &day(1)).unwrap();
    lib.ingest("2015-02-17", &wall(14), &day(2)).unwrap();
    lib.ingest("día 3 ☕", &wall(2), &day(3)).unwrap();
    assert_eq!(lib.layouts().len(), 2);
    lib
}

fn problem(result: haunts_affordance::Result<LayoutLibrary>) -> LibraryFileProblem {
    match result {
        Err(AffordanceError::CorruptLibrary { problem, .. }) => problem,
        other => panic!("expected a corrupt-library error, got {other:?}"),
    }
}

/// `bytes` with its payload replaced and the header and checksum made consistent again.
fn reseal(bytes: &[u8], edit: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut payload = bytes[HEADER_LEN..bytes.len() - CHECKSUM_LEN].to_vec();
    edit(&mut payload);
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&payload);
    out.extend_from_slice(&Sha256::digest(&payload));
    out
}

#[test]
fn a_saved_library_loads_back_equal() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layouts.hlib");
    let lib = small_library();
    lib.save(&path).unwrap();
    let back = LayoutLibrary::load(&path).unwrap();
    assert_eq!(back, lib);
    assert_eq!(std::fs::read(&path).unwrap(), lib.to_bytes());
    // Saving again over the file replaces it.
    let mut more = lib.clone();
    let map = back.layouts()[1]
        .composite()
        .occupied_counts()
        .map(|c| if *c > 0 { OCCUPIED } else { -1 });
    let map = OccupancyGrid::from_grid(map).unwrap();
    let g = *lib.geometry();
    more.ingest(
        "again",
        &map,
        &DailyDensity::new(Grid::filled(g, 0), Grid::filled(g, 1), 1).unwrap(),
    )
    .unwrap();
    more.save(&path).unwrap();
    assert_eq!(LayoutLibrary::load(&path).unwrap(), more);
    // Nothing but the library is left in the directory.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn the_header_is_as_documented() {
    let bytes = small_library().to_bytes();
    assert_eq!(&bytes[..8], &MAGIC);
    assert_eq!(&bytes[8..12], &FORMAT_VERSION.to_le_bytes());
    let n = u64::from_le_bytes(bytes[12..20].try_into().unwrap()) as usize;
    assert_eq!(bytes.len(), HEADER_LEN + n + CHECKSUM_LEN);
    assert_eq!(
        &bytes[HEADER_LEN + n..],
        Sha256::digest(&bytes[HEADER_LEN..HEADER_LEN + n]).as_slice()
    );
    // The payload opens with the geometry's resolution.
    assert_eq!(&bytes[20..28], &0.1f64.to_le_bytes());
}

#[test]
fn every_truncation_is_refused() {
    let bytes = small_library().to_bytes();
    for len in 0..bytes.len() {
        let p = problem(LayoutLibrary::from_bytes(&bytes[..len]));
        assert!(
            matches!(p, LibraryFileProblem::Truncated { found, .. } if found == len as u64),
            "length {len}: {p:?}"
        );
    }
}

#[test]
fn every_flipped_bit_is_refused() {
    let bytes = small_library().to_bytes();
    for i in 0..bytes.len() {
        let mut corrupt = bytes.clone();
        corrupt[i] ^= 1 << (i % 8);
        let p = problem(LayoutLibrary::from_bytes(&corrupt));
        let expected = match i {
            0..8 => matches!(p, LibraryFileProblem::BadMagic),
            8..12 => matches!(p, LibraryFileProblem::UnsupportedVersion { .. }),
            12..20 => matches!(
                p,
                LibraryFileProblem::Truncated { .. } | LibraryFileProblem::TrailingBytes { .. }
            ),
            _ => p == LibraryFileProblem::ChecksumMismatch,
        };
        assert!(expected, "byte {i}: {p:?}");
    }
}

#[test]
fn a_newer_version_is_refused_by_name() {
    let mut bytes = small_library().to_bytes();
    bytes[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    let p = problem(LayoutLibrary::from_bytes(&bytes));
    assert_eq!(
        p,
        LibraryFileProblem::UnsupportedVersion {
            found: FORMAT_VERSION + 1,
            supported: FORMAT_VERSION
        }
    );
    let newer = format!("version {}", FORMAT_VERSION + 1);
    assert!(p.to_string().contains(&newer), "{p}");
    bytes[8..12].copy_from_slice(&0u32.to_le_bytes());
    assert!(matches!(
        problem(LayoutLibrary::from_bytes(&bytes)),
        LibraryFileProblem::UnsupportedVersion { found: 0, .. }
    ));
}

#[test]
fn other_files_and_extra_bytes_are_refused() {
    assert_eq!(
        problem(LayoutLibrary::from_bytes(b"P5\n3 2\n255\n")),
        LibraryFileProblem::BadMagic
    );
    let mut bytes = small_library().to_bytes();
    bytes.push(0);
    let p = problem(LayoutLibrary::from_bytes(&bytes));
    assert!(
        matches!(p, LibraryFileProblem::TrailingBytes { expected, found } if found == expected + 1)
    );
}

#[test]
fn a_malformed_payload_with_a_valid_checksum_names_the_field() {
    let bytes = small_library().to_bytes();
    type Edit = Box<dyn Fn(&mut Vec<u8>)>;
    // A bad geometry's `what` is a part of its reason (`LibraryFileProblem::InvalidGeometry`).
    let cases: [(Edit, &str, usize); 13] = [
        (
            Box::new(|p: &mut Vec<u8>| p[0..8].copy_from_slice(&(-0.1f64).to_le_bytes())),
            "`resolution` = -0.1",
            HEADER_LEN,
        ),
        // Issue 49: a resolution of 1e308 (finite, so the checksum and the old rule passed it)
        // sent `haunts maps` into a loop over an infinite extent.
        (
            Box::new(|p: &mut Vec<u8>| p[0..8].copy_from_slice(&1e308f64.to_le_bytes())),
            "`resolution` = 1e308",
            HEADER_LEN,
        ),
        // An origin at 1e300: every cell's corner the same number (GridGeometry::MAX_ORIGIN).
        (
            Box::new(|p: &mut Vec<u8>| p[8..16].copy_from_slice(&1e300f64.to_le_bytes())),
            "`origin.x` = 1e300",
            HEADER_LEN,
        ),
        (
            Box::new(|p: &mut Vec<u8>| p[32] = 9),
            "unknown cutoff unit",
            HEADER_LEN + 32,
        ),
        (
            Box::new(|p: &mut Vec<u8>| p[41] = 7),
            "unknown threshold kind",
            HEADER_LEN + 41,
        ),
        (
            Box::new(|p: &mut Vec<u8>| p[50] = 4),
            "unknown symmetrisation",
            HEADER_LEN + 50,
        ),
        (
            Box::new(|p: &mut Vec<u8>| p[51..59].copy_from_slice(&0.0f64.to_le_bytes())),
            "invalid parameters",
            HEADER_LEN + 32,
        ),
        (
            Box::new(|p: &mut Vec<u8>| {
                let n = p.len();
                p.truncate(n - 1);
            }),
            "visit sums",
            0,
        ),
        (
            Box::new(|p: &mut Vec<u8>| p.push(0)),
            "bytes left over after the last layout",
            0,
        ),
        (
            // The day count says one more day than the layouts hold.
            Box::new(|p: &mut Vec<u8>| p[64..72].copy_from_slice(&4u64.to_le_bytes())),
            "the layouts do not hold every ingested day",
            0,
        ),
        (
            // The first day's id is 3, not below the day count.
            Box::new(|p: &mut Vec<u8>| p[80..88].copy_from_slice(&3u64.to_le_bytes())),
            "day id repeated or not below the day count",
            HEADER_LEN + 80,
        ),
        (
            // A label byte that is not UTF-8.
            Box::new(|p: &mut Vec<u8>| p[92] = 0xff),
            "label is not UTF-8",
            HEADER_LEN + 92,
        ),
        (
            // Version 2's observed-only flag, after the min visits.
            Box::new(|p: &mut Vec<u8>| p[63] = 2),
            "observed only is neither 0 nor 1",
            HEADER_LEN + 63,
        ),
    ];
    for (edit, what, offset) in cases {
        let p = problem(LayoutLibrary::from_bytes(&reseal(&bytes, edit)));
        let o = match &p {
            LibraryFileProblem::Malformed { offset: o, what: w } => {
                assert_eq!(*w, what);
                *o
            }
            LibraryFileProblem::InvalidGeometry { offset: o, reason } => {
                assert!(reason.contains(what), "{what}: {reason}");
                assert!(p.to_string().contains("invalid grid geometry"), "{p}");
                *o
            }
            other => panic!("{what}: {other:?}"),
        };
        if offset > 0 {
            assert_eq!(o, offset, "{what}");
        }
    }
}

#[test]
fn a_leftover_temporary_file_does_not_affect_loading() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layouts.hlib");
    let lib = small_library();
    lib.save(&path).unwrap();
    // What a save killed half-way through its write leaves behind.
    let half = lib.to_bytes();
    std::fs::write(
        dir.path().join(".layouts.hlib.tmp-4242-0"),
        &half[..half.len() / 2],
    )
    .unwrap();
    assert_eq!(LayoutLibrary::load(&path).unwrap(), lib);
    lib.save(&path).unwrap();
    assert_eq!(LayoutLibrary::load(&path).unwrap(), lib);
}

#[test]
fn a_failed_save_keeps_the_previous_file_and_io_errors_name_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layouts.hlib");
    let lib = small_library();
    lib.save(&path).unwrap();
    // A directory where the file should be renamed to: the rename fails, the old file in the
    // parent is untouched, and no temporary file is left.
    let blocked = dir.path().join("blocked");
    std::fs::create_dir(&blocked).unwrap();
    std::fs::write(blocked.join("inside"), b"x").unwrap();
    match lib.save(&blocked) {
        Err(AffordanceError::Io { path: p, .. }) => assert_eq!(p, blocked),
        other => panic!("{other:?}"),
    }
    assert_eq!(LayoutLibrary::load(&path).unwrap(), lib);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    // A missing directory and a missing file are I/O errors, not panics.
    assert!(matches!(
        lib.save(dir.path().join("no/such/dir/layouts.hlib")),
        Err(AffordanceError::Io { .. })
    ));
    match LayoutLibrary::load(dir.path().join("absent.hlib")) {
        Err(AffordanceError::Io { operation, .. }) => assert_eq!(operation, "read"),
        other => panic!("{other:?}"),
    }
    // A corrupt file names its path.
    let corrupt = dir.path().join("corrupt.hlib");
    std::fs::write(&corrupt, b"HAUNTLIB").unwrap();
    match LayoutLibrary::load(&corrupt) {
        Err(e @ AffordanceError::CorruptLibrary { .. }) => {
            assert!(e.to_string().contains("corrupt.hlib"), "{e}");
        }
        other => panic!("{other:?}"),
    }
}

fn params() -> impl Strategy<Value = LayoutParams> {
    (
        prop_oneof![
            (0.0..20.0f64).prop_map(Length::Cells),
            (0.0..1.0f64).prop_map(Length::Metres)
        ],
        prop_oneof![
            (0.0..3000.0f64).prop_map(LayoutThreshold::Cells),
            (0.0..5.0f64).prop_map(LayoutThreshold::SquareMetres),
            (0.0..5.0f64).prop_map(LayoutThreshold::PerOccupiedCell)
        ],
        prop_oneof![
            Just(Symmetrisation::Max),
            Just(Symmetrisation::Mean),
            Just(Symmetrisation::Min),
            Just(Symmetrisation::Sum)
        ],
        0.01..=1.0f64,
        1u32..4,
    )
        .prop_map(
            |(cutoff, threshold, symmetrisation, fraction, min_visits)| {
                LayoutParams::default()
                    .with_difference(DifferenceParams::default().with_cutoff(cutoff))
                    .with_cluster(
                        ClusterParams::default()
                            .with_threshold(threshold)
                            .with_symmetrisation(symmetrisation),
                    )
                    .with_composite_min_fraction(fraction)
                    .with_min_visits(min_visits)
            },
        )
}

/// A day: per cell an occupancy value (−1, 0 or 100), hits and visits.
fn days(cells: usize) -> impl Strategy<Value = Vec<Vec<(i8, u32, u32)>>> {
    let cell = (
        prop_oneof![Just(-1i8), Just(0), Just(100)],
        0u32..5,
        0u32..5,
    );
    prop::collection::vec(prop::collection::vec(cell, cells), 1..6)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn small_libraries_round_trip_bit_for_bit(
        (w, h, days) in (2usize..7, 2usize..7).prop_flat_map(|(w, h)| (Just(w), Just(h), days(w * h))),
        params in params(),
        res in prop_oneof![Just(0.05), Just(0.1), Just(0.3)],
        ox in -10.0..10.0f64,
    ) {
        let g = GridGeometry::new(res, Point2::new(ox, -ox / 3.0), w, h).unwrap();
        let mut lib = LayoutLibrary::new(g, params).unwrap();
        for (i, day) in days.iter().enumerate() {
            let mut values: Vec<i8> = day.iter().map(|c| c.0).collect();
            let n = values.len();
            values[i % n] = 100; // at least one occupied cell
            let map = OccupancyGrid::from_values(g, values).unwrap();
            let hits = Grid::from_vec(g, day.iter().map(|c| c.1).collect()).unwrap();
            let visits = Grid::from_vec(g, day.iter().map(|c| c.2).collect()).unwrap();
            lib.ingest(format!("day {i}"), &map, &DailyDensity::new(hits, visits, 1).unwrap()).unwrap();
        }
        let bytes = lib.to_bytes();
        let back = LayoutLibrary::from_bytes(&bytes).unwrap();
        prop_assert_eq!(&back, &lib);
        prop_assert_eq!(back.to_bytes(), bytes);
    }
}

/// Names of the temporary files beside `path`.
fn temporaries(path: &std::path::Path) -> Vec<String> {
    let prefix = format!(".{}.tmp-", path.file_name().unwrap().to_string_lossy());
    std::fs::read_dir(path.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&prefix))
        .collect()
}

/// Not a test: the child process of the test below (run only when it sets
/// `HAUNTS_SAVE_FOREVER`), saving a large library to that path until it is killed.
#[test]
#[ignore = "the child process of a_killed_save_leaves_a_temporary_that_the_next_save_or_load_removes"]
fn save_forever_child() {
    let Some(path) = std::env::var_os("HAUNTS_SAVE_FOREVER") else {
        return;
    };
    let g = GridGeometry::new(0.05, Point2::origin(), 700, 700).unwrap();
    let mut lib = LayoutLibrary::new(g, LayoutParams::default()).unwrap();
    let mut map = OccupancyGrid::unknown(g);
    for row in 0..700 {
        map.set(Cell::new(3, row), OCCUPIED);
        map.set(Cell::new(4, row), FREE);
    }
    let day = DailyDensity::new(Grid::filled(g, 1), Grid::filled(g, 2), 1).unwrap();
    lib.ingest("big", &map, &day).unwrap();
    loop {
        lib.save(&path).unwrap();
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_killed_save_leaves_a_temporary_that_the_next_save_or_load_removes() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layouts.hlib");
    let lib = small_library();
    // A live process's temporary is never touched (process 1 always runs).
    let live = dir.path().join(".layouts.hlib.tmp-1-0");
    std::fs::write(&live, b"in progress").unwrap();
    for round in 0..2 {
        // `kill -9` the child while a temporary file of its save exists; a kill that lands
        // between two saves leaves none, so try again.
        let mut orphan = None;
        for _ in 0..20 {
            let mut child = Command::new(std::env::current_exe().unwrap())
                .args(["--exact", "save_forever_child", "--ignored", "--nocapture"])
                .env("HAUNTS_SAVE_FOREVER", &path)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            let mine = format!(".layouts.hlib.tmp-{}-", child.id());
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(120)
                && !temporaries(&path).iter().any(|n| n.starts_with(&mine))
            {
                std::thread::sleep(Duration::from_millis(2));
            }
            child.kill().unwrap(); // SIGKILL
            child.wait().unwrap(); // reaped: its process id is no longer running
            orphan = temporaries(&path)
                .into_iter()
                .find(|n| n.starts_with(&mine));
            if orphan.is_some() {
                break;
            }
        }
        let orphan = dir
            .path()
            .join(orphan.expect("no save was caught half-way in 20 kills"));
        assert!(orphan.exists());
        if round == 0 {
            // A load removes it (whatever the target holds: a complete library or none).
            let _ = LayoutLibrary::load(&path);
        } else {
            lib.save(&path).unwrap();
            assert_eq!(LayoutLibrary::load(&path).unwrap(), lib);
        }
        assert!(!orphan.exists(), "round {round}: {orphan:?} left behind");
        assert_eq!(temporaries(&path), vec![".layouts.hlib.tmp-1-0".to_owned()]);
    }
    assert!(live.exists());
}

/// A version 1 file (written before `observed_only`) loads, with the whole-map comparison
/// it was built with; the same library written now is version 2 and keeps the flag.
#[test]
fn a_version_1_file_loads_with_whole_map_comparison() {
    let lib = small_library();
    assert!(lib.params().observed_only);
    let v2 = lib.to_bytes();
    assert_eq!(&v2[8..12], &2u32.to_le_bytes());
    // Version 1: the same payload without the flag byte (payload offset 63).
    let mut v1 = reseal(&v2, |p| {
        p.remove(63);
    });
    v1[8..12].copy_from_slice(&1u32.to_le_bytes());
    let back = LayoutLibrary::from_bytes(&v1).unwrap();
    assert!(!back.params().observed_only);
    assert_eq!(back.layouts().len(), lib.layouts().len());
    assert_eq!(back.day_count(), lib.day_count());
    assert!(
        LayoutLibrary::from_bytes(&v2)
            .unwrap()
            .params()
            .observed_only
    );
}
