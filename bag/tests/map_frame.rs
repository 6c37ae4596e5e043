//! Poses in the map frame: a recording whose `/tf` holds map → odom (as AMCL and slam_toolbox
//! publish it) has its odometry composed with it, interpolated at the odometry stamps and held
//! outside its span; `MapFrame::Off`, a missing map frame and the shared real bags keep raw
//! odometry.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::Path;

use haunts_bag::msg;
use haunts_bag::{Bag, BagError, MapFrame, McapWriter, RecordingOptions, convert};
use haunts_occupancy::recording::Recording;
use haunts_occupancy::{LaserScan, Pose2};
use nalgebra::{UnitComplex, Vector2};

/// Odometry stamps: 10.0, 10.1, …, 12.0 s.
fn odom_stamps() -> Vec<f64> {
    (0..=20).map(|i| 10.0 + 0.1 * f64::from(i)).collect()
}

/// The raw odometry (base in odom) at `t`: driving and turning.
fn odom_pose(t: f64) -> Pose2 {
    let s = t - 10.0;
    Pose2::new(Vector2::new(0.8 * s, 0.3 * (2.0 * s).sin()), 0.4 * s - 0.2)
}

fn pose(x: f64, y: f64, yaw: f64) -> Pose2 {
    Pose2::new(Vector2::new(x, y), yaw)
}

fn link(t: f64, parent: &str, child: &str, p: &Pose2) -> msg::TransformStamped {
    msg::TransformStamped {
        header: convert::header(t, parent),
        child_frame_id: child.into(),
        transform: msg::Transform {
            translation: msg::Point {
                x: p.translation.x,
                y: p.translation.y,
                z: 0.0,
            },
            rotation: convert::quaternion(p.rotation.angle()),
        },
    }
}

/// A recording of two scans, the odometry of [`odom_pose`] on `/odom`, the laser mount on
/// `/tf_static`, and `map_to_odom` samples `(stamp, parent, child, pose)` on `/tf`.
fn write(path: &Path, map_to_odom: &[(f64, &str, &str, Pose2)]) {
    let mut out = McapWriter::create(path).unwrap();
    for t in [10.0, 11.0] {
        let scan = LaserScan::new(t, -1.0, 0.5, 0.05, 8.0, vec![2.0; 5], vec![]).unwrap();
        out.write("/scan", t, &convert::laser_scan_msg(&scan, "laser"))
            .unwrap();
    }
    let mount = link(10.0, "base_link", "laser", &pose(0.2, 0.0, 0.0));
    out.write(
        "/tf_static",
        10.0,
        &msg::TfMessage {
            transforms: vec![mount],
        },
    )
    .unwrap();
    for t in odom_stamps() {
        let odometry = msg::Odometry {
            header: convert::header(t, "odom"),
            child_frame_id: "base_link".into(),
            pose: msg::PoseWithCovariance {
                pose: convert::pose_msg(&odom_pose(t)),
                covariance: [[0.0; 6]; 6],
            },
            ..Default::default()
        };
        out.write("/odom", t, &odometry).unwrap();
    }
    for (t, parent, child, p) in map_to_odom {
        let tf = msg::TfMessage {
            transforms: vec![link(*t, parent, child, p)],
        };
        out.write("/tf", *t, &tf).unwrap();
    }
    out.finish().unwrap();
}

fn recording(path: &Path, map_frame: MapFrame) -> Result<Recording, BagError> {
    Bag::open(path)
        .unwrap()
        .recording(&RecordingOptions::new().with_map_frame(map_frame))
}

/// The recording's odometry samples.
fn poses(recording: &Recording) -> Vec<(f64, Pose2)> {
    recording
        .odometry()
        .expect("odometry")
        .samples()
        .map(|(t, p)| (t, *p))
        .collect()
}

fn assert_pose_eq(got: &Pose2, expected: &Pose2, what: &str) {
    let d = got.translation.vector - expected.translation.vector;
    let turn = (got.rotation.inverse() * expected.rotation).angle();
    assert!(
        d.norm() < 1e-9 && turn.abs() < 1e-9,
        "{what}: {got:?} ≠ {expected:?}"
    );
}

/// Each recorded pose against `expected(t)`.
fn assert_poses(recording: &Recording, expected: impl Fn(f64) -> Pose2) {
    let got = poses(recording);
    assert_eq!(got.len(), odom_stamps().len());
    for (t, p) in &got {
        assert_pose_eq(p, &expected(*t), &format!("t = {t}"));
    }
}

/// A plain reference of map → odom between samples: linear translation, shortest-angle
/// heading, the first or last sample outside their span.
fn reference(samples: &[(f64, Pose2)], t: f64) -> Pose2 {
    let (first, last) = (samples[0], samples[samples.len() - 1]);
    if t <= first.0 {
        return first.1;
    }
    if t >= last.0 {
        return last.1;
    }
    let i = samples.iter().position(|(s, _)| *s > t).unwrap();
    let ((t0, p0), (t1, p1)) = (samples[i - 1], samples[i]);
    let u = (t - t0) / (t1 - t0);
    let v = p0.translation.vector + (p1.translation.vector - p0.translation.vector) * u;
    let turn = (p0.rotation.inverse() * p1.rotation).angle();
    Pose2::from_parts(v.into(), UnitComplex::new(p0.rotation.angle() + u * turn))
}

