//! The shared real bags: the ROS 1 benchmark bag and its ROS 2 MCAP twin, read through both
//! readers and cross-checked against the text export made from the same bag with the Python
//! `rosbags` package; leg_tracker's training bags (other topics, three lasers in one bag).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::collections::BTreeMap;

use haunts_bag::msg::{self, Message, Person};
use haunts_bag::{Bag, BagError, Format, RecordingOptions};
use serde::{Deserialize, Serialize};

/// The data lines of a text file of the export, split on whitespace.
fn text_rows(relative: &str) -> Vec<Vec<String>> {
    let path = common::shared_data(relative).unwrap();
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(str::to_owned).collect())
        .collect()
}

fn both() -> Option<[Bag; 2]> {
    let (bag, mcap) = (common::moving_bag()?, common::moving_mcap()?);
    Some([Bag::open(bag).unwrap(), Bag::open(mcap).unwrap()])
}

#[test]
fn both_formats_list_the_same_topics_and_counts() {
    let Some(bags) = both() else { return };
    assert_eq!(bags[0].format(), Format::Ros1);
    assert_eq!(bags[1].format(), Format::Mcap);
    let expected = [
        ("/ground_truth_people_tracks", 153),
        ("/map", 1),
        ("/odom", 11_561),
        ("/rosout", 21),
        ("/scan", 873),
        ("/tf", 21_744),
        ("/visualization_marker", 376),
    ];
    for bag in &bags {
        let got: Vec<(&str, u64)> = bag
            .topics()
            .iter()
            .map(|t| (t.name.as_str(), t.count.unwrap()))
            .collect();
        assert_eq!(got, expected, "{}", bag.path().display());
    }
    // ROS 1 names and MD5s; ROS 2 names and no MD5.
    let scan = bags[0].topic("/scan").unwrap();
    assert_eq!(scan.type_name, "sensor_msgs/LaserScan");
    assert_eq!(scan.md5.as_deref(), msg::LaserScan::ROS1_MD5);
    let scan = bags[1].topic("/scan").unwrap();
    assert_eq!(scan.type_name, "sensor_msgs/msg/LaserScan");
    assert_eq!(scan.md5, None);
}

#[test]
fn scans_equal_the_text_export_in_both_formats() {
    let Some(bags) = both() else { return };
    let rows = text_rows("leg_tracker/general_tracking_moving_1/scans.txt");
    assert_eq!(rows.len(), 873);
    for bag in &bags {
        let scans: Vec<(f64, msg::LaserScan)> = bag
            .read::<msg::LaserScan>("/scan")
            .unwrap()
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(scans.len(), rows.len());
        for ((bag_time, scan), row) in scans.iter().zip(&rows) {
            let num = |i: usize| row[i].parse::<f64>().unwrap();
            assert!(
                (bag_time - num(0)).abs() < 1e-6,
                "bag time {bag_time} vs {}",
                row[0]
            );
            assert!((scan.header.stamp.seconds() - num(1)).abs() < 1e-6);
            assert_eq!(scan.header.frame_id, row[2]);
            assert!((f64::from(scan.angle_min) - num(3)).abs() < 1e-9);
            assert!((f64::from(scan.angle_increment) - num(4)).abs() < 1e-9);
            let n: usize = row[7].parse().unwrap();
            assert_eq!(scan.ranges.len(), n);
            // The laser reports whole millimetres; the text has them to the millimetre.
            for (r, text) in scan.ranges.iter().zip(&row[8..]) {
                let t: f64 = text.parse().unwrap();
                assert!(
                    f64::from(*r) == t
                        || (f64::from(*r) - t).abs() < 5e-4
                        || (r.is_nan() && t.is_nan()),
                    "{r} vs {text}"
                );
            }
        }
    }
}

#[test]
fn odometry_and_ground_truth_equal_the_text_export() {
    let Some(bags) = both() else { return };
    let odom = text_rows("leg_tracker/general_tracking_moving_1/odom.txt");
    let truth = text_rows("leg_tracker/general_tracking_moving_1/ground_truth_people.txt");
    for bag in &bags {
        let got: Vec<(f64, msg::Odometry)> = bag
            .read::<msg::Odometry>("/odom")
            .unwrap()
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(got.len(), odom.len());
        for (i, ((t, m), row)) in got.iter().zip(&odom).enumerate() {
            let num = |k: usize| row[k].parse::<f64>().unwrap();
            assert!((t - num(0)).abs() < 1e-6, "odometry {i}");
            assert!((m.header.stamp.seconds() - num(1)).abs() < 1e-6);
            let p = haunts_bag::convert::pose2(&m.pose.pose.position, &m.pose.pose.orientation)
                .unwrap();
            assert!((p.translation.x - num(2)).abs() < 1e-6);
            assert!((p.translation.y - num(3)).abs() < 1e-6);
            assert!((p.rotation.angle() - num(4)).abs() < 1e-6);
        }
        let people: Vec<(f64, Person)> = bag
            .read::<Person>("/ground_truth_people_tracks")
            .unwrap()
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(people.len(), truth.len());
        for ((t, p), row) in people.iter().zip(&truth) {
            let num = |k: usize| row[k].parse::<f64>().unwrap();
            assert!((t - num(0)).abs() < 1e-6);
            assert_eq!(p.id.to_string(), row[1]);
            assert!((p.pose.position.x - num(2)).abs() < 1e-4);
            assert!((p.pose.position.y - num(3)).abs() < 1e-4);
        }
    }
}

