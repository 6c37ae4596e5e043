//! Seed 000's daily loop on recorded (here: simulated) days, the glue that the `pipeline`
//! example and the end-to-end tests share.
//!
//! Per day, [`process_day`]:
//! 1. **localises** the robot: odometry between keyframes, each keyframe scan matched by
//!    ICP (the similarity crate's [`icp`]) against the map the day has built so far
//!    ([`localise`]); the day starts at the robot's dock, whose pose in the reference frame
//!    is the first odometry pose;
//! 2. builds the day's **occupancy grid** from the keyframe scans at the corrected poses;
//! 3. **detects and tracks** people in every scan, in the world frame
//!    ([`OnlineTracker`]: leg detector, the day's [`RecurringObjects`] — legs that come back
//!    at most of the day's patrols are furniture —, Kalman + GNN tracker), and scores the
//!    tracks with CLEAR MOT against the people the laser saw (at least
//!    [`PipelineParams::visible_beams`] beams returned from their legs);
//! 4. builds the **daily density** (seed 000 III-B): human hits of the tracked positions and
//!    laser visits, both counted on every `density_every`-th scan so that their ratio keeps
//!    its meaning.
//!
//! The days then go to a [`LayoutLibrary`](haunts_affordance::LayoutLibrary) (done by the caller, in day order, since each
//! day's layout depends on the days before it); [`PipelineParams`] gathers every crate's
//! parameters with the defaults used by the example.

use haunts_affordance::{DailyDensity, DensityParams, TimedPoint};
use haunts_occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts_occupancy::{GridGeometry, LaserScan, OccupancyGrid, Pose2, pose_is_finite};
use haunts_sim::{Day, FurnitureKind};
use haunts_similarity::{IcpParams, IcpTarget, icp};
use haunts_tracking::Trajectory;
use haunts_tracking::detector::{LegDetector, LegDetectorParams};
use haunts_tracking::kalman::{KalmanParams, KalmanTracker};
use haunts_tracking::metrics::{ClearMot, ClearMotParams, Frame, clear_mot};
use haunts_tracking::tracker::online::OnlineTracker;
use haunts_tracking::tracker::recurring::{RecurringObjects, RecurringParams};
use haunts_tracking::tracker::static_map::StaticMapParams;
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
    /// A day whose per-scan series (scans, odometry, true poses, true people) differ in
    /// length.
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
    /// A parameter outside its range.
    #[error("invalid parameter {name} = {value}: {rule}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
}

/// The pipeline's result type.
pub type Result<T, E = PipelineError> = std::result::Result<T, E>;

/// Parameters of [`localise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocaliserParams {
    /// Cell size of the map scans are matched against, metres (default 0.05).
    pub resolution: f64,
    /// A new keyframe once odometry has moved this far since the last, metres (default 0.75).
    pub keyframe_distance: f64,
    /// … or turned this much, radians (default 0.4).
    pub keyframe_angle: f64,
    /// The ICP target is rebuilt from the growing map every this many keyframes (default 10).
    pub refresh_every: usize,
    /// ICP itself (default: the similarity crate's, correspondences within 0.3 m).
    pub icp: IcpParams,
    /// A match is kept only if at least this fraction of the scan's points lies near the map
    /// (default 0.6); otherwise the keyframe keeps its odometry prediction.
    pub min_fitness: f64,
    /// … and if it moves the prediction by at most this much, metres (default 0.3).
    pub max_correction: f64,
}

impl Default for LocaliserParams {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            keyframe_distance: 0.75,
            keyframe_angle: 0.4,
            refresh_every: 10,
            icp: IcpParams::default().with_max_correspondence_distance(0.3),
            min_fitness: 0.6,
            max_correction: 0.3,
        }
    }
}

impl LocaliserParams {
    /// The parameters after checking every rule.
    ///
    /// # Errors
    /// [`PipelineError::InvalidParameter`] naming the parameter; ICP's own errors.
    pub fn check(self) -> Result<Self> {
        positive("localiser.resolution", self.resolution)?;
        positive("localiser.keyframe_distance", self.keyframe_distance)?;
        positive("localiser.keyframe_angle", self.keyframe_angle)?;
        positive("localiser.max_correction", self.max_correction)?;
        at_least_one("localiser.refresh_every", self.refresh_every)?;
        if !(0.0..=1.0).contains(&self.min_fitness) {
            return Err(PipelineError::InvalidParameter {
                name: "localiser.min_fitness",
                value: self.min_fitness,
                rule: "must be in [0, 1]",
            });
        }
        self.icp.check()?;
        Ok(self)
    }
}

