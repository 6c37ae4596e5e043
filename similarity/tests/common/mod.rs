//! Helpers shared by the integration tests: where the real data lives.
#![allow(dead_code)]

#[path = "../../../tests/support/data.rs"]
mod data;
pub use data::shared_data;
