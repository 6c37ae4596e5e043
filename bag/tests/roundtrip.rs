//! Write → read round trips of random messages (MCAP files bit for bit; the ROS 1 codec), and
//! broken files: truncated at many bytes, garbage, corrupted chunks.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use haunts_bag::codec::{self, Encoding};
use haunts_bag::msg::{self, Header, Message, Time};
use haunts_bag::{Bag, BagError, McapWriter};
use proptest::prelude::*;

fn header() -> impl Strategy<Value = Header> {
    (any::<i32>(), 0u32..1_000_000_000, "[a-z_/]{0,12}").prop_map(|(sec, nanosec, frame_id)| {
        Header {
            stamp: Time { sec, nanosec },
            frame_id,
        }
    })
}

/// Any f32, NaN and infinities included (bit patterns).
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![any::<u32>().prop_map(f32::from_bits), -20.0f32..20.0]
}

fn laser_scan() -> impl Strategy<Value = msg::LaserScan> {
    (
        header(),
        prop::array::uniform7(any_f32()),
        prop::collection::vec(any_f32(), 0..50),
        prop::collection::vec(any_f32(), 0..3),
    )
        .prop_map(|(header, a, ranges, intensities)| msg::LaserScan {
            header,
            angle_min: a[0],
            angle_max: a[1],
            angle_increment: a[2],
            time_increment: a[3],
            scan_time: a[4],
            range_min: a[5],
            range_max: a[6],
            ranges,
            intensities,
        })
}

fn pose() -> impl Strategy<Value = msg::Pose> {
    prop::array::uniform7(-1e3f64..1e3).prop_map(|v| msg::Pose {
        position: msg::Point {
            x: v[0],
            y: v[1],
            z: v[2],
        },
        orientation: msg::Quaternion {
            x: v[3],
            y: v[4],
            z: v[5],
            w: v[6],
        },
    })
}

fn odometry() -> impl Strategy<Value = msg::Odometry> {
    (
        header(),
        "[a-z_]{0,10}",
        pose(),
        prop::array::uniform6(-5.0f64..5.0),
        -1.0f64..1.0,
    )
        .prop_map(|(header, child_frame_id, pose, twist, c)| msg::Odometry {
            header,
            child_frame_id,
            pose: msg::PoseWithCovariance {
                pose,
                covariance: [[c; 6]; 6],
            },
            twist: msg::TwistWithCovariance {
                twist: msg::Twist {
                    linear: msg::Point {
                        x: twist[0],
                        y: twist[1],
                        z: twist[2],
                    },
                    angular: msg::Point {
                        x: twist[3],
                        y: twist[4],
                        z: twist[5],
                    },
                },
                covariance: [[-c; 6]; 6],
            },
        })
}

fn tf() -> impl Strategy<Value = msg::TfMessage> {
    prop::collection::vec((header(), "[a-z_]{1,8}", pose()), 0..5).prop_map(|v| msg::TfMessage {
        transforms: v
            .into_iter()
            .map(|(header, child_frame_id, p)| msg::TransformStamped {
                header,
                child_frame_id,
                transform: msg::Transform {
                    translation: p.position,
                    rotation: p.orientation,
                },
            })
            .collect(),
    })
}

fn grid() -> impl Strategy<Value = msg::OccupancyGrid> {
    (
        header(),
        1u32..6,
        1u32..6,
        0.01f32..1.0,
        pose(),
        any::<i8>(),
    )
        .prop_map(
            |(header, width, height, resolution, origin, v)| msg::OccupancyGrid {
                header,
                info: msg::MapMetaData {
                    map_load_time: Time { sec: 7, nanosec: 9 },
                    resolution,
                    width,
                    height,
                    origin,
                },
                data: (0..width * height)
                    .map(|i| v.wrapping_add(i as i8))
                    .collect(),
            },
        )
}

fn path() -> impl Strategy<Value = msg::Path> {
    (header(), prop::collection::vec((header(), pose()), 0..6)).prop_map(|(header, poses)| {
        msg::Path {
            header,
            poses: poses
                .into_iter()
                .map(|(header, pose)| msg::PoseStamped { header, pose })
                .collect(),
        }
    })
}

fn color() -> impl Strategy<Value = msg::ColorRgba> {
    prop::array::uniform4(any_f32()).prop_map(|[r, g, b, a]| msg::ColorRgba { r, g, b, a })
}

fn point() -> impl Strategy<Value = msg::Point> {
    pose().prop_map(|p| p.position)
}

