//! The simulator: parameters, the per-day pipeline (layout → displaced furniture →
//! ground-truth grid → people → patrol → scans and odometry) and the day's output.

use std::ops::Range;

use haunts_occupancy::{Grid, GridGeometry, LaserScan, OccupancyGrid, Pose2};
use nalgebra::{Point2, Vector2};
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
use rand_distr::{Distribution, StandardNormal};

use crate::error::{Result, SimError};
use crate::laser::{Caster, LaserParams};
use crate::office::{Furniture, FurnitureKind, Office};
use crate::people::{PeopleParams, PersonTruth, Visit, draw_visits};
use crate::rng::{Stream, stream_seed};
use crate::robot::{OdometryParams, Patrol, PatrolParams};
use crate::schedule::{MAX_DAY, ScheduleParams};
use crate::shapes::Shape;

/// Largest accepted number of cells of the ground-truth grid.
const MAX_GRID_CELLS: usize = 50_000_000;

/// How far furniture is pushed around each day: Gaussian displacement (metres) and
/// rotation (radians) standard deviations per kind, clipped at 3 σ.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FurnitureNoise {
    /// Chairs: displacement σ, metres.
    pub chair_sd: f64,
    /// Chairs: rotation σ, radians.
    pub chair_angle_sd: f64,
    /// Tables: displacement σ, metres.
    pub table_sd: f64,
    /// Tables: rotation σ, radians.
    pub table_angle_sd: f64,
    /// Sofas and cabinets: displacement σ, metres.
    pub solid_sd: f64,
    /// Sofas and cabinets: rotation σ, radians.
    pub solid_angle_sd: f64,
}

impl Default for FurnitureNoise {
    /// Chairs 0.12 m / 0.3 rad, tables 0.03 m / 0.03 rad, sofas and cabinets 0.02 m /
    /// 0.01 rad: small day-to-day changes well below the layouts' differences.
    fn default() -> Self {
        Self {
            chair_sd: 0.12,
            chair_angle_sd: 0.3,
            table_sd: 0.03,
            table_angle_sd: 0.03,
            solid_sd: 0.02,
            solid_angle_sd: 0.01,
        }
    }
}

impl FurnitureNoise {
    /// No displacement at all.
    pub fn none() -> Self {
        Self {
            chair_sd: 0.0,
            chair_angle_sd: 0.0,
            table_sd: 0.0,
            table_angle_sd: 0.0,
            solid_sd: 0.0,
            solid_angle_sd: 0.0,
        }
    }

    /// The parameters if usable.
    ///
    /// # Errors
    /// [`SimError::InvalidParameter`] for a value that is not finite in `[0, 10]`.
    pub fn check(self) -> Result<Self> {
        for (param, v) in [
            ("furniture.chair_sd", self.chair_sd),
            ("furniture.chair_angle_sd", self.chair_angle_sd),
            ("furniture.table_sd", self.table_sd),
            ("furniture.table_angle_sd", self.table_angle_sd),
            ("furniture.solid_sd", self.solid_sd),
            ("furniture.solid_angle_sd", self.solid_angle_sd),
        ] {
            if !(v.is_finite() && (0.0..=10.0).contains(&v)) {
                return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                    name: param,
                    value: v,
                    rule: "must be in [0, 10]",
                }));
            }
        }
        Ok(self)
    }
}

