//! A live session: a robot's messages pushed one at a time, in arrival order, and the people
//! it sees out after each scan, in the fixed (odometry) frame. This is the shape a robot node
//! owns: [`LiveSession`] keeps everything it needs between messages (the odometry around the
//! scans still waiting, the sensors' mounts, the tracker) and nothing more.
//!
//! A scan is tracked once its pose is known: an odometry sample stamped after the scan has
//! arrived (the pose is then interpolated between the two samples around the scan's stamp,
//! bit for bit as [`PoseHistory::pose_at`] does over a whole recording) and the chain of
//! transforms from the scan's frame to the robot's base is known. Until then it waits, at
//! most [`LiveParams::window`] seconds of arrival time, so that odometry and transforms that
//! come a little after their scan (as they do on a real robot, and in bags) are still used;
//! scans are tracked in arrival order, so a waiting scan holds back the ones behind it.
//!
//! Bad input on the stream is dropped and counted by reason ([`Dropped`]), never a panic and
//! never an error that ends the session: a scan without beams or with more than
//! [`LiveParams::max_beams`], a scan whose description does not check, a stamp going
//! backwards, no odometry or no transform at a scan's stamp once its window has passed, a
//! non-finite odometry or transform. NaN and infinite ranges keep their REP 117 meaning (no
//! return) and are counted, not dropped: the detector reads them as the offline evaluation
//! does.
//!
//! With [`LiveSession::with_defaults`] (`eval_tracking`'s defaults: the geometric leg
//! detector, the particle tracker, the map of static objects) the people reported after each
//! scan are those the offline evaluation
//! ([`haunts_tracking::eval::sequence::evaluate_sequence`]) reports after the same scan of the
//! same recording, when every scan's odometry arrives within the window (`tests/live.rs`).
//!
//! # Example
//! ```
//! use haunts::live::{LiveParams, LiveSession};
//! use haunts::nalgebra::{Isometry2, Vector2};
//! use haunts::occupancy::LaserScan;
//!
//! let mut live = LiveSession::with_defaults(LiveParams::default())?;
//! let pose = |x: f64| Isometry2::new(Vector2::new(x, 0.0), 0.0);
//! live.push_tf(0.0, ("base_link", "laser"), 0.0, &pose(0.2), true);
//! live.push_odom(0.0, 0.0, &pose(0.0));
//! // An empty room: the scan waits for the odometry after its stamp, then is tracked.
//! let scan = LaserScan::new(0.05, -1.5, 0.01, 0.05, 20.0, vec![f64::INFINITY; 300], vec![])?;
//! assert!(live.push_scan(0.06, "laser", scan).is_empty());
//! let tracked = live.push_odom(0.1, 0.1, &pose(0.1));
//! assert_eq!(tracked.len(), 1);
//! assert!(tracked[0].people.is_empty());
//! assert!((tracked[0].sensor.translation.x - 0.25).abs() < 1e-12);
//! // A scan from before the last one is dropped and counted.
//! let old = LaserScan::new(0.0, -1.5, 0.01, 0.05, 20.0, vec![f64::INFINITY; 300], vec![])?;
//! assert!(live.push_scan(0.12, "laser", old).is_empty());
//! assert_eq!(live.dropped().stamp_backwards, 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#[cfg(feature = "serde")]
pub mod day;
pub mod messages;
pub mod replay;

use std::collections::VecDeque;

use haunts_occupancy::{LaserScan, Pose2, PoseHistory, TransformTree, frame_name};
use haunts_tracking::detect::static_map::StaticMapParams;
use haunts_tracking::detect::{Detector, LegDetector, LegDetectorParams};
use haunts_tracking::track::Tracker;
use haunts_tracking::track::online::OnlineTracker;
use haunts_tracking::track::particle::{ParticleParams, ParticleTracker};
use nalgebra::{Point2, Vector2};

