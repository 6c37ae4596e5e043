//! Coordinate frames: sensor → robot → world composition (seed 002, eq. 5), robot poses
//! interpolated in time, and chains of static transforms.
//!
//! A target seen by a sensor at time `t` is put into the world as
//! `x̂_target,t = x_sensor,t ⊕ x_target,t` (seed 002, eq. 5), where the sensor's pose is the
//! robot's pose at `t` composed with the fixed pose of the sensor on the robot:
//!
//! ```text
//! p_world = T_world←robot(t) · T_robot←sensor · p_sensor
//! ```
//!
//! [`PoseHistory`] gives `T_world←robot(t)` from timestamped poses (odometry or SLAM),
//! [`static_chain`] gives `T_robot←sensor` from `static_tf.txt`, and
//! [`PoseHistory::to_world`] / [`PoseHistory::to_sensor`] map points both ways.
//!
//! # The frames of the `leg_tracker` benchmark bag
//!
//! What `../shared/data/leg_tracker/general_tracking_moving_1/` holds, checked against
//! `angusleigh/leg_tracker_benchmarks` (`annotate_rosbags.py`, `annotate.launch`,
//! `clear_mot.py`, the `general_tracking_moving_1_*.launch` files) and against the data itself
//! (the real-data tests in `tests/frames.rs`):
//!
//! - Frames: `odom` → `base_link` (`odom.txt`, about 100 Hz, header stamps strictly
//!   increasing) → `left_laser` (`static_tf.txt`: x 0.850 m, y 0.235 m, yaw 0.735 rad). The
//!   scans are in `left_laser`. There is no `map` frame in the transforms.
//! - **The ground truth (`ground_truth_people.txt`) is in the laser frame `left_laser`, at the
//!   time of the annotated scan**: the annotation tool ran rviz with `fixed_frame:
//!   left_laser` and stored the clicked point as is. Its positions therefore move with the
//!   robot; they are not world positions.
//! - An annotation's `bag_time` is the midpoint between the bag times of the annotated scan and
//!   of the next scan (`annotate_rosbags.py`), so it belongs to the **last scan whose
//!   `bag_time` is before it** (in the file: 62–71 ms after that scan, within 0.3 ms of the
//!   midpoint). [`crate::metrics::truth_frames_for_scans`] does this grouping.
//! - `clear_mot.py` compares the tracker's `people_tracked` published in `left_laser`
//!   (`publish_people_frame: left_laser`, tracking itself in `fixed_frame: odom`) with the
//!   ground truth of the same scan. To evaluate tracks kept in the odometry frame, map each
//!   track to the laser frame of that scan: `history.to_sensor(scan.stamp, p_odom,
//!   &laser_to_base)`, with `laser_to_base = static_chain(&tfs, "left_laser", "base_link")`
//!   and the history built from `odom.txt` header stamps; the benchmark's tracker looked up
//!   transforms at the scan header stamp (`use_scan_header_stamp_for_tfs`), which is
//!   62–72 ms before the scan's bag time.
//! - A laser point `p` of a scan with header stamp `t` is at
//!   `T_odom←base_link(t) · T_base_link←left_laser · p` in `odom`. With this chain the six
//!   people who stand still in the bag (ids 1000–1006) stay within 0.36 m of their mean
//!   position in `odom` while they move by up to 3.3 m in `left_laser`; leaving out the static
//!   transform spreads them by up to 1.5 m.
//! - `map.{pgm,yaml}` is the bag's `/map` (origin −50, −50 m); nothing in the export links
//!   the `map` frame to `odom`.

use std::collections::{BTreeMap, VecDeque};

use nalgebra::{Isometry2, Point2};

use crate::{OdomPose, Result, StaticTransform, TrackingError};

/// Which of an [`OdomPose`]'s two times a [`PoseHistory`] is indexed by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum OdomClock {
    /// The message's header stamp: when the pose was measured (what tf uses; the default).
    #[default]
    HeaderStamp,
    /// When the message was recorded in the bag.
    BagTime,
}

