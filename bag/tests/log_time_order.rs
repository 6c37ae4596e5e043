//! Messages come in log-time order even when a file's chunks overlap in time: ROS 1 bags
//! written by `rosbags` with overlapping chunks (`benches/peers/out_of_order_bag.py`), and
//! MCAP files written here with `mcap::Writer` chunk by chunk. The reference is the plain way:
//! every message as written, sorted by log time. An MCAP file without a summary is read in
//! file order, and its notes say so.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use haunts_bag::codec;
use haunts_bag::msg::{self, Message, PoseStamped};
use haunts_bag::{Bag, convert};

const T0: u64 = 1_700_000_000_000_000_000;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// (topic, log time ns, write index) of every message of `topics`, as read.
fn read_all(bag: &Bag, topics: &[&str]) -> (Vec<(String, u64, u64)>, usize) {
    let mut messages = bag.messages(topics).unwrap();
    let mut out = Vec::new();
    for m in messages.by_ref() {
        let m = m.unwrap();
        let topic = m.topic.to_string();
        let info = bag.topic(&topic).unwrap();
        let pose: PoseStamped = codec::decode(info.encoding, &m.data).unwrap();
        // The header stamp is the log time, and x the write index.
        assert_eq!(pose.header.stamp.nanos() as u64, m.log_time);
        out.push((topic, m.log_time, pose.pose.position.x as u64));
    }
    (out, messages.most_chunks_held())
}

/// The plain reference: what was written (in write order), the `topics` kept, sorted by log
/// time.
fn sorted(written: &[(String, u64, u64)], topics: &[&str]) -> Vec<(String, u64, u64)> {
    let mut v: Vec<_> = written
        .iter()
        .filter(|m| topics.contains(&m.0.as_str()))
        .cloned()
        .collect();
    v.sort_by_key(|m| m.1);
    v
}

/// What `benches/peers/out_of_order_bag.py` wrote, in write order.
fn ros1_written() -> Vec<(String, u64, u64)> {
    (0..24u64)
        .map(|i| {
            let topic = if i % 3 == 0 { "/b" } else { "/a" };
            (topic.to_owned(), T0 + (7 * i % 24) * 100_000_000, i)
        })
        .collect()
}

#[test]
fn a_ros1_bag_with_overlapping_chunks_reads_in_log_time_order() {
    let written = ros1_written();
    // The fixture is not in log-time order in the file.
    assert_ne!(sorted(&written, &["/a", "/b"]), written);
    for name in ["out_of_order.bag", "out_of_order_lz4.bag"] {
        let bag = Bag::open(fixture(name)).unwrap();
        for topics in [&["/a", "/b"][..], &["/a"], &["/b"]] {
            let (got, held) = read_all(&bag, topics);
            assert_eq!(got, sorted(&written, topics), "{name} {topics:?}");
            // Overlapping chunks are held together, but not the whole file (nine chunks).
            assert!(
                held > 1 && held < 9,
                "{name} {topics:?}: {held} chunks held"
            );
        }
        // The typed reader gives the same order.
        let times: Vec<f64> = bag
            .read::<PoseStamped>("/a")
            .unwrap()
            .map(|m| m.unwrap().0)
            .collect();
        assert_eq!(times.len(), 16);
        assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
    }
}

/// Writes an MCAP file of `chunks` (each a list of (topic, log time, write index)), one chunk
/// record per list, with or without a summary; returns what was written, in write order.
fn write_mcap(path: &Path, chunks: &[Vec<(&str, u64)>], summary: bool) -> Vec<(String, u64, u64)> {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut writer = mcap::WriteOptions::new()
        .profile("ros2")
        .chunk_size(None)
        .emit_summary_records(summary)
        .emit_chunk_indexes(summary)
        .emit_summary_offsets(summary)
        .emit_statistics(summary)
        .create(file)
        .unwrap();
    let schema = writer
        .add_schema(
            PoseStamped::ROS2_TYPE,
            "ros2msg",
            PoseStamped::ROS2_DEFINITION.as_bytes(),
        )
        .unwrap();
    let mut channels = BTreeMap::new();
    let mut written = Vec::new();
    for chunk in chunks {
        for &(topic, t) in chunk {
            let i = written.len() as u64;
            let channel = *channels.entry(topic).or_insert_with(|| {
                writer
                    .add_channel(schema, topic, "cdr", &BTreeMap::new())
                    .unwrap()
            });
            let mut m = PoseStamped {
                header: convert::header(0.0, "map"),
                pose: msg::Pose::default(),
            };
            m.header.stamp = msg::Time::from_nanos(t as i64).unwrap();
            m.pose.position.x = i as f64;
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: i as u32,
                log_time: t,
                publish_time: t,
            };
            writer
                .write_to_known_channel(&header, &codec::encode_cdr(&m).unwrap())
                .unwrap();
            written.push((topic.to_owned(), t, i));
        }
        writer.flush().unwrap();
    }
    writer.finish().unwrap();
    written
}

#[test]
fn an_mcap_file_with_overlapping_chunks_reads_in_log_time_order() {
    let dir = tempfile::tempdir().unwrap();
    let ms = |k: u64| T0 + k * 1_000_000;
    // Two recorders' chunks interleaved, one chunk out of order inside, and a late chunk that
    // starts before all others.
    let chunks = vec![
        vec![("/a", ms(10)), ("/b", ms(30)), ("/a", ms(50))],
        vec![("/b", ms(20)), ("/a", ms(40)), ("/b", ms(60))],
        vec![("/a", ms(90)), ("/a", ms(70)), ("/b", ms(80))],
        vec![("/b", ms(100)), ("/a", ms(110))],
        vec![("/a", ms(5)), ("/b", ms(120))],
    ];
    let path = dir.path().join("overlap.mcap");
    let written = write_mcap(&path, &chunks, true);
    assert_ne!(sorted(&written, &["/a", "/b"]), written);
    let bag = Bag::open(&path).unwrap();
    assert!(bag.notes().is_empty(), "{:?}", bag.notes());
    for topics in [&["/a", "/b"][..], &["/a"], &["/b"]] {
        let (got, held) = read_all(&bag, topics);
        assert_eq!(got, sorted(&written, topics), "{topics:?}");
        assert!(held > 1 && held <= 5, "{topics:?}: {held}");
    }

    // Chunks that do not overlap are held one at a time.
    let path = dir.path().join("ordered.mcap");
    let ordered = vec![
        vec![("/a", ms(1)), ("/b", ms(2))],
        vec![("/a", ms(3)), ("/a", ms(4))],
        vec![("/b", ms(5))],
    ];
    let written = write_mcap(&path, &ordered, true);
    let (got, held) = read_all(&Bag::open(&path).unwrap(), &["/a", "/b"]);
    assert_eq!((got, held), (written, 1));
}

#[test]
fn an_mcap_file_without_a_summary_is_read_in_file_order_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let ms = |k: u64| T0 + k * 1_000_000;
    let chunks = vec![vec![("/a", ms(30)), ("/b", ms(10))], vec![("/a", ms(20))]];
    let path = dir.path().join("nosummary.mcap");
    let written = write_mcap(&path, &chunks, false);
    let bag = Bag::open(&path).unwrap();
    let notes = bag.notes().join(" ");
    assert!(notes.contains("file order"), "{notes}");
    let (got, held) = read_all(&bag, &["/a", "/b"]);
    assert_eq!((got, held), (written, 0));
}