/// Parameters of a [`LiveSession`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct LiveParams {
    /// The robot's frame, which the odometry moves and the sensors' mounts lead to
    /// (default `base_link`).
    pub base_frame: String,
    /// The frame the odometry gives the robot's pose in, where the people are tracked
    /// (default `odom`; the name is written to the day's spool).
    pub fixed_frame: String,
    /// Seconds of arrival time a scan waits for its odometry and transforms (default 0.5 s:
    /// five scans at 10 Hz).
    pub window: f64,
    /// Whether odometry is expected (default): people are tracked in the odometry frame. Without,
    /// in each scan's own frame, as the offline evaluation does for a recording without
    /// odometry (a moving robot then moves the people it sees).
    pub odometry: bool,
    /// Whether a sensor whose frame no transform links to the base is taken as mounted at the
    /// base's origin (default `false`: such a scan is dropped as `missing_tf`). The offline
    /// evaluation assumes so for a recording with no static transform at all.
    pub mount_at_base: bool,
    /// Scans with more beams are dropped (default 100 000: ten times a 0.1°, 360° scanner).
    pub max_beams: usize,
    /// Scans that may wait at once; beyond, the oldest is dropped (default 64).
    pub max_pending: usize,
    /// Odometry samples kept while no scan needs them; beyond, the oldest go (default 10 000:
    /// 100 s at 100 Hz).
    pub max_odometry: usize,
    /// The map of static objects whose legs are dropped before pairing (default: on, as in
    /// `eval_tracking`).
    pub static_map: Option<StaticMapParams>,
}

impl Default for LiveParams {
    fn default() -> Self {
        Self {
            base_frame: "base_link".into(),
            fixed_frame: "odom".into(),
            window: 0.5,
            odometry: true,
            mount_at_base: false,
            max_beams: 100_000,
            max_pending: 64,
            max_odometry: 10_000,
            static_map: Some(StaticMapParams::default()),
        }
    }
}

impl LiveParams {
    /// Sets [`LiveParams::base_frame`].
    pub fn with_base_frame(mut self, frame: impl Into<String>) -> Self {
        self.base_frame = frame.into();
        self
    }

    /// Sets [`LiveParams::fixed_frame`].
    pub fn with_fixed_frame(mut self, frame: impl Into<String>) -> Self {
        self.fixed_frame = frame.into();
        self
    }

    /// Sets [`LiveParams::window`].
    pub fn with_window(mut self, seconds: f64) -> Self {
        self.window = seconds;
        self
    }

    /// Sets [`LiveParams::odometry`].
    pub fn with_odometry(mut self, expected: bool) -> Self {
        self.odometry = expected;
        self
    }

    /// Sets [`LiveParams::mount_at_base`].
    pub fn with_mount_at_base(mut self, assume: bool) -> Self {
        self.mount_at_base = assume;
        self
    }

    /// Sets [`LiveParams::max_beams`].
    pub fn with_max_beams(mut self, beams: usize) -> Self {
        self.max_beams = beams;
        self
    }

    /// Sets [`LiveParams::static_map`].
    pub fn with_static_map(mut self, static_map: Option<StaticMapParams>) -> Self {
        self.static_map = static_map;
        self
    }

    /// The parameters, if the window is finite and ≥ 0 and the counts are at least 1.
    ///
    /// # Errors
    /// [`haunts_core::InvalidParameter`] naming the parameter.
    pub fn check(self) -> Result<Self, haunts_core::InvalidParameter> {
        haunts_core::non_negative("window", self.window)?;
        haunts_core::at_least_one("max_beams", self.max_beams)?;
        haunts_core::at_least_one("max_pending", self.max_pending)?;
        haunts_core::at_least_one("max_odometry", self.max_odometry)?;
        Ok(self)
    }
}

/// A person the session tracks, in the fixed frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Person {
    /// The track's id.
    pub id: u64,
    /// Position, metres.
    pub position: Point2<f64>,
    /// Velocity, metres per second.
    pub velocity: Vector2<f64>,
}

/// One tracked scan: the confirmed people after it.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanPeople {
    /// The scan's position in the stream (0 for the first scan pushed, dropped ones included).
    pub index: usize,
    /// Its header stamp, seconds.
    pub stamp: f64,
    /// When it arrived, seconds.
    pub received: f64,
    /// Its frame.
    pub frame: String,
    /// The sensor's pose in the fixed frame at the stamp.
    pub sensor: Pose2,
    /// The confirmed people, in the fixed frame.
    pub people: Vec<Person>,
}

/// What the session dropped, by reason (and the ranges it read as no return).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct Dropped {
    /// Scans without a beam.
    pub empty_scan: usize,
    /// Scans with more than [`LiveParams::max_beams`] beams.
    pub too_many_beams: usize,
    /// Scans whose description does not check (a non-finite stamp or angle, a zero
    /// increment, bad range limits, intensities not one per range) or whose arrival time is
    /// not finite.
    pub invalid_scan: usize,
    /// Scans stamped before the last tracked one.
    pub stamp_backwards: usize,
    /// Scans with no odometry at their stamp once their window had passed.
    pub no_odometry: usize,
    /// Scans whose frame no transform linked to the base once their window had passed.
    pub missing_tf: usize,
    /// Scans dropped because [`LiveParams::max_pending`] scans were waiting already.
    pub pending_overflow: usize,
    /// Scans the detector or the tracker refused.
    pub tracker_refused: usize,
    /// Odometry samples with a non-finite stamp or pose.
    pub bad_odometry: usize,
    /// Odometry samples stamped like one already held (the first is kept, as a recording's
    /// history keeps it).
    pub duplicate_odometry: usize,
    /// Transforms with a non-finite pose or an empty frame name.
    pub bad_tf: usize,
    /// Ranges that are NaN or infinite, over all tracked scans: not dropped, read as no
    /// return (REP 117).
    pub non_finite_ranges: usize,
}

