//! The record layer of ROS 1 bags (format 2.0), read over `Read + Seek` one record at a time:
//! the bag header, any record's header and data, connection records, chunk records (`none`,
//! `bz2`, `lz4`) and the connection and message-data records inside a chunk (the index
//! section and the linear scan built on these are in `ros1_index.rs`). Every
//! length is checked against the file's size (or the chunk's) and a cap before anything is
//! allocated; a problem is a `String` naming the byte where it is, never a panic.
//!
//! A record is `header_len: u32`, `header` (fields `len: u32`, `name=value`), `data_len: u32`,
//! `data`; every header has `op` (one byte). Little-endian throughout; times are `sec: u32,
//! nsec: u32`.

use std::io::{Read, Seek, SeekFrom};

/// A message-data record.
pub(crate) const OP_MESSAGE: u8 = 0x02;
/// The bag header record.
const OP_BAG_HEADER: u8 = 0x03;
/// An index-data record (after each chunk: the times and offsets of one connection's messages).
pub(crate) const OP_INDEX_DATA: u8 = 0x04;
/// A chunk record.
pub(crate) const OP_CHUNK: u8 = 0x05;
/// A chunk-info record (index section).
pub(crate) const OP_CHUNK_INFO: u8 = 0x06;
/// A connection record (inside chunks, and again in the index section).
pub(crate) const OP_CONNECTION: u8 = 0x07;

/// The largest decompressed ROS 1 chunk read: 1 GiB. `rosbag record` writes chunks of 768 KB;
/// a larger `size` (or a longer record) is a corrupt header, refused before anything is
/// allocated.
pub(crate) const MAX_ROS1_CHUNK: u64 = 1 << 30;

/// The longest record header read: 1 MiB (recorders write headers of tens of bytes; the long
/// texts of a connection, its message definition, are in its data).
const MAX_HEADER: u64 = 1 << 20;

/// What went wrong and where (the text names the byte).
pub(crate) type Problem = String;

/// The `name=value` fields of a record header, or of a connection record's data.
pub(crate) struct Fields<'a>(pub(crate) &'a [u8]);

impl<'a> Iterator for Fields<'a> {
    type Item = Result<(&'a [u8], &'a [u8]), Problem>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.0.is_empty() {
            return None;
        }
        let Some((len, rest)) = self.0.split_first_chunk::<4>() else {
            self.0 = &[];
            return Some(Err("a field's length is cut off".to_owned()));
        };
        let len = u32::from_le_bytes(*len) as usize;
        let Some((field, rest)) = rest.split_at_checked(len) else {
            self.0 = &[];
            return Some(Err(format!(
                "a field of {len} bytes runs past the end of its header"
            )));
        };
        self.0 = rest;
        Some(match field.iter().position(|&b| b == b'=') {
            Some(eq) => Ok((&field[..eq], &field[eq + 1..])),
            None => Err("a field without `=`".to_owned()),
        })
    }
}

/// A field's value as a `u32`.
pub(crate) fn u32_of(name: &[u8], value: &[u8]) -> Result<u32, Problem> {
    <[u8; 4]>::try_from(value)
        .map(u32::from_le_bytes)
        .map_err(|_| bad_width(name, value, 4))
}

/// A field's value as a `u64`.
pub(crate) fn u64_of(name: &[u8], value: &[u8]) -> Result<u64, Problem> {
    <[u8; 8]>::try_from(value)
        .map(u64::from_le_bytes)
        .map_err(|_| bad_width(name, value, 8))
}

/// A time field (`sec: u32, nsec: u32`) in nanoseconds since the UNIX epoch.
pub(crate) fn time_of(name: &[u8], value: &[u8]) -> Result<u64, Problem> {
    let v = u64_of(name, value)?;
    Ok((v & 0xffff_ffff) * 1_000_000_000 + (v >> 32))
}

fn bad_width(name: &[u8], value: &[u8], want: usize) -> Problem {
    format!(
        "field `{}` has {} bytes, not {want}",
        String::from_utf8_lossy(name),
        value.len()
    )
}

