//! The `bag_ros1` and `bag_mcap` fuzzers' inputs as tests: the seed corpora of
//! `fuzz/seeds/bag_ros1/` and `fuzz/seeds/bag_mcap/` (each with its expected outcome) and every
//! crash input saved under `tests/fuzz_regressions/` (named `<target>-<what broke>`), run
//! through `fuzz/common/bag_check.rs`, the very code the fuzz targets run.

#[path = "../../fuzz/common/bag_check.rs"]
mod bag_check;

use std::collections::BTreeMap;

use bag_check::{Outcome, exercise_bytes};
use haunts_bag::{BagError, Format};

use haunts_test_support::crate_files as files;

/// What a file is expected to give.
#[derive(Debug)]
enum Expect {
    /// It opens; the outcome is exactly this.
    Opens(Outcome),
    /// `Bag::open` fails with an error this accepts.
    Fails(fn(&BagError) -> bool),
}

fn run(target: &str, expected: &BTreeMap<&str, Expect>) {
    let seeds = files!(format!("../fuzz/seeds/{target}"));
    let have: Vec<&str> = seeds.keys().map(String::as_str).collect();
    let want: Vec<&str> = expected.keys().copied().collect();
    assert_eq!(have, want, "seed files and expectations differ");
    for (name, data) in &seeds {
        let got = exercise_bytes(data);
        match (&expected[name.as_str()], &got) {
            (Expect::Opens(want), Ok(out)) => assert_eq!(out, want, "{target}/{name}"),
            (Expect::Fails(accept), Err(e)) => assert!(accept(e), "{target}/{name}: {e}"),
            (want, got) => panic!("{target}/{name}: expected {want:?}, got {got:?}"),
        }
    }
}

/// A file of the tiny recording of `fuzz/scripts/make_bag_seeds.py` read in full: eight
/// topics, fourteen messages (all of built-in types), three scans.
fn tiny(format: Format) -> Expect {
    Expect::Opens(Outcome {
        format: Some(format),
        topics: 8,
        raw: 14,
        raw_errors: 0,
        decoded: 14,
        decode_errors: 0,
        recording: Some(true),
        scans: 3,
        scan_errors: 0,
    })
}

fn is_ros1(e: &BagError) -> bool {
    matches!(e, BagError::Ros1 { .. })
}

/// An MCAP error of the file or of one chunk (`bad-garbled.mcap`'s first chunk, uncompressed
/// as `rosbags` writes them, has records running past its end: a `McapChunk` error).
fn is_mcap(e: &BagError) -> bool {
    matches!(e, BagError::Mcap { .. } | BagError::McapChunk { .. })
}

#[test]
fn ros1_seeds_give_their_expected_outcome() {
    let expected = BTreeMap::from([
        ("bad-garbled.bag", Expect::Fails(is_ros1)),
        // Cut in its chunk section (no index left): the chunks are found by a linear scan,
        // the messages before the cut are read, and the chunk cut short is one error a read
        // (of each topic: its counts are not known).
        (
            "bad-truncated-half.bag",
            Expect::Opens(Outcome {
                format: Some(Format::Ros1),
                topics: 5,
                raw: 7,
                raw_errors: 1,
                decoded: 7,
                decode_errors: 5,
                recording: Some(true),
                scans: 2,
                scan_errors: 1,
            }),
        ),
        ("ok-bz2.bag", tiny(Format::Ros1)),
        ("ok-lz4.bag", tiny(Format::Ros1)),
        ("ok-plain.bag", tiny(Format::Ros1)),
        // ok-lz4.bag as a killed recorder leaves it (index_pos 0, no index section): found by
        // a linear scan, everything read.
        ("ok-unindexed-lz4.bag", tiny(Format::Ros1)),
        // The real recording (leg_tracker training data): /training_scan, /leg_cluster_positions
        // (PoseArray) and /visualization_marker_array, 83 messages each (as `rosbags` counts
        // them); all 249 decode (the markers with the Indigo-to-Lunar MD5 of MarkerArray).
        (
            "ok-positive_2_extracted.bag",
            Expect::Opens(Outcome {
                format: Some(Format::Ros1),
                topics: 3,
                raw: 249,
                raw_errors: 0,
                decoded: 249,
                decode_errors: 0,
                recording: Some(true),
                scans: 83,
                scan_errors: 0,
            }),
        ),
    ]);
    run("bag_ros1", &expected);
}

