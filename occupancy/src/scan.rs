//! `LaserScan`: one sweep of a planar range finder, and what each of its readings means.

use nalgebra::Point2;

use crate::{OccupancyError, Pose2, Result};

/// A planar laser scan, as ROS `sensor_msgs/LaserScan`: beam `i` points at
/// `angle_min + i·angle_increment` radians in the sensor frame (x forward, y left).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "LaserScanFields"))]
pub struct LaserScan {
    /// Acquisition time, seconds (UNIX time, or the log's own clock).
    pub stamp: f64,
    /// Angle of the first beam, radians.
    pub angle_min: f64,
    /// Angle between consecutive beams, radians (negative for clockwise scanners).
    pub angle_increment: f64,
    /// Shortest valid range, metres.
    pub range_min: f64,
    /// Longest valid range, metres; readings at or beyond it are max-range readings.
    pub range_max: f64,
    /// Ranges, metres; NaN, ±inf and zero are allowed and classified by [`LaserScan::reading`]
    /// (with the `serde` feature, non-finite ones are written as `serde_float` says).
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_float::vec"))]
    pub ranges: Vec<f64>,
    /// Intensities, empty or one per range.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_float::vec"))]
    pub intensities: Vec<f64>,
}

/// What one range reading says, following ROS REP 117.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reading {
    /// An obstacle at this range.
    Hit(f64),
    /// No return within `range_max` (a reading `>= range_max` or `+inf`): the beam saw free
    /// space up to the range it was cut at, but no obstacle.
    MaxRange,
    /// No information: NaN, `-inf`, zero, negative, or shorter than `range_min`.
    Invalid,
}

/// One beam of a scan in the sensor frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beam {
    /// Index of the beam in the scan.
    pub index: usize,
    /// Direction, radians in the sensor frame.
    pub angle: f64,
    /// What the beam reported.
    pub reading: Reading,
}

/// A beam as a segment in some frame: from the sensor to its endpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Sensor position.
    pub from: Point2<f64>,
    /// Where the beam ends: the obstacle for a hit, the clearing limit for a max-range reading.
    pub to: Point2<f64>,
    /// True when `to` is an obstacle.
    pub hit: bool,
}

/// What a max-range reading does when a scan is turned into rays.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MaxRangeRule {
    /// Ignored: no ray (the ROS costmap's default `inf_is_valid: false`).
    Ignore,
    /// Clears free space along the beam up to this many metres (capped at `range_max`).
    Clear(f64),
}

impl Default for MaxRangeRule {
    /// Max-range readings clear space up to 5 m (Cartographer's `missing_data_ray_length`):
    /// far enough to clear a room, short enough that a "no return" through a window or a
    /// glass door does not erase the walls it missed.
    fn default() -> Self {
        Self::Clear(5.0)
    }
}

impl LaserScan {
    /// A scan after checking its description and lengths.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidScan`] for a non-finite stamp or angle, a zero or non-finite
    /// increment, a negative or non-finite `range_min`, or `range_max <= range_min`;
    /// [`OccupancyError::ScanLengthMismatch`] when intensities are given but not one per range.
    pub fn new(
        stamp: f64,
        angle_min: f64,
        angle_increment: f64,
        range_min: f64,
        range_max: f64,
        ranges: Vec<f64>,
        intensities: Vec<f64>,
    ) -> Result<Self> {
        Self {
            stamp,
            angle_min,
            angle_increment,
            range_min,
            range_max,
            ranges,
            intensities,
        }
        .check()
    }

