//! Checks of MCAP bytes made before the `mcap` crate reads them, for what it does not check.
//!
//! Two things `mcap` 0.26 trusts, both found by `bag_mcap`:
//! - the length of each record inside an uncompressed chunk is subtracted from what is left of
//!   the chunk unchecked (`linear_reader.rs:745`): a record running past its chunk panics with
//!   overflow checks on (debug builds, tests, fuzzing) and misreads the next records without;
//! - `parse_record` allocates each length-prefixed string, byte array and map at the length
//!   the file claims (`records.rs:142`, through `binrw`): a 4 GiB string length inside a
//!   record of a few bytes allocates 4 GiB.
//!
//! So uncompressed chunks are walked first, and every record is checked here ([`record_fits`])
//! before `mcap` parses it: the file-order reader of this module ([`LinearMessages`], in place
//! of `mcap::io::MessageReader`), the summary before `mcap`'s summary reader, and the indexed
//! reader (which parses only message records, whose one variable field is the rest of the
//! record).

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use crate::{BagError, Result};

/// The longest MCAP record (a chunk, compressed or not) read: 1 GiB. Recorders write chunks of
/// a few MB; a length beyond this is a corrupt file, refused before anything is allocated.
pub(crate) const MAX_MCAP_RECORD: usize = 1 << 30;

/// How MCAP files are read: chunk CRCs checked (where the writer stored one), records capped
/// at [`MAX_MCAP_RECORD`].
pub(crate) fn mcap_options() -> mcap::sans_io::LinearReaderOptions {
    mcap::sans_io::LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_record_length_limit(MAX_MCAP_RECORD)
}

/// The records of an uncompressed chunk (opcode, `u64` length, body, …) fit in the
/// `declared` length of its records section exactly, as far as the file shows: `head(at)` is
/// the opcode and length of the record at byte `at` of the section, `None` past the file's
/// end (a file cut short: the reader meets the end first, an error, not a panic).
fn records_fit(
    declared: u64,
    mut head: impl FnMut(u64) -> std::io::Result<Option<[u8; 9]>>,
) -> std::io::Result<bool> {
    let mut at = 0u64;
    while at < declared {
        let left = declared - at;
        if left < 9 {
            return Ok(false);
        }
        let Some(h) = head(at)? else {
            return Ok(true);
        };
        let len = u64::from_le_bytes([h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]]);
        if len > left - 9 {
            return Ok(false);
        }
        at += 9 + len;
    }
    Ok(true)
}

/// [`records_fit`] of the records section `records` (its bytes that the file holds) of
/// `declared` bytes.
pub(crate) fn plain_records_fit(records: &[u8], declared: u64) -> bool {
    records_fit(declared, |at| {
        Ok(usize::try_from(at)
            .ok()
            .and_then(|at| records.get(at..at.checked_add(9)?))
            .and_then(|b| <[u8; 9]>::try_from(b).ok()))
    })
    .unwrap_or(false)
}

/// The body of a chunk record (after opcode and length): its compression, the bytes of its
/// records section that `body` holds, and the section's declared length. `None` when the body
/// is too short for its own fields.
pub(crate) fn chunk_parts(body: &[u8]) -> Option<(&[u8], &[u8], u64)> {
    // message_start_time, message_end_time, uncompressed_size (u64 each), uncompressed_crc (u32).
    let name_len = u32::from_le_bytes(body.get(28..32)?.try_into().ok()?) as usize;
    let name = body.get(32..32usize.checked_add(name_len)?)?;
    let at = 32 + name_len;
    let declared = u64::from_le_bytes(body.get(at..at + 8)?.try_into().ok()?);
    let records = body.get(at + 8..)?;
    let held = usize::try_from(declared).map_or(records.len(), |d| d.min(records.len()));
    Some((name, &records[..held], declared))
}

/// Why the compressed chunk whose record body is `body` must not be inflated, or `None`: the
/// decompression-bomb rule of [`crate::limits`] on its header's `uncompressed_size` and the
/// length of its compressed records (an uncompressed chunk, or a body too short for its own
/// fields, is for the other checks).
pub(crate) fn chunk_bomb(body: &[u8]) -> Option<String> {
    let (uncompressed, compressed) = chunk_sizes(body)?;
    bomb(uncompressed, compressed)
}

