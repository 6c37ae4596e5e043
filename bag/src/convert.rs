//! Messages into haunts types and back: laser scans (REP 117 readings kept as they are),
//! planar poses, transforms, occupancy grids, and people tracks as markers.

use haunts_occupancy::{Grid, GridGeometry, OccupancyGrid, Pose2};
use nalgebra::{Point2, UnitComplex, Vector2};

use crate::msg::{self, Header, Quaternion, Time};

/// The heading (rotation about z) of a quaternion, radians: `atan2(2(wz + xy), 1 − 2(y² + z²))`.
/// A quaternion of zero norm has no heading (`None`); any other is normalised first.
pub fn yaw(q: &Quaternion) -> Option<f64> {
    let n = (q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w).sqrt();
    if !(n.is_finite() && n > 1e-12) {
        return None;
    }
    let (x, y, z, w) = (q.x / n, q.y / n, q.z / n, q.w / n);
    Some((2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z)))
}

/// The quaternion of a rotation by `yaw` about z.
pub fn quaternion(yaw: f64) -> Quaternion {
    let (s, c) = (0.5 * yaw).sin_cos();
    Quaternion {
        x: 0.0,
        y: 0.0,
        z: s,
        w: c,
    }
}

/// A planar pose from a position and an orientation (height and tilt dropped).
///
/// # Errors
/// When a component is not finite or the quaternion has zero norm.
pub fn pose2(position: &msg::Point, orientation: &Quaternion) -> Result<Pose2, String> {
    let yaw =
        yaw(orientation).ok_or_else(|| format!("orientation {orientation:?} has no heading"))?;
    if !(position.x.is_finite() && position.y.is_finite()) {
        return Err(format!("position {position:?} is not finite"));
    }
    Ok(Pose2::from_parts(
        Vector2::new(position.x, position.y).into(),
        UnitComplex::new(yaw),
    ))
}

/// A `geometry_msgs/Pose` of a planar pose (z = 0).
pub fn pose_msg(pose: &Pose2) -> msg::Pose {
    msg::Pose {
        position: msg::Point {
            x: pose.translation.x,
            y: pose.translation.y,
            z: 0.0,
        },
        orientation: quaternion(pose.rotation.angle()),
    }
}

/// A haunts scan from a `sensor_msgs/LaserScan`: stamp in seconds, angles and ranges widened to
/// f64 as they are (NaN, ±inf, zero and out-of-range readings keep their REP 117 meaning).
///
/// # Errors
/// What [`haunts_occupancy::LaserScan::new`] rejects (no beams is allowed; a bad increment or
/// range limits are not).
pub fn laser_scan(m: &msg::LaserScan) -> Result<haunts_occupancy::LaserScan, String> {
    let intensities = if m.intensities.len() == m.ranges.len() {
        m.intensities.iter().map(|&v| f64::from(v)).collect()
    } else {
        // Drivers that do not measure intensity send none, or (some) a wrong count.
        Vec::new()
    };
    haunts_occupancy::LaserScan::new(
        m.header.stamp.seconds(),
        f64::from(m.angle_min),
        f64::from(m.angle_increment),
        f64::from(m.range_min),
        f64::from(m.range_max),
        m.ranges.iter().map(|&r| f64::from(r)).collect(),
        intensities,
    )
    .map_err(|e| e.to_string())
}

/// A `geometry_msgs/TransformStamped`: `child`'s pose in `parent` at `seconds`.
pub fn transform_msg(
    seconds: f64,
    parent: &str,
    child: &str,
    pose: &Pose2,
) -> msg::TransformStamped {
    msg::TransformStamped {
        header: header(seconds, parent),
        child_frame_id: child.to_owned(),
        transform: msg::Transform {
            translation: msg::Vector3 {
                x: pose.translation.x,
                y: pose.translation.y,
                z: 0.0,
            },
            rotation: quaternion(pose.rotation.angle()),
        },
    }
}

/// A `nav_msgs/Odometry`: `child`'s pose in `frame` at `seconds` (no twist, no covariance).
pub fn odometry_msg(seconds: f64, frame: &str, child: &str, pose: &Pose2) -> msg::Odometry {
    msg::Odometry {
        header: header(seconds, frame),
        child_frame_id: child.to_owned(),
        pose: msg::PoseWithCovariance {
            pose: pose_msg(pose),
            ..msg::PoseWithCovariance::default()
        },
        ..msg::Odometry::default()
    }
}

/// A `sensor_msgs/LaserScan` of a haunts scan in `frame` (ranges narrowed to f32).
pub fn laser_scan_msg(scan: &haunts_occupancy::LaserScan, frame: &str) -> msg::LaserScan {
    let n = scan.ranges.len();
    msg::LaserScan {
        header: header(scan.stamp, frame),
        angle_min: scan.angle_min as f32,
        angle_max: (scan.angle_min + scan.angle_increment * n.saturating_sub(1) as f64) as f32,
        angle_increment: scan.angle_increment as f32,
        time_increment: 0.0,
        scan_time: 0.0,
        range_min: scan.range_min as f32,
        range_max: scan.range_max as f32,
        ranges: scan.ranges.iter().map(|&r| r as f32).collect(),
        intensities: scan.intensities.iter().map(|&r| r as f32).collect(),
    }
}

