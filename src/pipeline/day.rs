//! [`DayProcessor`]: one recorded day → its map, tracks and density, with no ground truth.

use haunts_affordance::{DailyDensity, HitCounter, TimedPoint, move_day};
use haunts_occupancy::mapping::OccupancyMapper;
use haunts_occupancy::raycast::{ScanStats, VisitCounter};
use haunts_occupancy::recording::{RecordedScan, Recording};
use haunts_occupancy::{GridGeometry, LaserScan, OccupancyGrid, Pose2};
use haunts_similarity::Localiser;
use haunts_tracking::Trajectory;
use haunts_tracking::detect::recurring::RecurringObjects;
use haunts_tracking::detect::{Detection, Detector, Leg, LegDetector};
use haunts_tracking::track::kalman::KalmanTracker;
use haunts_tracking::track::online::OnlineTracker;
use nalgebra::Point2;

use super::{PipelineError, PipelineParams, Result, TrackingFrame};

/// The corrected pose of one scan of the recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanPose {
    /// The scan's position in the recording (0 for the first scan read, skipped ones
    /// included).
    pub index: usize,
    /// The scan's header stamp, seconds.
    pub stamp: f64,
    /// When it was recorded (a bag's log time), seconds.
    pub received: f64,
    /// The sensor's pose in the day's frame (the odometry frame at the first scan, corrected
    /// by scan matching).
    pub pose: Pose2,
    /// Whether the scan was a keyframe (matched, and drawn into the day's map).
    pub keyframe: bool,
    /// The sensor's pose by odometry alone, in the odometry frame (the corrected `pose`
    /// without odometry).
    pub odometry: Pose2,
}

/// `recording` as if its odometry had been zeroed elsewhere: every odometry pose `p` becomes
/// `by · p` (scans, mounts, map and notes as they are). Processed again on a library's grid
/// with `by` a registration's transform (day frame → library frame), a day is mapped,
/// tracked and counted directly in the library's frame: the localiser's corrections do not
/// depend on where the odometry was zeroed (it matches in the frame of the odometry's first
/// pose), so this is the day itself, drawn once onto the library's cells rather than
/// resampled ([`DayOutput::moved`]).
///
/// # Errors
/// [`PipelineError::EmptyDay`] for a recording without odometry (its poses come from scan
/// matching alone, in its first scan's frame: there is nothing to move).
pub fn moved_recording(recording: Recording, by: &Pose2) -> Result<Recording> {
    let Some(odometry) = recording.odometry() else {
        return Err(PipelineError::EmptyDay {
            what: "odometry to move",
        });
    };
    let moved = haunts_occupancy::PoseHistory::new(odometry.samples().map(|(t, p)| (t, by * p)))?
        .with_tolerance(odometry.tolerance())?;
    let (odom, base) = (
        recording.odom_frame().to_owned(),
        recording.base_frame().to_owned(),
    );
    Ok(recording.with_odometry(moved, &odom, &base))
}

/// `trajectories` moved by `pose`.
pub(crate) fn moved_trajectories(trajectories: &[Trajectory], pose: &Pose2) -> Vec<Trajectory> {
    trajectories
        .iter()
        .map(|t| Trajectory {
            id: t.id,
            samples: t.samples.iter().map(|&(s, p)| (s, pose * p)).collect(),
        })
        .collect()
}

/// Timed `points` moved by `pose`.
pub(crate) fn moved_points(points: &[TimedPoint], pose: &Pose2) -> Vec<TimedPoint> {
    points
        .iter()
        .map(|t| TimedPoint {
            time: t.time,
            position: pose * t.position,
        })
        .collect()
}

