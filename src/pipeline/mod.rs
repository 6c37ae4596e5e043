//! Seed 000's daily loop on recorded days — a robot's bags as well as simulated days —,
//! the library calls that the `pipeline` example, the `haunts` command and the end-to-end
//! tests share.
//!
//! - [`DayProcessor`] turns one [`Recording`](haunts_occupancy::recording::Recording) into a
//!   [`DayOutput`]: corrected poses (the keyframe [`Localiser`](haunts_similarity::Localiser)
//!   of the similarity crate), the day's occupancy grid, the tracks of people (leg detector,
//!   the day's recurring objects, Kalman + GNN tracker) and the daily density (seed 000
//!   III-B). It reads no ground truth.
//! - [`score`] compares a day with ground truth: the simulator's ([`score::simulated`]) or a
//!   bag's annotated people ([`score::annotated`], `leg_tracker`'s protocol).
//! - [`serve`] turns a layout of the library into what a planner uses: its composite as a
//!   static map, its affordance map as a costmap layer (seed 000's use), and plans without
//!   and with that layer ([`serve::serve_layout`], [`serve::compare_plans`]).
//!
//! The days then go to a [`LayoutLibrary`](haunts_affordance::LayoutLibrary) (done by the
//! caller, in day order, since each day's layout depends on the days before it);
//! [`PipelineParams`] gathers every crate's parameters with the defaults of the example.
//!
//! # Example
//! ```
//! use haunts::pipeline::{DayProcessor, PipelineParams, score};
//! use haunts::sim::{PatrolParams, SimParams, Simulator};
//!
//! // One 40-second patrol of the simulated office.
//! let patrol = PatrolParams::sessions(9.0 * 3600.0, 40.0, 7200.0, 1);
//! let sim = Simulator::new(SimParams::default().with_patrol(patrol))?;
//! let day = sim.day(0)?;
//! let processor = DayProcessor::new(sim.geometry(), PipelineParams::default())?;
//! let output = processor.process(&day.to_recording()?)?;
//! assert_eq!(output.poses.len(), day.scans.len());
//! let scored = score::simulated(&output, &day, processor.params())?;
//! assert!(scored.pose_errors.corrected_rms < 0.2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod day;
pub mod flow;
pub mod results;
pub mod score;
pub mod serve;
pub mod study;

pub use day::{
    DayCounts, DayOutput, DayProcessor, ScanPose, SkippedScan, TrackReport, moved_recording,
};
#[cfg(feature = "serde")]
pub(crate) use day::{moved_points, moved_trajectories};

use haunts_affordance::DensityParams;
use haunts_occupancy::mapping::MapperParams;
use haunts_similarity::LocaliserParams;
use haunts_tracking::detect::LegDetectorParams;
use haunts_tracking::detect::recurring::RecurringParams;
use haunts_tracking::detect::static_map::StaticMapParams;
use haunts_tracking::eval::mot::ClearMotParams;
use haunts_tracking::track::kalman::KalmanParams;
use nalgebra::Point2;

