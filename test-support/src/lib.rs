//! Test helpers shared by the haunts crates: [`data`] (where `../shared/data` is, a folder's
//! files), [`bag`] (the shared ROS 1 bag unzipped once, its MCAP twin), [`json`] (round
//! trips and one-change corruptions for the crates' `tests/serde.rs`), [`plan`] (a floor
//! plan for registration tests) and [`netns`] (networked tests in a network namespace of
//! their own). A dev-dependency of every crate of the workspace, never published.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

pub mod bag;
pub mod data;
pub mod json;
pub mod netns;
pub mod plan;

/// The files of `folder`, relative to the calling crate's manifest directory (see
/// [`data::files`]).
#[macro_export]
macro_rules! crate_files {
    ($folder:expr) => {
        $crate::data::files(::std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join($folder))
    };
}

/// The committed seeds of fuzz target `target` (`fuzz/seeds/<target>/` of the workspace, seen
/// from the calling crate), by name; panics when there are none.
#[macro_export]
macro_rules! fuzz_seeds {
    ($target:expr) => {{
        let target: &str = $target;
        let seeds = $crate::crate_files!(format!("../fuzz/seeds/{target}"));
        assert!(!seeds.is_empty(), "no seeds for {target}");
        seeds
    }};
}