#[test]
fn the_recording_of_both_formats_is_the_same() {
    let Some(bags) = both() else { return };
    let tf = text_rows("leg_tracker/general_tracking_moving_1/static_tf.txt");
    let (x, y, yaw): (f64, f64, f64) = (
        tf[0][2].parse().unwrap(),
        tf[0][3].parse().unwrap(),
        tf[0][4].parse().unwrap(),
    );
    let mut first_poses = Vec::new();
    for bag in &bags {
        let recording = bag.recording(&RecordingOptions::new()).unwrap();
        let notes = recording.notes().join("\n");
        assert!(notes.contains("LaserScan from /scan"), "{notes}");
        assert!(notes.contains("Odometry from /odom"), "{notes}");
        assert!(notes.contains("base_link → left_laser"), "{notes}");
        assert_eq!(
            (recording.odom_frame(), recording.base_frame()),
            ("odom", "base_link")
        );
        assert_eq!(recording.scan_count_hint(), Some(873));
        let map = recording.map().expect("the bag's /map");
        assert!((map.geometry().origin().x + 50.0).abs() < 1e-9);
        let mount = recording.mount_at("left_laser", 0.0).unwrap();
        assert!((mount.translation.x - x).abs() < 1e-6);
        assert!((mount.translation.y - y).abs() < 1e-6);
        assert!((mount.rotation.angle() - yaw).abs() < 1e-6);
        let mut frames = BTreeMap::new();
        let mut poses = Vec::new();
        for scan in recording.scans().unwrap() {
            let scan = scan.unwrap();
            *frames.entry(scan.frame.clone()).or_insert(0) += 1;
            if let Ok(p) = recording.sensor_pose_at(&scan.frame, scan.scan.stamp) {
                poses.push(p);
            }
        }
        assert_eq!(frames, BTreeMap::from([("left_laser".to_owned(), 873)]));
        first_poses.push(poses);
    }
    // The two formats give the same sensor poses (stamps agree to the nanosecond).
    assert_eq!(first_poses[0].len(), first_poses[1].len());
    assert!(first_poses[0].len() > 860);
    for (a, b) in first_poses[0].iter().zip(&first_poses[1]) {
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-9);
    }
}

#[test]
fn wrong_types_and_topics_are_typed_errors() {
    let Some(bags) = both() else { return };
    for bag in &bags {
        assert!(matches!(
            bag.read::<msg::Odometry>("/scan"),
            Err(BagError::TypeMismatch { .. })
        ));
        assert!(matches!(
            bag.read::<msg::LaserScan>("/no_such_topic"),
            Err(BagError::NoSuchTopic { .. })
        ));
        assert!(matches!(
            bag.recording(&RecordingOptions::new().with_scan_topic("/odom")),
            Err(BagError::TypeMismatch { .. })
        ));
    }
    // A definition whose ROS 1 MD5 differs from the recorded one.
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    struct NotAScan {
        value: u8,
    }
    impl Message for NotAScan {
        const ROS2_TYPE: &'static str = "sensor_msgs/msg/LaserScan";
        const ROS1_MD5: Option<&'static str> = Some("00000000000000000000000000000000");
        const ROS2_DEFINITION: &'static str = "uint8 value\n";
        type Ros1 = Self;
        fn from_ros1(wire: Self) -> Self {
            wire
        }
        fn to_ros1(&self) -> Self {
            self.clone()
        }
    }
    assert!(matches!(
        bags[0].read::<NotAScan>("/scan"),
        Err(BagError::Md5Mismatch { .. })
    ));
    // In the MCAP (no MD5), the bytes do not match the type: a decode error naming the index.
    let first = bags[1].read::<NotAScan>("/scan").unwrap().next().unwrap();
    assert!(
        matches!(first, Err(BagError::Decode { index: 0, ref topic, .. }) if topic == "/scan"),
        "{first:?}"
    );
}

