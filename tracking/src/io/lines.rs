//! The line loop shared by every reader: gzip detection, comments, and skipped-line accounting.

use std::io::Read;
use std::path::Path;

use crate::error::{Result, io_error};

/// How many skipped lines a [`Parsed`] keeps for the report.
pub const KEEP_SKIPPED: usize = 10;

/// Why a line was skipped.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum SkipReason {
    /// Fewer fields than the format needs.
    TooFewFields {
        /// Fields the format needs.
        expected: usize,
        /// Fields present.
        found: usize,
    },
    /// More fields than a fixed-width format has.
    TooManyFields {
        /// Fields the format has.
        expected: usize,
        /// Fields present.
        found: usize,
    },
    /// A field is not a number.
    BadNumber {
        /// 0-based index of the field.
        field: usize,
    },
    /// A field that must be finite (a time, a position, a pose) is NaN or infinite.
    NonFinite {
        /// 0-based index of the field.
        field: usize,
    },
    /// An id or a count is not a non-negative integer (integral floats such as
    /// `1.0000000e+00` are accepted).
    BadInteger {
        /// 0-based index of the field.
        field: usize,
    },
    /// A scan line holds a different number of ranges than it declares.
    CountMismatch {
        /// The declared number of ranges.
        declared: usize,
        /// Ranges present.
        found: usize,
    },
    /// A scan's geometry is rejected by [`haunts_occupancy::LaserScan::new`].
    BadScan {
        /// The offending field of the scan (e.g. `angle_increment`).
        field: &'static str,
    },
    /// The line is not valid UTF-8.
    NotText,
}

impl std::fmt::Display for SkipReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TooFewFields { expected, found } => {
                write!(f, "{found} fields, at least {expected} needed")
            }
            Self::TooManyFields { expected, found } => {
                write!(f, "{found} fields, at most {expected} expected")
            }
            Self::BadNumber { field } => write!(f, "field {field} is not a number"),
            Self::NonFinite { field } => write!(f, "field {field} is not finite"),
            Self::BadInteger { field } => {
                write!(f, "field {field} is not a non-negative integer")
            }
            Self::CountMismatch { declared, found } => {
                write!(f, "{declared} ranges declared, {found} present")
            }
            Self::BadScan { field } => write!(f, "invalid scan field `{field}`"),
            Self::NotText => write!(f, "not UTF-8 text"),
        }
    }
}

/// A skipped line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SkippedLine {
    /// Line number (1-based).
    pub line: usize,
    /// Why it was skipped.
    pub reason: SkipReason,
}

/// What a reader found: the records, and the malformed lines it skipped.
///
/// Blank lines, `#` comments and declared header lines are neither records nor skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct Parsed<T> {
    /// The records, in file order (trajectory readers: by id).
    pub records: Vec<T>,
    /// Number of malformed lines skipped.
    pub skipped: usize,
    /// Of those, the lines skipped because a number was NaN or infinite
    /// ([`SkipReason::NonFinite`]): the `non_finite` of a command's `skipped_rows`.
    pub non_finite: usize,
    /// The first skipped lines (up to [`KEEP_SKIPPED`]).
    pub first_skipped: Vec<SkippedLine>,
}

impl<T> Default for Parsed<T> {
    fn default() -> Self {
        Self {
            records: Vec::new(),
            skipped: 0,
            non_finite: 0,
            first_skipped: Vec::new(),
        }
    }
}

impl<T> Parsed<T> {
    /// The same skip report around other records.
    pub(crate) fn with_records<U>(self, records: Vec<U>) -> Parsed<U> {
        Parsed {
            records,
            skipped: self.skipped,
            non_finite: self.non_finite,
            first_skipped: self.first_skipped,
        }
    }
}

/// Opens `path`, gzipped or not (told apart by the gzip magic bytes), and runs `parse` on it.
pub(crate) fn read_path<T>(
    path: &Path,
    parse: impl FnOnce(&mut dyn Read) -> std::io::Result<T>,
) -> Result<T> {
    let io = |e| io_error(path, e);
    let mut reader = haunts_occupancy::text::open_maybe_gzip(path).map_err(io)?;
    parse(&mut reader).map_err(io)
}

/// Runs `parse` on a caller's reader, naming it `(reader)` in errors.
pub(crate) fn read_reader<T>(
    mut reader: impl Read,
    parse: impl FnOnce(&mut dyn Read) -> std::io::Result<T>,
) -> Result<T> {
    parse(&mut reader).map_err(|e| io_error(Path::new("(reader)"), e))
}

