//! Typed ROS messages: the fields of each message as it is serialised, in ROS 2 form, and the
//! [`Message`] trait that ties a type to its names, its ROS 1 MD5 sum and its ROS 1 wire form.
//!
//! ROS 1 and ROS 2 serialise the same fields but for `std_msgs/Header`, which in ROS 1 starts
//! with a `uint32 seq`. Every message with a header is therefore generic over it: the public
//! type (`LaserScan`, i.e. `LaserScan<Header>`) has the ROS 2 header, and
//! `LaserScan<Ros1Header>` is the ROS 1 wire form that [`Message::from_ros1`] converts from.
//! Times are `builtin_interfaces/Time` (`int32 sec`, `uint32 nanosec`); a ROS 1 `time`
//! (`uint32 secs`, `uint32 nsecs`) has the same eight bytes, read as ROS 2 reads them, so a
//! ROS 1 stamp after 2038-01-19 would read as negative ([`Time::seconds`] says so by being
//! negative; no recording of ours comes near it).
//!
//! A user's own message is any serde type implementing [`Message`] (see its docs).

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

mod definitions;
mod marker;

pub use marker::{
    ColorRgba, CompressedImage, Duration, Marker, MarkerArray, MeshFile, Ros1Marker, UvCoordinate,
};

/// A ROS message type that the bag readers can decode and the MCAP writer can write.
///
/// Implement it for your own types to read them from bags (the benchmark bags' ground truth is
/// `leg_tracker/msg/Person`, a type of the `leg_tracker` package):
///
/// ```
/// use haunts_bag::msg::{Message, Pose};
/// use serde::{Deserialize, Serialize};
///
/// /// `leg_tracker/msg/Person`: a tracked person (no header).
/// #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
/// struct Person {
///     pose: Pose,
///     id: u32,
/// }
///
/// impl Message for Person {
///     const ROS2_TYPE: &'static str = "leg_tracker/msg/Person";
///     const ROS1_MD5: Option<&'static str> = None; // not checked
///     const ROS2_DEFINITION: &'static str = "geometry_msgs/Pose pose\nuint32 id\n";
///     type Ros1 = Self;
///     fn from_ros1(wire: Self) -> Self {
///         wire
///     }
///     fn to_ros1(&self) -> Self {
///         self.clone()
///     }
/// }
/// assert_eq!(Person::ros1_type(), "leg_tracker/Person");
/// ```
pub trait Message: Serialize + DeserializeOwned + Clone {
    /// The ROS 2 type name, `package/msg/Name` (e.g. `sensor_msgs/msg/LaserScan`).
    const ROS2_TYPE: &'static str;
    /// The ROS 1 MD5 sum of the definition, checked against a ROS 1 bag's connection when
    /// given (`None`: not checked).
    const ROS1_MD5: Option<&'static str>;
    /// Other ROS 1 MD5 sums accepted: definitions of older distributions with the same
    /// fields on the wire, whose constants or types of constants differ (none by default).
    const ROS1_OTHER_MD5S: &'static [&'static str] = &[];
    /// The ROS 2 `ros2msg` definition written as the schema of an MCAP channel (dependencies
    /// after `MSG:` separators, as `ros2 bag record` writes them).
    const ROS2_DEFINITION: &'static str;
    /// The ROS 1 wire form (the message with [`Ros1Header`]s; `Self` for a message without a
    /// header).
    type Ros1: Serialize + DeserializeOwned;

    /// The message from its ROS 1 wire form (the headers lose their `seq`).
    fn from_ros1(wire: Self::Ros1) -> Self;

    /// The ROS 1 wire form of the message (headers get `seq` 0).
    fn to_ros1(&self) -> Self::Ros1;

    /// The ROS 1 type name, `package/Name`.
    fn ros1_type() -> String {
        ros1_name(Self::ROS2_TYPE)
    }
}

/// `package/msg/Name` → `package/Name` (ROS 1 names have no `msg/`).
pub(crate) fn ros1_name(ros2: &str) -> String {
    ros2.replacen("/msg/", "/", 1)
}

