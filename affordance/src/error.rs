//! The error type of the affordance crate.

/// Errors of `haunts-affordance`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AffordanceError {
    /// A parameter breaks its rule.
    #[error(transparent)]
    InvalidParameter(#[from] haunts_core::InvalidParameter),
    /// An error of the occupancy crate (grids, geometry, raycasting).
    #[error(transparent)]
    Occupancy(#[from] haunts_occupancy::OccupancyError),
    /// An error of the Gaussian-process crate.
    #[error(transparent)]
    Gp(#[from] haunts_gp::GpError),
    /// An error of the similarity crate (map comparison parameters and grids).
    #[error(transparent)]
    Similarity(#[from] haunts_similarity::SimilarityError),
    /// Grids that must lie on the same cells do not (counts are never resampled; build them on
    /// the reference geometry).
    #[error("{what} lies on {found:?}, expected {expected:?}")]
    GeometryMismatch {
        /// Which grid is off (e.g. `day map`, `day hits`, `visits`).
        what: &'static str,
        /// The geometry required.
        expected: Box<haunts_occupancy::GridGeometry>,
        /// The geometry given.
        found: Box<haunts_occupancy::GridGeometry>,
    },
    /// A day's map has no occupied cell, so its distance field is undefined and it cannot be
    /// compared with any layout.
    #[error("the day's map has no occupied cell: it cannot be compared with a layout")]
    EmptyDayMap,
    /// A day with this label is already in the layout library.
    #[error("day `{label}` is already in the layout library")]
    DuplicateDay {
        /// The label.
        label: String,
    },
    /// A file could not be read or written.
    #[error("{path}: cannot {operation}: {source}")]
    Io {
        /// The file (or directory).
        path: std::path::PathBuf,
        /// The step that failed (e.g. `read`, `fsync the temporary file`).
        operation: &'static str,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A layout library file (or byte buffer) is not a valid library: corrupt, truncated,
    /// malformed or of a newer format version.
    #[error(
        "layout library{}: {problem}",
        .path.as_ref().map(|p| format!(" {}", p.display())).unwrap_or_default()
    )]
    CorruptLibrary {
        /// The file, or `None` for bytes given directly.
        path: Option<std::path::PathBuf>,
        /// What is wrong.
        problem: crate::layout::file::LibraryFileProblem,
    },
    /// Fewer (finite) points than clusters: the clustering needs at least one point per
    /// cluster.
    #[error("{points} points for {clusters} clusters: need at least one point per cluster")]
    TooFewPoints {
        /// Points available.
        points: usize,
        /// Clusters asked for.
        clusters: usize,
    },
    /// A flat row-major array whose length is not a multiple of its row length (or rows of
    /// length 0).
    #[error("{len} values cannot be rows of {dim}")]
    BadShape {
        /// Number of values.
        len: usize,
        /// Values per row.
        dim: usize,
    },
    /// A value given to the clustering is NaN or infinite.
    #[error("value at row {row}, column {column} is not finite")]
    NonFiniteInput {
        /// Row (point) index.
        row: usize,
        /// Column (dimension) index.
        column: usize,
    },
    /// A cluster's covariance is not finite (overflow) or not positive definite after
    /// regularisation.
    #[error("covariance of cluster {cluster} is degenerate")]
    DegenerateCovariance {
        /// The cluster.
        cluster: usize,
    },
    /// The fuzzy clustering did not converge within its iteration cap; the clustering after
    /// the last iteration is inside.
    #[error(
        "clustering did not converge in {iterations} iterations (last membership change {change})"
    )]
    NotConverged {
        /// Iterations run.
        iterations: usize,
        /// The largest membership change of the last iteration.
        change: f64,
        /// The clustering after the last iteration.
        partial: Box<crate::hypertime::GkClustering>,
    },
    /// A held-out split left no point on one side (all detections in kept blocks, or all in
    /// held-out blocks).
    #[error("the held-out split of {points} points left one side empty")]
    EmptyHoldOut {
        /// Points split.
        points: usize,
    },
    /// A trajectory's time stamps go back (TA map input: trajectories must be sorted by
    /// time, as the readers and the dummy filter leave them).
    #[error("session {session}, trajectory {id}: sample {sample} is earlier than the one before")]
    UnorderedTimes {
        /// Index of the session (0 for a single session).
        session: usize,
        /// The trajectory's id.
        id: u64,
        /// Index of the offending sample in the trajectory.
        sample: usize,
    },
    /// No usable sample is left to regress on: no trajectory (or robot position) given, or
    /// every sample was skipped.
    #[error("no usable {what}: {given} given, {non_finite} not finite, {outside} outside the map")]
    NoUsableData {
        /// What was missing (`trajectory samples`, `robot positions`).
        what: &'static str,
        /// Samples given.
        given: usize,
        /// Samples skipped because a coordinate (or the time) is NaN or infinite.
        non_finite: usize,
        /// Samples skipped because they lie outside the map.
        outside: usize,
    },
    /// Deserialised data (feature `serde`) that breaks a rule the type's constructors keep:
    /// sizes that do not match, a model without components, values no fit produces.
    #[error("invalid {model}: {problem}")]
    InvalidModel {
        /// The type read (e.g. `hypertime model`, `layout library`).
        model: &'static str,
        /// What is wrong.
        problem: String,
    },
    /// A session's map could not be registered onto the reference map.
    #[error("session {session} cannot be registered onto the reference map: {source}")]
    SessionRegistration {
        /// Index of the session among the sources.
        session: usize,
        /// Why (typically `NoReliableMatch`).
        #[source]
        source: Box<haunts_similarity::SimilarityError>,
    },
    /// A day's map could not be registered onto the layout library: it must not be merged
    /// (misaligned, it would start a layout of its own or corrupt one).
    #[error("the day cannot be registered onto the library: {refusal}")]
    NotRegistered {
        /// Why.
        refusal: crate::layout::register::Refusal,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = AffordanceError> = std::result::Result<T, E>;
