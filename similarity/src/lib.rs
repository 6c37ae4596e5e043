#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// The `nalgebra` this crate's API is built on (points, poses, vectors), so that a caller
/// whose own `Cargo.toml` pins another version can name the exact types:
/// `use haunts_similarity::nalgebra::Point2`.
pub use nalgebra;

mod agreement;
mod change;
mod cluster;
mod difference;
mod error;
mod global;
mod icp;
mod localise;
mod matrix;
mod resample;
mod umeyama;

pub use agreement::{Agreement, agreement};
pub use change::{ChangeParams, RegionChange, RegionChanges, local_changes};
pub use cluster::{
    ClusterParams, Clustering, LayoutThreshold, complete_linkage_layouts, greedy_layouts,
};
pub use difference::{
    DifferenceParams, Length, PairDifference, PreparedMap, Symmetrisation, compare,
    difference_grid, directed_difference,
};
pub use error::{Result, SimilarityError};
pub use global::{Fit, GlobalMatch, GlobalParams, fit_at, register_maps, register_maps_onto_each};
pub use icp::{IcpParams, IcpResult, IcpTarget, RobustLoss, icp, icp_map_to_map};
pub use localise::{Localised, Localiser, LocaliserParams};
pub use matrix::{SimilarityMatrix, similarity_matrix, similarity_matrix_prepared};
pub use resample::{common_geometry, resample, resample_grid, resample_posed};
pub use umeyama::{UmeyamaFit, umeyama_rigid, umeyama_similarity};