#[test]
fn mcap_seeds_give_their_expected_outcome() {
    let expected = BTreeMap::from([
        ("bad-garbled.mcap", Expect::Fails(is_mcap)),
        // No footer: the summary is unreadable, the linear scan keeps what precedes the cut
        // (13 of the 14 messages) and reports the cut once per read.
        (
            "bad-truncated-half.mcap",
            Expect::Opens(Outcome {
                format: Some(Format::Mcap),
                topics: 7,
                raw: 13,
                raw_errors: 1,
                decoded: 13,
                decode_errors: 7,
                recording: Some(true),
                scans: 3,
                scan_errors: 1,
            }),
        ),
        ("ok-ros2.mcap", tiny(Format::Mcap)),
    ]);
    run("bag_mcap", &expected);
}

fn saved(name: &str) -> Vec<u8> {
    let all = files!("tests/fuzz_regressions");
    all.get(name)
        .unwrap_or_else(|| panic!("no saved input {name}"))
        .clone()
}

/// `bag_ros1` OOM: a mutated `ok-lz4.bag` whose chunk header announces about 4 GiB of
/// decompressed data; the `rosbag` crate reserved that before decompressing. Now the chunk is
/// refused (a `Ros1` error naming it) and the other chunks are read.
#[test]
fn ros1_chunk_announcing_4_gib_is_refused_before_allocating() {
    let out = exercise_bytes(&saved("bag_ros1-chunk-size-4gib")).expect("it opens");
    assert!(out.raw_errors >= 1, "{out:?}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("chunk.bag");
    std::fs::write(&path, saved("bag_ros1-chunk-size-4gib")).unwrap();
    let bag = haunts_bag::Bag::open(&path).unwrap();
    let names: Vec<&str> = bag.topics().iter().map(|t| t.name.as_str()).collect();
    let errors: Vec<String> = bag
        .messages(&names)
        .unwrap()
        .filter_map(|m| m.err().map(|e| e.to_string()))
        .collect();
    assert!(
        errors.iter().any(|e| e.contains("over the limit")),
        "{errors:?}"
    );
}

/// `bag_mcap` OOM: a mutated `ok-ros2.mcap` whose summary section holds a record with a
/// length prefix near 4 GiB; `mcap::sans_io::SummaryReader` (mcap 0.26, records.rs:142)
/// reserved it while parsing. Now the summary reader and the linear scan it falls back to are
/// given the file's size and the 1 GiB record cap: the oversized record is a typed error,
/// refused before anything is allocated.
#[test]
fn mcap_summary_record_announcing_4_gib_is_refused() {
    let got = exercise_bytes(&saved("bag_mcap-summary-record-4gib-alloc"));
    assert!(
        matches!(
            got,
            Err(BagError::Mcap {
                source: mcap::McapError::RecordTooLarge { .. },
                ..
            })
        ),
        "{got:?}"
    );
}

/// `bag_ros1` panic: a mutated `ok-lz4.bag` whose bag header record announces 24 755 bytes of
/// data (padding), so that the chunk section would start after `index_pos`; the `rosbag`
/// crate sliced `data[start..index_pos]` with start > end. Now `index_pos` is checked against
/// the end of the header record's data, and the file is refused as a `Ros1` error naming both.
#[test]
fn ros1_index_pos_before_the_chunk_section_is_refused() {
    let got = exercise_bytes(&saved("bag_ros1-index-pos-before-chunk-section"));
    match got {
        Err(BagError::Ros1 { what, .. }) => {
            assert!(
                what.contains("index_pos 17005 is before the chunk section"),
                "{what}"
            );
            assert!(what.contains("24755 bytes of data"), "{what}");
        }
        other => panic!("{other:?}"),
    }
}

/// `bag_mcap` panic: a mutated `ok-ros2.mcap` (no summary left) whose uncompressed chunk at
/// byte 43 holds a record longer than the chunk; `mcap` 0.26's linear reader subtracted it
/// from the chunk's remaining length unchecked (overflow panic in debug builds, the next
/// records misread in release ones). Now uncompressed chunks are walked first: the file is
/// refused with a `McapChunk` error naming the chunk's byte, and nothing panics.
#[test]
fn mcap_chunk_record_running_past_its_chunk_is_refused() {
    assert_refused_at_chunk("bag_mcap-plain-chunk-record-past-its-end", 43);
}

/// The saved input `name` fails to open with a `McapChunk` error naming the chunk at `offset`.
fn assert_refused_at_chunk(name: &str, offset: u64) {
    let got = exercise_bytes(&saved(name));
    assert!(
        matches!(got, Err(BagError::McapChunk { offset: o, .. }) if o == offset),
        "{name}: {got:?}"
    );
}

/// `bag_mcap` OOM: a mutated `ok-ros2.mcap` (no summary left) with a record whose string
/// length prefix is 0xFF00001B inside a record of a few bytes; `mcap`'s `parse_record`
/// allocated the 4 GiB before reading (`records.rs:142`, `binrw`). Now every record's
/// length-prefixed fields are checked against the record before `mcap` parses it. This input
/// also has an uncompressed chunk whose records run past the file, which the later fix
/// refuses first (a `McapChunk` error); the hand-made file below keeps the string alone.
#[test]
fn mcap_record_field_announcing_4_gib_is_refused() {
    assert_refused_at_chunk("bag_mcap-channel-topic-4gib-alloc", 43);

    // One channel record at the top level (no chunks, no summary) whose topic claims
    // 0xFF00001B bytes.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("string.mcap");
    let mut writer = mcap::WriteOptions::new()
        .use_chunks(false)
        .emit_summary_records(false)
        .create(std::io::BufWriter::new(
            std::fs::File::create(&path).unwrap(),
        ))
        .unwrap();
    let channel = writer
        .add_channel(0, "/topic", "cdr", &Default::default())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 0,
        log_time: 1,
        publish_time: 1,
    };
    writer
        .write_to_known_channel(&header, &[0, 1, 0, 0])
        .unwrap();
    writer.finish().unwrap();
    drop(writer);
    let mut bytes = std::fs::read(&path).unwrap();
    let needle = [&6u32.to_le_bytes()[..], b"/topic"].concat();
    let at = bytes
        .windows(needle.len())
        .position(|w| w == needle)
        .unwrap();
    bytes[at..at + 4].copy_from_slice(&0xFF00_001Bu32.to_le_bytes());
    let got = exercise_bytes(&bytes);
    assert!(
        matches!(got, Err(BagError::McapRecord { opcode: 0x04, .. })),
        "{got:?}"
    );
}