/// `(uncompressed_size, compressed records' length)` of the compressed chunk whose record
/// body is `body`; `None` for an uncompressed chunk or a body too short for its own fields.
pub(crate) fn chunk_sizes(body: &[u8]) -> Option<(u64, u64)> {
    let word = |at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(body.get(at..at + 8)?.try_into().ok()?))
    };
    let uncompressed = word(16)?;
    let name_len = u32::from_le_bytes(body.get(28..32)?.try_into().ok()?) as usize;
    if name_len == 0 {
        return None;
    }
    Some((uncompressed, word(32usize.checked_add(name_len)?)?))
}

/// [`crate::limits::decompressed_limit`] for an MCAP chunk, its refusal as text.
fn bomb(uncompressed: u64, compressed: u64) -> Option<String> {
    crate::limits::decompressed_limit(Some(uncompressed), compressed, MAX_MCAP_RECORD as u64).err()
}

/// The byte offset of the first chunk of the data section that must not be read: an
/// uncompressed one whose records do not fit in it (or whose own fields do not), or a
/// compressed one that breaks the decompression-bomb rule ([`chunk_bomb`], with its reason),
/// walking the top-level records from the magic to `DataEnd` and the records of uncompressed
/// chunks by their headers (memory O(1)); `None` when there is none. A chunk running past the file is walked as far as the file goes;
/// another record running past it ends the walk (the reader reports it).
fn first_bad_chunk(
    file: &mut File,
    size: u64,
    mut inflation: crate::limits::Inflation,
) -> std::io::Result<Option<(u64, Option<String>)>> {
    let mut file = std::io::BufReader::new(file);
    let read_at = |file: &mut BufReader<&mut File>, at: u64, buf: &mut [u8]| {
        file.seek(SeekFrom::Start(at))?;
        match file.read_exact(buf) {
            Ok(()) => Ok(true),
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => Ok(false),
            Err(e) => Err(e),
        }
    };
    let mut at = 8u64;
    loop {
        let mut head = [0u8; 9];
        if !read_at(&mut file, at, &mut head)? {
            return Ok(None);
        }
        let op = head[0];
        let len = u64::from_le_bytes([
            head[1], head[2], head[3], head[4], head[5], head[6], head[7], head[8],
        ]);
        if op == mcap::records::op::DATA_END || op == mcap::records::op::FOOTER {
            return Ok(None);
        }
        if op == mcap::records::op::CHUNK {
            // Fixed fields, the compression's name length (0: uncompressed), the records
            // section's length.
            let mut fixed = [0u8; 40];
            let body = at + 9;
            let whole = len >= 40 && read_at(&mut file, body, &mut fixed)?;
            let name_len = u64::from(u32::from_le_bytes([
                fixed[28], fixed[29], fixed[30], fixed[31],
            ]));
            if whole && name_len > 0 {
                let word = |b: &[u8]| u64::from_le_bytes(b.try_into().unwrap_or([0; 8]));
                let mut compressed = [0u8; 8];
                if read_at(&mut file, body + 32 + name_len, &mut compressed)? {
                    let (uncompressed, compressed) = (word(&fixed[16..24]), word(&compressed));
                    // The chunk's own rule, then the whole file's allowance.
                    if let Some(why) = bomb(uncompressed, compressed)
                        .or_else(|| inflation.charge(compressed, uncompressed).err())
                    {
                        return Ok(Some((at, Some(why))));
                    }
                }
            }
            if whole && name_len == 0 {
                let declared = u64::from_le_bytes([
                    fixed[32], fixed[33], fixed[34], fixed[35], fixed[36], fixed[37], fixed[38],
                    fixed[39],
                ]);
                let records = body + 40;
                let fit = records_fit(declared, |r| {
                    let mut h = [0u8; 9];
                    Ok(read_at(&mut file, records.saturating_add(r), &mut h)?.then_some(h))
                })?;
                if !fit {
                    return Ok(Some((at, None)));
                }
            }
        }
        let end = at.saturating_add(9).saturating_add(len);
        if end > size {
            return Ok(None);
        }
        at = end;
    }
}

/// The messages of an MCAP file in file order, read through `mcap`'s sans-io linear reader
/// (framing, decompression, chunk CRCs) with every record checked by [`record_fits`] before
/// `mcap` parses it. It stops before the first uncompressed chunk whose records run past its
/// end or compressed chunk that would inflate like a bomb ([`LinearMessages::stop_error`]), at the
/// data section's end, or at the first error.
pub(crate) struct LinearMessages {
    path: std::path::PathBuf,
    file: BufReader<std::io::Take<File>>,
    reader: mcap::sans_io::LinearReader,
    channels: mcap::read::ChannelAccumulator<'static>,
    stop: Option<u64>,
    /// Why it stops there: a decompression bomb's refusal, or `None` for records running past
    /// an uncompressed chunk's end.
    stop_reason: Option<String>,
    /// Bytes left to read (to the file's end or the stop).
    left: u64,
    done: bool,
}

