//! The node: a [`LiveSession`] fed from DDS, its people published after every tracked scan,
//! the library's maps served, the day closed and merged on request.
//!
//! # Order and time
//! Each [`HauntsNode::spin_once`] takes every message waiting on the four inputs (and
//! `/clock` with [`NodeParams::use_sim_time`]), orders them by their publishers' source
//! timestamps (the order they were sent in, across topics: DDS keeps the order within a
//! topic only) and pushes them into the session in that order. A message's arrival time is
//! the wall clock when it was taken (UNIX seconds), or with `use_sim_time` the latest
//! `/clock` before it (0 before the first), as a ROS node with `use_sim_time` reads its
//! clock: a replay that publishes `/clock` then gives the session the arrival times `haunts
//! replay` gives it offline, and the people are the same.
//!
//! # Bad input
//! A message that does not deserialize is counted by topic ([`NodeStats::undecodable`]) and
//! skipped; one that deserializes but is not a scan (a bad description) is counted in
//! [`NodeStats::unconvertible`]; everything else the session checks and counts itself
//! ([`LiveSession::dropped`]). Nothing on the wire ends the node.

use std::path::PathBuf;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use haunts::affordance::LayoutId;
use haunts::affordance::LayoutLibrary;
use haunts::bag::msg::Message as _;
use haunts::bag::msg::{LaserScan, MarkerArray, OccupancyGrid, Odometry, PoseArray, TfMessage};
use haunts::live::day::ClosedDay;
use haunts::live::replay::Replay;
use haunts::live::{LiveParams, LiveSession, ScanPeople, messages};
use haunts::pipeline::serve::{ServeParams, serve_layout};
use ros2_client::dds::rustdds::mio1::{Events, Interest, Poll, Token};
use ros2_client::dds::{Context, Node, Publisher, Subscription};
use ros2_client::{MessageInfo, NodeName, NodeOptions, QosProfile};
use serde::de::DeserializeOwned;

use crate::maps::{LayoutMessages, MapParams, layout_messages};
use crate::wire::{self, Clock, CostmapFilterInfo, Empty};
use crate::{Error, Result};

/// The node's parameters.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct NodeParams {
    /// The node's name (default `haunts`) and namespace (default `/`).
    pub name: String,
    /// See [`NodeParams::name`].
    pub namespace: String,
    /// The input topics: scans, odometry, tf and tf_static (defaults `/scan`, `/odom`, `/tf`,
    /// `/tf_static`).
    pub scan_topic: String,
    /// See [`NodeParams::scan_topic`].
    pub odom_topic: String,
    /// See [`NodeParams::scan_topic`].
    pub tf_topic: String,
    /// See [`NodeParams::scan_topic`].
    pub tf_static_topic: String,
    /// The people after each tracked scan: `geometry_msgs/PoseArray` (default
    /// `/haunts/people`) and `visualization_msgs/MarkerArray` (default
    /// `/haunts/people_markers`), in the session's fixed frame.
    pub people_topic: String,
    /// See [`NodeParams::people_topic`].
    pub markers_topic: String,
    /// The served layout's composite (default `/haunts/map`), costmap (default
    /// `/haunts/costmap`) and speed filter info (default `/haunts/costmap_filter_info`; the
    /// mask's topic is [`MapParams::mask_topic`]), all transient local.
    pub map_topic: String,
    /// See [`NodeParams::map_topic`].
    pub costmap_topic: String,
    /// See [`NodeParams::map_topic`].
    pub filter_info_topic: String,
    /// A `std_msgs/Empty` here closes the day (default `/haunts/close_day`).
    pub close_day_topic: String,
    /// Arrival times from `/clock` instead of the wall clock, 0 before the first (default
    /// false).
    pub use_sim_time: bool,
    /// Read the scan, odometry, tf and clock topics reliably (default false: best effort,
    /// as stock drivers publish sensor data and as every writer matches). A reliable reader
    /// matches only reliable writers, such as a replay's (`haunts replay --dds`), which
    /// then resend what a loaded machine dropped: for scoring a recording over DDS, not for a
    /// robot's drivers.
    pub reliable_inputs: bool,
    /// Messages each input keeps waiting (default 100: a few seconds of a laser at 40 Hz).
    pub depth: usize,
    /// The session's parameters (frames, window).
    pub live: LiveParams,
    /// The layout library the day is merged into and whose maps are served.
    pub library: Option<PathBuf>,
    /// The day's spool (needed to close a day; default: none).
    pub spool: Option<PathBuf>,
    /// The layout served (default: the layout the last closed day joined; at start the one
    /// with the most days).
    pub layout: Option<usize>,
    /// How the maps are served.
    pub maps: MapParams,
    /// How long a close waits for another merge into the library (default 60 s).
    pub merge_wait: Duration,
    /// Close the day when the arrival time passes this hour of the UTC day (0 to 24; default
    /// none).
    pub close_at_hour: Option<f64>,
}