/// `bag_mcap` slow unit (10.6 s, 1.1 GB under ASan): a mutated `ok-ros2.mcap` whose record
/// at byte 14 319 claims 1 072 693 248 bytes (under the 1 GiB cap) in a file of 22 kB; the
/// file-order reader gave `mcap` room for the whole claimed length before finding the file's
/// end. Now it never gives more room than the file has left (0.08 s, 49 MB): the messages
/// before the record are read, then the end of the file is an error.
#[test]
fn mcap_record_claiming_near_1_gib_in_a_small_file_meets_its_end() {
    let out = exercise_bytes(&saved("bag_mcap-slow-record-near-1gib")).expect("it opens");
    assert!(out.raw > 0 && out.raw_errors == 1, "{out:?}");
}

/// `bag_mcap` panic, the same subtraction as `bag_mcap-plain-chunk-record-past-its-end` in a
/// chunk whose record claims 1.45 MB in a file of 21 kB: the walk of uncompressed chunks gave
/// up on a chunk running past the file, which `mcap` still reads record by record. Now such a
/// chunk is walked as far as the file goes: the file is refused naming the chunk at byte 43.
#[test]
fn mcap_plain_chunk_running_past_the_file_is_walked_too() {
    assert_refused_at_chunk("bag_mcap-plain-chunk-past-the-file", 43);
}
