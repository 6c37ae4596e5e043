//! Tests of map loading and saving on small synthetic files.

use super::*;
use crate::{Cell, CellState};
use proptest::prelude::*;

fn write_map(dir: &Path, yaml: &str, pgm: &[u8]) -> PathBuf {
    std::fs::write(dir.join("m.pgm"), pgm).unwrap();
    let p = dir.join("m.yaml");
    std::fs::write(&p, yaml).unwrap();
    p
}

const YAML: &str = "image: m.pgm\nresolution: 0.5\norigin: [1.0, -2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

fn load_with(yaml: &str, pgm: &[u8], options: &MapLoadOptions) -> Result<LoadedMap> {
    let dir = tempfile::tempdir().unwrap();
    load_map(write_map(dir.path(), yaml, pgm), options)
}

#[test]
fn image_is_flipped_so_row_0_is_the_bottom() {
    // Top image row: black (occupied), white (free); bottom row: grey 205 (unknown), white.
    let map = load_with(
        YAML,
        b"P5 2 2 255\n\x00\xfe\xcd\xfe",
        &MapLoadOptions::default(),
    )
    .unwrap();
    let g = &map.grid;
    assert_eq!(g.geometry().origin(), Point2::new(1.0, -2.0));
    assert_eq!(g.state(Cell::new(0, 1)), Some(CellState::Occupied));
    assert_eq!(g.state(Cell::new(1, 1)), Some(CellState::Free));
    assert_eq!(g.state(Cell::new(0, 0)), Some(CellState::Unknown));
    assert!(
        map.notes
            .iter()
            .any(|n| matches!(n, LoadNote::Defaulted { field: "mode", .. }))
    );
}

