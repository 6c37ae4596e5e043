//! The day artifact: one processed recording, as `haunts day` writes it and `haunts merge`
//! reads it (feature `serde`; here rather than in the CLI so that a fuzz target and other
//! programs read and write the same files).
//!
//! File layout (all integers little-endian):
//!
//! | bytes | what |
//! |---|---|
//! | 8 | magic `HAUNTDAY` |
//! | 4 | format version (this build writes and reads [`FORMAT_VERSION`]) |
//! | 8 | payload length `n` |
//! | n | payload: the [`DayArtifact`] as JSON (every `f64` read back bit for bit) |
//! | 32 | SHA-256 of everything before it |
//!
//! Loading checks the magic, the version (a newer file is refused by name, not misread), the
//! length against the file's, the checksum, and then the payload through the crates' own
//! deserialisers, which check what their constructors check. Saving writes a temporary file
//! beside the target, syncs it and renames it over the target: a reader, or a `kill -9`
//! half-way, sees the old file or the new one, never a mix. It is the layout library's code
//! (`crate::occupancy::atomic`), so the next save or load of the same artifact removes the
//! temporary file a killed save left behind.

mod merge;

use std::path::{Path, PathBuf};

use crate::affordance::{
    AffordanceError, DailyDensity, LayoutLibrary, Refusal, RegisterParams, Registration,
    TimedPoint, move_day,
};
use crate::occupancy::{GridGeometry, OccupancyGrid, Pose2};
use crate::pipeline::DayOutput;
use crate::pipeline::{moved_points, moved_trajectories};
use crate::tracking::Trajectory;
use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

pub use merge::{
    LibraryMerge, LibraryMergeError, MergeReport, MergedDay, RefusedDay, library_params,
    merge_days, merge_into_file, recording_order,
};

/// The file's first bytes.
pub const MAGIC: [u8; 8] = *b"HAUNTDAY";
/// The format version this build writes.
pub const FORMAT_VERSION: u32 = 1;
const HEADER_LEN: usize = 20;
const CHECKSUM_LEN: usize = 32;

/// Why a day artifact could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ArtifactError {
    /// The file system refused.
    #[error("{path}: {operation}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What was being done.
        operation: &'static str,
        /// The cause.
        source: std::io::Error,
    },
    /// Not a day artifact (a layout library is named as such).
    #[error("{path}: not a haunts day artifact ({found})")]
    BadMagic {
        /// The file.
        path: PathBuf,
        /// What the first bytes look like.
        found: String,
    },
    /// Written by a newer haunts.
    #[error("{path}: day artifact format {found}, this haunts reads up to {FORMAT_VERSION}")]
    NewerVersion {
        /// The file.
        path: PathBuf,
        /// Its version.
        found: u32,
    },
    /// Shorter or longer than its header says (a copy cut short).
    #[error("{path}: {found} bytes where the header announces {expected}")]
    Length {
        /// The file.
        path: PathBuf,
        /// Bytes the header announces.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The checksum does not match: the bytes changed after writing.
    #[error("{path}: checksum mismatch (the file is corrupt)")]
    Checksum {
        /// The file.
        path: PathBuf,
    },
    /// The payload does not decode, or breaks a rule of the crates' types.
    #[error("{path}: payload: {source}")]
    Payload {
        /// The file.
        path: PathBuf,
        /// The decoder's error.
        source: serde_json::Error,
    },
}

/// One processed recording: what the layout library and the maps need of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DayArtifact {
    /// The day's label in the library (default: the recording's file name).
    pub label: String,
    /// The recording it came from, as given on the command line.
    pub source: String,
    /// Stamp of the first and last scan used, seconds (merge orders days by the first).
    pub span: (f64, f64),
    /// The day's occupancy grid.
    pub map: OccupancyGrid,
    /// Its hits and visits.
    pub density: DailyDensity,
    /// Every track of the day, in the day's frame.
    pub trajectories: Vec<Trajectory>,
    /// Tracked positions at the density scans (for a hypertime model).
    pub tracked: Vec<TimedPoint>,
    /// The robot's positions at the keyframes.
    pub robot: Vec<Point2<f64>>,
    /// Scans read, skipped, keyframes, refused matches.
    pub counts: Counts,
    /// What was chosen or assumed while processing.
    pub notes: Vec<String>,
    /// The transform that brought the day from its own frame (its odometry at the first
    /// scan) into the library's, with its inlier share and residual; `None` for a day left in
    /// its own frame (the first day of a library, a day already on its cells, a day refused).
    /// Absent from files written before it existed, and not written when `None` (so the
    /// files of days in their own frame are as before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alignment: Option<Registration>,
}

