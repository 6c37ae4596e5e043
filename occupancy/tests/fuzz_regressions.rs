//! The fuzzers' inputs as tests: the committed seed corpora of `fuzz/seeds/` (each with
//! its expected outcome) and any crash input saved under `tests/fuzz_regressions/`.
//!
//! Inputs are exactly what the fuzz targets of `fuzz/fuzz_targets/` receive: YAML text for
//! `map_yaml`, CARMEN log bytes for `carmen`, and for `map_image` one configuration byte
//! followed by the image (see `fuzz/common/image_config.rs`). Regression files are named
//! `<target>-<short name>`.

#[path = "../../fuzz/common/image_config.rs"]
mod image_config;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use haunts_occupancy::carmen::{CarmenOptions, LaserKind, SkipReason, parse_carmen};
use haunts_occupancy::{
    LoadNote, MapLoadOptions, MapMetadata, MapMode, OccupancyError, PgmProblem, decode_map_image,
    parse_map_yaml,
};

use haunts_test_support::data::assert_same_names;
use haunts_test_support::{crate_files as files, fuzz_seeds as seeds};

// ------------------------------------------------------------------------------ map_yaml

const YAML_PATH: &str = "maps/seed.yaml";

fn yaml(
    bytes: &[u8],
    options: &MapLoadOptions,
) -> haunts_occupancy::Result<(MapMetadata, Vec<LoadNote>)> {
    let text = std::str::from_utf8(bytes).expect("YAML seeds are UTF-8");
    parse_map_yaml(text, Path::new(YAML_PATH), options)
}

fn strict() -> MapLoadOptions {
    {
        let mut p = MapLoadOptions::default();
        p.keep_yaw = true;
        p.default_free_thresh = None;
        p.default_negate = None;
        p
    }
}

fn defaulted(field: &'static str, value: &str) -> LoadNote {
    LoadNote::Defaulted {
        field,
        value: value.into(),
    }
}

fn metadata(
    image: &str,
    mode: MapMode,
    resolution: f64,
    origin: [f64; 3],
    negate: bool,
    (occupied_thresh, free_thresh): (f64, f64),
) -> MapMetadata {
    MapMetadata {
        image: PathBuf::from(image),
        mode,
        resolution,
        origin,
        negate,
        occupied_thresh,
        free_thresh,
    }
}