/// Everything the simulation depends on besides the office.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct SimParams {
    /// The seed every random stream derives from.
    pub seed: u64,
    /// UNIX time of midnight of day 0, seconds.
    pub start_time: f64,
    /// Cell side of the ground-truth grid, metres.
    pub grid_resolution: f64,
    /// Which layout each day uses.
    pub schedule: ScheduleParams,
    /// Daily displacement of the furniture.
    pub furniture: FurnitureNoise,
    /// The people.
    pub people: PeopleParams,
    /// When and how the robot patrols.
    pub patrol: PatrolParams,
    /// The laser.
    pub laser: LaserParams,
    /// The odometry's drift.
    pub odometry: OdometryParams,
    /// Refuse days with more scans than this.
    pub max_scans_per_day: usize,
    /// Whether each day starts at a random pose (default `false`: the odometry frame is the
    /// world frame, drift aside). A real robot's odometry is zeroed wherever it was switched
    /// on; with this on, each day's robot was switched on at a random free pose of the office
    /// (a position drawn uniformly over the free cells of the day's true grid at least
    /// [`START_CLEARANCE`] from any obstacle, a heading uniform in [−π, π)), its odometry
    /// zero there, and then drove to its patrol: the day's odometry is in that pose's frame
    /// ([`Day::odometry_frame`]), so that days must be registered to one another before they
    /// share cells. The patrols, the laser and the ground truth are those of the same day
    /// without it, in the office frame.
    #[cfg_attr(feature = "serde", serde(default))]
    pub random_start: bool,
}

impl Default for SimParams {
    /// Seed 0, day 0 on Monday 2026-01-05, 5 cm cells, the defaults of every part: a
    /// 15-minute patrol at 12:30 with a 10 Hz, 541-beam laser (9000 scans a day).
    fn default() -> Self {
        Self {
            seed: 0,
            start_time: 1_767_571_200.0,
            grid_resolution: 0.05,
            schedule: ScheduleParams::default(),
            furniture: FurnitureNoise::default(),
            people: PeopleParams::default(),
            patrol: PatrolParams::default(),
            laser: LaserParams::default(),
            odometry: OdometryParams::default(),
            max_scans_per_day: 2_000_000,
            random_start: false,
        }
    }
}

impl SimParams {
    /// Sets the seed.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
    /// Sets the patrol.
    pub fn with_patrol(mut self, patrol: PatrolParams) -> Self {
        self.patrol = patrol;
        self
    }
    /// Sets the laser.
    pub fn with_laser(mut self, laser: LaserParams) -> Self {
        self.laser = laser;
        self
    }
    /// Sets the people.
    pub fn with_people(mut self, people: PeopleParams) -> Self {
        self.people = people;
        self
    }
    /// Sets the odometry.
    pub fn with_odometry(mut self, odometry: OdometryParams) -> Self {
        self.odometry = odometry;
        self
    }
    /// Sets the layout schedule.
    pub fn with_schedule(mut self, schedule: ScheduleParams) -> Self {
        self.schedule = schedule;
        self
    }
    /// Sets the daily furniture displacement.
    pub fn with_furniture(mut self, furniture: FurnitureNoise) -> Self {
        self.furniture = furniture;
        self
    }
    /// Sets whether each day's odometry starts at a random pose.
    pub fn with_random_start(mut self, random_start: bool) -> Self {
        self.random_start = random_start;
        self
    }

    /// The parameters if usable with `layouts` layouts.
    ///
    /// # Errors
    /// The first error of the parts' `check`s; [`SimError::InvalidParameter`] for a non-finite
    /// `start_time` or a resolution not finite in `(0, 100]`; [`SimError::TooLarge`] when a
    /// day would exceed `max_scans_per_day`.
    pub fn check(self, layouts: usize) -> Result<Self> {
        if !self.start_time.is_finite() || self.start_time.abs() > 1e15 {
            return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                name: "start_time",
                value: self.start_time,
                rule: "must be finite, |t| <= 1e15",
            }));
        }
        if !(self.grid_resolution.is_finite()
            && self.grid_resolution > 0.0
            && self.grid_resolution <= 100.0)
        {
            return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                name: "grid_resolution",
                value: self.grid_resolution,
                rule: "must be in (0, 100]",
            }));
        }
        let schedule = self.schedule.check(layouts)?;
        let furniture = self.furniture.check()?;
        let people = self.people.check()?;
        let patrol = self.patrol.check()?;
        let laser = self.laser.check()?;
        let odometry = self.odometry.check()?;
        let this = Self {
            schedule,
            furniture,
            people,
            patrol,
            laser,
            odometry,
            ..self
        };
        let scans = this.patrol.scans_per_day(this.laser.rate);
        if scans > this.max_scans_per_day as f64 {
            return Err(SimError::TooLarge {
                what: "scans per day",
                count: scans,
                limit: this.max_scans_per_day,
            });
        }
        Ok(this)
    }
}

