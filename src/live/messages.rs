//! ROS messages in and out of a [`LiveSession`](super::LiveSession): what a scan, an
//! odometry sample and a transform message become before they are pushed, and what a tracked
//! scan's people are published as. `haunts replay` (from a recording) and the ROS 2 node
//! `haunts-ros2` (from DDS) read and write with these, so the two agree message for message.
//!
//! # Example
//! ```
//! use haunts::bag::convert;
//! use haunts::live::messages;
//! use haunts::occupancy::{LaserScan, Pose2};
//!
//! let scan = LaserScan::new(2.5, -1.0, 0.5, 0.05, 20.0, vec![1.0, 2.0, f64::NAN, 3.0, 4.0], vec![])?;
//! let (back, frame) = messages::scan(&convert::laser_scan_msg(&scan, "laser"))?;
//! assert_eq!((back.stamp, frame.as_str()), (2.5, "laser"));
//! let odom = convert::odometry_msg(2.5, "odom", "base_link", &Pose2::translation(1.0, 2.0));
//! let (stamp, pose) = messages::odometry(&odom);
//! assert_eq!((stamp, pose.translation.x), (2.5, 1.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use haunts_bag::convert;
use haunts_bag::msg::{self, MarkerArray, PoseArray};
use haunts_occupancy::{LaserScan, Pose2};
use nalgebra::Point2;

use super::ScanPeople;

/// A `sensor_msgs/LaserScan` as the session takes it: the scan and its frame.
///
/// # Errors
/// The message's description does not make a scan ([`convert::laser_scan`]).
pub fn scan(m: &msg::LaserScan) -> Result<(LaserScan, String), String> {
    Ok((convert::laser_scan(m)?, m.header.frame_id.clone()))
}

/// A `nav_msgs/Odometry` as the session takes it: its stamp and the base's pose. A pose
/// without a heading (a zero quaternion) is made non-finite, for the session to drop and count
/// as bad odometry.
pub fn odometry(m: &msg::Odometry) -> (f64, Pose2) {
    let p = &m.pose.pose;
    (
        m.header.stamp.seconds(),
        pose_or_nan(&p.position, &p.orientation),
    )
}

/// One transform of a `tf2_msgs/TFMessage`, as the session takes it.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// The parent frame.
    pub parent: String,
    /// The child frame.
    pub child: String,
    /// The stamp, seconds.
    pub stamp: f64,
    /// The child's pose in the parent (non-finite when the rotation has no heading, for the
    /// session to drop and count).
    pub pose: Pose2,
}

/// The transforms of a `tf2_msgs/TFMessage`.
pub fn transforms(m: &msg::TfMessage) -> impl Iterator<Item = Link> + '_ {
    m.transforms.iter().map(|t| Link {
        parent: t.header.frame_id.clone(),
        child: t.child_frame_id.clone(),
        stamp: t.header.stamp.seconds(),
        pose: pose_or_nan(&t.transform.translation, &t.transform.rotation),
    })
}

fn pose_or_nan(position: &msg::Point, orientation: &msg::Quaternion) -> Pose2 {
    convert::pose2(position, orientation).unwrap_or_else(|_| Pose2::translation(f64::NAN, f64::NAN))
}

/// A tracked scan's people as a node publishes them, in `frame`, stamped with the scan's
/// stamp: a `geometry_msgs/PoseArray` (each person's position, heading along its velocity)
/// and a `visualization_msgs/MarkerArray` ([`convert::track_markers`]: a sphere per person,
/// its marker id the track's id).
pub fn people(scan: &ScanPeople, frame: &str) -> (PoseArray, MarkerArray) {
    let poses = PoseArray {
        header: convert::header(scan.stamp, frame),
        poses: scan
            .people
            .iter()
            .map(|p| {
                let heading = p.velocity.y.atan2(p.velocity.x);
                convert::pose_msg(&Pose2::new(p.position.coords, heading))
            })
            .collect(),
    };
    let tracks: Vec<(i32, [Point2<f64>; 1])> = scan
        .people
        .iter()
        .map(|p| (p.id as i32, [p.position]))
        .collect();
    let tracks: Vec<(i32, &[Point2<f64>])> = tracks.iter().map(|(id, p)| (*id, &p[..])).collect();
    (poses, convert::track_markers(scan.stamp, frame, &tracks))
}
