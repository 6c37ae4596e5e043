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
    /// A parameter violates its rule.
    #[error("parameter `{name}` = {value}: {rule}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The rule it broke.
        rule: &'static str,
    },
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
}

/// Shorthand for results of this crate.
pub type Result<T, E = TrackingError> = std::result::Result<T, E>;

pub(crate) fn io_error(path: &Path, source: std::io::Error) -> TrackingError {
    TrackingError::Io {
        path: path.to_path_buf(),
        source,
    }
}
