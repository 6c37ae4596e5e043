//! Fuzzes the facade's day artifact reader, `haunts::artifact::DayArtifact::from_bytes` (see
//! `common/artifact_check.rs`, shared with the facade's `tests/artifact_fuzz_regressions.rs`).
//! Only values or typed errors; an accepted artifact round-trips through its own bytes.
#![no_main]

#[path = "../common/artifact_check.rs"]
mod artifact_check;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = artifact_check::day_artifact(data);
});