    /// The scan, if its fields keep the rules of [`LaserScan::new`].
    ///
    /// # Errors
    /// As [`LaserScan::new`].
    pub fn check(self) -> Result<Self> {
        let bad = |field, value, expected| {
            Err(OccupancyError::InvalidScan {
                field,
                value,
                expected,
            })
        };
        if !self.stamp.is_finite() {
            return bad("stamp", self.stamp, "finite");
        }
        if !self.angle_min.is_finite() {
            return bad("angle_min", self.angle_min, "finite");
        }
        if !(self.angle_increment.is_finite() && self.angle_increment != 0.0) {
            return bad(
                "angle_increment",
                self.angle_increment,
                "finite and non-zero",
            );
        }
        if !(self.range_min.is_finite() && self.range_min >= 0.0) {
            return bad("range_min", self.range_min, "finite and >= 0");
        }
        if !(self.range_max.is_finite() && self.range_max > self.range_min) {
            return bad("range_max", self.range_max, "finite and > range_min");
        }
        if !self.intensities.is_empty() && self.intensities.len() != self.ranges.len() {
            return Err(OccupancyError::ScanLengthMismatch {
                ranges: self.ranges.len(),
                intensities: self.intensities.len(),
            });
        }
        Ok(self)
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.ranges.len()
    }
    /// Whether the scan has no beam.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// The meaning of a range value in this scan (REP 117): `+inf` or `>= range_max` is a
    /// max-range reading; NaN, `-inf`, values `<= 0` and values `< range_min` are invalid.
    pub fn reading(&self, range: f64) -> Reading {
        if range.is_nan() || range <= 0.0 || range < self.range_min {
            Reading::Invalid
        } else if range >= self.range_max {
            Reading::MaxRange
        } else {
            Reading::Hit(range)
        }
    }

    /// Every beam with its angle and reading.
    pub fn beams(&self) -> impl Iterator<Item = Beam> + '_ {
        self.ranges.iter().enumerate().map(|(index, &r)| Beam {
            index,
            angle: self.angle_min + index as f64 * self.angle_increment,
            reading: self.reading(r),
        })
    }

    /// Endpoints of the hits in the sensor frame. NaN, inf, zero, too-short and max-range
    /// readings are never endpoints.
    pub fn endpoints(&self) -> impl Iterator<Item = Point2<f64>> + '_ {
        self.beams().filter_map(|b| match b.reading {
            Reading::Hit(r) => Some(Point2::new(r * b.angle.cos(), r * b.angle.sin())),
            _ => None,
        })
    }

    /// Endpoints of the hits in the world frame, for a sensor at `sensor_pose`.
    pub fn endpoints_world<'a>(
        &'a self,
        sensor_pose: &'a Pose2,
    ) -> impl Iterator<Item = Point2<f64>> + 'a {
        self.endpoints().map(move |p| sensor_pose * p)
    }

    /// The beams as world-frame segments for a sensor at `sensor_pose`: hits end at the
    /// obstacle; max-range readings become clearing rays as `max_range` says; invalid
    /// readings give no ray.
    pub fn rays<'a>(
        &'a self,
        sensor_pose: &'a Pose2,
        max_range: MaxRangeRule,
    ) -> impl Iterator<Item = Ray> + 'a {
        self.beams().filter_map(move |b| {
            self.ray(
                sensor_pose,
                max_range,
                b.reading,
                (b.angle.cos(), b.angle.sin()),
            )
        })
    }

    /// [`LaserScan::rays`] with the beams' `(cos, sin)` taken from `directions` (which must
    /// be [`BeamDirections::of`] this scan's angles): the same rays, without a `sin_cos`
    /// per beam for every scan of a laser.
    pub(crate) fn rays_along<'a>(
        &'a self,
        sensor_pose: &'a Pose2,
        max_range: MaxRangeRule,
        directions: &'a [(f64, f64)],
    ) -> impl Iterator<Item = Ray> + 'a {
        self.ranges
            .iter()
            .zip(directions)
            .filter_map(move |(&r, &d)| self.ray(sensor_pose, max_range, self.reading(r), d))
    }

    /// The ray of one beam in direction `(cos, sin)` (sensor frame), if it gives one.
    #[inline(always)]
    fn ray(
        &self,
        sensor_pose: &Pose2,
        max_range: MaxRangeRule,
        reading: Reading,
        (cos, sin): (f64, f64),
    ) -> Option<Ray> {
        let (range, hit) = match (reading, max_range) {
            (Reading::Hit(r), _) => (r, true),
            (Reading::MaxRange, MaxRangeRule::Clear(limit)) if limit > 0.0 => {
                (limit.min(self.range_max), false)
            }
            _ => return None,
        };
        Some(Ray {
            from: sensor_pose * Point2::origin(),
            to: sensor_pose * Point2::new(range * cos, range * sin),
            hit,
        })
    }
}

