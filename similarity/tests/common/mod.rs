//! Helpers shared by the integration tests: where the real data lives.
#![allow(dead_code)]

pub use data::shared_data;
use haunts_test_support::data;