impl LinearMessages {
    /// A reader of the MCAP file at `path`.
    pub fn open(path: &Path) -> Result<Self> {
        let io = |source| BagError::Io {
            path: path.to_path_buf(),
            source,
        };
        let mut file = File::open(path).map_err(io)?;
        let size = file.metadata().map_err(io)?.len();
        let allowance = crate::limits::Inflation::default();
        let (stop, stop_reason) = match first_bad_chunk(&mut file, size, allowance).map_err(io)? {
            Some((at, why)) => (Some(at), why),
            None => (None, None),
        };
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        let left = stop.unwrap_or(size).min(size);
        Ok(Self {
            path: path.to_path_buf(),
            file: BufReader::new(file.take(left)),
            reader: mcap::sans_io::LinearReader::new_with_options(mcap_options()),
            channels: mcap::read::ChannelAccumulator::default(),
            stop,
            stop_reason,
            left,
            done: false,
        })
    }

    /// The error of the chunk before which reading stops, if any (naming its byte offset).
    pub fn stop_error(&self) -> Option<BagError> {
        let at = self.stop?;
        Some(match &self.stop_reason {
            Some(why) => bomb_chunk(&self.path, at, why),
            None => bad_chunk(&self.path, at),
        })
    }

    fn next_inner(&mut self) -> Option<Result<mcap::Message<'static>>> {
        let mcap_error = |source| BagError::Mcap {
            path: self.path.clone(),
            source,
        };
        loop {
            let event = match self.reader.next_event()? {
                Ok(event) => event,
                Err(e) => return Some(Err(mcap_error(e))),
            };
            let (opcode, data) = match event {
                mcap::sans_io::LinearReadEvent::ReadRequest(need) => {
                    // Never more room than the file has left: a record claiming a length near
                    // the 1 GiB cap in a small file is not allocated, it meets the file's end.
                    let room = usize::try_from(self.left).map_or(need, |left| need.min(left));
                    match self.file.read(self.reader.insert(room)) {
                        Ok(n) => {
                            self.left = self.left.saturating_sub(n as u64);
                            self.reader.notify_read(n);
                        }
                        Err(source) => {
                            return Some(Err(BagError::Io {
                                path: self.path.clone(),
                                source,
                            }));
                        }
                    }
                    continue;
                }
                mcap::sans_io::LinearReadEvent::Record { opcode, data } => (opcode, data),
            };
            // The summary repeats schemas and channels; only messages are wanted.
            if opcode == mcap::records::op::DATA_END || opcode == mcap::records::op::FOOTER {
                return None;
            }
            if !matches!(
                opcode,
                mcap::records::op::SCHEMA | mcap::records::op::CHANNEL | mcap::records::op::MESSAGE
            ) {
                continue;
            }
            if !record_fits(opcode, data) {
                return Some(Err(BagError::McapRecord {
                    path: self.path.clone(),
                    opcode,
                    length: data.len() as u64,
                }));
            }
            let record = match mcap::parse_record(opcode, data) {
                Ok(record) => record.into_owned(),
                Err(e) => return Some(Err(mcap_error(e))),
            };
            let added = match record {
                mcap::records::Record::Schema { header, data } => {
                    self.channels.add_schema(header, data)
                }
                mcap::records::Record::Channel(channel) => self.channels.add_channel(channel),
                mcap::records::Record::Message { header, data } => {
                    let Some(channel) = self.channels.get(header.channel_id) else {
                        return Some(Err(mcap_error(mcap::McapError::UnknownChannel(
                            header.sequence,
                            header.channel_id,
                        ))));
                    };
                    return Some(Ok(mcap::Message {
                        channel,
                        sequence: header.sequence,
                        log_time: header.log_time,
                        publish_time: header.publish_time,
                        data,
                    }));
                }
                _ => Ok(()),
            };
            if let Err(e) = added {
                return Some(Err(mcap_error(e)));
            }
        }
    }
}

impl Iterator for LinearMessages {
    type Item = Result<mcap::Message<'static>>;

