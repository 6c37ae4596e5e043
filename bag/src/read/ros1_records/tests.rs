//! The record layer on small bags written here byte by byte (as the format describes them):
//! every field of a connection, the index against a linear scan, the three compressions, and
//! every truncation and single-byte corruption read without a panic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::{Cursor, Write};

use super::*;
use crate::read::ros1_index::{Index, read_index, scan_chunks};

fn field(name: &str, value: &[u8]) -> Vec<u8> {
    let mut f = ((name.len() + 1 + value.len()) as u32)
        .to_le_bytes()
        .to_vec();
    f.extend_from_slice(name.as_bytes());
    f.push(b'=');
    f.extend_from_slice(value);
    f
}

fn record(fields: &[Vec<u8>], data: &[u8]) -> Vec<u8> {
    let header = fields.concat();
    let mut r = (header.len() as u32).to_le_bytes().to_vec();
    r.extend_from_slice(&header);
    r.extend_from_slice(&(data.len() as u32).to_le_bytes());
    r.extend_from_slice(data);
    r
}

fn time(ns: u64) -> Vec<u8> {
    let (s, n) = ((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32);
    [s.to_le_bytes(), n.to_le_bytes()].concat()
}

fn connection_record(id: u32, topic: &str) -> Vec<u8> {
    let data = [
        field("topic", topic.as_bytes()),
        field("type", b"pkg/Thing"),
        field("md5sum", b"0123456789ABCDEF0123456789abcdef"),
        field("message_definition", b"int32 x\n"),
        field("callerid", b"/node"),
        field("latching", if id == 0 { b"1" } else { b"0" }),
    ]
    .concat();
    record(
        &[
            field("op", &[OP_CONNECTION]),
            field("conn", &id.to_le_bytes()),
            field("topic", topic.as_bytes()),
        ],
        &data,
    )
}

fn message(conn: u32, ns: u64) -> Vec<u8> {
    record(
        &[
            field("op", &[OP_MESSAGE]),
            field("conn", &conn.to_le_bytes()),
            field("time", &time(ns)),
        ],
        &ns.to_le_bytes(),
    )
}

const S: u64 = 1_000_000_000;

/// `bytes` compressed as a ROS 1 chunk's `compression` says (`none`, `bz2`, `lz4`).
fn compress(compression: &str, bytes: &[u8]) -> Vec<u8> {
    match compression {
        "none" => bytes.to_vec(),
        "bz2" => {
            let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::default());
            e.write_all(bytes).unwrap();
            e.finish().unwrap()
        }
        _ => {
            let mut e = lz4::EncoderBuilder::new().build(Vec::new()).unwrap();
            e.write_all(bytes).unwrap();
            e.finish().0
        }
    }
}

/// The chunks of the tiny bag: (connection, log time) of each message, connection records
/// before a connection's first message.
fn chunks() -> Vec<Vec<(u32, u64)>> {
    vec![vec![(0, 3 * S), (1, S + 5), (0, 2 * S)], vec![(1, 5 * S)]]
}

/// A bag of two connections (`/a`, `/b`) in two chunks compressed with `compression`; with
/// `index`, the index section and its position, otherwise `index_pos` 0 (not closed).
fn tiny_bag(compression: &str, index: bool) -> Vec<u8> {
    let mut body = Vec::new();
    let mut infos = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    let start = 13 + 4096u64;
    for chunk in chunks() {
        let mut records = Vec::new();
        for &(conn, ns) in &chunk {
            if seen.insert(conn) {
                records.extend(connection_record(conn, ["/a", "/b"][conn as usize]));
            }
            records.extend(message(conn, ns));
        }
        let data = compress(compression, &records);
        let at = start + body.len() as u64;
        body.extend(record(
            &[
                field("op", &[OP_CHUNK]),
                field("compression", compression.as_bytes()),
                field("size", &(records.len() as u32).to_le_bytes()),
            ],
            &data,
        ));
        // Index data: ver 1, one record per connection (times and offsets not needed here).
        let mut counts = std::collections::BTreeMap::<u32, u32>::new();
        for &(conn, _) in &chunk {
            *counts.entry(conn).or_default() += 1;
        }
        for (&conn, &n) in &counts {
            body.extend(record(
                &[
                    field("op", &[OP_INDEX_DATA]),
                    field("ver", &1u32.to_le_bytes()),
                    field("conn", &conn.to_le_bytes()),
                    field("count", &n.to_le_bytes()),
                ],
                &vec![0; 12 * n as usize],
            ));
        }
        let first = chunk.iter().map(|c| c.1).min().unwrap();
        let last = chunk.iter().map(|c| c.1).max().unwrap();
        let entries: Vec<u8> = counts
            .iter()
            .flat_map(|(c, n)| [c.to_le_bytes(), n.to_le_bytes()].concat())
            .collect();
        infos.push(record(
            &[
                field("op", &[OP_CHUNK_INFO]),
                field("ver", &1u32.to_le_bytes()),
                field("chunk_pos", &at.to_le_bytes()),
                field("start_time", &time(first)),
                field("end_time", &time(last)),
                field("count", &(counts.len() as u32).to_le_bytes()),
            ],
            &entries,
        ));
    }
    let index_pos = start + body.len() as u64;
    if index {
        body.extend(connection_record(0, "/a"));
        body.extend(connection_record(1, "/b"));
        body.extend(infos.concat());
    }
    let header_fields = [
        field("op", &[OP_BAG_HEADER]),
        field(
            "index_pos",
            &(if index { index_pos } else { 0 }).to_le_bytes(),
        ),
        field("conn_count", &2u32.to_le_bytes()),
        field("chunk_count", &2u32.to_le_bytes()),
    ];
    let header_len = header_fields.concat().len();
    let padding = 4096 - 4 - header_len - 4;
    let mut bag = b"#ROSBAG V2.0\n".to_vec();
    bag.extend(record(&header_fields, &vec![b' '; padding]));
    assert_eq!(bag.len() as u64, start);
    bag.extend(body);
    bag
}

