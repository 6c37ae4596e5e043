//! Pedestrian trajectories, and their readers: ETH `obsmat.txt` and generic delimited files.
//!
//! Both readers group rows by id, sort each trajectory's samples by time, and return the
//! trajectories by increasing id. Malformed lines are skipped and counted (see [`Parsed`]).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use haunts_occupancy::bounds::{BoundsRule, Kept};
use nalgebra::Point2;

use crate::io::lines::{Fields, Parsed, parse_lines, read_path, read_reader};
use crate::{Result, TrackingError};

/// One person's path: positions at increasing times.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Trajectory {
    /// The person's id in the file.
    pub id: u64,
    /// `(time in seconds, position in metres)`, sorted by time (ties keep file order).
    pub samples: Vec<(f64, Point2<f64>)>,
}

/// One row of a trajectory file before grouping.
#[derive(Debug, Clone, Copy)]
struct Row {
    time: f64,
    id: u64,
    position: Point2<f64>,
}

/// Groups rows by id, each group sorted by time.
fn group(rows: Parsed<Row>, time_scale: f64) -> Parsed<Trajectory> {
    let mut by_id: BTreeMap<u64, Vec<(f64, Point2<f64>)>> = BTreeMap::new();
    for row in &rows.records {
        by_id
            .entry(row.id)
            .or_default()
            .push((row.time * time_scale, row.position));
    }
    let trajectories = by_id
        .into_iter()
        .map(|(id, mut samples)| {
            samples.sort_by(|a, b| a.0.total_cmp(&b.0));
            Trajectory { id, samples }
        })
        .collect();
    rows.with_records(trajectories)
}

/// The trajectories through the bounds rule ([`haunts_occupancy::bounds`]): each sample far
/// from the bulk of all samples, or not finite, is removed from its trajectory, and a
/// trajectory left without samples is dropped. The counts and the named rows are of
/// samples (indexed in the order of `trajectories`, then of their samples); the kept
/// trajectories keep their order, and their samples theirs, so a file of good rows plus far
/// rows gives the trajectories of the good rows alone.
///
/// # Errors
/// [`TrackingError::Occupancy`] with [`NoUsableRows`](haunts_occupancy::OccupancyError::NoUsableRows)
/// when no sample is kept, or for a rule its check refuses.
///
/// ```
/// use haunts_occupancy::bounds::BoundsRule;
/// use haunts_tracking::io::trajectory::{keep_near, Trajectory};
/// use nalgebra::Point2;
/// let walk = |id, x0: f64| Trajectory {
///     id,
///     samples: (0..30).map(|i| (f64::from(i), Point2::new(x0 + f64::from(i) * 0.3, 1.0))).collect(),
/// };
/// let mut glitch = walk(1, 0.0);
/// glitch.samples[7].1.x = 1.0e7;
/// let kept = keep_near(vec![glitch, walk(2, 5.0)], &BoundsRule::default())?;
/// assert_eq!(kept.rows[0].samples.len(), 29);
/// assert_eq!(kept.skipped.counts.far, 1);
/// assert_eq!(kept.skipped.first_far[0].index, 7);
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
pub fn keep_near(trajectories: Vec<Trajectory>, rule: &BoundsRule) -> Result<Kept<Trajectory>> {
    let samples: Vec<(usize, (f64, Point2<f64>))> = trajectories
        .iter()
        .enumerate()
        .flat_map(|(k, t)| t.samples.iter().map(move |s| (k, *s)))
        .collect();
    let mut kept = rule.split("trajectory samples", samples, |(_, s)| s.1)?;
    let mut out: Vec<Trajectory> = trajectories
        .into_iter()
        .map(|t| Trajectory {
            id: t.id,
            samples: Vec::new(),
        })
        .collect();
    for (k, sample) in std::mem::take(&mut kept.rows) {
        out[k].samples.push(sample);
    }
    out.retain(|t| !t.samples.is_empty());
    Ok(kept.with_rows(out))
}

/// The annotation rate of the ETH (and UCY) sequences, Hz: one annotated frame every 0.4 s
/// (`info.txt` of both ETH sequences).
pub(crate) const ETH_ANNOTATION_RATE: f64 = 2.5;

/// How to read an ETH `obsmat.txt`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct EthOptions {
    /// Video frame rate, Hz: a row's time is `frame / frame_rate` seconds.
    ///
    /// `None` (the default) infers it as OpenTraj's ETH loader does: the most common step
    /// between consecutive annotated frame numbers, times the annotation rate of 2.5 Hz, so that
    /// annotations are 0.4 s apart. That gives 15 Hz for `seq_eth` (frames in steps of 6)
    /// and 25 Hz for `seq_hotel` (steps of 10, its stated video rate).
    pub frame_rate: Option<f64>,
}

