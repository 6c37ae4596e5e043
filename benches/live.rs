//! The live session on the shared `leg_tracker` recording (issue 47): the whole replay from
//! the MCAP file (reading, decoding and the session: its real-time factor), the session
//! alone on the recording's messages decoded beforehand, and the per-scan latency of the
//! session (median, 99th percentile and maximum over the recording's scans, printed).

mod common;

use std::hint::black_box;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts::bag::{Bag, RecordingOptions, convert, msg};
use haunts::live::replay::Replay;
use haunts::live::{LiveParams, LiveSession};
use haunts::occupancy::{LaserScan, Pose2};

/// One message of the recording, decoded.
enum Event {
    Scan(f64, String, LaserScan),
    Odom(f64, f64, Pose2),
    Tf(f64, String, String, f64, Pose2, bool),
}

/// The recording's scans, odometry and transforms in log-time order, decoded.
fn events(replay: &Replay) -> Vec<Event> {
    let bag = replay.bag();
    let topics = replay.topics();
    let mut names: Vec<&str> = vec![topics.scan.as_str()];
    names.extend(topics.odom.as_deref());
    names.extend(topics.tf.iter().map(String::as_str));
    let mut out = Vec::new();
    for m in bag.messages(&names).expect("messages") {
        let m = m.expect("message");
        let t = m.log_seconds();
        if *m.topic == *topics.scan {
            let s: msg::LaserScan = bag.decode(&m).expect("scan");
            let scan = convert::laser_scan(&s).expect("scan converts");
            out.push(Event::Scan(t, s.header.frame_id, scan));
        } else if topics.odom.as_deref() == Some(&*m.topic) {
            let o: msg::Odometry = bag.decode(&m).expect("odometry");
            let p = &o.pose.pose;
            let pose = convert::pose2(&p.position, &p.orientation).expect("pose");
            out.push(Event::Odom(t, o.header.stamp.seconds(), pose));
        } else {
            let tf: msg::TfMessage = bag.decode(&m).expect("tf");
            for x in tf.transforms {
                let pose = convert::pose2(&x.transform.translation, &x.transform.rotation)
                    .expect("transform");
                let stamp = x.header.stamp.seconds();
                let is_static = m.topic.ends_with("tf_static");
                out.push(Event::Tf(
                    t,
                    x.header.frame_id,
                    x.child_frame_id,
                    stamp,
                    pose,
                    is_static,
                ));
            }
        }
    }
    out
}

/// The events through a fresh session; each push that tracked scans, its seconds per scan.
fn run(replay: &Replay, events: &[Event]) -> Vec<f64> {
    let mut session =
        LiveSession::with_defaults(replay.params(LiveParams::default())).expect("session");
    let mut latency = Vec::with_capacity(1000);
    for e in events {
        let start = Instant::now();
        let tracked = match e {
            Event::Scan(t, frame, scan) => session.push_scan(*t, frame, scan.clone()),
            Event::Odom(t, stamp, pose) => session.push_odom(*t, *stamp, pose),
            Event::Tf(t, parent, child, stamp, pose, is_static) => {
                session.push_tf(*t, (parent, child), *stamp, pose, *is_static)
            }
        };
        let seconds = start.elapsed().as_secs_f64();
        latency.extend(tracked.iter().map(|_| seconds));
        black_box(tracked);
    }
    black_box(session.finish());
    latency
}

fn live(c: &mut Criterion) {
    let path = common::shared_data("leg_tracker/general_tracking_moving_1.mcap");
    let open = || {
        Replay::new(
            Bag::open(&path).expect("bag"),
            &RecordingOptions::new(),
            None,
        )
        .expect("replay")
    };
    let replay = open();
    let events = events(&replay);
    let span = {
        let mut session =
            LiveSession::with_defaults(replay.params(LiveParams::default())).expect("session");
        replay.run(&mut session, |_| Ok(())).expect("replay").span
    };
    let mut group = c.benchmark_group("live");
    group.sample_size(10);
    group.bench_function("replay_moving_1_mcap", |b| {
        b.iter(|| {
            let replay = open();
            let mut session =
                LiveSession::with_defaults(replay.params(LiveParams::default())).expect("session");
            black_box(replay.run(&mut session, |_| Ok(())).expect("replay"))
        });
    });
    group.bench_function("session_moving_1_decoded", |b| {
        b.iter(|| black_box(run(&replay, &events)));
    });
    group.finish();

    // The per-scan latency over the recording (the session alone), in five runs.
    let mut ms: Vec<f64> = (0..5)
        .flat_map(|_| run(&replay, &events))
        .map(|s| s * 1e3)
        .collect();
    ms.sort_by(f64::total_cmp);
    let rank = |q: f64| ms[((q * ms.len() as f64).ceil() as usize).clamp(1, ms.len()) - 1];
    eprintln!(
        "recording span {span:.1} s; per-scan latency over {} scans: p50 {:.3} ms, p99 {:.3} ms, \
         max {:.3} ms",
        ms.len(),
        rank(0.5),
        rank(0.99),
        ms.last().copied().unwrap_or(f64::NAN)
    );
}

criterion_group!(benches, live);
criterion_main!(benches);
