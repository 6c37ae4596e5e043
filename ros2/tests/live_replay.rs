//! The node over DDS, end to end, inside a network namespace of the test's own (only `lo`;
//! see `haunts_test_support::netns`): a recording published onto its topics, the node
//! tracking it, a subscriber recording what the node publishes.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use haunts::affordance::LayoutLibrary;
use haunts::bag::msg::{Marker, MarkerArray, Message as _, OccupancyGrid, Time};
use haunts::bag::{Bag, RecordingOptions, convert};
use haunts::live::replay::{Replay, Replayed};
use haunts::live::{LiveParams, LiveSession, ScanPeople};
use haunts::occupancy::{MapLoadOptions, load_map};
use haunts::pipeline::serve::{ServeParams, save_layout_maps, serve_layout};
use haunts::tracking::detect::static_map::StaticMapParams;
use haunts::tracking::eval::mot::Frame;
use haunts::tracking::eval::sequence::EvalParams;
use haunts_ros2::node::{HauntsNode, NodeParams};
use haunts_ros2::publish::{DdsReplay, Published, ReplayParams};
use haunts_ros2::ros2_client::dds::{Context, Node, Subscription};
use haunts_ros2::ros2_client::{NodeName, NodeOptions};
use haunts_ros2::wire;
use haunts_test_support::{bag::moving_mcap, netns};

/// The node running on a thread of its own until `stop`; the node back when it stops.
fn spawn_node(params: NodeParams, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<HauntsNode> {
    let context = Context::new().unwrap();
    let mut node = HauntsNode::new(&context, params).unwrap();
    std::thread::spawn(move || {
        let _context = context;
        node.spin_until(&stop, Duration::from_millis(20)).unwrap();
        node
    })
}

/// The node's parameters for `replay`'s recording, with `haunts replay`'s window.
fn node_params(replay: &Replay) -> NodeParams {
    NodeParams::for_recording(replay, LiveParams::default().with_window(0.5))
}

/// `mcap` published over DDS at `rate` times its pace, once its subscribers matched.
fn publish(mcap: &std::path::Path, rate: f64) -> Published {
    let context = Context::new().unwrap();
    let dds = DdsReplay::new(&context, Bag::open(mcap).unwrap(), &RecordingOptions::new()).unwrap();
    let params = ReplayParams::default()
        .with_rate(rate)
        .with_wait(Duration::from_secs(20));
    let published = dds.run(&params).unwrap();
    assert!(published.matched, "{published:?}");
    published
}

/// A ROS node of the test's own, with its discovery task running (to see matches).
fn test_node(name: &str) -> (Context, Node) {
    let context = Context::new().unwrap();
    let mut node = context
        .new_node(
            NodeName::new("/", name).unwrap(),
            NodeOptions::new().enable_rosout(false),
        )
        .unwrap();
    let spinner = node.spinner().unwrap();
    std::thread::spawn(move || futures::executor::block_on(spinner.spin()));
    (context, node)
}

/// Takes every message waiting on `sub`, until `want` have come or `patience` has passed
/// without a new one.
fn collect<M: serde::de::DeserializeOwned + 'static>(
    sub: &Subscription<M>,
    out: &mut Vec<M>,
    want: usize,
    patience: Duration,
) {
    let mut last = Instant::now();
    while out.len() < want && last.elapsed() < patience {
        match sub.take() {
            Ok(Some((m, _))) => {
                out.push(m);
                last = Instant::now();
            }
            _ => std::thread::sleep(Duration::from_millis(5)),
        }
    }
}

/// A recorder of the node's people markers: its context and node (kept while it records) and
/// its reader.
fn recorder() -> ((Context, Node), Subscription<MarkerArray>) {
    let (context, mut node) = test_node("recorder");
    let markers = subscription::<MarkerArray>(
        &mut node,
        "/haunts/people_markers",
        MarkerArray::ROS2_TYPE,
        wire::stream_qos(5000),
    );
    ((context, node), markers)
}

