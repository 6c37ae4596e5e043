//! The `Tracker` trait, the `Track` it reports, the time rules every tracker shares, and a
//! trivial tracker for tests.
//!
//! Trackers take the detections of one instant (in a fixed frame: world or odometry, so that
//! a moving robot does not move the people) and return their current tracks. The two real
//! trackers are [`crate::track::kalman::KalmanTracker`] and [`crate::track::particle::ParticleTracker`];
//! [`crate::eval::evaluate_sequence`] runs any of them on a recorded sequence and scores it with CLEAR MOT.

pub(crate) mod assign;
mod combination;
pub mod dummy;
pub mod kalman;
pub mod online;
pub mod particle;

pub use combination::CombinationParams;
pub use dummy::{
    DropReason, Dropped, DummyFilterParams, DummyReport, SpeedMeasure, TrajectoryStats,
    filter_dummies,
};
pub use kalman::{KalmanParams, KalmanTracker};
pub use online::OnlineTracker;
pub use particle::{ParticleParams, ParticleTracker};

use nalgebra::{Matrix2, Point2, Vector2};

use crate::detect::{Detection, check_detections, rule};
use crate::{Result, TrackingError, Trajectory};

/// One tracked person.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Track {
    /// Identity, unique within one tracker and never reused.
    pub id: u64,
    /// Estimated position, metres, in the frame of the detections.
    pub position: Point2<f64>,
    /// Estimated velocity, m/s.
    pub velocity: Vector2<f64>,
    /// Covariance of the position, m².
    pub covariance: Matrix2<f64>,
    /// Seconds since the track was born.
    pub age: f64,
    /// Number of updates in which a detection supported the track.
    pub hits: usize,
    /// The running average of the confidences of the detections that supported the track
    /// (`leg_tracker`'s track confidence; with the forest detector, the mean leg
    /// probability).
    #[cfg_attr(feature = "serde", serde(default))]
    pub confidence: f64,
    /// `(time, estimated position)` after each update since birth (before confirmation
    /// too), oldest first; capped at the tracker's `max_history` (the oldest samples are
    /// dropped). A finished track's history ends at the last time it could be reported
    /// (its last detection plus the tracker's `max_report_coast`).
    pub history: Vec<(f64, Point2<f64>)>,
}

impl Track {
    /// The track's history as a [`Trajectory`] with the same id.
    pub fn trajectory(&self) -> Trajectory {
        Trajectory {
            id: self.id,
            samples: self.history.clone(),
        }
    }

    /// The track with its history after `last` dropped (the last time the track was reported or could have
    /// been): a track that ends because nobody is seen any more ends where it was last seen,
    /// not where the motion model coasted it to before it was deleted.
    pub(crate) fn ended_at(mut self, last: f64) -> Self {
        self.history.retain(|s| s.0 <= last);
        self
    }

    /// Appends `(time, position)` to the history, dropping the oldest samples beyond `cap`.
    pub(crate) fn record(&mut self, time: f64, cap: Option<usize>) {
        self.history.push((time, self.position));
        if let Some(cap) = cap {
            if self.history.len() > cap {
                let excess = self.history.len() - cap;
                self.history.drain(..excess);
            }
        }
    }
}

/// Turns the detections of successive instants into tracks.
///
/// Object safe, `Send` and `Sync` (as the other traits of the workspace), and implemented for
/// `&mut T` and `Box<T>` of any tracker, so a robot node can own a boxed tracker or lend one.
/// A tracker implements two methods: [`Tracker::update`], which returns the lists it
/// publishes ([`TrackLists`]: reported, confirmed, tentative and finished tracks, and the
/// resets), and [`Tracker::lists`], the same lists between updates; every other method is
/// provided from them. No track is ever lost silently: tracks that end move to
/// [`TrackLists::finished`], and time jumps are counted in [`TrackLists::resets`].
///
/// Every tracker of this crate follows the same time rules: a time earlier than the last one
/// is a [`TrackingError::TimeWentBackwards`] and leaves the state unchanged; a step longer
/// than the tracker's `max_time_gap` ends every live track (they move to
/// [`TrackLists::finished`]), counts one reset, and starts again from the new detections.
#[auto_impl::auto_impl(&mut, Box)]
pub trait Tracker: Send + Sync {
    /// Advances to `time` (seconds) with the detections made then, and returns the lists
    /// after that update (the reported tracks are [`TrackLists::reported`]).
    ///
    /// # Errors
    /// [`TrackingError::NonFiniteTime`], [`TrackingError::TimeWentBackwards`], and the
    /// error of the first detection that [`Detection::checked_covariance`] refuses; the
    /// state is unchanged on error.
    fn update(&mut self, time: f64, detections: &[Detection]) -> Result<&TrackLists>;

