//! Fuzzes the ROS 1 bag reader of `haunts-bag`: the input is a whole file (seeds in
//! `seeds/bag_ros1/`), run through `common/bag_check.rs`: open, topics, every message raw,
//! the built-in types decoded, the recording and its scans. Only values and typed errors.
#![no_main]

#[path = "../common/bag_check.rs"]
mod bag_check;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = bag_check::exercise_bytes(data);
});