/// The people messages on `markers` once a replay ended: all but the scans still waiting at
/// the end of the stream before the node is stopped, the rest after it flushed; the node.
fn stop_and_collect(
    node: std::thread::JoinHandle<HauntsNode>,
    stop: &AtomicBool,
    markers: &Subscription<MarkerArray>,
    want: usize,
) -> (HauntsNode, Vec<MarkerArray>) {
    let mut got = Vec::new();
    collect(
        markers,
        &mut got,
        want.saturating_sub(5),
        Duration::from_secs(5),
    );
    stop.store(true, Ordering::Relaxed);
    let mut node = node.join().unwrap();
    node.flush();
    collect(markers, &mut got, want, Duration::from_secs(5));
    (node, got)
}

/// The people of a MarkerArray the node published: (track id, position), from its spheres.
fn people_of(markers: &MarkerArray) -> Vec<(u64, [f64; 2])> {
    markers
        .markers
        .iter()
        .filter(|m| m.type_ == Marker::SPHERE)
        .map(|m| (m.id as u64, [m.pose.position.x, m.pose.position.y]))
        .collect()
}

/// moving_1's MCAP, once inside the network namespace of `test` (see [`netns::enter`]);
/// `None` (skip) in the process that ran it there, or where the shared data is absent.
fn moving_1_in_netns(test: &str) -> Option<std::path::PathBuf> {
    if !netns::enter(test) {
        return None;
    }
    let mcap = moving_mcap();
    if mcap.is_none() {
        eprintln!("skipped: ../shared/data is absent");
    }
    mcap
}

/// `mcap` replayed offline as `haunts replay` runs it, with the node's own parameters: the
/// replay, its session, every tracked scan's people and the replay's report.
fn offline(mcap: &std::path::Path) -> (Replay, LiveSession, Vec<ScanPeople>, Replayed) {
    let replay = Replay::new(Bag::open(mcap).unwrap(), &RecordingOptions::new(), None).unwrap();
    let mut session = LiveSession::with_defaults(node_params(&replay).live).unwrap();
    let mut people = Vec::new();
    let replayed = replay
        .run(&mut session, |s| {
            people.push(s.clone());
            Ok(())
        })
        .unwrap();
    (replay, session, people, replayed)
}

/// The people of a scan tracked offline, as [`people_of`] reads them off the wire.
fn people_of_scan(scan: &ScanPeople) -> Vec<(u64, [f64; 2])> {
    scan.people
        .iter()
        .map(|p| (p.id, [p.position.x, p.position.y]))
        .collect()
}

