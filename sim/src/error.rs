//! `SimError`: every way a simulation can be refused.

/// Errors of `haunts-sim`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A parameter breaks its rule.
    #[error(transparent)]
    InvalidParameter(#[from] haunts_core::InvalidParameter),
    /// The office has no layout to choose from.
    #[error("the office has no furniture layout")]
    NoLayouts,
    /// A patrol needs at least two distinct waypoints.
    #[error("patrol has {count} usable waypoints; at least 2 distinct finite ones are needed")]
    TooFewWaypoints {
        /// Waypoints that were usable.
        count: usize,
    },
    /// The office description is unusable.
    #[error("office: {what} #{index} is invalid ({reason})")]
    InvalidOffice {
        /// Which list: `wall`, `fixed furniture`, `layout`, `door`, `coffee`, `desk`.
        what: &'static str,
        /// Index in that list (for furniture in a layout: the layout index).
        index: usize,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A day beyond what the simulator supports was asked for.
    #[error("day {day} is beyond the last simulated day {max}")]
    DayOutOfRange {
        /// The day asked for.
        day: usize,
        /// The largest day index supported.
        max: usize,
    },
    /// The day would hold more scans or beams than the configured limits.
    #[error("{what}: {count} exceeds the limit {limit}")]
    TooLarge {
        /// `scans per day`, `beams per scan` or `grid cells`.
        what: &'static str,
        /// The count the parameters imply.
        count: f64,
        /// The limit.
        limit: usize,
    },
    /// An error of the occupancy types (scan or grid construction).
    #[error(transparent)]
    Occupancy(#[from] haunts_occupancy::OccupancyError),
}

/// Results of `haunts-sim`.
pub type Result<T> = std::result::Result<T, SimError>;

/// The [`SimError::InvalidParameter`] for `param = value`, which breaks `rule`.
pub(crate) fn invalid(param: &'static str, value: f64, rule: &'static str) -> SimError {
    haunts_core::InvalidParameter::new(param, value, rule).into()
}