/// The `(cos, sin)` of a scan's beam angles, kept while the scans that follow have the same
/// angles (one laser's scans do): computed as [`LaserScan::beams`]' angles are, so the rays
/// are bit for bit those of [`LaserScan::rays`].
#[derive(Debug, Clone, Default)]
pub(crate) struct BeamDirections {
    /// The bits of `angle_min` and `angle_increment` the table holds.
    key: (u64, u64),
    table: Vec<(f64, f64)>,
}

impl BeamDirections {
    /// The directions of `scan`'s beams, computed again only when its angles differ from
    /// the last scan's.
    pub(crate) fn of(&mut self, scan: &LaserScan) -> &[(f64, f64)] {
        let key = (scan.angle_min.to_bits(), scan.angle_increment.to_bits());
        if key != self.key || self.table.len() < scan.len() {
            self.key = key;
            self.table.clear();
            self.table
                .extend(scan.beams().map(|b| (b.angle.cos(), b.angle.sin())));
        }
        &self.table[..scan.len()]
    }
}

/// The fields of a [`LaserScan`] as deserialised, before [`LaserScan::check`].
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct LaserScanFields {
    stamp: f64,
    angle_min: f64,
    angle_increment: f64,
    range_min: f64,
    range_max: f64,
    #[serde(with = "crate::serde_float::vec")]
    ranges: Vec<f64>,
    #[serde(default, with = "crate::serde_float::vec")]
    intensities: Vec<f64>,
}

#[cfg(feature = "serde")]
impl TryFrom<LaserScanFields> for LaserScan {
    type Error = OccupancyError;
    fn try_from(f: LaserScanFields) -> Result<Self> {
        Self::new(
            f.stamp,
            f.angle_min,
            f.angle_increment,
            f.range_min,
            f.range_max,
            f.ranges,
            f.intensities,
        )
    }
}