    /// The lists after the last update (empty before the first).
    fn lists(&self) -> &TrackLists;

    /// The tracks reported by the last update ([`TrackLists::reported`]).
    fn tracks(&self) -> &[Track] {
        self.lists().reported()
    }

    /// Tracks that ended ([`TrackLists::finished`]).
    fn finished(&self) -> &[Track] {
        self.lists().finished()
    }

    /// How many times a time jump made the tracker start afresh ([`TrackLists::resets`]).
    fn resets(&self) -> usize {
        self.lists().resets()
    }

    /// Every confirmed live track, reported or not ([`TrackLists::confirmed`]).
    fn live(&self) -> &[Track] {
        self.lists().confirmed()
    }

    /// The live tracks not yet confirmed as people ([`TrackLists::tentative`]).
    fn tentative(&self) -> &[Track] {
        self.lists().tentative()
    }

    /// Every finished and confirmed live track as a trajectory, by increasing id
    /// ([`TrackLists::trajectories`]).
    fn trajectories(&self) -> Vec<Trajectory> {
        self.lists().trajectories()
    }
}

/// The lists a tracker publishes after each update: its reported, confirmed and tentative
/// tracks, every track that ended, and how often a time jump reset it. A tracker of your
/// own keeps one and fills it with [`TrackLists::clear_live`], [`TrackLists::list`],
/// [`TrackLists::finish`] and [`TrackLists::count_reset`] (see the second example).
///
/// # Example
/// ```
/// use haunts_tracking::{Detection, DetectionTracker, Tracker};
/// use nalgebra::Point2;
///
/// let mut tracker = DetectionTracker::new(5.0)?;
/// let d = Detection::isotropic(Point2::new(1.0, 2.0), 0.1);
/// let lists = tracker.update(0.0, &[d])?;
/// assert_eq!(lists.reported().len(), 1);
/// // Ten seconds later: longer than the gap, so the tracker starts afresh.
/// let lists = tracker.update(10.0, &[])?;
/// assert_eq!((lists.reported().len(), lists.finished().len(), lists.resets()), (0, 1, 1));
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
///
/// A tracker of your own: one track that follows the first detection.
/// ```
/// use haunts_tracking::{Detection, Result, Track, TrackLists, Tracker};
/// use nalgebra::{Matrix2, Point2, Vector2};
///
/// #[derive(Default)]
/// struct FollowFirst {
///     lists: TrackLists,
/// }
///
/// impl Tracker for FollowFirst {
///     fn update(&mut self, time: f64, detections: &[Detection]) -> Result<&TrackLists> {
///         self.lists.clear_live();
///         if let Some(d) = detections.first() {
///             let track = Track {
///                 id: 0,
///                 position: d.position,
///                 velocity: Vector2::zeros(),
///                 covariance: Matrix2::identity(),
///                 age: time,
///                 hits: 1,
///                 confidence: d.confidence,
///                 history: vec![(time, d.position)],
///             };
///             self.lists.list(&track, true, true);
///         }
///         Ok(&self.lists)
///     }
///
///     fn lists(&self) -> &TrackLists {
///         &self.lists
///     }
/// }
///
/// let mut tracker = FollowFirst::default();
/// let d = Detection::isotropic(Point2::new(1.0, 2.0), 0.1);
/// assert_eq!(tracker.update(0.0, &[d])?.reported()[0].position, Point2::new(1.0, 2.0));
/// assert_eq!(tracker.live().len(), 1); // provided by the trait
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TrackLists {
    reported: Vec<Track>,
    confirmed: Vec<Track>,
    tentative: Vec<Track>,
    finished: Vec<Track>,
    resets: usize,
}

impl TrackLists {
    /// The tracks reported by the last update: confirmed as people and seen recently enough
    /// (within the tracker's `max_report_coast`).
    pub fn reported(&self) -> &[Track] {
        &self.reported
    }