/// (a) moving_1's MCAP published over DDS at 4× its pace with `/clock`; the node (sim time,
/// reliable inputs) tracks it; a subscriber records the people. Every tracked scan's people arrive, equal to
/// the offline replay's (`haunts replay`: same ids, same positions), and the CLEAR MOT of the
/// people received is the offline one's exactly.
#[test]
fn replay_over_dds_tracks_as_offline() {
    let Some(mcap) = moving_1_in_netns("replay_over_dds_tracks_as_offline") else {
        return;
    };
    let (replay, offline, want, replayed) = offline(&mcap);
    let protocol =
        EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()));
    let (offline_every, offline_annotated) = replayed.scores(&protocol).unwrap().unwrap();

    // The recorder first, so it is matched when the node publishes.
    let (_recorder, markers) = recorder();
    let stop = Arc::new(AtomicBool::new(false));
    // Reliable inputs: what a loaded machine drops is resent, and the comparison is exact.
    let node = spawn_node(
        node_params(&replay).with_reliable_inputs(true),
        stop.clone(),
    );
    let published = publish(&mcap, 4.0);
    assert_eq!(published.undecodable, 0);
    assert_eq!(published.publish_failures, 0);

    let (node, got) = stop_and_collect(node, &stop, &markers, want.len());
    let stats = node.stats().clone();
    eprintln!(
        "published {published:?}; node took {} messages, undecodable {:?}, dropped {:?}; \
         processing {}; end to end {}",
        stats.messages,
        stats.undecodable,
        node.session().dropped(),
        stats.processing.summary(),
        stats.end_to_end.summary()
    );
    assert_eq!(stats.undecodable.total(), 0);
    assert_eq!(*node.session().dropped(), *offline.dropped());
    assert_eq!(got.len(), want.len(), "people messages received");

    // Scan by scan: the same stamps, ids and positions as offline.
    let mut hypotheses: Vec<Frame> = replayed
        .scan_times
        .iter()
        .map(|&t| Frame::new(t, Vec::new()))
        .collect();
    for (k, (m, w)) in got.iter().zip(&want).enumerate() {
        let stamp = m.markers.first().map(|m| m.header.stamp).unwrap();
        assert_eq!(stamp, Time::from_seconds(w.stamp).unwrap(), "scan {k}");
        let people = people_of(m);
        assert_eq!(people, people_of_scan(w), "scan {k}");
        hypotheses[w.index].objects = people
            .iter()
            .map(|(id, [x, y])| {
                let p = haunts::nalgebra::Point2::new(*x, *y);
                (*id, w.sensor.inverse_transform_point(&p))
            })
            .collect();
    }
    let mut received = replayed.clone();
    received.hypotheses = hypotheses;
    let (every, annotated) = received.scores(&protocol).unwrap().unwrap();
    eprintln!(
        "MOTA over DDS {:.4} (every scan) {:.4} (annotated); offline {:.4} {:.4}",
        every.scores.mota,
        annotated.scores.mota,
        offline_every.scores.mota,
        offline_annotated.scores.mota
    );
    assert_eq!(every.scores, offline_every.scores);
    assert_eq!(annotated.scores, offline_annotated.scores);
}

/// A subscription of `M` on `name` by `node`, with `qos`.
fn subscription<M: serde::de::DeserializeOwned + 'static>(
    node: &mut Node,
    name: &str,
    ros2: &str,
    qos: haunts_ros2::ros2_client::QosProfile,
) -> Subscription<M> {
    let topic = topic(node, name, ros2, &qos);
    node.create_subscription(&topic, Some(qos)).unwrap()
}

/// The topic `name` of ROS 2 type `ros2`, with `qos`.
fn topic(
    node: &mut Node,
    name: &str,
    ros2: &str,
    qos: &haunts_ros2::ros2_client::QosProfile,
) -> haunts_ros2::ros2_client::dds::rustdds::Topic {
    node.create_topic(
        &wire::topic_name(name).unwrap(),
        wire::type_name(ros2).unwrap(),
        qos,
    )
    .unwrap()
}

/// A publisher of `M` on `name` (ROS 2 type `ros2`) with `qos`, once a reader matched it.
fn matched_publisher<M: serde::Serialize>(
    node: &mut Node,
    name: &str,
    ros2: &str,
    qos: haunts_ros2::ros2_client::QosProfile,
) -> haunts_ros2::ros2_client::Publisher<M> {
    let topic = topic(node, name, ros2, &qos);
    let publisher = node.create_publisher::<M>(&topic, Some(qos)).unwrap();
    let waited = Instant::now();
    while publisher.get_subscription_count(node) == 0 && waited.elapsed() < Duration::from_secs(20)
    {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(
        publisher.get_subscription_count(node) > 0,
        "{name} not matched"
    );
    publisher
}

/// The same cells, but for the resolution's rounding to `float32` on the wire
/// (`nav_msgs/MapMetaData`).
fn same_cells(got: &haunts::occupancy::GridGeometry, want: &haunts::occupancy::GridGeometry) {
    assert_eq!((got.width(), got.height()), (want.width(), want.height()));
    assert!((got.resolution() - want.resolution()).abs() < 1e-7 * want.resolution());
    assert_eq!(got.origin(), want.origin());
}

/// The first message on `sub` within `patience`.
fn first<M: serde::de::DeserializeOwned + 'static>(sub: &Subscription<M>, patience: Duration) -> M {
    let mut got = Vec::new();
    collect(sub, &mut got, 1, patience);
    got.pop().expect("a message")
}

