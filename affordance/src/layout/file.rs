//! Saving and loading a [`LayoutLibrary`]: one file, versioned, checksummed, written
//! atomically.
//!
//! # Format (version 2)
//!
//! Every number is little-endian; `f64` is its IEEE 754 bit pattern, so values come back bit
//! for bit.
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic: the bytes `HAUNTLIB` |
//! | 8 | 4 | `u32` format version (2) |
//! | 12 | 8 | `u64` payload length `N` |
//! | 20 | `N` | payload |
//! | 20 + `N` | 32 | SHA-256 of the payload |
//!
//! The file is exactly `52 + N` bytes long. The payload is, in order:
//!
//! 1. the reference geometry: `f64` resolution, `f64` origin x, `f64` origin y, `u32` width,
//!    `u32` height;
//! 2. the parameters: `u8` cutoff unit (0 cells, 1 metres) and `f64` cutoff; `u8` threshold
//!    kind (0 cells², 1 square metres, 2 per occupied cell) and `f64` threshold; `u8`
//!    symmetrisation (0 max, 1 mean, 2 min, 3 sum); `f64` composite min fraction; `u32` min
//!    visits; `u8` observed only (0 or 1; version 2 on: version 1 files, written before the
//!    parameter, read as 0, the whole-map comparison they were built with);
//! 3. `u64` number of days ingested, `u32` number of layouts `L`;
//! 4. `L` layouts, each: `u32` number of days `D` (≥ 1); `D` day records (`u64` day id, `u32`
//!    label length in bytes, the label in UTF-8, `u8` 1 if a distance follows its value or 0,
//!    `f64` distance, 0 when absent); the geometric composite as `u32` occupied counts then
//!    `u32` free counts, one per cell in row-major order (row 0 at the bottom), over `D` maps;
//!    the affordance composite as `u64` Σ hits then `u64` Σ visits per cell, over `D` days.
//!
//! Loading checks, in this order: the magic, the version (a newer version is refused, not
//! guessed at), the length, the checksum, then every field of the payload (a valid geometry
//! and parameters, known enum tags, UTF-8 labels, unique day ids and labels below the day
//! count, every ingested day in exactly one layout, occupied + free ≤ maps per cell, no byte
//! left over). Each failure is a [`LibraryFileProblem`]; nothing panics and nothing is
//! allocated beyond what the file holds.
//!
//! # Atomic saves
//!
//! [`LayoutLibrary::save`] writes a temporary file `.<name>.tmp-<pid>-<n>` in the target's
//! directory, fsyncs it, renames it over the target and fsyncs the directory (on Unix). A
//! crash at any point leaves either the previous file or the new one, never a mixture; a
//! temporary file left by a crash is never read, and the next save or load of the same
//! library removes it once its process is gone (`haunts_occupancy::atomic`, the code the
//! CLI's day artifacts are saved with too, states the rule).

use std::fs;
use std::path::Path;

use haunts_occupancy::GeometricComposite;
use haunts_occupancy::{FREE, Grid, GridGeometry, OCCUPIED, OccupancyGrid, UNKNOWN};
use haunts_similarity::{ClusterParams, DifferenceParams, LayoutThreshold, Length, Symmetrisation};
use nalgebra::Point2;
use sha2::{Digest, Sha256};

use super::{DayId, DayRecord, Layout, LayoutId, LayoutLibrary, LayoutParams};
use crate::density::CumulativeDensity;
use crate::{AffordanceError, Result};

/// The first eight bytes of every library file.
pub const MAGIC: [u8; 8] = *b"HAUNTLIB";
/// The format version this build writes, and the newest it reads.
pub const FORMAT_VERSION: u32 = 2;
/// Bytes before the payload: magic, version, payload length.
const HEADER_LEN: usize = 20;
/// Bytes of the SHA-256 checksum after the payload.
const CHECKSUM_LEN: usize = 32;

