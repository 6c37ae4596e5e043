//! The text export of a `leg_tracker` benchmark bag: `scans.txt`, `odom.txt`, `static_tf.txt`
//! and `ground_truth_people.txt`.
//!
//! Each file holds one record per line, whitespace separated, after a `#` comment naming the
//! columns. Times are seconds: `bag_time` is when the message was recorded in the bag,
//! `stamp` the time in its header. Malformed lines are skipped and counted (see [`Parsed`]);
//! only I/O failures are errors.

use std::io::Read;
use std::path::Path;

use haunts_occupancy::{LaserScan, OccupancyError, Pose2};
use nalgebra::Point2;

use crate::Result;
use crate::io::lines::{Fields, Parsed, SkipReason, parse_lines, read_path, read_reader};

/// One laser scan of `scans.txt`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StampedScan {
    /// When the scan was recorded in the bag, seconds.
    pub bag_time: f64,
    /// The frame the scan is expressed in (e.g. `left_laser`).
    pub frame: String,
    /// The scan; its `stamp` is the header stamp.
    pub scan: LaserScan,
    /// Line number (1-based).
    pub line: usize,
}

/// One odometry pose of `odom.txt`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct OdomPose {
    /// When the message was recorded in the bag, seconds.
    pub bag_time: f64,
    /// Header stamp, seconds.
    pub stamp: f64,
    /// Pose of the robot base in the odometry frame.
    pub pose: Pose2,
    /// Line number (1-based).
    pub line: usize,
}

/// One static transform of `static_tf.txt`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StaticTransform {
    /// The parent frame (e.g. `base_link`).
    pub parent: String,
    /// The child frame (e.g. `left_laser`).
    pub child: String,
    /// Pose of the child frame in the parent frame.
    pub transform: Pose2,
    /// Line number (1-based).
    pub line: usize,
}

/// One annotated position of `ground_truth_people.txt`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PersonPosition {
    /// When the annotation was recorded in the bag, seconds.
    pub bag_time: f64,
    /// The person's id.
    pub id: u64,
    /// The person's position, metres, in the annotation's frame (the laser frame in the
    /// `leg_tracker` benchmarks).
    pub position: Point2<f64>,
    /// Line number (1-based).
    pub line: usize,
}

/// Reads `scans.txt` (plain or gzipped): per line `bag_time stamp frame_id angle_min
/// angle_increment range_min range_max n r_1 … r_n`.
///
/// Ranges may be `inf` or `nan`; times and the scan's geometry must be finite and keep the
/// rules of [`LaserScan::new`], and the line must hold exactly `n` ranges.
///
/// # Errors
/// [`crate::TrackingError::Io`] when the file cannot be read.
pub fn read_scans(path: impl AsRef<Path>) -> Result<Parsed<StampedScan>> {
    read_path(path.as_ref(), scans)
}

/// Parses `scans.txt` lines from any reader (see [`read_scans`]).
///
/// # Errors
/// [`crate::TrackingError::Io`] (path `(reader)`) for the reader's errors.
pub fn parse_scans(reader: impl Read) -> Result<Parsed<StampedScan>> {
    read_reader(reader, scans)
}

fn scans(reader: &mut dyn Read) -> std::io::Result<Parsed<StampedScan>> {
    parse_lines(reader, 0, |text, line| {
        let f = Fields::whitespace(text);
        f.at_least(8)?;
        let bag_time = f.finite(0)?;
        let stamp = f.finite(1)?;
        let frame = f.text(2)?.to_owned();
        let angle_min = f.num(3)?;
        let angle_increment = f.num(4)?;
        let range_min = f.num(5)?;
        let range_max = f.num(6)?;
        let declared = f.integer(7)?;
        let found = f.words.len() - 8;
        if usize::try_from(declared).ok() != Some(found) {
            return Err(SkipReason::CountMismatch {
                declared: usize::try_from(declared).unwrap_or(usize::MAX),
                found,
            });
        }
        let ranges = (8..f.words.len())
            .map(|i| f.num(i))
            .collect::<Result<Vec<_>, _>>()?;
        let scan = LaserScan::new(
            stamp,
            angle_min,
            angle_increment,
            range_min,
            range_max,
            ranges,
            Vec::new(),
        )
        .map_err(|e| match e {
            OccupancyError::InvalidScan { field, .. } => SkipReason::BadScan { field },
            _ => SkipReason::BadScan { field: "ranges" },
        })?;
        Ok(StampedScan {
            bag_time,
            frame,
            scan,
            line,
        })
    })
}