/// The frame the localiser matches in: the odometry frame moved to the odometry's first
/// pose, so that the day's corrections depend on the robot's motion only, not on where its
/// odometry was zeroed. Scan matching on a grid is not invariant under a rotation of the
/// grid (rasterisation, the sub-cell phase of the matching map): on
/// `general_tracking_moving_1` with its odometry moved by a rigid transform, matching in the
/// odometry frame itself drifted 2–3 m differently in each frame, and only 17–23 % of the
/// moved day's map lay on the original's at the true transform (BENCHMARKS.md, issue 46).
#[derive(Debug, Clone, Copy)]
struct Anchor {
    /// The odometry's first finite pose, in the odometry frame.
    pose: Pose2,
    /// Its inverse: odometry frame → anchored frame.
    into: Pose2,
    /// The localiser's grid in the anchored frame: the anchored odometry's box grown by
    /// [`ANCHOR_MARGIN`], its corners on multiples of the localiser's resolution.
    geometry: GridGeometry,
}

/// Metres around the odometry's box that the localiser's matching map covers (the laser's
/// useful range, as [`DayProcessor::geometry_for`]'s usual margin).
const ANCHOR_MARGIN: f64 = 12.0;

impl Anchor {
    /// The anchor of a recording with odometry (`None` without: scan matching alone starts
    /// in the first scan's own frame already).
    ///
    /// # Errors
    /// [`PipelineError::EmptyDay`] when no odometry pose is finite; a box too large for a
    /// grid.
    fn of(recording: &Recording, resolution: f64) -> Result<Option<Self>> {
        let Some(odometry) = recording.odometry() else {
            return Ok(None);
        };
        let finite = |p: &Pose2| {
            p.translation.vector.iter().all(|v| v.is_finite()) && p.rotation.angle().is_finite()
        };
        let Some(pose) = odometry.samples().map(|(_, p)| *p).find(|p| finite(p)) else {
            return Err(PipelineError::EmptyDay {
                what: "odometry with a finite pose",
            });
        };
        let into = pose.inverse();
        let (mut lo, mut hi) = (Point2::origin(), Point2::origin());
        for (_, p) in odometry.samples() {
            if finite(p) {
                let q: Point2<f64> = (into * *p).translation.vector.into();
                (lo, hi) = (lo.inf(&q), hi.sup(&q));
            }
        }
        let snap = |v: f64| (v / resolution).floor() * resolution;
        let origin = Point2::new(snap(lo.x - ANCHOR_MARGIN), snap(lo.y - ANCHOR_MARGIN));
        let cells = |from: f64, to: f64| ((to + ANCHOR_MARGIN - from) / resolution).ceil() as usize;
        let geometry = GridGeometry::new(
            resolution,
            origin,
            cells(origin.x, hi.x).max(1),
            cells(origin.y, hi.y).max(1),
        )?;
        Ok(Some(Self {
            pose,
            into,
            geometry,
        }))
    }
}

/// A scan the day left out, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedScan {
    /// The scan's position in the recording.
    pub index: usize,
    /// Its header stamp, when it could be read.
    pub stamp: Option<f64>,
    /// When it was recorded, when it could be read (scoring by a bag's clock counts the
    /// skipped scans too, as `leg_tracker_benchmarks` does).
    pub received: Option<f64>,
    /// Why it was left out.
    pub reason: String,
}

/// The tracks reported after one scan.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackReport {
    /// The scan's position in the recording.
    pub index: usize,
    /// `(track id, position in the day's frame)` of every confirmed track.
    pub tracks: Vec<(u64, Point2<f64>)>,
}

/// What the day's processing counted.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DayCounts {
    /// Scans read from the recording (skipped ones included).
    pub scans: usize,
    /// Keyframes of the localisation.
    pub keyframes: usize,
    /// Keyframes whose scan match was refused (they kept their predicted pose).
    pub refused_matches: usize,
    /// Detections given to the tracker.
    pub detections: usize,
    /// Scans whose beams and tracked people went into the density.
    pub density_scans: usize,
    /// What the density's raycasting counted.
    pub density_rays: ScanStats,
}

