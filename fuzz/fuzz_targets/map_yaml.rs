//! Fuzzes `parse_map_yaml` (ROS map_server YAML) under two option sets (the defaults, and
//! strict: keep_yaw on, no defaults), checks the invariants of every accepted file, and
//! that the two option sets agree with each other.
#![no_main]

use std::path::Path;

use haunts_occupancy::{LoadNote, MapLoadOptions, MapMetadata, OccupancyError, parse_map_yaml};
use libfuzzer_sys::fuzz_target;

fn check_metadata(m: &MapMetadata, notes: &[LoadNote], options: &MapLoadOptions) {
    assert!(m.resolution.is_finite() && m.resolution > 0.0, "{m:?}");
    assert!(m.origin.iter().all(|v| v.is_finite()), "{m:?}");
    if !options.keep_yaw {
        assert_eq!(m.origin[2], 0.0, "{m:?}");
    }
    assert!((0.0..=1.0).contains(&m.occupied_thresh), "{m:?}");
    // Written or defaulted, free_thresh lies in [0, occupied_thresh).
    assert!(
        m.free_thresh >= 0.0 && m.free_thresh < m.occupied_thresh,
        "{m:?}"
    );
    let defaulted = |field| {
        notes
            .iter()
            .any(|n| matches!(n, LoadNote::Defaulted { field: f, .. } if *f == field))
    };
    if defaulted("free_thresh") {
        assert_eq!(Some(m.free_thresh), options.default_free_thresh);
    }
    if defaulted("negate") {
        assert_eq!(Some(m.negate), options.default_negate);
    }
    assert!(!m.image.as_os_str().is_empty(), "{m:?}");
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("maps/fuzz.yaml");
    let default = MapLoadOptions::default();
    // keep_yaw on, no defaults: everything must be in the file.
    let mut strict = MapLoadOptions::default();
    strict.keep_yaw = true;
    strict.default_free_thresh = None;
    strict.default_negate = None;

    let by_default = parse_map_yaml(text, path, &default);
    let by_strict = parse_map_yaml(text, path, &strict);
    if let Ok((m, notes)) = &by_default {
        check_metadata(m, notes, &default);
    }
    if let Ok((m, notes)) = &by_strict {
        check_metadata(m, notes, &strict);
        // A file complete enough for the strict options reads the same with the defaults,
        // unless its yaw is non-zero.
        match &by_default {
            Ok((d, _)) => assert_eq!(d, m),
            Err(OccupancyError::NonZeroYaw { yaw, .. }) => assert_eq!(*yaw, m.origin[2]),
            Err(e) => panic!("strict options accept, default options reject: {e}"),
        }
    }
    if by_default.is_ok() && by_strict.is_err() {
        // Only a missing field that has a default may tell them apart.
        assert!(
            matches!(
                &by_strict,
                Err(OccupancyError::MissingField {
                    field: "free_thresh" | "negate",
                    ..
                })
            ),
            "default options accept, strict options reject: {by_strict:?}"
        );
    }
});