/// What is wrong with a library file (or byte buffer) that cannot be loaded.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum LibraryFileProblem {
    /// The data does not start with [`MAGIC`]: not a layout library.
    BadMagic,
    /// The format version is not one this build reads (a newer version, or 0).
    UnsupportedVersion {
        /// The version in the file.
        found: u32,
        /// The newest version this build reads.
        supported: u32,
    },
    /// The data is shorter than its header says.
    Truncated {
        /// Bytes the header announces (or the header's own length).
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The data is longer than its header says.
    TrailingBytes {
        /// Bytes the header announces.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The payload's SHA-256 differs from the stored checksum: the data was corrupted.
    ChecksumMismatch,
    /// The payload passed its checksum but does not describe a valid library (written by a
    /// faulty program).
    Malformed {
        /// Byte offset in the file of the field that is wrong.
        offset: usize,
        /// What is wrong.
        what: &'static str,
    },
    /// The payload passed its checksum but its grid (resolution, origin, size) is not one
    /// [`GridGeometry::new`] accepts: a resolution of 1e308, an origin at 1e300.
    InvalidGeometry {
        /// Byte offset in the file of the geometry.
        offset: usize,
        /// The geometry's error.
        reason: String,
    },
}

impl std::fmt::Display for LibraryFileProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::BadMagic => write!(f, "not a layout library (bad magic)"),
            Self::UnsupportedVersion { found, supported } => write!(
                f,
                "format version {found} is not supported (this build reads versions 1 to {supported})"
            ),
            Self::Truncated { expected, found } => {
                write!(f, "truncated: {found} of {expected} bytes present")
            }
            Self::TrailingBytes { expected, found } => {
                write!(f, "{found} bytes where the header announces {expected}")
            }
            Self::ChecksumMismatch => write!(f, "payload checksum mismatch (corrupted data)"),
            Self::Malformed { offset, what } => write!(f, "byte {offset}: {what}"),
            Self::InvalidGeometry { offset, reason } => {
                write!(f, "byte {offset}: invalid grid geometry: {reason}")
            }
        }
    }
}

impl LayoutLibrary {
    /// The library in the file format of the [module docs](crate::layout::file).
    ///
    /// # Complexity
    /// O(layouts · cells + days).
    pub fn to_bytes(&self) -> Vec<u8> {
        let payload = self.payload();
        let mut out = Vec::with_capacity(HEADER_LEN + payload.len() + CHECKSUM_LEN);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&payload);
        out.extend_from_slice(Sha256::digest(&payload).as_slice());
        out
    }

    /// A library from bytes in the file format of the [module docs](crate::layout::file).
    ///
    /// # Errors
    /// [`AffordanceError::CorruptLibrary`] (without a path) naming the
    /// [`LibraryFileProblem`].
    ///
    /// # Complexity
    /// O(size + Σ over layouts of days · cells): each geometric composite is rebuilt by
    /// adding its days' states again.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        decode(bytes).map_err(|problem| AffordanceError::CorruptLibrary {
            path: None,
            problem,
        })
    }

    /// Saves the library to `path` atomically: a temporary file in the same directory is
    /// written and fsynced, renamed over `path`, and the directory is fsynced (on Unix). A
    /// crash during a save leaves the previous file intact. Temporary files of `path` left
    /// by interrupted saves of processes no longer running are removed first
    /// (`haunts_occupancy::atomic::remove_stale_temporaries`).
    ///
    /// # Errors
    /// [`AffordanceError::Io`] naming the path and the failed step; the previous file is then
    /// untouched and the temporary file removed.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        haunts_occupancy::atomic::save(path.as_ref(), &self.to_bytes(), io)
    }

    /// Loads a library saved by [`LayoutLibrary::save`] (removing, as a save does, the
    /// temporary files that interrupted saves of `path` left behind).
    ///
    /// # Errors
    /// [`AffordanceError::Io`] when the file cannot be read; [`AffordanceError::CorruptLibrary`]
    /// naming the path and the [`LibraryFileProblem`] when it is not a valid library.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        haunts_occupancy::atomic::remove_stale_temporaries(path);
        let bytes = fs::read(path).map_err(|e| io(path, "read", e))?;
        decode(&bytes).map_err(|problem| AffordanceError::CorruptLibrary {
            path: Some(path.to_path_buf()),
            problem,
        })
    }

    fn payload(&self) -> Vec<u8> {
        let g = &self.geometry;
        let mut w = Writer(Vec::new());
        w.f64(g.resolution());
        w.f64(g.origin().x);
        w.f64(g.origin().y);
        // GridGeometry keeps width · height ≤ u32::MAX, so both sides fit u32.
        w.u32(g.width() as u32);
        w.u32(g.height() as u32);
        let p = &self.params;
        let (unit, cutoff) = match p.difference.cutoff {
            Length::Cells(v) => (0, v),
            Length::Metres(v) => (1, v),
        };
        w.u8(unit);
        w.f64(cutoff);
        let (kind, threshold) = match p.cluster.threshold {
            LayoutThreshold::Cells(v) => (0, v),
            LayoutThreshold::SquareMetres(v) => (1, v),
            LayoutThreshold::PerOccupiedCell(v) => (2, v),
        };
        w.u8(kind);
        w.f64(threshold);
        w.u8(match p.cluster.symmetrisation {
            Symmetrisation::Max => 0,
            Symmetrisation::Mean => 1,
            Symmetrisation::Min => 2,
            Symmetrisation::Sum => 3,
        });
        w.f64(p.composite_min_fraction);
        w.u32(p.min_visits);
        w.u8(u8::from(p.observed_only));
        w.u64(self.next_day);
        w.u32(self.layouts.len() as u32);
        for layout in &self.layouts {
            w.u32(layout.days.len() as u32);
            for day in &layout.days {
                w.u64(day.id.0);
                w.u32(day.label.len() as u32);
                w.0.extend_from_slice(day.label.as_bytes());
                w.u8(u8::from(day.distance.is_some()));
                w.f64(day.distance.unwrap_or(0.0));
            }
            for v in layout.composite.occupied_counts().data() {
                w.u32(*v);
            }
            for v in layout.composite.free_counts().data() {
                w.u32(*v);
            }
            for v in layout.affordance.hits().data() {
                w.u64(*v);
            }
            for v in layout.affordance.visits().data() {
                w.u64(*v);
            }
        }
        w.0
    }
}