/// Whether a recorded type name names `T`: the ROS 2 name, or the ROS 1 name, with or without
/// `msg/` (a ROS 1 bag says `sensor_msgs/LaserScan`, a ROS 2 one `sensor_msgs/msg/LaserScan`).
/// ROS 1's `tf/tfMessage` is accepted for `tf2_msgs/msg/TFMessage` (the same definition and
/// MD5).
pub(crate) fn names_type<T: Message>(recorded: &str) -> bool {
    recorded == T::ROS2_TYPE
        || ros1_name(recorded) == T::ros1_type()
        || (T::ROS2_TYPE == "tf2_msgs/msg/TFMessage" && recorded == "tf/tfMessage")
}

/// `builtin_interfaces/Time`: seconds and nanoseconds since the UNIX epoch.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, 0..1e9.
    pub nanosec: u32,
}

impl Time {
    /// The time in seconds (f64: about 0.2 µs resolution at today's UNIX times).
    pub fn seconds(&self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    /// Nanoseconds since the epoch.
    pub fn nanos(&self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// The time of `nanos` nanoseconds since the epoch, if its seconds fit an `i32`.
    pub fn from_nanos(nanos: i64) -> Option<Self> {
        let sec = i32::try_from(nanos.div_euclid(1_000_000_000)).ok()?;
        let nanosec = u32::try_from(nanos.rem_euclid(1_000_000_000)).ok()?;
        Some(Self { sec, nanosec })
    }

    /// The time nearest to `seconds` (to the nanosecond), if finite and within `i32` seconds.
    pub fn from_seconds(seconds: f64) -> Option<Self> {
        let nanos = (seconds * 1e9).round();
        if !(nanos.is_finite() && nanos.abs() < 9.2e18) {
            return None;
        }
        Self::from_nanos(nanos as i64)
    }
}

/// `std_msgs/Header` as ROS 2 has it.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Header {
    /// When the data was measured.
    pub stamp: Time,
    /// The frame the data is in.
    pub frame_id: String,
}

/// `std_msgs/Header` as ROS 1 serialises it: a sequence number first.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Ros1Header {
    /// The publisher's sequence number (dropped on conversion).
    pub seq: u32,
    /// When the data was measured.
    pub stamp: Time,
    /// The frame the data is in.
    pub frame_id: String,
}

impl From<Ros1Header> for Header {
    fn from(h: Ros1Header) -> Self {
        Self {
            stamp: h.stamp,
            frame_id: h.frame_id,
        }
    }
}

impl From<&Header> for Ros1Header {
    fn from(h: &Header) -> Self {
        Self {
            seq: 0,
            stamp: h.stamp,
            frame_id: h.frame_id.clone(),
        }
    }
}

/// `geometry_msgs/Point` (and `Vector3`: the same three doubles).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// z, metres.
    pub z: f64,
}

/// `geometry_msgs/Vector3`.
pub type Vector3 = Point;

/// `geometry_msgs/Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    /// The identity rotation.
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// `geometry_msgs/Pose`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position, metres.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/Transform`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Translation, metres.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/Twist`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// Linear velocity, m/s.
    pub linear: Vector3,
    /// Angular velocity, rad/s.
    pub angular: Vector3,
}

/// `geometry_msgs/PoseWithCovariance`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Its covariance over (x, y, z, rotation about x, y, z): 6 × 6, row-major (`float64[36]`;
    /// serde has no 36-element arrays, and six rows of six serialise to the same bytes).
    pub covariance: [[f64; 6]; 6],
}

/// `geometry_msgs/TwistWithCovariance`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    /// The twist.
    pub twist: Twist,
    /// Its covariance, 6 × 6, row-major (as the pose's).
    pub covariance: [[f64; 6]; 6],
}