/// The `op` of a header.
fn op_of(header: &[u8]) -> Result<u8, Problem> {
    for field in Fields(header) {
        if let (b"op", value) = field? {
            return match value {
                [op] => Ok(*op),
                _ => Err(bad_width(b"op", value, 1)),
            };
        }
    }
    Err("a record header without `op`".to_owned())
}

/// A record as found in the file: its header read, its data left where it is.
#[derive(Debug)]
pub(crate) struct Record {
    /// The byte of the record.
    pub at: u64,
    /// Its op.
    pub op: u8,
    /// Its header's fields.
    pub header: Vec<u8>,
    /// The byte of its data.
    pub data_at: u64,
    /// The length of its data.
    pub data_len: u64,
}

impl Record {
    /// The byte after the record.
    pub fn end(&self) -> u64 {
        self.data_at + self.data_len
    }
}

/// A bag file: a reader, where it is, and the file's length.
pub(crate) struct Ros1File<R> {
    inner: R,
    pos: u64,
    len: u64,
    /// This pass's chunks against the whole-file allowance of inflation.
    pub(crate) inflation: crate::limits::Inflation,
}

impl<R: Read + Seek> Ros1File<R> {
    /// `inner` at byte 0, of `len` bytes.
    pub fn new(inner: R, len: u64) -> Self {
        Self {
            inner,
            pos: 0,
            len,
            inflation: crate::limits::Inflation::default(),
        }
    }

    /// The file's length.
    pub fn len(&self) -> u64 {
        self.len
    }

    fn goto(&mut self, at: u64) -> Result<(), Problem> {
        if at != self.pos {
            self.inner
                .seek(SeekFrom::Start(at))
                .map_err(|e| format!("seeking to byte {at}: {e}"))?;
            self.pos = at;
        }
        Ok(())
    }

    /// Reads `n` bytes at byte `at` into `buf` (cleared first), `n` checked against the file.
    pub(crate) fn read_into(
        &mut self,
        at: u64,
        n: u64,
        buf: &mut Vec<u8>,
        what: &str,
    ) -> Result<(), Problem> {
        buf.clear();
        if at.checked_add(n).is_none_or(|end| end > self.len) {
            return Err(format!(
                "{what} of {n} bytes at byte {at} runs past the end of the file ({} bytes)",
                self.len
            ));
        }
        self.goto(at)?;
        // `n` is at most the file's size, and the callers cap it.
        buf.reserve_exact(n as usize);
        // Where the reader is after a failed read is not known: the next read seeks.
        self.pos = u64::MAX;
        let got = (&mut self.inner)
            .take(n)
            .read_to_end(buf)
            .map_err(|e| format!("reading {what} at byte {at}: {e}"))?;
        self.pos = at + got as u64;
        if (got as u64) < n {
            return Err(format!(
                "{what} at byte {at}: the file ends after {got} of its {n} bytes"
            ));
        }
        Ok(())
    }

    fn read_u32(&mut self, at: u64, what: &str) -> Result<u32, Problem> {
        if at.checked_add(4).is_none_or(|end| end > self.len) {
            return Err(format!(
                "{what} at byte {at} runs past the end of the file ({} bytes)",
                self.len
            ));
        }
        self.goto(at)?;
        let mut b = [0; 4];
        // Where the reader is after a failed read is not known: the next read seeks.
        self.pos = u64::MAX;
        self.inner
            .read_exact(&mut b)
            .map_err(|e| format!("reading {what} at byte {at}: {e}"))?;
        self.pos = at + 4;
        Ok(u32::from_le_bytes(b))
    }

    /// The record at byte `at`: its header read (at most 1 MiB), its data's place checked
    /// against the file.
    pub fn record(&mut self, at: u64) -> Result<Record, Problem> {
        let record = self.record_head(at)?;
        if record.end() > self.len {
            return Err(cut_record(&record, self.len));
        }
        Ok(record)
    }

