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
            // The seeds that are valid closed bags (the peer refuses a bag without an index).
            let seed_ok = name.starts_with("ok-") && !name.contains("unindexed");
            if name.ends_with(".bag") && (prefix != "seeds" || seed_ok) {
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

/// `bytes` of a closed bag as a recorder killed before closing leaves it: `index_pos` 0 and no
/// index section.
fn without_index(bytes: &[u8]) -> Vec<u8> {
    let at = bytes.windows(10).position(|w| w == b"index_pos=").unwrap() + 10;
    let index_pos = u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
    let mut cut = bytes[..index_pos].to_vec();
    cut[at..at + 8].copy_from_slice(&0u64.to_le_bytes());
    cut
}

#[test]
fn a_bag_without_its_index_reads_the_same_messages_by_a_linear_scan_and_says_so() {
    let Some(bags) = bags() else { return };
    let fixture: Value = serde_json::from_str(include_str!("fixtures/ros1_digests.json")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "general_tracking_moving_1.bag",
        "fixtures/out_of_order_lz4.bag",
        "seeds/ok-bz2.bag",
    ] {
        let path = dir.path().join("unindexed.bag");
        std::fs::write(&path, without_index(&std::fs::read(&bags[name]).unwrap())).unwrap();
        let bag = Bag::open(&path).unwrap();
        let notes = bag.notes().join(" ");
        assert!(
            notes.contains("index_pos is 0") && notes.contains("linear scan"),
            "{name}: {notes}"
        );
        if name == "general_tracking_moving_1.bag" {
            let recording = bag.recording(&haunts_bag::RecordingOptions::new()).unwrap();
            assert!(recording.notes().iter().any(|n| n.contains("linear scan")));
            assert_eq!(recording.scans().unwrap().count(), 873);
        }
        let names: Vec<&str> = bag.topics().iter().map(|t| t.name.as_str()).collect();
        let mut messages = bag.messages(&names).unwrap();
        let all: Vec<_> = messages
            .by_ref()
            .map(|m| {
                let m = m.unwrap();
                (m.topic.to_string(), m.log_time, m.data)
            })
            .collect();
        // Still in log-time order, the overlapping chunks of the fixture held together only.
        assert!(all.windows(2).all(|w| w[0].1 <= w[1].1), "{name}");
        if name.starts_with("fixtures/") {
            let held = messages.most_chunks_held();
            assert!(held > 1 && held < 9, "{name}: {held}");
        }
        assert_eq!(&digests(all.into_iter()), &fixture["bags"][name], "{name}");
        // The counts of the topic list come from the scan.
        for t in bag.topics() {
            assert_eq!(
                t.count,
                fixture["bags"][name][&t.name]["count"].as_u64(),
                "{name} {}",
                t.name
            );
        }
    }
}

#[test]
fn a_broken_chunk_is_one_error_naming_its_byte_and_the_others_are_read() {
    let Some(bags) = bags() else { return };
    let mut bytes = std::fs::read(&bags["fixtures/out_of_order.bag"]).unwrap();
    let needle = b"compression=none";
    let at = bytes
        .windows(needle.len())
        .enumerate()
        .filter(|(_, w)| w == needle)
        .nth(1)
        .unwrap()
        .0;
    bytes[at + 12..at + 16].copy_from_slice(b"zzzz");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.bag");
    std::fs::write(&path, &bytes).unwrap();
    let bag = Bag::open(&path).unwrap();
    let (mut ok, mut errors) = (0, Vec::new());
    for m in bag.messages(&["/a", "/b"]).unwrap() {
        match m {
            Ok(_) => ok += 1,
            Err(e) => errors.push(e),
        }
    }
    assert_eq!(errors.len(), 1, "{errors:?}");
    match &errors[0] {
        haunts_bag::BagError::Ros1Chunk { offset, what, .. } => {
            // The chunk record starts a few bytes before its header's field.
            assert!(
                *offset < at as u64 && at as u64 - offset < 64,
                "{offset} {at}"
            );
            assert!(what.contains("unknown compression `zzzz`"), "{what}");
        }
        other => panic!("{other:?}"),
    }
    // Nine chunks of 24 messages: one is lost.
    assert!((16..24).contains(&ok), "{ok}");
}
