//! CARMEN log files (`FLASER`, `RLASER`, `ROBOTLASER1`, `ODOM`), plain or gzipped.
//!
//! Malformed lines are skipped and counted, with the first few kept for the report; other
//! message types (`PARAM`, `NEFF`, `SYNC`, …) are counted by type. Only I/O failures are
//! errors.
//!
//! Old-style `FLASER`/`RLASER` lines do not state their geometry. CARMEN's own reader
//! assumes a 180° field of view starting at −90°, with 1° steps for 180 or 181 beams, 0.5°
//! for 360 or 361, and `fov / (n − 1)` otherwise; we do the same. They do not state a
//! maximum range either: SICK scanners log "no return" as about 81.9 m, so readings at or
//! beyond [`CarmenOptions::max_range`] (80 m) are max-range readings.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use crate::{LaserScan, OccupancyError, Pose2, Result};

/// How to read a CARMEN log.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct CarmenOptions {
    /// `range_max` of old-style laser lines: readings at or beyond it are max-range.
    pub max_range: f64,
    /// `range_min` of every laser line.
    pub min_range: f64,
    /// How many skipped lines to keep for the report.
    pub keep_skipped: usize,
}

impl Default for CarmenOptions {
    fn default() -> Self {
        Self {
            max_range: 80.0,
            min_range: 0.0,
            keep_skipped: 10,
        }
    }
}

impl CarmenOptions {
    /// The options, after checking `0 <= min_range < max_range`, both finite.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`] naming the rule broken.
    pub fn check(self) -> Result<Self> {
        haunts_core::non_negative("min_range", self.min_range)?;
        if !(self.max_range.is_finite() && self.max_range > self.min_range) {
            return Err(OccupancyError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "max_range",
                    value: self.max_range,
                    rule: "must be finite and > min_range",
                },
            ));
        }
        Ok(self)
    }
}

/// Which laser message a scan came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LaserKind {
    /// `FLASER`: front laser, old format.
    Front,
    /// `RLASER`: rear laser, old format.
    Rear,
    /// `ROBOTLASER1`: new format with its own geometry.
    Robot,
}

/// One laser message.
#[derive(Debug, Clone, PartialEq)]
pub struct CarmenScan {
    /// The message type.
    pub kind: LaserKind,
    /// The scan (stamp = the message's timestamp).
    pub scan: LaserScan,
    /// Pose of the laser in the world (corrected, in a corrected log).
    pub laser_pose: Pose2,
    /// Odometry pose (`FLASER`/`RLASER`) or robot pose (`ROBOTLASER1`).
    pub robot_pose: Pose2,
    /// Line number (1-based) in the file.
    pub line: usize,
}

/// One `ODOM` message.
#[derive(Debug, Clone, PartialEq)]
pub struct OdomRecord {
    /// Odometry pose.
    pub pose: Pose2,
    /// Translational velocity, m/s.
    pub tv: f64,
    /// Rotational velocity, rad/s.
    pub rv: f64,
    /// Timestamp, seconds.
    pub stamp: f64,
    /// Line number (1-based).
    pub line: usize,
}

/// Why a line was skipped.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum SkipReason {
    /// Fewer fields than the message needs.
    TooFewFields {
        /// Fields the message needs.
        expected: usize,
        /// Fields present.
        found: usize,
    },
    /// A field is not a number (or a count not a non-negative integer).
    BadNumber {
        /// 0-based index of the field after the message name.
        field: usize,
    },
    /// A pose or timestamp is NaN or infinite.
    NonFinite,
    /// The scan description is invalid (e.g. zero angular resolution).
    BadScan,
    /// The line is not valid UTF-8.
    NotText,
}

/// A skipped line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SkippedLine {
    /// Line number (1-based).
    pub line: usize,
    /// The message type (first word).
    pub message: String,
    /// Why.
    pub reason: SkipReason,
}

/// The content of a CARMEN log.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CarmenLog {
    /// Laser messages in file order.
    pub scans: Vec<CarmenScan>,
    /// Odometry messages in file order.
    pub odometry: Vec<OdomRecord>,
    /// Number of malformed lines skipped.
    pub skipped: usize,
    /// Of those, the lines skipped because a pose or timestamp was NaN or infinite
    /// ([`SkipReason::NonFinite`]).
    pub non_finite: usize,
    /// The first skipped lines (up to [`CarmenOptions::keep_skipped`]).
    pub first_skipped: Vec<SkippedLine>,
    /// Counts of messages of other types, by type (comments under `#`).
    pub other_messages: BTreeMap<String, usize>,
}