fn at_least_one(name: &'static str, value: usize) -> Result<()> {
    if value >= 1 {
        Ok(())
    } else {
        Err(PipelineError::InvalidParameter {
            name,
            value: value as f64,
            rule: "must be >= 1",
        })
    }
}

fn positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(PipelineError::InvalidParameter {
            name,
            value,
            rule: "must be finite and > 0",
        })
    }
}

/// Every parameter of the daily loop.
#[derive(Debug, Clone, Copy, PartialEq)]
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
    /// people (default `Some`: see [`RecurringObjects`]); their legs are dropped before
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
}

impl Default for PipelineParams {
    fn default() -> Self {
        Self {
            resolution: 0.1,
            localiser: LocaliserParams::default(),
            mapper: MapperParams::default(),
            detector: LegDetectorParams::default(),
            tracker: KalmanParams {
                confirm_hits: 5,
                confirm_strong_hits: 0,
                ..KalmanParams::default()
            },
            static_map: None,
            recurring: Some(RecurringParams::default()),
            density: DensityParams::default(),
            density_every: 10,
            mot: ClearMotParams::default(),
            visible_beams: 6,
        }
    }
}

impl PipelineParams {
    /// The parameters after checking every rule.
    ///
    /// # Errors
    /// [`PipelineError::InvalidParameter`] naming the parameter, or the owning crate's
    /// error for its own parameters.
    pub fn check(self) -> Result<Self> {
        positive("resolution", self.resolution)?;
        at_least_one("density_every", self.density_every)?;
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

/// The corrected poses of a day's scans.
#[derive(Debug, Clone, PartialEq)]
pub struct Localised {
    /// One pose per scan, in the frame of the first odometry pose.
    pub poses: Vec<Pose2>,
    /// Indices of the keyframe scans.
    pub keyframes: Vec<usize>,
    /// Keyframes whose match was refused (kept their odometry prediction).
    pub refused: usize,
}

/// Corrects `odometry` (one pose per scan) by matching keyframe scans against the map built
/// so far from the earlier keyframes (`geometry` bounds that map; its resolution is
/// replaced by the params'). Scans between keyframes follow odometry from the last keyframe.
///
/// A keyframe's match is refused — the keyframe keeps its odometry prediction, and the
/// refusal is counted — when ICP fails, fits less than `min_fitness` of the scan, or moves
/// the prediction by more than `max_correction`.
///
/// # Errors
/// [`PipelineError::DayLengths`] when `odometry` and `scans` differ in length (`day` = 0);
/// [`PipelineError::InvalidParameter`] for bad parameters; a non-finite odometry pose is an
/// [`haunts_occupancy::OccupancyError`] from the mapper.
pub fn localise(
    scans: &[LaserScan],
    odometry: &[Pose2],
    geometry: GridGeometry,
    params: &LocaliserParams,
) -> Result<Localised> {
    let params = params.check()?;
    if scans.len() != odometry.len() {
        return Err(PipelineError::DayLengths {
            day: 0,
            what: "odometry",
            len: odometry.len(),
            scans: scans.len(),
        });
    }
    let fine = geometry.with_resolution(params.resolution)?;
    let mut mapper = OccupancyMapper::new(fine, MapperParams::default())?;
    let mut target: Option<IcpTarget> = None;
    let mut poses = Vec::with_capacity(scans.len());
    let (mut keyframes, mut refused) = (Vec::new(), 0);
    // The last keyframe: its odometry pose and its corrected pose.
    let mut last: Option<(Pose2, Pose2)> = None;
    let mut points: Vec<Point2<f64>> = Vec::new();
    for (i, (scan, odom)) in scans.iter().zip(odometry).enumerate() {
        let Some((odom_kf, pose_kf)) = last else {
            mapper.insert(scan, odom)?;
            keyframes.push(i);
            last = Some((*odom, *odom));
            poses.push(*odom);
            continue;
        };
        let step = odom_kf.inverse() * odom;
        let predicted = pose_kf * step;
        let moved = step.translation.vector.norm() >= params.keyframe_distance
            || step.rotation.angle().abs() >= params.keyframe_angle;
        if !moved {
            poses.push(predicted);
            continue;
        }
        if target.is_none() || keyframes.len() % params.refresh_every == 0 {
            target = IcpTarget::new(&mapper.occupancy_grid()).ok();
        }
        points.clear();
        points.extend(scan.endpoints());
        let matched = target
            .as_ref()
            .and_then(|t| icp(t, &points, &predicted, &params.icp).ok())
            .filter(|r| {
                r.fitness >= params.min_fitness
                    && (r.pose.translation.vector - predicted.translation.vector).norm()
                        <= params.max_correction
            });
        let pose = match matched {
            Some(r) => r.pose,
            None => {
                refused += 1;
                predicted
            }
        };
        if pose_is_finite(&pose) {
            mapper.insert(scan, &pose)?;
        }
        keyframes.push(i);
        last = Some((*odom, pose));
        poses.push(pose);
    }
    Ok(Localised {
        poses,
        keyframes,
        refused,
    })
}

/// How well the localisation did against the true poses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseErrors {
    /// RMS position error of raw odometry, metres.
    pub odometry_rms: f64,
    /// RMS position error of the corrected poses, metres.
    pub corrected_rms: f64,
    /// Largest position error of the corrected poses, metres.
    pub corrected_max: f64,
}

/// One processed day.
#[derive(Debug, Clone)]
pub struct DayResult {
    /// The day's index.
    pub index: usize,
    /// The true layout (for scoring only).
    pub layout: usize,
    /// The day's occupancy grid from the corrected keyframe poses.
    pub map: OccupancyGrid,
    /// Human hits and laser visits.
    pub density: DailyDensity,
    /// Every track of the day, world frame.
    pub trajectories: Vec<Trajectory>,
    /// Tracked positions at the density scans: the detections of the hypertime model.
    pub tracked: Vec<TimedPoint>,
    /// The robot's corrected positions at the keyframes.
    pub robot: Vec<Point2<f64>>,
    /// CLEAR MOT of the tracks against the visible true people, every scan.
    pub mot: ClearMot,
    /// Localisation errors.
    pub pose_errors: PoseErrors,
    /// Keyframes of the localisation.
    pub keyframes: usize,
    /// Keyframes whose scan match was refused.
    pub refused_matches: usize,
    /// Detections given to the tracker.
    pub detections: usize,
    /// Centres of the day's tables and sofas, where visitors gather (true, for scoring the
    /// affordance maps).
    pub tables_and_sofas: Vec<Point2<f64>>,
}

/// Runs the daily loop (see the [module docs](self)) on one simulated day; `geometry` is the
/// reference grid of maps and densities (every day on the same cells).
///
/// # Errors
/// [`PipelineError::DayLengths`] for a malformed day; bad parameters; the crates' errors.
pub fn process_day(
    day: &Day,
    geometry: GridGeometry,
    params: &PipelineParams,
) -> Result<DayResult> {
    let params = params.check()?;
    let n = day.scans.len();
    for (what, len) in [
        ("odometry", day.odometry.len()),
        ("poses", day.poses.len()),
        ("people", day.people.len()),
    ] {
        if len != n {
            return Err(PipelineError::DayLengths {
                day: day.index,
                what,
                len,
                scans: n,
            });
        }
    }
    let localised = localise(&day.scans, &day.odometry, geometry, &params.localiser)?;
    let poses = &localised.poses;

    let mut mapper = OccupancyMapper::new(geometry, params.mapper)?;
    for &k in &localised.keyframes {
        if pose_is_finite(&poses[k]) {
            mapper.insert(&day.scans[k], &poses[k])?;
        }
    }
    let map = mapper.occupancy_grid();

    let detector = LegDetector::new(params.detector)?;
    let mut tracker = KalmanTracker::new(params.tracker)?;
    let recurring = params
        .recurring
        .map(|r| RecurringObjects::build(&detector, day.scans.iter().zip(poses.iter()), r))
        .transpose()?;
    let mut online = OnlineTracker::new(&detector, &mut tracker, params.static_map)?;
    if let Some(r) = &recurring {
        online = online.with_recurring(r);
    }
    let (mut truth, mut hypotheses) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut tracked, mut detections) = (Vec::new(), 0);
    let mut density_scans = Vec::new();
    for (i, scan) in day.scans.iter().enumerate() {
        let pose = &poses[i];
        if !pose_is_finite(pose) {
            continue;
        }
        detections += online.step(scan, pose)?.detections;
        let tracks = online.tracker().tracks();
        let (visible, ignored) = visible_people(&day.people[i], &params);
        // A track nearer to a don't-care person (within the match threshold) than to any
        // visible one is left out of the scoring.
        let cares = |p: &Point2<f64>| {
            let nearest = |set: &mut dyn Iterator<Item = Point2<f64>>| {
                set.map(|q| (q - p).norm()).fold(f64::INFINITY, f64::min)
            };
            let ignored = nearest(&mut ignored.iter().copied());
            ignored > params.mot.match_threshold
                || nearest(&mut visible.iter().map(|v| v.1)) <= ignored
        };
        hypotheses.push(Frame::new(
            scan.stamp,
            tracks
                .iter()
                .filter(|t| cares(&t.position))
                .map(|t| (t.id, t.position))
                .collect(),
        ));
        truth.push(Frame::new(scan.stamp, visible));
        if i % params.density_every == 0 {
            density_scans.push((scan, pose));
            tracked.extend(
                tracks
                    .iter()
                    .map(|t| TimedPoint::new(scan.stamp, t.position.x, t.position.y)),
            );
        }
    }
    let trajectories = online.tracker().trajectories();
    let mot = clear_mot(&truth, &hypotheses, &params.mot)?;
    let (density, _) = DailyDensity::from_day(
        geometry,
        &density_scans,
        |&(scan, pose)| (scan, pose),
        tracked.iter().map(|p| p.position),
        &params.density,
    )?;