/// One processed day.
#[derive(Debug, Clone)]
pub struct DayOutput {
    /// The day's occupancy grid, from the keyframe scans at their corrected poses.
    pub map: OccupancyGrid,
    /// The corrected pose of every scan that was not skipped, in recording order.
    pub poses: Vec<ScanPose>,
    /// The scans left out, and why.
    pub skipped: Vec<SkippedScan>,
    /// The confirmed tracks after each scan of `poses`, in the same order.
    pub reports: Vec<TrackReport>,
    /// Every track of the day from its birth, in the day's frame.
    pub trajectories: Vec<Trajectory>,
    /// Tracked positions at the density scans: the detections of a hypertime model.
    pub tracked: Vec<TimedPoint>,
    /// Human hits and laser visits (seed 000 III-B).
    pub density: DailyDensity,
    /// What was counted.
    pub counts: DayCounts,
    /// What was chosen or assumed (the recording's own notes first).
    pub notes: Vec<String>,
}

impl DayOutput {
    /// The day moved into another frame, where its own frame lies at `pose` (a registration's
    /// transform, day frame → library frame), onto `geometry` at the day's resolution: its
    /// map and density resampled by nearest neighbour ([`move_day`]), and every pose,
    /// track, report and tracked point moved by `pose` (the odometry poses too: the moved
    /// day's frames are all the target's). The second value counts the day's occupied cells
    /// that fell outside `geometry`.
    ///
    /// # Errors
    /// A resolution other than the day's; the density's own checks.
    pub fn moved(&self, pose: &Pose2, geometry: &GridGeometry) -> Result<(Self, usize)> {
        let moved = move_day(&self.map, &self.density, pose, geometry)?;
        let day = Self {
            map: moved.map,
            density: moved.density,
            poses: self
                .poses
                .iter()
                .map(|p| ScanPose {
                    pose: pose * p.pose,
                    odometry: pose * p.odometry,
                    ..*p
                })
                .collect(),
            skipped: self.skipped.clone(),
            reports: self
                .reports
                .iter()
                .map(|r| TrackReport {
                    index: r.index,
                    tracks: r.tracks.iter().map(|&(id, p)| (id, pose * p)).collect(),
                })
                .collect(),
            trajectories: moved_trajectories(&self.trajectories, pose),
            tracked: moved_points(&self.tracked, pose),
            counts: self.counts,
            notes: self.notes.clone(),
        };
        Ok((day, moved.outside))
    }

    /// The robot's (sensor's) positions at the keyframes.
    pub fn keyframe_positions(&self) -> Vec<Point2<f64>> {
        self.poses
            .iter()
            .filter(|p| p.keyframe)
            .map(|p| p.pose.translation.vector.into())
            .collect()
    }
}

/// Seed 000's daily loop on one [`Recording`], with no ground truth: it owns the loop's
/// parameters and its leg detector; each [`DayProcessor::process`] builds the day's own
/// localiser, mappers and tracker, so one processor serves any number of days, in parallel.
///
/// A day is processed in three passes over the recording's scans, each read anew from its
/// source (a bag is streamed from the file, never held in memory):
/// 1. **localisation and mapping**: each scan's sensor pose from odometry and the mounts of
///    the transform tree ([`Recording::sensor_pose_at`]), corrected by the keyframe
///    [`Localiser`] (scan matching alone when the recording has no odometry); keyframes are
///    drawn into the day's occupancy grid;
/// 2. the day's **recurring objects** (legs that come back at most of the day's patrols are
///    furniture, [`RecurringObjects`]);
/// 3. **detection and tracking** in the day's frame (leg detector, Kalman + GNN tracker),
///    and the **daily density** on every [`PipelineParams::density_every`]-th scan: its
///    beams' visits and the tracked positions' hits.
///
/// Scans that cannot be used are skipped and listed in [`DayOutput::skipped`] with the
/// reason: an unreadable message, a stamp that is not finite or goes backwards, a stamp
/// outside the odometry, a sensor frame the transform tree does not link to the robot.
#[derive(Debug, Clone)]
pub struct DayProcessor {
    geometry: GridGeometry,
    params: PipelineParams,
    detector: LegDetector,
}