fn file(bytes: &[u8]) -> Ros1File<Cursor<&[u8]>> {
    Ros1File::new(Cursor::new(bytes), bytes.len() as u64)
}

/// The messages of every chunk of `index`, (connection, time, data) in file order.
fn messages(bytes: &[u8], index: &Index) -> Result<Vec<(u32, u64, Vec<u8>)>, Problem> {
    let mut f = file(bytes);
    let (mut raw, mut out, mut all) = (Vec::new(), Vec::new(), Vec::new());
    for chunk in &index.chunks {
        read_chunk(&mut f, chunk.at, &mut raw, &mut out)?;
        chunk_records(&out, |r| {
            if let Inner::Message { conn, time, data } = r {
                all.push((conn, time, data.to_vec()));
            }
            Ok(())
        })?;
    }
    Ok(all)
}

fn expected_messages() -> Vec<(u32, u64, Vec<u8>)> {
    chunks()
        .concat()
        .into_iter()
        .map(|(c, t)| (c, t, t.to_le_bytes().to_vec()))
        .collect()
}

#[test]
fn the_index_lists_every_field_of_the_connections_and_the_chunks() {
    let bytes = tiny_bag("none", true);
    let mut f = file(&bytes);
    let header = bag_header(&mut f).unwrap();
    assert_eq!((header.conn_count, header.chunk_count), (Some(2), Some(2)));
    let index = read_index(&mut f, &header, header.index_pos.unwrap()).unwrap();
    let a = &index.connections[&0];
    assert_eq!(
        a,
        &Connection {
            id: 0,
            topic: "/a".into(),
            type_name: "pkg/Thing".into(),
            md5sum: Some("0123456789abcdef0123456789abcdef".into()),
            message_definition: "int32 x\n".into(),
            callerid: Some("/node".into()),
            latching: true,
        }
    );
    assert!(!index.connections[&1].latching);
    let chunks: Vec<(u64, Vec<(u32, u32)>)> = index
        .chunks
        .iter()
        .map(|c| (c.start, c.counts.clone()))
        .collect();
    assert_eq!(
        chunks,
        vec![(S + 5, vec![(0, 2), (1, 1)]), (5 * S, vec![(1, 1)])]
    );
    assert!(index.notes.is_empty());
}

#[test]
fn every_compression_gives_the_same_messages() {
    for compression in ["none", "bz2", "lz4"] {
        let bytes = tiny_bag(compression, true);
        let mut f = file(&bytes);
        let header = bag_header(&mut f).unwrap();
        let index = read_index(&mut f, &header, header.index_pos.unwrap()).unwrap();
        assert_eq!(
            messages(&bytes, &index).unwrap(),
            expected_messages(),
            "{compression}"
        );
    }
}