impl Default for NodeParams {
    fn default() -> Self {
        Self {
            name: "haunts".into(),
            namespace: "/".into(),
            scan_topic: "/scan".into(),
            odom_topic: "/odom".into(),
            tf_topic: "/tf".into(),
            tf_static_topic: "/tf_static".into(),
            people_topic: "/haunts/people".into(),
            markers_topic: "/haunts/people_markers".into(),
            map_topic: "/haunts/map".into(),
            costmap_topic: "/haunts/costmap".into(),
            filter_info_topic: "/haunts/costmap_filter_info".into(),
            close_day_topic: "/haunts/close_day".into(),
            use_sim_time: false,
            reliable_inputs: false,
            depth: 100,
            live: LiveParams::default(),
            library: None,
            spool: None,
            layout: None,
            maps: MapParams::default(),
            merge_wait: Duration::from_secs(60),
            close_at_hour: None,
        }
    }
}

impl NodeParams {
    /// Sets the session's parameters.
    pub fn with_live(mut self, live: LiveParams) -> Self {
        self.live = live;
        self
    }

    /// Sets the input topics (scan, odometry, tf, tf_static).
    pub fn with_inputs(mut self, scan: &str, odom: &str, tf: &str, tf_static: &str) -> Self {
        (self.scan_topic, self.odom_topic) = (scan.into(), odom.into());
        (self.tf_topic, self.tf_static_topic) = (tf.into(), tf_static.into());
        self
    }

    /// The node for `replay`'s recording published over DDS ([`DdsReplay`](crate::publish::DdsReplay),
    /// `haunts replay REC --dds`): its scan, odometry and first tf topic, the session's
    /// `live` parameters with the recording's frames ([`Replay::params`]), and arrival
    /// times from the replay's `/clock`, so that the node tracks as `haunts replay` does
    /// offline.
    pub fn for_recording(replay: &Replay, live: LiveParams) -> Self {
        let topics = replay.topics();
        let defaults = Self::default();
        let odom = topics.odom.as_deref().unwrap_or(&defaults.odom_topic);
        let tf = topics.tf.first().unwrap_or(&defaults.tf_topic);
        let tf_static = defaults.tf_static_topic.clone();
        Self::default()
            .with_live(replay.params(live))
            .with_inputs(&topics.scan, odom, tf, &tf_static)
            .with_sim_time(true)
    }

    /// Sets [`NodeParams::reliable_inputs`].
    pub fn with_reliable_inputs(mut self, reliable: bool) -> Self {
        self.reliable_inputs = reliable;
        self
    }

    /// Sets [`NodeParams::use_sim_time`].
    pub fn with_sim_time(mut self, sim: bool) -> Self {
        self.use_sim_time = sim;
        self
    }

    /// The library the day is merged into and served from, and the day's spool.
    pub fn with_library(mut self, library: impl Into<PathBuf>, spool: impl Into<PathBuf>) -> Self {
        self.library = Some(library.into());
        self.spool = Some(spool.into());
        self
    }

    /// Sets [`NodeParams::layout`].
    pub fn with_layout(mut self, layout: Option<usize>) -> Self {
        self.layout = layout;
        self
    }

    /// Sets [`NodeParams::close_at_hour`].
    pub fn with_close_at_hour(mut self, hour: Option<f64>) -> Self {
        self.close_at_hour = hour;
        self
    }

