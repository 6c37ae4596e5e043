//! haunts-bag's own ROS 1 reader against a peer, message for message, on every shared ROS 1
//! bag: the benchmark bag, leg_tracker's training bags, the out-of-order fixtures and the fuzz
//! seeds (plain, bz2 and lz4 chunks). `tests/fixtures/ros1_digests.json` is what the Python
//! `rosbags` reader found (`benches/peers/ros1_digests.py`): per topic the count, the first and
//! last log time and a digest of every message's log time and bytes, whatever their order.
//! The same digests were checked equal to the `rosbag` crate's, the reader haunts-bag used
//! before its own, in the commit that brought this reader in (6af3901), before that crate was
//! dropped.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use haunts_bag::Bag;
use serde_json::{Value, json};
use sha2::{Digest, Sha256};

/// Per topic: count, first and last log time, digest (as the peer script computes them) of
/// `(topic, log time, bytes)` triples.
fn digests(messages: impl Iterator<Item = (String, u64, Vec<u8>)>) -> Value {
    let mut per_topic: BTreeMap<String, Vec<Vec<u8>>> = BTreeMap::new();
    for (topic, time, data) in messages {
        let mut entry = time.to_le_bytes().to_vec();
        entry.extend_from_slice(&Sha256::digest(&data));
        per_topic.entry(topic).or_default().push(entry);
    }
    let mut out = serde_json::Map::new();
    for (topic, mut entries) in per_topic {
        entries.sort();
        let time = |e: &Vec<u8>| u64::from_le_bytes(e[..8].try_into().unwrap());
        let mut h = Sha256::new();
        for e in &entries {
            h.update(e);
        }
        let digest: String = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
        out.insert(
            topic,
            json!({
                "count": entries.len(),
                "first": entries.iter().map(time).min().unwrap(),
                "last": entries.iter().map(time).max().unwrap(),
                "digest": digest,
            }),
        );
    }
    Value::Object(out)
}

/// Every message of every topic of `path` through `Bag::messages`.
fn ours(path: &Path) -> Value {
    let bag = Bag::open(path).unwrap();
    assert!(bag.notes().is_empty(), "{:?}", bag.notes());
    let names: Vec<&str> = bag.topics().iter().map(|t| t.name.as_str()).collect();
    let messages = bag.messages(&names).unwrap().map(|m| {
        let m = m.unwrap();
        (m.topic.to_string(), m.log_time, m.data)
    });
    let got = digests(messages);
    // The topic list's counts (from the index) agree with what was read.
    for t in bag.topics() {
        assert_eq!(
            Some(got[&t.name]["count"].as_u64().unwrap()),
            t.count,
            "{}: {}",
            path.display(),
            t.name
        );
    }
    got
}

/// The bags of the fixture, by its names.
fn bags() -> Option<BTreeMap<String, PathBuf>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut bags = BTreeMap::new();
    bags.insert(
        "general_tracking_moving_1.bag".to_owned(),
        common::moving_bag()?,
    );
    let training = common::shared_data("leg_tracker/training/bags")?;
    let dirs = [
        ("training", training),
        ("fixtures", root.join("tests/fixtures")),
        ("seeds", root.join("../fuzz/seeds/bag_ros1")),
    ];
    for (prefix, dir) in dirs {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if name.ends_with(".bag") && (prefix != "seeds" || name.starts_with("ok-")) {
                bags.insert(format!("{prefix}/{name}"), path);
            }
        }
    }
    Some(bags)
}

#[test]
fn every_shared_bag_reads_as_the_rosbags_peer_reads_it() {
    let Some(bags) = bags() else { return };
    let fixture: Value = serde_json::from_str(include_str!("fixtures/ros1_digests.json")).unwrap();
    let expected = fixture["bags"].as_object().unwrap();
    assert_eq!(
        bags.keys().collect::<Vec<_>>(),
        expected.keys().collect::<Vec<_>>(),
        "the bags found and the fixture's differ"
    );
    for (name, path) in &bags {
        assert_eq!(&ours(path), &expected[name], "{name}");
    }
}