    /// The next message; after an error, `None`. Reading up to the chunk it stops before ends
    /// with that chunk's error ([`LinearMessages::stop_error`]), not with the end of the bytes
    /// it was given.
    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let mut next = self.next_inner();
        if !matches!(next, Some(Ok(_))) && self.left == 0 {
            next = self.stop_error().map(Err).or(next);
        }
        self.done = !matches!(next, Some(Ok(_)));
        next
    }
}

/// One field of a record, as [`record_fits`] walks it.
#[derive(Clone, Copy)]
enum Field {
    /// So many bytes.
    Fixed(usize),
    /// A string: `u32` length, bytes.
    Str,
    /// Bytes with a `u32` length.
    Bytes32,
    /// Bytes with a `u64` length.
    Bytes64,
    /// A map of strings to strings: `u32` length in bytes, then key and value strings.
    StrMap,
    /// An array or map of fixed-size entries: `u32` length in bytes.
    FixedMap,
}

/// The fields of each record of the MCAP specification, up to its last length-prefixed one
/// (what follows is of fixed size, or the rest of the record).
fn layout(opcode: u8) -> &'static [Field] {
    use Field::*;
    match opcode {
        0x01 => &[Str, Str],                           // Header
        0x03 => &[Fixed(2), Str, Str, Bytes32],        // Schema
        0x04 => &[Fixed(4), Str, Str, StrMap],         // Channel
        0x06 => &[Fixed(28), Str, Bytes64],            // Chunk
        0x07 => &[Fixed(2), FixedMap],                 // MessageIndex
        0x08 => &[Fixed(32), FixedMap, Fixed(8), Str], // ChunkIndex
        0x09 => &[Fixed(16), Str, Str, Bytes64],       // Attachment
        0x0A => &[Fixed(40), Str, Str],                // AttachmentIndex
        0x0B => &[Fixed(42), FixedMap],                // Statistics
        0x0C => &[Str, StrMap],                        // Metadata
        0x0D => &[Fixed(16), Str],                     // MetadataIndex
        _ => &[], // Footer, Message, SummaryOffset, DataEnd: fixed fields (and the rest)
    }
}

/// Takes a length-prefixed field (`width`-byte length) off the front of `rest`: its contents,
/// or `None` when the length runs past `rest`.
fn prefixed<'a>(rest: &mut &'a [u8], width: usize) -> Option<&'a [u8]> {
    let head = rest.get(..width)?;
    let mut len = [0u8; 8];
    len[..width].copy_from_slice(head);
    let len = usize::try_from(u64::from_le_bytes(len)).ok()?;
    let body = rest.get(width..width.checked_add(len)?)?;
    *rest = &rest[width + len..];
    Some(body)
}

/// Whether every length-prefixed field of the record `body` of `opcode` (strings, byte
/// arrays, maps, and the strings inside maps) lies within it, so that parsing it allocates
/// no more than the record holds.
pub(crate) fn record_fits(opcode: u8, body: &[u8]) -> bool {
    let mut rest = body;
    for field in layout(opcode) {
        let ok = match *field {
            Field::Fixed(n) => match rest.get(n..) {
                Some(r) => {
                    rest = r;
                    true
                }
                None => false,
            },
            Field::Str | Field::Bytes32 | Field::FixedMap => prefixed(&mut rest, 4).is_some(),
            Field::Bytes64 => prefixed(&mut rest, 8).is_some(),
            Field::StrMap => match prefixed(&mut rest, 4) {
                Some(mut map) => {
                    let mut ok = true;
                    while ok && !map.is_empty() {
                        ok = prefixed(&mut map, 4).is_some();
                    }
                    ok
                }
                None => false,
            },
        };
        if !ok {
            return false;
        }
    }
    true
}