    /// Every confirmed live track, reported or not. A tracker that reports only some of its
    /// confirmed tracks (those seen lately) keeps the others here, so that
    /// [`TrackLists::trajectories`] includes them.
    pub fn confirmed(&self) -> &[Track] {
        &self.confirmed
    }

    /// The live tracks not yet confirmed as people: followed, but neither reported nor
    /// kept as trajectories unless they are confirmed later. For display and diagnosis
    /// (how many people a tracker follows before it dares to report them). Empty for a
    /// tracker without a confirmation stage.
    pub fn tentative(&self) -> &[Track] {
        &self.tentative
    }

    /// Tracks that ended (deleted, or closed by a reset), in the order they ended. Only
    /// tracks that were confirmed are kept.
    pub fn finished(&self) -> &[Track] {
        &self.finished
    }

    /// How many times a time jump made the tracker start afresh.
    pub fn resets(&self) -> usize {
        self.resets
    }

    /// Every finished and confirmed live track as a trajectory, by increasing id.
    pub fn trajectories(&self) -> Vec<Trajectory> {
        let mut all: Vec<Trajectory> = self
            .finished
            .iter()
            .chain(&self.confirmed)
            .map(Track::trajectory)
            .collect();
        all.sort_by_key(|t| t.id);
        all.dedup_by_key(|t| t.id);
        all
    }

    /// Forgets the live lists of the last update (the finished tracks and the resets stay):
    /// the first step of an update, before its tracks are listed again.
    pub fn clear_live(&mut self) {
        self.reported.clear();
        self.confirmed.clear();
        self.tentative.clear();
    }

    /// Lists a live track after an update: tentative unless `confirmed`; a confirmed track is
    /// also reported when `reported`.
    pub fn list(&mut self, track: &Track, confirmed: bool, reported: bool) {
        match (confirmed, reported) {
            (false, _) => self.tentative.push(track.clone()),
            (true, false) => self.confirmed.push(track.clone()),
            (true, true) => {
                self.confirmed.push(track.clone());
                self.reported.push(track.clone());
            }
        }
    }

    /// `track` ended: it joins the finished tracks with its history kept up to `last`, the
    /// last time it was or could have been reported.
    pub fn finish(&mut self, track: Track, last: f64) {
        self.finished.push(track.ended_at(last));
    }

    /// Counts one reset (a time jump that made the tracker start afresh).
    pub fn count_reset(&mut self) {
        self.resets += 1;
    }
}

/// What one new time means to a tracker (see [`Clock`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Step {
    /// The first update, or the first after a reset.
    First,
    /// An ordinary step of `dt ≥ 0` seconds.
    Advance(f64),
    /// A jump longer than the allowed gap: reset, then start afresh.
    Reset,
}

/// The time rules shared by the trackers: monotonic time, resets on long gaps.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Clock {
    last: Option<f64>,
    max_gap: f64,
}

impl Clock {
    pub(crate) fn new(max_gap: f64) -> Self {
        Self {
            last: None,
            max_gap,
        }
    }

    /// What `time` would be, without changing anything; checks the detections too.
    pub(crate) fn check(&self, time: f64, detections: &[Detection]) -> Result<Step> {
        if !time.is_finite() {
            return Err(TrackingError::NonFiniteTime { time });
        }
        check_detections(detections)?;
        Ok(match self.last {
            None => Step::First,
            Some(previous) if time < previous => {
                return Err(TrackingError::TimeWentBackwards { previous, time });
            }
            Some(previous) if time - previous > self.max_gap => Step::Reset,
            Some(previous) => Step::Advance(time - previous),
        })
    }

    /// Accepts `time` after [`Clock::check`] returned `step` for it; a reset is counted in
    /// `lists`.
    pub(crate) fn commit(&mut self, time: f64, step: Step, lists: &mut TrackLists) {
        if step == Step::Reset {
            lists.count_reset();
        }
        self.last = Some(time);
    }
}

/// What a new track has shown so far of being a person, and the rule that confirms it:
/// at least `hits` detections, and either `strong_hits` detections of at least
/// `strong_confidence` (leg pairs: people show both legs now and then, a post or a table leg
/// never does), a walk of at least `min_travel` metres from where it was born (people
/// walk, furniture does not), or a running average of its detections' confidences of at
/// least `mean_confidence` (`leg_tracker`'s rule, for a learned detector's probabilities).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Evidence {
    pub(crate) hits: usize,
    pub(crate) strong: usize,
    pub(crate) origin: Point2<f64>,
    pub(crate) travel: f64,
    pub(crate) confidence_sum: f64,
}