impl Dropped {
    /// Messages dropped (scans, odometry samples and transforms; the ranges read as no return
    /// are not counted).
    pub fn messages(&self) -> usize {
        self.scans() + self.bad_odometry + self.duplicate_odometry + self.bad_tf
    }

    /// Scans dropped.
    pub fn scans(&self) -> usize {
        self.empty_scan
            + self.too_many_beams
            + self.invalid_scan
            + self.stamp_backwards
            + self.no_odometry
            + self.missing_tf
            + self.pending_overflow
            + self.tracker_refused
    }
}

/// A scan waiting for its pose.
#[derive(Debug, Clone)]
struct Pending {
    index: usize,
    received: f64,
    frame: String,
    scan: LaserScan,
}

/// What a waiting scan can do now.
enum Resolve {
    Wait,
    Drop(fn(&mut Dropped) -> &mut usize),
    /// Tracked from the sensor's pose; with the mount it was found with, to keep.
    Track(Pose2, Option<Pose2>),
}

/// Detection and tracking on a live stream of scans, odometry and transforms (see the
/// [module docs](self)). `D` and `T` are any [`Detector`] and [`Tracker`], owned or boxed.
pub struct LiveSession<D = Box<dyn Detector>, T = Box<dyn Tracker>> {
    online: OnlineTracker<D, T>,
    params: LiveParams,
    /// Odometry samples `(stamp, pose)`, by increasing stamp: from the last one at or before
    /// the last tracked scan's stamp on.
    odometry: VecDeque<(f64, Pose2)>,
    /// The latest transform of each `(parent, child)` link, static or not.
    links: Vec<(String, String, Pose2)>,
    /// The sensors' mounts found so far (frame → its pose on the base), kept once found.
    mounts: Vec<(String, Pose2)>,
    pending: VecDeque<Pending>,
    /// The latest arrival time seen.
    now: f64,
    last_stamp: f64,
    scans: usize,
    tracked: usize,
    dropped: Dropped,
    /// The day's messages, spooled for [`LiveSession::close_day`].
    #[cfg(feature = "serde")]
    spool: Option<day::DaySpool>,
}

impl<D, T> std::fmt::Debug for LiveSession<D, T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveSession")
            .field("params", &self.params)
            .field("scans", &self.scans)
            .field("tracked", &self.tracked)
            .field("pending", &self.pending.len())
            .field("dropped", &self.dropped)
            .finish_non_exhaustive()
    }
}

impl LiveSession {
    /// A session with `eval_tracking`'s defaults: the geometric leg detector and the
    /// particle tracker with their default parameters, except that a track keeps only its
    /// latest position ([`ParticleParams::max_history`] 1; the history decides nothing, and a
    /// session that runs all day must not keep every track's every sample).
    ///
    /// # Errors
    /// Bad parameters.
    pub fn with_defaults(params: LiveParams) -> crate::pipeline::Result<Self> {
        let detector: Box<dyn Detector> = Box::new(LegDetector::new(LegDetectorParams::default())?);
        let tracker: Box<dyn Tracker> = Box::new(ParticleTracker::new(
            ParticleParams::default().with_max_history(Some(1)),
        )?);
        Self::new(detector, tracker, params)
    }
}

