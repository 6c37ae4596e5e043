//! The error type of the occupancy crate: every way user data can be rejected.

use std::path::PathBuf;

/// What was wrong in a PGM image.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum PgmProblem {
    /// The file does not start with `P5` (binary) or `P2` (plain).
    BadMagic,
    /// A header field (width, height or maxval) is missing or not a positive integer.
    BadHeaderField {
        /// Which field: `width`, `height` or `maxval`.
        field: &'static str,
    },
    /// The maxval is outside 1..=65535.
    MaxvalOutOfRange {
        /// The maxval read.
        maxval: u32,
    },
    /// The file ends before all pixels were read.
    Truncated {
        /// Pixels the header announced.
        expected: usize,
        /// Pixels present.
        found: usize,
    },
    /// A plain (`P2`) pixel is not an integer or is larger than maxval.
    BadPixel {
        /// Index of the pixel, counted from the top-left corner of the image.
        index: usize,
    },
}

impl std::fmt::Display for PgmProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::BadMagic => write!(f, "not a PGM file (magic is not P5 or P2)"),
            Self::BadHeaderField { field } => write!(f, "bad or missing header field `{field}`"),
            Self::MaxvalOutOfRange { maxval } => write!(f, "maxval {maxval} is outside 1..=65535"),
            Self::Truncated { expected, found } => {
                write!(f, "truncated: {found} of {expected} pixels present")
            }
            Self::BadPixel { index } => write!(f, "pixel {index} is not a valid sample"),
        }
    }
}