impl EthOptions {
    /// Options with a fixed frame rate, Hz.
    pub fn with_frame_rate(mut self, frame_rate: f64) -> Self {
        self.frame_rate = Some(frame_rate);
        self
    }

    /// The options, after checking that a given frame rate is finite and positive.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] for a bad frame rate.
    pub fn check(self) -> Result<Self> {
        if let Some(rate) = self.frame_rate {
            haunts_core::positive("frame_rate", rate)?;
        }
        Ok(self)
    }
}

/// Reads an ETH `obsmat.txt` (plain or gzipped): whitespace-separated rows `frame id pos_x
/// pos_z pos_y v_x v_z v_y` (metres). Positions are `(pos_x, pos_y)`, columns 2 and 4; the
/// velocities are ignored, so rows need only the first five columns.
///
/// # Errors
/// [`TrackingError::InvalidParameter`] for bad options; [`TrackingError::Io`] when the file
/// cannot be read.
pub fn read_eth(path: impl AsRef<Path>, options: &EthOptions) -> Result<Parsed<Trajectory>> {
    let options = options.check()?;
    let rows = read_path(path.as_ref(), |r| rows(r, &DelimitedOptions::ETH))?;
    Ok(eth_trajectories(rows, &options))
}

/// Parses ETH `obsmat.txt` rows from any reader (see [`read_eth`]).
///
/// # Errors
/// [`TrackingError::InvalidParameter`] for bad options; [`TrackingError::Io`] (path
/// `(reader)`) for the reader's errors.
pub fn parse_eth(reader: impl Read, options: &EthOptions) -> Result<Parsed<Trajectory>> {
    let options = options.check()?;
    let rows = read_reader(reader, |r| rows(r, &DelimitedOptions::ETH))?;
    Ok(eth_trajectories(rows, &options))
}

fn eth_trajectories(rows: Parsed<Row>, options: &EthOptions) -> Parsed<Trajectory> {
    let rate = options
        .frame_rate
        .unwrap_or_else(|| usual_frame_step(&rows.records) * ETH_ANNOTATION_RATE);
    group(rows, 1.0 / rate)
}

/// The most common positive step between consecutive distinct frame numbers (the smallest
/// on ties), or 1 when there are fewer than two frames.
fn usual_frame_step(rows: &[Row]) -> f64 {
    let mut frames: Vec<f64> = rows.iter().map(|r| r.time).collect();
    frames.sort_by(f64::total_cmp);
    frames.dedup();
    let mut steps: Vec<f64> = frames.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let mut best = (1.0, 0);
    for run in steps.chunk_by(|a, b| a == b) {
        if run.len() > best.1 {
            best = (run[0], run.len());
        }
    }
    best.0
}

/// What separates the fields of a delimited file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Delimiter {
    /// Any run of spaces and tabs.
    #[default]
    Whitespace,
    /// One character (e.g. `,` or `;`); fields are trimmed of surrounding spaces.
    Char(char),
}

/// Which columns of a delimited file hold what (0-based), and how fields are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct DelimitedOptions {
    /// Column of the time, seconds.
    pub time: usize,
    /// Column of the person's id (a non-negative integer, or an integral float).
    pub id: usize,
    /// Column of x, metres.
    pub x: usize,
    /// Column of y, metres.
    pub y: usize,
    /// The field separator.
    pub delimiter: Delimiter,
    /// Lines to ignore at the top of the file (a header row); later `#` comments and blank
    /// lines are always ignored.
    pub header_lines: usize,
}

impl Default for DelimitedOptions {
    /// `time id x y`, whitespace separated, no header.
    fn default() -> Self {
        Self {
            time: 0,
            id: 1,
            x: 2,
            y: 3,
            delimiter: Delimiter::Whitespace,
            header_lines: 0,
        }
    }
}

impl DelimitedOptions {
    /// ETH `obsmat.txt`: frame, id, x in column 2, y in column 4.
    const ETH: Self = Self {
        time: 0,
        id: 1,
        x: 2,
        y: 4,
        delimiter: Delimiter::Whitespace,
        header_lines: 0,
    };