#[test]
fn scale_and_raw_modes_differ_between_ros1_and_nav2() {
    // occ = (255 - p) / 255 for p = 128: 0.498; ratio = (0.498 - 0.196) / 0.454 = 0.6653.
    let yaml = YAML.replace("negate: 0", "negate: 0\nmode: scale");
    let pgm = b"P5 1 1 255\n\x80";
    let ros1 = load_with(&yaml, pgm, &MapLoadOptions::default()).unwrap();
    let nav2 = load_with(
        &yaml,
        pgm,
        &MapLoadOptions {
            interpretation: Interpretation::Nav2,
            ..Default::default()
        },
    )
    .unwrap();
    let ratio: f64 = ((255.0 - 128.0) / 255.0 - 0.196) / (0.65 - 0.196);
    assert_eq!(
        ros1.grid.value(Cell::new(0, 0)),
        Some((1.0 + 98.0 * ratio) as i8)
    );
    assert_eq!(
        nav2.grid.value(Cell::new(0, 0)),
        Some((100.0 * ratio).round() as i8)
    );
    assert_ne!(
        ros1.grid.value(Cell::new(0, 0)),
        nav2.grid.value(Cell::new(0, 0))
    );

    // Raw with negate: ROS 1 negates (255 - 200 = 55), Nav2 ignores negate (200 > 100: unknown).
    let yaml = YAML.replace("negate: 0", "negate: 1\nmode: raw");
    let pgm = b"P5 2 1 255\n\xc8\x28";
    let ros1 = load_with(&yaml, pgm, &MapLoadOptions::default()).unwrap();
    let nav2 = load_with(
        &yaml,
        pgm,
        &MapLoadOptions {
            interpretation: Interpretation::Nav2,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(ros1.grid.values().data(), &[55, UNKNOWN]);
    assert_eq!(nav2.grid.values().data(), &[UNKNOWN, 40]);
}

#[test]
fn sixteen_bit_images_are_read() {
    let map = load_with(
        YAML,
        b"P5 2 1 65535\n\x00\x00\xff\xff",
        &MapLoadOptions::default(),
    )
    .unwrap();
    assert_eq!(map.grid.values().data(), &[100, 0]);
}

#[test]
fn repeated_fields_are_accepted_when_equal_and_rejected_when_not() {
    let pgm = b"P5 1 1 255\n\xfe";
    let yaml = format!("{YAML}free_thresh: 0.196\n");
    let map = load_with(&yaml, pgm, &MapLoadOptions::default()).unwrap();
    assert!(map.notes.contains(&LoadNote::RepeatedField {
        field: "free_thresh".into(),
        line: 7
    }));
    let yaml = format!("{YAML}free_thresh: 0.25\n");
    let r = load_with(&yaml, pgm, &MapLoadOptions::default());
    assert!(
        matches!(r, Err(OccupancyError::ConflictingField { line: 7, .. })),
        "{r:?}"
    );
}

#[test]
fn bad_yaml_fields_name_the_field_and_line() {
    let pgm = b"P5 1 1 255\n\xfe";
    let cases = [
        ("resolution: 0.5", "resolution: -0.5", "resolution", 2),
        ("resolution: 0.5", "resolution: abc", "resolution", 2),
        (
            "origin: [1.0, -2.0, 0.0]",
            "origin: [1.0, nan, 0.0]",
            "origin",
            3,
        ),
        (
            "origin: [1.0, -2.0, 0.0]",
            "origin: [1.0, 2.0]",
            "origin",
            3,
        ),
        ("negate: 0", "negate: 2", "negate", 4),
        ("free_thresh: 0.196", "free_thresh: 0.9", "free_thresh", 6),
    ];
    for (from, to, field, expected_line) in cases {
        let r = load_with(&YAML.replace(from, to), pgm, &MapLoadOptions::default());
        match r {
            Err(OccupancyError::InvalidField { field: f, line, .. }) => {
                assert_eq!((f.as_str(), line), (field, expected_line));
            }
            other => panic!("{to}: expected InvalidField, got {other:?}"),
        }
    }
    let r = load_with(
        &YAML.replace("image: m.pgm\n", ""),
        pgm,
        &MapLoadOptions::default(),
    );
    assert!(matches!(
        r,
        Err(OccupancyError::MissingField { field: "image", .. })
    ));
    let strict = MapLoadOptions {
        default_free_thresh: None,
        ..Default::default()
    };
    let r = load_with(&YAML.replace("free_thresh: 0.196\n", ""), pgm, &strict);
    assert!(matches!(
        r,
        Err(OccupancyError::MissingField {
            field: "free_thresh",
            ..
        })
    ));
    let r = load_with("image: [m.pgm", pgm, &MapLoadOptions::default());
    assert!(matches!(r, Err(OccupancyError::YamlSyntax { .. })), "{r:?}");
}

#[test]
fn a_default_free_thresh_is_checked_when_used() {
    let yaml = YAML.replace("free_thresh: 0.196\n", "");
    let pgm = b"P5 1 1 255\n\xfe";
    let options = MapLoadOptions {
        default_free_thresh: Some(0.7),
        ..Default::default()
    };
    let r = load_with(&yaml, pgm, &options);
    assert!(
        matches!(
            r,
            Err(OccupancyError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "default_free_thresh",
                    ..
                }
            ))
        ),
        "{r:?}"
    );
    let map = load_with(&yaml, pgm, &MapLoadOptions::default()).unwrap();
    assert_eq!(map.metadata.free_thresh, 0.196);
    assert!(map.notes.contains(&LoadNote::Defaulted {
        field: "free_thresh",
        value: "0.196".into()
    }));
}

