//! The error type of the similarity crate: every way input can be rejected.

use haunts_occupancy::{GridGeometry, OccupancyError};

/// Errors of `haunts-similarity`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimilarityError {
    /// A map has no occupied cell, so its distance field is undefined (all-unknown and
    /// all-free maps land here).
    #[error("map {index} has no occupied cell: its distance field is undefined")]
    EmptyMap {
        /// Position of the map in the input (0 for the first of a pair, 1 for the second).
        index: usize,
    },
    /// Two maps that must share a geometry do not (resample them with
    /// [`crate::resample`] onto [`crate::common_geometry`] first).
    #[error("map {index} lies on {found:?}, expected {expected:?}")]
    GeometryMismatch {
        /// Position of the offending map in the input.
        index: usize,
        /// The geometry of the first map.
        expected: Box<GridGeometry>,
        /// The geometry of the offending map.
        found: Box<GridGeometry>,
    },
    /// Maps of different resolutions were to be put on one grid.
    #[error("map {index} has resolution {found} m, expected {expected} m")]
    ResolutionMismatch {
        /// Position of the offending map in the input.
        index: usize,
        /// The resolution of the first map (or the target geometry).
        expected: f64,
        /// The offending resolution.
        found: f64,
    },
    /// A parameter breaks its rule.
    #[error(transparent)]
    InvalidParameter(#[from] haunts_core::InvalidParameter),
    /// Two sequences that must have the same length do not.
    #[error("{what}: {left} vs {right} elements")]
    LengthMismatch {
        /// What was compared (e.g. `labels`, `correspondences`).
        what: &'static str,
        /// Length of the first sequence.
        left: usize,
        /// Length of the second sequence.
        right: usize,
    },
    /// Too few elements to compute anything.
    #[error("{what}: {found} given, at least {needed} needed")]
    TooFew {
        /// What was counted (e.g. `labels`, `point pairs`).
        what: &'static str,
        /// How many were given.
        found: usize,
        /// How many are needed.
        needed: usize,
    },
    /// A point is NaN or infinite.
    #[error("{what} point {index} is not finite")]
    NonFinitePoint {
        /// Which set (`source` or `target`).
        what: &'static str,
        /// Index of the point.
        index: usize,
    },
    /// Correspondences do not determine a transform (e.g. all source points coincide).
    #[error("degenerate correspondences: {reason}")]
    Degenerate {
        /// Why no unique transform exists.
        reason: &'static str,
    },
    /// ICP found too few correspondences within the search distance to go on.
    #[error("ICP iteration {iteration}: {found} correspondences within reach, {needed} needed")]
    NoCorrespondences {
        /// The iteration (0-based) at which it happened.
        iteration: usize,
        /// Correspondences found.
        found: usize,
        /// Correspondences needed.
        needed: usize,
    },
    /// ICP did not converge within its iteration budget; the last estimate is kept.
    #[error("ICP did not converge in {} iterations", partial.iterations)]
    NotConverged {
        /// The estimate after the last iteration.
        partial: Box<crate::IcpResult>,
    },
    /// Global registration found no transform it can vouch for: too few consistent keypoint
    /// matches, or too little of the source lands on the target's structure.
    #[error(
        "no reliable match: best hypothesis has {inliers} consistent keypoint matches and {overlap:.3} overlap"
    )]
    NoReliableMatch {
        /// Consistent keypoint matches of the best hypothesis.
        inliers: usize,
        /// Fraction of the source's occupied cells near the target's under that hypothesis
        /// (0 when too few matches agreed for the overlap to be checked).
        overlap: f64,
    },
    /// An error of the occupancy crate (e.g. a grid too large for the distance transform).
    #[error(transparent)]
    Occupancy(#[from] OccupancyError),
}

/// Shorthand for results of this crate.
pub type Result<T, E = SimilarityError> = std::result::Result<T, E>;

/// `Ok(value)` when `ok`, else [`SimilarityError::InvalidParameter`].
pub(crate) fn rule(name: &'static str, value: f64, ok: bool, rule: &'static str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(SimilarityError::InvalidParameter(
            haunts_core::InvalidParameter { name, value, rule },
        ))
    }
}
