//! The day of a live session: its messages spooled to an MCAP file as they arrive, and
//! [`LiveSession::close_day`], which processes the spool as `haunts day` processes a
//! recording and folds it into a layout library as `haunts merge` does (the same code, the
//! same lock and the same atomic save).
//!
//! The spool holds what the session accepted: the scans that passed its checks, the finite
//! odometry samples and transforms, each logged at its arrival time, on `/scan`, `/odom`,
//! `/tf` and `/tf_static`. It is written chunk by chunk (memory stays flat); a process killed
//! mid-day leaves a spool without its summary, which an MCAP reader still reads in file
//! order up to the cut (see [`haunts_bag::Bag::messages`]).

use std::path::{Path, PathBuf};

use haunts_affordance::{LayoutId, RegisterParams};
use haunts_bag::msg::TfMessage;
use haunts_bag::{Bag, McapWriter, RecordingOptions, convert};
use haunts_occupancy::bounds::BoundsRule;
use haunts_occupancy::{LaserScan, Pose2};
use haunts_tracking::detect::Detector;
use haunts_tracking::track::Tracker;

use super::LiveSession;
use crate::artifact::{
    DayArtifact, LibraryMerge, LibraryMergeError, library_params, merge_into_file,
};
use crate::pipeline::serve::{ServeParams, ServedLayout, serve_layout};
use crate::pipeline::{DayProcessor, PipelineError, PipelineParams};

/// The spool of the day so far.
pub(super) struct DaySpool {
    path: PathBuf,
    writer: Option<McapWriter>,
    /// The first message's arrival time (the day's label).
    first: Option<f64>,
    messages: usize,
    /// Messages the file refused (a write error; the session goes on).
    failed: usize,
}

impl DaySpool {
    fn create(path: &Path) -> crate::pipeline::Result<Self> {
        Ok(Self {
            path: path.to_path_buf(),
            writer: Some(McapWriter::create(path)?),
            first: None,
            messages: 0,
            failed: 0,
        })
    }

    fn write<T: haunts_bag::msg::Message>(&mut self, topic: &str, received: f64, message: &T) {
        let Some(writer) = &mut self.writer else {
            self.failed += 1;
            return;
        };
        match writer.write(topic, received, message) {
            Ok(()) => {
                self.messages += 1;
                self.first.get_or_insert(received);
            }
            Err(_) => self.failed += 1,
        }
    }

    pub(super) fn scan(&mut self, received: f64, frame: &str, scan: &LaserScan) {
        self.write("/scan", received, &convert::laser_scan_msg(scan, frame));
    }

    pub(super) fn odometry(
        &mut self,
        received: f64,
        stamp: f64,
        frames: (&str, &str),
        pose: &Pose2,
    ) {
        let m = convert::odometry_msg(stamp, frames.0, frames.1, pose);
        self.write("/odom", received, &m);
    }

    pub(super) fn transform(
        &mut self,
        received: f64,
        stamp: f64,
        link: (&str, &str),
        pose: &Pose2,
        is_static: bool,
    ) {
        let m = TfMessage {
            transforms: vec![convert::transform_msg(stamp, link.0, link.1, pose)],
        };
        let topic = if is_static { "/tf_static" } else { "/tf" };
        self.write(topic, received, &m);
    }
}

/// What [`LiveSession::close_day`] did.
#[derive(Debug, Clone)]
pub struct ClosedDay {
    /// The day's label in the library: `live-` and its first message's arrival time.
    pub label: String,
    /// Messages the day's spool held.
    pub messages: usize,
    /// Messages the spool could not write (the file system refused).
    pub spool_failures: usize,
    /// The merge: the library as saved, and what became of the day.
    pub merge: LibraryMerge,
    /// The layout the day joined, when it joined one.
    pub layout: Option<LayoutId>,
    /// Every layout's maps after the merge (composite, costmap with the affordance layer).
    pub maps: Vec<(LayoutId, ServedLayout)>,
}

impl<D: Detector, T: Tracker> LiveSession<D, T> {
    /// Spools the day's messages to the MCAP file `path` (created, or truncated), so that
    /// [`LiveSession::close_day`] can fold the day into a library.
    ///
    /// # Errors
    /// The file cannot be created.
    pub fn with_spool(mut self, path: impl AsRef<Path>) -> crate::pipeline::Result<Self> {
        self.spool = Some(DaySpool::create(path.as_ref())?);
        Ok(self)
    }