#[test]
fn map_yaml_seeds_give_their_expected_outcome() {
    type Check = fn(&[u8]);
    let expected: BTreeMap<&str, Check> = BTreeMap::from([
        (
            "ok-willow-2010-02-18-0.10.yaml",
            (|b: &[u8]| {
                let (m, notes) = yaml(b, &MapLoadOptions::default()).unwrap();
                assert_eq!(
                    m,
                    metadata(
                        "maps/willow-2010-02-18-0.10.pgm",
                        MapMode::Trinary,
                        0.1,
                        [0.0; 3],
                        false,
                        (0.65, 0.196)
                    )
                );
                assert_eq!(notes, vec![defaulted("mode", "trinary")]);
                // Every field the strict options need is in the file.
                assert_eq!(yaml(b, &strict()).unwrap().0, m);
            }) as Check,
        ),
        ("ok-y4_aaf-cropped.yaml", |b| {
            // free_thresh comes first, the other fields in alphabetical order.
            let (m, notes) = yaml(b, &MapLoadOptions::default()).unwrap();
            assert_eq!(
                m,
                metadata(
                    "maps/y4_aaf-cropped.pgm",
                    MapMode::Trinary,
                    0.05,
                    [-39.849999999999994, -77.95, 0.0],
                    false,
                    (0.65, 0.196)
                )
            );
            assert_eq!(notes, vec![defaulted("mode", "trinary")]);
            assert_eq!(yaml(b, &strict()).unwrap().0, m);
        }),
        ("ok-repeated.yaml", |b| {
            // An equal repetition is accepted and noted.
            let (m, notes) = yaml(b, &MapLoadOptions::default()).unwrap();
            assert_eq!(m.resolution, 0.05);
            assert_eq!(
                notes,
                vec![
                    LoadNote::RepeatedField {
                        field: "resolution".into(),
                        line: 7
                    },
                    defaulted("mode", "trinary"),
                ]
            );
        }),
        ("ok-full-scale.yaml", |b| {
            let (m, notes) = yaml(b, &MapLoadOptions::default()).unwrap();
            assert_eq!(
                m,
                metadata(
                    "/maps/full.png",
                    MapMode::Scale,
                    0.025,
                    [-10.5, 3.0, 0.0],
                    true,
                    (0.9, 0.1)
                )
            );
            assert!(notes.is_empty(), "{notes:?}");
        }),
        ("ok-raw-comments.yaml", |b| {
            let (m, notes) = yaml(b, &MapLoadOptions::default()).unwrap();
            // The comment after the image name is not part of it; the block list is read.
            assert_eq!(
                m,
                metadata(
                    "maps/raw.pgm",
                    MapMode::Raw,
                    1.0,
                    [1.0, -2.0, 0.0],
                    false,
                    (1.0, 0.0)
                )
            );
            assert_eq!(
                notes,
                vec![LoadNote::UnknownField {
                    field: "extra_field".into(),
                    line: 12
                }]
            );
        }),
        ("ok-minimal.yaml", |b| {
            let (m, notes) = yaml(b, &MapLoadOptions::default()).unwrap();
            assert_eq!(
                m,
                metadata(
                    "maps/m.pgm",
                    MapMode::Trinary,
                    0.05,
                    [0.0; 3],
                    false,
                    (0.65, 0.196)
                )
            );
            assert_eq!(
                notes,
                vec![
                    defaulted("free_thresh", "0.196"),
                    defaulted("negate", "false"),
                    defaulted("mode", "trinary"),
                ]
            );
        }),
        ("ok-yaw.yaml", |b| {
            let r = yaml(b, &MapLoadOptions::default());
            assert!(
                matches!(r, Err(OccupancyError::NonZeroYaw { yaw, .. }) if yaw == 0.5),
                "{r:?}"
            );
            let (m, _) = yaml(b, &strict()).unwrap();
            assert_eq!(m.origin, [1.0, 2.0, 0.5]);
        }),
        ("bad-syntax.yaml", |b| {
            let r = yaml(b, &MapLoadOptions::default());
            assert!(
                matches!(r, Err(OccupancyError::YamlSyntax { line: 2.., .. })),
                "{r:?}"
            );
        }),
        ("bad-not-a-mapping.yaml", |b| {
            let r = yaml(b, &MapLoadOptions::default());
            assert!(
                matches!(&r, Err(OccupancyError::InvalidField { field, .. }) if field == "(document)"),
                "{r:?}"
            );
        }),
        ("bad-conflicting.yaml", |b| {
            let r = yaml(b, &MapLoadOptions::default());
            assert!(
                matches!(&r, Err(OccupancyError::ConflictingField { field, line: 3, .. }) if field == "resolution"),
                "{r:?}"
            );
        }),
        ("bad-missing-image.yaml", |b| {
            let r = yaml(b, &MapLoadOptions::default());
            assert!(
                matches!(r, Err(OccupancyError::MissingField { field: "image", .. })),
                "{r:?}"
            );
        }),
        ("bad-origin.yaml", |b| {
            let r = yaml(b, &MapLoadOptions::default());
            assert!(
                matches!(&r, Err(OccupancyError::InvalidField { field, line: 3, value, .. })
                    if field == "origin" && value == "[0, nan, 0]"),
                "{r:?}"
            );
        }),
        ("bad-resolution.yaml", |b| {
            let r = yaml(b, &MapLoadOptions::default());
            assert!(
                matches!(&r, Err(OccupancyError::InvalidField { field, value, .. })
                    if field == "resolution" && value == "-0.05"),
                "{r:?}"
            );
        }),
        ("bad-thresholds.yaml", |b| {
            let r = yaml(b, &MapLoadOptions::default());
            assert!(
                matches!(&r, Err(OccupancyError::InvalidField { field, line: 5, .. }) if field == "free_thresh"),
                "{r:?}"
            );
        }),
    ]);
    let seeds = seeds!("map_yaml");
    assert_same_names(&seeds, &expected);
    for (name, bytes) in &seeds {
        println!("map_yaml seed {name}");
        expected[name.as_str()](bytes);
    }
}