/// What [`DayArtifact::align`] made of a day.
#[derive(Debug, Clone, PartialEq)]
pub enum Aligned {
    /// Registered (or measured at a forced pose) and moved onto the library's cells.
    Moved {
        /// The day on the library's cells, its alignment recorded.
        day: Box<DayArtifact>,
        /// The transform found or given, with its evidence.
        registration: Registration,
        /// The day's occupied cells that fell outside the library's grid.
        outside: usize,
    },
    /// Not trustworthy: the day must stay in its own frame, and not be merged.
    Refused(Refusal),
}

/// What processing the day counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counts {
    /// Scans read.
    pub scans: usize,
    /// Scans skipped (unreadable, stamps out of order, no pose).
    pub skipped: usize,
    /// Keyframes of the localisation.
    pub keyframes: usize,
    /// Keyframe matches refused.
    pub refused_matches: usize,
}

impl DayArtifact {
    /// The artifact of a processed day, in the day's own frame: `label` names it in the
    /// library, `source` says where it came from.
    pub fn from_output(output: DayOutput, label: String, source: String) -> Self {
        let span = match (output.poses.first(), output.poses.last()) {
            (Some(a), Some(b)) => (a.stamp, b.stamp),
            _ => (f64::NAN, f64::NAN),
        };
        Self {
            label,
            source,
            span,
            robot: output.keyframe_positions(),
            counts: Counts {
                scans: output.counts.scans,
                skipped: output.skipped.len(),
                keyframes: output.counts.keyframes,
                refused_matches: output.counts.refused_matches,
            },
            map: output.map,
            density: output.density,
            trajectories: output.trajectories,
            tracked: output.tracked,
            notes: output.notes,
            alignment: None,
        }
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        // Serialising plain data with finite and non-finite floats cannot fail: serde_json
        // writes non-finite values as null, and the crates' types refuse them on reading.
        let payload = serde_json::to_vec(self).unwrap_or_default();
        let mut bytes = Vec::with_capacity(HEADER_LEN + payload.len() + CHECKSUM_LEN);
        bytes.extend_from_slice(&MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        bytes.extend_from_slice(&payload);
        let sum = Sha256::digest(&bytes);
        bytes.extend_from_slice(&sum);
        bytes
    }

    /// The artifact in `bytes` (`path` names it in errors).
    ///
    /// # Errors
    /// See [`ArtifactError`].
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self, ArtifactError> {
        let path = path.to_path_buf();
        if bytes.len() < 8 || bytes[..8] != MAGIC {
            let head = &bytes[..bytes.len().min(8)];
            let found = if head == b"HAUNTLIB" {
                "a layout library".to_owned()
            } else {
                format!("first bytes {:?}", String::from_utf8_lossy(head))
            };
            return Err(ArtifactError::BadMagic { path, found });
        }
        let short = |expected: u64| ArtifactError::Length {
            path: path.clone(),
            expected,
            found: bytes.len() as u64,
        };
        if bytes.len() < HEADER_LEN {
            return Err(short(HEADER_LEN as u64));
        }
        let mut version = [0u8; 4];
        version.copy_from_slice(&bytes[8..12]);
        let version = u32::from_le_bytes(version);
        if version > FORMAT_VERSION {
            return Err(ArtifactError::NewerVersion {
                path,
                found: version,
            });
        }
        let mut len = [0u8; 8];
        len.copy_from_slice(&bytes[12..HEADER_LEN]);
        let len = u64::from_le_bytes(len);
        let expected = len.saturating_add((HEADER_LEN + CHECKSUM_LEN) as u64);
        if bytes.len() as u64 != expected {
            return Err(short(expected));
        }
        let body = bytes.len() - CHECKSUM_LEN;
        if Sha256::digest(&bytes[..body])[..] != bytes[body..] {
            return Err(ArtifactError::Checksum { path });
        }
        serde_json::from_slice(&bytes[HEADER_LEN..body])
            .map_err(|source| ArtifactError::Payload { path, source })
    }

    /// Writes the artifact to `path` atomically (temporary file, sync, rename; stale
    /// temporaries of `path` removed first, see `crate::occupancy::atomic`).
    ///
    /// # Errors
    /// [`ArtifactError::Io`] naming the step that failed; the target is then unchanged.
    pub fn save(&self, path: &Path) -> Result<(), ArtifactError> {
        save_atomically(path, &self.to_bytes())
    }

    /// The day moved onto a library's `geometry` by `alignment` (day frame → library frame):
    /// its map and density resampled onto the library's cells
    /// ([`move_day`]), its trajectories, tracked points and
    /// robot positions moved by the transform, the alignment recorded. The second value
    /// counts the day's occupied cells that fell outside the library's grid (named in a note
    /// when there are any).
    ///
    /// # Errors
    /// A resolution other than the library's; the density's own checks.
    pub fn moved(
        &self,
        alignment: &Registration,
        geometry: &GridGeometry,
    ) -> Result<(Self, usize), AffordanceError> {
        let pose = alignment.pose();
        let moved = move_day(&self.map, &self.density, &pose, geometry)?;
        let mut notes = self.notes.clone();
        if moved.outside > 0 {
            notes.push(format!(
                "{} occupied cells of the day fell outside the library's grid and were left out",
                moved.outside
            ));
        }
        let day = Self {
            label: self.label.clone(),
            source: self.source.clone(),
            span: self.span,
            map: moved.map,
            density: moved.density,
            trajectories: moved_trajectories(&self.trajectories, &pose),
            tracked: moved_points(&self.tracked, &pose),
            robot: self.robot.iter().map(|&p| pose * p).collect(),
            counts: self.counts,
            notes,
            alignment: Some(*alignment),
        };
        Ok((day, moved.outside))
    }

    /// The day brought into `library`'s frame: registered onto its layouts
    /// ([`LayoutLibrary::register`] under `params`), or measured at a given `pose` (a user's
    /// forced transform, [`LayoutLibrary::measure`]: never refused), then
    /// [`moved`](Self::moved) onto its cells. A day already aligned (onto another library)
    /// keeps the composition of both transforms as its alignment: day frame → this library.
    ///
    /// # Errors
    /// [`AffordanceError::EmptyDayMap`] for a day without structure; a resolution other than
    /// the library's; bad parameters. A day that does not register is not an error but
    /// [`Aligned::Refused`].
    pub fn align(
        &self,
        library: &LayoutLibrary,
        params: &RegisterParams,
        pose: Option<&Pose2>,
    ) -> Result<Aligned, AffordanceError> {
        let found = match pose {
            Some(pose) => library.measure(&self.map, pose),
            None => library.register(&self.map, params),
        };
        let registration = match found {
            Ok(r) => r,
            Err(AffordanceError::NotRegistered { refusal }) => {
                return Ok(Aligned::Refused(refusal));
            }
            Err(e) => return Err(e),
        };
        let (mut day, outside) = self.moved(&registration, library.geometry())?;
        if let Some(before) = self.alignment {
            let total = registration.pose() * before.pose();
            day.alignment = Some(Registration {
                x: total.translation.x,
                y: total.translation.y,
                yaw: total.rotation.angle(),
                ..registration
            });
        }
        Ok(Aligned::Moved {
            day: Box::new(day),
            registration,
            outside,
        })
    }

    /// Reads the artifact at `path`.
    ///
    /// # Errors
    /// See [`ArtifactError`].
    pub fn load(path: &Path) -> Result<Self, ArtifactError> {
        crate::occupancy::atomic::remove_stale_temporaries(path);
        let bytes = std::fs::read(path).map_err(|source| ArtifactError::Io {
            path: path.to_path_buf(),
            operation: "read",
            source,
        })?;
        Self::from_bytes(&bytes, path)
    }
}

/// Writes `bytes` to `path` atomically with `crate::occupancy::atomic::save` (the layout
/// library's code): temporary file, sync, rename, stale temporaries of `path` removed first.
///
/// # Errors
/// [`ArtifactError::Io`] naming the file and the step that failed.
pub fn save_atomically(path: &Path, bytes: &[u8]) -> Result<(), ArtifactError> {
    crate::occupancy::atomic::save(path, bytes, |path, operation, source| ArtifactError::Io {
        path: path.to_path_buf(),
        operation,
        source,
    })
}
