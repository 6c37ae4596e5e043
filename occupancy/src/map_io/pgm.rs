//! PGM images (Netpbm `P5` binary and `P2` plain, 8- and 16-bit): read and write.

use std::path::Path;

use crate::{OccupancyError, PgmProblem, Result};

/// A greyscale or colour raster read from a map image, top row first.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Raster {
    pub width: usize,
    pub height: usize,
    /// Largest sample value (255 for 8-bit images).
    pub maxval: u16,
    /// Samples per pixel: 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA.
    pub channels: usize,
    /// `width · height · channels` samples, row-major, top row first.
    pub samples: Vec<u16>,
}

/// A cursor over a PGM header: whitespace and `#` comments between tokens.
struct Header<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl Header<'_> {
    fn skip_space_and_comments(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if b == b'#' {
                while self
                    .bytes
                    .get(self.pos)
                    .is_some_and(|&c| c != b'\n' && c != b'\r')
                {
                    self.pos += 1;
                }
            } else if b.is_ascii_whitespace() {
                self.pos += 1;
            } else {
                break;
            }
        }
    }

    /// The next unsigned integer token, or `None`.
    fn number(&mut self) -> Option<u32> {
        self.skip_space_and_comments();
        let start = self.pos;
        while self.bytes.get(self.pos).is_some_and(u8::is_ascii_digit) {
            self.pos += 1;
        }
        std::str::from_utf8(&self.bytes[start..self.pos])
            .ok()?
            .parse()
            .ok()
    }
}

/// Parses a PGM file's bytes; `path` only names the file in errors.
pub(crate) fn parse_pgm(bytes: &[u8], path: &Path) -> Result<Raster> {
    let err = |offset, problem| OccupancyError::Pgm {
        path: path.to_path_buf(),
        offset,
        problem,
    };
    let plain = match bytes.get(..2) {
        Some(b"P5") => false,
        Some(b"P2") => true,
        _ => return Err(err(0, PgmProblem::BadMagic)),
    };
    // The magic number ends at white space (or a comment): `P51 …` is not a PGM.
    if bytes
        .get(2)
        .is_some_and(|&b| !b.is_ascii_whitespace() && b != b'#')
    {
        return Err(err(0, PgmProblem::BadMagic));
    }
    let mut h = Header { bytes, pos: 2 };
    let field = |h: &mut Header<'_>, name| {
        h.number()
            .filter(|n| *n > 0)
            .ok_or_else(|| err(h.pos, PgmProblem::BadHeaderField { field: name }))
    };
    let width = field(&mut h, "width")? as usize;
    let height = field(&mut h, "height")? as usize;
    let maxval = field(&mut h, "maxval")?;
    if maxval > 65535 {
        return Err(err(h.pos, PgmProblem::MaxvalOutOfRange { maxval }));
    }
    let expected = width
        .checked_mul(height)
        .filter(|n| *n <= u32::MAX as usize)
        .ok_or_else(|| err(h.pos, PgmProblem::BadHeaderField { field: "width" }))?;
    let samples = if plain {
        let mut samples = Vec::with_capacity(expected.min(bytes.len()));
        for index in 0..expected {
            let at = h.pos;
            match h.number() {
                Some(v) if v <= maxval => samples.push(v as u16),
                Some(_) => return Err(err(at, PgmProblem::BadPixel { index })),
                None if h.pos >= bytes.len() => {
                    return Err(err(
                        at,
                        PgmProblem::Truncated {
                            expected,
                            found: index,
                        },
                    ));
                }
                None => return Err(err(at, PgmProblem::BadPixel { index })),
            }
        }
        samples
    } else {
        // Exactly one white-space byte separates maxval from the raster.
        if !bytes.get(h.pos).is_some_and(u8::is_ascii_whitespace) {
            return Err(err(h.pos, PgmProblem::BadHeaderField { field: "maxval" }));
        }
        let start = h.pos + 1;
        let bytes_per = if maxval > 255 { 2 } else { 1 };
        let body = bytes.get(start..).unwrap_or_default();
        let found = body.len() / bytes_per;
        if found < expected {
            return Err(err(start, PgmProblem::Truncated { expected, found }));
        }
        let samples: Vec<u16> = if bytes_per == 1 {
            body[..expected].iter().map(|&b| u16::from(b)).collect()
        } else {
            body[..2 * expected]
                .chunks_exact(2)
                .map(|c| u16::from_be_bytes([c[0], c[1]]))
                .collect()
        };
        if let Some(index) = samples.iter().position(|&s| u32::from(s) > maxval) {
            return Err(err(
                start + index * bytes_per,
                PgmProblem::BadPixel { index },
            ));
        }
        samples
    };
    Ok(Raster {
        width,
        height,
        maxval: maxval as u16,
        channels: 1,
        samples,
    })
}

