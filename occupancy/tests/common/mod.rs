//! Helpers shared by the integration tests: where the real data lives, and fixtures.
#![allow(dead_code)]

use std::path::PathBuf;

pub use data::shared_data;
use haunts_test_support::data;

/// A JSON fixture of `tests/fixtures/`.
pub fn fixture(name: &str) -> serde_json::Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}