/// A header at `seconds` in `frame` (a time that does not fit is written as 0).
pub fn header(seconds: f64, frame: &str) -> Header {
    Header {
        stamp: Time::from_seconds(seconds).unwrap_or_default(),
        frame_id: frame.to_owned(),
    }
}

/// A haunts occupancy grid from a `nav_msgs/OccupancyGrid`.
///
/// # Errors
/// A rotated origin (haunts grids are axis-aligned), a bad geometry, or data of the wrong
/// length or with values outside −1 and 0–100.
pub fn occupancy_grid(m: &msg::OccupancyGrid) -> Result<OccupancyGrid, String> {
    let origin = pose2(&m.info.origin.position, &m.info.origin.orientation)?;
    if origin.rotation.angle().abs() > 1e-9 {
        return Err(format!(
            "the map's origin is rotated by {} rad; only axis-aligned grids are supported",
            origin.rotation.angle()
        ));
    }
    let geometry = GridGeometry::new(
        f64::from(m.info.resolution),
        Point2::new(origin.translation.x, origin.translation.y),
        m.info.width as usize,
        m.info.height as usize,
    )
    .map_err(|e| e.to_string())?;
    OccupancyGrid::from_values(geometry, m.data.clone()).map_err(|e| e.to_string())
}

/// A `nav_msgs/OccupancyGrid` of a haunts grid, stamped `seconds`, in `frame`.
pub fn occupancy_grid_msg(grid: &OccupancyGrid, seconds: f64, frame: &str) -> msg::OccupancyGrid {
    grid_msg(
        grid.geometry(),
        grid.values().data().to_vec(),
        seconds,
        frame,
    )
}

/// A `nav_msgs/OccupancyGrid` of cells `data` (row-major from the origin) on `g`.
fn grid_msg(g: &GridGeometry, data: Vec<i8>, seconds: f64, frame: &str) -> msg::OccupancyGrid {
    msg::OccupancyGrid {
        header: header(seconds, frame),
        info: msg::MapMetaData {
            map_load_time: Time::from_seconds(seconds).unwrap_or_default(),
            resolution: g.resolution() as f32,
            width: u32::try_from(g.width()).unwrap_or(u32::MAX),
            height: u32::try_from(g.height()).unwrap_or(u32::MAX),
            origin: pose_msg(&Pose2::translation(g.origin().x, g.origin().y)),
        },
        data,
    }
}

/// A `nav_msgs/OccupancyGrid` of a scalar grid (a density, a cost) for viewers that colour
/// occupancy grids: each finite value as `round(100 · v / top)` clamped to 0–100, NaN and
/// infinite values as −1 (unknown). `top` is the value drawn as 100; a `top` that is not
/// finite and positive draws every finite cell as 0.
pub fn scalar_grid_msg(
    grid: &Grid<f64>,
    top: f64,
    seconds: f64,
    frame: &str,
) -> msg::OccupancyGrid {
    let scale = if top.is_finite() && top > 0.0 {
        100.0 / top
    } else {
        0.0
    };
    let data = grid
        .data()
        .iter()
        .map(|&v| {
            if v.is_finite() {
                // In 0–100 after the clamp, so the cast is exact.
                (v * scale).round().clamp(0.0, 100.0) as i8
            } else {
                -1
            }
        })
        .collect();
    grid_msg(grid.geometry(), data, seconds, frame)
}

/// A `nav_msgs/Path` through `poses` (each `(seconds, pose)`), in `frame`.
pub fn path_msg(poses: &[(f64, Pose2)], frame: &str) -> msg::Path {
    msg::Path {
        header: header(poses.first().map_or(0.0, |p| p.0), frame),
        poses: poses
            .iter()
            .map(|(t, p)| msg::PoseStamped {
                header: header(*t, frame),
                pose: pose_msg(p),
            })
            .collect(),
    }
}

/// Eight colours told apart easily (Okabe–Ito), for markers coloured by id.
const PALETTE: [[f32; 3]; 8] = [
    [0.902, 0.624, 0.0],
    [0.337, 0.706, 0.914],
    [0.0, 0.620, 0.451],
    [0.941, 0.894, 0.259],
    [0.0, 0.447, 0.698],
    [0.835, 0.369, 0.0],
    [0.800, 0.475, 0.655],
    [0.0, 0.0, 0.0],
];

/// A point of the plane as a `geometry_msgs/Point` (z = 0).
fn point_msg(p: &Point2<f64>) -> msg::Point {
    msg::Point {
        x: p.x,
        y: p.y,
        z: 0.0,
    }
}