/// Reads `odom.txt` (plain or gzipped): per line `bag_time stamp x y yaw`, all finite.
///
/// # Errors
/// [`crate::TrackingError::Io`] when the file cannot be read.
pub fn read_odometry(path: impl AsRef<Path>) -> Result<Parsed<OdomPose>> {
    read_path(path.as_ref(), odometry)
}

/// Parses `odom.txt` lines from any reader (see [`read_odometry`]).
///
/// # Errors
/// [`crate::TrackingError::Io`] (path `(reader)`) for the reader's errors.
pub fn parse_odometry(reader: impl Read) -> Result<Parsed<OdomPose>> {
    read_reader(reader, odometry)
}

fn odometry(reader: &mut dyn Read) -> std::io::Result<Parsed<OdomPose>> {
    parse_lines(reader, 0, |text, line| {
        let f = Fields::whitespace(text);
        f.exactly(5)?;
        Ok(OdomPose {
            bag_time: f.finite(0)?,
            stamp: f.finite(1)?,
            pose: Pose2::new([f.finite(2)?, f.finite(3)?].into(), f.finite(4)?),
            line,
        })
    })
}

/// Reads `static_tf.txt` (plain or gzipped): per line `parent child x y yaw`, numbers finite.
///
/// # Errors
/// [`crate::TrackingError::Io`] when the file cannot be read.
pub fn read_static_transforms(path: impl AsRef<Path>) -> Result<Parsed<StaticTransform>> {
    read_path(path.as_ref(), static_transforms)
}

/// Parses `static_tf.txt` lines from any reader (see [`read_static_transforms`]).
///
/// # Errors
/// [`crate::TrackingError::Io`] (path `(reader)`) for the reader's errors.
pub fn parse_static_transforms(reader: impl Read) -> Result<Parsed<StaticTransform>> {
    read_reader(reader, static_transforms)
}

fn static_transforms(reader: &mut dyn Read) -> std::io::Result<Parsed<StaticTransform>> {
    parse_lines(reader, 0, |text, line| {
        let f = Fields::whitespace(text);
        f.exactly(5)?;
        Ok(StaticTransform {
            parent: f.text(0)?.to_owned(),
            child: f.text(1)?.to_owned(),
            transform: Pose2::new([f.finite(2)?, f.finite(3)?].into(), f.finite(4)?),
            line,
        })
    })
}

/// Reads `ground_truth_people.txt` (plain or gzipped): per line `bag_time person_id x y`,
/// numbers finite, the id a non-negative integer.
///
/// # Errors
/// [`crate::TrackingError::Io`] when the file cannot be read.
pub fn read_ground_truth(path: impl AsRef<Path>) -> Result<Parsed<PersonPosition>> {
    read_path(path.as_ref(), ground_truth)
}

/// Parses `ground_truth_people.txt` lines from any reader (see [`read_ground_truth`]).
///
/// # Errors
/// [`crate::TrackingError::Io`] (path `(reader)`) for the reader's errors.
pub fn parse_ground_truth(reader: impl Read) -> Result<Parsed<PersonPosition>> {
    read_reader(reader, ground_truth)
}