    /// Sets [`NodeParams::maps`].
    pub fn with_maps(mut self, maps: MapParams) -> Self {
        self.maps = maps;
        self
    }

    fn check(self) -> Result<Self> {
        let live = self.live.clone().check()?;
        let maps = self.maps.clone().check()?;
        if self.depth == 0 {
            return Err(Error::Invalid("depth must be at least 1".into()));
        }
        if let Some(h) = self.close_at_hour
            && !(0.0..24.0).contains(&h)
        {
            return Err(Error::Invalid(format!(
                "close_at_hour {h} must be in [0, 24)"
            )));
        }
        Ok(Self { live, maps, ..self })
    }
}

/// Messages that did not deserialize, by input.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct PerInput {
    /// On the scan topic.
    pub scan: usize,
    /// On the odometry topic.
    pub odom: usize,
    /// On `/tf`.
    pub tf: usize,
    /// On `/tf_static`.
    pub tf_static: usize,
    /// On `/clock`.
    pub clock: usize,
    /// On the close-day topic.
    pub close_day: usize,
}

impl PerInput {
    /// All of them.
    pub fn total(&self) -> usize {
        self.scan + self.odom + self.tf + self.tf_static + self.clock + self.close_day
    }
}

/// Latencies in a fixed histogram of 10 µs bins up to 1 s (and beyond, one bin): memory stays
/// flat however long the node runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Latencies {
    bins: Vec<u64>,
    count: u64,
    max_us: u64,
}

impl Default for Latencies {
    fn default() -> Self {
        Self {
            bins: vec![0; Self::BINS + 1],
            count: 0,
            max_us: 0,
        }
    }
}

impl Latencies {
    const BIN_US: u64 = 10;
    const BINS: usize = 100_000;

    /// Adds one latency.
    pub fn add(&mut self, d: Duration) {
        let us = u64::try_from(d.as_micros()).unwrap_or(u64::MAX);
        let bin = usize::try_from(us / Self::BIN_US).map_or(Self::BINS, |b| b.min(Self::BINS));
        self.bins[bin] += 1;
        self.count += 1;
        self.max_us = self.max_us.max(us);
    }