/// The marker that clears what a viewer shows before an array replaces it.
fn delete_all(head: &Header) -> msg::Marker {
    msg::Marker {
        header: head.clone(),
        action: msg::Marker::DELETEALL,
        ..msg::Marker::default()
    }
}

/// A `visualization_msgs/MarkerArray` of a flow field at `seconds` in `frame`: a
/// [`Marker::DELETEALL`](msg::Marker::DELETEALL) first (the field replaces the previous one),
/// then per arrow `(tail, head, [r, g, b])` an [`ARROW`](msg::Marker::ARROW) from tail to head
/// (namespace `flow`, ids from 0, shaft 4 cm, head 10 cm wide and a quarter of the arrow
/// long) in its colour (each channel 0 to 1).
///
/// ```
/// use haunts_bag::{convert, msg::Marker};
/// use nalgebra::Point2;
///
/// let east = (Point2::new(1.0, 2.0), Point2::new(1.8, 2.0), [1.0, 0.0, 0.0]);
/// let array = convert::flow_markers(3.0, "map", &[east]);
/// assert_eq!(array.markers[0].action, Marker::DELETEALL);
/// assert_eq!(array.markers[1].type_, Marker::ARROW);
/// assert_eq!((array.markers[1].points[1].x, array.markers[1].color.r), (1.8, 1.0));
/// ```
pub fn flow_markers(
    seconds: f64,
    frame: &str,
    arrows: &[(Point2<f64>, Point2<f64>, [f32; 3])],
) -> msg::MarkerArray {
    let head = header(seconds, frame);
    let point = point_msg;
    let mut markers = vec![delete_all(&head)];
    for (id, (tail, tip, [r, g, b])) in arrows.iter().enumerate() {
        markers.push(msg::Marker {
            header: head.clone(),
            ns: "flow".to_owned(),
            id: i32::try_from(id).unwrap_or(i32::MAX),
            type_: msg::Marker::ARROW,
            action: msg::Marker::ADD,
            points: vec![point(tail), point(tip)],
            scale: msg::Vector3 {
                x: 0.04,
                y: 0.10,
                z: 0.25 * (tip - tail).norm(),
            },
            color: msg::ColorRgba {
                r: *r,
                g: *g,
                b: *b,
                a: 1.0,
            },
            ..msg::Marker::default()
        });
    }
    msg::MarkerArray { markers }
}

/// A `visualization_msgs/MarkerArray` of people tracks at `seconds` in `frame`, each track an
/// id and its positions (oldest first): a [`Marker::DELETEALL`](msg::Marker::DELETEALL) first,
/// so tracks that ended disappear when the array replaces the previous one, then per track a
/// [`SPHERE`](msg::Marker::SPHERE) of 0.3 m at its last position (namespace `people`) and a
/// [`LINE_STRIP`](msg::Marker::LINE_STRIP) 5 cm wide through its positions (namespace
/// `tracks`), both with the track's id and one colour per id. A track without positions is
/// left out; one of a single position gets no line.
///
/// ```
/// use haunts_bag::{convert, msg::Marker};
/// use nalgebra::Point2;
///
/// let walk = [Point2::new(0.0, 0.0), Point2::new(0.5, 0.1), Point2::new(1.0, 0.3)];
/// let array = convert::track_markers(12.5, "map", &[(7, &walk[..])]);
/// let kinds: Vec<i32> = array.markers.iter().map(|m| m.type_).collect();
/// assert_eq!(array.markers[0].action, Marker::DELETEALL);
/// assert_eq!(kinds[1..], [Marker::SPHERE, Marker::LINE_STRIP]);
/// assert_eq!(array.markers[1].pose.position.x, 1.0);
/// assert_eq!(array.markers[2].points.len(), 3);
/// ```
pub fn track_markers(
    seconds: f64,
    frame: &str,
    tracks: &[(i32, &[Point2<f64>])],
) -> msg::MarkerArray {
    let head = header(seconds, frame);
    let marker = |ns: &str, id: i32, type_: i32| {
        let [r, g, b] = PALETTE[id.rem_euclid(PALETTE.len() as i32) as usize];
        msg::Marker {
            header: head.clone(),
            ns: ns.to_owned(),
            id,
            type_,
            action: msg::Marker::ADD,
            color: msg::ColorRgba { r, g, b, a: 1.0 },
            ..msg::Marker::default()
        }
    };
    let point = point_msg;
    let mut markers = vec![delete_all(&head)];
    for &(id, positions) in tracks {
        let Some(last) = positions.last() else {
            continue;
        };
        let mut person = marker("people", id, msg::Marker::SPHERE);
        person.pose.position = point(last);
        person.scale = msg::Vector3 {
            x: 0.3,
            y: 0.3,
            z: 0.3,
        };
        markers.push(person);
        if positions.len() > 1 {
            let mut line = marker("tracks", id, msg::Marker::LINE_STRIP);
            line.scale.x = 0.05;
            line.points = positions.iter().map(point).collect();
            markers.push(line);
        }
    }
    msg::MarkerArray { markers }
}