/// Errors of `haunts-occupancy`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OccupancyError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A YAML file is not valid YAML.
    #[error("{path}:{line}:{column}: YAML syntax error: {message}")]
    YamlSyntax {
        /// The file.
        path: PathBuf,
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// A required field is absent from a map YAML file.
    #[error("{path}: missing field `{field}`")]
    MissingField {
        /// The file.
        path: PathBuf,
        /// The field.
        field: &'static str,
    },
    /// A field of a map YAML file has a value that cannot be used.
    #[error("{path}:{line}: field `{field}` = `{value}`: expected {expected}")]
    InvalidField {
        /// The file.
        path: PathBuf,
        /// Line (1-based) of the value.
        line: usize,
        /// The field.
        field: String,
        /// The value as written.
        value: String,
        /// What would have been accepted.
        expected: &'static str,
    },
    /// A field appears twice with different values (equal repeats are accepted, as ROS does).
    #[error("{path}:{line}: field `{field}` is repeated with a different value")]
    ConflictingField {
        /// The file.
        path: PathBuf,
        /// Line (1-based) of the repetition.
        line: usize,
        /// The field.
        field: String,
    },
    /// The map origin has a non-zero yaw and the caller did not ask to keep it.
    #[error(
        "{path}: origin yaw is {yaw} rad; grids are axis aligned (set `keep_yaw` to accept it)"
    )]
    NonZeroYaw {
        /// The file.
        path: PathBuf,
        /// The yaw read.
        yaw: f64,
    },
    /// A PGM image is malformed.
    #[error("{path}: byte {offset}: {problem}")]
    Pgm {
        /// The file.
        path: PathBuf,
        /// Byte offset where the problem was found.
        offset: usize,
        /// What was wrong.
        problem: PgmProblem,
    },
    /// An image format other than PGM (or PNG with the `png` feature) was given.
    #[error("{path}: unsupported image format (expected .pgm{png})", png = if cfg!(feature = "png") { " or .png" } else { "" })]
    UnsupportedImage {
        /// The file.
        path: PathBuf,
    },
    /// A PNG image could not be decoded or encoded.
    #[cfg(feature = "png")]
    #[error("{path}: PNG: {message}")]
    Png {
        /// The file.
        path: PathBuf,
        /// The codec's message.
        message: String,
    },
    /// Pixels that do not fill a picture of the given size.
    #[cfg(feature = "png")]
    #[error("a {width} × {height} picture needs {width}·{height} pixels, not {pixels}")]
    Picture {
        /// Width asked for.
        width: usize,
        /// Height asked for.
        height: usize,
        /// Pixels given.
        pixels: usize,
    },
    /// A grid geometry parameter is not finite, not positive, or out of its range. (The
    /// value is written as `{:?}` writes it: 1e308, not 309 digits.)
    #[error("grid geometry: `{field}` = {value:?} is invalid ({expected})")]
    InvalidGeometry {
        /// The parameter.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The rule it broke.
        expected: &'static str,
    },
    /// A grid has zero width or height (or, for the distance transform, sides whose squared
    /// distances would not fit `u32`).
    #[error("grid of {width}×{height} cells is empty or too large")]
    BadGridSize {
        /// Width in cells.
        width: usize,
        /// Height in cells.
        height: usize,
    },
    /// A grid would have more cells than the cell budget allows ([`crate::budget`]): refused
    /// before anything is allocated. The sides are those asked for, not rounded or saturated
    /// (they may not fit an integer).
    #[error(
        "a grid of {} × {} cells of {resolution} m over ({}, {}) to ({}, {}) exceeds the budget of {budget} cells (haunts_occupancy::budget::set_max_cells raises it)",
        crate::budget::count(*width), crate::budget::count(*height), from[0], from[1], to[0], to[1]
    )]
    GridTooLarge {
        /// Columns asked for.
        width: f64,
        /// Rows asked for.
        height: f64,
        /// Side of a cell, metres.
        resolution: f64,
        /// World position of the lower-left corner of the area (x, y).
        from: [f64; 2],
        /// World position of the upper-right corner of the area (x, y): the far coordinate.
        to: [f64; 2],
        /// The cell budget in force.
        budget: usize,
    },
    /// A job sized by data would take more elementary operations than the work budget
    /// allows ([`crate::budget::check_work`]): refused before it starts. The factors are
    /// those asked for, in the job's own words.
    #[error(
        "{what}: {} = {} units exceeds the work budget of {budget} units (haunts_occupancy::budget::set_max_work raises it)",
        crate::budget::factors(factors), crate::budget::count(*work)
    )]
    WorkTooLarge {
        /// The job.
        what: &'static str,
        /// Its factors: what each counts and how many.
        factors: Vec<(&'static str, f64)>,
        /// Their product (infinite or NaN when a factor is).
        work: f64,
        /// The work budget in force.
        budget: u64,
    },
    /// The data given for a grid does not have width × height elements.
    #[error("grid data has {found} elements, expected {expected}")]
    DataLength {
        /// width × height.
        expected: usize,
        /// Elements given.
        found: usize,
    },
    /// Two grids that must share a geometry do not.
    #[error("grid geometries differ: {expected:?} vs {found:?}")]
    GeometryMismatch {
        /// The geometry required.
        expected: Box<crate::GridGeometry>,
        /// The geometry given.
        found: Box<crate::GridGeometry>,
    },
    /// A pose has a NaN or infinite component.
    #[error("pose of {what} is not finite")]
    NonFinitePose {
        /// Which pose (e.g. `scan 12`).
        what: String,
    },
    /// A laser scan's description is invalid.
    #[error("laser scan: `{field}` = {value} is invalid ({expected})")]
    InvalidScan {
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The rule it broke.
        expected: &'static str,
    },
    /// A scan's intensities do not match its ranges in length.
    #[error("laser scan has {ranges} ranges but {intensities} intensities")]
    ScanLengthMismatch {
        /// Number of ranges.
        ranges: usize,
        /// Number of intensities.
        intensities: usize,
    },
    /// A parameter breaks its rule.
    #[error(transparent)]
    InvalidParameter(#[from] haunts_core::InvalidParameter),
    /// Two lists that must be as long as each other are not.
    #[error("`{first}` has {first_len} elements but `{second}` has {second_len}")]
    LengthMismatch {
        /// The first list.
        first: &'static str,
        /// Its length.
        first_len: usize,
        /// The second list.
        second: &'static str,
        /// Its length.
        second_len: usize,
    },
    /// A time series that needs at least one valid sample has none.
    #[error("{what}: no valid samples")]
    NoSamples {
        /// What was empty (e.g. `pose history`).
        what: &'static str,
    },
    /// A time outside the span a time series covers (or NaN).
    #[error("time {time} s is outside the covered span [{start}, {end}] s")]
    TimeOutOfRange {
        /// The time asked for, seconds.
        time: f64,
        /// The first covered time, seconds.
        start: f64,
        /// The last covered time, seconds.
        end: f64,
    },
    /// No chain of transforms links two frames.
    #[error("no chain of transforms from `{from}` to `{to}`")]
    NoTransformChain {
        /// The frame the chain starts from.
        from: String,
        /// The frame it should reach.
        to: String,
    },
    /// A frame is given two different parents, or two different static poses under one
    /// parent, or is both static and moving (a transform tree gives a frame one parent).
    #[error("frame `{child}` has conflicting transforms: {what}")]
    ConflictingTransform {
        /// The child frame.
        child: String,
        /// What conflicts (e.g. `parents base_link and odom`).
        what: String,
    },
    /// A recording's scans could not be read (the error of the file or source behind them).
    #[error("reading the scans of {what}: {source}")]
    ScanSource {
        /// The source (e.g. a file name and topic).
        what: String,
        /// The source's own error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A distance transform was asked of a mask with no obstacle cell: distances are undefined.
    #[error("the mask has no obstacle cell: the distance field is undefined")]
    EmptyMask,
    /// Every row of a reader was skipped by the [bounds rule](crate::bounds): none is left
    /// to size a grid on or to compute with.
    #[error(
        "no usable {what}: of {given} rows, {far} lie far from the rest and {non_finite} are not finite"
    )]
    NoUsableRows {
        /// The rows (e.g. `detections`, `odometry poses`).
        what: &'static str,
        /// Rows given.
        given: usize,
        /// Rows skipped as far.
        far: usize,
        /// Rows skipped as non-finite.
        non_finite: usize,
    },
    /// A composite was asked of no maps at all.
    #[error("no maps were added to the composite")]
    EmptyComposite,
}

/// Shorthand for results of this crate.
pub type Result<T, E = OccupancyError> = std::result::Result<T, E>;

pub(crate) fn io_error(path: &std::path::Path, source: std::io::Error) -> OccupancyError {
    OccupancyError::Io {
        path: path.to_path_buf(),
        source,
    }
}