/// What went wrong in the pipeline: the error of the crate that refused, or bad input.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// Grids, scans, mapping.
    #[error(transparent)]
    Occupancy(#[from] haunts_occupancy::OccupancyError),
    /// Detection, tracking, metrics.
    #[error(transparent)]
    Tracking(#[from] haunts_tracking::TrackingError),
    /// Scan matching, map comparison, clustering.
    #[error(transparent)]
    Similarity(#[from] haunts_similarity::SimilarityError),
    /// Densities, layouts, hypertime, TA maps.
    #[error(transparent)]
    Affordance(#[from] haunts_affordance::AffordanceError),
    /// The simulator.
    #[error(transparent)]
    Sim(#[from] haunts_sim::SimError),
    /// Planning.
    #[error(transparent)]
    Planning(#[from] haunts_planning::PlanningError),
    /// Reading or writing a bag (a recording, a results MCAP).
    #[error(transparent)]
    Bag(#[from] haunts_bag::BagError),
    /// A simulated day whose per-scan series (scans, true poses, true people) differ in
    /// length from the scans processed.
    #[error("day {day}: {what} has {len} entries for {scans} scans")]
    DayLengths {
        /// The day's index.
        day: usize,
        /// The series that does not match the scans.
        what: &'static str,
        /// Its length.
        len: usize,
        /// The number of scans.
        scans: usize,
    },
    /// A flow map without any traffic: nothing to plan around.
    #[error("the flow map has no traffic (no observation inside its grid)")]
    NoTraffic,
    /// A recording with nothing to process.
    #[error("the recording has no {what}")]
    EmptyDay {
        /// What was missing.
        what: &'static str,
    },
    /// A file could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A later pass over a recording read fewer scans than the first (the file changed
    /// while the day was processed).
    #[error("the recording changed while it was read: {first} scans at first, ended at scan {now}")]
    RecordingChanged {
        /// Scans read by the first pass.
        first: usize,
        /// Where a later pass ended.
        now: usize,
    },
    /// A day scored against annotations of which none falls to a scored frame (no ground
    /// truth, none of it at the day's scans or in the bearing window): no score, rather than
    /// a perfect MOTA of nothing.
    #[error(
        "nothing to score: no annotated person in the {scans} scans scored ({annotations} annotations, {unassigned} of them belonging to no scan)"
    )]
    NothingScored {
        /// Scans with a time (processed or skipped).
        scans: usize,
        /// Ground-truth records given.
        annotations: usize,
        /// Ground-truth records that belong to no scan.
        unassigned: usize,
    },
    /// A parameter breaks its rule.
    #[error(transparent)]
    InvalidParameter(#[from] haunts_core::InvalidParameter),
    /// A training bag has several `geometry_msgs/PoseArray` topics and none was named as
    /// its labels (feature `train`, [`crate::training`]).
    #[cfg(feature = "train")]
    #[error("{path}: several geometry_msgs/PoseArray topics ({topics:?}); name the labels' topic")]
    LabelTopics {
        /// The bag.
        path: std::path::PathBuf,
        /// Its PoseArray topics.
        topics: Vec<String>,
    },
    /// A figure or a report could not be drawn or written (feature `figures`).
    #[cfg(feature = "figures")]
    #[error(transparent)]
    Figure(#[from] crate::figure::FigureError),
    /// A day could not be folded into a layout library (feature `serde`: a live session's
    /// `close_day`).
    #[cfg(feature = "serde")]
    #[error(transparent)]
    LibraryMerge(Box<crate::artifact::LibraryMergeError>),
}

/// The pipeline's result type.
pub type Result<T, E = PipelineError> = std::result::Result<T, E>;

/// Every parameter of the daily loop.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct PipelineParams {
    /// Cell size of the daily maps, densities and layouts, metres (default 0.1).
    pub resolution: f64,
    /// Scan matching.
    pub localiser: LocaliserParams,
    /// The daily occupancy grid's sensor model.
    pub mapper: MapperParams,
    /// The leg detector.
    pub detector: LegDetectorParams,
    /// The Kalman + GNN tracker (default: [`KalmanParams::default`] but confirmed after 5
    /// hits without further evidence — with the recurring objects' legs dropped, what
    /// remains is people, and standing people seldom show a leg pair or walk).
    pub tracker: KalmanParams,
    /// The online map of static objects whose legs are not people (default `None`: on the
    /// simulated office it absorbs people standing at tables for minutes, and `recurring`
    /// does its work; it also triples the tracking cost).
    pub static_map: Option<StaticMapParams>,
    /// Objects whose legs recur across the day's patrols — table and chair legs — are not
    /// people (default `Some`: see [`RecurringObjects`](haunts_tracking::detect::recurring::RecurringObjects)); their legs are dropped before
    /// tracking. A day of a single patrol marks nothing.
    pub recurring: Option<RecurringParams>,
    /// Human hits and laser visits.
    pub density: DensityParams,
    /// Hits and visits are counted on every this many scans (default 10: 1 Hz of a 10 Hz
    /// laser).
    pub density_every: usize,
    /// CLEAR MOT's matching.
    pub mot: ClearMotParams,
    /// A true person counts as visible to the laser when at least `visible_beams` beams of
    /// the scan returned from their legs ([`PersonTruth::beams`](haunts_sim::PersonTruth),
    /// default 6: both legs hit by the leg detector's minimum of 3 beams each). The other people in the
    /// room are *don't care*: a track on one of them (within the match threshold, and
    /// nearer to it than to any visible person) is neither a match nor a false positive,
    /// as MOT benchmarks treat occluded and distractor objects.
    pub visible_beams: usize,
    /// The frame people are tracked in (default [`TrackingFrame::Corrected`]); tracks,
    /// trajectories and the density are reported in the corrected day frame either way.
    pub tracking_frame: TrackingFrame,
}

/// The frame the tracker of a day works in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TrackingFrame {
    /// The corrected (scan-matched) frame: one frame for the whole day, so that the day's
    /// recurring objects line up across patrols hours apart, but a corrected keyframe can
    /// move it under the live tracks.
    #[default]
    Corrected,
    /// The odometry frame, as `leg_tracker` tracks: smooth from scan to scan whatever the
    /// corrections, with each reported position moved into the corrected frame by its scan's
    /// correction. Right for a single patrol, where odometry drifts little while a person
    /// is in view.
    Odometry,
}

impl Default for PipelineParams {
    fn default() -> Self {
        Self {
            resolution: 0.1,
            localiser: LocaliserParams::default(),
            mapper: MapperParams::default(),
            detector: LegDetectorParams::default(),
            tracker: KalmanParams::default()
                .with_confirm_hits(5)
                .with_confirm_strong_hits(0),
            static_map: None,
            recurring: Some(RecurringParams::default()),
            density: DensityParams::default(),
            density_every: 10,
            mot: ClearMotParams::default(),
            visible_beams: 6,
            tracking_frame: TrackingFrame::Corrected,
        }
    }
}

impl PipelineParams {
    /// The parameters for a real laser: the tracking crate's own defaults — the Kalman
    /// tracker's confirmation by leg pairs or a walk, and the online map of static objects
    /// (`leg_tracker`'s local map) instead of the recurring objects of a day of patrols —,
    /// tracking in the odometry frame ([`TrackingFrame::Odometry`]). The
    /// [`Default`] tracker settings were chosen on the simulated office, whose legs are
    /// clean; on a real laser they confirm clutter (BENCHMARKS.md, "daily loop on a real
    /// bag"). Every keyframe is drawn into the localiser's map
    /// ([`LocaliserParams::revisit_distance`] 0): the revisit rule was measured on the
    /// simulated patrol only, and on `general_tracking_moving_1`, a robot that does not
    /// patrol, it refused 49 keyframe matches instead of 39 (BENCHMARKS.md, issue 19).
    pub fn real_laser() -> Self {
        Self {
            tracker: KalmanParams::default(),
            static_map: Some(StaticMapParams::default()),
            recurring: None,
            tracking_frame: TrackingFrame::Odometry,
            localiser: LocaliserParams::default().with_revisit_distance(0.0),
            ..Self::default()
        }
    }

    /// The same parameters for a laser of `hz` scans per second. The counts given in scans —
    /// the tracker's [`KalmanParams::confirm_hits`], the recurring objects'
    /// [`RecurringParams::min_scans`] and [`PipelineParams::density_every`] — are set for a
    /// 10 Hz laser (the simulated office's and most 2-D lasers'); this scales each by
    /// `hz / 10` (rounded, at least 1) so that they keep their durations. On the simulated
    /// office at 40 Hz, the 10 Hz counts confirm clutter four times as fast: 1,258 false
    /// positives instead of 52 over the same two minutes (`tests/pipeline.rs`).
    /// A rate that is not finite and positive leaves the parameters unchanged; `check`
    /// still checks them.
    ///
    /// ```
    /// use haunts::pipeline::PipelineParams;
    /// let fast = PipelineParams::default().at_scan_rate(40.0);
    /// assert_eq!(fast.tracker.confirm_hits, 4 * PipelineParams::default().tracker.confirm_hits);
    /// assert_eq!(fast.density_every, 40);
    /// ```
    #[must_use]
    pub fn at_scan_rate(mut self, hz: f64) -> Self {
        if !(hz.is_finite() && hz > 0.0) {
            return self;
        }
        let scale = |count: usize| ((count as f64 * hz / 10.0).round() as usize).max(1);
        self.tracker.confirm_hits = scale(self.tracker.confirm_hits);
        self.density_every = scale(self.density_every);
        if let Some(r) = &mut self.recurring {
            r.min_scans = scale(r.min_scans);
        }
        self
    }

    /// The parameters after checking every rule.
    ///
    /// # Errors
    /// [`PipelineError::InvalidParameter`] naming the parameter, or the owning crate's
    /// error for its own parameters.
    pub fn check(self) -> Result<Self> {
        haunts_core::positive("resolution", self.resolution)?;
        haunts_core::at_least_one("density_every", self.density_every)?;
        self.localiser.check()?;
        self.mapper.check()?;
        self.detector.check()?;
        self.tracker.check()?;
        if let Some(r) = self.recurring {
            r.check()?;
        }
        if let Some(s) = self.static_map {
            s.check()?;
        }
        self.density.check()?;
        self.mot.check()?;
        Ok(self)
    }
}

/// Mean of the known (finite) values of `density` over the cells whose centre lies within
/// 1 m of one of `points` and farther than 1 m from every point of `except` (0 if there is
/// none): where one layout's tables stand and another's do not. With `points` a layout's
/// tables and sofas and `except` those of the other layouts, a layout's affordance map that
/// follows its furniture scores higher than with the roles swapped.
pub(crate) fn density_near(
    density: &haunts_occupancy::Grid<f64>,
    points: &[Point2<f64>],
    except: &[Point2<f64>],
) -> f64 {
    let g = density.geometry();
    let within = |c, set: &[Point2<f64>]| set.iter().any(|p| (g.cell_center(c) - p).norm() <= 1.0);
    let (sum, n) = density
        .cells()
        .filter(|(c, v)| v.is_finite() && within(*c, points) && !within(*c, except))
        .fold((0.0, 0usize), |(s, n), (_, v)| (s + v, n + 1));
    sum / n.max(1) as f64
}