/// Whether a pose's translation and angle are finite.
pub fn pose_is_finite(pose: &Pose2) -> bool {
    pose.translation.vector.iter().all(|v| v.is_finite())
        && pose.rotation.re.is_finite()
        && pose.rotation.im.is_finite()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn scan(ranges: Vec<f64>) -> LaserScan {
        LaserScan::new(0.0, -0.5, 0.5, 0.1, 10.0, ranges, vec![]).unwrap()
    }

    /// The cached directions give the rays of `rays` bit for bit, across scans whose angles
    /// or lengths change (the table is computed again) or stay (it is reused).
    #[test]
    fn rays_along_cached_directions_are_the_rays() {
        let mut directions = BeamDirections::default();
        let pose = Pose2::new(nalgebra::Vector2::new(1.3, -0.7), 2.1);
        let bits = |r: &Ray| {
            (
                r.from.x.to_bits(),
                r.from.y.to_bits(),
                r.to.x.to_bits(),
                r.to.y.to_bits(),
                r.hit,
            )
        };
        for (k, (angle_min, increment, n)) in [
            (-2.356194490192345, 0.004363323129985824, 1081),
            (-2.356194490192345, 0.004363323129985824, 1081),
            (-std::f64::consts::FRAC_PI_2, 0.017453292519943295, 181),
            (-std::f64::consts::FRAC_PI_2, 0.017453292519943295, 90),
            (-std::f64::consts::FRAC_PI_2, 0.017453292519943295, 181),
            (0.0, 0.0, 3),
            (3.0, -0.0123, 541),
            (-100.0, 0.37, 541),
        ]
        .into_iter()
        .enumerate()
        {
            let ranges = (0..n)
                .map(|i| match (i + k) % 11 {
                    0 => f64::NAN,
                    1 => 40.0,
                    _ => 0.2 + 0.37 * ((i * 7 + k) % 50) as f64,
                })
                .collect();
            let mut scan = LaserScan::new(0.0, angle_min, 0.1, 0.1, 30.0, ranges, vec![]).unwrap();
            // Public fields: a scan built by hand may hold any increment, 0 too (the
            // empty cache's key).
            scan.angle_increment = increment;
            for rule in [MaxRangeRule::Ignore, MaxRangeRule::Clear(5.0)] {
                let fast: Vec<_> = scan
                    .rays_along(&pose, rule, directions.of(&scan))
                    .map(|r| bits(&r))
                    .collect();
                let plain: Vec<_> = scan.rays(&pose, rule).map(|r| bits(&r)).collect();
                assert_eq!(fast, plain, "scan {k}");
                assert!(!plain.is_empty());
            }
        }
    }

    #[test]
    fn readings_follow_rep_117() {
        let s = scan(vec![]);
        assert_eq!(s.reading(f64::NAN), Reading::Invalid);
        assert_eq!(s.reading(f64::NEG_INFINITY), Reading::Invalid);
        assert_eq!(s.reading(0.0), Reading::Invalid);
        assert_eq!(s.reading(0.05), Reading::Invalid);
        assert_eq!(s.reading(f64::INFINITY), Reading::MaxRange);
        assert_eq!(s.reading(10.0), Reading::MaxRange);
        assert_eq!(s.reading(3.0), Reading::Hit(3.0));
    }

    #[test]
    fn only_hits_are_endpoints_and_max_range_clears() {
        let s = scan(vec![1.0, f64::NAN, f64::INFINITY, 0.0, 2.0]);
        let pts: Vec<_> = s.endpoints().collect();
        assert_eq!(pts.len(), 2);
        assert_relative_eq!(pts[0], Point2::new((-0.5f64).cos(), (-0.5f64).sin()));
        assert_relative_eq!(pts[1], Point2::new(2.0 * 1.5f64.cos(), 2.0 * 1.5f64.sin()));

        let pose = Pose2::new(
            nalgebra::Vector2::new(1.0, 2.0),
            std::f64::consts::FRAC_PI_2,
        );
        let world: Vec<_> = s.endpoints_world(&pose).collect();
        assert_relative_eq!(world[0], pose * pts[0], epsilon = 1e-12);

        let rays: Vec<_> = s.rays(&pose, MaxRangeRule::Clear(4.0)).collect();
        assert_eq!(rays.len(), 3);
        assert!(!rays[1].hit);
        assert_relative_eq!((rays[1].to - rays[1].from).norm(), 4.0, epsilon = 1e-12);
        assert_eq!(s.rays(&pose, MaxRangeRule::Ignore).count(), 2);
    }

    #[test]
    fn bad_descriptions_are_rejected() {
        let r = LaserScan::new(0.0, 0.0, 0.0, 0.0, 1.0, vec![], vec![]);
        assert!(matches!(
            r,
            Err(OccupancyError::InvalidScan {
                field: "angle_increment",
                ..
            })
        ));
        let r = LaserScan::new(0.0, 0.0, 0.1, 0.0, 1.0, vec![1.0; 3], vec![1.0; 2]);
        assert!(matches!(
            r,
            Err(OccupancyError::ScanLengthMismatch {
                ranges: 3,
                intensities: 2
            })
        ));
        let r = LaserScan::new(f64::NAN, 0.0, 0.1, 0.0, 1.0, vec![], vec![]);
        assert!(matches!(
            r,
            Err(OccupancyError::InvalidScan { field: "stamp", .. })
        ));
        let r = LaserScan::new(0.0, 0.0, 0.1, 2.0, 1.0, vec![], vec![]);
        assert!(matches!(
            r,
            Err(OccupancyError::InvalidScan {
                field: "range_max",
                ..
            })
        ));
    }
}
