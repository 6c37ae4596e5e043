//! Writes the MCAP file that `benches/peers/mcap_ros2_check.py` decodes with the Python
//! `mcap-ros2-support` decoder: one `LaserScan`, `OccupancyGrid`, `Path`, `TFMessage`,
//! `PoseArray` and `MarkerArray` of known content (made through haunts' conversions where one exists), written
//! by [`McapWriter`]. `bag/tests/peer_fixture.rs` includes this file, writes the same messages
//! and checks them against the script's fixture.
//!
//! ```sh
//! cargo run -p haunts-bag --example peer_mcap -- /tmp/peer.mcap
//! ```
#![allow(dead_code)]

use haunts_bag::{McapWriter, convert, msg};
use haunts_occupancy::{LaserScan, Pose2};

/// A message kept as what it means: topic, log time and its fields as JSON (serde's names are
/// the ROS 2 field names).
pub struct Written {
    /// The topic.
    pub topic: &'static str,
    /// The log time, seconds since the UNIX epoch.
    pub seconds: f64,
    /// The message's fields.
    pub fields: serde_json::Value,
}

fn pose2(x: f64, y: f64, yaw: f64) -> Pose2 {
    Pose2::new(nalgebra::Vector2::new(x, y), yaw)
}

fn put<T: msg::Message>(
    out: &mut McapWriter,
    kept: &mut Vec<Written>,
    topic: &'static str,
    seconds: f64,
    message: &T,
) -> Result<(), Box<dyn std::error::Error>> {
    out.write(topic, seconds, message)?;
    kept.push(Written {
        topic,
        seconds,
        fields: serde_json::to_value(message)?,
    });
    Ok(())
}