/// The thresholds of [`Evidence::confirms`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ConfirmRule {
    pub(crate) hits: usize,
    pub(crate) strong_confidence: f64,
    pub(crate) strong_hits: usize,
    pub(crate) min_travel: f64,
    pub(crate) mean_confidence: Option<f64>,
}

impl Evidence {
    /// The evidence of a track born at `origin` from a detection of `confidence`.
    pub(crate) fn new(origin: Point2<f64>, confidence: f64, rule: &ConfirmRule) -> Self {
        Self {
            hits: 1,
            strong: usize::from(confidence >= rule.strong_confidence),
            origin,
            travel: 0.0,
            confidence_sum: confidence,
        }
    }

    /// The running average of the detections' confidences.
    pub(crate) fn mean_confidence(&self) -> f64 {
        self.confidence_sum / self.hits.max(1) as f64
    }

    /// Adds one detection of `confidence` supporting a track now estimated at `position`.
    pub(crate) fn add(&mut self, position: &Point2<f64>, confidence: f64, rule: &ConfirmRule) {
        self.hits += 1;
        self.strong += usize::from(confidence >= rule.strong_confidence);
        self.travel = self.travel.max((position - self.origin).norm());
        self.confidence_sum += confidence;
    }

    /// Whether the evidence confirms a person.
    pub(crate) fn confirms(&self, rule: &ConfirmRule) -> bool {
        self.hits >= rule.hits
            && (self.strong >= rule.strong_hits
                || self.travel >= rule.min_travel
                || rule
                    .mean_confidence
                    .is_some_and(|c| self.mean_confidence() >= c))
    }
}

/// Checks a `max_time_gap` parameter.
pub(crate) fn check_gap(max_time_gap: f64) -> Result<()> {
    haunts_core::positive("max_time_gap", max_time_gap)?;
    Ok(())
}

/// Checks a `confirm_mean_confidence` parameter (finite when given).
pub(crate) fn check_confirm_mean(confirm_mean_confidence: Option<f64>) -> Result<()> {
    let mean = confirm_mean_confidence.unwrap_or(0.0);
    rule(
        mean.is_finite(),
        "confirm_mean_confidence",
        mean,
        "must be finite when given",
    )
}

/// Checks a `max_history` parameter.
pub(crate) fn check_history(max_history: Option<usize>) -> Result<()> {
    let v = max_history.unwrap_or(1);
    rule(v >= 1, "max_history", v as f64, "must be >= 1 when given")
}

/// The trivial tracker: every detection is a new one-update track (no association); the
/// previous update's tracks end at each update. Useful in tests and as the floor any real
/// tracker must beat.
///
/// # Example
/// ```
/// use haunts_tracking::{Detection, DetectionTracker, Tracker};
/// use nalgebra::Point2;
///
/// let mut t = DetectionTracker::new(5.0)?;
/// let d = Detection::isotropic(Point2::new(1.0, 2.0), 0.1);
/// assert_eq!(t.update(0.0, &[d, d])?.reported().len(), 2);
/// let ids: Vec<u64> = t.update(0.1, &[d])?.reported().iter().map(|t| t.id).collect();
/// assert_eq!(ids, vec![2]);
/// assert_eq!(t.finished().len(), 2);
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct DetectionTracker {
    clock: Clock,
    next_id: u64,
    lists: TrackLists,
}

impl DetectionTracker {
    /// A tracker that resets on steps longer than `max_time_gap` seconds.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] unless `max_time_gap` is finite and > 0.
    pub fn new(max_time_gap: f64) -> Result<Self> {
        check_gap(max_time_gap)?;
        Ok(Self {
            clock: Clock::new(max_time_gap),
            next_id: 0,
            lists: TrackLists::default(),
        })
    }
}