    /// How many were added.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The `q` quantile (nearest rank), milliseconds, to the bin's upper edge (10 µs): `None`
    /// when empty.
    pub fn quantile_ms(&self, q: f64) -> Option<f64> {
        if self.count == 0 {
            return None;
        }
        let rank = ((q.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= rank {
                let edge = (i as u64 + 1) * Self::BIN_US;
                return Some(edge.min(self.max_us.max(1)) as f64 / 1000.0);
            }
        }
        Some(self.max_us as f64 / 1000.0)
    }

    /// The maximum, milliseconds.
    pub fn max_ms(&self) -> f64 {
        self.max_us as f64 / 1000.0
    }

    /// Median, 99th percentile and maximum, milliseconds, as JSON.
    pub fn summary(&self) -> serde_json::Value {
        serde_json::json!({
            "count": self.count,
            "p50": self.quantile_ms(0.5),
            "p99": self.quantile_ms(0.99),
            "max": self.max_ms(),
        })
    }
}

/// What the node has done.
#[derive(Debug, Clone, Default)]
pub struct NodeStats {
    /// Messages taken from the wire (all inputs).
    pub messages: usize,
    /// Messages that did not deserialize.
    pub undecodable: PerInput,
    /// Scans that deserialized but do not describe a scan.
    pub unconvertible: usize,
    /// People messages published (a `PoseArray` and a `MarkerArray` each).
    pub people_messages: usize,
    /// Messages the middleware refused to publish.
    pub publish_failures: usize,
    /// Days closed, and those whose close failed.
    pub days_closed: usize,
    /// See [`NodeStats::days_closed`].
    pub close_failures: usize,
    /// Per tracked scan: from the message that let it be tracked being taken to its people
    /// published.
    pub processing: Latencies,
    /// Per tracked scan: from that message's publisher sending it (its source timestamp) to
    /// the people published: the latency over DDS.
    pub end_to_end: Latencies,
    /// The spool of a day that a node before this one left unclosed (killed), found at
    /// [`NodeParams::spool`] at the start and moved here (`NAME.unclosed-SECONDS.mcap`, the
    /// file's modification time), for `haunts day` and `haunts merge` to fold in by hand.
    pub unclosed_spool: Option<PathBuf>,
}

/// One message taken, before it is pushed.
enum Incoming {
    Scan(LaserScan),
    Odom(Box<Odometry>),
    Tf(TfMessage, bool),
    Clock(Clock),
    CloseDay,
}

struct Inputs {
    scan: Subscription<LaserScan>,
    odom: Subscription<Odometry>,
    tf: Subscription<TfMessage>,
    tf_static: Subscription<TfMessage>,
    clock: Option<Subscription<Clock>>,
    close_day: Subscription<Empty>,
}

struct Outputs {
    people: Publisher<PoseArray>,
    markers: Publisher<MarkerArray>,
    map: Publisher<OccupancyGrid>,
    costmap: Publisher<OccupancyGrid>,
    mask: Publisher<OccupancyGrid>,
    filter_info: Publisher<CostmapFilterInfo>,
}

/// The haunts node (see the [module docs](self)).
pub struct HauntsNode {
    session: LiveSession,
    params: NodeParams,
    inputs: Inputs,
    outputs: Outputs,
    poll: Poll,
    events: Events,
    stats: NodeStats,
    /// The latest `/clock`, seconds.
    clock: Option<f64>,
    /// The UTC day (counted from the close hour) of the latest arrival.
    day: Option<i64>,
    close_requested: bool,
    served: Option<(LayoutId, LayoutMessages)>,
    last_close: Option<std::result::Result<ClosedDay, String>>,
    /// Kept last: the ROS node its readers and writers belong to.
    node: Node,
}

impl std::fmt::Debug for HauntsNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HauntsNode")
            .field("params", &self.params)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// A topic of messages of ROS 2 type `ros2` named `name`, read or written by `node`.
fn topic(
    node: &Node,
    name: &str,
    ros2: &str,
    qos: &QosProfile,
) -> Result<ros2_client::dds::rustdds::Topic> {
    let type_name =
        wire::type_name(ros2).ok_or_else(|| Error::Invalid(format!("type name {ros2:?}")))?;
    node.create_topic(
        &wire::topic_name(name).map_err(Error::Invalid)?,
        type_name,
        qos,
    )
    .map_err(Error::dds)
}

/// A subscription to `name`.
pub(crate) fn subscribe<M: DeserializeOwned + 'static>(
    node: &mut Node,
    name: &str,
    ros2: &str,
    qos: QosProfile,
) -> Result<Subscription<M>> {
    let t = topic(node, name, ros2, &qos)?;
    node.create_subscription(&t, Some(qos)).map_err(Error::dds)
}

/// A publisher on `name`.
pub(crate) fn advertise<M: serde::Serialize>(
    node: &mut Node,
    name: &str,
    ros2: &str,
    qos: QosProfile,
) -> Result<Publisher<M>> {
    let t = topic(node, name, ros2, &qos)?;
    node.create_publisher(&t, Some(qos)).map_err(Error::dds)
}

/// A ROS node named `name` in `namespace`, with its discovery task running on a thread of
/// its own (it ends when the node is dropped).
pub(crate) fn ros_node(context: &Context, namespace: &str, name: &str) -> Result<Node> {
    let node_name = NodeName::new(namespace, name)
        .map_err(|e| Error::Invalid(format!("node name {namespace}{name}: {e:?}")))?;
    let mut node = context
        .new_node(node_name, NodeOptions::new().enable_rosout(false))
        .map_err(|e| Error::Dds(format!("{e:?}")))?;
    let spinner = node.spinner().map_err(Error::dds)?;
    std::thread::Builder::new()
        .name("haunts-ros2-spin".into())
        .spawn(move || futures::executor::block_on(spinner.spin()))?;
    Ok(node)
}

/// The wall clock, UNIX seconds.
fn wall_clock() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// The wall clock, UNIX nanoseconds (as DDS source timestamps count).
fn wall_nanos() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