fn ground_truth(reader: &mut dyn Read) -> std::io::Result<Parsed<PersonPosition>> {
    parse_lines(reader, 0, |text, line| {
        let f = Fields::whitespace(text);
        f.exactly(4)?;
        Ok(PersonPosition {
            bag_time: f.finite(0)?,
            id: f.integer(1)?,
            position: Point2::new(f.finite(2)?, f.finite(3)?),
            line,
        })
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use approx::assert_relative_eq;

    use super::*;
    use crate::SkippedLine;

    fn reasons<T>(parsed: &Parsed<T>) -> Vec<(usize, SkipReason)> {
        parsed
            .first_skipped
            .iter()
            .map(|SkippedLine { line, reason }| (*line, reason.clone()))
            .collect()
    }

    #[test]
    fn scans_keep_good_lines_and_count_bad_ones() {
        let text = "# bag_time stamp frame angle_min inc rmin rmax n ranges\n\
            10.5 10.4 laser -1.0 0.5 0.03 11.0 3 1.0 inf nan\n\
            10.6 10.5 laser -1.0 0.5 0.03 11.0\n\
            10.7 10.6 laser -1.0 0.5 0.03 11.0 3 1.0 2.0\n\
            10.8 10.7 laser -1.0 0.5 0.03 11.0 2 1.0 2.0 3.0\n\
            nan 10.8 laser -1.0 0.5 0.03 11.0 1 1.0\n\
            11.0 nan laser -1.0 0.5 0.03 11.0 1 1.0\n\
            11.1 11.0 laser -1.0 0.0 0.03 11.0 1 1.0\n\
            11.2 11.1 laser -1.0 0.5 0.03 11.0 1 x\n\
            11.3 11.2 laser -1.0 0.5 0.03 11.0 1.5 1.0\n\
            \n\
            11.4 11.3 laser -1.0 0.5 0.03 11.0 0\n";
        let parsed = parse_scans(text.as_bytes()).unwrap();
        assert_eq!(parsed.records.len(), 2);
        let first = &parsed.records[0];
        assert_eq!((first.line, first.frame.as_str()), (2, "laser"));
        assert_relative_eq!(first.bag_time, 10.5);
        assert_relative_eq!(first.scan.stamp, 10.4);
        assert_eq!(first.scan.ranges.len(), 3);
        assert!(first.scan.ranges[1].is_infinite() && first.scan.ranges[2].is_nan());
        assert!(parsed.records[1].scan.is_empty());
        assert_eq!(parsed.skipped, 8);
        assert_eq!(
            reasons(&parsed),
            vec![
                (
                    3,
                    SkipReason::TooFewFields {
                        expected: 8,
                        found: 7
                    }
                ),
                (
                    4,
                    SkipReason::CountMismatch {
                        declared: 3,
                        found: 2
                    }
                ),
                (
                    5,
                    SkipReason::CountMismatch {
                        declared: 2,
                        found: 3
                    }
                ),
                (6, SkipReason::NonFinite { field: 0 }),
                (7, SkipReason::NonFinite { field: 1 }),
                (
                    8,
                    SkipReason::BadScan {
                        field: "angle_increment"
                    }
                ),
                (9, SkipReason::BadNumber { field: 8 }),
                (10, SkipReason::BadInteger { field: 7 }),
            ]
        );
    }

    #[test]
    fn odometry_rejects_nan_poses_and_wrong_widths() {
        let text = "# bag_time stamp x y yaw\n\
            1.0 0.9 1.0 2.0 0.5\n\
            1.1 1.0 nan 2.0 0.5\n\
            1.2 1.1 1.0 2.0 inf\n\
            1.3 1.2 1.0 2.0\n\
            1.4 1.3 1.0 2.0 0.5 9\n\
            1.5 1.4 1.0 two 0.5\n";
        let parsed = parse_odometry(text.as_bytes()).unwrap();
        assert_eq!(parsed.records.len(), 1);
        let odom = &parsed.records[0];
        assert_relative_eq!(odom.pose.translation.vector.x, 1.0);
        assert_relative_eq!(odom.pose.translation.vector.y, 2.0);
        assert_relative_eq!(odom.pose.rotation.angle(), 0.5, epsilon = 1e-12);
        assert_eq!(parsed.skipped, 5);
        assert_eq!(
            reasons(&parsed),
            vec![
                (3, SkipReason::NonFinite { field: 2 }),
                (4, SkipReason::NonFinite { field: 4 }),
                (
                    5,
                    SkipReason::TooFewFields {
                        expected: 5,
                        found: 4
                    }
                ),
                (
                    6,
                    SkipReason::TooManyFields {
                        expected: 5,
                        found: 6
                    }
                ),
                (7, SkipReason::BadNumber { field: 3 }),
            ]
        );
    }

    #[test]
    fn static_transforms_read_names_and_pose() {
        let text = "base_link left_laser 0.85 0.24 0.73\nbase_link right_laser 1 2\n";
        let parsed = parse_static_transforms(text.as_bytes()).unwrap();
        assert_eq!(parsed.records.len(), 1);
        let tf = &parsed.records[0];
        assert_eq!(
            (tf.parent.as_str(), tf.child.as_str()),
            ("base_link", "left_laser")
        );
        assert_relative_eq!(tf.transform.rotation.angle(), 0.73, epsilon = 1e-12);
        assert_eq!(
            reasons(&parsed),
            vec![(
                2,
                SkipReason::TooFewFields {
                    expected: 5,
                    found: 4
                }
            )]
        );
    }

    #[test]
    fn ground_truth_rejects_bad_ids_and_positions() {
        let text = "1.0 3 4.5 -2.5\n1.1 -3 4.5 -2.5\n1.2 3.5 4.5 -2.5\n1.3 3 nan 1\n1.4 7.0 1 1\n";
        let parsed = parse_ground_truth(text.as_bytes()).unwrap();
        let ids: Vec<u64> = parsed.records.iter().map(|p| p.id).collect();
        assert_eq!(ids, vec![3, 7]);
        assert_relative_eq!(parsed.records[0].position.y, -2.5);
        assert_eq!(parsed.skipped, 3);
        assert_eq!(
            reasons(&parsed),
            vec![
                (2, SkipReason::BadInteger { field: 1 }),
                (3, SkipReason::BadInteger { field: 1 }),
                (4, SkipReason::NonFinite { field: 2 }),
            ]
        );
    }

    #[test]
    fn non_utf8_lines_are_skipped_and_only_the_first_few_kept() {
        let mut text = b"1.0 3 4.5 -2.5\n\xff\xfe\n".to_vec();
        for _ in 0..20 {
            text.extend_from_slice(b"bad\n");
        }
        let parsed = parse_ground_truth(&text[..]).unwrap();
        assert_eq!(parsed.records.len(), 1);
        assert_eq!(parsed.skipped, 21);
        assert_eq!(parsed.first_skipped.len(), crate::KEEP_SKIPPED);
        assert_eq!(parsed.first_skipped[0].reason, SkipReason::NotText);
    }

    #[test]
    fn gzipped_and_plain_files_read_the_same() {
        use std::io::Write;
        let text = "1.0 0.9 1.0 2.0 0.5\n1.1 1.0 nan 2.0 0.5\n";
        let dir = std::env::temp_dir().join(format!("haunts-tracking-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let plain = dir.join("odom.txt");
        let gz = dir.join("odom.txt.gz");
        std::fs::write(&plain, text).unwrap();
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        enc.write_all(text.as_bytes()).unwrap();
        std::fs::write(&gz, enc.finish().unwrap()).unwrap();
        let a = read_odometry(&plain).unwrap();
        let b = read_odometry(&gz).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(a, b);
        assert_eq!((a.records.len(), a.skipped), (1, 1));
    }

    #[test]
    fn a_missing_file_is_an_io_error_naming_it() {
        let err = read_scans("/nonexistent/scans.txt").unwrap_err();
        assert!(
            matches!(&err, crate::TrackingError::Io { path, .. } if path.ends_with("scans.txt"))
        );
    }
}