impl Tracker for DetectionTracker {
    fn update(&mut self, time: f64, detections: &[Detection]) -> Result<&TrackLists> {
        let step = self.clock.check(time, detections)?;
        self.clock.commit(time, step, &mut self.lists);
        // The previous update's tracks end now, where they were seen.
        let ended = std::mem::take(&mut self.lists.reported);
        self.lists.finished.extend(ended);
        self.lists.clear_live();
        for d in detections {
            let id = self.next_id;
            self.next_id += 1;
            let track = Track {
                id,
                position: d.position,
                velocity: Vector2::zeros(),
                covariance: d.covariance,
                age: 0.0,
                hits: 1,
                confidence: d.confidence,
                history: vec![(time, d.position)],
            };
            self.lists.list(&track, true, true);
        }
        Ok(&self.lists)
    }

    fn lists(&self) -> &TrackLists {
        &self.lists
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn the_clock_rejects_reversal_and_flags_jumps() {
        let mut clock = Clock::new(5.0);
        let mut lists = TrackLists::default();
        assert_eq!(clock.check(10.0, &[]).unwrap(), Step::First);
        clock.commit(10.0, Step::First, &mut lists);
        assert_eq!(clock.check(10.5, &[]).unwrap(), Step::Advance(0.5));
        assert_eq!(clock.check(10.0, &[]).unwrap(), Step::Advance(0.0));
        assert!(matches!(
            clock.check(9.0, &[]),
            Err(TrackingError::TimeWentBackwards {
                previous: 10.0,
                time: 9.0
            })
        ));
        assert_eq!(clock.check(20.0, &[]).unwrap(), Step::Reset);
        clock.commit(20.0, Step::Reset, &mut lists);
        assert_eq!(lists.resets(), 1);
        assert!(matches!(
            clock.check(f64::INFINITY, &[]),
            Err(TrackingError::NonFiniteTime { .. })
        ));
    }

    #[test]
    fn evidence_confirms_on_leg_pairs_or_on_a_walk() {
        let rule = ConfirmRule {
            hits: 3,
            strong_confidence: 1.0,
            strong_hits: 2,
            min_travel: 1.2,
            mean_confidence: None,
        };
        // A post: many weak hits in place.
        let mut post = Evidence::new(Point2::origin(), 0.5, &rule);
        for _ in 0..20 {
            post.add(&Point2::new(0.05, 0.0), 0.5, &rule);
        }
        assert!(!post.confirms(&rule));
        // A person standing: two pairs among three hits.
        let mut standing = Evidence::new(Point2::origin(), 1.0, &rule);
        standing.add(&Point2::origin(), 0.5, &rule);
        assert!(!standing.confirms(&rule));
        standing.add(&Point2::origin(), 1.0, &rule);
        assert!(standing.confirms(&rule));
        // A walker seen as one leg: confirmed once 1.2 m from where it was born, even if it
        // comes back (the farthest distance counts).
        let mut walker = Evidence::new(Point2::origin(), 0.5, &rule);
        walker.add(&Point2::new(0.6, 0.0), 0.5, &rule);
        walker.add(&Point2::new(1.1, 0.0), 0.5, &rule);
        assert!(!walker.confirms(&rule));
        walker.add(&Point2::new(1.25, 0.0), 0.5, &rule);
        walker.add(&Point2::new(0.2, 0.0), 0.5, &rule);
        assert!(walker.confirms(&rule));
        // With a learned detector: confirmed once three hits average a leg probability of
        // 0.6, the post above never (0.5).
        let learned = ConfirmRule {
            mean_confidence: Some(0.6),
            ..rule
        };
        assert!(!post.confirms(&learned));
        let mut leg = Evidence::new(Point2::origin(), 0.9, &learned);
        leg.add(&Point2::origin(), 0.3, &learned);
        assert!(!leg.confirms(&learned));
        leg.add(&Point2::origin(), 0.6, &learned);
        assert!(leg.confirms(&learned));
        approx::assert_relative_eq!(leg.mean_confidence(), 0.6);
    }

    #[test]
    fn history_is_capped_from_the_oldest_end() {
        let mut t = Track {
            id: 1,
            position: Point2::origin(),
            velocity: Vector2::zeros(),
            covariance: Matrix2::identity(),
            age: 0.0,
            hits: 0,
            confidence: 0.0,
            history: Vec::new(),
        };
        for k in 0..5 {
            t.position.x = k as f64;
            t.record(k as f64, Some(3));
        }
        let times: Vec<f64> = t.history.iter().map(|s| s.0).collect();
        assert_eq!(times, vec![2.0, 3.0, 4.0]);
        assert!(check_history(Some(0)).is_err());
        assert!(check_history(None).is_ok());
    }
}