/// Metres of free ground around a random start pose ([`SimParams::random_start`]): the
/// robot's footprint.
pub const START_CLEARANCE: f64 = 0.3;

/// The identity pose: a day written before random start poses has its odometry in the world
/// frame.
#[cfg(feature = "serde")]
fn identity() -> Pose2 {
    Pose2::identity()
}

/// One simulated day with its ground truth. Index `k` of `scans`, `odometry`, `poses` and
/// `people` refers to the same instant `scans[k].stamp`.
///
/// With the `serde` feature a day (de)serialises field by field; its scans, ground-truth grid
/// and visits are checked as they are read. Dropouts (NaN) and `+inf` max-range readings are
/// written as `"NaN"` / `"inf"` in JSON (`haunts_occupancy::serde_float`), so every day reads
/// back.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Day {
    /// Day index (0-based).
    pub index: usize,
    /// The true layout (index into [`Office::layouts`]).
    pub layout: usize,
    /// UNIX time of the day's midnight.
    pub midnight: f64,
    /// The laser scans, in the robot frame (the laser sits at the robot's origin).
    pub scans: Vec<LaserScan>,
    /// Odometry poses, in the odometry frame: they start at the first true pose moved into
    /// that frame, then drift.
    pub odometry: Vec<Pose2>,
    /// The pose of the odometry frame in the world frame: the identity, or the day's random
    /// start pose ([`SimParams::random_start`]). `odometry_frame · odometry[k]` is the
    /// odometry in the world frame.
    #[cfg_attr(feature = "serde", serde(default = "identity"))]
    pub odometry_frame: Pose2,
    /// True robot (and laser) poses in the world frame.
    pub poses: Vec<Pose2>,
    /// The people present at each scan (positions are the midpoints between the legs).
    pub people: Vec<Vec<PersonTruth>>,
    /// Every visit of the day, also those outside the patrol.
    pub visits: Vec<Visit>,
    /// The day's movable furniture after its daily displacement.
    pub furniture: Vec<Furniture>,
    /// Ground-truth occupancy: 100 where a wall or furniture shape overlaps the cell, 0
    /// elsewhere in the office's area. People are not in it.
    pub truth: OccupancyGrid,
}

impl Day {
    /// The day as a [`Recording`](haunts_occupancy::recording::Recording), as a robot would
    /// have recorded it: the scans in frame `laser` (mounted at the origin of `base_link`, a
    /// static link of the tree), received at their stamps, and the drifting odometry of
    /// `base_link` in `odom`. The ground truth (true poses, people, layout) is left out.
    ///
    /// # Errors
    /// [`SimError::Occupancy`] when the day has no scan (no odometry sample).
    pub fn to_recording(&self) -> Result<haunts_occupancy::recording::Recording> {
        use haunts_occupancy::recording::{RecordedScan, Recording, ScanList};
        use haunts_occupancy::{PoseHistory, TransformTree};
        let scans = ScanList(
            self.scans
                .iter()
                .map(|scan| RecordedScan {
                    scan: scan.clone(),
                    frame: "laser".to_owned(),
                    received: scan.stamp,
                })
                .collect(),
        );
        let odometry = PoseHistory::new(
            self.scans
                .iter()
                .zip(&self.odometry)
                .map(|(s, pose)| (s.stamp, *pose)),
        )?;
        let mut tree = TransformTree::new();
        tree.add_static("base_link", "laser", Pose2::identity())?;
        Ok(Recording::new(scans)
            .with_transforms(tree)
            .with_odometry(odometry, "odom", "base_link")
            .with_note(format!(
                "simulated day {} ({} scans)",
                self.index,
                self.scans.len()
            )))
    }