#[test]
fn a_linear_scan_finds_what_the_index_lists() {
    for compression in ["none", "bz2", "lz4"] {
        let indexed = tiny_bag(compression, true);
        let mut f = file(&indexed);
        let header = bag_header(&mut f).unwrap();
        let index = read_index(&mut f, &header, header.index_pos.unwrap()).unwrap();
        // Without an index, and over a closed bag's index section too.
        for bytes in [tiny_bag(compression, false), indexed.clone()] {
            let mut f = file(&bytes);
            let header = bag_header(&mut f).unwrap();
            let scanned = scan_chunks(&mut f, &header, bytes.len() as u64);
            assert_eq!(scanned.connections, index.connections);
            #[allow(clippy::type_complexity)]
            let key = |i: &Index| -> Vec<(u64, u64, Vec<(u32, u32)>)> {
                i.chunks
                    .iter()
                    .map(|c| (c.at, c.start, c.counts.clone()))
                    .collect()
            };
            assert_eq!(key(&scanned), key(&index), "{compression}");
            assert!(scanned.notes.is_empty(), "{:?}", scanned.notes);
        }
    }
}

#[test]
fn an_index_shorter_than_the_header_announces_is_refused() {
    let bytes = tiny_bag("none", true);
    let mut f = file(&bytes);
    let header = bag_header(&mut f).unwrap();
    // The last chunk info cut off at a record boundary: the index still parses.
    let cut = &bytes[..bytes.len() - 140];
    let mut short = file(cut);
    let got = read_index(&mut short, &header, header.index_pos.unwrap());
    assert!(got.is_err(), "{got:?}");
}

#[test]
fn bad_chunks_are_problems_naming_what_broke() {
    let bytes = tiny_bag("lz4", true);
    let mut f = file(&bytes);
    let header = bag_header(&mut f).unwrap();
    let at = header.data_start;
    let (mut raw, mut out) = (Vec::new(), Vec::new());
    let edit = |from: &[u8], to: &[u8]| {
        let mut b = bytes.clone();
        let i = b.windows(from.len()).position(|w| w == from).unwrap();
        b[i..i + to.len()].copy_from_slice(to);
        b
    };
    let unknown = edit(b"compression=lz4", b"compression=zz4");
    let e = read_chunk(&mut file(&unknown), at, &mut raw, &mut out).unwrap_err();
    assert!(e.contains("unknown compression `zz4`"), "{e}");
    let mut huge = bytes.clone();
    let size = huge.windows(5).position(|w| w == b"size=").unwrap() + 5;
    huge[size..size + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = read_chunk(&mut file(&huge), at, &mut raw, &mut out).unwrap_err();
    assert!(e.contains("over the limit"), "{e}");
    huge[size..size + 4].copy_from_slice(&1000u32.to_le_bytes());
    let e = read_chunk(&mut file(&huge), at, &mut raw, &mut out).unwrap_err();
    assert!(e.contains("announces 1000"), "{e}");
    let e = read_chunk(
        &mut file(&bytes[..at as usize + 60]),
        at,
        &mut raw,
        &mut out,
    )
    .unwrap_err();
    assert!(e.contains("past the end of the file"), "{e}");
}

/// Runs every reader of this module over `bytes`, ignoring the results: only panics matter.
fn exercise(bytes: &[u8]) {
    let mut f = file(bytes);
    let Ok(header) = bag_header(&mut f) else {
        return;
    };
    let scanned = scan_chunks(&mut f, &header, bytes.len() as u64);
    let _ = messages(bytes, &scanned);
    if let Some(at) = header.index_pos
        && let Ok(index) = read_index(&mut f, &header, at)
    {
        let _ = messages(bytes, &index);
    }
}

#[test]
fn every_truncation_and_corrupted_byte_is_read_without_a_panic() {
    for compression in ["none", "bz2", "lz4"] {
        let bytes = tiny_bag(compression, true);
        for cut in 0..bytes.len() {
            exercise(&bytes[..cut]);
        }
        // Every byte after the padding set to 0xff, then to 0x00.
        for i in (0..bytes.len()).filter(|&i| !(200..4109).contains(&i)) {
            for v in [0x00, 0xff] {
                let mut b = bytes.clone();
                b[i] = v;
                exercise(&b);
            }
        }
    }
}

/// A reader whose next read moves 2 bytes on and fails, once.
struct Flaky {
    inner: Cursor<Vec<u8>>,
    fail: bool,
}

impl std::io::Read for Flaky {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if std::mem::take(&mut self.fail) {
            self.inner.set_position(self.inner.position() + 2);
            return Err(std::io::Error::other("flaky"));
        }
        self.inner.read(buf)
    }
}

impl std::io::Seek for Flaky {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(to)
    }
}

#[test]
fn a_failed_read_is_followed_by_a_seek_not_a_read_from_where_it_stopped() {
    let bytes = tiny_bag("none", true);
    let len = bytes.len() as u64;
    let mut f = Ros1File::new(
        Flaky {
            inner: Cursor::new(bytes),
            fail: false,
        },
        len,
    );
    let header = bag_header(&mut f).unwrap();
    let first = f.record(header.data_start).unwrap();
    f.inner.fail = true;
    let e = f.record(header.data_start).unwrap_err();
    assert!(e.contains("flaky"), "{e}");
    let again = f.record(header.data_start).unwrap();
    assert_eq!(
        (again.op, again.header, again.data_len),
        (first.op, first.header, first.data_len)
    );
}