impl CarmenLog {
    /// The log as a [`Recording`](crate::recording::Recording): every laser message in
    /// file order in frame `laser`, received at its own stamp, and the laser's logged pose as
    /// the odometry of frame `laser` in `odom` (so each scan is placed where the log says its
    /// laser was; a corrected log's poses are corrected). Of laser messages with the same
    /// stamp the pose of the first is kept, and a note counts the others.
    ///
    /// # Errors
    /// [`OccupancyError::NoSamples`] when the log has no scan with a finite pose.
    pub fn to_recording(&self) -> crate::Result<crate::recording::Recording> {
        use crate::recording::{RecordedScan, Recording, ScanList};
        let scans = ScanList(
            self.scans
                .iter()
                .map(|s| RecordedScan {
                    scan: s.scan.clone(),
                    frame: "laser".to_owned(),
                    received: s.scan.stamp,
                })
                .collect(),
        );
        let history = crate::frames::PoseHistory::new(
            self.scans.iter().map(|s| (s.scan.stamp, s.laser_pose)),
        )?;
        let notes = format!(
            "CARMEN log: {} laser messages; laser poses as odometry ({} with a repeated stamp, \
             {} not finite, left out)",
            self.scans.len(),
            history.dropped_duplicates(),
            history.skipped_non_finite()
        );
        Ok(Recording::new(scans)
            .with_odometry(history, "odom", "laser")
            .with_note(notes))
    }
}

/// Reads a CARMEN log file, gzipped or not (told apart by the gzip magic bytes).
///
/// # Errors
/// [`OccupancyError::Io`] when the file cannot be read or the gzip stream is broken;
/// [`OccupancyError::InvalidParameter`] for bad options.
///
/// ```no_run
/// let log = haunts_occupancy::carmen::read_carmen("intel.log.gz", &Default::default())?;
/// println!("{} scans, {} skipped lines", log.scans.len(), log.skipped);
/// # Ok::<(), haunts_occupancy::OccupancyError>(())
/// ```
pub fn read_carmen(path: impl AsRef<Path>, options: &CarmenOptions) -> Result<CarmenLog> {
    let path = path.as_ref();
    let options = options.clone().check()?;
    let io = |e| crate::error::io_error(path, e);
    let reader = crate::text::open_maybe_gzip(path).map_err(io)?;
    parse_lines(reader, &options).map_err(io)
}

/// Parses CARMEN log lines from any reader.
///
/// # Errors
/// [`OccupancyError::InvalidParameter`] for bad options; [`OccupancyError::Io`] (path
/// `(reader)`) for the reader's errors. Malformed lines are skipped and counted.
pub fn parse_carmen(reader: impl Read, options: &CarmenOptions) -> Result<CarmenLog> {
    let options = options.clone().check()?;
    parse_lines(reader, &options).map_err(|e| crate::error::io_error(Path::new("(reader)"), e))
}

fn parse_lines(reader: impl Read, options: &CarmenOptions) -> std::io::Result<CarmenLog> {
    let mut log = CarmenLog::default();
    crate::text::for_each_line(reader, |line_no, text| {
        let outcome = match text {
            Some(text) => parse_line(text, line_no, options, &mut log),
            None => Err(("?".to_owned(), SkipReason::NotText)),
        };
        if let Err((message, reason)) = outcome {
            log.skipped += 1;
            log.non_finite += usize::from(reason == SkipReason::NonFinite);
            if log.first_skipped.len() < options.keep_skipped {
                log.first_skipped.push(SkippedLine {
                    line: line_no,
                    message,
                    reason,
                });
            }
        }
    })?;
    Ok(log)
}

/// Numbers of one line after its message name.
struct Fields<'a> {
    words: Vec<&'a str>,
}