// ----------------------------------------------------------------------------- map_image

fn image(input: &[u8]) -> haunts_occupancy::Result<haunts_occupancy::OccupancyGrid> {
    let (&config, bytes) = input.split_first().expect("a configuration byte");
    let (metadata, interpretation) = image_config::image_config(config);
    decode_map_image(bytes, &metadata, interpretation)
}

/// Width, height and values (row 0 = the image's bottom row) of a decoded seed.
fn decoded(input: &[u8]) -> (usize, usize, Vec<i8>) {
    let grid = image(input).unwrap();
    let g = grid.geometry();
    (g.width(), g.height(), grid.values().data().to_vec())
}

fn pgm_problem(input: &[u8]) -> PgmProblem {
    match image(input) {
        Err(OccupancyError::Pgm { problem, .. }) => problem,
        other => panic!("expected a PGM error, got {other:?}"),
    }
}

#[test]
fn map_image_seeds_give_their_expected_outcome() {
    type Check = fn(&[u8]);
    let expected: BTreeMap<&str, Check> = BTreeMap::from([
        // Pixels 0 205 254 / 255 100 10, thresholds 0.65 / 0.196: 205 (occ 0.19608) and 100
        // are between the thresholds.
        (
            "ok-p5-8bit-3x2-ros1-trinary",
            (|b: &[u8]| {
                assert_eq!(decoded(b), (3, 2, vec![0, -1, 100, 100, -1, 0]));
            }) as Check,
        ),
        // Nav2 scale: 128 → rint(100 · (0.49804 − 0.196) / 0.454) = 67; 205 → 0.
        ("ok-p2-8bit-3x2-nav2-scale", |b| {
            assert_eq!(decoded(b), (3, 2, vec![0, 100, 0, 100, 67, 0]));
        }),
        // 16-bit raw, samples scaled to 8 bits: 12850 → 50, 25700 → 100, 65535 → 255 (unknown).
        ("ok-p5-16bit-2x2-ros1-raw", |b| {
            assert_eq!(decoded(b), (2, 2, vec![-1, 100, 0, 50]));
        }),
        // maxval 1000, negated: occupancy = v / 1000.
        ("ok-p2-16bit-2x3-nav2-trinary-negate", |b| {
            assert_eq!(decoded(b), (2, 3, vec![0, -1, -1, 100, 0, 100]));
        }),
        // ROS 1 scale: 1 + 98 · ratio, truncated: 205 → 1, 128 → 66.
        ("ok-png-grey8-2x2-ros1-scale", |b| {
            assert_eq!(decoded(b), (2, 2, vec![1, 0, 100, 66]));
        }),
        // Nav2 scale: unknown unless fully opaque.
        ("ok-png-greyalpha8-2x1-nav2-scale", |b| {
            assert_eq!(decoded(b), (2, 1, vec![67, -1]));
        }),
        ("ok-png-rgb8-1x2-ros1-trinary", |b| {
            assert_eq!(decoded(b), (1, 2, vec![0, 100]));
        }),
        ("ok-png-rgba16-1x1-nav2-raw", |b| {
            assert_eq!(decoded(b), (1, 1, vec![0]));
        }),
        // A 4-bit palette (black, white) expanded to RGB.
        ("ok-png-palette4-2x1-ros1-trinary", |b| {
            assert_eq!(decoded(b), (2, 1, vec![100, 0]));
        }),
        ("bad-p5-truncated", |b| {
            assert_eq!(
                pgm_problem(b),
                PgmProblem::Truncated {
                    expected: 4,
                    found: 2
                }
            );
        }),
        // A header announcing 65535 × 65535 pixels with one byte of data is rejected before
        // any allocation of that size.
        ("bad-p5-huge-header-truncated", |b| {
            assert_eq!(
                pgm_problem(b),
                PgmProblem::Truncated {
                    expected: 65535 * 65535,
                    found: 1
                }
            );
        }),
        ("bad-p5-too-many-cells", |b| {
            assert_eq!(
                pgm_problem(b),
                PgmProblem::BadHeaderField { field: "width" }
            );
        }),
        ("bad-p2-pixel-above-maxval", |b| {
            assert_eq!(pgm_problem(b), PgmProblem::BadPixel { index: 1 });
        }),
        ("bad-p5-maxval", |b| {
            assert_eq!(
                pgm_problem(b),
                PgmProblem::MaxvalOutOfRange { maxval: 70000 }
            );
        }),
        ("bad-p6-unsupported", |b| {
            let r = image(b);
            assert!(
                matches!(r, Err(OccupancyError::UnsupportedImage { .. })),
                "{r:?}"
            );
        }),
        ("bad-png-crc", |b| {
            let r = image(b);
            assert!(matches!(r, Err(OccupancyError::Png { .. })), "{r:?}");
        }),
        ("bad-nan-resolution", |b| {
            let r = image(b);
            assert!(
                matches!(
                    r,
                    Err(OccupancyError::InvalidGeometry {
                        field: "resolution",
                        ..
                    })
                ),
                "{r:?}"
            );
        }),
    ]);
    let seeds = seeds!("map_image");
    assert_same_names(&seeds, &expected);
    for (name, bytes) in &seeds {
        println!("map_image seed {name}");
        expected[name.as_str()](bytes);
    }
}

