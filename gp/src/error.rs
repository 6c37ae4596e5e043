//! The error type of the Gaussian-process crate: every way user data can be rejected.

/// Errors of `haunts-gp`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GpError {
    /// A hyperparameter (given in natural or log space) violates its rule.
    #[error("hyperparameter `{name}` = {value}: {rule}")]
    InvalidHyperparameter {
        /// The hyperparameter's name, as [`crate::Kernel::param_names`] gives it.
        name: String,
        /// The value given (in log space when it came through
        /// [`crate::Kernel::set_log_params`]).
        value: f64,
        /// The rule it broke.
        rule: &'static str,
    },
    /// A hyperparameter was named that the kernel does not have.
    #[error("the kernel has no hyperparameter `{name}` (it has {known:?})")]
    UnknownHyperparameter {
        /// The name given.
        name: String,
        /// The kernel's names, as [`crate::Kernel::param_names`] gives them.
        known: Vec<String>,
    },
    /// A kernel was given the wrong number of (log) hyperparameters.
    #[error("expected {expected} hyperparameters, found {found}")]
    WrongParameterCount {
        /// The kernel's number of hyperparameters.
        expected: usize,
        /// The number given.
        found: usize,
    },
    /// Points (or two kernels) do not have the dimension required.
    #[error("dimension mismatch: expected {expected}, found {found}")]
    DimensionMismatch {
        /// The dimension required (e.g. the number of ARD length scales).
        expected: usize,
        /// The dimension given.
        found: usize,
    },
    /// A flat row-major point array's length is not a multiple of the dimension, or the
    /// dimension is zero.
    #[error("point array of {len} numbers cannot hold points of dimension {dim}")]
    BadPointArray {
        /// Length of the flat array.
        len: usize,
        /// Dimension of a point.
        dim: usize,
    },
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate")]
    NonFiniteInput {
        /// Index of the point (0 for the first argument of [`crate::Kernel::try_value`], 1 for
        /// the second).
        index: usize,
    },
    /// A parameter breaks its rule.
    #[error(transparent)]
    InvalidParameter(#[from] haunts_core::InvalidParameter),
    /// The numbers of points and of targets differ.
    #[error("{points} points but {targets} targets")]
    LengthMismatch {
        /// Number of points.
        points: usize,
        /// Number of targets.
        targets: usize,
    },
    /// An array of a model read back (with the `serde` feature) does not have the length its
    /// other fields imply.
    #[error("`{name}` has {found} numbers, {expected} expected")]
    WrongLength {
        /// The field.
        name: &'static str,
        /// The length its other fields imply.
        expected: usize,
        /// The length found.
        found: usize,
    },
    /// There are no training points.
    #[error("no training points")]
    NoData,
    /// A target is NaN or infinite.
    #[error("target {index} is not finite")]
    NonFiniteTarget {
        /// Index of the target.
        index: usize,
    },
    /// A covariance matrix has a NaN or infinite entry on its diagonal (a kernel whose value
    /// overflowed).
    #[error("covariance matrix has a non-finite diagonal entry at {index}")]
    NonFiniteMatrix {
        /// Row of the entry.
        index: usize,
    },
    /// A covariance matrix is not positive definite even with the largest jitter of the
    /// [`crate::JitterPolicy`].
    #[error(
        "covariance matrix is not positive definite (pivot {pivot}) even with jitter {max_jitter:e}"
    )]
    NotPositiveDefinite {
        /// The pivot at which the last attempt failed.
        pivot: usize,
        /// The largest (absolute) jitter tried.
        max_jitter: f64,
    },
    /// Fewer data points than an algorithm needs.
    #[error("{found} data points, at least {required} needed")]
    TooFewPoints {
        /// Points given.
        found: usize,
        /// Points needed.
        required: usize,
    },
    /// Every data point is the same point: a kernel's length scales cannot be estimated.
    #[error("all {n} data points are identical")]
    IdenticalInputs {
        /// Number of points.
        n: usize,
    },
    /// The configuration asks for something not implemented.
    #[error("not supported: {what}")]
    Unsupported {
        /// What is not supported.
        what: &'static str,
    },
    /// An optimisation could not evaluate its objective at the start, or failed every
    /// restart.
    #[error("optimisation failed: {reason}")]
    OptimisationFailed {
        /// What went wrong.
        reason: String,
    },
}

impl GpError {
    pub(crate) fn invalid(name: &'static str, value: f64, rule: &'static str) -> Self {
        Self::InvalidParameter(haunts_core::InvalidParameter { name, value, rule })
    }
}

/// Shorthand for results of this crate.
pub type Result<T, E = GpError> = std::result::Result<T, E>;
