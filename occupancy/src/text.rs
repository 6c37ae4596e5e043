//! Reading line-oriented text logs: files that may be gzipped, and lines with their numbers.
//! The CARMEN reader here and the readers of `haunts-tracking` share these.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// Opens `path` for reading, un-gzipping it when it starts with the gzip magic bytes
/// (whatever its name says).
///
/// # Errors
/// The file's I/O errors.
pub fn open_maybe_gzip(path: &Path) -> std::io::Result<Box<dyn BufRead>> {
    let mut file = BufReader::new(std::fs::File::open(path)?);
    if file.fill_buf()?.starts_with(&[0x1f, 0x8b]) {
        Ok(Box::new(BufReader::new(
            flate2::bufread::MultiGzDecoder::new(file),
        )))
    } else {
        Ok(Box::new(file))
    }
}

/// Calls `f(number, line)` for every line of `reader` (numbered from 1, line ending
/// included), with `None` for a line that is not valid UTF-8, so the caller can count it.
///
/// # Errors
/// The reader's I/O errors.
///
/// ```
/// let mut seen = Vec::new();
/// haunts_occupancy::text::for_each_line(&b"a\n\xff\nb"[..], |n, line| seen.push((n, line.map(str::to_owned))))?;
/// assert_eq!(seen, [(1, Some("a\n".into())), (2, None), (3, Some("b".into()))]);
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn for_each_line(
    reader: impl Read,
    mut f: impl FnMut(usize, Option<&str>),
) -> std::io::Result<()> {
    let mut reader = BufReader::new(reader);
    let mut buf = Vec::new();
    let mut number = 0;
    loop {
        buf.clear();
        if reader.read_until(b'\n', &mut buf)? == 0 {
            return Ok(());
        }
        number += 1;
        f(number, std::str::from_utf8(&buf).ok());
    }
}
