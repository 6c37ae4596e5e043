//! `Recording`: what a robot recorded, in haunts types, whatever the file it came from.
//!
//! A recording is time-ordered laser scans, each with the frame of the sensor that took it,
//! the robot's odometry, the tree of coordinate frames (fixed mounts and moving links), an
//! optional map, and the notes of what was assumed while building it. ROS 1 bags and ROS 2
//! MCAP files (`haunts-bag`), CARMEN logs ([`crate::carmen`]), the `leg_tracker` text export
//! (`haunts-tracking`) and the simulator (`haunts-sim`) all produce one, so everything
//! downstream reads one type. Ground truth is not part of a recording: only scoring reads it.
//!
//! Scans are streamed from a [`ScanSource`]: a bag is read scan by scan when they are
//! iterated, so a day of a 40 Hz laser is never held in memory; sources in memory
//! ([`ScanList`]) serve the readers of small files and the simulator.

use std::fmt;

use nalgebra::Isometry2;

use crate::frames::{PoseHistory, TransformTree, frame_name};
use crate::{LaserScan, OccupancyError, OccupancyGrid, Result};

/// One scan of a recording: the scan (its `stamp` is the sensor's header stamp), the frame of
/// the sensor that took it, and when it was received (a bag's log time; the stamp where the
/// source has no other clock).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RecordedScan {
    /// The scan; `scan.stamp` is the header stamp, seconds.
    pub scan: LaserScan,
    /// The sensor's frame (e.g. `base_laser`, `left_laser`).
    pub frame: String,
    /// When the scan was recorded, seconds (a bag's log time).
    pub received: f64,
}

/// A boxed iterator over the scans of a source, each one read or an error.
pub type Scans<'a> = Box<dyn Iterator<Item = Result<RecordedScan>> + Send + 'a>;

/// Where the scans of a [`Recording`] come from: iterated from the start each time it is
/// asked, in the order they were recorded.
///
/// Implemented by [`ScanList`] (scans in memory) and by the bag readers of `haunts-bag`,
/// which read the file anew on every call.
pub trait ScanSource: Send + Sync + fmt::Debug {
    /// The scans from the first, in recorded order. A source that reads a file returns the
    /// errors of that file as [`OccupancyError::ScanSource`].
    ///
    /// # Errors
    /// When the source cannot be opened again.
    fn scans(&self) -> Result<Scans<'_>>;

    /// How many scans the source holds, when known without reading them.
    fn len_hint(&self) -> Option<usize> {
        None
    }
}

/// Scans held in memory, in the order given.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScanList(pub Vec<RecordedScan>);

impl ScanSource for ScanList {
    fn scans(&self) -> Result<Scans<'_>> {
        Ok(Box::new(self.0.iter().cloned().map(Ok)))
    }

    fn len_hint(&self) -> Option<usize> {
        Some(self.0.len())
    }
}

/// What a robot recorded: scans (streamed), odometry, the transform tree, an optional map, and
/// notes of the choices made while reading it (which topic, which frame was assumed).
///
/// The odometry is the pose of `base_frame` in `odom_frame` over time; the transform tree
/// holds the sensors' mounts (and any other links the recording carried). The pose of a
/// sensor in the odometry frame at time `t` is `odometry(t) · mount(sensor → base, t)`
/// ([`Recording::sensor_pose_at`]).
///
/// # Example
/// ```
/// use haunts_occupancy::{PoseHistory, TransformTree};
/// use haunts_occupancy::recording::{RecordedScan, Recording, ScanList};
/// use haunts_occupancy::LaserScan;
/// use nalgebra::{Isometry2, Vector2};
///
/// let scan = LaserScan::new(1.0, -1.0, 0.5, 0.1, 10.0, vec![2.0; 5], vec![])?;
/// let scans = ScanList(vec![RecordedScan { scan, frame: "laser".into(), received: 1.01 }]);
/// let mut tree = TransformTree::new();
/// tree.add_static("base_link", "laser", Isometry2::new(Vector2::new(0.2, 0.0), 0.0))?;
/// let odometry = PoseHistory::new([
///     (0.0, Isometry2::identity()),
///     (2.0, Isometry2::new(Vector2::new(2.0, 0.0), 0.0)),
/// ])?;
/// let recording = Recording::new(scans)
///     .with_transforms(tree)
///     .with_odometry(odometry, "odom", "base_link");
/// let first = recording.scans()?.next().unwrap()?;
/// let pose = recording.sensor_pose_at(&first.frame, first.scan.stamp)?;
/// approx::assert_relative_eq!(pose.translation.vector, Vector2::new(1.2, 0.0), epsilon = 1e-12);
/// # Ok::<(), haunts_occupancy::OccupancyError>(())
/// ```
#[derive(Debug)]
pub struct Recording {
    scans: Box<dyn ScanSource>,
    odometry: Option<PoseHistory>,
    odom_frame: String,
    base_frame: String,
    transforms: TransformTree,
    map: Option<OccupancyGrid>,
    notes: Vec<String>,
}