    /// The record at byte `at`, its data's place not checked (it may run past the file).
    pub(crate) fn record_head(&mut self, at: u64) -> Result<Record, Problem> {
        let header_len = u64::from(self.read_u32(at, "record header length")?);
        if header_len > MAX_HEADER {
            return Err(format!(
                "record at byte {at}: a header of {header_len} bytes, over the limit of {MAX_HEADER}"
            ));
        }
        let mut header = Vec::new();
        self.read_into(at + 4, header_len, &mut header, "record header")?;
        let op = op_of(&header).map_err(|e| format!("record at byte {at}: {e}"))?;
        let data_len = u64::from(self.read_u32(at + 4 + header_len, "record data length")?);
        let data_at = at + 8 + header_len;
        Ok(Record {
            at,
            op,
            header,
            data_at,
            data_len,
        })
    }

    /// The data of `record` into `buf`, capped at [`MAX_ROS1_CHUNK`].
    pub fn data(&mut self, record: &Record, buf: &mut Vec<u8>) -> Result<(), Problem> {
        if record.data_len > MAX_ROS1_CHUNK {
            return Err(format!(
                "record at byte {}: {} bytes of data, over the limit of {MAX_ROS1_CHUNK}",
                record.at, record.data_len
            ));
        }
        self.read_into(record.data_at, record.data_len, buf, "record data")
    }
}

pub(crate) fn cut_record(record: &Record, len: u64) -> Problem {
    format!(
        "record at byte {} (op {:#04x}): its {} bytes of data run past the end of the file ({len} \
         bytes)",
        record.at, record.op, record.data_len
    )
}

/// The bag header record: where the index is, what it should hold, where the chunks start.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BagHeader {
    /// `index_pos` (`None`: no such field).
    pub index_pos: Option<u64>,
    /// `conn_count`, the connections the index should list.
    pub conn_count: Option<u32>,
    /// `chunk_count`, the chunk infos the index should list.
    pub chunk_count: Option<u32>,
    /// The byte after the header record (and its padding): the first chunk.
    pub data_start: u64,
}

/// Reads the bag header record (after the 13 bytes of `#ROSBAG V2.0\n`). Its data (padding)
/// is not read, but where it ends is where the chunks start.
pub(crate) fn bag_header<R: Read + Seek>(file: &mut Ros1File<R>) -> Result<BagHeader, Problem> {
    let len = file.len();
    let header_len = u64::from(
        file.read_u32(13, "bag header length")
            .map_err(|_| format!("file of {len} bytes ends inside its header"))?,
    );
    if header_len > MAX_HEADER || 17 + header_len > len {
        return Err(format!(
            "bag header of {header_len} bytes runs past the file"
        ));
    }
    let mut header = Vec::new();
    file.read_into(17, header_len, &mut header, "bag header")?;
    let padding = u64::from(
        file.read_u32(17 + header_len, "bag header data length")
            .map_err(|_| "bag header record ends before its data length".to_owned())?,
    );
    let data_start = 21 + header_len + padding;
    let mut h = BagHeader {
        index_pos: None,
        conn_count: None,
        chunk_count: None,
        data_start,
    };
    let mut op = None;
    for field in Fields(&header) {
        let (name, value) = field.map_err(|e| format!("bag header: {e}"))?;
        let bad = |e| format!("bag header: {e}");
        match name {
            b"op" => op = Some(value),
            b"index_pos" => h.index_pos = Some(u64_of(name, value).map_err(bad)?),
            b"conn_count" => h.conn_count = Some(u32_of(name, value).map_err(bad)?),
            b"chunk_count" => h.chunk_count = Some(u32_of(name, value).map_err(bad)?),
            _ => {}
        }
    }
    if op != Some(&[OP_BAG_HEADER][..]) {
        return Err(format!(
            "the first record (byte 13) is not a bag header ({}, not {OP_BAG_HEADER:#04x})",
            op.map_or("no op".to_owned(), |v| format!("op {v:02x?}"))
        ));
    }
    if let Some(index_pos) = h.index_pos
        && index_pos != 0
        && index_pos <= len
        && index_pos < data_start
    {
        return Err(format!(
            "index_pos {index_pos} is before the chunk section, which starts at byte \
             {data_start} (after the bag header and its {padding} bytes of data)"
        ));
    }
    if data_start > len {
        return Err(format!(
            "the bag header's {padding} bytes of data run past the end of the file ({len} bytes)"
        ));
    }
    Ok(h)
}