/// The summary section of an MCAP file of `size` bytes, checked record by record with
/// [`record_fits`]: `Err` says what is wrong, `Ok` also when there is no summary (or no
/// footer: the summary reader says so itself).
pub(crate) fn check_summary(file: &mut File, size: u64) -> std::io::Result<Result<(), String>> {
    // Footer record (opcode, length 20, summary_start, summary_offset_start, crc), magic.
    let Some(footer_at) = size.checked_sub(8 + 9 + 20) else {
        return Ok(Ok(()));
    };
    let mut footer = [0u8; 29];
    file.seek(SeekFrom::Start(footer_at))?;
    file.read_exact(&mut footer)?;
    if footer[0] != mcap::records::op::FOOTER {
        return Ok(Ok(()));
    }
    let mut start = [0u8; 8];
    start.copy_from_slice(&footer[9..17]);
    let start = u64::from_le_bytes(start);
    if start == 0 {
        return Ok(Ok(()));
    }
    if start > footer_at {
        return Ok(Err(format!(
            "the footer puts the summary at byte {start}, past the footer at {footer_at}"
        )));
    }
    let len = footer_at - start;
    if len > MAX_MCAP_RECORD as u64 {
        return Ok(Err(format!("a summary section of {len} bytes")));
    }
    let mut summary = Vec::new();
    file.seek(SeekFrom::Start(start))?;
    (&mut *file).take(len).read_to_end(&mut summary)?;
    let mut rest = summary.as_slice();
    let mut at = start;
    while !rest.is_empty() {
        let opcode = rest[0];
        let mut after = &rest[1..];
        let Some(body) = prefixed(&mut after, 8) else {
            return Ok(Err(format!(
                "the summary record at byte {at} runs past the footer"
            )));
        };
        if !record_fits(opcode, body) {
            return Ok(Err(format!(
                "the summary record at byte {at} (opcode {opcode:#04x}) has a field running past \
                 its end"
            )));
        }
        at += (rest.len() - after.len()) as u64;
        rest = after;
    }
    Ok(Ok(()))
}

/// The error of a compressed chunk refused by the decompression-bomb rule.
pub(crate) fn bomb_chunk(path: &Path, offset: u64, why: &str) -> BagError {
    BagError::McapChunk {
        path: path.to_path_buf(),
        offset,
        source: mcap::McapError::DecompressionError(why.to_owned()),
    }
}

/// The error of a chunk whose records run past its end.
pub(crate) fn bad_chunk(path: &Path, offset: u64) -> BagError {
    BagError::McapChunk {
        path: path.to_path_buf(),
        offset,
        source: mcap::McapError::UnexpectedEoc,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_whose_fields_run_past_them_do_not_fit() {
        let string = |s: &[u8]| {
            let mut v = (s.len() as u32).to_le_bytes().to_vec();
            v.extend(s);
            v
        };
        // A channel: id, schema id, topic, encoding, metadata {"a": "bc"}.
        let mut channel = vec![1, 0, 1, 0];
        channel.extend(string(b"/scan"));
        channel.extend(string(b"cdr"));
        let mut map = string(b"a");
        map.extend(string(b"bc"));
        channel.extend(string(&map));
        assert!(record_fits(0x04, &channel));
        // Every cut of it does not fit.
        for cut in 0..channel.len() {
            assert!(!record_fits(0x04, &channel[..cut]), "cut at {cut}");
        }
        // A topic length of 4 GiB in a record of 30 bytes (what `bag_mcap` found).
        let mut huge = channel.clone();
        huge[4..8].copy_from_slice(&0xFF00_001Bu32.to_le_bytes());
        assert!(!record_fits(0x04, &huge));
        // A string inside the map running past the map.
        let mut inner = channel.clone();
        let key_at = channel.len() - map.len();
        inner[key_at..key_at + 4].copy_from_slice(&100u32.to_le_bytes());
        assert!(!record_fits(0x04, &inner));
        // Records without length-prefixed fields always fit; extra bytes are allowed.
        assert!(record_fits(0x05, &[0; 3]));
        channel.extend([9, 9]);
        assert!(record_fits(0x04, &channel));
    }

    #[test]
    fn records_fit_their_chunk_exactly_or_not() {
        let record = |op: u8, body: &[u8]| {
            let mut r = vec![op];
            r.extend((body.len() as u64).to_le_bytes());
            r.extend(body);
            r
        };
        let mut two = record(5, b"abc");
        two.extend(record(5, b""));
        let n = two.len() as u64;
        assert!(plain_records_fit(&two, n));
        assert!(plain_records_fit(&[], 0));
        // Declared longer than the records: the last "record" has no room for its header.
        assert!(!plain_records_fit(&two, n + 3));
        // The file ends inside the section (a file cut short): left to the reader.
        assert!(plain_records_fit(&two[..12], n));
        // Cut anywhere inside: does not fit.
        for cut in 1..two.len() {
            if cut == 12 {
                continue; // the end of the first record: one whole record
            }
            assert!(!plain_records_fit(&two, cut as u64), "cut at {cut}");
        }
        // A length past the end, and one that overflows.
        let mut long = record(5, b"abc");
        long[1] = 200;
        assert!(!plain_records_fit(&long, long.len() as u64));
        long[1..9].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(!plain_records_fit(&long, long.len() as u64));
    }
}
