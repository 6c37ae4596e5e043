//! The commands on ROS 2 over DDS (`haunts-ros2`): `haunts node`, and `haunts replay --dds`.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use haunts::bag::{Bag, RecordingOptions};
use haunts::live::LiveParams;
use haunts_ros2::maps::MapParams;
use haunts_ros2::node::{HauntsNode, NodeParams};
use haunts_ros2::publish::{DdsReplay, ReplayParams};
use serde_json::{Value, json};

type Error = Box<dyn std::error::Error>;

/// `haunts node`.
#[derive(Debug, clap::Args)]
pub struct NodeArgs {
    /// The layout library: the layout served (`--layout`, else the one with the most days),
    /// and the library each day is merged into when it closes (created when absent).
    #[arg(long)]
    library: Option<PathBuf>,
    /// The day's spool, an MCAP of the messages the session accepted (default: beside the
    /// library, its name with `.day.mcap` for its extension). A day a killed node left in it
    /// is moved aside first (`NAME.unclosed-SECONDS.mcap`).
    #[arg(long, requires = "library")]
    spool: Option<PathBuf>,
    /// The layout served (default: the one the last closed day joined).
    #[arg(long)]
    layout: Option<usize>,
    /// The `LaserScan` topic.
    #[arg(long, default_value = "/scan")]
    scan_topic: String,
    /// The `Odometry` topic.
    #[arg(long, default_value = "/odom")]
    odom_topic: String,
    /// The robot's frame.
    #[arg(long, default_value = "base_link")]
    base_frame: String,
    /// The odometry's frame (the people's).
    #[arg(long, default_value = "odom")]
    fixed_frame: String,
    /// Seconds a scan waits for its odometry and transforms.
    #[arg(long, default_value_t = 0.5)]
    window: f64,
    /// Arrival times from `/clock` (a replay, a simulator).
    #[arg(long)]
    use_sim_time: bool,
    /// Read the inputs reliably: for a replay (`haunts replay --dds`), which then resends what
    /// a loaded machine drops; a best-effort driver does not match.
    #[arg(long)]
    reliable_inputs: bool,
    /// Close the day when the clock passes this hour of the UTC day (0 to 24).
    #[arg(long, value_name = "HOUR")]
    close_at: Option<f64>,
    /// The speed filter's limit at the busiest cells, percent of the maximum speed.
    #[arg(long, default_value_t = 30.0)]
    min_speed: f64,
    /// How long a close waits, in seconds, for another merge into the library.
    #[arg(long, default_value_t = 60.0, value_name = "SECONDS")]
    wait: f64,
    /// Stop after this many seconds (default: at SIGINT or SIGTERM).
    #[arg(long, value_name = "SECONDS")]
    duration: Option<f64>,
}

/// `haunts node`: the live session on ROS 2 (`haunts_ros2::node`) until SIGINT or SIGTERM
/// (or `--duration`); then, with a library, the day is closed and merged.
pub fn node(args: &NodeArgs) -> Result<Value, Error> {
    let seconds = |s: f64, what: &str| {
        if s.is_finite() && (0.0..=1e9).contains(&s) {
            Ok(Duration::from_secs_f64(s))
        } else {
            Err(format!("{what} must be 0 to 1e9 seconds, found {s}"))
        }
    };
    let wait = seconds(args.wait, "--wait")?;
    let duration = args
        .duration
        .map(|d| seconds(d, "--duration"))
        .transpose()?;
    let live = LiveParams::default()
        .with_base_frame(args.base_frame.clone())
        .with_fixed_frame(args.fixed_frame.clone())
        .with_window(args.window);
    let mut params = NodeParams::default()
        .with_live(live)
        .with_inputs(&args.scan_topic, &args.odom_topic, "/tf", "/tf_static")
        .with_sim_time(args.use_sim_time)
        .with_reliable_inputs(args.reliable_inputs)
        .with_layout(args.layout)
        .with_close_at_hour(args.close_at)
        .with_maps(MapParams::default().with_min_speed_percent(args.min_speed));
    params.merge_wait = wait;
    if let Some(library) = &args.library {
        let spool = args
            .spool
            .clone()
            .unwrap_or_else(|| library.with_extension("day.mcap"));
        params = params.with_library(library, spool);
    }
    let stop = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(signal, Arc::clone(&stop))?;
    }
    if let Some(d) = duration {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            std::thread::sleep(d);
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        });
    }
    let context = haunts_ros2::context_from_env()?;
    let mut node = HauntsNode::new(&context, params)?;
    eprintln!("note: haunts node running; SIGINT or SIGTERM ends the day");
    node.spin_until(&stop, Duration::from_millis(100))?;
    let closed = if args.library.is_some() {
        Some(match node.close_day() {
            Ok(day) => json!({
                "day": day.label,
                "messages": day.messages,
                "layout": day.layout.map(|l| l.0),
                "saved": day.merge.saved,
                "layouts": day.merge.library.layouts().len(),
            }),
            Err(e) => json!({"error": e.to_string()}),
        })
    } else {
        node.flush();
        None
    };
    let mut report = stats_json(&node);
    if let Some(closed) = closed {
        report["closed_day"] = closed;
    }
    if let Some(aside) = &node.stats().unclosed_spool {
        report["unclosed_spool"] = json!(aside.display().to_string());
    }
    Ok(report)
}

/// The node's counts and latencies.
fn stats_json(node: &HauntsNode) -> Value {
    let s = node.stats();
    json!({
        "messages": s.messages,
        "scans": node.session().scans(),
        "tracked_scans": node.session().tracked(),
        "people_messages": s.people_messages,
        "undecodable": s.undecodable,
        "unconvertible": s.unconvertible,
        "dropped": node.session().dropped(),
        "publish_failures": s.publish_failures,
        "days_closed": s.days_closed,
        "close_failures": s.close_failures,
        "layout_served": node.served().map(|(id, _)| id.0),
        "latency_ms": s.end_to_end.summary(),
        "processing_ms": s.processing.summary(),
    })
}

/// `haunts replay REC --dds`: the recording published onto its topics with `/clock`
/// (`haunts_ros2::publish`), at `rate` times its pace.
pub fn replay_dds(
    recording: &std::path::Path,
    options: &RecordingOptions,
    rate: f64,
    wait: f64,
) -> Result<Value, Error> {
    if !(wait.is_finite() && (0.0..=1e6).contains(&wait)) {
        return Err(format!("--subscriber-wait must be 0 to 1e6 seconds, found {wait}").into());
    }
    let context = haunts_ros2::context_from_env()?;
    let replay = DdsReplay::new(&context, Bag::open(recording)?, options)?;
    let params = ReplayParams::default()
        .with_rate(rate)
        .with_wait(Duration::from_secs_f64(wait));
    let published = replay.run(&params)?;
    let mut report = serde_json::to_value(published)?;
    report["recording"] = json!(recording.display().to_string());
    report["topics"] = json!({
        "scan": replay.topics().scan,
        "odom": replay.topics().odom,
        "tf": replay.topics().tf,
    });
    Ok(report)
}