impl HauntsNode {
    /// The node on `context`: its inputs subscribed, its outputs advertised, the library's
    /// layout served when there is a library (see [`NodeParams::layout`]).
    ///
    /// # Errors
    /// Parameters that do not check; the middleware's errors; the library's and the spool's.
    pub fn new(context: &Context, params: NodeParams) -> Result<Self> {
        let params = params.check()?;
        let mut session = LiveSession::with_defaults(params.live.clone())?;
        let mut unclosed_spool = None;
        if let Some(spool) = &params.spool {
            unclosed_spool = set_aside_unclosed(spool)?;
            session = session.with_spool(spool)?;
        }
        let mut node = ros_node(context, &params.namespace, &params.name)?;
        let sensor = if params.reliable_inputs {
            wire::stream_qos(params.depth)
        } else {
            wire::sensor_qos(params.depth)
        };
        let n = &mut node;
        let inputs = Inputs {
            scan: subscribe(n, &params.scan_topic, LaserScan::ROS2_TYPE, sensor.clone())?,
            odom: subscribe(n, &params.odom_topic, Odometry::ROS2_TYPE, sensor.clone())?,
            tf: subscribe(n, &params.tf_topic, TfMessage::ROS2_TYPE, sensor.clone())?,
            tf_static: subscribe(
                n,
                &params.tf_static_topic,
                TfMessage::ROS2_TYPE,
                wire::latched_qos().history(ros2_client::qos::History::KeepLast {
                    depth: params.depth,
                }),
            )?,
            clock: if params.use_sim_time {
                Some(subscribe(n, "/clock", Clock::ROS2_TYPE, sensor.clone())?)
            } else {
                None
            },
            close_day: subscribe(
                n,
                &params.close_day_topic,
                Empty::ROS2_TYPE,
                wire::stream_qos(10),
            )?,
        };
        let stream = wire::stream_qos(10);
        let latched = wire::latched_qos();
        let outputs = Outputs {
            people: advertise(
                n,
                &params.people_topic,
                PoseArray::ROS2_TYPE,
                stream.clone(),
            )?,
            markers: advertise(n, &params.markers_topic, MarkerArray::ROS2_TYPE, stream)?,
            map: advertise(
                n,
                &params.map_topic,
                OccupancyGrid::ROS2_TYPE,
                latched.clone(),
            )?,
            costmap: advertise(
                n,
                &params.costmap_topic,
                OccupancyGrid::ROS2_TYPE,
                latched.clone(),
            )?,
            mask: advertise(
                n,
                &params.maps.mask_topic,
                OccupancyGrid::ROS2_TYPE,
                latched.clone(),
            )?,
            filter_info: advertise(
                n,
                &params.filter_info_topic,
                CostmapFilterInfo::ROS2_TYPE,
                latched,
            )?,
        };
        let poll = Poll::new()?;
        let mut node = Self {
            session,
            params,
            inputs,
            outputs,
            poll,
            events: Events::with_capacity(64),
            stats: NodeStats {
                unclosed_spool,
                ..NodeStats::default()
            },
            clock: None,
            day: None,
            close_requested: false,
            served: None,
            last_close: None,
            node,
        };
        node.register()?;
        node.serve_library()?;
        Ok(node)
    }

    fn register(&mut self) -> Result<()> {
        let registry = self.poll.registry();
        let i = &mut self.inputs;
        registry.register(&mut i.scan, Token(0), Interest::READABLE)?;
        registry.register(&mut i.odom, Token(1), Interest::READABLE)?;
        registry.register(&mut i.tf, Token(2), Interest::READABLE)?;
        registry.register(&mut i.tf_static, Token(3), Interest::READABLE)?;
        registry.register(&mut i.close_day, Token(4), Interest::READABLE)?;
        if let Some(clock) = &mut i.clock {
            registry.register(clock, Token(5), Interest::READABLE)?;
        }
        Ok(())
    }

    /// The session.
    pub fn session(&self) -> &LiveSession {
        &self.session
    }

    /// What the node has done.
    pub fn stats(&self) -> &NodeStats {
        &self.stats
    }

    /// The parameters.
    pub fn params(&self) -> &NodeParams {
        &self.params
    }

    /// The ROS node (to wait for matches, say).
    pub fn ros_node(&self) -> &Node {
        &self.node
    }