fn marker() -> impl Strategy<Value = msg::Marker> {
    let shape = (
        header(),
        "[a-z_ é]{0,8}",
        any::<i32>(),
        0i32..12,
        prop::sample::select(vec![
            msg::Marker::ADD,
            msg::Marker::DELETE,
            msg::Marker::DELETEALL,
        ]),
        pose(),
        point(),
        color(),
        (any::<i32>(), 0u32..1_000_000_000),
        any::<bool>(),
        prop::collection::vec(point(), 0..5),
        prop::collection::vec(color(), 0..3),
    );
    let extras = (
        "[a-z:/]{0,10}",
        (
            header(),
            "[a-z]{0,4}",
            prop::collection::vec(any::<u8>(), 0..9),
        ),
        prop::collection::vec((any_f32(), any_f32()), 0..3),
        "[a-zA-Z0-9 ]{0,12}",
        "[a-z:/.]{0,10}",
        ("[a-z.]{0,6}", prop::collection::vec(any::<u8>(), 0..5)),
        any::<bool>(),
    );
    (shape, extras).prop_map(|(s, e)| msg::Marker {
        header: s.0,
        ns: s.1,
        id: s.2,
        type_: s.3,
        action: s.4,
        pose: s.5,
        scale: s.6,
        color: s.7,
        lifetime: msg::Duration {
            sec: s.8.0,
            nanosec: s.8.1,
        },
        frame_locked: s.9,
        points: s.10,
        colors: s.11,
        texture_resource: e.0,
        texture: msg::CompressedImage {
            header: e.1.0,
            format: e.1.1,
            data: e.1.2,
        },
        uv_coordinates: e
            .2
            .into_iter()
            .map(|(u, v)| msg::UvCoordinate { u, v })
            .collect(),
        text: e.3,
        mesh_resource: e.4,
        mesh_file: msg::MeshFile {
            filename: e.5.0,
            data: e.5.1,
        },
        mesh_use_embedded_materials: e.6,
    })
}

/// Equality that takes NaN for NaN: compare the CDR bytes of the two messages.
fn same<T: Message>(a: &T, b: &T) -> bool {
    codec::encode_cdr(a).unwrap() == codec::encode_cdr(b).unwrap()
}

/// Writes `messages` to one topic of an MCAP file, reads them back, and checks every one
/// (bytes and log times).
fn mcap_round_trip<T: Message + std::fmt::Debug>(messages: &[T]) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.mcap");
    let mut writer = McapWriter::create(&path).unwrap();
    for (i, m) in messages.iter().enumerate() {
        writer.write("/topic", 100.0 + i as f64 * 0.25, m).unwrap();
    }
    writer.finish().unwrap();
    let bag = Bag::open(&path).unwrap();
    if messages.is_empty() {
        prop_assert!(bag.topics().is_empty());
        return Ok(());
    }
    let info = bag.topic("/topic").unwrap();
    prop_assert_eq!(&info.type_name, T::ROS2_TYPE);
    prop_assert_eq!(info.count, Some(messages.len() as u64));
    let back: Vec<(f64, T)> = bag
        .read::<T>("/topic")
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    prop_assert_eq!(back.len(), messages.len());
    for (i, ((t, b), a)) in back.iter().zip(messages).enumerate() {
        prop_assert!((t - (100.0 + i as f64 * 0.25)).abs() < 1e-9);
        prop_assert!(same(a, b), "{a:?} != {b:?}");
    }
    Ok(())
}

/// The ROS 1 codec: encode, decode, equal.
fn ros1_round_trip<T: Message + std::fmt::Debug>(m: &T) -> Result<(), TestCaseError> {
    ros1_round_trip_to(m, m)
}

