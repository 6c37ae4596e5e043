//! The node's per-scan latency over DDS (issue 52): moving_1's MCAP published message by
//! message onto its topics (with `/clock`) inside a network namespace of the bench's own
//! (only `lo`; see `haunts_test_support::netns`), the node taking each one. The time of a
//! tracked scan runs from the publish of the message that let it be tracked (`/clock` before
//! it included) to the node having published its people (`PoseArray` and `MarkerArray`):
//! DDS over loopback, the take, the session and the two publishes.
//!
//! Criterion's figure is that time per tracked scan; the median, 99th percentile and maximum
//! over the recording's 873 scans (three passes, each a fresh node) are printed after it,
//! with the node's own histogram of the same (from the publisher's source timestamp).
//! Publisher and node share the bench's thread, so nothing but DDS runs between the two.

use std::time::{Duration, Instant};

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use haunts::bag::{Bag, RawMessage, RecordingOptions};
use haunts::live::LiveParams;
use haunts::live::replay::Replay;
use haunts_ros2::node::{HauntsNode, NodeParams};
use haunts_ros2::publish::{DdsReplay, Published};
use haunts_ros2::ros2_client::dds::Context;

/// The longest a published message may take to reach the node before it is given up
/// (a best-effort sample lost: never seen on `lo` once matched).
const PATIENCE: Duration = Duration::from_millis(200);

/// A node tracking the recording as `replay`'s messages are published to it one at a time.
struct Bench {
    params: NodeParams,
    dds: DdsReplay,
    /// `None` between a node dropped and the next made.
    node: Option<HauntsNode>,
    /// The node's DDS participant (one of its own: RustDDS does not match a participant's
    /// writers with its own readers), dropped after it.
    node_context: Option<Context>,
    /// The replay's participant, kept while its publishers are (dropped after them).
    _replay_context: Context,
    messages: std::vec::IntoIter<RawMessage>,
    all: Vec<RawMessage>,
    last_clock: f64,
    published: Published,
}

impl Bench {
    fn new(mcap: &std::path::Path) -> Self {
        let open = || Bag::open(mcap).expect("the recording opens");
        let replay = Replay::new(open(), &RecordingOptions::new(), None).expect("a replay");
        let params = NodeParams::for_recording(&replay, LiveParams::default().with_window(0.5));
        let context = Context::new().expect("a DDS context");
        let dds = DdsReplay::new(&context, open(), &RecordingOptions::new()).expect("publishers");

        let all: Vec<RawMessage> = dds
            .messages()
            .expect("messages")
            .collect::<Result<_, _>>()
            .expect("every message reads");
        let node_context = Context::new().expect("a DDS context");
        let node = Some(Self::node(&node_context, &params, &dds));
        Self {
            messages: all.clone().into_iter(),
            all,
            params,
            dds,
            node,
            node_context: Some(node_context),
            _replay_context: context,
            last_clock: f64::NEG_INFINITY,
            published: Published::default(),
        }
    }

    /// A fresh node, once the publishers matched its readers.
    fn node(context: &Context, params: &NodeParams, dds: &DdsReplay) -> HauntsNode {
        let node = HauntsNode::new(context, params.clone()).expect("the node");
        let waited = Instant::now();
        while !dds.matched() && waited.elapsed() < Duration::from_secs(20) {
            std::thread::sleep(Duration::from_millis(20));
        }
        assert!(dds.matched(), "the node's readers did not match");
        // Their side of discovery (and the latched tf_static) too.
        std::thread::sleep(Duration::from_secs(1));
        node
    }

    /// Starts the recording again with a fresh node (its session starts anew).
    fn restart(&mut self) {
        // The old node's readers gone first, so that the publishers' match is the new one's.
        self.node = None;
        self.node_context = None;
        std::thread::sleep(Duration::from_millis(500));
        let context = Context::new().expect("a DDS context");
        self.node = Some(Self::node(&context, &self.params, &self.dds));
        self.node_context = Some(context);
        self.messages = self.all.clone().into_iter();
        self.last_clock = f64::NEG_INFINITY;
    }

    /// Publishes messages until one lets the node track a scan: the time from that message's
    /// publish to the node's people published; `None` when the recording ended first.
    fn next_scan(&mut self) -> Option<Duration> {
        let node = self.node.as_mut()?;
        for m in self.messages.by_ref() {
            let before = (self.published, node.stats().clone());
            let start = Instant::now();
            self.dds
                .publish(&m, Some(&mut self.last_clock), &mut self.published);
            let sent = (self.published.messages + self.published.clock_messages)
                - (before.0.messages + before.0.clock_messages);
            while node.stats().messages < before.1.messages + sent && start.elapsed() < PATIENCE {
                node.spin_once(PATIENCE).expect("the node's poll works");
            }
            if node.stats().people_messages > before.1.people_messages {
                return Some(start.elapsed());
            }
        }
        None
    }

    /// [`Bench::next_scan`], the recording started again whenever it ends.
    fn next_scan_looped(&mut self) -> Duration {
        loop {
            if let Some(d) = self.next_scan() {
                return d;
            }
            self.restart();
        }
    }
}

fn node(c: &mut Criterion) {
    if !haunts_test_support::netns::enter_bench("the node's DDS bench") {
        return;
    }
    let Some(mcap) = haunts_test_support::bag::moving_mcap() else {
        eprintln!("skipped: ../shared/data is absent");
        return;
    };
    let mut bench = Bench::new(&mcap);
    let mut group = c.benchmark_group("node");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    group.bench_function("moving_1_per_scan_over_dds", |b| {
        b.iter_custom(|iters| (0..iters).map(|_| bench.next_scan_looped()).sum());
    });
    group.finish();

    // The distribution over whole passes, each with a fresh node.
    let mut ms = Vec::new();
    let mut own = Vec::new();
    for _ in 0..3 {
        bench.restart();
        while let Some(d) = bench.next_scan() {
            ms.push(d.as_secs_f64() * 1e3);
        }
        if let Some(node) = &bench.node {
            own.push(node.stats().end_to_end.summary());
        }
    }
    ms.sort_by(f64::total_cmp);
    let rank = |q: f64| ms[((q * ms.len() as f64).ceil() as usize).clamp(1, ms.len()) - 1];
    eprintln!(
        "per-scan latency over DDS, {} scans in 3 passes: p50 {:.3} ms, p99 {:.3} ms, max \
         {:.3} ms; the node's own end-to-end histograms (source timestamp to people \
         published): {}",
        ms.len(),
        rank(0.5),
        rank(0.99),
        ms.last().copied().unwrap_or(f64::NAN),
        serde_json::Value::from(own)
    );
}

criterion_group!(benches, node);
criterion_main!(benches);