/// The robot's pose in the world (or odometry) frame over time, interpolated between samples.
///
/// Built from timestamped poses: samples with a non-finite time, translation or rotation
/// are skipped and counted; the rest are sorted by time (stable), and of several samples
/// with the same time only the first is kept (the others are counted).
///
/// # Example
/// ```
/// use haunts_tracking::frames::PoseHistory;
/// use nalgebra::{Isometry2, Point2, Vector2};
///
/// let history = PoseHistory::new([
///     (0.0, Isometry2::new(Vector2::new(0.0, 0.0), 0.0)),
///     (2.0, Isometry2::new(Vector2::new(2.0, 0.0), std::f64::consts::FRAC_PI_2)),
/// ])?;
/// let pose = history.pose_at(1.0)?;
/// approx::assert_relative_eq!(pose.translation.vector, Vector2::new(1.0, 0.0), epsilon = 1e-12);
/// approx::assert_relative_eq!(pose.rotation.angle(), std::f64::consts::FRAC_PI_4, epsilon = 1e-12);
///
/// // A sensor 0.5 m ahead of the robot sees a point 1 m ahead of itself.
/// let sensor = Isometry2::new(Vector2::new(0.5, 0.0), 0.0);
/// let world = history.to_world(2.0, &Point2::new(1.0, 0.0), &sensor)?;
/// approx::assert_relative_eq!(world, Point2::new(2.0, 1.5), epsilon = 1e-12);
/// assert!(history.pose_at(2.5).is_err());
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "PoseHistoryFields"))]
pub struct PoseHistory {
    times: Vec<f64>,
    poses: Vec<Isometry2<f64>>,
    tolerance: f64,
    skipped_non_finite: usize,
    dropped_duplicates: usize,
}

/// Whether every component of a pose is finite.
fn is_finite(pose: &Isometry2<f64>) -> bool {
    let c = pose.rotation.complex();
    pose.translation.vector.iter().all(|v| v.is_finite()) && c.re.is_finite() && c.im.is_finite()
}

impl PoseHistory {
    /// A history of `(time in seconds, pose of the robot in the world)` samples, in any order.
    ///
    /// # Errors
    /// [`TrackingError::NoSamples`] when no sample is finite.
    ///
    /// # Complexity
    /// `O(n log n)` for `n` samples.
    pub fn new(samples: impl IntoIterator<Item = (f64, Isometry2<f64>)>) -> Result<Self> {
        let mut skipped_non_finite = 0;
        let mut kept: Vec<(f64, Isometry2<f64>)> = Vec::new();
        for (t, pose) in samples {
            if t.is_finite() && is_finite(&pose) {
                kept.push((t, pose));
            } else {
                skipped_non_finite += 1;
            }
        }
        kept.sort_by(|a, b| a.0.total_cmp(&b.0));
        let before = kept.len();
        kept.dedup_by(|later, first| later.0 == first.0);
        let dropped_duplicates = before - kept.len();
        if kept.is_empty() {
            return Err(TrackingError::NoSamples {
                what: "pose history",
            });
        }
        let (times, poses) = kept.into_iter().unzip();
        Ok(Self {
            times,
            poses,
            tolerance: 0.0,
            skipped_non_finite,
            dropped_duplicates,
        })
    }

    /// A history from `odom.txt` records, indexed by the chosen clock.
    ///
    /// # Errors
    /// [`TrackingError::NoSamples`] when `records` is empty.
    pub fn from_odometry(records: &[OdomPose], clock: OdomClock) -> Result<Self> {
        Self::new(records.iter().map(|r| {
            let t = match clock {
                OdomClock::HeaderStamp => r.stamp,
                OdomClock::BagTime => r.bag_time,
            };
            (t, r.pose)
        }))
    }

    /// The history, answering times up to `seconds` before its first or after its last sample
    /// with the first or last pose (no extrapolation). The default tolerance is 0.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] unless `seconds` is finite and ≥ 0.
    pub fn with_tolerance(mut self, seconds: f64) -> Result<Self> {
        if !(seconds.is_finite() && seconds >= 0.0) {
            return Err(TrackingError::InvalidParameter {
                name: "tolerance",
                value: seconds,
                rule: "must be finite and >= 0",
            });
        }
        self.tolerance = seconds;
        Ok(self)
    }

    /// The clamping tolerance at both ends, seconds.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The first and last sample times, seconds.
    pub fn span(&self) -> (f64, f64) {
        let first = self.times.first().copied().unwrap_or(f64::NAN);
        let last = self.times.last().copied().unwrap_or(f64::NAN);
        (first, last)
    }

