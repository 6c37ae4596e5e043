//! JSON round trips for the `tests/serde.rs` of every crate of the workspace, which include
//! this file with `#[path = "../../tests/support/json.rs"] mod json;` (one copy instead of one
//! per crate). Not every crate uses every helper.
#![allow(dead_code, clippy::unwrap_used)]

use std::fmt::{Debug, Display};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// `value` written to JSON and read back (for types without `PartialEq`: compare what
/// matters yourself).
pub fn trip<T: Serialize + DeserializeOwned>(value: &T) -> T {
    serde_json::from_str(&serde_json::to_string(value).unwrap()).unwrap()
}

/// `value` through JSON and back, checked equal to the original.
pub fn round_trip<T: Serialize + DeserializeOwned + PartialEq + Debug>(value: &T) -> T {
    let text = serde_json::to_string(value).unwrap();
    let back: T = serde_json::from_str(&text).unwrap();
    assert_eq!(&back, value, "{text}");
    back
}

/// The error of reading `json` (text, or a `serde_json::Value`) as a `T`, as text; panics
/// if it is accepted.
pub fn rejection<T: DeserializeOwned>(json: impl Display) -> String {
    let text = json.to_string();
    match serde_json::from_str::<T>(&text) {
        Ok(_) => panic!("{text} was accepted"),
        Err(e) => e.to_string(),
    }
}