    /// Sets the columns of time, id, x and y.
    pub fn with_columns(mut self, time: usize, id: usize, x: usize, y: usize) -> Self {
        (self.time, self.id, self.x, self.y) = (time, id, x, y);
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

    /// The options, after checking that the four columns differ and are below `usize::MAX`.
    ///
    /// # Errors
    /// [`TrackingError::ColumnClash`] naming two roles given the same column;
    /// [`TrackingError::InvalidParameter`] (named after the role) for a column `usize::MAX`.
    pub fn check(self) -> Result<Self> {
        let roles = [
            ("time", self.time),
            ("id", self.id),
            ("x", self.x),
            ("y", self.y),
        ];
        for (i, &(first, column)) in roles.iter().enumerate() {
            // A line would need `column + 1` fields, which must not wrap.
            if column == usize::MAX {
                return Err(TrackingError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: first,
                        value: column as f64,
                        rule: "a column index must be below usize::MAX",
                    },
                ));
            }
            if let Some(&(second, _)) = roles[i + 1..].iter().find(|r| r.1 == column) {
                return Err(TrackingError::ColumnClash {
                    first,
                    second,
                    column,
                });
            }
        }
        Ok(self)
    }
}

/// Reads a delimited trajectory file (plain or gzipped) with the given columns. A line
/// needs every chosen column; its time and position must be finite.
///
/// # Errors
/// [`TrackingError::ColumnClash`] or [`TrackingError::InvalidParameter`] for bad options;
/// [`TrackingError::Io`] when the file cannot be read.
pub fn read_delimited(
    path: impl AsRef<Path>,
    options: &DelimitedOptions,
) -> Result<Parsed<Trajectory>> {
    let options = options.check()?;
    let rows = read_path(path.as_ref(), |r| rows(r, &options))?;
    Ok(group(rows, 1.0))
}

/// Parses a delimited trajectory file from any reader (see [`read_delimited`]).
///
/// # Errors
/// [`TrackingError::ColumnClash`] or [`TrackingError::InvalidParameter`] for bad options;
/// [`TrackingError::Io`] (path `(reader)`) for the reader's errors.
pub fn parse_delimited(
    reader: impl Read,
    options: &DelimitedOptions,
) -> Result<Parsed<Trajectory>> {
    let options = options.check()?;
    let rows = read_reader(reader, |r| rows(r, &options))?;
    Ok(group(rows, 1.0))
}