#[test]
fn a_constant_map_to_odom_is_composed_with_the_odometry() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("amcl.mcap");
    let m = pose(3.0, -2.0, 0.5);
    write(&path, &[(10.0, "map", "odom", m), (11.0, "map", "odom", m)]);
    let recording = recording(&path, MapFrame::Auto).unwrap();
    assert_eq!(recording.odom_frame(), "map");
    assert_eq!(recording.base_frame(), "base_link");
    assert_poses(&recording, |t| m * odom_pose(t));
    let notes = recording.notes().join("\n");
    assert!(
        notes.contains("poses in map: map → odom of the transforms (chosen automatically)"),
        "{notes}"
    );
    assert!(!notes.contains("held"), "{notes}");
    // The laser, 0.2 m ahead of the base, in the map frame.
    let laser = recording.sensor_pose_at("laser", 10.5).unwrap();
    assert_pose_eq(
        &laser,
        &(m * odom_pose(10.5) * pose(0.2, 0.0, 0.0)),
        "laser at 10.5 s",
    );
    // Named "map" is the same, without "chosen automatically".
    let named = recording_named(&path, "map");
    assert_eq!(poses(&named), poses(&recording));
    assert!(!named.notes().join("\n").contains("automatically) composed"));
}

fn recording_named(path: &Path, frame: &str) -> Recording {
    recording(path, MapFrame::Named(frame.into())).unwrap()
}

#[test]
fn a_moving_map_to_odom_is_interpolated_and_held_outside_its_span() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("slam.mcap");
    // ROS 1 style names with a leading slash; the heading crosses ±π between the last two.
    let samples = [
        (10.45, pose(3.0, -2.0, 0.5)),
        (11.0, pose(3.4, -1.5, 1.5)),
        (11.55, pose(2.9, -1.8, 3.0)),
        (11.65, pose(3.1, -1.7, -3.1)),
    ];
    let tf: Vec<_> = samples
        .iter()
        .map(|(t, p)| (*t, "/map", "/odom", *p))
        .collect();
    write(&path, &tf);
    let recording = recording(&path, MapFrame::Auto).unwrap();
    assert_eq!(recording.odom_frame(), "map");
    // The stamps as the bag stores them (nanoseconds).
    let stamped: Vec<(f64, Pose2)> = samples
        .iter()
        .map(|(t, p)| (msg::Time::from_seconds(*t).unwrap().seconds(), *p))
        .collect();
    assert_poses(&recording, |t| reference(&stamped, t) * odom_pose(t));
    // 10.0–10.4 before the first transform, 11.7–12.0 after the last.
    let notes = recording.notes().join("\n");
    assert!(
        notes.contains(
            "9 of 21 odometry stamps outside the map → odom span [10.450, 11.650] s \
             (5 before, 4 after): held at its first or last transform"
        ),
        "{notes}"
    );
}

#[test]
fn map_frame_off_keeps_the_raw_odometry() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("off.mcap");
    let m = pose(3.0, -2.0, 0.5);
    write(&path, &[(10.0, "map", "odom", m), (11.0, "map", "odom", m)]);
    let recording = recording(&path, MapFrame::Off).unwrap();
    assert_eq!(recording.odom_frame(), "odom");
    assert_poses(&recording, odom_pose);
    assert!(!recording.notes().join("\n").contains("poses in"));
    // The odometry frame named as the map frame is raw odometry too.
    let same = recording_named(&path, "odom");
    assert_eq!(same.odom_frame(), "odom");
    assert_eq!(poses(&same), poses(&recording));
}

#[test]
fn a_named_map_frame_that_is_absent_is_a_typed_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no_world.mcap");
    let m = pose(3.0, -2.0, 0.5);
    write(&path, &[(10.0, "map", "odom", m)]);
    let err = recording(&path, MapFrame::Named("world".into())).unwrap_err();
    match &err {
        BagError::NoMapFrame {
            path: p,
            frame,
            odom_frame,
            seen,
        } => {
            assert_eq!(p, &path);
            assert_eq!(frame, "world");
            assert_eq!(odom_frame, "odom");
            assert_eq!(seen, &["base_link", "laser", "map", "odom"]);
        }
        other => panic!("expected NoMapFrame, got {other:?}"),
    }
    let text = err.to_string();
    assert!(
        text.contains("`world`") && text.contains("map, odom"),
        "{text}"
    );
}

#[test]
fn without_a_map_frame_auto_keeps_the_raw_odometry() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("odom_only.mcap");
    write(&path, &[]);
    let auto = recording(&path, MapFrame::Auto).unwrap();
    assert_eq!(auto.odom_frame(), "odom");
    assert_poses(&auto, odom_pose);
    let off = recording(&path, MapFrame::Off).unwrap();
    assert_eq!(auto.notes(), off.notes());
    // A `map` frame that is not above odom (here below the base) is said, and not used.
    let below = dir.path().join("map_below.mcap");
    write(&below, &[(10.0, "base_link", "map", pose(1.0, 0.0, 0.0))]);
    let auto = recording(&below, MapFrame::Auto).unwrap();
    assert_eq!(auto.odom_frame(), "odom");
    assert_poses(&auto, odom_pose);
    let notes = auto.notes().join("\n");
    assert!(
        notes.contains("frame map is in the transforms but not above odom"),
        "{notes}"
    );
}

#[test]
fn the_shared_bags_without_a_map_frame_are_unchanged() {
    let (Some(bag), Some(mcap)) = (common::moving_bag(), common::moving_mcap()) else {
        return;
    };
    for path in [bag, mcap] {
        let bag = Bag::open(&path).unwrap();
        let auto = bag.recording(&RecordingOptions::new()).unwrap();
        let off = bag
            .recording(&RecordingOptions::new().with_map_frame(MapFrame::Off))
            .unwrap();
        assert_eq!(auto.odom_frame(), "odom");
        assert_eq!(auto.notes(), off.notes());
        assert_eq!(auto.odometry(), off.odometry());
        assert!(auto.odometry().is_some_and(|h| h.len() > 10_000));
    }
}

#[test]
fn the_default_options_look_for_map() {
    assert_eq!(RecordingOptions::new().map_frame, MapFrame::Auto);
}