/// A connection: a topic with its type, as its connection record has it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Connection {
    /// Its id, which message records name.
    pub id: u32,
    /// Its topic (the data's `topic`, else the header's).
    pub topic: String,
    /// Its message type (`sensor_msgs/LaserScan`).
    pub type_name: String,
    /// The MD5 sum of its definition, as recorded (32 lower-case hex digits, or `*`).
    pub md5sum: Option<String>,
    /// The full text of its message definition.
    pub message_definition: String,
    /// The publishing node, where recorded.
    pub callerid: Option<String>,
    /// Whether the publisher latched.
    pub latching: bool,
}

/// A connection record from its header and data.
pub(crate) fn connection(header: &[u8], data: &[u8]) -> Result<Connection, Problem> {
    let (mut id, mut storage_topic) = (None, None);
    for field in Fields(header) {
        match field? {
            (b"conn", v) => id = Some(u32_of(b"conn", v)?),
            (b"topic", v) => storage_topic = Some(v),
            _ => {}
        }
    }
    let id = id.ok_or("a connection record without `conn`")?;
    let text = |v: &[u8]| String::from_utf8_lossy(v).into_owned();
    let mut c = Connection {
        id,
        topic: storage_topic.map(text).unwrap_or_default(),
        type_name: String::new(),
        md5sum: None,
        message_definition: String::new(),
        callerid: None,
        latching: false,
    };
    for field in Fields(data) {
        match field.map_err(|e| format!("connection {id}: {e}"))? {
            (b"topic", v) => c.topic = text(v),
            (b"type", v) => c.type_name = text(v),
            (b"md5sum", v) => c.md5sum = Some(text(v).to_ascii_lowercase()),
            (b"message_definition", v) => c.message_definition = text(v),
            (b"callerid", v) => c.callerid = Some(text(v)),
            (b"latching", v) => c.latching = v == b"1",
            _ => {}
        }
    }
    if c.topic.is_empty() {
        return Err(format!("connection {id} names no topic"));
    }
    Ok(c)
}

/// Reads the chunk record at byte `at` and decompresses its records into `out` (its
/// compressed bytes go through `raw`; both are reused between chunks).
pub(crate) fn read_chunk<R: Read + Seek>(
    file: &mut Ros1File<R>,
    at: u64,
    raw: &mut Vec<u8>,
    out: &mut Vec<u8>,
) -> Result<(), Problem> {
    let record = file.record(at)?;
    chunk_data(file, &record, raw, out)
}

/// The decompressed records of the chunk `record` into `out`.
pub(crate) fn chunk_data<R: Read + Seek>(
    file: &mut Ros1File<R>,
    record: &Record,
    raw: &mut Vec<u8>,
    out: &mut Vec<u8>,
) -> Result<(), Problem> {
    if record.op != OP_CHUNK {
        return Err(format!(
            "a record of op {:#04x} where a chunk should be",
            record.op
        ));
    }
    let (mut compression, mut size): (&[u8], Option<u64>) = (b"none", None);
    for field in Fields(&record.header) {
        match field? {
            (b"compression", v) => compression = v,
            (b"size", v) => size = Some(u64::from(u32_of(b"size", v)?)),
            _ => {}
        }
    }
    let size = match compression {
        // Stored bytes: the record's own length is what is read.
        b"none" => {
            let size = size.unwrap_or(record.data_len);
            if size > MAX_ROS1_CHUNK {
                return Err(format!(
                    "announces {size} decompressed bytes, over the limit of {MAX_ROS1_CHUNK}"
                ));
            }
            size
        }
        // Within the announced size, the cap and the decompression-bomb ratio, checked on the
        // header before anything is inflated (`crate::limits`).
        // And, with the chunks before it, within the whole file's allowance.
        b"bz2" | b"lz4" => {
            let size = crate::limits::decompressed_limit(size, record.data_len, MAX_ROS1_CHUNK)?;
            file.inflation.charge(record.data_len, size)?;
            size
        }
        // Refused below, by name.
        _ => size.unwrap_or(MAX_ROS1_CHUNK),
    };
    let decoded = match compression {
        b"none" => {
            file.data(record, out)?;
            return check_size(out.len(), size);
        }
        b"bz2" | b"lz4" => {
            file.data(record, raw)?;
            out.clear();
            out.reserve(size.min(4 * raw.len() as u64 + 4096) as usize);
            // At most one byte more than announced is decompressed: a longer chunk is refused
            // without inflating the rest.
            if compression == b"bz2" {
                bzip2::read::BzDecoder::new(raw.as_slice())
                    .take(size + 1)
                    .read_to_end(out)
            } else {
                lz4::Decoder::new(raw.as_slice()).and_then(|d| d.take(size + 1).read_to_end(out))
            }
        }
        other => {
            return Err(format!(
                "unknown compression `{}`",
                String::from_utf8_lossy(other)
            ));
        }
    };
    decoded.map_err(|e| format!("{} data: {e}", String::from_utf8_lossy(compression)))?;
    check_size(out.len(), size)
}