    /// The layout served and its messages, when one is.
    pub fn served(&self) -> Option<&(LayoutId, LayoutMessages)> {
        self.served.as_ref()
    }

    /// The outcome of the last close (a close from a request or the hour is not returned to
    /// anyone: it is kept here), taken.
    pub fn take_last_close(&mut self) -> Option<std::result::Result<ClosedDay, String>> {
        self.last_close.take()
    }

    /// Serves the library's layout, when there is a library file.
    fn serve_library(&mut self) -> Result<()> {
        let Some(path) = self.params.library.as_ref().filter(|p| p.exists()) else {
            return Ok(());
        };
        let library = LayoutLibrary::load(path).map_err(haunts::pipeline::PipelineError::from)?;
        let chosen = match self.params.layout {
            Some(id) => library.layouts().iter().find(|l| l.id().0 == id),
            None => library.layouts().iter().max_by_key(|l| l.days().len()),
        };
        if let Some(layout) = chosen {
            let served = serve_layout(layout, &ServeParams::default())?;
            self.publish_maps(layout.id(), &served);
        }
        Ok(())
    }

    fn publish_maps(&mut self, id: LayoutId, served: &haunts::pipeline::serve::ServedLayout) {
        let stamp = self.now();
        let m = layout_messages(served, &self.params.maps, stamp);
        let o = &self.outputs;
        let failures = [
            o.map.publish(m.map.clone()).is_err(),
            o.costmap.publish(m.costmap.clone()).is_err(),
            o.mask.publish(m.speed_mask.clone()).is_err(),
            o.filter_info.publish(m.filter_info.clone()).is_err(),
        ];
        self.stats.publish_failures += failures.iter().filter(|f| **f).count();
        self.served = Some((id, m));
    }

    /// The node's time now, a message's arrival time: the wall clock, or with sim time the latest `/clock`, and 0 before
    /// the first (as a ROS node's time is zero until `/clock` comes): a message before the
    /// replay's clock then waits for nothing, where a wall-clock arrival decades after the
    /// log's would hold it past every later scan.
    fn now(&self) -> f64 {
        match (self.params.use_sim_time, self.clock) {
            (true, Some(c)) => c,
            (true, None) => 0.0,
            (false, _) => wall_clock(),
        }
    }

