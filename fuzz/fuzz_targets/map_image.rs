//! Fuzzes `decode_map_image` (PGM P5/P2 8/16-bit, PNG).
//!
//! The first input byte chooses the reading, the rest is the image:
//! bit 0 interpretation (Ros1/Nav2), bits 1-2 mode (trinary/scale/raw, 3 = trinary),
//! bit 3 negate, bits 4-5 thresholds, bits 6-7 geometry (bit pattern 10 = NaN resolution,
//! which must be rejected).
#![no_main]

use std::path::PathBuf;

use haunts_occupancy::{Interpretation, MapMetadata, MapMode, OccupancyError, decode_map_image};
use libfuzzer_sys::fuzz_target;

/// (occupied_thresh, free_thresh): ROS defaults, the extremes, a narrow band, and an
/// inverted pair, which `decode_map_image` must reject as `parse_map_yaml` does.
const THRESHOLDS: [(f64, f64); 4] = [(0.65, 0.196), (1.0, 0.0), (0.5, 0.49), (0.1, 0.196)];

/// (resolution, origin x, origin y).
const GEOMETRY: [(f64, f64, f64); 4] = [
    (0.05, 0.0, 0.0),
    (1e-300, -1e300, 1e300),
    (f64::NAN, 0.0, 0.0),
    (0.05, -39.85, -77.95),
];

fuzz_target!(|data: &[u8]| {
    let Some((&config, image)) = data.split_first() else {
        return;
    };
    let interpretation = if config & 1 == 0 {
        Interpretation::Ros1
    } else {
        Interpretation::Nav2
    };
    let mode = match (config >> 1) & 3 {
        1 => MapMode::Scale,
        2 => MapMode::Raw,
        _ => MapMode::Trinary,
    };
    let negate = config & 8 != 0;
    let (occupied_thresh, free_thresh) = THRESHOLDS[usize::from((config >> 4) & 3)];
    let (resolution, x, y) = GEOMETRY[usize::from(config >> 6)];
    let metadata = MapMetadata {
        image: PathBuf::from("fuzz.pgm"),
        mode,
        resolution,
        origin: [x, y, 0.0],
        negate,
        occupied_thresh,
        free_thresh,
    };
    match decode_map_image(image, &metadata, interpretation) {
        Ok(grid) => {
            assert!(resolution.is_finite(), "NaN resolution accepted");
            assert!(free_thresh < occupied_thresh, "inverted thresholds accepted");
            let g = grid.geometry();
            assert!(g.width() > 0 && g.height() > 0);
            assert_eq!(grid.values().data().len(), g.width() * g.height());
            for &v in grid.values().data() {
                match mode {
                    MapMode::Trinary => assert!(matches!(v, -1 | 0 | 100), "trinary value {v}"),
                    _ => assert!((-1..=100).contains(&v), "value {v}"),
                }
            }
        }
        // The image's own faults, and the geometry's.
        Err(
            OccupancyError::Pgm { .. }
            | OccupancyError::Png { .. }
            | OccupancyError::UnsupportedImage { .. }
            | OccupancyError::InvalidGeometry { .. }
            | OccupancyError::BadGridSize { .. },
        ) => {}
        // Inverted thresholds are the caller's fault.
        Err(OccupancyError::InvalidParameter { name: "free_thresh", .. })
            if free_thresh >= occupied_thresh => {}
        // Anything else (e.g. InvalidParameter from an out-of-range pixel value) means the
        // pixel reader produced something it should not have.
        Err(e) => panic!("unexpected error for {mode:?}/{interpretation:?}: {e:?}"),
    }
});