/// `sensor_msgs/LaserScan`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LaserScan<H = Header> {
    /// Stamp of the first beam and the laser's frame.
    pub header: H,
    /// Angle of the first beam, radians.
    pub angle_min: f32,
    /// Angle of the last beam, radians.
    pub angle_max: f32,
    /// Angle between beams, radians.
    pub angle_increment: f32,
    /// Time between beams, seconds.
    pub time_increment: f32,
    /// Time between scans, seconds.
    pub scan_time: f32,
    /// Shortest valid range, metres.
    pub range_min: f32,
    /// Longest valid range, metres.
    pub range_max: f32,
    /// Ranges, metres (REP 117: NaN, ±inf and out-of-range values are meaningful).
    pub ranges: Vec<f32>,
    /// Intensities (empty or one per range).
    pub intensities: Vec<f32>,
}

/// `nav_msgs/Odometry`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Odometry<H = Header> {
    /// Stamp and the odometry frame (`odom`).
    pub header: H,
    /// The robot frame the pose is of (`base_link`).
    pub child_frame_id: String,
    /// Pose of the child frame in the header's frame.
    pub pose: PoseWithCovariance,
    /// Velocity in the child frame.
    pub twist: TwistWithCovariance,
}

/// `geometry_msgs/TransformStamped`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped<H = Header> {
    /// Stamp and the parent frame.
    pub header: H,
    /// The child frame.
    pub child_frame_id: String,
    /// Child coordinates → parent coordinates.
    pub transform: Transform,
}

/// `tf2_msgs/TFMessage` (`/tf`, `/tf_static`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TfMessage<H = Header> {
    /// The transforms.
    pub transforms: Vec<TransformStamped<H>>,
}

/// `geometry_msgs/PoseStamped`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped<H = Header> {
    /// Stamp and frame.
    pub header: H,
    /// The pose.
    pub pose: Pose,
}

/// `geometry_msgs/PoseWithCovarianceStamped` (e.g. AMCL's `/amcl_pose`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovarianceStamped<H = Header> {
    /// Stamp and frame.
    pub header: H,
    /// The pose and its covariance.
    pub pose: PoseWithCovariance,
}

/// `geometry_msgs/PoseArray` (leg_tracker's training labels).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseArray<H = Header> {
    /// Stamp and frame.
    pub header: H,
    /// The poses.
    pub poses: Vec<Pose>,
}

/// `nav_msgs/MapMetaData`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MapMetaData {
    /// When the map was loaded.
    pub map_load_time: Time,
    /// Metres per cell.
    pub resolution: f32,
    /// Cells along x.
    pub width: u32,
    /// Cells along y.
    pub height: u32,
    /// Pose of cell (0, 0)'s lower-left corner in the map frame.
    pub origin: Pose,
}

/// `nav_msgs/OccupancyGrid`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct OccupancyGrid<H = Header> {
    /// Stamp and the map frame.
    pub header: H,
    /// Geometry.
    pub info: MapMetaData,
    /// Row-major cells, row 0 at the bottom: −1 unknown, 0–100 occupancy probability.
    pub data: Vec<i8>,
}

/// `nav_msgs/Path`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Path<H = Header> {
    /// Stamp and frame.
    pub header: H,
    /// The poses along the path.
    pub poses: Vec<PoseStamped<H>>,
}

/// Implements [`Message`] for a message generic over its header, given how to move its
/// headers between the two forms.
macro_rules! message {
    ($ty:ident, $ros2:literal, $md5:path, $def:path, |$m:ident, $h:ident| $convert:expr) => {
        impl Message for $ty {
            const ROS2_TYPE: &'static str = $ros2;
            const ROS1_MD5: Option<&'static str> = Some($md5);
            const ROS2_DEFINITION: &'static str = $def;
            type Ros1 = $ty<Ros1Header>;
            fn from_ros1(wire: Self::Ros1) -> Self {
                let $m = wire;
                let $h = |h: Ros1Header| Header::from(h);
                $convert
            }
            fn to_ros1(&self) -> Self::Ros1 {
                let $m = self.clone();
                let $h = |h: Header| Ros1Header::from(&h);
                $convert
            }
        }
    };
}