impl Recording {
    /// A recording of `scans` alone: no odometry (scans are then in their own frame), no
    /// transforms, no map. The frames default to `odom` and `base_link`.
    pub fn new(scans: impl ScanSource + 'static) -> Self {
        Self {
            scans: Box::new(scans),
            odometry: None,
            odom_frame: "odom".to_owned(),
            base_frame: "base_link".to_owned(),
            transforms: TransformTree::new(),
            map: None,
            notes: Vec::new(),
        }
    }

    /// The recording with odometry: the pose of `base_frame` in `odom_frame` over time.
    pub fn with_odometry(
        mut self,
        odometry: PoseHistory,
        odom_frame: &str,
        base_frame: &str,
    ) -> Self {
        self.odometry = Some(odometry);
        self.odom_frame = frame_name(odom_frame).to_owned();
        self.base_frame = frame_name(base_frame).to_owned();
        self
    }

    /// The recording with the robot frame named `base_frame` (the frame odometry moves and
    /// the sensors' mounts lead to), when it has no odometry.
    pub fn with_base_frame(mut self, base_frame: &str) -> Self {
        self.base_frame = frame_name(base_frame).to_owned();
        self
    }

    /// The recording with its transform tree.
    pub fn with_transforms(mut self, transforms: TransformTree) -> Self {
        self.transforms = transforms;
        self
    }

    /// The recording with a map.
    pub fn with_map(mut self, map: OccupancyGrid) -> Self {
        self.map = Some(map);
        self
    }

    /// The recording with one more note of what was chosen or assumed while reading it.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    /// The recording with its odometry's samples far from the bulk of the odometry removed
    /// by the bounds rule ([`PoseHistory::retain_near`]), and a note when any was; the
    /// report names them. A recording without odometry is returned as it is, with an empty
    /// report.
    ///
    /// # Errors
    /// As [`PoseHistory::retain_near`].
    pub fn without_far_poses(
        mut self,
        rule: &crate::bounds::BoundsRule,
    ) -> Result<(Self, crate::bounds::SkipReport)> {
        let Some(odometry) = self.odometry.take() else {
            return Ok((self, crate::bounds::SkipReport::default()));
        };
        let (odometry, report) = odometry.retain_near(rule)?;
        if report.counts.far > 0 {
            self.notes.push(format!(
                "{} odometry poses far from the rest were skipped (the bounds rule)",
                report.counts.far
            ));
        }
        self.odometry = Some(odometry);
        Ok((self, report))
    }

    /// The scans, from the first, in recorded order (read from the source anew).
    ///
    /// # Errors
    /// When the source cannot be read again; each item is the scan or the error reading it.
    pub fn scans(&self) -> Result<Scans<'_>> {
        self.scans.scans()
    }

    /// How many scans there are, when the source knows without reading them.
    pub fn scan_count_hint(&self) -> Option<usize> {
        self.scans.len_hint()
    }

    /// The odometry (pose of the base frame in the odometry frame), if recorded.
    pub fn odometry(&self) -> Option<&PoseHistory> {
        self.odometry.as_ref()
    }

    /// The odometry frame (default `odom`).
    pub fn odom_frame(&self) -> &str {
        &self.odom_frame
    }

    /// The robot's base frame (default `base_link`).
    pub fn base_frame(&self) -> &str {
        &self.base_frame
    }

    /// The transform tree (sensor mounts, and whatever else was recorded).
    pub fn transforms(&self) -> &TransformTree {
        &self.transforms
    }

    /// The map, if one was recorded.
    pub fn map(&self) -> Option<&OccupancyGrid> {
        self.map.as_ref()
    }

    /// What was chosen or assumed while reading the recording, in order.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The pose of sensor frame `frame` on the robot (sensor → base) at time `t`: the
    /// identity when `frame` is the base frame, or when the tree is empty and there is
    /// nothing to compose (a note says so when a recording is built that way).
    ///
    /// # Errors
    /// [`OccupancyError::NoTransformChain`] when the tree does not link `frame` to the base
    /// frame; [`OccupancyError::TimeOutOfRange`] when a moving link does not cover `t`.
    pub fn mount_at(&self, frame: &str, t: f64) -> Result<Isometry2<f64>> {
        if self.transforms.is_empty() {
            return Ok(Isometry2::identity());
        }
        self.transforms.lookup(frame, &self.base_frame, t)
    }

    /// The pose of sensor frame `frame` in the odometry frame at time `t`:
    /// `odometry(t) · mount(frame, t)`.
    ///
    /// # Errors
    /// [`OccupancyError::NoSamples`] when the recording has no odometry; the errors of
    /// [`PoseHistory::pose_at`] and [`Recording::mount_at`].
    pub fn sensor_pose_at(&self, frame: &str, t: f64) -> Result<Isometry2<f64>> {
        let odometry = self.odometry.as_ref().ok_or(OccupancyError::NoSamples {
            what: "odometry of the recording",
        })?;
        Ok(odometry.pose_at(t)? * self.mount_at(frame, t)?)
    }
}