    /// Waits up to `timeout` for messages, and handles every message waiting: the number
    /// handled.
    ///
    /// # Errors
    /// The poll failed (the operating system's error; a signal that interrupts the wait is
    /// not an error).
    pub fn spin_once(&mut self, timeout: Duration) -> Result<usize> {
        match self.poll.poll(&mut self.events, Some(timeout)) {
            Ok(()) => {}
            // A signal woke the wait (the owner's SIGTERM, whose flag it looks at next): take
            // what is waiting, as after a timeout.
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
        // Edge-triggered: whatever fired, every reader is drained.
        let taken_at = Instant::now();
        let mut batch: Vec<(Option<i64>, Incoming)> = Vec::new();
        let u = &mut self.stats.undecodable;
        let i = &self.inputs;
        take_all(&i.scan, &mut batch, &mut u.scan, Incoming::Scan);
        take_all(&i.odom, &mut batch, &mut u.odom, |m| {
            Incoming::Odom(Box::new(m))
        });
        take_all(&i.tf, &mut batch, &mut u.tf, |m| Incoming::Tf(m, false));
        take_all(&i.tf_static, &mut batch, &mut u.tf_static, |m| {
            Incoming::Tf(m, true)
        });
        take_all(&i.close_day, &mut batch, &mut u.close_day, |_| {
            Incoming::CloseDay
        });
        if let Some(clock) = &i.clock {
            take_all(clock, &mut batch, &mut u.clock, Incoming::Clock);
        }
        // By source timestamp; a stable sort keeps each topic's order among equal stamps.
        batch.sort_by_key(|(sent, _)| *sent);
        let handled = batch.len();
        self.stats.messages += handled;
        for (sent, message) in batch {
            self.handle(message, sent, taken_at);
        }
        if self.close_requested {
            self.close_requested = false;
            let closed = self.close_day().map_err(|e| e.to_string());
            self.last_close = Some(closed);
        }
        Ok(handled)
    }

    /// Spins until `stop` is set (a signal handler's flag, say), waking at least every
    /// `tick` to look at it.
    ///
    /// # Errors
    /// As [`HauntsNode::spin_once`].
    pub fn spin_until(
        &mut self,
        stop: &std::sync::atomic::AtomicBool,
        tick: Duration,
    ) -> Result<()> {
        while !stop.load(std::sync::atomic::Ordering::Relaxed) {
            self.spin_once(tick)?;
        }
        Ok(())
    }

    fn handle(&mut self, message: Incoming, sent: Option<i64>, taken_at: Instant) {
        if let Incoming::Clock(c) = &message {
            self.clock = Some(c.clock.seconds());
            return;
        }
        let received = self.now();
        self.watch_hour(received);
        let tracked = match message {
            Incoming::Scan(m) => match messages::scan(&m) {
                Ok((scan, frame)) => self.session.push_scan(received, &frame, scan),
                Err(_) => {
                    self.stats.unconvertible += 1;
                    return;
                }
            },
            Incoming::Odom(m) => {
                let (stamp, pose) = messages::odometry(&m);
                self.session.push_odom(received, stamp, &pose)
            }
            Incoming::Tf(m, is_static) => {
                let mut tracked = Vec::new();
                for t in messages::transforms(&m) {
                    let link = (t.parent.as_str(), t.child.as_str());
                    tracked.extend(
                        self.session
                            .push_tf(received, link, t.stamp, &t.pose, is_static),
                    );
                }
                tracked
            }
            Incoming::CloseDay => {
                self.close_requested = true;
                return;
            }
            Incoming::Clock(_) => return,
        };
        for scan in &tracked {
            self.publish_people(scan);
            self.stats.processing.add(taken_at.elapsed());
            if let Some(sent) = sent {
                let nanos = u64::try_from(wall_nanos().saturating_sub(sent)).unwrap_or(0);
                self.stats.end_to_end.add(Duration::from_nanos(nanos));
            }
        }
    }

    /// Requests a close when the arrival time enters a new day (counted from the close hour).
    fn watch_hour(&mut self, received: f64) {
        let Some(hour) = self.params.close_at_hour else {
            return;
        };
        let day = ((received - hour * 3600.0) / 86_400.0).floor() as i64;
        if self.day.is_some_and(|d| d != day) {
            self.close_requested = true;
        }
        self.day = Some(day);
    }

    fn publish_people(&mut self, scan: &ScanPeople) {
        let frame = if self.params.live.odometry {
            self.params.live.fixed_frame.clone()
        } else {
            scan.frame.clone()
        };
        let (poses, markers) = messages::people(scan, &frame);
        let failed = [
            self.outputs.people.publish(poses).is_err(),
            self.outputs.markers.publish(markers).is_err(),
        ];
        self.stats.publish_failures += failed.iter().filter(|f| **f).count();
        self.stats.people_messages += 1;
    }

    /// Tracks every waiting scan with what has arrived ([`LiveSession::finish`]) and
    /// publishes their people: the end of a stream (a replay that ended, say).
    pub fn flush(&mut self) {
        for scan in self.session.finish() {
            self.publish_people(&scan);
        }
    }

    /// Closes the day now: the waiting scans tracked ([`LiveSession::finish`]) and published,
    /// the spool processed and merged into the library ([`LiveSession::close_day`]), the
    /// served layout's maps published again (the layout the day joined, unless
    /// [`NodeParams::layout`] names one).
    ///
    /// # Errors
    /// No library configured; the close's errors (the day is then kept beside the spool, see
    /// [`LiveSession::close_day`]).
    pub fn close_day(&mut self) -> Result<ClosedDay> {
        self.flush();
        let Some(library) = self.params.library.clone() else {
            return Err(Error::Invalid("no library to close the day into".into()));
        };
        let closed = self.session.close_day(&library, self.params.merge_wait);
        let day = match closed {
            Ok(day) => day,
            Err(e) => {
                self.stats.close_failures += 1;
                return Err(e.into());
            }
        };
        self.stats.days_closed += 1;
        let want = self.params.layout.map(LayoutId).or(day.layout);
        if let Some((id, served)) = day.maps.iter().find(|(id, _)| Some(*id) == want) {
            let served = served.clone();
            self.publish_maps(*id, &served);
        }
        Ok(day)
    }
}

/// Moves a spool that holds a day aside (see [`NodeStats::unclosed_spool`]) before a new
/// day's spool truncates it: one with a message in it, or one that does not read as a
/// recording at all (a process killed mid-write leaves the last chunk unfinished). The empty
/// spool a clean close leaves is left to be truncated.
fn set_aside_unclosed(spool: &std::path::Path) -> Result<Option<PathBuf>> {
    let Ok(meta) = std::fs::metadata(spool) else {
        return Ok(None);
    };
    let holds_a_day = match haunts::bag::Bag::open(spool) {
        Ok(bag) => {
            let names: Vec<&str> = bag.topics().iter().map(|t| t.name.as_str()).collect();
            bag.messages(&names)
                .map_or(true, |mut messages| messages.next().is_some())
        }
        Err(_) => meta.len() > 0,
    };
    if !holds_a_day {
        return Ok(None);
    }
    let seconds = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_secs());
    let stem = spool
        .file_stem()
        .map_or_else(|| "spool".into(), |s| s.to_string_lossy());
    // Another killed in the same second keeps its own file.
    let mut aside = spool.with_file_name(format!("{stem}.unclosed-{seconds}.mcap"));
    for k in 1.. {
        if !aside.exists() {
            break;
        }
        aside = spool.with_file_name(format!("{stem}.unclosed-{seconds}-{k}.mcap"));
    }
    std::fs::rename(spool, &aside)?;
    Ok(Some(aside))
}

