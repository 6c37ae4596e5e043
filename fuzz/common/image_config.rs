//! The reading the `map_image` fuzz target derives from an input's first byte, shared with
//! `occupancy/tests/fuzz_regressions.rs` so that saved inputs replay exactly as fuzzed:
//! bit 0 interpretation (Ros1/Nav2), bits 1-2 mode (trinary/scale/raw, 3 = trinary), bit 3
//! negate, bits 4-5 thresholds, bits 6-7 geometry (pattern 10 = NaN resolution, which must be
//! rejected).

use std::path::PathBuf;

use haunts_occupancy::{Interpretation, MapMetadata, MapMode};

/// (occupied_thresh, free_thresh): ROS defaults, the extremes, a narrow band, and an
/// inverted pair, which `decode_map_image` must reject as `parse_map_yaml` does.
pub const THRESHOLDS: [(f64, f64); 4] = [(0.65, 0.196), (1.0, 0.0), (0.5, 0.49), (0.1, 0.196)];

/// (resolution, origin x, origin y).
pub const GEOMETRY: [(f64, f64, f64); 4] = [
    (0.05, 0.0, 0.0),
    (1e-300, -1e300, 1e300),
    (f64::NAN, 0.0, 0.0),
    (0.05, -39.85, -77.95),
];

/// The metadata and interpretation that configuration byte `config` selects.
pub fn image_config(config: u8) -> (MapMetadata, Interpretation) {
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
    let (occupied_thresh, free_thresh) = THRESHOLDS[usize::from((config >> 4) & 3)];
    let (resolution, x, y) = GEOMETRY[usize::from(config >> 6)];
    let metadata = MapMetadata {
        image: PathBuf::from("fuzz.pgm"),
        mode,
        resolution,
        origin: [x, y, 0.0],
        negate: config & 8 != 0,
        occupied_thresh,
        free_thresh,
    };
    (metadata, interpretation)
}