impl<D: Detector, T: Tracker> LiveSession<D, T> {
    /// A session detecting with `detector` and tracking with `tracker` (fresh: its time must
    /// not be past the first scan's stamp).
    ///
    /// # Errors
    /// Bad parameters.
    pub fn new(detector: D, tracker: T, params: LiveParams) -> crate::pipeline::Result<Self> {
        let params = params.check()?;
        Ok(Self {
            online: OnlineTracker::new(detector, tracker, params.static_map)?,
            params,
            odometry: VecDeque::new(),
            links: Vec::new(),
            mounts: Vec::new(),
            pending: VecDeque::new(),
            now: f64::NEG_INFINITY,
            last_stamp: f64::NEG_INFINITY,
            scans: 0,
            tracked: 0,
            dropped: Dropped::default(),
            #[cfg(feature = "serde")]
            spool: None,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &LiveParams {
        &self.params
    }

    /// What was dropped so far, by reason.
    pub fn dropped(&self) -> &Dropped {
        &self.dropped
    }

    /// Scans pushed so far.
    pub fn scans(&self) -> usize {
        self.scans
    }

    /// Scans tracked so far.
    pub fn tracked(&self) -> usize {
        self.tracked
    }

    /// Scans waiting for their odometry or transforms.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// The tracker.
    pub fn tracker(&self) -> &T {
        self.online.tracker()
    }

    /// A laser scan from the sensor frame `frame`, arrived at `received` (seconds, the clock
    /// of the other messages' arrival): the scans tracked now, in order (this one, once its
    /// pose is known, and any that waited before it), each with its confirmed people.
    pub fn push_scan(&mut self, received: f64, frame: &str, scan: LaserScan) -> Vec<ScanPeople> {
        let index = self.scans;
        self.scans += 1;
        self.arrived(received);
        let (beams, d) = (scan.ranges.len(), &mut self.dropped);
        let refused = if beams == 0 {
            Some(&mut d.empty_scan)
        } else if beams > self.params.max_beams {
            Some(&mut d.too_many_beams)
        } else if !received.is_finite() {
            Some(&mut d.invalid_scan)
        } else {
            None
        };
        if let Some(count) = refused {
            *count += 1;
            return self.drain(false);
        }
        let Ok(scan) = scan.check() else {
            self.dropped.invalid_scan += 1;
            return self.drain(false);
        };
        #[cfg(feature = "serde")]
        if let Some(spool) = &mut self.spool {
            spool.scan(received, frame, &scan);
        }
        if self.pending.len() >= self.params.max_pending {
            self.pending.pop_front();
            self.dropped.pending_overflow += 1;
        }
        self.pending.push_back(Pending {
            index,
            received,
            frame: frame_name(frame).to_owned(),
            scan,
        });
        self.drain(false)
    }

    /// An odometry sample: the base's pose in the fixed frame at `stamp`, arrived at
    /// `received`. Returns the scans it let be tracked.
    pub fn push_odom(&mut self, received: f64, stamp: f64, pose: &Pose2) -> Vec<ScanPeople> {
        self.arrived(received);
        if !stamp.is_finite() || !haunts_occupancy::pose_is_finite(pose) {
            self.dropped.bad_odometry += 1;
            return self.drain(false);
        }
        let at = self.odometry.partition_point(|s| s.0 < stamp);
        if self.odometry.get(at).is_some_and(|s| s.0 == stamp) {
            self.dropped.duplicate_odometry += 1;
            return self.drain(false);
        }
        self.odometry.insert(at, (stamp, *pose));
        #[cfg(feature = "serde")]
        if let Some(spool) = &mut self.spool {
            let frames = (
                self.params.fixed_frame.as_str(),
                self.params.base_frame.as_str(),
            );
            spool.odometry(received, stamp, frames, pose);
        }
        if self.pending.is_empty() && self.odometry.len() > self.params.max_odometry {
            self.odometry.pop_front();
        }
        self.drain(false)
    }

    /// A transform: `child`'s pose in `parent` at `stamp` (`/tf_static` when `is_static`,
    /// else `/tf`), arrived at `received`. The latest pose of each link is kept, static or
    /// not (a sensor's mount published on `/tf` is as good as on `/tf_static`); a sensor's
    /// mount, once found, stays. Returns the scans it let be tracked.
    pub fn push_tf(
        &mut self,
        received: f64,
        link: (&str, &str),
        stamp: f64,
        transform: &Pose2,
        is_static: bool,
    ) -> Vec<ScanPeople> {
        self.arrived(received);
        let (parent, child) = (frame_name(link.0), frame_name(link.1));
        if parent.is_empty() || child.is_empty() || !haunts_occupancy::pose_is_finite(transform) {
            self.dropped.bad_tf += 1;
            return self.drain(false);
        }
        #[cfg(feature = "serde")]
        if let Some(spool) = &mut self.spool {
            spool.transform(received, stamp, (parent, child), transform, is_static);
        }
        #[cfg(not(feature = "serde"))]
        let _ = (stamp, is_static);
        match self
            .links
            .iter_mut()
            .find(|(p, c, _)| p == parent && c == child)
        {
            Some(link) => link.2 = *transform,
            None => self
                .links
                .push((parent.to_owned(), child.to_owned(), *transform)),
        }
        self.drain(false)
    }

    /// The end of the stream: every waiting scan is tracked with what has arrived, or dropped.
    pub fn finish(&mut self) -> Vec<ScanPeople> {
        self.drain(true)
    }

    fn arrived(&mut self, received: f64) {
        if received.is_finite() {
            self.now = self.now.max(received);
        }
    }

    /// Tracks or drops the waiting scans in order, until one must wait (none with `flush`).
    fn drain(&mut self, flush: bool) -> Vec<ScanPeople> {
        let mut out = Vec::new();
        while let Some(front) = self.pending.front() {
            let expired = flush || self.now > front.received + self.params.window;
            let resolve = self.resolve(front, expired);
            match resolve {
                Resolve::Wait => break,
                Resolve::Drop(reason) => {
                    self.pending.pop_front();
                    *reason(&mut self.dropped) += 1;
                }
                Resolve::Track(sensor, mount) => {
                    let Some(p) = self.pending.pop_front() else {
                        break;
                    };
                    if let Some(m) = mount
                        && !self.mounts.iter().any(|(f, _)| *f == p.frame)
                    {
                        self.mounts.push((p.frame.clone(), m));
                    }
                    if let Some(people) = self.track(p, sensor) {
                        out.push(people);
                    }
                }
            }
        }
        out
    }

    /// What the scan at the front can do: wait, be dropped, or be tracked from a pose.
    fn resolve(&self, p: &Pending, expired: bool) -> Resolve {
        let t = p.scan.stamp;
        if t < self.last_stamp {
            return Resolve::Drop(|d| &mut d.stamp_backwards);
        }
        if !self.params.odometry {
            return Resolve::Track(Pose2::identity(), None);
        }
        let Some(mount) = self.mount(&p.frame) else {
            return if expired {
                Resolve::Drop(|d| &mut d.missing_tf)
            } else {
                Resolve::Wait
            };
        };
        // The first sample after `t`, as `PoseHistory::pose_at` picks it.
        let after = self.odometry.partition_point(|s| s.0 <= t);
        let pose = match (after.checked_sub(1), self.odometry.get(after)) {
            (Some(before), Some(next)) => {
                let (t0, p0) = &self.odometry[before];
                PoseHistory::interpolate((*t0, p0), (next.0, &next.1), t)
            }
            // At the last sample's stamp exactly, with none after it: that sample's pose.
            (Some(before), None) if expired && self.odometry[before].0 == t => {
                self.odometry[before].1
            }
            _ if expired => return Resolve::Drop(|d| &mut d.no_odometry),
            _ => return Resolve::Wait,
        };
        Resolve::Track(pose * mount, Some(mount))
    }

    /// The mount of the sensor frame `frame` on the base, when the transforms link them.
    fn mount(&self, frame: &str) -> Option<Pose2> {
        if let Some((_, m)) = self.mounts.iter().find(|(f, _)| f == frame) {
            return Some(*m);
        }
        let mut tree = TransformTree::new();
        for (parent, child, pose) in &self.links {
            // A frame with two parents keeps the first: the tree refuses the second.
            let _ = tree.add_static(parent, child, *pose);
        }
        match tree.lookup_static(frame, &self.params.base_frame) {
            Ok(m) => Some(m),
            Err(_) if self.params.mount_at_base => Some(Pose2::identity()),
            Err(_) => None,
        }
    }

    /// Tracks one scan from `sensor`.
    fn track(&mut self, p: Pending, sensor: Pose2) -> Option<ScanPeople> {
        self.last_stamp = p.scan.stamp;
        self.trim_odometry();
        self.dropped.non_finite_ranges += p.scan.ranges.iter().filter(|r| !r.is_finite()).count();
        let Ok(step) = self.online.step(&p.scan, &sensor) else {
            self.dropped.tracker_refused += 1;
            return None;
        };
        let people = step
            .lists
            .reported()
            .iter()
            .map(|t| Person {
                id: t.id,
                position: t.position,
                velocity: t.velocity,
            })
            .collect();
        self.tracked += 1;
        Some(ScanPeople {
            index: p.index,
            stamp: p.scan.stamp,
            received: p.received,
            frame: p.frame,
            sensor,
            people,
        })
    }

    /// Drops the odometry samples no later scan can use: all but the last at or before the
    /// last tracked stamp.
    fn trim_odometry(&mut self) {
        while self.odometry.len() >= 2 && self.odometry[1].0 <= self.last_stamp {
            self.odometry.pop_front();
        }
    }
}