/// Issue 49, item 1: a bz2 or lz4 chunk that announces, and truly holds, far more bytes than
/// a thousand times its compressed length (16 MiB of zeros in 45 bytes) is refused
/// from its header, before anything is inflated; the same records at a real ratio read.
#[test]
fn a_decompression_bomb_is_refused_from_its_header() {
    let zeros = vec![0u8; 16 << 20];
    for compression in ["bz2", "lz4"] {
        let data = compress(compression, &zeros);
        // bz2 packs the zeros hundreds of thousands to one; an lz4 frame some 250 to one.
        let bomb = (data.len() as u64) * crate::limits::MAX_RATIO < zeros.len() as u64;
        assert_eq!(
            bomb,
            compression == "bz2",
            "{compression}: {} bytes",
            data.len()
        );
        let chunk = |size: u32, data: &[u8]| {
            let mut bytes = b"#ROSBAG V2.0\n".to_vec();
            bytes.extend(record(
                &[
                    field("op", &[OP_CHUNK]),
                    field("compression", compression.as_bytes()),
                    field("size", &size.to_le_bytes()),
                ],
                data,
            ));
            bytes
        };
        let bytes = chunk(zeros.len() as u32, &data);
        let (mut raw, mut out) = (Vec::new(), Vec::new());
        let result = read_chunk(&mut file(&bytes), 13, &mut raw, &mut out);
        if bomb {
            let e = result.unwrap_err();
            assert!(e.contains("decompression bomb"), "{compression}: {e}");
            assert!(out.is_empty(), "nothing inflated");
        } else {
            // Within the ratio: read whole.
            result.unwrap();
            assert_eq!(out.len(), zeros.len());
        }
    }
}

/// Issue 49, item 1, the whole file: chunks each within their own rule (a megabyte of zeros,
/// under the free megabyte any chunk may hold) add up, on one pass, to a refusal once the
/// file's allowance beyond the ratio is spent (here lowered to 3 MiB).
#[test]
fn many_small_bombs_are_refused_once_the_file_allowance_is_spent() {
    for compression in ["bz2", "lz4"] {
        let mut records = connection_record(0, "/a");
        records.extend(record(
            &[
                field("op", &[OP_MESSAGE]),
                field("conn", &0u32.to_le_bytes()),
                field("time", &time(S)),
            ],
            &vec![0u8; 1_000_000],
        ));
        assert!((records.len() as u64) < crate::limits::FREE_BYTES);
        let data = compress(compression, &records);
        let mut bytes = b"#ROSBAG V2.0\n".to_vec();
        let mut starts = Vec::new();
        for _ in 0..6 {
            starts.push(bytes.len() as u64);
            bytes.extend(record(
                &[
                    field("op", &[OP_CHUNK]),
                    field("compression", compression.as_bytes()),
                    field("size", &(records.len() as u32).to_le_bytes()),
                ],
                &data,
            ));
        }
        // bz2 packs the megabyte in some hundred bytes, far beyond the ratio; lz4 some 250 to
        // one, within it: its chunks cost nothing and all six read.
        let beyond =
            (records.len() as u64).saturating_sub(data.len() as u64 * crate::limits::MAX_RATIO);
        assert_eq!(
            beyond > 0,
            compression == "bz2",
            "{compression}: {}",
            data.len()
        );
        let mut f = file(&bytes);
        f.inflation = crate::limits::Inflation::with_allowance(3 << 20);
        let (mut raw, mut out) = (Vec::new(), Vec::new());
        let fit = (3u64 << 20).checked_div(beyond).unwrap_or(u64::MAX);
        for (k, &at) in starts.iter().enumerate() {
            let result = read_chunk(&mut f, at, &mut raw, &mut out);
            if (k as u64) < fit {
                result.unwrap();
                assert_eq!(out.len(), records.len());
            } else {
                let e = result.unwrap_err();
                assert!(
                    e.contains("spread over many small chunks"),
                    "{compression} {k}: {e}"
                );
                break;
            }
        }
        assert_eq!(
            fit < 6,
            compression == "bz2",
            "{compression}: {fit} fit, {beyond} beyond each"
        );
        // A new pass (a new handle) starts its own total.
        let mut again = file(&bytes);
        read_chunk(&mut again, starts[0], &mut raw, &mut out).unwrap();
    }
}