impl Fields<'_> {
    fn need(&self, n: usize) -> Result<(), SkipReason> {
        if self.words.len() < n {
            return Err(SkipReason::TooFewFields {
                expected: n,
                found: self.words.len(),
            });
        }
        Ok(())
    }
    fn num(&self, i: usize) -> Result<f64, SkipReason> {
        self.need(i + 1)?;
        self.words[i]
            .parse()
            .map_err(|_| SkipReason::BadNumber { field: i })
    }
    fn finite(&self, i: usize) -> Result<f64, SkipReason> {
        self.num(i).and_then(|v| {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(SkipReason::NonFinite)
            }
        })
    }
    /// A count of values that follow field `i`; more than the line holds is `TooFewFields`,
    /// so that no later index arithmetic can overflow.
    fn count(&self, i: usize) -> Result<usize, SkipReason> {
        self.need(i + 1)?;
        let n: usize = self.words[i]
            .parse()
            .map_err(|_| SkipReason::BadNumber { field: i })?;
        if n > self.words.len() - i - 1 {
            return Err(SkipReason::TooFewFields {
                expected: n.saturating_add(i + 1),
                found: self.words.len(),
            });
        }
        Ok(n)
    }
    fn pose(&self, i: usize) -> Result<Pose2, SkipReason> {
        Ok(Pose2::new(
            nalgebra::Vector2::new(self.finite(i)?, self.finite(i + 1)?),
            self.finite(i + 2)?,
        ))
    }
    fn ranges(&self, from: usize, n: usize) -> Result<Vec<f64>, SkipReason> {
        self.need(from + n)?;
        (from..from + n).map(|i| self.num(i)).collect()
    }
}

fn old_laser_geometry(n: usize) -> (f64, f64) {
    use std::f64::consts::PI;
    let increment = match n {
        180 | 181 => PI / 180.0,
        360 | 361 => PI / 360.0,
        0 | 1 => PI,
        _ => PI / (n - 1) as f64,
    };
    (-PI / 2.0, increment)
}

type LineOutcome = std::result::Result<(), (String, SkipReason)>;