/// Calls `parse` on each line after the first `header_lines` that is neither blank nor a `#`
/// comment (the line's text without its ending, and its 1-based number); a line it rejects
/// is counted as skipped, and a line that is not UTF-8 text is skipped as
/// [`SkipReason::NotText`]. The line loop of every text reader of the workspace: a reader of
/// another delimited format needs only its per-line rule, usually on [`Fields`].
///
/// # Errors
/// The reader's I/O errors.
///
/// ```
/// use haunts_tracking::io::{Fields, parse_lines};
/// use haunts_tracking::{Delimiter, SkipReason};
///
/// let text = "# t x\n1 2.5\n2 nan\n";
/// let parsed = parse_lines(&mut text.as_bytes(), 0, |line, _| {
///     let f = Fields::of(line, Delimiter::Whitespace);
///     f.at_least(2)?;
///     Ok((f.finite(0)?, f.finite(1)?))
/// })?;
/// assert_eq!(parsed.records, vec![(1.0, 2.5)]);
/// assert_eq!(parsed.first_skipped[0].reason, SkipReason::NonFinite { field: 1 });
/// assert_eq!((parsed.skipped, parsed.non_finite), (1, 1));
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn parse_lines<T>(
    reader: &mut dyn Read,
    header_lines: usize,
    mut parse: impl FnMut(&str, usize) -> Result<T, SkipReason>,
) -> std::io::Result<Parsed<T>> {
    let mut out = Parsed::default();
    haunts_occupancy::text::for_each_line(reader, |line, text| {
        if line <= header_lines {
            return;
        }
        let outcome = match text {
            Some(text) => {
                let probe = text.trim();
                if probe.is_empty() || probe.starts_with('#') {
                    return;
                }
                // Only the line ending goes: a leading delimiter still opens an empty field.
                parse(text.trim_end_matches(['\n', '\r']), line)
            }
            None => Err(SkipReason::NotText),
        };
        match outcome {
            Ok(record) => out.records.push(record),
            Err(reason) => {
                out.skipped += 1;
                out.non_finite += usize::from(matches!(reason, SkipReason::NonFinite { .. }));
                if out.first_skipped.len() < KEEP_SKIPPED {
                    out.first_skipped.push(SkippedLine { line, reason });
                }
            }
        }
    })?;
    Ok(out)
}

/// The fields of one line, and the rules a field must meet (each failure a [`SkipReason`]
/// naming the field).
pub struct Fields<'a> {
    pub(crate) words: Vec<&'a str>,
}

impl<'a> Fields<'a> {
    /// The fields of `text` separated by `delimiter` (whitespace-separated, or
    /// as [`Fields::split`]).
    pub fn of(text: &'a str, delimiter: crate::Delimiter) -> Self {
        match delimiter {
            crate::Delimiter::Whitespace => Self::whitespace(text),
            crate::Delimiter::Char(c) => Self::split(text, c),
        }
    }

    /// Whitespace-separated fields.
    pub(crate) fn whitespace(text: &'a str) -> Self {
        Self {
            words: text.split_whitespace().collect(),
        }
    }

    /// Fields separated by `delimiter`, each trimmed.
    pub fn split(text: &'a str, delimiter: char) -> Self {
        Self {
            words: text.split(delimiter).map(str::trim).collect(),
        }
    }

    /// Checks that the line has exactly `n` fields.
    pub(crate) fn exactly(&self, n: usize) -> Result<(), SkipReason> {
        self.at_least(n)?;
        if self.words.len() > n {
            return Err(SkipReason::TooManyFields {
                expected: n,
                found: self.words.len(),
            });
        }
        Ok(())
    }

    /// Checks that the line has at least `n` fields.
    pub fn at_least(&self, n: usize) -> Result<(), SkipReason> {
        if self.words.len() < n {
            return Err(SkipReason::TooFewFields {
                expected: n,
                found: self.words.len(),
            });
        }
        Ok(())
    }

    /// Field `i` as a number (NaN and infinities allowed).
    pub fn num(&self, i: usize) -> Result<f64, SkipReason> {
        self.at_least(i + 1)?;
        self.words[i]
            .parse()
            .map_err(|_| SkipReason::BadNumber { field: i })
    }

    /// Field `i` as a finite number.
    pub fn finite(&self, i: usize) -> Result<f64, SkipReason> {
        let v = self.num(i)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(SkipReason::NonFinite { field: i })
        }
    }

    /// Field `i` as a non-negative integer, written as one or as an integral float.
    pub(crate) fn integer(&self, i: usize) -> Result<u64, SkipReason> {
        self.at_least(i + 1)?;
        let word = self.words[i];
        if let Ok(n) = word.parse::<u64>() {
            return Ok(n);
        }
        // Integral floats up to 2^53 are exact; beyond that they no longer name one integer.
        const EXACT: f64 = 9_007_199_254_740_992.0;
        match word.parse::<f64>() {
            Ok(v) if v.fract() == 0.0 && (0.0..=EXACT).contains(&v) => Ok(v as u64),
            _ => Err(SkipReason::BadInteger { field: i }),
        }
    }

    /// Field `i` as text.
    pub fn text(&self, i: usize) -> Result<&'a str, SkipReason> {
        self.at_least(i + 1)?;
        Ok(self.words[i])
    }
}
