//! `haunts node` and `haunts replay --dds` end to end, as two processes inside a network
//! namespace of the test's own (only `lo`; see `haunts_test_support::netns`).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use haunts::bag::{Bag, RecordingOptions};
use haunts::live::replay::Replay;
use haunts::live::{LiveParams, LiveSession};
use serde_json::Value;

/// The last stdout line of a finished `haunts` as JSON.
fn last_json(out: &std::process::Output) -> Value {
    let stdout = String::from_utf8_lossy(&out.stdout);
    stdout
        .lines()
        .last()
        .and_then(|l| serde_json::from_str(l).ok())
        .unwrap_or(Value::Null)
}

/// A node started on moving_1's topics and frames (arrival times from `/clock`, a library to
/// close the day into), the recording replayed onto DDS at 8× its pace, then SIGTERM: the node
/// tracks every scan the offline session tracks, counts nothing undecodable, and closes the
/// day into the library, which it creates.
#[test]
fn a_node_tracks_a_dds_replay_and_closes_the_day_at_sigterm() {
    let test = "a_node_tracks_a_dds_replay_and_closes_the_day_at_sigterm";
    if !haunts_test_support::netns::enter(test) {
        return;
    }
    let Some(mcap) = haunts_test_support::bag::moving_mcap() else {
        eprintln!("skipped: ../shared/data is absent");
        return;
    };
    let replay = Replay::new(Bag::open(&mcap).unwrap(), &RecordingOptions::new(), None).unwrap();
    let mut offline = LiveSession::with_defaults(replay.params(LiveParams::default())).unwrap();
    replay.run(&mut offline, |_| Ok(())).unwrap();
    let live = replay.params(LiveParams::default());
    let topics = replay.topics();

    let dir = tempfile::tempdir().unwrap();
    let library = dir.path().join("site.haunts");
    // The node on moving_1's topics and frames, its output kept.
    let node_command = || {
        let mut c = Command::new(env!("CARGO_BIN_EXE_haunts"));
        c.args([
            "node",
            "--library",
            library.to_str().unwrap(),
            "--use-sim-time",
            "--reliable-inputs",
        ])
        .args(["--scan-topic", &topics.scan])
        .args(["--odom-topic", topics.odom.as_deref().unwrap()])
        .args(["--base-frame", &live.base_frame])
        .args(["--fixed-frame", &live.fixed_frame])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
        c
    };
    let node = node_command().args(["--duration", "300"]).spawn().unwrap();
    let replayed = Command::new(env!("CARGO_BIN_EXE_haunts"))
        .args(["replay", mcap.to_str().unwrap(), "--dds", "--rate", "8"])
        .args(["--subscriber-wait", "30"])
        .output()
        .unwrap();
    let published = last_json(&replayed);
    assert!(replayed.status.success(), "{published}");
    assert_eq!(published["matched"], true, "{published}");
    assert_eq!(published["undecodable"], 0, "{published}");

    // The last scans in, then the signal a service manager sends.
    std::thread::sleep(Duration::from_secs(2));
    let killed = Command::new("kill")
        .args(["-TERM", &node.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let waited = Instant::now();
    let out = node.wait_with_output().unwrap();
    let json = last_json(&out);
    eprintln!(
        "replay {published}\nnode ({:.1} s after SIGTERM) {json}\n{}",
        waited.elapsed().as_secs_f64(),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{json}");
    // Every scan (reliable inputs: best effort lost one of 873 with a build on both cores).
    assert_eq!(json["tracked_scans"], offline.tracked() as u64, "{json}");
    assert_eq!(json["people_messages"], json["tracked_scans"], "{json}");
    for input in ["scan", "odom", "tf", "tf_static", "clock", "close_day"] {
        assert_eq!(json["undecodable"][input], 0, "{input}: {json}");
    }
    assert_eq!(json["unconvertible"], 0, "{json}");
    let latency = &json["latency_ms"];
    assert_eq!(latency["count"], json["tracked_scans"], "{json}");
    assert!(latency["p99"].as_f64().unwrap() >= latency["p50"].as_f64().unwrap());
    let closed = &json["closed_day"];
    assert_eq!(closed["saved"], true, "{json}");
    assert_eq!(closed["layouts"], 1, "{json}");
    assert!(closed["layout"].is_u64(), "{json}");
    assert_eq!(json["days_closed"], 1, "{json}");
    let saved = haunts::affordance::LayoutLibrary::load(&library).unwrap();
    assert_eq!(saved.layouts().len(), 1);
    assert!(json.get("unclosed_spool").is_none(), "{json}");

    // `kill -9` in the middle of the next day: the library is as the first close left it,
    // and the next node sets the killed day's spool aside, where `haunts day` reads it.
    let before = std::fs::read(&library).unwrap();
    let mut node = node_command().spawn().unwrap();
    let mut replay = Command::new(env!("CARGO_BIN_EXE_haunts"))
        .args(["replay", mcap.to_str().unwrap(), "--dds", "--rate", "8"])
        .args(["--subscriber-wait", "30"])
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(8));
    node.kill().unwrap();
    node.wait().unwrap();
    replay.kill().unwrap();
    replay.wait().unwrap();
    assert_eq!(
        std::fs::read(&library).unwrap(),
        before,
        "kill -9 changed the library"
    );
    let next = node_command().args(["--duration", "2"]).output().unwrap();
    let json = last_json(&next);
    assert!(next.status.success(), "{json}");
    let aside = std::path::PathBuf::from(json["unclosed_spool"].as_str().expect("set aside"));
    assert!(aside.exists(), "{json}");
    assert_eq!(std::fs::read(&library).unwrap(), before);
    let day = Command::new(env!("CARGO_BIN_EXE_haunts"))
        .args(["day", aside.to_str().unwrap(), "-o"])
        .arg(dir.path().join("killed.haunts"))
        .output()
        .unwrap();
    let day_json = last_json(&day);
    eprintln!("the killed day's spool, {}: {day_json}", aside.display());
    assert!(
        day.status.success(),
        "{}",
        String::from_utf8_lossy(&day.stderr)
    );
}
