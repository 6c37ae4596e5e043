//! Fuzzes `haunts-affordance`'s `layout_library` reader (see `common/affordance_check.rs`, shared
//! with `affordance/tests/fuzz_regressions.rs`). Only values or typed errors.
#![no_main]

#[path = "../common/affordance_check.rs"]
mod affordance_check;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = affordance_check::layout_library(data);
});
