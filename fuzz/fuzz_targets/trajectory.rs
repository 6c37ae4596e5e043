//! Fuzzes the `trajectory` text readers of `haunts-tracking`: byte 0 picks the reader and its
//! options, the rest is the file (see `common/text_check.rs`, shared with
//! `tracking/tests/fuzz_regressions.rs`). Only values; the invariants are asserted there.
#![no_main]

#[path = "../common/text_check.rs"]
mod text_check;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = text_check::trajectory(data);
});