impl DayProcessor {
    /// A processor whose maps and densities lie on `geometry` (every day on the same cells,
    /// so that days compare; its resolution is replaced by [`PipelineParams::resolution`]).
    ///
    /// # Errors
    /// Bad parameters (the owning crate's error for its own), a geometry that cannot take
    /// the resolution.
    pub fn new(geometry: GridGeometry, params: PipelineParams) -> Result<Self> {
        let params = params.check()?;
        Ok(Self {
            geometry: geometry.with_resolution(params.resolution)?,
            detector: LegDetector::new(params.detector)?,
            params,
        })
    }

    /// A geometry for one recording: the box of its odometry positions grown by `margin`
    /// metres on every side (the laser's useful range), at `resolution`. Without odometry,
    /// the recording's map's geometry when it has one (at `resolution`), else a square of
    /// side 2·`margin` around the first scan. (A recorded map often covers a whole building,
    /// far more than a day sees: the odometry's box keeps the day's grids small.)
    ///
    /// # Errors
    /// [`PipelineError::InvalidParameter`] for a resolution or margin that is not finite
    /// and positive; a grid too large for the occupancy crate.
    pub fn geometry_for(
        recording: &Recording,
        resolution: f64,
        margin: f64,
    ) -> Result<GridGeometry> {
        haunts_core::positive("resolution", resolution)?;
        haunts_core::positive("margin", margin)?;
        let (mut lo, mut hi) = (Point2::new(0.0, 0.0), Point2::new(0.0, 0.0));
        if recording.odometry().is_none()
            && let Some(map) = recording.map()
        {
            return Ok(map.geometry().with_resolution(resolution)?);
        }
        if let Some(odometry) = recording.odometry() {
            lo = Point2::new(f64::INFINITY, f64::INFINITY);
            hi = -lo;
            for (_, pose) in odometry.samples() {
                let p = pose.translation.vector;
                if p.iter().all(|v| v.is_finite()) {
                    lo = lo.inf(&p.into());
                    hi = hi.sup(&p.into());
                }
            }
            if !lo.x.is_finite() {
                return Err(PipelineError::EmptyDay {
                    what: "odometry with a finite pose",
                });
            }
        }
        let origin = lo - nalgebra::Vector2::repeat(margin);
        let size = hi - lo + nalgebra::Vector2::repeat(2.0 * margin);
        let cells = |len: f64| (len / resolution).ceil().max(1.0) as usize;
        Ok(GridGeometry::new(
            resolution,
            origin,
            cells(size.x),
            cells(size.y),
        )?)
    }

    /// The geometry of the day's maps and densities.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The parameters.
    pub fn params(&self) -> &PipelineParams {
        &self.params
    }

