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
use haunts::live::replay::Replay;
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

/// The node's parameters for `replay`'s recording: its topics and frames, arrival times from
/// `/clock` (as the offline replay takes the log times), `haunts replay`'s window.
fn node_params(replay: &Replay) -> NodeParams {
    let topics = replay.topics();
    let tf = topics.tf.first().map_or("/tf", String::as_str);
    NodeParams::default()
        .with_live(replay.params(LiveParams::default().with_window(0.5)))
        .with_inputs(
            &topics.scan,
            topics.odom.as_deref().unwrap(),
            tf,
            "/tf_static",
        )
        .with_sim_time(true)
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

/// The people of a MarkerArray the node published: (track id, position), from its spheres.
fn people_of(markers: &MarkerArray) -> Vec<(u64, [f64; 2])> {
    markers
        .markers
        .iter()
        .filter(|m| m.type_ == Marker::SPHERE)
        .map(|m| (m.id as u64, [m.pose.position.x, m.pose.position.y]))
        .collect()
}

/// (a) moving_1's MCAP published over DDS at 4× its pace with `/clock`; the node (sim time)
/// tracks it; a subscriber records the people. Every tracked scan's people arrive, equal to
/// the offline replay's (`haunts replay`: same ids, same positions), and the CLEAR MOT of the
/// people received is the offline one's exactly.
#[test]
fn replay_over_dds_tracks_as_offline() {
    if !netns::enter("replay_over_dds_tracks_as_offline") {
        return;
    }
    let Some(mcap) = moving_mcap() else {
        eprintln!("skipped: ../shared/data is absent");
        return;
    };
    // Offline, as `haunts replay` runs it.
    let replay = Replay::new(Bag::open(&mcap).unwrap(), &RecordingOptions::new(), None).unwrap();
    // The node's own parameters.
    let mut offline = LiveSession::with_defaults(node_params(&replay).live).unwrap();
    let mut want: Vec<ScanPeople> = Vec::new();
    let replayed = replay
        .run(&mut offline, |s| {
            want.push(s.clone());
            Ok(())
        })
        .unwrap();
    let protocol =
        EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()));
    let (offline_every, offline_annotated) = replayed.scores(&protocol).unwrap().unwrap();

    // The recorder first, so it is matched when the node publishes.
    let (_recorder_context, mut recorder) = test_node("recorder");
    let markers = subscription::<MarkerArray>(
        &mut recorder,
        "/haunts/people_markers",
        MarkerArray::ROS2_TYPE,
        wire::stream_qos(5000),
    );
    let stop = Arc::new(AtomicBool::new(false));
    let node = spawn_node(node_params(&replay), stop.clone());
    let published = publish(&mcap, 4.0);
    assert_eq!(published.undecodable, 0);
    assert_eq!(published.publish_failures, 0);

    let mut got = Vec::new();
    // All but the scans still waiting at the end of the stream, before the node is stopped.
    collect(
        &markers,
        &mut got,
        want.len().saturating_sub(5),
        Duration::from_secs(5),
    );
    stop.store(true, Ordering::Relaxed);
    let mut node = node.join().unwrap();
    node.flush();
    collect(&markers, &mut got, want.len(), Duration::from_secs(5));
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
        let expected: Vec<(u64, [f64; 2])> = w
            .people
            .iter()
            .map(|p| (p.id, [p.position.x, p.position.y]))
            .collect();
        assert_eq!(people, expected, "scan {k}");
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
    let topic = node
        .create_topic(
            &wire::topic_name(name).unwrap(),
            wire::type_name(ros2).unwrap(),
            &qos,
        )
        .unwrap();
    node.create_subscription(&topic, Some(qos)).unwrap()
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
    if !netns::enter("closed_day_is_served_as_haunts_maps_saves_it") {
        return;
    }
    let Some(mcap) = moving_mcap() else {
        eprintln!("skipped: ../shared/data is absent");
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
    let close_topic = test_node
        .create_topic(
            &wire::topic_name("/haunts/close_day").unwrap(),
            wire::type_name(wire::Empty::ROS2_TYPE).unwrap(),
            &wire::stream_qos(10),
        )
        .unwrap();
    let close = test_node
        .create_publisher::<wire::Empty>(&close_topic, Some(wire::stream_qos(10)))
        .unwrap();
    let waited = Instant::now();
    while close.get_subscription_count(&test_node) == 0
        && waited.elapsed() < Duration::from_secs(20)
    {
        std::thread::sleep(Duration::from_millis(20));
    }
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
