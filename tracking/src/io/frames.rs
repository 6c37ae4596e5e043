//! Coordinate frames of the tracking data: robot poses from odometry records, chains of
//! static transforms, and the frames of the `leg_tracker` benchmark bag. The machinery itself
//! ([`PoseHistory`], [`TransformTree`]) lives in `haunts_occupancy`, below every crate
//! that reads recordings; it is re-exported here.
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
//!   midpoint). [`crate::eval::mot::truth_frames_for_scans`] does this grouping.
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

use nalgebra::Isometry2;

pub use haunts_occupancy::{Link, PoseHistory, TransformTree, frame_name};

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

/// A history from `odom.txt` records, indexed by the chosen clock.
///
/// # Errors
/// [`haunts_occupancy::OccupancyError::NoSamples`] (inside [`TrackingError::Occupancy`])
/// when no record is finite.
pub fn odometry_history(records: &[OdomPose], clock: OdomClock) -> Result<PoseHistory> {
    Ok(PoseHistory::new(records.iter().map(|r| {
        let t = match clock {
            OdomClock::HeaderStamp => r.stamp,
            OdomClock::BagTime => r.bag_time,
        };
        (t, r.pose)
    }))?)
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
/// use haunts_tracking::io::frames::static_chain;
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
    let mut tree = TransformTree::new();
    for (i, tf) in transforms.iter().enumerate() {
        if let Err(e) = tree.add_static(&tf.parent, &tf.child, tf.transform) {
            let child = frame_name(&tf.child);
            let first = transforms[..i]
                .iter()
                .find(|f| frame_name(&f.child) == child);
            return Err(match first {
                Some(first) => TrackingError::ConflictingTransform {
                    child: child.to_owned(),
                    first_line: first.line,
                    second_line: tf.line,
                },
                None => e.into(),
            });
        }
    }
    tree.lookup_static(from, to).map_err(|e| match e {
        haunts_occupancy::OccupancyError::NoTransformChain { from, to } => {
            TrackingError::NoTransformChain { from, to }
        }
        e => e.into(),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use approx::assert_relative_eq;
    use nalgebra::Vector2;

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
    fn odometry_records_use_the_chosen_clock() {
        let rec = |bag_time, stamp, x| OdomPose {
            bag_time,
            stamp,
            pose: pose(x, 0.0, 0.0),
            line: 1,
        };
        let records = [rec(1.1, 1.0, 0.0), rec(2.1, 2.0, 1.0)];
        let by_stamp = odometry_history(&records, OdomClock::HeaderStamp).unwrap();
        let by_bag = odometry_history(&records, OdomClock::BagTime).unwrap();
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
}