fn rows(reader: &mut dyn Read, options: &DelimitedOptions) -> std::io::Result<Parsed<Row>> {
    let needed = 1 + options.time.max(options.id).max(options.x).max(options.y);
    parse_lines(reader, options.header_lines, |text, _line| {
        let f = Fields::of(text, options.delimiter);
        f.at_least(needed)?;
        Ok(Row {
            time: f.finite(options.time)?,
            id: f.integer(options.id)?,
            position: Point2::new(f.finite(options.x)?, f.finite(options.y)?),
        })
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use approx::assert_relative_eq;

    use super::*;
    use crate::{SkipReason, SkippedLine};

    const OBSMAT: &str = "\
   7.8000000e+02   1.0000000e+00   8.4568443e+00   0.0000000e+00   3.5880664e+00   1.6717144e+00   0.0000000e+00   1.7629183e-01
   7.9200000e+02   1.0000000e+00   9.7871460e+00   0.0000000e+00   3.8494445e+00   1.6833339e+00   0.0000000e+00   3.7108399e-01
   7.8600000e+02   1.0000000e+00   9.1255301e+00   0.0000000e+00   3.6585832e+00   1.6628772e+00   0.0000000e+00   3.2672255e-01
   7.8600000e+02   2.0000000e+00   1.0000000e+00   0.0000000e+00   2.0000000e+00
   7.9800000e+02   2.5000000e+00   1.0000000e+00   0.0000000e+00   2.0000000e+00
   8.0400000e+02   3.0000000e+00   1.0000000e+00   0.0000000e+00
   8.1000000e+02   3.0000000e+00   nan   0.0000000e+00   2.0000000e+00
";

    #[test]
    fn eth_groups_by_id_sorts_by_time_and_infers_the_frame_rate() {
        let parsed = parse_eth(OBSMAT.as_bytes(), &EthOptions::default()).unwrap();
        let ids: Vec<u64> = parsed.records.iter().map(|t| t.id).collect();
        assert_eq!(ids, vec![1, 2]);
        let one = &parsed.records[0];
        // Frames step by 6, so the inferred rate is 6 × 2.5 = 15 Hz.
        let times: Vec<f64> = one.samples.iter().map(|s| s.0).collect();
        assert_relative_eq!(times[0], 780.0 / 15.0, epsilon = 1e-9);
        assert_relative_eq!(times[1] - times[0], 0.4, epsilon = 1e-9);
        assert_relative_eq!(times[2] - times[1], 0.4, epsilon = 1e-9);
        assert_relative_eq!(one.samples[1].1.x, 9.1255301, epsilon = 1e-12);
        assert_relative_eq!(one.samples[1].1.y, 3.6585832, epsilon = 1e-12);
        assert_eq!(parsed.skipped, 3);
        assert_eq!(
            parsed.first_skipped,
            vec![
                SkippedLine {
                    line: 5,
                    reason: SkipReason::BadInteger { field: 1 }
                },
                SkippedLine {
                    line: 6,
                    reason: SkipReason::TooFewFields {
                        expected: 5,
                        found: 4
                    }
                },
                SkippedLine {
                    line: 7,
                    reason: SkipReason::NonFinite { field: 2 }
                },
            ]
        );
    }

    #[test]
    fn eth_uses_a_given_frame_rate_and_rejects_a_bad_one() {
        let parsed = parse_eth(
            OBSMAT.as_bytes(),
            &EthOptions::default().with_frame_rate(25.0),
        );
        assert_relative_eq!(parsed.unwrap().records[0].samples[0].0, 780.0 / 25.0);
        let bad = parse_eth(
            OBSMAT.as_bytes(),
            &EthOptions::default().with_frame_rate(0.0),
        );
        assert!(matches!(
            bad,
            Err(TrackingError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "frame_rate",
                    ..
                }
            ))
        ));
    }

    #[test]
    fn delimited_reads_chosen_columns_with_a_char_delimiter() {
        let text = "t;who;skip;y;x\n\
            # a comment\n\
            2.0; 7; a; 1.5; 0.5\n\
            1.0; 7; b; 1.0; 0.0\n\
            1.5; 3; c; 9.0; 8.0\n\
            1.5; 3; c; 9.0\n\
            inf; 3; c; 9.0; 8.0\n\
            1.7; x; c; 9.0; 8.0\n";
        let options = DelimitedOptions::default()
            .with_columns(0, 1, 4, 3)
            .with_delimiter(Delimiter::Char(';'))
            .with_header_lines(1);
        let parsed = parse_delimited(text.as_bytes(), &options).unwrap();
        assert_eq!(parsed.records.len(), 2);
        assert_eq!(parsed.records[0].id, 3);
        let seven = &parsed.records[1];
        assert_eq!(seven.id, 7);
        assert_eq!(
            seven.samples,
            vec![(1.0, Point2::new(0.0, 1.0)), (2.0, Point2::new(0.5, 1.5))]
        );
        let reasons: Vec<_> = parsed
            .first_skipped
            .iter()
            .map(|s| (s.line, s.reason.clone()))
            .collect();
        assert_eq!(
            reasons,
            vec![
                (
                    6,
                    SkipReason::TooFewFields {
                        expected: 5,
                        found: 4
                    }
                ),
                (7, SkipReason::NonFinite { field: 0 }),
                (8, SkipReason::BadInteger { field: 1 }),
            ]
        );
    }

    #[test]
    fn delimited_defaults_to_whitespace_time_id_x_y() {
        let parsed = parse_delimited("0 1 2 3\n1\t1\t4\t5\n".as_bytes(), &Default::default());
        let parsed = parsed.unwrap();
        assert_eq!(parsed.skipped, 0);
        assert_eq!(parsed.records[0].samples[1], (1.0, Point2::new(4.0, 5.0)));
    }

    #[test]
    fn clashing_columns_are_rejected() {
        let options = DelimitedOptions::default().with_columns(0, 1, 2, 1);
        assert!(matches!(
            options.check(),
            Err(TrackingError::ColumnClash {
                first: "id",
                second: "y",
                column: 1
            })
        ));
    }

    #[test]
    fn a_column_of_usize_max_is_an_error_not_a_wrapped_panic() {
        // `1 + max` wrapped to 0 fields needed, then indexing panicked.
        let options = DelimitedOptions::default().with_columns(0, 1, usize::MAX, 3);
        assert!(matches!(
            parse_delimited("1 2 3 4\n".as_bytes(), &options),
            Err(TrackingError::InvalidParameter(
                haunts_core::InvalidParameter { name: "x", .. }
            ))
        ));
        // The largest usable column only skips lines that are too short.
        let options = DelimitedOptions::default().with_columns(0, 1, usize::MAX - 1, 3);
        let parsed = parse_delimited("1 2 3 4\n".as_bytes(), &options).unwrap();
        assert_eq!((parsed.records.len(), parsed.skipped), (0, 1));
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..400)) {
            let parsed = parse_delimited(&bytes[..], &Default::default()).unwrap();
            proptest::prop_assert!(parsed.first_skipped.len() <= parsed.skipped);
            let _ = parse_eth(&bytes[..], &EthOptions::default()).unwrap();
            let _ = crate::parse_scans(&bytes[..]).unwrap();
        }
    }
}
