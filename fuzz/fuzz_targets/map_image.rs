//! Fuzzes `decode_map_image` (PGM P5/P2 8/16-bit, PNG).
//!
//! The first input byte chooses the reading (see `fuzz/common/image_config.rs`), the rest is
//! the image.
#![no_main]

#[path = "../common/image_config.rs"]
mod image_config;

use haunts_occupancy::{MapMode, OccupancyError, decode_map_image};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&config, image)) = data.split_first() else {
        return;
    };
    let (metadata, interpretation) = image_config::image_config(config);
    let (mode, resolution) = (metadata.mode, metadata.resolution);
    let (occupied_thresh, free_thresh) = (metadata.occupied_thresh, metadata.free_thresh);
    match decode_map_image(image, &metadata, interpretation) {
        Ok(grid) => {
            assert!(resolution.is_finite(), "NaN resolution accepted");
            assert!(
                free_thresh < occupied_thresh,
                "inverted thresholds accepted"
            );
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
            | OccupancyError::BadGridSize { .. }
            | OccupancyError::GridTooLarge { .. },
        ) => {}
        // Inverted thresholds are the caller's fault.
        Err(OccupancyError::InvalidParameter(haunts_core::InvalidParameter {
            name: "free_thresh",
            ..
        })) if free_thresh >= occupied_thresh => {}
        // Anything else (e.g. InvalidParameter from an out-of-range pixel value) means the
        // pixel reader produced something it should not have.
        Err(e) => panic!("unexpected error for {mode:?}/{interpretation:?}: {e:?}"),
    }
});