fn check_size(got: usize, size: u64) -> Result<(), Problem> {
    if got as u64 != size {
        return Err(format!(
            "{got} bytes of records where its header announces {size}"
        ));
    }
    Ok(())
}

/// A record inside a chunk.
pub(crate) enum Inner<'a> {
    /// A connection record.
    Connection(Connection),
    /// A message: its connection, log time (ns) and bytes.
    Message {
        /// The connection id.
        conn: u32,
        /// The log time, ns.
        time: u64,
        /// Its serialised bytes.
        data: &'a [u8],
    },
}

/// Calls `each` on every record of the decompressed chunk `records`, in order; a problem names
/// the byte within the decompressed chunk.
pub(crate) fn chunk_records<'a>(
    records: &'a [u8],
    mut each: impl FnMut(Inner<'a>) -> Result<(), Problem>,
) -> Result<(), Problem> {
    let mut rest = records;
    while !rest.is_empty() {
        let at = records.len() - rest.len();
        let within = |e: Problem| format!("record at byte {at} of the decompressed chunk: {e}");
        let (header, data, after) = split_record(rest).map_err(within)?;
        rest = after;
        let (mut op, mut conn, mut time) = (None, None, None);
        for field in Fields(header) {
            let (name, v) = field.map_err(within)?;
            match name {
                b"op" => op = v.first().copied().filter(|_| v.len() == 1),
                b"conn" => conn = Some(u32_of(name, v).map_err(within)?),
                b"time" => time = Some(time_of(name, v).map_err(within)?),
                _ => {}
            }
        }
        match (op, conn, time) {
            (Some(OP_MESSAGE), Some(conn), Some(time)) => {
                each(Inner::Message { conn, time, data })?
            }
            (Some(OP_MESSAGE), ..) => {
                return Err(within("a message without `conn` or `time`".into()));
            }
            (Some(OP_CONNECTION), ..) => {
                each(Inner::Connection(connection(header, data).map_err(within)?))?
            }
            (Some(op), ..) => {
                return Err(within(format!("a record of op {op:#04x} inside a chunk")));
            }
            (None, ..) => return Err(within("a record without a one-byte op".to_owned())),
        }
    }
    Ok(())
}

/// A little-endian `u32` off the front of `b`, and the rest.
fn take_u32(b: &[u8]) -> Option<(u32, &[u8])> {
    b.split_first_chunk::<4>()
        .map(|(n, rest)| (u32::from_le_bytes(*n), rest))
}

/// A record's header, its data, and what follows it.
type Split<'a> = (&'a [u8], &'a [u8], &'a [u8]);

/// Splits `bytes` into the first record's header and data, and what follows.
fn split_record(bytes: &[u8]) -> Result<Split<'_>, Problem> {
    let (n, rest) = take_u32(bytes).ok_or("a header length cut off")?;
    let (header, rest) = rest
        .split_at_checked(n as usize)
        .ok_or_else(|| format!("a header of {n} bytes runs past the end of the chunk"))?;
    let (n, rest) = take_u32(rest).ok_or("a data length cut off")?;
    let (data, rest) = rest
        .split_at_checked(n as usize)
        .ok_or_else(|| format!("{n} bytes of data run past the end of the chunk"))?;
    Ok((header, data, rest))
}

#[cfg(test)]
#[path = "ros1_records/tests.rs"]
mod tests;