#[test]
fn training_bags_have_their_topics_and_labels() {
    let Some(dir) = common::shared_data("leg_tracker/training/bags") else {
        return;
    };
    let counts = [(1, 197), (2, 83), (3, 175), (4, 295), (6, 187), (7, 267)];
    for (k, n) in counts {
        let bag = Bag::open(dir.join(format!("positive_{k}_extracted.bag"))).unwrap();
        let scans = bag
            .read::<msg::LaserScan>("/training_scan")
            .unwrap()
            .count();
        let labels: Vec<(f64, msg::PoseArray)> = bag
            .read::<msg::PoseArray>("/leg_cluster_positions")
            .unwrap()
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!((scans, labels.len()), (n, n), "positive_{k}");
        // The scan topic is not /scan: the only LaserScan topic is chosen.
        let recording = bag.recording(&RecordingOptions::new()).unwrap();
        assert!(
            recording
                .notes()
                .iter()
                .any(|n| n.contains("/training_scan"))
        );
        assert!(recording.odometry().is_none());
    }
    let labels: usize = counts
        .iter()
        .map(|(k, _)| {
            let bag = Bag::open(dir.join(format!("positive_{k}_extracted.bag"))).unwrap();
            bag.read::<msg::PoseArray>("/leg_cluster_positions")
                .unwrap()
                .map(|m| m.unwrap().1.poses.len())
                .sum::<usize>()
        })
        .sum();
    // counts.json: 1,852 labelled legs, of which one matched no cluster.
    assert!((1852..=1853).contains(&labels), "{labels}");

    let bag = Bag::open(dir.join("negative_2.bag")).unwrap();
    // Three lasers: no automatic choice.
    let err = bag.recording(&RecordingOptions::new()).unwrap_err();
    assert!(matches!(err, BagError::TopicChoice { .. }), "{err}");
    assert!(err.to_string().contains("/left_scan"));
    for (topic, n) in [
        ("/left_scan", 435),
        ("/rear_scan", 435),
        ("/right_scan", 434),
    ] {
        let recording = bag
            .recording(&RecordingOptions::new().with_scan_topic(topic))
            .unwrap();
        assert_eq!(recording.scans().unwrap().count(), n, "{topic}");
    }
}

#[test]
fn training_bag_markers_decode_as_rosbags_reads_them() {
    // positive_2's /visualization_marker_array has the Indigo-era MD5 (accepted through
    // `ROS1_OTHER_MD5S`). The expected values are what the Python `rosbags` reader (0.11.9,
    // Noetic type store) decodes from the same bag.
    let Some(dir) = common::shared_data("leg_tracker/training/bags") else {
        return;
    };
    let bag = Bag::open(dir.join("positive_2_extracted.bag")).unwrap();
    let arrays: Vec<(f64, msg::MarkerArray)> = bag
        .read::<msg::MarkerArray>("/visualization_marker_array")
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(arrays.len(), 83);
    let total: usize = arrays.iter().map(|a| a.1.markers.len()).sum();
    assert_eq!(total, 116);
    let (_, first) = &arrays[0];
    assert_eq!(first.markers.len(), 2);
    let m = &first.markers[0];
    assert_eq!(
        (m.header.frame_id.as_str(), m.header.stamp, m.ns.as_str()),
        ("laser_frame", msg::Time::default(), "LEGS")
    );
    assert_eq!((m.id, m.type_, m.action), (0, msg::Marker::SPHERE, 0));
    assert_eq!(
        m.pose.position,
        msg::Point {
            x: 1.8198952674865723,
            y: -0.1904856115579605,
            z: 0.1
        }
    );
    assert_eq!(
        (m.pose.orientation.w, m.scale.x, m.scale.z),
        (0.0, 0.2, 0.2)
    );
    assert_eq!(
        m.color,
        msg::ColorRgba {
            r: 1.0,
            g: 0.0,
            b: 0.0,
            a: 1.0
        }
    );
    assert_eq!(
        m.lifetime,
        msg::Duration {
            sec: 0,
            nanosec: 200_000_000
        }
    );
    assert!(!m.frame_locked && m.points.is_empty() && m.text.is_empty());
    assert_eq!(first.markers[1].id, 1);
    assert_eq!(first.markers[1].pose.position.x, 1.6064690351486206);
    let (t, last) = arrays.last().unwrap();
    assert!((t - 1_426_475_811.926_093_3).abs() < 1e-6, "{t}");
    assert_eq!(last.markers.len(), 1);
    assert_eq!(last.markers[0].pose.position.y, 0.18452538549900055);
}

#[test]
fn the_shared_bags_read_in_log_time_order_one_chunk_at_a_time() {
    let Some(bags) = both() else { return };
    for bag in &bags {
        let names: Vec<&str> = bag.topics().iter().map(|t| t.name.as_str()).collect();
        let mut messages = bag.messages(&names).unwrap();
        let times: Vec<u64> = messages.by_ref().map(|m| m.unwrap().log_time).collect();
        let total: u64 = bag.topics().iter().map(|t| t.count.unwrap()).sum();
        assert_eq!(times.len() as u64, total);
        assert!(times.windows(2).all(|w| w[0] <= w[1]), "{:?}", bag.format());
        // Both files' chunks (about 30) do not overlap in time: one is held at a time.
        assert_eq!(messages.most_chunks_held(), 1, "{:?}", bag.format());
    }
}
