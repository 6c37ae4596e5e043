//! Fuzzes `haunts-tracking`'s OpenTraj `map.xml` reader and its drawing (see
//! `common/scene_check.rs`, shared with `tracking/tests/fuzz_regressions.rs`). Only values or
//! typed errors.
#![no_main]

#[path = "../common/scene_check.rs"]
mod scene_check;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = scene_check::scene_map(data);
});