/// Writes the six messages to `out` (which it finishes) and returns them.
///
/// # Errors
/// Those of the writer.
pub fn write_peer_messages(
    mut out: McapWriter,
) -> Result<Vec<Written>, Box<dyn std::error::Error>> {
    let mut kept = Vec::new();
    let t0 = 1_700_000_000.25;

    // A scan of 7 beams, 0.1 m steps (not exact in binary: the peer must see the same f32 bits),
    // with intensities.
    let ranges = (0..7).map(|i| 0.5 + 0.1 * f64::from(i)).collect();
    let intensities = (0..7).map(|i| 100.0 * f64::from(i)).collect();
    let scan = LaserScan::new(t0, -0.75, 0.25, 0.05, 25.0, ranges, intensities)?;
    put(
        &mut out,
        &mut kept,
        "/scan",
        t0,
        &convert::laser_scan_msg(&scan, "läser"),
    )?;

    // A 4 × 3 grid with unknown (-1), free (0) and occupied (100) cells and a turned origin.
    let grid = msg::OccupancyGrid {
        header: convert::header(t0 + 0.5, "map"),
        info: msg::MapMetaData {
            map_load_time: msg::Time {
                sec: 1_700_000_000,
                nanosec: 999_999_999,
            },
            resolution: 0.05,
            width: 4,
            height: 3,
            origin: convert::pose_msg(&pose2(-1.5, 2.25, 0.3)),
        },
        data: vec![-1, 0, 100, 50, 0, 0, -1, 100, 1, 99, 0, -1],
    };
    put(&mut out, &mut kept, "/map", t0 + 0.5, &grid)?;

    // A path of three poses.
    let poses: Vec<(f64, Pose2)> = (0..3)
        .map(|i| {
            let i = f64::from(i);
            (t0 + i, pose2(i * 0.7, -i * 0.2, 0.1 + i))
        })
        .collect();
    put(
        &mut out,
        &mut kept,
        "/plan",
        t0 + 1.0,
        &convert::path_msg(&poses, "odom"),
    )?;

    // Two transforms: a moving odom → base_link and the laser mount.
    let tf = msg::TfMessage {
        transforms: vec![
            msg::TransformStamped {
                header: convert::header(t0 + 1.5, "odom"),
                child_frame_id: "base_link".into(),
                transform: msg::Transform {
                    translation: msg::Vector3 {
                        x: 1.25,
                        y: -0.5,
                        z: 0.0,
                    },
                    rotation: convert::quaternion(-2.5),
                },
            },
            msg::TransformStamped {
                header: convert::header(t0 + 1.5, "base_link"),
                child_frame_id: "läser".into(),
                transform: msg::Transform {
                    translation: msg::Vector3 {
                        x: 0.3,
                        y: 0.0,
                        z: 0.2,
                    },
                    rotation: convert::quaternion(std::f64::consts::PI),
                },
            },
        ],
    };
    put(&mut out, &mut kept, "/tf", t0 + 1.5, &tf)?;

    // People as a pose array, the second one with a general (not yaw-only) orientation.
    let people = msg::PoseArray {
        header: convert::header(t0 + 2.0, "map"),
        poses: vec![
            convert::pose_msg(&pose2(3.0, 4.0, 1.0)),
            msg::Pose {
                position: msg::Point {
                    x: -1e-3,
                    y: 1e6,
                    z: 0.5,
                },
                orientation: msg::Quaternion {
                    x: 0.5,
                    y: -0.5,
                    z: 0.5,
                    w: 0.5,
                },
            },
        ],
    };
    put(&mut out, &mut kept, "/people", t0 + 2.0, &people)?;

    // Tracks as markers (DELETEALL, spheres, line strips), and one marker that fills every
    // other field: text, per-point colours, a lifetime, texture and mesh bytes.
    let walk = [
        nalgebra::Point2::new(0.0, 0.0),
        nalgebra::Point2::new(0.5, 0.1),
        nalgebra::Point2::new(1.0, -0.3),
    ];
    let mut markers = convert::track_markers(t0 + 2.5, "map", &[(3, &walk[..]), (-12, &walk[2..])]);
    markers.markers.push(msg::Marker {
        header: convert::header(t0 + 2.5, "läser"),
        ns: "labels".into(),
        id: i32::MAX,
        type_: msg::Marker::TRIANGLE_LIST,
        action: msg::Marker::MODIFY,
        pose: convert::pose_msg(&pose2(0.25, -4.0, -1.0)),
        scale: msg::Vector3 {
            x: 1.0,
            y: 0.1,
            z: 1e-3,
        },
        color: msg::ColorRgba {
            r: 0.1,
            g: 0.2,
            b: 0.3,
            a: 0.4,
        },
        lifetime: msg::Duration {
            sec: 2,
            nanosec: 500_000_000,
        },
        frame_locked: true,
        points: vec![
            msg::Point {
                x: 0.0,
                y: 0.0,
                z: 0.0,
            },
            msg::Point {
                x: 1.0,
                y: 0.0,
                z: 0.5,
            },
            msg::Point {
                x: 0.0,
                y: -1.0,
                z: 0.25,
            },
        ],
        colors: vec![
            msg::ColorRgba {
                r: 1.0,
                g: 0.0,
                b: 0.0,
                a: 1.0,
            };
            3
        ],
        texture_resource: "embedded://texture".into(),
        texture: msg::CompressedImage {
            header: convert::header(t0, "tex"),
            format: "png".into(),
            data: vec![0x89, b'P', b'N', b'G', 0, 255],
        },
        uv_coordinates: vec![
            msg::UvCoordinate { u: 0.0, v: 0.0 },
            msg::UvCoordinate { u: 1.0, v: 0.0 },
            msg::UvCoordinate { u: 0.0, v: 1.0 },
        ],
        text: "personne n° 3".into(),
        mesh_resource: "package://haunts/mesh.dae".into(),
        mesh_file: msg::MeshFile {
            filename: "mesh.stl".into(),
            data: vec![1, 2, 3],
        },
        mesh_use_embedded_materials: true,
    });
    put(&mut out, &mut kept, "/markers", t0 + 2.5, &markers)?;

    out.finish()?;
    Ok(kept)
}

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: peer_mcap OUT.mcap");
        std::process::exit(2);
    };
    let result = McapWriter::create(&path)
        .map_err(Into::into)
        .and_then(write_peer_messages);
    match result {
        Ok(kept) => println!("wrote {} messages to {path}", kept.len()),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