    /// Whether [`PoseHistory::pose_at`] answers time `t` (tolerance included).
    pub fn covers(&self, t: f64) -> bool {
        let (start, end) = self.span();
        t >= start - self.tolerance && t <= end + self.tolerance
    }

    /// The number of samples kept (at least 1).
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Always `false`: a history holds at least one sample.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// The kept samples, sorted by strictly increasing time.
    pub fn samples(&self) -> impl Iterator<Item = (f64, &Isometry2<f64>)> {
        self.times.iter().copied().zip(&self.poses)
    }

    /// Samples skipped because their time or pose was not finite.
    pub fn skipped_non_finite(&self) -> usize {
        self.skipped_non_finite
    }

    /// Samples dropped because an earlier sample had the same time.
    pub fn dropped_duplicates(&self) -> usize {
        self.dropped_duplicates
    }

    /// The robot's pose at time `t`: linear interpolation of the translation and
    /// shortest-angle interpolation of the heading between the samples around `t` (a turn of
    /// exactly π between two samples goes counter-clockwise). Within the tolerance outside the
    /// span, the first or last pose.
    ///
    /// # Errors
    /// [`TrackingError::TimeOutOfRange`] when `t` is NaN or outside the span by more than the
    /// tolerance.
    ///
    /// # Complexity
    /// `O(log n)`.
    pub fn pose_at(&self, t: f64) -> Result<Isometry2<f64>> {
        let (start, end) = self.span();
        if !self.covers(t) {
            return Err(TrackingError::TimeOutOfRange {
                time: t,
                start,
                end,
            });
        }
        // Index of the first sample after t; 1..len inside the span.
        let after = self.times.partition_point(|&s| s <= t);
        if after == 0 {
            return Ok(self.poses[0]);
        }
        if after == self.times.len() {
            return Ok(self.poses[after - 1]);
        }
        let (t0, t1) = (self.times[after - 1], self.times[after]);
        let (p0, p1) = (&self.poses[after - 1], &self.poses[after]);
        let u = (t - t0) / (t1 - t0);
        let translation = p0.translation.vector.lerp(&p1.translation.vector, u);
        let rotation = p0.rotation.slerp(&p1.rotation, u);
        Ok(Isometry2::from_parts(translation.into(), rotation))
    }

    /// The sensor's pose in the world at time `t`: `pose_at(t) · sensor_to_robot`.
    ///
    /// # Errors
    /// As [`PoseHistory::pose_at`].
    pub fn sensor_pose_at(
        &self,
        t: f64,
        sensor_to_robot: &Isometry2<f64>,
    ) -> Result<Isometry2<f64>> {
        Ok(self.pose_at(t)? * sensor_to_robot)
    }

    /// A point seen by the sensor at time `t` (sensor coordinates), in world coordinates
    /// (seed 002, eq. 5).
    ///
    /// # Errors
    /// As [`PoseHistory::pose_at`].
    pub fn to_world(
        &self,
        t: f64,
        sensor_point: &Point2<f64>,
        sensor_to_robot: &Isometry2<f64>,
    ) -> Result<Point2<f64>> {
        Ok(self.sensor_pose_at(t, sensor_to_robot)? * sensor_point)
    }

    /// A world point in the sensor's coordinates at time `t`: the inverse of
    /// [`PoseHistory::to_world`] (e.g. a track kept in `odom`, in the laser frame its ground
    /// truth is annotated in).
    ///
    /// # Errors
    /// As [`PoseHistory::pose_at`].
    pub fn to_sensor(
        &self,
        t: f64,
        world_point: &Point2<f64>,
        sensor_to_robot: &Isometry2<f64>,
    ) -> Result<Point2<f64>> {
        Ok(self
            .sensor_pose_at(t, sensor_to_robot)?
            .inverse_transform_point(world_point))
    }
}

/// A frame name as tf compares it: without leading `/` (ROS 1 allowed `/odom` for `odom`).
fn frame_name(name: &str) -> &str {
    name.trim_start_matches('/')
}