    /// Whether two days are bit-identical: every field equal, and scan ranges equal bit for
    /// bit (`==` on the `Day`s says no as soon as a dropout's NaN is involved).
    pub fn bit_eq(&self, other: &Day) -> bool {
        let scans_equal = self.scans.len() == other.scans.len()
            && self.scans.iter().zip(&other.scans).all(|(a, b)| {
                a.stamp.to_bits() == b.stamp.to_bits()
                    && a.ranges.len() == b.ranges.len()
                    && a.ranges
                        .iter()
                        .zip(&b.ranges)
                        .all(|(x, y)| x.to_bits() == y.to_bits())
                    && LaserScan {
                        ranges: Vec::new(),
                        ..a.clone()
                    } == LaserScan {
                        ranges: Vec::new(),
                        ..b.clone()
                    }
            });
        scans_equal
            && self.index == other.index
            && self.layout == other.layout
            && self.midnight.to_bits() == other.midnight.to_bits()
            && self.odometry == other.odometry
            && self.poses == other.poses
            && self.people == other.people
            && self.visits == other.visits
            && self.furniture == other.furniture
            && self.truth == other.truth
    }
}

/// The simulator of an office (checked once, then any day can be simulated alone).
#[derive(Debug, Clone)]
pub struct Simulator {
    office: Office,
    params: SimParams,
    patrol: Patrol,
    geometry: GridGeometry,
}

impl Simulator {
    /// The built-in office ([`Office::builtin`]) with `params`.
    ///
    /// # Errors
    /// As [`Simulator::with_office`].
    pub fn new(params: SimParams) -> Result<Self> {
        Self::with_office(Office::builtin(), params)
    }

    /// A simulator of `office` with `params`.
    ///
    /// # Errors
    /// [`Office::check`], [`SimParams::check`]; [`SimError::TooLarge`] when the
    /// ground-truth grid would exceed 50 000 000 cells.
    pub fn with_office(office: Office, params: SimParams) -> Result<Self> {
        let office = office.check()?;
        let layouts = office.layouts.len();
        let params = params.check(layouts)?;
        let patrol = Patrol::new(&office.waypoints, &params.patrol)
            .ok_or(SimError::TooFewWaypoints { count: 1 })?;
        let extent = office.max - office.min;
        let (w, h) = (
            (extent.x / params.grid_resolution).ceil(),
            (extent.y / params.grid_resolution).ceil(),
        );
        if w * h > MAX_GRID_CELLS as f64 {
            return Err(SimError::TooLarge {
                what: "grid cells",
                count: w * h,
                limit: MAX_GRID_CELLS,
            });
        }
        let geometry =
            GridGeometry::new(params.grid_resolution, office.min, w as usize, h as usize)?;
        Ok(Self {
            office,
            params,
            patrol,
            geometry,
        })
    }

    /// The office.
    pub fn office(&self) -> &Office {
        &self.office
    }
    /// The parameters.
    pub fn params(&self) -> &SimParams {
        &self.params
    }
    /// The geometry of the ground-truth grids.
    pub fn geometry(&self) -> GridGeometry {
        self.geometry
    }

    /// The layout of each day in `0..days`.
    ///
    /// # Errors
    /// [`SimError::DayOutOfRange`] beyond [`MAX_DAY`].
    pub fn layouts(&self, days: usize) -> Result<Vec<usize>> {
        self.params
            .schedule
            .layouts(self.params.seed, self.office.layouts.len(), days)
    }