/// Encodes an 8-bit binary (`P5`) PGM, top row first.
pub(crate) fn encode_pgm(width: usize, height: usize, pixels: &[u8]) -> Vec<u8> {
    let mut out = format!("P5\n# CREATOR: haunts-occupancy\n{width} {height}\n255\n").into_bytes();
    out.extend_from_slice(pixels);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(bytes: &[u8]) -> Result<Raster> {
        parse_pgm(bytes, Path::new("t.pgm"))
    }

    #[test]
    fn reads_p5_with_comments_and_p2_and_16_bit() {
        let r = parse(b"P5\n# a comment\n2 1\n# another\n255\n\x00\xff").unwrap();
        assert_eq!(
            (r.width, r.height, r.maxval, r.samples),
            (2, 1, 255, vec![0, 255])
        );
        let r = parse(b"P2 2 2 10\n0 1\n# c\n9 10\n").unwrap();
        assert_eq!(r.samples, vec![0, 1, 9, 10]);
        let r = parse(b"P5 1 2 65535\n\x01\x02\xff\xff").unwrap();
        assert_eq!(r.samples, vec![0x0102, 0xffff]);
        assert_eq!(
            parse(&encode_pgm(2, 1, &[7, 8])).unwrap().samples,
            vec![7, 8]
        );
    }

    #[test]
    fn malformed_images_say_what_and_where() {
        let problem = |b: &[u8]| match parse(b) {
            Err(OccupancyError::Pgm { problem, .. }) => problem,
            other => panic!("expected a PGM error, got {other:?}"),
        };
        assert_eq!(problem(b"P6 1 1 255\n\0"), PgmProblem::BadMagic);
        assert_eq!(problem(b""), PgmProblem::BadMagic);
        assert_eq!(problem(b"P51 1 255\n\0"), PgmProblem::BadMagic);
        assert_eq!(
            problem(b"P5 1 1 255X\0"),
            PgmProblem::BadHeaderField { field: "maxval" }
        );
        assert_eq!(
            problem(b"P5 x"),
            PgmProblem::BadHeaderField { field: "width" }
        );
        assert_eq!(
            problem(b"P5 1 0 255\n"),
            PgmProblem::BadHeaderField { field: "height" }
        );
        assert_eq!(
            problem(b"P5 1 1 70000\n\0"),
            PgmProblem::MaxvalOutOfRange { maxval: 70000 }
        );
        assert_eq!(
            problem(b"P5 2 2 255\n\0\0"),
            PgmProblem::Truncated {
                expected: 4,
                found: 2
            }
        );
        assert_eq!(
            problem(b"P2 2 1 9\n3"),
            PgmProblem::Truncated {
                expected: 2,
                found: 1
            }
        );
        assert_eq!(
            problem(b"P2 2 1 9\n3 12"),
            PgmProblem::BadPixel { index: 1 }
        );
        assert_eq!(
            problem(b"P5 1 1 9\n\x0a"),
            PgmProblem::BadPixel { index: 0 }
        );
    }
}
