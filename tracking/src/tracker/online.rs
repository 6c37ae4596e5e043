//! Detection and tracking scan by scan, in the world (or odometry) frame: the loop that the
//! real-data evaluation ([`crate::tracker::eval`]) and a robot's pipeline share.
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
use crate::detector::Detector;
use crate::tracker::Tracker;
use crate::tracker::recurring::RecurringObjects;
use crate::tracker::static_map::{StaticMap, StaticMapParams};

/// A detector, an optional map of static objects and a tracker, stepped scan by scan.
///
/// # Example
/// ```
/// use haunts_occupancy::{LaserScan, Pose2};
/// use haunts_tracking::detector::{LegDetector, LegDetectorParams};
/// use haunts_tracking::kalman::{KalmanParams, KalmanTracker};
/// use haunts_tracking::tracker::online::OnlineTracker;
/// use haunts_tracking::tracker::static_map::StaticMapParams;
///
/// let detector = LegDetector::new(LegDetectorParams::default())?;
/// let mut tracker = KalmanTracker::new(KalmanParams::default())?;
/// let mut online = OnlineTracker::new(&detector, &mut tracker, Some(StaticMapParams::default()))?;
/// // An empty room: nothing to detect, nothing tracked.
/// let scan = LaserScan::new(0.0, -1.5, 0.01, 0.05, 20.0, vec![f64::INFINITY; 300], vec![])?;
/// let step = online.step(&scan, &Pose2::identity())?;
/// assert_eq!(step.detections, 0);
/// assert!(online.tracker().tracks().is_empty());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct OnlineTracker<'a> {
    detector: &'a dyn Detector,
    tracker: &'a mut dyn Tracker,
    statics: Option<StaticMap>,
    recurring: Option<&'a RecurringObjects>,
    /// Scratch: the live tracks' positions, which the static map must not absorb.
    people: Vec<Point2<f64>>,
}

/// What one [`OnlineTracker::step`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Step {
    /// Detections given to the tracker.
    pub detections: usize,
}

impl<'a> OnlineTracker<'a> {
    /// Detection with `detector`, tracking with `tracker`, and (when `static_map` is given)
    /// an online map of static objects that removes their legs.
    ///
    /// # Errors
    /// As [`StaticMapParams::check`].
    pub fn new(
        detector: &'a dyn Detector,
        tracker: &'a mut dyn Tracker,
        static_map: Option<StaticMapParams>,
    ) -> Result<Self> {
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
    pub fn with_recurring(mut self, recurring: &'a RecurringObjects) -> Self {
        self.recurring = Some(recurring);
        self
    }

    /// Detects people in `scan`, taken from `sensor` (the sensor's pose in the tracking
    /// frame), and updates the tracker at the scan's stamp; the reported tracks are
    /// [`Tracker::tracks`] of [`OnlineTracker::tracker`].
    ///
    /// # Errors
    /// The static map's and the tracker's time and pose errors (a stamp earlier than the
    /// previous one, a non-finite pose), the detector's errors. The static map may already
    /// hold the scan when the tracker refuses it.
    pub fn step(&mut self, scan: &LaserScan, sensor: &Pose2) -> Result<Step> {
        let recurring = self.recurring;
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
        self.tracker.update(scan.stamp, &moved)?;
        Ok(Step {
            detections: found.len(),
        })
    }

    /// The tracker (its tracks, finished tracks, trajectories).
    pub fn tracker(&self) -> &dyn Tracker {
        self.tracker
    }

    /// The map of static objects, when there is one.
    pub fn static_map(&self) -> Option<&StaticMap> {
        self.statics.as_ref()
    }
}