    /// Processes one recorded day (see the [type docs](Self)).
    ///
    /// # Errors
    /// [`PipelineError::EmptyDay`] when no scan could be used;
    /// [`PipelineError::RecordingChanged`] when a later pass reads a different number of
    /// scans than the first (the file changed underneath); the crates' errors for the
    /// parameters' and the tracker's refusals.
    pub fn process(&self, recording: &Recording) -> Result<DayOutput> {
        let params = &self.params;
        let mut notes: Vec<String> = recording.notes().to_vec();
        // Pass 1: localisation and the day's map.
        let anchor = Anchor::of(recording, params.localiser.resolution)?;
        let mut localiser = Localiser::new(
            anchor.as_ref().map_or(self.geometry, |a| a.geometry),
            params.localiser,
        )?;
        let mut mapper = OccupancyMapper::new(self.geometry, params.mapper)?;
        let (mut poses, mut skipped) = (Vec::new(), Vec::new());
        let mut last_stamp = f64::NEG_INFINITY;
        let mut read = 0;
        if recording.odometry().is_none() {
            notes.push("no odometry: poses from scan matching alone".to_owned());
        }
        for (index, item) in recording.scans()?.enumerate() {
            read += 1;
            let skip = |times: Option<(f64, f64)>, reason: String| SkippedScan {
                index,
                stamp: times.map(|t| t.0),
                received: times.map(|t| t.1),
                reason,
            };
            let recorded = match item {
                Ok(r) => r,
                Err(e) => {
                    skipped.push(skip(None, e.to_string()));
                    continue;
                }
            };
            let stamp = recorded.scan.stamp;
            let times = Some((stamp, recorded.received));
            if !stamp.is_finite() || stamp < last_stamp {
                let why = format!("stamp {stamp} is not finite or before {last_stamp}");
                skipped.push(skip(times, why));
                continue;
            }
            let located = self.locate(recording, &recorded, anchor.as_ref(), &mut localiser);
            let (located, odometry) = match located {
                Ok(l) => l,
                Err(e) => {
                    skipped.push(skip(times, e.to_string()));
                    continue;
                }
            };
            last_stamp = stamp;
            if located.keyframe {
                mapper.insert(&recorded.scan, &located.pose)?;
            }
            poses.push(ScanPose {
                index,
                stamp,
                received: recorded.received,
                pose: located.pose,
                keyframe: located.keyframe,
                odometry,
            });
        }
        if poses.is_empty() {
            return Err(PipelineError::EmptyDay {
                what: "scan that could be used",
            });
        }
        let map = mapper.occupancy_grid();
        if let Some(hz) = scan_rate(&poses) {
            notes.push(format!(
                "scans at {hz:.1} Hz (median interval); counts given in scans assume 10 Hz \
                 (PipelineParams::at_scan_rate)"
            ));
        }

        // Pass 2: recurring objects. Each scan's legs are kept for pass 3.
        let detector = DayLegs::new(&self.detector);
        let mut day_legs: Vec<Vec<Leg>> = Vec::new();
        let recurring = params
            .recurring
            .map(|r| {
                let pairs = self.posed_scans(recording, &poses, read)?;
                let mut failed = None;
                let built = RecurringObjects::build(
                    &detector,
                    pairs
                        .map_while(|p| p.map_err(|e| failed = Some(e)).ok())
                        .map(|(scan, pose)| {
                            let legs = self.detector.legs(&scan);
                            day_legs.push(legs.clone());
                            detector.next_is(legs);
                            (scan, self.tracking_pose(&pose))
                        }),
                    r,
                );
                match failed {
                    Some(e) => Err(e),
                    None => Ok(built?),
                }
            })
            .transpose()?;

        // Pass 3: tracking and the density.
        let tracker = KalmanTracker::new(params.tracker)?;
        let mut online = OnlineTracker::new(&detector, tracker, params.static_map)?;
        if let Some(r) = recurring {
            online = online.with_recurring(r);
        }
        let mut hits = HitCounter::new(self.geometry, params.density.person_radius)?;
        let mut visits = VisitCounter::new(self.geometry, params.density.visit_rule)?;
        let mut counts = DayCounts {
            scans: read,
            keyframes: localiser.keyframes(),
            refused_matches: localiser.refused(),
            ..DayCounts::default()
        };
        let (mut reports, mut tracked) = (Vec::with_capacity(poses.len()), Vec::new());
        // Per scan: its stamp and the map from the tracking frame to the day's frame.
        let mut corrections: Vec<(f64, Pose2)> = Vec::with_capacity(poses.len());
        for (k, pair) in self.posed_scans(recording, &poses, read)?.enumerate() {
            let (scan, at) = pair?;
            let sensor = self.tracking_pose(&at);
            // Identity in the corrected frame (exactly: positions are not recomposed).
            let correction = match self.params.tracking_frame {
                TrackingFrame::Corrected => Pose2::identity(),
                TrackingFrame::Odometry => at.pose * sensor.inverse(),
            };
            corrections.push((at.stamp, correction));
            if let Some(legs) = day_legs.get_mut(k) {
                detector.next_is(std::mem::take(legs));
            }
            let step = online.step(&scan, &sensor)?;
            counts.detections += step.detections;
            let tracks: Vec<(u64, Point2<f64>)> = step
                .lists
                .reported()
                .iter()
                .map(|t| (t.id, correction * t.position))
                .collect();
            if k % params.density_every == 0 {
                counts.density_scans += 1;
                let rays = visits.add_scan(&scan, &at.pose, params.density.max_range)?;
                counts.density_rays.rays += rays.rays;
                counts.density_rays.skipped_beams += rays.skipped_beams;
                counts.density_rays.cell_visits += rays.cell_visits;
                for (_, p) in &tracks {
                    hits.add(*p);
                    tracked.push(TimedPoint::new(scan.stamp, p.x, p.y));
                }
            }
            reports.push(TrackReport {
                index: at.index,
                tracks,
            });
        }
        let mut trajectories = online.lists().trajectories();
        if self.params.tracking_frame == TrackingFrame::Odometry {
            // Each sample into the day's frame with the correction of the scan it was
            // recorded at (the last scan at or before its time).
            for t in &mut trajectories {
                for (time, p) in &mut t.samples {
                    let k = corrections
                        .partition_point(|c| c.0 <= *time)
                        .saturating_sub(1);
                    if let Some((_, c)) = corrections.get(k) {
                        *p = c * *p;
                    }
                }
            }
        }
        let density = DailyDensity::new(
            hits.into_counts(),
            visits.into_counts(),
            params.density.min_visits,
        )?;
        Ok(DayOutput {
            map,
            poses,
            skipped,
            reports,
            trajectories,
            tracked,
            density,
            counts,
            notes,
        })
    }

