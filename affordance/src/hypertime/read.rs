//! Reading timed detections `(t, x, y)` from delimited text files, with the line loop and
//! field rules of `haunts_tracking::io::lines` (whose trajectory reader needs an id column
//! that detection logs do not have).

use std::io::Read;
use std::path::Path;

use haunts_tracking::io::{Fields, parse_lines};
use haunts_tracking::{Delimiter, Parsed};

use super::projection::TimedPoint;
use crate::{AffordanceError, Result};

/// Which columns (0-based) of a delimited file hold the time, x and y, and how fields are
/// separated. Blank lines and `#` comments are ignored; other columns are not read.
///
/// With the `serde` feature the delimiter is written as `"Whitespace"` or `{"Char": ","}`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DetectionColumns {
    /// Column of the UNIX time, seconds.
    pub time: usize,
    /// Column of x, metres.
    pub x: usize,
    /// Column of y, metres.
    pub y: usize,
    /// The field separator.
    pub delimiter: Delimiter,
    /// Lines to ignore at the top of the file.
    pub header_lines: usize,
}

impl Default for DetectionColumns {
    /// `t x y …`, whitespace separated, no header.
    fn default() -> Self {
        Self {
            time: 0,
            x: 1,
            y: 2,
            delimiter: Delimiter::Whitespace,
            header_lines: 0,
        }
    }
}

impl DetectionColumns {
    /// Sets the columns of time, x and y.
    pub fn with_columns(mut self, time: usize, x: usize, y: usize) -> Self {
        (self.time, self.x, self.y) = (time, x, y);
        self
    }
    /// Sets the field separator.
    pub fn with_delimiter(mut self, delimiter: Delimiter) -> Self {
        self.delimiter = delimiter;
        self
    }
    /// Sets the number of header lines.
    pub fn with_header_lines(mut self, header_lines: usize) -> Self {
        self.header_lines = header_lines;
        self
    }

    /// The columns, after checking that they differ and are below `usize::MAX`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] (`columns`) with the repeated column, or named
    /// after the role given column `usize::MAX`.
    pub fn check(self) -> Result<Self> {
        // A line would need `column + 1` fields, which must not wrap.
        for (name, column) in [("time", self.time), ("x", self.x), ("y", self.y)] {
            if column == usize::MAX {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name,
                        value: column as f64,
                        rule: "a column index must be below usize::MAX",
                    },
                ));
            }
        }
        if self.time == self.x || self.time == self.y || self.x == self.y {
            let repeated = if self.time == self.x || self.time == self.y {
                self.time
            } else {
                self.x
            };
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "columns",
                    value: repeated as f64,
                    rule: "time, x and y must be different columns",
                },
            ));
        }
        Ok(self)
    }
}

/// Reads detections from a delimited file (plain or gzipped). A line needs every chosen
/// column, each a finite number; other lines are skipped and counted.
///
/// # Errors
/// [`AffordanceError::InvalidParameter`] for clashing columns; [`AffordanceError::Io`] when
/// the file cannot be read.
pub fn read_detections(
    path: impl AsRef<Path>,
    columns: &DetectionColumns,
) -> Result<Parsed<TimedPoint>> {
    let path = path.as_ref();
    let columns = columns.check()?;
    let io = |source| AffordanceError::Io {
        path: path.to_path_buf(),
        operation: "read",
        source,
    };
    let reader = haunts_occupancy::text::open_maybe_gzip(path).map_err(io)?;
    rows(reader, &columns).map_err(io)
}

/// Parses detections from any reader (see [`read_detections`]).
///
/// # Errors
/// [`AffordanceError::InvalidParameter`] for clashing columns; [`AffordanceError::Io`]
/// (path `(reader)`) for the reader's errors.
///
/// ```
/// use haunts_affordance::hypertime::{parse_detections, DetectionColumns};
/// let text = "# t x y\n10 1.5 2.5\n11 nan 0\n12 1 2 extra\nbad line\n";
/// let parsed = parse_detections(text.as_bytes(), &DetectionColumns::default())?;
/// assert_eq!(parsed.records.len(), 2);
/// assert_eq!(parsed.skipped, 2);
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
pub fn parse_detections(
    reader: impl Read,
    columns: &DetectionColumns,
) -> Result<Parsed<TimedPoint>> {
    let columns = columns.check()?;
    rows(reader, &columns).map_err(|source| AffordanceError::Io {
        path: "(reader)".into(),
        operation: "read",
        source,
    })
}

fn rows(mut reader: impl Read, c: &DetectionColumns) -> std::io::Result<Parsed<TimedPoint>> {
    let needed = 1 + c.time.max(c.x).max(c.y);
    parse_lines(&mut reader, c.header_lines, |text, _line| {
        let f = Fields::of(text, c.delimiter);
        f.at_least(needed)?;
        Ok(TimedPoint::new(
            f.finite(c.time)?,
            f.finite(c.x)?,
            f.finite(c.y)?,
        ))
    })
}

/// A note when the times of `points` do not look like UNIX seconds, which the hypertime
/// model's periods and time-of-day features assume: a median time above 10¹¹ (milliseconds
/// since 1970 are about 1.7·10¹²) or below 10⁸ (before 1973: frame numbers, or seconds since
/// a recording's start, whose time of day means nothing). `None` when they do, or when no
/// time is finite.
///
/// ```
/// use haunts_affordance::hypertime::{TimedPoint, time_units_note};
/// let at = |t: f64| TimedPoint::new(t, 0.0, 0.0);
/// assert!(time_units_note(&[at(1.4958e9), at(1.4959e9)]).is_none());
/// assert!(time_units_note(&[at(1.4958e12)]).unwrap().contains("milliseconds"));
/// assert!(time_units_note(&[at(12.0), at(13.0)]).is_some());
/// ```
pub fn time_units_note(points: &[TimedPoint]) -> Option<String> {
    let mut times: Vec<f64> = points
        .iter()
        .map(|p| p.time)
        .filter(|t| t.is_finite())
        .collect();
    let median = haunts_core::median(&mut times)?;
    if median > 1e11 {
        Some(format!(
            "the median time {median:.0} looks like milliseconds, not UNIX seconds (divide by 1000)"
        ))
    } else if median < 1e8 {
        Some(format!(
            "the median time {median:.0} is not UNIX seconds (before 1973: frame numbers or \
             seconds since a start?); periods and times of day assume UNIX seconds"
        ))
    } else {
        None
    }
}