/// (b) The day closed on request (`std_msgs/Empty` on `/haunts/close_day`) after moving_1
/// was replayed over DDS: the node merges it into a new library (saved atomically) and serves
/// the layout the day joined; a subscriber that comes afterwards (transient local) receives
/// the costmap equal cell for cell to what `haunts maps` saves of that library
/// (`save_layout_maps`, read back), the composite likewise, and the speed mask with its filter
/// info (slower exactly where the layout's density is above zero).
#[test]
fn closed_day_is_served_as_haunts_maps_saves_it() {
    let Some(mcap) = moving_1_in_netns("closed_day_is_served_as_haunts_maps_saves_it") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let library = dir.path().join("library.haunts");
    let replay = Replay::new(Bag::open(&mcap).unwrap(), &RecordingOptions::new(), None).unwrap();
    let params = node_params(&replay).with_library(&library, dir.path().join("day.mcap"));
    let stop = Arc::new(AtomicBool::new(false));
    let node = spawn_node(params, stop.clone());
    publish(&mcap, 8.0);

    // The request to close, once the node's reader has matched it.
    let (_test_context, mut test_node) = test_node("tester");
    let close = matched_publisher::<wire::Empty>(
        &mut test_node,
        "/haunts/close_day",
        wire::Empty::ROS2_TYPE,
        wire::stream_qos(10),
    );
    std::thread::sleep(Duration::from_millis(300));
    close.publish(wire::Empty::default()).unwrap();
    let waited = Instant::now();
    while !library.exists() && waited.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(100));
    }
    assert!(library.exists(), "the day was not merged");

    // A late subscriber gets the maps (transient local).
    let latched = wire::latched_qos();
    let n = &mut test_node;
    let costmap = subscription::<OccupancyGrid>(
        n,
        "/haunts/costmap",
        OccupancyGrid::ROS2_TYPE,
        latched.clone(),
    );
    let composite =
        subscription::<OccupancyGrid>(n, "/haunts/map", OccupancyGrid::ROS2_TYPE, latched.clone());
    let mask = subscription::<OccupancyGrid>(
        n,
        "/haunts/speed_mask",
        OccupancyGrid::ROS2_TYPE,
        latched.clone(),
    );
    let info = subscription::<wire::CostmapFilterInfo>(
        n,
        "/haunts/costmap_filter_info",
        wire::CostmapFilterInfo::ROS2_TYPE,
        latched,
    );
    let patience = Duration::from_secs(20);
    let (costmap, composite, mask, info) = (
        first(&costmap, patience),
        first(&composite, patience),
        first(&mask, patience),
        first(&info, patience),
    );
    stop.store(true, Ordering::Relaxed);
    let mut node = node.join().unwrap();
    let closed = node
        .take_last_close()
        .expect("a close")
        .expect("the close succeeded");
    assert_eq!(node.stats().days_closed, 1);
    let layout_id = closed.layout.expect("the day joined a layout");
    assert_eq!(node.served().map(|(id, _)| *id), Some(layout_id));

    // What `haunts maps` saves of the library, read back.
    let saved = LayoutLibrary::load(&library).unwrap();
    let layout = saved
        .layouts()
        .iter()
        .find(|l| l.id() == layout_id)
        .unwrap();
    let served = serve_layout(layout, &ServeParams::default()).unwrap();
    let maps = dir.path().join("maps");
    std::fs::create_dir_all(&maps).unwrap();
    let (composite_yaml, costmap_yaml) = save_layout_maps(&maps, layout_id.0, &served).unwrap();
    let load = |yaml: &std::path::Path| load_map(yaml, &MapLoadOptions::default()).unwrap().grid;
    let (want_costmap, want_composite) = (load(&costmap_yaml), load(&composite_yaml));
    let got_costmap = convert::occupancy_grid(&costmap).unwrap();
    let got_composite = convert::occupancy_grid(&composite).unwrap();
    same_cells(got_costmap.geometry(), want_costmap.geometry());
    assert_eq!(got_costmap.values().data(), want_costmap.values().data());
    same_cells(got_composite.geometry(), want_composite.geometry());
    assert_eq!(
        got_composite.values().data(),
        want_composite.values().data()
    );
    let busy = want_costmap
        .values()
        .data()
        .iter()
        .filter(|&&v| v > 0)
        .count();
    eprintln!(
        "costmap {}×{} cells, {busy} with a cost, equal to haunts maps' file",
        want_costmap.geometry().width(),
        want_costmap.geometry().height()
    );

    // The speed mask: a limit exactly where the layout saw people, as Nav2 reads it.
    assert_eq!(info.type_, wire::CostmapFilterInfo::SPEED_PERCENT);
    assert_eq!(info.filter_mask_topic, "/haunts/speed_mask");
    assert_eq!(mask.data.len(), served.density.data().len());
    let mut slowed = 0;
    for (v, d) in mask.data.iter().zip(served.density.data()) {
        let limit = haunts_ros2::maps::speed_limit(&info, *v);
        assert_eq!(
            limit.is_some(),
            d.is_finite() && *d > 0.0,
            "mask {v}, density {d}"
        );
        if let Some(l) = limit {
            assert!((30.0 - 1e-3..100.0).contains(&l), "limit {l}");
            slowed += 1;
        }
    }
    assert!(slowed > 0, "no cell slowed");
}