// -------------------------------------------------------------------------------- carmen

fn carmen(bytes: &[u8]) -> haunts_occupancy::carmen::CarmenLog {
    parse_carmen(bytes, &CarmenOptions::default()).expect("reading memory cannot fail")
}

#[test]
fn carmen_seeds_give_their_expected_outcome() {
    type Check = fn(&[u8]);
    let expected: BTreeMap<&str, Check> = BTreeMap::from([
        (
            "ok-intel-head.log",
            (|b: &[u8]| {
                let log = carmen(b);
                assert_eq!(
                    (log.scans.len(), log.odometry.len(), log.skipped),
                    (1, 4, 0)
                );
                let s = &log.scans[0];
                assert_eq!((s.kind, s.line, s.scan.len()), (LaserKind::Front, 8, 180));
                assert_eq!(s.scan.stamp, 32.9068);
                assert_eq!(
                    log.other_messages,
                    BTreeMap::from([("#".into(), 2), ("NEFF".into(), 1), ("PARAM".into(), 2)])
                );
            }) as Check,
        ),
        ("ok-csail-flaser.log", |b| {
            let log = carmen(b);
            assert_eq!(
                (log.scans.len(), log.odometry.len(), log.skipped),
                (2, 5, 0)
            );
            assert!(
                log.scans
                    .iter()
                    .all(|s| s.scan.len() == 361 && s.kind == LaserKind::Front)
            );
            // 361 beams: half-degree steps over 180°.
            assert!(
                (log.scans[0].scan.angle_increment - std::f64::consts::PI / 360.0).abs() < 1e-15
            );
            // 39 of the first scan's readings are at 81.91 m: max-range, no endpoint.
            assert_eq!(log.scans[0].scan.endpoints().count(), 361 - 39);
        }),
        ("ok-rlaser.log", |b| {
            let log = carmen(b);
            assert_eq!(log.skipped, 0, "{:?}", log.first_skipped);
            let lens: Vec<_> = log.scans.iter().map(|s| (s.kind, s.scan.len())).collect();
            // A zero-beam scan is accepted.
            assert_eq!(lens, vec![(LaserKind::Rear, 3), (LaserKind::Rear, 0)]);
        }),
        ("ok-robotlaser1.log", |b| {
            let log = carmen(b);
            assert_eq!(log.skipped, 0, "{:?}", log.first_skipped);
            let shape: Vec<_> = log
                .scans
                .iter()
                .map(|s| {
                    (
                        s.kind,
                        s.scan.len(),
                        s.scan.intensities.len(),
                        s.scan.range_max,
                    )
                })
                .collect();
            assert_eq!(
                shape,
                vec![
                    (LaserKind::Robot, 4, 4, 30.0),
                    (LaserKind::Robot, 3, 0, 81.9)
                ]
            );
        }),
        ("ok-odom.log", |b| {
            let log = carmen(b);
            // Poses, stamps and velocities must be finite: the NaN/inf velocity line is skipped.
            assert_eq!((log.odometry.len(), log.skipped), (1, 1));
            assert_eq!(log.first_skipped[0].reason, SkipReason::NonFinite);
            assert_eq!(log.odometry[0].stamp, 15.0);
        }),
        ("bad-lines.log", |b| {
            let log = carmen(b);
            assert!(log.scans.is_empty() && log.odometry.is_empty());
            assert_eq!(log.other_messages, BTreeMap::from([("SYNC".into(), 1)]));
            let reasons: Vec<_> = log
                .first_skipped
                .iter()
                .map(|s| (s.line, s.message.as_str(), s.reason.clone()))
                .collect();
            assert_eq!(
                reasons,
                vec![
                    (
                        1,
                        "FLASER",
                        SkipReason::TooFewFields {
                            expected: 4,
                            found: 3
                        }
                    ),
                    (2, "FLASER", SkipReason::BadNumber { field: 0 }),
                    (3, "FLASER", SkipReason::NonFinite),
                    (
                        4,
                        "ODOM",
                        SkipReason::TooFewFields {
                            expected: 3,
                            found: 2
                        }
                    ),
                    (5, "ROBOTLASER1", SkipReason::BadScan),
                    (7, "?", SkipReason::NotText),
                ]
            );
            assert_eq!(log.skipped, 6);
        }),
    ]);
    let seeds = seeds!("carmen");
    assert_same_names(&seeds, &expected);
    for (name, bytes) in &seeds {
        println!("carmen seed {name}");
        expected[name.as_str()](bytes);
    }
}