#[test]
fn yaw_is_an_error_unless_kept() {
    let yaml = YAML.replace("0.0]", "0.3]");
    let pgm = b"P5 1 1 255\n\xfe";
    let r = load_with(&yaml, pgm, &MapLoadOptions::default());
    assert!(matches!(r, Err(OccupancyError::NonZeroYaw { yaw, .. }) if yaw == 0.3));
    let kept = load_with(
        &yaml,
        pgm,
        &MapLoadOptions {
            keep_yaw: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(kept.metadata.origin[2], 0.3);
}

#[test]
fn missing_and_truncated_images_are_typed_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.yaml");
    std::fs::write(&p, YAML).unwrap();
    let r = load_map(&p, &MapLoadOptions::default());
    assert!(
        matches!(&r, Err(OccupancyError::Io { path, .. }) if path.ends_with("m.pgm")),
        "{r:?}"
    );
    let r = load_with(YAML, b"P5 4 4 255\n\x00", &MapLoadOptions::default());
    assert!(matches!(
        r,
        Err(OccupancyError::Pgm {
            problem: crate::PgmProblem::Truncated { .. },
            ..
        })
    ));
    let r = load_with(YAML, b"GIF89a", &MapLoadOptions::default());
    assert!(matches!(r, Err(OccupancyError::UnsupportedImage { .. })));
}

#[test]
fn relative_images_resolve_against_the_yaml_folder() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("img")).unwrap();
    std::fs::write(dir.path().join("img/m.pgm"), b"P5 1 1 255\n\x00").unwrap();
    let p = dir.path().join("m.yaml");
    std::fs::write(&p, YAML.replace("image: m.pgm", "image: img/m.pgm")).unwrap();
    let map = load_map(&p, &MapLoadOptions::default()).unwrap();
    assert_eq!(map.metadata.image, dir.path().join("img/m.pgm"));
    assert_eq!(map.grid.values().data(), &[100]);
}

#[test]
fn thresholds_that_cannot_round_trip_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let g = GridGeometry::new(0.1, Point2::origin(), 1, 1).unwrap();
    let grid = OccupancyGrid::unknown(g);
    let options = MapSaveOptions {
        free_thresh: 0.0,
        ..Default::default()
    };
    let r = save_map(dir.path().join("m.yaml"), &grid, &options);
    assert!(matches!(
        r,
        Err(OccupancyError::InvalidParameter(
            haunts_core::InvalidParameter { .. }
        ))
    ));
    let options = MapSaveOptions {
        mode: MapMode::Scale,
        ..Default::default()
    };
    assert!(save_map(dir.path().join("m.yaml"), &grid, &options).is_err());
}

fn arb_grid() -> impl Strategy<Value = OccupancyGrid> {
    (1usize..12, 1usize..12, -50i32..50, -50i32..50, 1u32..20).prop_flat_map(|(w, h, ox, oy, r)| {
        proptest::collection::vec(prop_oneof![Just(-1i8), 0i8..=100], w * h).prop_map(move |v| {
            let res = f64::from(r) * 0.025;
            let origin = Point2::new(f64::from(ox) * 0.1, f64::from(oy) * 0.1);
            OccupancyGrid::from_values(GridGeometry::new(res, origin, w, h).unwrap(), v).unwrap()
        })
    })
}

proptest! {
    #[test]
    fn saving_and_reloading_gives_the_same_grid(
        grid in arb_grid(),
        free in 0.01f64..0.4,
        gap in 0.05f64..0.5,
    ) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("map.yaml");
        for interpretation in [Interpretation::Ros1, Interpretation::Nav2] {
            let load = MapLoadOptions { interpretation, ..Default::default() };
            let trinary = MapSaveOptions { free_thresh: free, occupied_thresh: (free + gap).min(0.95), ..Default::default() };
            save_map(&path, &grid, &trinary).unwrap();
            let back = load_map(&path, &load).unwrap();
            prop_assert!(back.grid.geometry().same_cells(grid.geometry(), 1e-9));
            prop_assert_eq!(back.grid.states(), grid.states().clone());
            prop_assert!(back.notes.is_empty(), "{:?}", back.notes);

            save_map(&path, &grid, &MapSaveOptions { mode: MapMode::Raw, ..Default::default() }).unwrap();
            let back = load_map(&path, &load).unwrap();
            prop_assert_eq!(back.grid.values().data(), grid.values().data());
        }
    }
}