    /// The spool file of the day, when there is one.
    pub fn spool_path(&self) -> Option<&Path> {
        self.spool.as_ref().map(|s| s.path.as_path())
    }

    /// Ends the day: the spool is closed and processed as `haunts day` processes a recording
    /// (the daily loop, `PipelineParams::real_laser`, at the library's resolution when it
    /// exists, else 0.1 m), and the day folded into the library at `library` as
    /// `haunts merge` does it ([`merge_into_file`]: the library's lock, waited for up to
    /// `wait`; registration onto its layouts; one atomic save, so that a process killed during
    /// the close leaves the old library or the new one). A new spool starts at the same path
    /// for the next day; the tracker goes on (people do not vanish at midnight). The spool of
    /// a day that could not be merged is kept beside, as `NAME.LABEL.mcap`.
    ///
    /// # Errors
    /// [`PipelineError::EmptyDay`] without a spool or when the day has no usable scan; the
    /// reading, processing and merging errors ([`PipelineError::LibraryMerge`]).
    pub fn close_day(
        &mut self,
        library: &Path,
        wait: std::time::Duration,
    ) -> crate::pipeline::Result<ClosedDay> {
        let Some(mut spool) = self.spool.take() else {
            return Err(PipelineError::EmptyDay {
                what: "spool (LiveSession::with_spool)",
            });
        };
        if let Some(writer) = spool.writer.take() {
            writer.finish()?;
        }
        let label = format!("live-{:.3}", spool.first.unwrap_or(0.0));
        let result = fold_day(&spool.path, &label, library, wait);
        let kept = spool
            .path
            .with_extension(format!("{label}.{}", extension(&spool.path)));
        let outcome = match &result {
            Ok(_) => std::fs::remove_file(&spool.path),
            Err(_) => std::fs::rename(&spool.path, &kept),
        };
        let io = |source| PipelineError::Io {
            path: spool.path.clone(),
            source,
        };
        self.spool = Some(DaySpool::create(&spool.path)?);
        let (merge, layout) = result?;
        outcome.map_err(io)?;
        let maps = merge
            .library
            .layouts()
            .iter()
            .map(|l| Ok((l.id(), serve_layout(l, &ServeParams::default())?)))
            .collect::<crate::pipeline::Result<_>>()?;
        Ok(ClosedDay {
            label,
            messages: spool.messages,
            spool_failures: spool.failed,
            merge,
            layout,
            maps,
        })
    }
}

/// The spool's extension (`mcap` when it has none).
fn extension(path: &Path) -> String {
    path.extension()
        .map_or_else(|| "mcap".to_owned(), |e| e.to_string_lossy().into_owned())
}

/// The spooled day processed and merged into `library`.
fn fold_day(
    spool: &Path,
    label: &str,
    library: &Path,
    wait: std::time::Duration,
) -> crate::pipeline::Result<(LibraryMerge, Option<LayoutId>)> {
    let recording = Bag::open(spool)?
        .recording(&RecordingOptions::new())?
        .without_far_poses(&BoundsRule::default())?
        .0;
    let resolution = if library.exists() {
        haunts_affordance::LayoutLibrary::load(library)?
            .geometry()
            .resolution()
    } else {
        0.1
    };
    let geometry = DayProcessor::geometry_for(&recording, resolution, 12.0)?;
    let mut params = PipelineParams::real_laser();
    params.resolution = resolution;
    let output = DayProcessor::new(geometry, params)?.process(&recording)?;
    let day = DayArtifact::from_output(output, label.to_owned(), spool.display().to_string());
    let merge = merge_into_file(
        library,
        vec![day],
        library_params(),
        &RegisterParams::default(),
        wait,
    )?;
    let layout = merge.report.ingested.first().map(|d| d.layout);
    Ok((merge, layout))
}

impl From<LibraryMergeError> for PipelineError {
    fn from(e: LibraryMergeError) -> Self {
        PipelineError::LibraryMerge(Box::new(e))
    }
}