    /// The movable furniture of `layout` as displaced on `day`.
    ///
    /// # Errors
    /// [`SimError::InvalidParameter`] for a layout index out of range.
    pub fn furniture(&self, day: usize, layout: usize) -> Result<Vec<Furniture>> {
        let l = self
            .office
            .layouts
            .get(layout)
            .ok_or(SimError::InvalidParameter(haunts_core::InvalidParameter {
                name: "layout",
                value: layout as f64,
                rule: "must be an index below the number of layouts",
            }))?;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
            self.params.seed,
            day as u64,
            Stream::Furniture,
            layout as u64,
        ));
        let n = &self.params.furniture;
        let mut g = |sd: f64| {
            let z: f64 = StandardNormal.sample(&mut rng);
            sd * z.clamp(-3.0, 3.0)
        };
        Ok(l.furniture
            .iter()
            .map(|f| {
                let (sd, asd) = match f.kind {
                    FurnitureKind::Chair => (n.chair_sd, n.chair_angle_sd),
                    FurnitureKind::Table => (n.table_sd, n.table_angle_sd),
                    FurnitureKind::Sofa | FurnitureKind::Cabinet => (n.solid_sd, n.solid_angle_sd),
                };
                let (dx, dy, da) = (g(sd), g(sd), g(asd));
                Furniture {
                    center: f.center + Vector2::new(dx, dy),
                    angle: f.angle + da,
                    ..*f
                }
            })
            .collect())
    }

    /// The static shapes of a day: walls, fixed furniture and the given movable furniture.
    pub fn static_shapes(&self, furniture: &[Furniture]) -> Vec<Shape> {
        let mut shapes = self.office.walls.clone();
        for f in self.office.fixed.iter().chain(furniture) {
            f.push_shapes(&mut shapes);
        }
        shapes
    }

    /// The ground-truth occupancy of `shapes`: 100 where a shape overlaps the cell's square
    /// (exact test), 0 elsewhere.
    ///
    /// # Errors
    /// Not with a constructed simulator (the geometry is checked).
    pub fn truth_grid(&self, shapes: &[Shape]) -> Result<OccupancyGrid> {
        let g = self.geometry;
        let mut grid = Grid::filled(g, 0i8);
        let res = g.resolution();
        for s in shapes {
            let (lo, hi) = s.bounds();
            let (c0, r0) = g.world_to_grid(lo);
            let (c1, r1) = g.world_to_grid(hi);
            let clamp = |v: f64, n: usize| v.floor().clamp(0.0, n as f64 - 1.0) as usize;
            if c1 < 0.0 || r1 < 0.0 || c0 >= g.width() as f64 || r0 >= g.height() as f64 {
                continue;
            }
            for row in clamp(r0, g.height())..=clamp(r1, g.height()) {
                for col in clamp(c0, g.width())..=clamp(c1, g.width()) {
                    let cell = haunts_occupancy::Cell { col, row };
                    if s.overlaps_square(g.cell_center(cell), res / 2.0) {
                        grid[cell] = 100;
                    }
                }
            }
        }
        Ok(OccupancyGrid::from_grid(grid)?)
    }

    /// Simulates day `day`.
    ///
    /// # Errors
    /// [`SimError::DayOutOfRange`] beyond [`MAX_DAY`].
    ///
    /// Complexity: O(day) for the schedule, then O(scans · (shapes log shapes + beams)).
    pub fn day(&self, day: usize) -> Result<Day> {
        if day > MAX_DAY {
            return Err(SimError::DayOutOfRange { day, max: MAX_DAY });
        }
        let layout = self.layouts(day + 1)?[day];
        self.simulate(day, layout)
    }

    /// Simulates the days of `range`, in parallel with the `rayon` feature; the result is
    /// the same with any number of threads. All the days are held at once (≈ 40 MB per
    /// default day): simulate long runs in chunks.
    ///
    /// # Errors
    /// As [`Simulator::day`], for the first failing day.
    pub fn days(&self, range: Range<usize>) -> Result<Vec<Day>> {
        if range.end > MAX_DAY + 1 {
            return Err(SimError::DayOutOfRange {
                day: range.end - 1,
                max: MAX_DAY,
            });
        }
        let layouts = self.layouts(range.end)?;
        let days: Vec<usize> = range.collect();
        par_map(&days, |&d| self.simulate(d, layouts[d]))
            .into_iter()
            .collect()
    }

    fn simulate(&self, day: usize, layout: usize) -> Result<Day> {
        let p = &self.params;
        let furniture = self.furniture(day, layout)?;
        let shapes = self.static_shapes(&furniture);
        let truth = self.truth_grid(&shapes)?;
        let midnight = p.start_time + day as f64 * 86_400.0;
        let visits = draw_visits(&self.office, &furniture, &p.people, p.seed, day, midnight);
        let per_session = (p.patrol.duration * p.laser.rate).floor() as usize;
        // (stamp, seconds since the start of its patrol) of every scan.
        let times: Vec<(f64, f64)> = p
            .patrol
            .session_starts()
            .flat_map(|s| {
                (0..per_session).map(move |k| {
                    let e = k as f64 / p.laser.rate;
                    (midnight + s + e, e)
                })
            })
            .collect();
        let count = times.len();
        let poses: Vec<Pose2> = times.iter().map(|&(_, e)| self.patrol.pose(e)).collect();
        let (t0, t1) = (
            times.first().map_or(0.0, |t| t.0),
            times.last().map_or(0.0, |t| t.0),
        );
        let active: Vec<&Visit> = visits
            .iter()
            .filter(|v| v.departure() >= t0 && v.arrival() <= t1)
            .collect();
        let indices: Vec<usize> = (0..count).collect();
        let caster = Caster::new(&p.laser);
        let frames = par_map(&indices, |&k| {
            let stamp = times[k].0;
            let mut all = shapes.clone();
            let mut people = Vec::new();
            for v in &active {
                if let (Some(truth), Some(legs)) = (v.at(stamp), v.legs(stamp, &p.people)) {
                    people.push(truth);
                    all.extend(legs);
                }
            }
            let (scan, exact) = p
                .laser
                .scan(&caster, &poses[k], &all, stamp, (p.seed, day, k))?;
            count_beams(
                &mut people,
                &all[shapes.len()..],
                &caster,
                &exact,
                &poses[k],
            );
            Ok::<_, SimError>((scan, people))
        });
        let mut scans = Vec::with_capacity(count);
        let mut people = Vec::with_capacity(count);
        for f in frames {
            let (s, q) = f?;
            scans.push(s);
            people.push(q);
        }
        let mut odometry = p.odometry.integrate(&poses, p.seed, day);
        // With a random start the odometry was zeroed at a random free pose.
        let odometry_frame = if p.random_start {
            self.random_start(day, &truth)
        } else {
            Pose2::identity()
        };
        if p.random_start {
            let into = odometry_frame.inverse();
            odometry.iter_mut().for_each(|o| *o = into * *o);
        }
        Ok(Day {
            index: day,
            layout,
            midnight,
            scans,
            odometry,
            odometry_frame,
            poses,
            people,
            visits,
            furniture,
            truth,
        })
    }

    /// Day `day`'s random start pose, from the day's own stream: positions drawn uniformly
    /// over the office's box until one lies on free ground of `truth` with
    /// [`START_CLEARANCE`] to every obstacle (at most 10 000 draws; the last one otherwise),
    /// a heading uniform in [−π, π).
    fn random_start(&self, day: usize, truth: &OccupancyGrid) -> Pose2 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
            self.params.seed,
            day as u64,
            Stream::Start,
            0,
        ));
        let g = truth.geometry();
        let (lo, hi) = (g.origin(), g.upper_corner());
        let reach = (START_CLEARANCE / g.resolution()).ceil() as i64;
        let clear = |p: Point2<f64>| {
            let Some(c) = g.world_to_cell(p) else {
                return false;
            };
            (-reach..=reach).all(|dc| {
                (-reach..=reach).all(|dr| {
                    g.checked_cell(c.col as i64 + dc, c.row as i64 + dr)
                        .is_some_and(|n| truth.value(n) == Some(0))
                })
            })
        };
        let mut p = Point2::new(lo.x, lo.y);
        for _ in 0..10_000 {
            p = Point2::new(
                lo.x + (hi.x - lo.x) * rng.random::<f64>(),
                lo.y + (hi.y - lo.y) * rng.random::<f64>(),
            );
            if clear(p) {
                break;
            }
        }
        let yaw = std::f64::consts::PI * (2.0 * rng.random::<f64>() - 1.0);
        Pose2::new(p.coords, yaw)
    }

    /// The exact (noise-free) range of every beam of the laser from `pose` against
    /// `shapes` (`+inf` for no return within range): the reference the scans are drawn
    /// around. Shapes containing the sensor are not seen.
    ///
    /// # Complexity
    /// O(s log s + Σ beams covered by each shape), s = shapes within range.
    pub fn exact_ranges(&self, pose: &Pose2, shapes: &[Shape]) -> Vec<f64> {
        Caster::new(&self.params.laser).cast(pose, shapes)
    }

    /// The leg circles of the people of `day` at `stamp`.
    pub fn legs_at(&self, day: &Day, stamp: f64) -> Vec<Shape> {
        day.visits
            .iter()
            .filter_map(|v| v.legs(stamp, &self.params.people))
            .flatten()
            .collect()
    }
}

