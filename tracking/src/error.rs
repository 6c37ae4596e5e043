//! The error type of the tracking crate: every way input can be rejected.

use std::path::{Path, PathBuf};

/// Errors of `haunts-tracking`.
///
/// Readers fail only on I/O; malformed lines are skipped and counted instead (see
/// [`crate::SkipReason`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TrackingError {
    /// A file could not be read (or a gzip stream is broken).
    #[error("{path}: {source}")]
    Io {
        /// The file (`(reader)` for a reader given to a `parse_*` function).
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A parameter breaks its rule.
    #[error(transparent)]
    InvalidParameter(#[from] haunts_core::InvalidParameter),
    /// Two roles of a delimited file were given the same column.
    #[error("columns `{first}` and `{second}` are both column {column}")]
    ColumnClash {
        /// The first role (e.g. `time`).
        first: &'static str,
        /// The second role.
        second: &'static str,
        /// The shared 0-based column index.
        column: usize,
    },
    /// A row-major matrix does not hold `rows × cols` entries.
    #[error("a {rows} × {cols} matrix needs {} entries, got {len}", rows.saturating_mul(*cols))]
    MatrixShape {
        /// Entries given.
        len: usize,
        /// Rows declared.
        rows: usize,
        /// Columns declared.
        cols: usize,
    },
    /// No chain of transforms links two frames.
    #[error("no chain of static transforms from `{from}` to `{to}`")]
    NoTransformChain {
        /// The frame the chain starts from.
        from: String,
        /// The frame it should reach.
        to: String,
    },
    /// A frame is given two different parents or poses (a transform tree allows one).
    #[error(
        "frame `{child}` has conflicting static transforms (lines {first_line} and {second_line})"
    )]
    ConflictingTransform {
        /// The child frame.
        child: String,
        /// Line of the first record.
        first_line: usize,
        /// Line of the conflicting record.
        second_line: usize,
    },
    /// A trajectory sample is not finite or goes back in time.
    #[error("trajectory {id}, sample {sample}: {rule}")]
    InvalidTrajectory {
        /// The trajectory's id.
        id: u64,
        /// 0-based index of the offending sample.
        sample: usize,
        /// The rule it broke.
        rule: &'static str,
    },
    /// Two sequences that must pair up element by element have different lengths.
    #[error("{first} has {first_len} elements but {second} has {second_len}")]
    LengthMismatch {
        /// The first sequence.
        first: &'static str,
        /// Its length.
        first_len: usize,
        /// The second sequence.
        second: &'static str,
        /// Its length.
        second_len: usize,
    },
    /// An object of an evaluation frame is invalid (non-finite position, repeated id).
    #[error("{side} frame {frame}, object id {id}: {rule}")]
    InvalidObject {
        /// `truth` or `hypotheses`.
        side: &'static str,
        /// 0-based index of the frame.
        frame: usize,
        /// The object's id.
        id: u64,
        /// The rule it broke.
        rule: &'static str,
    },
    /// A sequence of times that must be finite and sorted is not.
    #[error("{what}: element {index} is not finite or earlier than the one before it")]
    NotSorted {
        /// The sequence (e.g. `scans`).
        what: &'static str,
        /// 0-based index of the first element out of order.
        index: usize,
    },
    /// A tracker or a Gaussian combination was given a time earlier than the last one; its
    /// state is unchanged.
    #[error("time {time} s is before the previous time {previous} s")]
    TimeWentBackwards {
        /// The last accepted time, seconds.
        previous: f64,
        /// The rejected time, seconds.
        time: f64,
    },
    /// A time is NaN or infinite.
    #[error("time {time} is not finite")]
    NonFiniteTime {
        /// The rejected time.
        time: f64,
    },
    /// A detection has a non-finite position or confidence, or a negative confidence.
    #[error("detection {index} has a non-finite position or a bad confidence")]
    InvalidDetection {
        /// Its index in the slice given.
        index: usize,
    },
    /// A detection's covariance is not symmetric positive definite (singular, negative or
    /// non-finite).
    #[error("detection {index}: covariance is not symmetric positive definite")]
    SingularCovariance {
        /// Its index in the slice given.
        index: usize,
    },
    /// A `<Line>` or `<Circle>` tag of an OpenTraj `map.xml` ([`crate::parse_scene_map`]) is
    /// missing a coordinate or holds one that is not a finite number.
    #[error("map.xml: {rule}: {tag}")]
    SceneMap {
        /// The tag (its first 120 characters).
        tag: String,
        /// The rule it broke.
        rule: &'static str,
    },
    /// The occupancy crate rejected a grid, a scan's pose (the static map), a pose history or
    /// a transform lookup (the frames machinery lives there).
    #[error("occupancy: {source}")]
    Occupancy {
        /// The underlying error.
        #[from]
        source: haunts_occupancy::OccupancyError,
    },
    /// A leg-classifier model file is not one this version reads.
    #[error("leg forest model: {what}")]
    InvalidModel {
        /// What is wrong (bad magic, unknown version, checksum mismatch, a node out of
        /// range, …).
        what: &'static str,
    },
    /// An evaluation found no annotated person to score: CLEAR MOT is undefined there (MOTA
    /// would read 1 for tracks judged against nothing), so nothing is reported as a score.
    #[error(
        "nothing to score: no annotated person in the {frames} frames scored ({scans} scans read, {annotations} annotations, {unassigned} of them belonging to no scan read)"
    )]
    NothingScored {
        /// Scans read.
        scans: usize,
        /// Frames scored (instants of the protocol).
        frames: usize,
        /// Ground-truth records given.
        annotations: usize,
        /// Ground-truth records that belong to no scan read.
        unassigned: usize,
    },
    /// The forest could not be trained (feature `train`): smartcore's reason.
    #[error("training the leg forest: {message}")]
    Training {
        /// smartcore's message.
        message: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = TrackingError> = std::result::Result<T, E>;

pub(crate) fn io_error(path: &Path, source: std::io::Error) -> TrackingError {
    TrackingError::Io {
        path: path.to_path_buf(),
        source,
    }
}
