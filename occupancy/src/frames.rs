//! Coordinate frames over time: poses interpolated between timestamped samples
//! ([`PoseHistory`]) and a tree of static and moving transforms ([`TransformTree`]), as ROS tf
//! keeps them.

use std::collections::BTreeMap;

use nalgebra::{Isometry2, Point2};

use crate::{OccupancyError, Result};

/// The robot's pose in the world (or odometry) frame over time, interpolated between samples.
///
/// Built from timestamped poses: samples with a non-finite time, translation or rotation
/// are skipped and counted; the rest are sorted by time (stable), and of several samples
/// with the same time only the first is kept (the others are counted).
///
/// # Example
/// ```
/// use haunts_occupancy::PoseHistory;
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
/// # Ok::<(), haunts_occupancy::OccupancyError>(())
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

impl PoseHistory {
    /// A history of `(time in seconds, pose of the robot in the world)` samples, in any order.
    ///
    /// # Errors
    /// [`OccupancyError::NoSamples`] when no sample is finite.
    ///
    /// # Complexity
    /// `O(n log n)` for `n` samples.
    pub fn new(samples: impl IntoIterator<Item = (f64, Isometry2<f64>)>) -> Result<Self> {
        let mut skipped_non_finite = 0;
        let mut kept: Vec<(f64, Isometry2<f64>)> = Vec::new();
        for (t, pose) in samples {
            if t.is_finite() && crate::pose_is_finite(&pose) {
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
            return Err(OccupancyError::NoSamples {
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

    /// The history, answering times up to `seconds` before its first or after its last sample
    /// with the first or last pose (no extrapolation). The default tolerance is 0.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`] unless `seconds` is finite and ≥ 0.
    pub fn with_tolerance(mut self, seconds: f64) -> Result<Self> {
        haunts_core::non_negative("tolerance", seconds)?;
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

    /// The history without its samples far from the bulk of its positions, by the bounds
    /// rule ([`crate::bounds`]): one odometry glitch (a pose at 10⁵ m) goes, and a pose is
    /// interpolated across the gap it leaves; the counts of non-finite and duplicate samples
    /// stay. Non-finite samples were skipped when the history was made
    /// ([`skipped_non_finite`](Self::skipped_non_finite)), so the report counts far ones only.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`] for a rule its check refuses;
    /// [`OccupancyError::NoUsableRows`] when every sample is far (only with a given box).
    ///
    /// ```
    /// use haunts_occupancy::{PoseHistory, bounds::BoundsRule};
    /// use nalgebra::{Isometry2, Vector2};
    /// let mut samples: Vec<(f64, Isometry2<f64>)> = (0..100)
    ///     .map(|i| (f64::from(i), Isometry2::new(Vector2::new(f64::from(i) * 0.1, 0.0), 0.0)))
    ///     .collect();
    /// samples[50].1 = Isometry2::new(Vector2::new(1.0e5, 0.0), 0.0);
    /// let (history, report) = PoseHistory::new(samples)?.retain_near(&BoundsRule::default())?;
    /// assert_eq!((history.len(), report.counts.far), (99, 1));
    /// approx::assert_relative_eq!(history.pose_at(50.0)?.translation.x, 5.0, epsilon = 1e-12);
    /// # Ok::<(), haunts_occupancy::OccupancyError>(())
    /// ```
    pub fn retain_near(
        self,
        rule: &crate::bounds::BoundsRule,
    ) -> Result<(Self, crate::bounds::SkipReport)> {
        let Self {
            times,
            poses,
            tolerance,
            skipped_non_finite,
            dropped_duplicates,
        } = self;
        let samples: Vec<(f64, Isometry2<f64>)> = times.into_iter().zip(poses).collect();
        let kept = rule.split("poses", samples, |(_, pose)| pose.translation.vector.into())?;
        let (times, poses) = kept.rows.into_iter().unzip();
        Ok((
            Self {
                times,
                poses,
                tolerance,
                skipped_non_finite,
                dropped_duplicates,
            },
            kept.skipped,
        ))
    }

    /// The robot's pose at time `t`: linear interpolation of the translation and
    /// shortest-angle interpolation of the heading between the samples around `t` (a turn of
    /// exactly π between two samples goes counter-clockwise). Within the tolerance outside the
    /// span, the first or last pose.
    ///
    /// # Errors
    /// [`OccupancyError::TimeOutOfRange`] when `t` is NaN or outside the span by more than the
    /// tolerance.
    ///
    /// # Complexity
    /// `O(log n)`.
    pub fn pose_at(&self, t: f64) -> Result<Isometry2<f64>> {
        let (start, end) = self.span();
        if !self.covers(t) {
            return Err(OccupancyError::TimeOutOfRange {
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
        Ok(Self::interpolate(
            (self.times[after - 1], &self.poses[after - 1]),
            (self.times[after], &self.poses[after]),
            t,
        ))
    }

    /// The pose at `t` between two samples `(time, pose)`, as [`PoseHistory::pose_at`]
    /// interpolates between the samples around `t`: for a caller that holds only the two
    /// samples around `t` of a stream (a live session), bit for bit the pose the whole
    /// history gives.
    pub fn interpolate(
        before: (f64, &Isometry2<f64>),
        after: (f64, &Isometry2<f64>),
        t: f64,
    ) -> Isometry2<f64> {
        let ((t0, p0), (t1, p1)) = (before, after);
        let u = (t - t0) / (t1 - t0);
        let translation = p0.translation.vector.lerp(&p1.translation.vector, u);
        let rotation = p0.rotation.slerp(&p1.rotation, u);
        Isometry2::from_parts(translation.into(), rotation)
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
    type Error = OccupancyError;
    fn try_from(f: PoseHistoryFields) -> Result<Self> {
        if f.times.len() != f.poses.len() {
            return Err(OccupancyError::LengthMismatch {
                first: "times",
                first_len: f.times.len(),
                second: "poses",
                second_len: f.poses.len(),
            });
        }
        let invalid = |name, value, rule| {
            OccupancyError::InvalidParameter(haunts_core::InvalidParameter { name, value, rule })
        };
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

/// A frame name as tf compares it: without a leading `/`.
pub fn frame_name(name: &str) -> &str {
    name.trim_start_matches('/')
}

/// What links a child frame to its parent in a [`TransformTree`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Link {
    /// A fixed transform (a sensor's mount, `/tf_static`).
    Static(Isometry2<f64>),
    /// A transform that moves with time (odometry, localisation), interpolated between its
    /// samples.
    Moving(PoseHistory),
}

/// A tree of coordinate frames, as ROS tf keeps it: each frame has at most one parent, linked
/// by a fixed or a moving transform (child coordinates → parent coordinates).
///
/// A transform from `child` to `parent` maps coordinates in `child` to coordinates in
/// `parent` (ROS's `TransformStamped` convention: `header.frame_id` is the parent,
/// `child_frame_id` the child). A point seen by a sensor at time `t` is in the world at
///
/// ```text
/// p_world = T_world←robot(t) · T_robot←sensor · p_sensor
/// ```
///
/// (seed 002, eq. 5). Frame names are compared without a leading `/` (ROS 1 allowed `/odom`
/// for `odom`; see [`frame_name`]).
///
/// Built with [`TransformTree::add_static`] and [`TransformTree::add_moving`]; looked up with
/// [`TransformTree::lookup`], which composes the links along the path between two frames
/// (up and down the tree), each moving link interpolated at the time asked for.
///
/// # Example
/// ```
/// use haunts_occupancy::{PoseHistory, TransformTree};
/// use nalgebra::{Isometry2, Point2, Vector2};
///
/// let mut tree = TransformTree::new();
/// // The laser 0.5 m ahead of the robot, the robot driving along x in `odom`.
/// tree.add_static("base_link", "laser", Isometry2::new(Vector2::new(0.5, 0.0), 0.0))?;
/// tree.add_moving(
///     "odom",
///     "base_link",
///     PoseHistory::new([
///         (0.0, Isometry2::identity()),
///         (2.0, Isometry2::new(Vector2::new(2.0, 0.0), 0.0)),
///     ])?,
/// )?;
/// let laser_in_odom = tree.lookup("laser", "odom", 1.0)?;
/// approx::assert_relative_eq!(laser_in_odom * Point2::origin(), Point2::new(1.5, 0.0), epsilon = 1e-12);
/// // The mount alone needs no time.
/// assert!(tree.lookup_static("laser", "base_link").is_ok());
/// assert!(tree.lookup_static("laser", "odom").is_err());
/// # Ok::<(), haunts_occupancy::OccupancyError>(())
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TransformTree {
    /// child → (parent, link).
    links: BTreeMap<String, (String, Link)>,
}

impl TransformTree {
    /// An empty tree.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the fixed transform of `child` under `parent`. Repeating the same link is fine.
    ///
    /// # Errors
    /// [`OccupancyError::ConflictingTransform`] when `child` already has another parent, a
    /// different static pose, or a moving link; [`OccupancyError::NonFinitePose`] for a
    /// non-finite transform.
    pub fn add_static(
        &mut self,
        parent: &str,
        child: &str,
        transform: Isometry2<f64>,
    ) -> Result<()> {
        if !crate::pose_is_finite(&transform) {
            return Err(OccupancyError::NonFinitePose {
                what: format!("static transform {parent} → {child}"),
            });
        }
        self.insert(parent, child, Link::Static(transform))
    }

    /// Adds the moving transform of `child` under `parent`.
    ///
    /// # Errors
    /// [`OccupancyError::ConflictingTransform`] when `child` already has a link.
    pub fn add_moving(&mut self, parent: &str, child: &str, history: PoseHistory) -> Result<()> {
        self.insert(parent, child, Link::Moving(history))
    }

    fn insert(&mut self, parent: &str, child: &str, link: Link) -> Result<()> {
        let (parent, child) = (frame_name(parent), frame_name(child));
        if parent == child {
            return Err(OccupancyError::ConflictingTransform {
                child: child.to_owned(),
                what: "a frame cannot be its own parent".to_owned(),
            });
        }
        match self.links.get(child) {
            None => {
                self.links
                    .insert(child.to_owned(), (parent.to_owned(), link));
                Ok(())
            }
            Some((p, l)) if p == parent && *l == link => Ok(()),
            Some((p, l)) => Err(OccupancyError::ConflictingTransform {
                child: child.to_owned(),
                what: if p != parent {
                    format!("parents `{p}` and `{parent}`")
                } else {
                    match (l, &link) {
                        (Link::Static(_), Link::Static(_)) => {
                            format!("two different static poses under `{p}`")
                        }
                        (Link::Moving(_), Link::Moving(_)) => {
                            format!("two moving links under `{p}`")
                        }
                        _ => format!("both a static and a moving link under `{p}`"),
                    }
                },
            }),
        }
    }

    /// The parent of `frame` and its link, if it has one.
    pub fn parent(&self, frame: &str) -> Option<(&str, &Link)> {
        self.links
            .get(frame_name(frame))
            .map(|(p, l)| (p.as_str(), l))
    }

    /// Every frame of the tree (children and parents), sorted.
    pub fn frames(&self) -> Vec<&str> {
        let mut all: Vec<&str> = self
            .links
            .iter()
            .flat_map(|(c, (p, _))| [c.as_str(), p.as_str()])
            .collect();
        all.sort_unstable();
        all.dedup();
        all
    }

    /// Whether the tree has no link.
    pub fn is_empty(&self) -> bool {
        self.links.is_empty()
    }

    /// The transform that maps coordinates in frame `from` to coordinates in frame `to` at
    /// time `t`, composed along the path between them; `from == to` gives the identity.
    ///
    /// # Errors
    /// [`OccupancyError::NoTransformChain`] when the frames are not connected;
    /// [`OccupancyError::TimeOutOfRange`] when a moving link on the path does not cover `t`.
    ///
    /// # Complexity
    /// `O(f + k log n)` for `f` frames, `k` moving links on the path of `n` samples each.
    pub fn lookup(&self, from: &str, to: &str, t: f64) -> Result<Isometry2<f64>> {
        self.compose(from, to, |link| match link {
            Link::Static(s) => Ok(*s),
            Link::Moving(h) => h.pose_at(t),
        })
    }

    /// As [`TransformTree::lookup`] along static links only.
    ///
    /// # Errors
    /// [`OccupancyError::NoTransformChain`] when no path of static links joins the frames.
    pub fn lookup_static(&self, from: &str, to: &str) -> Result<Isometry2<f64>> {
        let no_chain = || OccupancyError::NoTransformChain {
            from: frame_name(from).to_owned(),
            to: frame_name(to).to_owned(),
        };
        self.compose(from, to, |link| match link {
            Link::Static(s) => Ok(*s),
            Link::Moving(_) => Err(no_chain()),
        })
    }

    /// The ancestors of `frame`, itself first, each with the link to the next one.
    fn ancestors<'a>(&'a self, mut frame: &'a str) -> Vec<(&'a str, Option<&'a Link>)> {
        let mut chain = Vec::new();
        while let Some((parent, link)) = self.links.get(frame) {
            chain.push((frame, Some(link)));
            frame = parent;
            // `insert` cannot make a cycle; the bound keeps a hand-built one finite.
            if chain.len() > self.links.len() {
                break;
            }
        }
        chain.push((frame, None));
        chain
    }

    /// Composes `value(link)` along the path from `from` to `to`: up from `from` to the
    /// common ancestor, then down to `to`.
    fn compose(
        &self,
        from: &str,
        to: &str,
        value: impl Fn(&Link) -> Result<Isometry2<f64>>,
    ) -> Result<Isometry2<f64>> {
        let (from, to) = (frame_name(from), frame_name(to));
        let (up, down) = (self.ancestors(from), self.ancestors(to));
        let Some(common) = up
            .iter()
            .position(|(f, _)| down.iter().any(|(g, _)| g == f))
        else {
            return Err(OccupancyError::NoTransformChain {
                from: from.to_owned(),
                to: to.to_owned(),
            });
        };
        let root = up[common].0;
        // from → root: compose child→parent links.
        let mut from_to_root = Isometry2::identity();
        for (_, link) in &up[..common] {
            if let Some(link) = link {
                from_to_root = value(link)? * from_to_root;
            }
        }
        let mut to_to_root = Isometry2::identity();
        for (frame, link) in &down {
            if *frame == root {
                break;
            }
            if let Some(link) = link {
                to_to_root = value(link)? * to_to_root;
            }
        }
        Ok(to_to_root.inverse() * from_to_root)
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
                Err(OccupancyError::TimeOutOfRange {
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
                Err(OccupancyError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "tolerance",
                        ..
                    }
                ))
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
            Err(OccupancyError::NoSamples { .. })
        ));
    }

    #[test]
    fn a_single_sample_answers_its_own_time_only() {
        let h = PoseHistory::new([(5.0, pose(1.0, 1.0, 1.0))]).unwrap();
        assert_eq!(h.pose_at(5.0).unwrap(), pose(1.0, 1.0, 1.0));
        assert!(h.pose_at(5.0 + 1e-9).is_err());
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
    fn tree_lookups_go_up_and_down_and_interpolate_moving_links() {
        let a = pose(0.5, 0.1, 0.3);
        let b = pose(-0.2, 0.4, -1.0);
        let c = pose(0.05, 0.0, 2.0);
        let mut tree = TransformTree::new();
        tree.add_static("base_link", "left_laser", a).unwrap();
        tree.add_static("/base_link", "torso", b).unwrap();
        tree.add_static("torso", "/head_cam", c).unwrap();
        // Repeating a link is fine; changing it is not.
        tree.add_static("base_link", "left_laser", a).unwrap();
        assert!(matches!(
            tree.add_static("base_link", "left_laser", b),
            Err(OccupancyError::ConflictingTransform { .. })
        ));
        assert!(matches!(
            tree.add_static("odom", "left_laser", a),
            Err(OccupancyError::ConflictingTransform { .. })
        ));
        let odom =
            PoseHistory::new([(0.0, pose(0.0, 0.0, 0.0)), (2.0, pose(2.0, 4.0, 1.0))]).unwrap();
        tree.add_moving("odom", "base_link", odom).unwrap();
        assert_eq!(tree.lookup_static("left_laser", "base_link").unwrap(), a);
        assert_relative_eq!(
            tree.lookup_static("head_cam", "left_laser").unwrap(),
            a.inverse() * b * c,
            epsilon = 1e-12
        );
        assert_eq!(
            tree.lookup("odom", "/odom", 7.0).unwrap(),
            Isometry2::identity()
        );
        let mid = pose(1.0, 2.0, 0.5);
        assert_relative_eq!(
            tree.lookup("left_laser", "odom", 1.0).unwrap(),
            mid * a,
            epsilon = 1e-12
        );
        assert_relative_eq!(
            tree.lookup("odom", "head_cam", 1.0).unwrap(),
            (mid * b * c).inverse(),
            epsilon = 1e-12
        );
        assert!(matches!(
            tree.lookup("left_laser", "odom", 3.0),
            Err(OccupancyError::TimeOutOfRange { .. })
        ));
        assert!(matches!(
            tree.lookup_static("left_laser", "odom"),
            Err(OccupancyError::NoTransformChain { .. })
        ));
        assert!(matches!(
            tree.lookup("left_laser", "map", 1.0),
            Err(OccupancyError::NoTransformChain { .. })
        ));
        assert_eq!(
            tree.frames(),
            ["base_link", "head_cam", "left_laser", "odom", "torso"]
        );
        assert!(tree.add_static("x", "x", a).is_err());
        assert!(tree.add_static("x", "y", pose(f64::NAN, 0.0, 0.0)).is_err());
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