/// Sets each person's [`PersonTruth::beams`]: the returned beams whose exact endpoint lies on
/// one of the person's two leg circles (`legs` holds them in the order of `people`).
fn count_beams(
    people: &mut [PersonTruth],
    legs: &[Shape],
    caster: &Caster,
    exact: &[f64],
    pose: &Pose2,
) {
    let origin = Point2::from(pose.translation.vector);
    let to_sensor = pose.rotation.inverse();
    let directions = caster.directions();
    let (angle_min, increment) = (caster.angle_min(), caster.increment());
    let n = exact.len() as i64;
    let full_circle = n as f64 * increment >= std::f64::consts::TAU - 1e-9;
    // In the sensor frame: the beam's endpoint against the leg's centre.
    let on_leg = |i: usize, center: Vector2<f64>, radius: f64| {
        let r = exact[i];
        r.is_finite() && ((directions[i] * r - center).norm() - radius).abs() <= 1e-6 * (1.0 + r)
    };
    let mut beams = Vec::new();
    for (person, legs) in people.iter_mut().zip(legs.chunks(2)) {
        beams.clear();
        for leg in legs {
            let Shape::Circle { center, radius } = *leg else {
                continue;
            };
            let m = to_sensor * (center - origin);
            let d = m.norm();
            if d <= radius {
                continue;
            }
            // The beams within the leg's angular extent (plus one on each side).
            let half = (radius / d).asin();
            let bearing = (m.y.atan2(m.x) - angle_min).rem_euclid(std::f64::consts::TAU);
            let lo = ((bearing - half) / increment).floor() as i64 - 1;
            let hi = ((bearing + half) / increment).ceil() as i64 + 1;
            for k in lo..=hi {
                // Beams past the ends exist only on a full circle, where they wrap.
                let i = if full_circle { k.rem_euclid(n) } else { k };
                if (0..n).contains(&i) && on_leg(i as usize, m, radius) {
                    beams.push(i as usize);
                }
            }
        }
        beams.sort_unstable();
        beams.dedup();
        person.beams = beams.len();
    }
}

/// `f` over `items`, in parallel with the `rayon` feature, results in order.
fn par_map<T: Sync, U: Send>(items: &[T], f: impl Fn(&T) -> U + Sync + Send) -> Vec<U> {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        items.par_iter().map(f).collect()
    }
    #[cfg(not(feature = "rayon"))]
    {
        items.iter().map(f).collect()
    }
}