/// The most messages taken from one reader in one spin.
const MAX_TAKE: usize = 10_000;

/// Takes every message waiting on `sub` into `batch` (with its source timestamp, nanoseconds),
/// counting those that do not deserialize in `undecodable`. RustDDS moves past a sample that
/// fails to deserialize, so this ends.
fn take_all<M: DeserializeOwned + 'static>(
    sub: &Subscription<M>,
    batch: &mut Vec<(Option<i64>, Incoming)>,
    undecodable: &mut usize,
    wrap: impl Fn(M) -> Incoming,
) {
    // Bounded all the same: a reader that kept failing must not hold the node.
    for _ in 0..MAX_TAKE {
        match sub.take() {
            Ok(Some((m, info))) => batch.push((sent_nanos(&info), wrap(m))),
            Ok(None) => break,
            Err(_) => *undecodable += 1,
        }
    }
}

fn sent_nanos(info: &MessageInfo) -> Option<i64> {
    info.source_timestamp().map(|t| t.to_nanos())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::set_aside_unclosed;
    use haunts::bag::McapWriter;
    use haunts::bag::msg::Odometry;

    /// A spool with a message is moved aside, and so is one that does not read at all; the
    /// empty spool a clean close leaves, and no file, are left alone.
    #[test]
    fn only_a_spool_holding_a_day_is_set_aside() {
        let dir = tempfile::tempdir().unwrap();
        let spool = dir.path().join("site.day.mcap");
        assert_eq!(set_aside_unclosed(&spool).unwrap(), None);

        McapWriter::create(&spool).unwrap().finish().unwrap();
        assert_eq!(set_aside_unclosed(&spool).unwrap(), None);
        assert!(spool.exists());

        let mut writer = McapWriter::create(&spool).unwrap();
        writer.write("/odom", 5.0, &Odometry::default()).unwrap();
        writer.finish().unwrap();
        let aside = set_aside_unclosed(&spool).unwrap().unwrap();
        assert!(!spool.exists() && aside.exists());
        let name = aside.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            name.starts_with("site.day.unclosed-") && name.ends_with(".mcap"),
            "{name}"
        );

        std::fs::write(&spool, b"\x89MCAP0\r\n then the process was killed").unwrap();
        let torn = set_aside_unclosed(&spool).unwrap().unwrap();
        assert!(torn.exists() && !spool.exists() && torn != aside && aside.exists());
    }
}