/// The ROS 1 codec: `m` encoded and decoded is `expected` (what ROS 1 keeps of `m`).
fn ros1_round_trip_to<T: Message + std::fmt::Debug>(
    m: &T,
    expected: &T,
) -> Result<(), TestCaseError> {
    let bytes = codec::encode_ros1(m).unwrap();
    let back: T = codec::decode(Encoding::Ros1, &bytes).unwrap();
    // ROS 1 headers carry a seq, dropped on the way back: the rest is equal.
    prop_assert!(same(expected, &back), "{expected:?} != {back:?}");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn laser_scans_round_trip(scans in prop::collection::vec(laser_scan(), 0..4)) {
        mcap_round_trip(&scans)?;
        for s in &scans { ros1_round_trip(s)?; }
    }

    #[test]
    fn odometry_round_trips(odom in prop::collection::vec(odometry(), 1..4)) {
        mcap_round_trip(&odom)?;
        for o in &odom { ros1_round_trip(o)?; }
    }

    #[test]
    fn transforms_grids_and_paths_round_trip(t in tf(), g in grid(), p in path()) {
        mcap_round_trip(std::slice::from_ref(&t))?;
        mcap_round_trip(std::slice::from_ref(&g))?;
        mcap_round_trip(std::slice::from_ref(&p))?;
        ros1_round_trip(&t)?;
        ros1_round_trip(&g)?;
        ros1_round_trip(&p)?;
    }

    #[test]
    fn marker_arrays_round_trip(arrays in prop::collection::vec(
        prop::collection::vec(marker(), 0..4).prop_map(|markers| msg::MarkerArray { markers }),
        0..3,
    )) {
        mcap_round_trip(&arrays)?;
        for a in &arrays {
            // ROS 1 (Noetic) has no texture or mesh-file fields: they come back empty.
            let kept = msg::MarkerArray {
                markers: a
                    .markers
                    .iter()
                    .map(|m| msg::Marker {
                        texture_resource: String::new(),
                        texture: msg::CompressedImage::default(),
                        uv_coordinates: Vec::new(),
                        mesh_file: msg::MeshFile::default(),
                        ..m.clone()
                    })
                    .collect(),
            };
            ros1_round_trip_to(a, &kept)?;
            ros1_round_trip(&kept)?;
            for m in &a.markers {
                mcap_round_trip(std::slice::from_ref(m))?;
            }
        }
    }
}

#[test]
fn cdr_bytes_of_a_known_message_match_the_ros2_layout() {
    // PoseStamped: header {sec, nanosec, frame_id "m"} then 7 doubles aligned to 8.
    let m = msg::PoseStamped {
        header: Header {
            stamp: Time { sec: 1, nanosec: 2 },
            frame_id: "m".into(),
        },
        pose: msg::Pose::default(),
    };
    let bytes = codec::encode_cdr(&m).unwrap();
    let mut expected = vec![0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, b'm', 0];
    // Padding to 16 bytes of body (doubles are 8-aligned from the end of the encapsulation).
    expected.extend([0; 2]);
    for v in [0.0f64, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
        expected.extend(v.to_le_bytes());
    }
    assert_eq!(bytes, expected);
    let back: msg::PoseStamped = codec::decode(Encoding::Cdr, &bytes).unwrap();
    assert_eq!(back, m);
    // Trailing bytes that the type does not use are an error, not ignored.
    let mut long = bytes.clone();
    long.extend([0; 16]);
    assert!(codec::decode::<msg::PoseStamped>(Encoding::Cdr, &long).is_err());
    // Too short.
    assert!(codec::decode::<msg::PoseStamped>(Encoding::Cdr, &bytes[..20]).is_err());
    assert!(codec::decode::<msg::PoseStamped>(Encoding::Cdr, &bytes[..2]).is_err());
}

/// Corrupts one chunk of a file: in a ROS 1 bag (whose chunks here are not compressed, so
/// flipped data bytes would only change values) the fifth chunk's compression becomes an
/// unknown name; in an MCAP file 64 bytes in the middle of the second chunk's compressed
/// records are flipped (its zstd frame, or its CRC, breaks).
fn corrupt_a_chunk(bytes: &mut [u8]) {
    if bytes.starts_with(b"#ROSBAG") {
        let needle = b"compression=none";
        let at = bytes
            .windows(needle.len())
            .enumerate()
            .filter(|(_, w)| w == needle)
            .nth(4)
            .map(|(i, _)| i)
            .unwrap();
        bytes[at + 12..at + 16].copy_from_slice(b"zzzz");
    } else {
        // Walk the records (opcode, u64 length, body) to the second chunk (opcode 0x06), and
        // flip 64 bytes in the middle of its compressed records.
        let (mut at, mut chunks) = (8usize, 0);
        loop {
            let op = bytes[at];
            let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
            if op == 0x06 {
                chunks += 1;
                if chunks == 2 {
                    let body = at + 9;
                    let name_len =
                        u32::from_le_bytes(bytes[body + 28..body + 32].try_into().unwrap())
                            as usize;
                    let records = body + 32 + name_len + 8;
                    let mid = records + (body + len - records) / 2;
                    for b in &mut bytes[mid..mid + 64] {
                        *b ^= 0x5a;
                    }
                    return;
                }
            }
            at += 9 + len;
        }
    }
}

/// Opening and reading every topic of `path` ends in values or typed errors, never a panic;
/// returns how many messages were read.
fn read_everything(path: &std::path::Path) -> Result<usize, BagError> {
    let bag = Bag::open(path)?;
    let topics: Vec<String> = bag.topics().iter().map(|t| t.name.clone()).collect();
    let names: Vec<&str> = topics.iter().map(String::as_str).collect();
    let mut n = 0;
    for m in bag.messages(&names)? {
        if m.is_ok() {
            n += 1;
        }
    }
    Ok(n)
}