message!(
    LaserScan,
    "sensor_msgs/msg/LaserScan",
    definitions::LASERSCAN_MD5,
    definitions::LASERSCAN_DEFINITION,
    |m, h| LaserScan {
        header: h(m.header),
        angle_min: m.angle_min,
        angle_max: m.angle_max,
        angle_increment: m.angle_increment,
        time_increment: m.time_increment,
        scan_time: m.scan_time,
        range_min: m.range_min,
        range_max: m.range_max,
        ranges: m.ranges,
        intensities: m.intensities,
    }
);

message!(
    Odometry,
    "nav_msgs/msg/Odometry",
    definitions::ODOMETRY_MD5,
    definitions::ODOMETRY_DEFINITION,
    |m, h| Odometry {
        header: h(m.header),
        child_frame_id: m.child_frame_id,
        pose: m.pose,
        twist: m.twist,
    }
);

message!(
    TfMessage,
    "tf2_msgs/msg/TFMessage",
    definitions::TFMESSAGE_MD5,
    definitions::TFMESSAGE_DEFINITION,
    |m, h| TfMessage {
        transforms: m
            .transforms
            .into_iter()
            .map(|t| TransformStamped {
                header: h(t.header),
                child_frame_id: t.child_frame_id,
                transform: t.transform,
            })
            .collect(),
    }
);

message!(
    PoseStamped,
    "geometry_msgs/msg/PoseStamped",
    definitions::POSESTAMPED_MD5,
    definitions::POSESTAMPED_DEFINITION,
    |m, h| PoseStamped {
        header: h(m.header),
        pose: m.pose,
    }
);

message!(
    PoseWithCovarianceStamped,
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    definitions::POSEWITHCOVARIANCESTAMPED_MD5,
    definitions::POSEWITHCOVARIANCESTAMPED_DEFINITION,
    |m, h| PoseWithCovarianceStamped {
        header: h(m.header),
        pose: m.pose,
    }
);

message!(
    PoseArray,
    "geometry_msgs/msg/PoseArray",
    definitions::POSEARRAY_MD5,
    definitions::POSEARRAY_DEFINITION,
    |m, h| PoseArray {
        header: h(m.header),
        poses: m.poses,
    }
);

message!(
    OccupancyGrid,
    "nav_msgs/msg/OccupancyGrid",
    definitions::OCCUPANCYGRID_MD5,
    definitions::OCCUPANCYGRID_DEFINITION,
    |m, h| OccupancyGrid {
        header: h(m.header),
        info: m.info,
        data: m.data,
    }
);

message!(
    Path,
    "nav_msgs/msg/Path",
    definitions::PATH_MD5,
    definitions::PATH_DEFINITION,
    |m, h| Path {
        header: h(m.header),
        poses: m
            .poses
            .into_iter()
            .map(|p| PoseStamped {
                header: h(p.header),
                pose: p.pose,
            })
            .collect(),
    }
);

/// `leg_tracker/msg/Person` (the `leg_tracker` package's own message, no header): the ground
/// truth of the public `leg_tracker` benchmark bags (`/ground_truth_people_tracks`). It is
/// here because those bags are the field's benchmark; it is also what a user's own type looks
/// like (see [`Message`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Person {
    /// The person's pose (the benchmark annotates positions in the laser frame).
    pub pose: Pose,
    /// The person's id.
    pub id: u32,
}

impl Message for Person {
    const ROS2_TYPE: &'static str = "leg_tracker/msg/Person";
    const ROS1_MD5: Option<&'static str> = Some("4f334171b5664340c323a1982b554a22");
    const ROS2_DEFINITION: &'static str = "geometry_msgs/Pose pose\nuint32 id\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
    type Ros1 = Self;
    fn from_ros1(wire: Self) -> Self {
        wire
    }
    fn to_ros1(&self) -> Self {
        self.clone()
    }
}
