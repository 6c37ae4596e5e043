//! What the Python `mcap-ros2-support` decoder reads in the MCAP haunts writes. The fixture
//! `tests/fixtures/mcap_ros2_peer.json` is written by `benches/peers/mcap_ros2_check.py` from
//! the file of the `peer_mcap` example; this test writes the same messages again and asserts
//! (1) that haunts still writes the very bytes the peer decoded (CDR payloads, topics, times,
//! schema names and `ros2msg` texts), and (2) that the peer's decoding equals, field by field,
//! the messages haunts meant. A change of the writer's output fails (1) until the fixture is
//! made again by the peer, and then (2) says whether the peer still reads the same meaning.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../examples/peer_mcap.rs"]
mod peer_mcap;

use haunts_bag::{Bag, McapWriter, msg::Message};
use serde_json::Value;

fn fixture() -> Value {
    let text = include_str!("fixtures/mcap_ros2_peer.json");
    serde_json::from_str(text).unwrap()
}

/// The first difference between `ours` and the peer's `theirs`, with its field path.
fn diff(path: &str, ours: &Value, theirs: &Value) -> Option<String> {
    match (ours, theirs) {
        (Value::Object(a), Value::Object(b)) => {
            let (ka, kb): (Vec<_>, Vec<_>) = (a.keys().collect(), b.keys().collect());
            let mut ka_sorted = ka.clone();
            let mut kb_sorted = kb.clone();
            ka_sorted.sort();
            kb_sorted.sort();
            if ka_sorted != kb_sorted {
                return Some(format!("{path}: fields {ka:?} (haunts) vs {kb:?} (peer)"));
            }
            a.iter()
                .find_map(|(k, v)| diff(&format!("{path}.{k}"), v, &b[k]))
        }
        (Value::Array(a), Value::Array(b)) => {
            if a.len() != b.len() {
                return Some(format!(
                    "{path}: {} items (haunts) vs {} (peer)",
                    a.len(),
                    b.len()
                ));
            }
            a.iter()
                .zip(b)
                .enumerate()
                .find_map(|(i, (x, y))| diff(&format!("{path}[{i}]"), x, y))
        }
        (Value::Number(a), Value::Number(b)) => {
            // Integers compare as integers; floats by their bits (f32 fields are held as the
            // exact double of the f32 on both sides).
            let same = match (a.as_i64(), b.as_i64(), a.as_u64(), b.as_u64()) {
                (Some(x), Some(y), _, _) => x == y,
                (_, _, Some(x), Some(y)) => x == y,
                _ => a.as_f64().map(f64::to_bits) == b.as_f64().map(f64::to_bits),
            };
            (!same).then(|| format!("{path}: {a} (haunts) vs {b} (peer)"))
        }
        _ => (ours != theirs).then(|| format!("{path}: {ours} (haunts) vs {theirs} (peer)")),
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn ros2_type(topic: &str) -> (&'static str, &'static str) {
    use haunts_bag::msg::{LaserScan, MarkerArray, OccupancyGrid, Path, PoseArray, TfMessage};
    match topic {
        "/scan" => (LaserScan::ROS2_TYPE, LaserScan::ROS2_DEFINITION),
        "/map" => (OccupancyGrid::ROS2_TYPE, OccupancyGrid::ROS2_DEFINITION),
        "/plan" => (Path::ROS2_TYPE, Path::ROS2_DEFINITION),
        "/tf" => (TfMessage::ROS2_TYPE, TfMessage::ROS2_DEFINITION),
        "/people" => (PoseArray::ROS2_TYPE, PoseArray::ROS2_DEFINITION),
        "/markers" => (MarkerArray::ROS2_TYPE, MarkerArray::ROS2_DEFINITION),
        other => panic!("unexpected topic {other}"),
    }
}

#[test]
fn the_peer_decodes_what_haunts_writes() {
    let fixture = fixture();
    let peer = fixture["messages"].as_array().unwrap();
    assert_eq!(fixture["profile"], "ros2");

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("peer.mcap");
    let written = peer_mcap::write_peer_messages(McapWriter::create(&path).unwrap()).unwrap();
    assert_eq!(written.len(), 6, "the example writes six messages");
    assert_eq!(
        peer.len(),
        written.len(),
        "the peer decoded another number of messages"
    );

    // (1) The same bytes as when the peer decoded them.
    let bag = Bag::open(&path).unwrap();
    let topics: Vec<&str> = written.iter().map(|w| w.topic).collect();
    let raw: Vec<_> = bag
        .messages(&topics)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(raw.len(), peer.len());
    for ((w, r), p) in written.iter().zip(&raw).zip(peer) {
        let (type_name, definition) = ros2_type(w.topic);
        assert_eq!(p["topic"], w.topic);
        assert_eq!(&*r.topic, w.topic);
        assert_eq!(p["message_encoding"], "cdr", "{}", w.topic);
        assert_eq!(p["schema"], type_name, "{}", w.topic);
        let schema = &fixture["schemas"][type_name];
        assert_eq!(schema["encoding"], "ros2msg", "{type_name}");
        assert_eq!(
            schema["data"], definition,
            "{type_name}: the schema text changed"
        );
        assert_eq!(p["log_time"].as_u64(), Some(r.log_time), "{}", w.topic);
        assert_eq!(p["publish_time"].as_u64(), Some(r.log_time), "{}", w.topic);
        assert!(
            (r.log_time as f64 * 1e-9 - w.seconds).abs() < 1e-6,
            "{}: log time",
            w.topic
        );
        assert_eq!(
            p["cdr_hex"].as_str().unwrap(),
            hex(&r.data),
            "{}: haunts writes other bytes than the peer decoded: run \
             benches/peers/mcap_ros2_check.py and look at what changed",
            w.topic
        );
    }

    // (2) What the peer decoded is what haunts meant, field by field.
    for (w, p) in written.iter().zip(peer) {
        if let Some(d) = diff(w.topic, &w.fields, &p["decoded"]) {
            panic!("the peer decodes another message than haunts wrote: {d}");
        }
    }
}

#[test]
fn the_comparison_sees_a_changed_field() {
    // The check of (2) is not vacuous: one changed bit of a float32 range is found.
    let fixture = fixture();
    let scan = &fixture["messages"][0];
    assert_eq!(scan["topic"], "/scan");
    let mut changed = scan["decoded"].clone();
    let r = changed["ranges"][3].as_f64().unwrap();
    changed["ranges"][3] = Value::from(f64::from(f32::from_bits((r as f32).to_bits() + 1)));
    let found = diff("/scan", &changed, &scan["decoded"]).unwrap();
    assert!(found.contains("ranges[3]"), "{found}");
}