    Ok(DayResult {
        index: day.index,
        layout: day.layout,
        map,
        density,
        trajectories,
        tracked,
        robot: localised
            .keyframes
            .iter()
            .map(|&k| poses[k].translation.vector.into())
            .collect(),
        mot,
        pose_errors: pose_errors(&day.odometry, poses, &day.poses),
        keyframes: localised.keyframes.len(),
        refused_matches: localised.refused,
        detections,
        tables_and_sofas: day
            .furniture
            .iter()
            .filter(|f| matches!(f.kind, FurnitureKind::Table | FurnitureKind::Sofa))
            .map(|f| f.center)
            .collect(),
    })
}

/// Mean of the known (finite) values of `density` over the cells whose centre lies within
/// 1 m of one of `points` and farther than 1 m from every point of `except` (0 if there is
/// none): where one layout's tables stand and another's do not. With `points` a layout's
/// tables and sofas and `except` those of the other layouts, a layout's affordance map that
/// follows its furniture scores higher than with the roles swapped.
pub fn density_near(
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

/// A person's id and position.
type Labelled = (u64, Point2<f64>);

/// The true people of one scan that the laser saw — at least `visible_beams` beams returned
/// from their legs —, and the positions of the others.
fn visible_people(
    people: &[haunts_sim::PersonTruth],
    params: &PipelineParams,
) -> (Vec<Labelled>, Vec<Point2<f64>>) {
    let (mut visible, mut ignored) = (Vec::new(), Vec::new());
    for p in people {
        if p.beams >= params.visible_beams {
            visible.push((p.id, p.position));
        } else {
            ignored.push(p.position);
        }
    }
    (visible, ignored)
}

fn pose_errors(odometry: &[Pose2], corrected: &[Pose2], truth: &[Pose2]) -> PoseErrors {
    let rms = |poses: &[Pose2]| {
        let n = poses.len().max(1) as f64;
        (poses
            .iter()
            .zip(truth)
            .map(|(p, t)| (p.translation.vector - t.translation.vector).norm_squared())
            .sum::<f64>()
            / n)
            .sqrt()
    };
    PoseErrors {
        odometry_rms: rms(odometry),
        corrected_rms: rms(corrected),
        corrected_max: corrected
            .iter()
            .zip(truth)
            .map(|(p, t)| (p.translation.vector - t.translation.vector).norm())
            .fold(0.0, f64::max),
    }
}
