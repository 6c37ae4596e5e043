//! Issue 49, item 1: decompression bombs in MCAP files. A zstd chunk that announces, and truly
//! holds, 16 MiB of zeros in a few hundred bytes breaks the rule of at most 1000 times its
//! compressed length (beyond 1 MiB): both readers refuse it from its header, naming the chunk,
//! the indexed one (a file with its summary) and the linear one (a file without). lz4 cannot
//! pack that tight (some 250 to one), so the same chunk in lz4 is read.
//! Chunks each within their own rule but adding up on one pass to more than the file's
//! allowance (1 GiB beyond the ratio) are refused at the chunk where it runs out.
//! The ROS 1 chunks' cases are unit tests of `read/ros1_records`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::Path;

use haunts_bag::{Bag, BagError};

/// Chunked MCAP writing with `compression`, chunks of `chunk_size` bytes, with or without the
/// summary (and its indexes).
fn options(compression: mcap::Compression, chunk_size: u64, summary: bool) -> mcap::WriteOptions {
    mcap::WriteOptions::new()
        .compression(Some(compression))
        .chunk_size(Some(chunk_size))
        .use_chunks(true)
        .emit_summary_records(summary)
        .emit_summary_offsets(summary)
        .emit_message_indexes(summary)
        .emit_chunk_indexes(summary)
}

/// An MCAP of one topic, one message `payload` in one chunk compressed with `compression`,
/// with or without its summary.
fn write(path: &Path, compression: mcap::Compression, payload: &[u8], summary: bool) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = options(compression, 64 << 20, summary)
        .create(file)
        .unwrap();
    let channel = w.add_channel(0, "/blob", "cdr", &BTreeMap::new()).unwrap();
    w.write_to_known_channel(
        &mcap::records::MessageHeader {
            channel_id: channel,
            sequence: 0,
            log_time: 1,
            publish_time: 1,
        },
        payload,
    )
    .unwrap();
    w.finish().unwrap();
}

fn read_all(path: &Path) -> Result<usize, BagError> {
    let bag = Bag::open(path)?;
    let mut n = 0;
    for m in bag.messages(&["/blob"])? {
        m?;
        n += 1;
    }
    Ok(n)
}

#[test]
fn mcap_chunks_that_inflate_like_bombs_are_refused_by_both_readers() {
    let dir = tempfile::tempdir().unwrap();
    for (name, compression) in [
        ("zstd", mcap::Compression::Zstd),
        ("lz4", mcap::Compression::Lz4),
    ] {
        for summary in [true, false] {
            let bomb = dir.path().join(format!("bomb-{name}-{summary}.mcap"));
            write(&bomb, compression, &vec![0; 16 << 20], summary);
            let size = std::fs::metadata(&bomb).unwrap().len();
            if name == "lz4" {
                // An lz4 frame packs zeros at most some 250 to one: within the rule, read.
                assert!(size * 300 > 16 << 20, "lz4: {size} bytes");
                assert_eq!(read_all(&bomb).unwrap(), 1);
                continue;
            }
            let text = read_all(&bomb)
                .expect_err(&format!("{name}, summary {summary}: read"))
                .to_string();
            assert!(
                text.contains("decompression bomb") && text.contains("MCAP chunk at byte"),
                "{name}, summary {summary}, {size} bytes: {text}"
            );
            // Within the rule: 512 KiB of zeros (any ratio within the free megabyte), and
            // 16 MiB of bytes that compress like recorded data (a few times).
            let mut state = 1u64;
            let noisy: Vec<u8> = (0..16 << 20)
                .map(|_| {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                    (state >> 61) as u8 // 3 random bits a byte
                })
                .collect();
            for (i, payload) in [vec![0; 512 << 10], noisy].iter().enumerate() {
                let fine = dir.path().join(format!("fine-{name}-{summary}-{i}.mcap"));
                write(&fine, compression, payload, summary);
                assert_eq!(
                    read_all(&fine).unwrap(),
                    1,
                    "{name}, summary {summary}, {i}"
                );
            }
        }
    }
}

/// An MCAP of `chunks` zstd chunks, each one message of `payload` zero bytes, with or
/// without its summary.
fn write_many(path: &Path, chunks: usize, payload: usize, summary: bool) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    // Chunks smaller than one message: a chunk per message.
    let mut w = options(mcap::Compression::Zstd, 1024, summary)
        .create(file)
        .unwrap();
    let channel = w.add_channel(0, "/blob", "cdr", &BTreeMap::new()).unwrap();
    let zeros = vec![0u8; payload];
    for k in 0..chunks {
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: k as u32,
            log_time: k as u64 + 1,
            publish_time: k as u64 + 1,
        };
        w.write_to_known_channel(&header, &zeros).unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn many_small_bombs_are_refused_once_the_file_allowance_is_spent() {
    let dir = tempfile::tempdir().unwrap();
    // A million zeros a chunk: under the free megabyte of any one chunk, so each passes its
    // own rule; zstd packs each in some 60 bytes, so nearly all of it is beyond the ratio.
    for summary in [true, false] {
        let bombs = dir.path().join(format!("many-{summary}.mcap"));
        write_many(&bombs, 1200, 1_000_000, summary);
        let size = std::fs::metadata(&bombs).unwrap().len();
        assert!(size < 1 << 20, "{size} bytes");
        let text = read_all(&bombs)
            .expect_err(&format!("summary {summary}: read"))
            .to_string();
        assert!(
            text.contains("spread over many small chunks") && text.contains("MCAP chunk at byte"),
            "summary {summary}: {text}"
        );
        // Two hundred of them (200 MB, within the allowance) read.
        let fine = dir.path().join(format!("some-{summary}.mcap"));
        write_many(&fine, 200, 1_000_000, summary);
        assert_eq!(read_all(&fine).unwrap(), 200, "summary {summary}");
    }
}