    /// The corrected sensor pose of one scan, and its odometry pose (the corrected one
    /// without odometry).
    fn locate(
        &self,
        recording: &Recording,
        recorded: &RecordedScan,
        anchor: Option<&Anchor>,
        localiser: &mut Localiser,
    ) -> Result<(haunts_similarity::Localised, Pose2)> {
        let stamp = recorded.scan.stamp;
        Ok(match (recording.odometry(), anchor) {
            (Some(_), Some(anchor)) => {
                let odom = recording.sensor_pose_at(&recorded.frame, stamp)?;
                let mut l = localiser.update(&recorded.scan, &(anchor.into * odom))?;
                l.pose = anchor.pose * l.pose;
                (l, odom)
            }
            (Some(_), None) => {
                let odom = recording.sensor_pose_at(&recorded.frame, stamp)?;
                (localiser.update(&recorded.scan, &odom)?, odom)
            }
            (None, _) => {
                let l = localiser.update_without_odometry(&recorded.scan)?;
                (l, l.pose)
            }
        })
    }

    /// The sensor pose the tracker is given for a scan.
    fn tracking_pose(&self, at: &ScanPose) -> Pose2 {
        match self.params.tracking_frame {
            TrackingFrame::Corrected => at.pose,
            TrackingFrame::Odometry => at.odometry,
        }
    }

    /// The scans of `poses`, read again, each with its corrected pose.
    fn posed_scans<'r>(
        &self,
        recording: &'r Recording,
        poses: &'r [ScanPose],
        expected: usize,
    ) -> Result<impl Iterator<Item = Result<(LaserScan, ScanPose)>> + 'r> {
        let mut scans = recording.scans()?.enumerate();
        let mut next = 0;
        let mut ended = false;
        Ok(std::iter::from_fn(move || {
            if ended {
                return None;
            }
            let want = poses.get(next)?;
            for (index, item) in scans.by_ref() {
                if index < want.index {
                    continue;
                }
                next += 1;
                return Some(match item {
                    Ok(r) => Ok((r.scan, *want)),
                    Err(e) => Err(e.into()),
                });
            }
            ended = true;
            Some(Err(PipelineError::RecordingChanged {
                first: expected,
                now: want.index,
            }))
        }))
    }
}