fn io(path: &Path, operation: &'static str, source: std::io::Error) -> AffordanceError {
    AffordanceError::Io {
        path: path.to_path_buf(),
        operation,
        source,
    }
}

struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
}

/// Reads the payload; offsets in errors are file offsets.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

type Decoded<T> = std::result::Result<T, LibraryFileProblem>;

fn malformed<T>(offset: usize, what: &'static str) -> Decoded<T> {
    Err(LibraryFileProblem::Malformed {
        offset: HEADER_LEN + offset,
        what,
    })
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &'static str) -> Decoded<&'a [u8]> {
        match self.pos.checked_add(n) {
            Some(end) if end <= self.bytes.len() => {
                let s = &self.bytes[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            _ => malformed(self.pos, what),
        }
    }
    fn array<const N: usize>(&mut self, what: &'static str) -> Decoded<[u8; N]> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(N, what)?);
        Ok(a)
    }
    fn u8(&mut self, what: &'static str) -> Decoded<u8> {
        Ok(self.array::<1>(what)?[0])
    }
    fn u32(&mut self, what: &'static str) -> Decoded<u32> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }
    fn u64(&mut self, what: &'static str) -> Decoded<u64> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }
    fn f64(&mut self, what: &'static str) -> Decoded<f64> {
        Ok(f64::from_le_bytes(self.array(what)?))
    }
    /// `n` values of `SIZE` bytes each, checked to be present before anything is allocated.
    fn values<const SIZE: usize, T>(
        &mut self,
        n: usize,
        what: &'static str,
        read: impl Fn([u8; SIZE]) -> T,
    ) -> Decoded<Vec<T>> {
        let Some(len) = n.checked_mul(SIZE) else {
            return malformed(self.pos, what);
        };
        let bytes = self.take(len, what)?;
        Ok(bytes
            .chunks_exact(SIZE)
            .map(|c| {
                let mut a = [0; SIZE];
                a.copy_from_slice(c);
                read(a)
            })
            .collect())
    }
}

fn decode(bytes: &[u8]) -> Decoded<LayoutLibrary> {
    let found = bytes.len() as u64;
    let magic_len = bytes.len().min(MAGIC.len());
    if bytes[..magic_len] != MAGIC[..magic_len] {
        return Err(LibraryFileProblem::BadMagic);
    }
    if bytes.len() < HEADER_LEN {
        return Err(LibraryFileProblem::Truncated {
            expected: HEADER_LEN as u64,
            found,
        });
    }
    let word = |at: usize| {
        let mut a = [0; 4];
        a.copy_from_slice(&bytes[at..at + 4]);
        u32::from_le_bytes(a)
    };
    let version = word(8);
    if version == 0 || version > FORMAT_VERSION {
        return Err(LibraryFileProblem::UnsupportedVersion {
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let mut len = [0; 8];
    len.copy_from_slice(&bytes[12..20]);
    let payload_len = u64::from_le_bytes(len);
    let expected = payload_len.saturating_add((HEADER_LEN + CHECKSUM_LEN) as u64);
    if found < expected {
        return Err(LibraryFileProblem::Truncated { expected, found });
    }
    if found > expected {
        return Err(LibraryFileProblem::TrailingBytes { expected, found });
    }
    // found == expected, so the payload length fits usize.
    let end = HEADER_LEN + payload_len as usize;
    let payload = &bytes[HEADER_LEN..end];
    if Sha256::digest(payload).as_slice() != &bytes[end..] {
        return Err(LibraryFileProblem::ChecksumMismatch);
    }
    decode_payload(payload, version)
}

fn decode_payload(payload: &[u8], version: u32) -> Decoded<LayoutLibrary> {
    let mut r = Reader {
        bytes: payload,
        pos: 0,
    };
    let at = r.pos;
    let resolution = r.f64("resolution")?;
    let origin = Point2::new(r.f64("origin x")?, r.f64("origin y")?);
    let width = r.u32("width")? as usize;
    let height = r.u32("height")? as usize;
    let geometry = GridGeometry::new(resolution, origin, width, height).map_err(|e| {
        LibraryFileProblem::InvalidGeometry {
            offset: HEADER_LEN + at,
            reason: e.to_string(),
        }
    })?;
    let params_at = r.pos;
    let at = r.pos;
    let cutoff = match (r.u8("cutoff unit")?, r.f64("cutoff")?) {
        (0, v) => Length::Cells(v),
        (1, v) => Length::Metres(v),
        _ => return malformed(at, "unknown cutoff unit"),
    };
    let at = r.pos;
    let threshold = match (r.u8("threshold kind")?, r.f64("threshold")?) {
        (0, v) => LayoutThreshold::Cells(v),
        (1, v) => LayoutThreshold::SquareMetres(v),
        (2, v) => LayoutThreshold::PerOccupiedCell(v),
        _ => return malformed(at, "unknown threshold kind"),
    };
    let at = r.pos;
    let symmetrisation = match r.u8("symmetrisation")? {
        0 => Symmetrisation::Max,
        1 => Symmetrisation::Mean,
        2 => Symmetrisation::Min,
        3 => Symmetrisation::Sum,
        _ => return malformed(at, "unknown symmetrisation"),
    };
    let params = LayoutParams {
        difference: DifferenceParams::default().with_cutoff(cutoff),
        cluster: ClusterParams::default()
            .with_threshold(threshold)
            .with_symmetrisation(symmetrisation),
        composite_min_fraction: r.f64("composite min fraction")?,
        min_visits: r.u32("min visits")?,
        observed_only: false,
    };
    let at = r.pos;
    let params = match version {
        1 => params,
        _ => match r.u8("observed only")? {
            0 => params,
            1 => params.with_observed_only(true),
            _ => return malformed(at, "observed only is neither 0 nor 1"),
        },
    };
    let Ok(params) = params.check() else {
        return malformed(params_at, "invalid parameters");
    };
    let next_day = r.u64("day count")?;
    let layout_count = r.u32("layout count")?;
    let cells = geometry.len();
    let mut layouts = Vec::new();
    let mut ids = std::collections::HashSet::new();
    let mut labels = std::collections::HashSet::new();
    for index in 0..layout_count as usize {
        let at = r.pos;
        let maps = r.u32("layout day count")?;
        if maps == 0 {
            return malformed(at, "a layout without days");
        }
        let mut days = Vec::new();
        for _ in 0..maps {
            let at = r.pos;
            let id = r.u64("day id")?;
            if id >= next_day || !ids.insert(id) {
                return malformed(at, "day id repeated or not below the day count");
            }
            let at = r.pos;
            let len = r.u32("label length")? as usize;
            let Ok(label) = std::str::from_utf8(r.take(len, "label")?) else {
                return malformed(at + 4, "label is not UTF-8");
            };
            if !labels.insert(label.to_owned()) {
                return malformed(at + 4, "label repeated");
            }
            let at = r.pos;
            let distance = match (r.u8("distance flag")?, r.f64("distance")?) {
                (0, _) => None,
                (1, d) if d.is_finite() && d >= 0.0 => Some(d),
                _ => return malformed(at, "bad distance flag or distance"),
            };
            days.push(DayRecord {
                id: DayId(id),
                label: label.to_owned(),
                distance,
            });
        }
        let at = r.pos;
        let occupied = r.values(cells, "occupied counts", u32::from_le_bytes)?;
        let free = r.values(cells, "free counts", u32::from_le_bytes)?;
        let Some(composite) = composite_from_counts(geometry, &occupied, &free, maps) else {
            return malformed(at, "occupied + free counts exceed the layout's days");
        };
        let at = r.pos;
        let hits = r.values(cells, "hit sums", u64::from_le_bytes)?;
        let visits = r.values(cells, "visit sums", u64::from_le_bytes)?;
        let affordance = match (
            Grid::from_vec(geometry, hits),
            Grid::from_vec(geometry, visits),
        ) {
            (Ok(h), Ok(v)) => CumulativeDensity::from_sums(h, v, maps, params.min_visits),
            _ => return malformed(at, "hit or visit sums"),
        };
        let Ok(affordance) = affordance else {
            return malformed(at, "hit or visit sums");
        };
        layouts.push(Layout {
            id: LayoutId(index),
            composite,
            affordance,
            days,
        });
    }
    if ids.len() as u64 != next_day {
        return malformed(r.pos, "the layouts do not hold every ingested day");
    }
    if r.pos != payload.len() {
        return malformed(r.pos, "bytes left over after the last layout");
    }
    Ok(LayoutLibrary {
        geometry,
        params,
        layouts,
        next_day,
    })
}

/// The composite of `maps` maps with these per-cell counts, or `None` when a cell's counts
/// exceed `maps`. `GeometricComposite` is built only by adding maps, so the maps are
/// replayed: map `k` has cell `i` occupied for `k < occupied[i]`, free for the next
/// `free[i]` maps, unknown after.
pub(super) fn composite_from_counts(
    geometry: GridGeometry,
    occupied: &[u32],
    free: &[u32],
    maps: u32,
) -> Option<GeometricComposite> {
    if occupied
        .iter()
        .zip(free)
        .any(|(o, f)| u64::from(*o) + u64::from(*f) > u64::from(maps))
    {
        return None;
    }
    let mut composite = GeometricComposite::new(geometry);
    let mut values = vec![UNKNOWN; geometry.len()];
    for k in 0..maps {
        for ((v, o), f) in values.iter_mut().zip(occupied).zip(free) {
            *v = if k < *o {
                OCCUPIED
            } else if k - *o < *f {
                FREE
            } else {
                UNKNOWN
            };
        }
        let map = OccupancyGrid::from_values(geometry, values.clone()).ok()?;
        composite.add(&map).ok()?;
    }
    Some(composite)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::density::DailyDensity;
    use haunts_occupancy::Cell;

    fn library() -> LayoutLibrary {
        let g = GridGeometry::new(0.1, Point2::new(-0.3, 0.2), 12, 9).unwrap();
        let mut lib = LayoutLibrary::new(g, LayoutParams::default()).unwrap();
        let mut map = OccupancyGrid::unknown(g);
        for row in 0..9 {
            map.set(Cell::new(2, row), OCCUPIED);
            map.set(Cell::new(3, row), FREE);
        }
        let hits = Grid::from_fn(g, |c| (c.col * c.row) as u32);
        let day = DailyDensity::new(hits, Grid::filled(g, 3), 1).unwrap();
        lib.ingest("a", &map, &day).unwrap();
        lib.ingest("b", &map, &day).unwrap();
        lib
    }

    #[test]
    fn composites_are_rebuilt_exactly_from_their_counts() {
        let lib = library();
        let back = LayoutLibrary::from_bytes(&lib.to_bytes()).unwrap();
        assert_eq!(back, lib);
        assert_eq!(back.layouts()[0].composite().maps(), 2);
        let g = *lib.geometry();
        assert!(composite_from_counts(g, &vec![2; g.len()], &vec![1; g.len()], 2).is_none());
    }

    #[test]
    fn an_interrupted_save_leaves_the_previous_file_loadable() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("library.bin");
        let before = library();
        before.save(&path).unwrap();
        // A second save that "crashes" after writing its temporary file, before the rename.
        let mut after = before.clone();
        let g = *after.geometry();
        let mut other = OccupancyGrid::unknown(g);
        other.set(Cell::new(11, 8), OCCUPIED);
        let day = DailyDensity::new(Grid::filled(g, 0), Grid::filled(g, 1), 1).unwrap();
        after.ingest("c", &other, &day).unwrap();
        let tmp = haunts_occupancy::atomic::write_temporary(&path, &after.to_bytes(), io).unwrap();
        assert!(tmp.exists());
        assert_eq!(tmp.parent(), path.parent());
        assert_eq!(LayoutLibrary::load(&path).unwrap(), before);
        // The next save goes through and does not collide with the leftover.
        after.save(&path).unwrap();
        assert_eq!(LayoutLibrary::load(&path).unwrap(), after);
    }
}