#[test]
fn truncated_files_are_errors_not_panics() {
    let (Some(bag), Some(mcap)) = (common::moving_bag(), common::moving_mcap()) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for source in [bag, mcap] {
        let bytes = std::fs::read(&source).unwrap();
        let whole = read_everything(&source).unwrap();
        assert_eq!(whole, 34_729);
        // Cuts in the header, in the middle, and just before the end.
        let len = bytes.len();
        let mut cuts = vec![0, 1, 7, 12, 13, 20, 100, 4096, 4200];
        cuts.extend((1..20).map(|k| k * len / 20));
        cuts.extend([len - 100, len - 37, len - 8, len - 1]);
        for cut in cuts {
            let path = dir.path().join("cut");
            std::fs::write(&path, &bytes[..cut]).unwrap();
            // A truncated file either fails to open, or reads what precedes the cut. An MCAP
            // cut inside its summary (after every message) keeps all of them, and says that
            // the summary was unreadable; a cut in the data loses what follows the cut only.
            match read_everything(&path) {
                Err(_) => {}
                Ok(n) if n == whole => {
                    let notes = Bag::open(&path).unwrap().notes().join(" ");
                    assert!(
                        notes.contains("summary unreadable"),
                        "{} cut at {cut}: all {n} read, notes: {notes}",
                        source.display()
                    );
                }
                Ok(n) => assert!(n < whole),
            }
            // A cut in the second half of a data section keeps most of it.
            if source.extension().is_some_and(|e| e == "mcap") && cut > len / 2 && cut < len - 200 {
                let n = read_everything(&path).unwrap();
                assert!(
                    n as f64 > 0.4 * whole as f64,
                    "cut at {cut}: {n} of {whole}"
                );
            }
        }
    }
}

#[test]
fn garbage_and_corrupted_chunks_are_typed_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("garbage.bag");
    std::fs::write(&path, b"SQLite format 3\0 not a bag").unwrap();
    assert!(matches!(
        Bag::open(&path),
        Err(BagError::UnknownFormat { .. })
    ));
    assert!(matches!(
        Bag::open(dir.path().join("absent.mcap")),
        Err(BagError::Io { .. })
    ));
    let (Some(bag), Some(mcap)) = (common::moving_bag(), common::moving_mcap()) else {
        return;
    };
    // The shared MCAP was written without chunk CRCs (rosbags-convert), so flipped bytes in
    // it can decode into other values unseen (zstd frames without a checksum do not always
    // fail on flipped bytes; measured on this file): one written here has them.
    let _ = mcap;
    let written = dir.path().join("written.mcap");
    let mut writer = McapWriter::create(&written).unwrap();
    let scan = msg::LaserScan {
        ranges: (0..2000).map(|i| (i * 7919 % 1000) as f32 * 0.01).collect(),
        ..Default::default()
    };
    for i in 0..400 {
        writer.write("/scan", 10.0 + f64::from(i), &scan).unwrap();
    }
    writer.finish().unwrap();
    for (source, whole) in [(bag, 34_729), (written, 400)] {
        let mut bytes = std::fs::read(&source).unwrap();
        corrupt_a_chunk(&mut bytes);
        let path = dir.path().join("flipped");
        std::fs::write(&path, &bytes).unwrap();
        match read_everything(&path) {
            Err(_) => {}
            Ok(n) => assert!(n < whole, "{}: {n}", source.display()),
        }
    }
}

#[test]
fn a_ros1_bag_with_a_broken_chunk_loses_that_chunk_only() {
    let Some(source) = common::moving_bag() else {
        return;
    };
    let mut bytes = std::fs::read(&source).unwrap();
    corrupt_a_chunk(&mut bytes);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flipped.bag");
    std::fs::write(&path, &bytes).unwrap();
    let bag = Bag::open(&path).unwrap();
    let (mut ok, mut errors) = (0, 0);
    for m in bag.messages(&["/scan"]).unwrap() {
        match m {
            Ok(_) => ok += 1,
            Err(e) => {
                errors += 1;
                assert!(e.to_string().contains("byte"), "{e}");
            }
        }
    }
    // The bag's chunks hold about 1 MB each (≈ 25 scans): one is lost, the rest are read.
    assert!(
        errors >= 1 && ok > 800 && ok < 873,
        "{ok} scans, {errors} errors"
    );
}
