//! Detection and tracking scan by scan, in the world (or odometry) frame: the loop that the
//! real-data evaluation ([`crate::eval::sequence`]) and a robot's pipeline share.
//!
//! Each [`OnlineTracker::step`] takes a scan and the sensor's pose when it was taken:
//! 1. with a [`StaticMap`], the scan is mapped first (tracked people excluded) and legs on
//!    objects that have been there for a while — posts, table and chair legs — are dropped
//!    before pairing, unless a tracked person stands there; with [`RecurringObjects`]
//!    (built from the whole day first), legs on objects that recur across the day's
//!    patrols are dropped too;
//! 2. the detections are moved to the world frame with the sensor pose;
//! 3. the tracker is updated at the scan's stamp.

use haunts_occupancy::{LaserScan, Pose2};
use nalgebra::Point2;

use crate::Result;
use crate::detect::Detector;
use crate::detect::recurring::RecurringObjects;
use crate::detect::static_map::{StaticMap, StaticMapParams};
use crate::track::{TrackLists, Tracker};

/// A detector, an optional map of static objects and a tracker, stepped scan by scan; it
/// owns its parts, so a robot node can keep one.
///
/// `D` and `T` are any [`Detector`] and [`Tracker`]: owned values, boxed trait objects (the
/// defaults, `Box<dyn Detector>` and `Box<dyn Tracker>`, chosen at run time) or borrowed ones
/// (`&dyn Detector`, `&mut dyn Tracker`), since both traits forward through `&`/`&mut`/`Box`.
///
/// # Example
/// ```
/// use haunts_occupancy::{LaserScan, Pose2};
/// use haunts_tracking::{
///     KalmanParams, KalmanTracker, LegDetector, LegDetectorParams, OnlineTracker,
///     StaticMapParams,
/// };
///
/// let detector = LegDetector::new(LegDetectorParams::default())?;
/// let tracker = KalmanTracker::new(KalmanParams::default())?;
/// let mut online = OnlineTracker::new(detector, tracker, Some(StaticMapParams::default()))?;
/// // An empty room: nothing to detect, nothing tracked.
/// let scan = LaserScan::new(0.0, -1.5, 0.01, 0.05, 20.0, vec![f64::INFINITY; 300], vec![])?;
/// let step = online.step(&scan, &Pose2::identity())?;
/// assert_eq!(step.detections, 0);
/// assert!(step.lists.reported().is_empty());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct OnlineTracker<D = Box<dyn Detector>, T = Box<dyn Tracker>> {
    detector: D,
    tracker: T,
    statics: Option<StaticMap>,
    recurring: Option<RecurringObjects>,
    /// Scratch: the live tracks' positions, which the static map must not absorb.
    people: Vec<Point2<f64>>,
}

/// What one [`OnlineTracker::step`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step<'a> {
    /// Detections given to the tracker.
    pub detections: usize,
    /// The tracker's lists after the step (the reported tracks are
    /// [`TrackLists::reported`]).
    pub lists: &'a TrackLists,
}

impl<D: Detector, T: Tracker> OnlineTracker<D, T> {
    /// Detection with `detector`, tracking with `tracker`, and (when `static_map` is given)
    /// an online map of static objects that removes their legs.
    ///
    /// # Errors
    /// As [`StaticMapParams::check`].
    pub fn new(detector: D, tracker: T, static_map: Option<StaticMapParams>) -> Result<Self> {
        Ok(Self {
            detector,
            tracker,
            statics: static_map.map(StaticMap::new).transpose()?,
            recurring: None,
            people: Vec::new(),
        })
    }

    /// Also drops the candidates (legs) on `recurring` objects, whose cells are in the
    /// frame of the sensor poses given to [`OnlineTracker::step`].
    pub fn with_recurring(mut self, recurring: RecurringObjects) -> Self {
        self.recurring = Some(recurring);
        self
    }

    /// Detects people in `scan`, taken from `sensor` (the sensor's pose in the tracking
    /// frame), updates the tracker at the scan's stamp, and returns the number of
    /// detections and the tracker's lists.
    ///
    /// # Errors
    /// The static map's and the tracker's time and pose errors (a stamp earlier than the
    /// previous one, a non-finite pose), the detector's errors. The static map may already
    /// hold the scan when the tracker refuses it.
    pub fn step(&mut self, scan: &LaserScan, sensor: &Pose2) -> Result<Step<'_>> {
        let recurring = self.recurring.as_ref();
        let off_recurring = |p: &Point2<f64>| recurring.is_none_or(|r| !r.contains(&(sensor * p)));
        let found = match &mut self.statics {
            None if recurring.is_none() => self.detector.detect(scan)?,
            None => self.detector.detect_where(scan, &off_recurring)?,
            Some(map) => {
                self.people.clear();
                self.people
                    .extend(self.tracker.live().iter().map(|tr| tr.position));
                map.insert(scan, sensor, &self.people)?;
                let clearance = map.params().person_clearance;
                let (map, people) = (&*map, &self.people);
                self.detector.detect_where(scan, &|p: &Point2<f64>| {
                    let w = sensor * p;
                    off_recurring(p)
                        && (!map.is_static(&w)
                            || people.iter().any(|q| (q - w).norm() <= clearance))
                })?
            }
        };
        let moved: Vec<_> = found.iter().map(|d| d.transformed(sensor)).collect();
        let lists = self.tracker.update(scan.stamp, &moved)?;
        Ok(Step {
            detections: found.len(),
            lists,
        })
    }

    /// The tracker's lists after the last step.
    pub fn lists(&self) -> &TrackLists {
        self.tracker.lists()
    }

    /// The tracker.
    pub fn tracker(&self) -> &T {
        &self.tracker
    }

    /// The detector.
    pub fn detector(&self) -> &D {
        &self.detector
    }

    /// The map of static objects, when there is one.
    pub fn static_map(&self) -> Option<&StaticMap> {
        self.statics.as_ref()
    }

    /// The recurring objects whose legs are dropped, when given.
    pub fn recurring(&self) -> Option<&RecurringObjects> {
        self.recurring.as_ref()
    }

    /// The detector and the tracker, for a node that ends its run.
    pub fn into_parts(self) -> (D, T) {
        (self.detector, self.tracker)
    }
}