/// The day's leg detector, finding each scan's legs once for both passes that detect
/// (recurring objects, then tracking): the pipeline hands it a scan's legs just before the
/// pass asks for them, and a scan it was handed nothing for is detected afresh. The legs of
/// the same detector on the same scan, so the day is the same, at about a tenth less of
/// its time (BENCHMARKS.md, issue 19).
struct DayLegs<'d> {
    detector: &'d LegDetector,
    next: std::sync::Mutex<Option<Vec<Leg>>>,
}

impl<'d> DayLegs<'d> {
    fn new(detector: &'d LegDetector) -> Self {
        Self {
            detector,
            next: std::sync::Mutex::new(None),
        }
    }

    /// The legs of the scan the next call is about.
    fn next_is(&self, legs: Vec<Leg>) {
        if let Ok(mut next) = self.next.lock() {
            *next = Some(legs);
        }
    }

    /// The legs handed over for `scan`, or found now.
    fn legs(&self, scan: &LaserScan) -> Vec<Leg> {
        self.next
            .lock()
            .ok()
            .and_then(|mut next| next.take())
            .unwrap_or_else(|| self.detector.legs(scan))
    }
}

impl Detector for DayLegs<'_> {
    fn detect(&self, scan: &LaserScan) -> haunts_tracking::Result<Vec<Detection>> {
        Ok(self.detector.pair(&self.legs(scan)))
    }

    fn detect_where(
        &self,
        scan: &LaserScan,
        keep: &dyn Fn(&Point2<f64>) -> bool,
    ) -> haunts_tracking::Result<Vec<Detection>> {
        let mut legs = self.legs(scan);
        legs.retain(|leg| keep(&leg.centre));
        Ok(self.detector.pair(&legs))
    }

    fn candidates(&self, scan: &LaserScan) -> haunts_tracking::Result<Vec<Point2<f64>>> {
        Ok(self.legs(scan).iter().map(|leg| leg.centre).collect())
    }
}

/// The scan rate of a day, Hz: one over the median interval between consecutive scans of a
/// patrol (intervals over a second are the gaps between patrols); `None` without two such
/// scans.
fn scan_rate(poses: &[ScanPose]) -> Option<f64> {
    let mut intervals: Vec<f64> = poses
        .windows(2)
        .map(|w| w[1].stamp - w[0].stamp)
        .filter(|d| *d > 0.0 && *d <= 1.0)
        .collect();
    haunts_core::median(&mut intervals).map(|median| 1.0 / median)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use haunts_tracking::detect::LegDetectorParams;

    use super::*;

    /// A wall at 3 m, and in front of it two legs at 1.5 m, 5 beams each.
    fn scan(legs: bool) -> LaserScan {
        let ranges = (0..200)
            .map(|i| {
                let leg = (100..105).contains(&i) || (110..115).contains(&i);
                if legs && leg { 1.5 } else { 3.0 }
            })
            .collect();
        LaserScan::new(0.0, -1.0, 0.01, 0.05, 10.0, ranges, vec![]).unwrap()
    }

    #[test]
    fn day_legs_detect_as_the_detector_and_use_handed_legs_once() {
        let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
        let day = DayLegs::new(&detector);
        let (people, empty) = (scan(true), scan(false));
        assert_eq!(detector.legs(&people).len(), 2);
        assert_eq!(detector.detect(&people).unwrap().len(), 1);
        assert_eq!(
            day.detect(&people).unwrap(),
            detector.detect(&people).unwrap()
        );
        let keep = |p: &Point2<f64>| p.y > 0.0;
        assert_eq!(
            day.detect_where(&people, &keep).unwrap(),
            detector.detect_where(&people, &keep).unwrap()
        );
        // Handed over, the legs answer the next call whatever the scan; then it detects.
        day.next_is(detector.legs(&people));
        assert_eq!(
            day.candidates(&empty).unwrap(),
            detector.candidates(&people).unwrap()
        );
        assert!(day.candidates(&empty).unwrap().is_empty());
    }
}