/// A payload of exactly these bytes after the encapsulation header (a CDR tuple of octets:
/// no length, no padding), to put bytes on a topic that its readers cannot decode.
#[derive(Debug)]
struct Raw(Vec<u8>);

impl serde::Serialize for Raw {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple as _;
        let mut t = s.serialize_tuple(self.0.len())?;
        for b in &self.0 {
            t.serialize_element(b)?;
        }
        t.end()
    }
}

/// A seeded xorshift64: the hostile bytes are the same every run.
struct Bytes(u64);

impl Bytes {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn take(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

/// A publisher of raw bytes as ROS 2 type `ros2` on `name`, once the node's reader matched.
fn raw_publisher(
    node: &mut Node,
    name: &str,
    ros2: &str,
) -> haunts_ros2::ros2_client::Publisher<Raw> {
    matched_publisher(node, name, ros2, wire::stream_qos(1000))
}

/// (c) Bad wire input: bytes on the node's inputs that do not decode (random, empty, a real
/// scan truncated), a scan that decodes but describes no scan (a NaN angle increment), a good
/// scan from another time and frame (dropped for want of its mount, counted), and
/// datagrams of random bytes and of broken RTPS to the DDS ports on `lo`. Each sample the node
/// takes is counted by input, nothing panics, and the moving_1 replay that follows is tracked
/// as offline, scan for scan.
#[test]
fn bad_wire_input_is_counted_and_tracking_goes_on() {
    let Some(mcap) = moving_1_in_netns("bad_wire_input_is_counted_and_tracking_goes_on") else {
        return;
    };
    let (replay, offline, want, _) = offline(&mcap);

    let (_recorder, markers) = recorder();
    // Reliable inputs, as in (a).
    let params = node_params(&replay).with_reliable_inputs(true);
    let inputs = [
        params.scan_topic.clone(),
        params.odom_topic.clone(),
        params.tf_topic.clone(),
    ];
    let stop = Arc::new(AtomicBool::new(false));
    let node = spawn_node(params, stop.clone());

    let (_hostile_context, mut hostile) = test_node("hostile");
    let n = &mut hostile;
    let scans = raw_publisher(n, &inputs[0], haunts::bag::msg::LaserScan::ROS2_TYPE);
    let odom = raw_publisher(n, &inputs[1], haunts::bag::msg::Odometry::ROS2_TYPE);
    let tf = raw_publisher(n, &inputs[2], haunts::bag::msg::TfMessage::ROS2_TYPE);
    let mut bytes = Bytes(0x9e37_79b9_7f4a_7c15);
    let scan =
        haunts::occupancy::LaserScan::new(1.0, -1.5, 0.01, 0.05, 20.0, vec![2.0; 300], vec![])
            .unwrap();
    let scan = convert::laser_scan_msg(&scan, "laser");
    let encoded = cdr_encoding::to_vec::<_, byteorder::LittleEndian>(&scan).unwrap();
    // Undecodable: empty, random lengths and bytes, the real scan cut short.
    let mut undecodable_scans = vec![Vec::new()];
    for k in 0..30 {
        undecodable_scans.push(bytes.take(k * 11 % 300));
    }
    // (RTPS pads a payload to four bytes, with zeros: a cut of fewer than four bytes off
    // the end, where the empty intensities' length is zero, gives the scan back.)
    for cut in [1, 7, 8, 20, encoded.len() / 2, encoded.len() - 4] {
        undecodable_scans.push(encoded[..cut].to_vec());
    }
    for b in &undecodable_scans {
        scans.publish(Raw(b.clone())).unwrap();
        std::thread::sleep(Duration::from_millis(2));
    }
    // Decodes, but no scan: a NaN increment, an inverted range interval.
    let mut nan_increment = scan.clone();
    nan_increment.angle_increment = f32::NAN;
    let mut inverted = scan.clone();
    inverted.range_max = 0.01;
    let unconvertible = [nan_increment, inverted];
    for m in &unconvertible {
        let b = cdr_encoding::to_vec::<_, byteorder::LittleEndian>(m).unwrap();
        scans.publish(Raw(b)).unwrap();
        std::thread::sleep(Duration::from_millis(2));
    }
    // A good scan from another time (stamp 1 s, frame `laser`, which the recording's tf does
    // not mount), before the replay's first `/clock`: the session drops it for want of its
    // mount, and it costs the recording no scan.
    scans.publish(Raw(encoded.clone())).unwrap();
    let others = 20;
    for k in 0..others {
        odom.publish(Raw(bytes.take(k * 17 % 400))).unwrap();
        tf.publish(Raw(bytes.take(k * 13 % 200))).unwrap();
        std::thread::sleep(Duration::from_millis(2));
    }
    // Datagrams to the DDS ports of domain 0 on `lo` (discovery 7400, then 7410 + 2i and
    // 7411 + 2i per participant): random, and an RTPS header with broken submessages.
    let socket = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    for port in 7400..7430 {
        for k in 0..10 {
            let mut datagram = bytes.take(k * 37 % 600);
            if k % 2 == 1 {
                let mut rtps = b"RTPS\x02\x04\x01\x0f".to_vec();
                rtps.extend(bytes.take(12));
                rtps.extend(datagram);
                datagram = rtps;
            }
            let _ = socket.send_to(&datagram, ("127.0.0.1", port));
        }
    }

    // Then a recording as in (a): tracked as offline.
    let published = publish(&mcap, 4.0);
    let (node, got) = stop_and_collect(node, &stop, &markers, want.len());
    let stats = node.stats().clone();
    eprintln!(
        "published {published:?}; node took {} messages, undecodable {:?}, unconvertible {}, \
         dropped {:?}",
        stats.messages,
        stats.undecodable,
        stats.unconvertible,
        node.session().dropped(),
    );
    // Every hostile sample taken is counted where it came in (best effort may lose a few
    // on the way, none once matched on `lo` in practice).
    let u = &stats.undecodable;
    let at_least = |sent: usize| sent * 9 / 10;
    assert!(
        (at_least(undecodable_scans.len())..=undecodable_scans.len()).contains(&u.scan),
        "{u:?}"
    );
    assert!((at_least(others)..=others).contains(&u.odom), "{u:?}");
    assert!((at_least(others)..=others).contains(&u.tf), "{u:?}");
    assert_eq!(u.tf_static + u.close_day + u.clock, 0, "{u:?}");
    assert!(stats.unconvertible <= unconvertible.len() && stats.unconvertible >= 1);
    let mut dropped = *offline.dropped();
    dropped.missing_tf += 1;
    assert_eq!(*node.session().dropped(), dropped);
    assert_eq!(got.len(), want.len(), "people messages received");
    for (k, (m, w)) in got.iter().zip(&want).enumerate() {
        assert_eq!(people_of(m), people_of_scan(w), "scan {k}");
    }
}