// ------------------------------------------------------------------- every input, every parser

/// Feeds one input to the function its target fuzzes; only a panic fails.
fn feed(target: &str, bytes: &[u8]) {
    match target {
        "map_yaml" => {
            if let Ok(text) = std::str::from_utf8(bytes) {
                for options in [MapLoadOptions::default(), strict()] {
                    let _ = parse_map_yaml(text, Path::new(YAML_PATH), &options);
                }
            }
        }
        "map_image" => {
            if !bytes.is_empty() {
                let _ = image(bytes);
            }
        }
        "carmen" => {
            parse_carmen(bytes, &CarmenOptions::default()).expect("reading memory cannot fail");
        }
        other => panic!("unknown fuzz target `{other}`"),
    }
}

const TARGETS: [&str; 3] = ["map_yaml", "map_image", "carmen"];

const REGRESSIONS: &str = "tests/fuzz_regressions";

/// Runs the check `check` on the saved input `name` in a child copy of this test binary
/// (the `child` test below), so that an abort — a failed allocation of terabytes is an
/// abort, not a panic — fails only the calling test, with the child's output, instead of
/// killing every test of this binary.
fn in_child(check: &str, name: &str) {
    if let Err(e) = try_in_child(check, name) {
        panic!("{e}");
    }
}