/// The transform that maps coordinates in frame `from` to coordinates in frame `to`,
/// composed along the tree of static transforms (each record maps its child's coordinates
/// to its parent's; the chain may go up and down the tree). `from == to` gives the
/// identity. Frame names are compared without leading `/`.
///
/// For the sensor's pose on the robot: `static_chain(&tfs, "left_laser", "base_link")`.
///
/// # Errors
/// - [`TrackingError::ConflictingTransform`] when a frame has two records that differ (two
///   parents, or two poses under one parent); identical repeats are fine.
/// - [`TrackingError::NoTransformChain`] when the two frames are not connected.
///
/// # Complexity
/// `O(n log n)` for `n` records.
///
/// # Example
/// ```
/// use haunts_tracking::frames::static_chain;
/// use haunts_tracking::parse_static_transforms;
/// use nalgebra::Point2;
///
/// let tfs = parse_static_transforms(
///     "base_link laser 0.5 0.0 1.5707963267948966\nbase_link camera 0.0 0.2 0.0\n".as_bytes(),
/// )?.records;
/// let laser_to_base = static_chain(&tfs, "laser", "base_link")?;
/// approx::assert_relative_eq!(laser_to_base * Point2::new(1.0, 0.0), Point2::new(0.5, 1.0), epsilon = 1e-12);
/// // Up to base_link and down to camera.
/// let laser_to_camera = static_chain(&tfs, "laser", "camera")?;
/// approx::assert_relative_eq!(laser_to_camera * Point2::new(1.0, 0.0), Point2::new(0.5, 0.8), epsilon = 1e-12);
/// assert!(static_chain(&tfs, "laser", "map").is_err());
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
pub fn static_chain(
    transforms: &[StaticTransform],
    from: &str,
    to: &str,
) -> Result<Isometry2<f64>> {
    let (from, to) = (frame_name(from), frame_name(to));
    // Each child's record; a tree gives a frame one parent.
    let mut parent_of: BTreeMap<&str, &StaticTransform> = BTreeMap::new();
    for tf in transforms {
        let child = frame_name(&tf.child);
        match parent_of.get(child) {
            Some(first)
                if frame_name(&first.parent) != frame_name(&tf.parent)
                    || first.transform != tf.transform =>
            {
                return Err(TrackingError::ConflictingTransform {
                    child: child.to_owned(),
                    first_line: first.line,
                    second_line: tf.line,
                });
            }
            Some(_) => {}
            None => {
                parent_of.insert(child, tf);
            }
        }
    }
    // Undirected edges: child → parent applies the record, parent → child its inverse.
    let mut edges: BTreeMap<&str, Vec<(&str, Isometry2<f64>)>> = BTreeMap::new();
    for (&child, tf) in &parent_of {
        let parent = frame_name(&tf.parent);
        edges.entry(child).or_default().push((parent, tf.transform));
        edges
            .entry(parent)
            .or_default()
            .push((child, tf.transform.inverse()));
    }
    // Breadth-first search from `from`; `seen[f]` maps `from` coordinates to `f` coordinates.
    let mut seen: BTreeMap<&str, Isometry2<f64>> = BTreeMap::new();
    seen.insert(from, Isometry2::identity());
    let mut queue = VecDeque::from([from]);
    while let Some(frame) = queue.pop_front() {
        let so_far = seen.get(frame).copied().unwrap_or_else(Isometry2::identity);
        if frame == to {
            return Ok(so_far);
        }
        for &(next, step) in edges.get(frame).map(Vec::as_slice).unwrap_or(&[]) {
            if !seen.contains_key(next) {
                seen.insert(next, step * so_far);
                queue.push_back(next);
            }
        }
    }
    Err(TrackingError::NoTransformChain {
        from: from.to_owned(),
        to: to.to_owned(),
    })
}

/// The fields of a [`PoseHistory`] as deserialised, before they are checked.
///
/// [`PoseHistory::new`] repairs what it is given (it sorts, and skips non-finite samples and
/// repeated times); a serialised history is already repaired, so anything it would repair
/// is rejected instead of being changed silently.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct PoseHistoryFields {
    times: Vec<f64>,
    poses: Vec<Isometry2<f64>>,
    #[serde(default)]
    tolerance: f64,
    #[serde(default)]
    skipped_non_finite: usize,
    #[serde(default)]
    dropped_duplicates: usize,
}