fn parse_line(
    text: &str,
    line: usize,
    options: &CarmenOptions,
    log: &mut CarmenLog,
) -> LineOutcome {
    let mut words = text.split_ascii_whitespace();
    let Some(message) = words.next() else {
        return Ok(());
    };
    let f = Fields {
        words: words.collect(),
    };
    let fail = |reason| (message.to_owned(), reason);
    match message {
        "FLASER" | "RLASER" => {
            let n = f.count(0).map_err(fail)?;
            let ranges = f.ranges(1, n).map_err(fail)?;
            let laser_pose = f.pose(1 + n).map_err(fail)?;
            let robot_pose = f.pose(4 + n).map_err(fail)?;
            let stamp = f.finite(7 + n).map_err(fail)?;
            let (angle_min, increment) = old_laser_geometry(n);
            let scan = LaserScan::new(
                stamp,
                angle_min,
                increment,
                options.min_range,
                options.max_range,
                ranges,
                vec![],
            )
            .map_err(|_| fail(SkipReason::BadScan))?;
            let kind = if message == "FLASER" {
                LaserKind::Front
            } else {
                LaserKind::Rear
            };
            log.scans.push(CarmenScan {
                kind,
                scan,
                laser_pose,
                robot_pose,
                line,
            });
        }
        "ROBOTLASER1" => {
            let start = f.finite(1).map_err(fail)?;
            let resolution = f.finite(3).map_err(fail)?;
            let max_range = f.finite(4).map_err(fail)?;
            let n = f.count(7).map_err(fail)?;
            let ranges = f.ranges(8, n).map_err(fail)?;
            let m = f.count(8 + n).map_err(fail)?;
            let remissions = f.ranges(9 + n, m).map_err(fail)?;
            let at = 9 + n + m;
            let laser_pose = f.pose(at).map_err(fail)?;
            let robot_pose = f.pose(at + 3).map_err(fail)?;
            let stamp = f.finite(at + 11).map_err(fail)?;
            let intensities = if m == n { remissions } else { vec![] };
            let scan = LaserScan::new(
                stamp,
                start,
                resolution,
                options.min_range,
                max_range,
                ranges,
                intensities,
            )
            .map_err(|_| fail(SkipReason::BadScan))?;
            log.scans.push(CarmenScan {
                kind: LaserKind::Robot,
                scan,
                laser_pose,
                robot_pose,
                line,
            });
        }
        "ODOM" => {
            let pose = f.pose(0).map_err(fail)?;
            let (tv, rv) = (f.finite(3).map_err(fail)?, f.finite(4).map_err(fail)?);
            let stamp = f.finite(6).map_err(fail)?;
            log.odometry.push(OdomRecord {
                pose,
                tv,
                rv,
                stamp,
                line,
            });
        }
        other => {
            let key = if other.starts_with('#') { "#" } else { other };
            *log.other_messages.entry(key.to_owned()).or_insert(0) += 1;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn parse(text: &str) -> CarmenLog {
        parse_carmen(text.as_bytes(), &CarmenOptions::default()).unwrap()
    }

    #[test]
    fn reads_every_message_type() {
        let log = parse(
            "# comment\nPARAM a 1 host 0\n\
             FLASER 3 1.0 2.0 81.9 0.5 0.25 0.1 0.6 0.3 0.2 12.5 host 12.5\n\
             RLASER 2 nan inf 1 2 3 1 2 3 13.0 host 13.0\n\
             ROBOTLASER1 0 -1.5 3.0 1.0 30.0 0.01 0 4 1 2 3 4 4 9 9 9 9 0 0 0 1 1 0 0.2 0.1 1 1 0 14.0 host 14.0\n\
             ODOM 1.5 2.5 0.3 0.4 0.05 0 15.0 host 15.0\n",
        );
        assert_eq!(log.skipped, 0, "{:?}", log.first_skipped);
        assert_eq!(log.scans.len(), 3);
        let f = &log.scans[0];
        assert_eq!((f.kind, f.line, f.scan.len()), (LaserKind::Front, 3, 3));
        assert_eq!(f.scan.endpoints().count(), 2); // 81.9 m is a max-range reading
        assert_relative_eq!(f.scan.angle_min, -std::f64::consts::FRAC_PI_2);
        assert_relative_eq!(f.laser_pose.translation.vector.x, 0.5);
        assert_relative_eq!(f.robot_pose.rotation.angle(), 0.2, epsilon = 1e-12);
        assert_eq!(f.scan.stamp, 12.5);
        assert_eq!(log.scans[1].kind, LaserKind::Rear);
        assert_eq!(log.scans[1].scan.endpoints().count(), 0);
        let r = &log.scans[2];
        assert_eq!(
            (r.kind, r.scan.len(), r.scan.intensities.len()),
            (LaserKind::Robot, 4, 4)
        );
        assert_eq!(
            (r.scan.angle_min, r.scan.angle_increment, r.scan.range_max),
            (-1.5, 1.0, 30.0)
        );
        assert_relative_eq!(r.robot_pose.translation.vector.x, 1.0);
        assert_eq!(r.scan.stamp, 14.0);
        assert_eq!(log.odometry.len(), 1);
        assert_eq!((log.odometry[0].stamp, log.odometry[0].tv), (15.0, 0.4));
        assert_eq!(log.other_messages.get("PARAM"), Some(&1));
        assert_eq!(log.other_messages.get("#"), Some(&1));
    }

    #[test]
    fn malformed_lines_are_skipped_counted_and_reported() {
        let log = parse(
            "FLASER 3 1.0 2.0\n\
             FLASER x 1.0\n\
             FLASER 1 1.0 nan 0 0 0 0 0 1.0 h 1.0\n\
             ODOM 1 2\n\
             ODOM 1 2 3 4 5 6 7 h 7\n",
        );
        assert_eq!(log.skipped, 4);
        assert_eq!(log.non_finite, 1);
        assert_eq!(log.odometry.len(), 1);
        assert_eq!(
            log.first_skipped[0].reason,
            SkipReason::TooFewFields {
                expected: 4,
                found: 3
            }
        );
        assert_eq!(
            log.first_skipped[1].reason,
            SkipReason::BadNumber { field: 0 }
        );
        assert_eq!(log.first_skipped[2].reason, SkipReason::NonFinite);
        assert_eq!(
            (
                log.first_skipped[3].line,
                log.first_skipped[3].message.as_str()
            ),
            (4, "ODOM")
        );
        let log = parse(
            "FLASER 18446744073709551615 1 2\nROBOTLASER1 0 0 1 1 9 0 0 1 1 18446744073709551615 1\n",
        );
        assert_eq!(
            log.skipped, 2,
            "counts beyond the line are short lines, not overflows"
        );
        assert!(matches!(
            log.first_skipped[0].reason,
            SkipReason::TooFewFields { found: 3, .. }
        ));
        let bad = CarmenOptions {
            max_range: 0.0,
            ..Default::default()
        };
        assert!(matches!(
            parse_carmen(&b""[..], &bad),
            Err(OccupancyError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "max_range",
                    ..
                }
            ))
        ));
        let bytes = b"FLASER \xff\xfe\nODOM 1 2 3 4 5 6 7 h 7\n";
        let log = parse_carmen(&bytes[..], &CarmenOptions::default()).unwrap();
        assert_eq!((log.skipped, log.odometry.len()), (1, 1));
        assert_eq!(log.first_skipped[0].reason, SkipReason::NotText);
    }
}
