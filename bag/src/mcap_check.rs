//! Checks of MCAP bytes made before the `mcap` crate reads them, for what it does not check.
//!
//! `mcap` 0.26's linear reader subtracts the length of each record inside an uncompressed
//! chunk from what is left of the chunk without checking it (`linear_reader.rs:745`): a record
//! that runs past the end of its chunk panics with overflow checks on (debug builds, tests,
//! fuzzing) and silently reads the next records as the chunk's without them. Found by
//! `bag_mcap`. Uncompressed chunks are therefore walked here first; a bad one is an error
//! (indexed reading) or where a linear read stops (a file read in file order keeps what comes
//! before it, as a file cut short does).

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use crate::{BagError, MAX_MCAP_RECORD, Result};

/// The records of a chunk (opcode, `u64` length, body, …) fit in it exactly.
pub(crate) fn plain_records_fit(mut records: &[u8]) -> bool {
    while !records.is_empty() {
        let Some(len) = records
            .get(1..9)
            .and_then(|b| <[u8; 8]>::try_from(b).ok())
            .map(u64::from_le_bytes)
        else {
            return false;
        };
        match usize::try_from(len)
            .ok()
            .and_then(|len| len.checked_add(9))
            .and_then(|end| records.get(end..))
        {
            Some(rest) => records = rest,
            None => return false,
        }
    }
    true
}

/// The body of a chunk record (after opcode and length): its compression and its records.
/// `None` when the body is too short for its own fields.
pub(crate) fn chunk_parts(body: &[u8]) -> Option<(&[u8], &[u8])> {
    // message_start_time, message_end_time, uncompressed_size (u64 each), uncompressed_crc (u32).
    let name_len = u32::from_le_bytes(body.get(28..32)?.try_into().ok()?) as usize;
    let name = body.get(32..32usize.checked_add(name_len)?)?;
    let at = 32 + name_len;
    let records_len = u64::from_le_bytes(body.get(at..at + 8)?.try_into().ok()?);
    let records = body.get(at + 8..)?;
    let records = records.get(..usize::try_from(records_len).ok()?)?;
    Some((name, records))
}

/// The byte offset of the first uncompressed chunk of the data section whose records do not
/// fit in it (or whose own fields do not), walking the top-level records from the magic to
/// `DataEnd`; `None` when there is none. A record running past the file ends the walk (the
/// reader reports it).
fn first_bad_plain_chunk(file: &mut File, size: u64) -> std::io::Result<Option<u64>> {
    let mut at = 8u64;
    loop {
        let mut head = [0u8; 9];
        if at.saturating_add(9) > size {
            return Ok(None);
        }
        file.seek(SeekFrom::Start(at))?;
        file.read_exact(&mut head)?;
        let op = head[0];
        let len = u64::from_le_bytes([
            head[1], head[2], head[3], head[4], head[5], head[6], head[7], head[8],
        ]);
        if op == mcap::records::op::DATA_END || op == mcap::records::op::FOOTER {
            return Ok(None);
        }
        let end = at.saturating_add(9).saturating_add(len);
        if end > size {
            return Ok(None);
        }
        if op == mcap::records::op::CHUNK && len <= MAX_MCAP_RECORD as u64 {
            // The fixed fields and the compression's name length first: only an uncompressed
            // chunk is read whole.
            let mut body = Vec::new();
            (&mut *file).take(len.min(32)).read_to_end(&mut body)?;
            let plain = body.get(28..32) == Some(&[0, 0, 0, 0][..]);
            if plain {
                (&mut *file).take(len - 32).read_to_end(&mut body)?;
            }
            if plain && !chunk_parts(&body).is_some_and(|(_, records)| plain_records_fit(records)) {
                return Ok(Some(at));
            }
        }
        at = end;
    }
}

/// Messages of an MCAP file in file order, up to where [`linear_reader`] stops.
pub(crate) type LinearReader = mcap::io::MessageReader<BufReader<std::io::Take<File>>>;

/// A linear reader of the MCAP file at `path`, which stops before the first uncompressed chunk
/// whose records run past its end, and that chunk's byte offset.
pub(crate) fn linear_reader(path: &Path) -> Result<(LinearReader, Option<u64>)> {
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    let bad = first_bad_plain_chunk(&mut file, size).map_err(io)?;
    file.seek(SeekFrom::Start(0)).map_err(io)?;
    let reader = mcap::io::MessageReader::new_with_options(
        BufReader::new(file.take(bad.unwrap_or(u64::MAX))),
        crate::read::mcap_options(),
    );
    Ok((reader, bad))
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
    fn records_fit_their_chunk_exactly_or_not() {
        let record = |op: u8, body: &[u8]| {
            let mut r = vec![op];
            r.extend((body.len() as u64).to_le_bytes());
            r.extend(body);
            r
        };
        let mut two = record(5, b"abc");
        two.extend(record(5, b""));
        assert!(plain_records_fit(&two));
        assert!(plain_records_fit(&[]));
        // Cut anywhere inside: does not fit.
        for cut in 1..two.len() {
            if cut == 12 {
                continue; // the end of the first record: one whole record
            }
            assert!(!plain_records_fit(&two[..cut]), "cut at {cut}");
        }
        // A length past the end, and one that overflows.
        let mut long = record(5, b"abc");
        long[1] = 200;
        assert!(!plain_records_fit(&long));
        long[1..9].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(!plain_records_fit(&long));
    }
}