#[cfg(feature = "serde")]
impl TryFrom<PoseHistoryFields> for PoseHistory {
    type Error = TrackingError;
    fn try_from(f: PoseHistoryFields) -> Result<Self> {
        if f.times.len() != f.poses.len() {
            return Err(TrackingError::LengthMismatch {
                first: "times",
                first_len: f.times.len(),
                second: "poses",
                second_len: f.poses.len(),
            });
        }
        let invalid = |name, value, rule| TrackingError::InvalidParameter { name, value, rule };
        if f.times.is_empty() {
            return Err(invalid("times", 0.0, "must hold at least one sample"));
        }
        for (i, &t) in f.times.iter().enumerate() {
            if !t.is_finite() || (i > 0 && t <= f.times[i - 1]) {
                return Err(invalid(
                    "times",
                    t,
                    "must be finite and strictly increasing",
                ));
            }
        }
        // nalgebra deserialises a rotation's complex number without normalising it.
        const RULE: &str = "must be finite, with a rotation of norm 1 (within 1e-6)";
        for pose in &f.poses {
            let translation = pose.translation.vector;
            if let Some(&v) = translation.iter().find(|v| !v.is_finite()) {
                return Err(invalid("poses", v, RULE));
            }
            let c = pose.rotation.complex();
            let norm = c.re.hypot(c.im);
            let unit = (norm - 1.0).abs() <= 1e-6;
            if !unit {
                return Err(invalid("poses", norm, RULE));
            }
        }
        let mut history =
            Self::new(f.times.into_iter().zip(f.poses))?.with_tolerance(f.tolerance)?;
        history.skipped_non_finite = f.skipped_non_finite;
        history.dropped_duplicates = f.dropped_duplicates;
        Ok(history)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use std::f64::consts::{FRAC_PI_2, PI};

    use approx::assert_relative_eq;
    use nalgebra::{UnitComplex, Vector2};
    use proptest::prelude::*;

    use super::*;

    fn pose(x: f64, y: f64, yaw: f64) -> Isometry2<f64> {
        Isometry2::new(Vector2::new(x, y), yaw)
    }

    fn tf(parent: &str, child: &str, p: Isometry2<f64>, line: usize) -> StaticTransform {
        StaticTransform {
            parent: parent.into(),
            child: child.into(),
            transform: p,
            line,
        }
    }

    #[test]
    fn interpolation_matches_hand_computed_values() {
        let h = PoseHistory::new([
            (10.0, pose(1.0, 2.0, 0.2)),
            (12.0, pose(3.0, -2.0, 0.6)),
            (13.0, pose(3.0, -2.0, 0.6)),
        ])
        .unwrap();
        // A quarter of the way from 10 s to 12 s.
        let p = h.pose_at(10.5).unwrap();
        assert_relative_eq!(
            p.translation.vector,
            Vector2::new(1.5, 1.0),
            epsilon = 1e-12
        );
        assert_relative_eq!(p.rotation.angle(), 0.3, epsilon = 1e-12);
        // Exactly on samples, including the last one.
        assert_eq!(h.pose_at(12.0).unwrap(), pose(3.0, -2.0, 0.6));
        assert_eq!(h.pose_at(13.0).unwrap(), pose(3.0, -2.0, 0.6));
        assert_eq!(h.pose_at(10.0).unwrap(), pose(1.0, 2.0, 0.2));
        assert_eq!(h.span(), (10.0, 13.0));
    }

    #[test]
    fn heading_takes_the_short_way_across_plus_minus_pi() {
        let h =
            PoseHistory::new([(0.0, pose(0.0, 0.0, 3.0)), (1.0, pose(0.0, 0.0, -3.0))]).unwrap();
        // 3.0 → −3.0 is a turn of 2π − 6 ≈ 0.283 rad counter-clockwise, through π.
        let mid = h.pose_at(0.5).unwrap().rotation;
        assert_relative_eq!((mid / UnitComplex::new(PI)).angle(), 0.0, epsilon = 1e-12);
        let quarter = h.pose_at(0.25).unwrap().rotation.angle();
        assert_relative_eq!(quarter, 3.0 + (2.0 * PI - 6.0) / 4.0, epsilon = 1e-12);
        // And the other way round.
        let h =
            PoseHistory::new([(0.0, pose(0.0, 0.0, -3.0)), (1.0, pose(0.0, 0.0, 3.0))]).unwrap();
        let quarter = h.pose_at(0.25).unwrap().rotation.angle();
        assert_relative_eq!(quarter, -3.0 - (2.0 * PI - 6.0) / 4.0, epsilon = 1e-12);
    }

    #[test]
    fn outside_the_span_is_an_error_unless_within_tolerance() {
        let h = PoseHistory::new([(1.0, pose(0.0, 0.0, 0.0)), (2.0, pose(1.0, 0.0, 0.0))]).unwrap();
        for t in [0.99, 2.01, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                h.pose_at(t),
                Err(TrackingError::TimeOutOfRange {
                    start: 1.0,
                    end: 2.0,
                    ..
                })
            ));
        }
        let h = h.with_tolerance(0.05).unwrap();
        assert_eq!(h.pose_at(0.96).unwrap(), pose(0.0, 0.0, 0.0));
        assert_eq!(h.pose_at(2.04).unwrap(), pose(1.0, 0.0, 0.0));
        assert!(h.pose_at(2.06).is_err());
        assert!(h.pose_at(f64::NAN).is_err());
        for bad in [-0.1, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                h.clone().with_tolerance(bad),
                Err(TrackingError::InvalidParameter {
                    name: "tolerance",
                    ..
                })
            ));
        }
    }

    #[test]
    fn unsorted_duplicate_and_non_finite_samples_are_handled() {
        let bad_rotation = Isometry2::from_parts(
            Vector2::new(0.0, 0.0).into(),
            UnitComplex::new_unchecked(nalgebra::Complex::new(f64::NAN, 0.0)),
        );
        let h = PoseHistory::new([
            (2.0, pose(2.0, 0.0, 0.0)),
            (0.0, pose(0.0, 0.0, 0.0)),
            (f64::NAN, pose(9.0, 9.0, 0.0)),
            (1.0, pose(f64::INFINITY, 0.0, 0.0)),
            (1.5, bad_rotation),
            (2.0, pose(7.0, 7.0, 0.0)),
        ])
        .unwrap();
        assert_eq!(
            (h.len(), h.skipped_non_finite(), h.dropped_duplicates()),
            (2, 3, 1)
        );
        // The first of the two 2 s samples is kept.
        assert_relative_eq!(h.pose_at(1.0).unwrap().translation.vector.x, 1.0);
        assert_eq!(h.pose_at(2.0).unwrap(), pose(2.0, 0.0, 0.0));
        assert!(matches!(
            PoseHistory::new([(f64::NAN, pose(0.0, 0.0, 0.0))]),
            Err(TrackingError::NoSamples { .. })
        ));
    }

    #[test]
    fn a_single_sample_answers_its_own_time_only() {
        let h = PoseHistory::new([(5.0, pose(1.0, 1.0, 1.0))]).unwrap();
        assert_eq!(h.pose_at(5.0).unwrap(), pose(1.0, 1.0, 1.0));
        assert!(h.pose_at(5.0 + 1e-9).is_err());
    }

    #[test]
    fn odometry_records_use_the_chosen_clock() {
        let rec = |bag_time, stamp, x| OdomPose {
            bag_time,
            stamp,
            pose: pose(x, 0.0, 0.0),
            line: 1,
        };
        let records = [rec(1.1, 1.0, 0.0), rec(2.1, 2.0, 1.0)];
        let by_stamp = PoseHistory::from_odometry(&records, OdomClock::HeaderStamp).unwrap();
        let by_bag = PoseHistory::from_odometry(&records, OdomClock::BagTime).unwrap();
        assert_eq!(by_stamp.span(), (1.0, 2.0));
        assert_eq!(by_bag.span(), (1.1, 2.1));
        assert_relative_eq!(
            by_stamp.pose_at(1.5).unwrap().translation.x,
            0.5,
            epsilon = 1e-12
        );
        assert_relative_eq!(
            by_bag.pose_at(1.5).unwrap().translation.x,
            0.4,
            epsilon = 1e-12
        );
    }

    #[test]
    fn sensor_points_compose_robot_and_mounting() {
        // Robot at (1, 1) facing +y; laser 0.5 m ahead, turned by +90° (facing −x in world).
        let h = PoseHistory::new([(0.0, pose(1.0, 1.0, FRAC_PI_2))]).unwrap();
        let mount = pose(0.5, 0.0, FRAC_PI_2);
        let world = h.to_world(0.0, &Point2::new(2.0, 0.0), &mount).unwrap();
        assert_relative_eq!(world, Point2::new(-1.0, 1.5), epsilon = 1e-12);
        let back = h.to_sensor(0.0, &world, &mount).unwrap();
        assert_relative_eq!(back, Point2::new(2.0, 0.0), epsilon = 1e-12);
    }

    #[test]
    fn static_chains_go_up_and_down_the_tree() {
        let a = pose(0.5, 0.1, 0.3);
        let b = pose(-0.2, 0.4, -1.0);
        let c = pose(0.05, 0.0, 2.0);
        let tfs = [
            tf("base_link", "left_laser", a, 1),
            tf("/base_link", "torso", b, 2),
            tf("torso", "/head_cam", c, 3),
            tf("base_link", "left_laser", a, 4),
        ];
        assert_eq!(static_chain(&tfs, "left_laser", "base_link").unwrap(), a);
        assert_eq!(
            static_chain(&tfs, "/left_laser", "left_laser").unwrap(),
            Isometry2::identity()
        );
        assert_relative_eq!(
            static_chain(&tfs, "base_link", "left_laser").unwrap(),
            a.inverse(),
            epsilon = 1e-12
        );
        // head_cam → torso → base_link → left_laser.
        assert_relative_eq!(
            static_chain(&tfs, "head_cam", "left_laser").unwrap(),
            a.inverse() * b * c,
            epsilon = 1e-12
        );
        assert!(matches!(
            static_chain(&tfs, "head_cam", "odom"),
            Err(TrackingError::NoTransformChain { .. })
        ));
        assert_eq!(
            static_chain(&[], "odom", "/odom").unwrap(),
            Isometry2::identity()
        );
    }

    #[test]
    fn a_frame_with_two_parents_is_a_conflict() {
        let tfs = [
            tf("base_link", "laser", pose(0.5, 0.0, 0.0), 1),
            tf("odom", "laser", pose(0.5, 0.0, 0.0), 7),
        ];
        assert!(matches!(
            static_chain(&tfs, "laser", "base_link"),
            Err(TrackingError::ConflictingTransform {
                first_line: 1,
                second_line: 7,
                ..
            })
        ));
        let tfs = [
            tf("base_link", "laser", pose(0.5, 0.0, 0.0), 1),
            tf("base_link", "laser", pose(0.5, 0.0, 0.1), 2),
        ];
        assert!(static_chain(&tfs, "laser", "base_link").is_err());
    }

    fn any_pose() -> impl Strategy<Value = Isometry2<f64>> {
        (-50.0f64..50.0, -50.0f64..50.0, -10.0f64..10.0).prop_map(|(x, y, a)| pose(x, y, a))
    }

    proptest! {
        #[test]
        fn world_and_sensor_mappings_are_inverse(
            p0 in any_pose(), p1 in any_pose(), mount in any_pose(),
            u in 0.0f64..=1.0, x in -20.0f64..20.0, y in -20.0f64..20.0,
        ) {
            let h = PoseHistory::new([(0.0, p0), (3.0, p1)]).unwrap();
            let t = 3.0 * u;
            let p = Point2::new(x, y);
            let world = h.to_world(t, &p, &mount).unwrap();
            let back = h.to_sensor(t, &world, &mount).unwrap();
            prop_assert!((back - p).norm() < 1e-9);
            // Composition: robot ⊕ mount ⊕ point, and its inverse.
            let robot = h.pose_at(t).unwrap();
            prop_assert!((robot * (mount * p) - world).norm() < 1e-9);
            let round = (robot * mount).inverse() * (robot * mount);
            prop_assert!(round.translation.vector.norm() < 1e-9);
            prop_assert!(round.rotation.angle().abs() < 1e-9);
        }

        #[test]
        fn interpolated_heading_stays_between_the_samples(
            a in -PI..PI, b in -PI..PI, u in 0.0f64..=1.0,
        ) {
            let h = PoseHistory::new([(0.0, pose(0.0, 0.0, a)), (1.0, pose(0.0, 0.0, b))]).unwrap();
            let r = h.pose_at(u).unwrap().rotation;
            let total = (UnitComplex::new(b) / UnitComplex::new(a)).angle();
            let part = (r / UnitComplex::new(a)).angle();
            prop_assert!((part - u * total).abs() < 1e-9);
            prop_assert!(total.abs() <= PI + 1e-12);
        }
    }
}