/// [`in_child`], returning the failure instead of panicking.
fn try_in_child(check: &str, name: &str) -> Result<(), String> {
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "child",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("HAUNTS_FUZZ_CHILD", format!("{check}:{name}"))
        .output()
        .unwrap();
    if out.status.success() {
        return Ok(());
    }
    Err(format!(
        "{check} on {REGRESSIONS}/{name} failed ({}):\n{}{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    ))
}

/// The child side of [`in_child`]; does nothing unless `HAUNTS_FUZZ_CHILD` is set.
#[test]
#[ignore = "run by `in_child` in a child process"]
fn child() {
    let Ok(job) = std::env::var("HAUNTS_FUZZ_CHILD") else {
        return;
    };
    let (check, name) = job.split_once(':').unwrap();
    let bytes = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(REGRESSIONS)
            .join(name),
    )
    .unwrap();
    match check {
        "feed" => {
            let target = TARGETS
                .iter()
                .find(|t| name.starts_with(&format!("{t}-")))
                .unwrap_or_else(|| {
                    panic!("{name}: name must start with one of {TARGETS:?} and `-`")
                });
            feed(target, &bytes);
        }
        // A PNG whose header announces more than memory can hold is an error.
        "png-too-large" => {
            let r = image(&bytes);
            assert!(
                matches!(
                    r,
                    Err(OccupancyError::Png { .. }
                        | OccupancyError::BadGridSize { .. }
                        | OccupancyError::GridTooLarge { .. })
                ),
                "{r:?}"
            );
        }
        // A PNG whose palette is not whole RGB entries is an error.
        "png-bad-palette" => {
            let r = image(&bytes);
            let text = format!("{r:?}");
            assert!(
                matches!(r, Err(OccupancyError::Png { .. })) && text.contains("palette"),
                "{text}"
            );
        }
        other => panic!("unknown check `{other}`"),
    }
}

/// Every input saved from the fuzzers returns (Ok or Err) without panicking or aborting.
#[test]
fn saved_fuzz_inputs_do_not_panic() {
    let failures: Vec<String> = files!(REGRESSIONS)
        .keys()
        .filter_map(|name| try_in_child("feed", name).err())
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// Fuzz crash (map_image, 48 bytes): a PNG whose IHDR announces 3401 × 1207959554 RGB
/// pixels, with no pixel data. `decode_png_raster` allocated the whole 12 TB output buffer
/// (`vec![0; size]`, picture.rs) before reading any data: an abort ("memory allocation of
/// 12324811329462 bytes failed"). It must be a typed error.
#[test]
fn png_header_announcing_terabytes_is_an_error_not_an_abort() {
    in_child("png-too-large", "map_image-png-huge-ihdr");
}

/// The same with 65535 × 65535 RGBA 16-bit pixels: fewer cells than `u32::MAX` (what a grid
/// may hold), yet a 34 GB buffer for a 48-byte file; a check of the cell count alone does
/// not fix it.
#[test]
fn png_header_announcing_34_gb_is_an_error_not_an_abort() {
    in_child("png-too-large", "map_image-png-huge-ihdr-under-u32-cells");
}

/// Fuzz crash (map_image, found by `fuzz/ci.sh` in CI, 2026-12-07): a palette PNG whose
/// `PLTE` chunk holds 134 bytes (44 RGB entries and two bytes over) panicked inside the `png`
/// crate (0.18.1, `decoder/transform/palette.rs`: "range end index 3 out of range for slice
/// of length 2") when it expanded the indices. Saved here as a minimal file with valid CRCs
/// (the fuzz build skips CRC checks, a normal build does not). It must be a typed error.
#[test]
fn png_palette_of_partial_entries_is_an_error_not_a_panic() {
    in_child("png-bad-palette", "map_image-png-palette-not-whole-entries");
}

/// Found by review, confirmed with the fuzz build (the 5-minute run did not reach it): a
/// beam count near `usize::MAX` overflows `from + n` in `Fields::ranges` (carmen.rs), a
/// panic with overflow checks; without them the sum wraps, the field check passes and the
/// FLASER line is accepted as a scan of 0 beams with a wrong pose. Such lines must be
/// skipped as too short, and the lines after them read.
#[test]
fn carmen_beam_count_near_usize_max_is_skipped_not_an_overflow() {
    let bytes = &files!(REGRESSIONS)["carmen-count-overflow"];
    let log = carmen(bytes);
    assert!(log.scans.is_empty(), "{:?}", log.scans);
    assert_eq!((log.skipped, log.odometry.len()), (2, 1));
    let skipped: Vec<_> = log
        .first_skipped
        .iter()
        .map(|s| (s.line, s.message.as_str()))
        .collect();
    assert_eq!(skipped, vec![(1, "FLASER"), (2, "ROBOTLASER1")]);
    assert!(
        log.first_skipped
            .iter()
            .all(|s| matches!(s.reason, SkipReason::TooFewFields { .. })),
        "{:?}",
        log.first_skipped
    );
}

/// Every seed, fed to every parser (also the other targets' seeds): no panic.
#[test]
fn every_seed_through_every_parser() {
    for from in TARGETS {
        for (name, bytes) in seeds!(from) {
            for to in TARGETS {
                println!("{from}/{name} → {to}");
                feed(to, &bytes);
            }
        }
    }
}
