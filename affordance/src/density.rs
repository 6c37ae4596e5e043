//! Daily and cumulative affordance densities (seed 000 III-B): human hits divided by laser
//! visits, cell by cell.
//!
//! * **Human hits**: for every tracked position (world frame), every cell whose centre lies
//!   strictly closer than `person_radius` (default 0.25 m: the person modelled as a disc) is
//!   counted once ([`HitCounter`]).
//! * **Laser visits**: every beam counts the cells it crosses for at least half a cell side
//!   (the occupancy crate's [`VisitCounter`] with its [`VisitRule`]).
//! * **Daily density** = hits / visits per cell, unknown where the laser visited a cell fewer
//!   than `min_visits` times (default 1: never) ([`DailyDensity`]).
//! * **Cumulative density** over days = Σ hits / Σ visits ([`CumulativeDensity`]).
//!
//! The density is a rate, not a probability: a person standing still while the robot looks
//! elsewhere adds hits without visits, so values above 1 are possible.
//!
//! All counts of one accumulation live on one [`GridGeometry`]. Counts are never resampled:
//! hits and visits come from world-frame positions and scans, so every day is counted directly
//! on the reference geometry, and adding a day on other cells is an
//! [`AffordanceError::GeometryMismatch`].

use haunts_occupancy::raycast::{ScanStats, VisitCounter, VisitRule};
use haunts_occupancy::{Cell, Grid, GridGeometry, LaserScan, MaxRangeRule, Pose2, pose_is_finite};
use haunts_tracking::Trajectory;
use nalgebra::Point2;

use crate::{AffordanceError, DensityMap, Result};

/// Parameters of the daily density.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct DensityParams {
    /// Radius of the disc that models a person, metres (seed 000: 0.25 m). A cell is hit when
    /// its centre lies strictly closer than this to a tracked position.
    pub person_radius: f64,
    /// When a beam visits a cell (default: it crosses half a cell side inside it).
    pub visit_rule: VisitRule,
    /// What max-range readings do (default: clear up to 5 m, as the occupancy mapper).
    pub max_range: MaxRangeRule,
    /// Fewest laser visits for a cell's density to be known (default 1).
    pub min_visits: u32,
}

impl Default for DensityParams {
    fn default() -> Self {
        Self {
            person_radius: 0.25,
            visit_rule: VisitRule::default(),
            max_range: MaxRangeRule::default(),
            min_visits: 1,
        }
    }
}

impl DensityParams {
    /// Sets the radius of a person's disc, metres.
    pub fn with_person_radius(mut self, person_radius: f64) -> Self {
        self.person_radius = person_radius;
        self
    }
    /// Sets the visit rule.
    pub fn with_visit_rule(mut self, visit_rule: VisitRule) -> Self {
        self.visit_rule = visit_rule;
        self
    }
    /// Sets what max-range readings do.
    pub fn with_max_range(mut self, max_range: MaxRangeRule) -> Self {
        self.max_range = max_range;
        self
    }
    /// Sets the fewest visits for a known density.
    pub fn with_min_visits(mut self, min_visits: u32) -> Self {
        self.min_visits = min_visits;
        self
    }

    /// The parameters, after checking every rule.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming `person_radius` (must be finite and > 0),
    /// `visit_rule.min_fraction` (in `[0, √2]`), `max_range` (a clearing length must be > 0)
    /// or `min_visits` (must be ≥ 1).
    pub fn check(self) -> Result<Self> {
        check_radius(self.person_radius)?;
        if self.visit_rule.check().is_err() {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "visit_rule.min_fraction",
                    value: self.visit_rule.min_fraction,
                    rule: "must be in [0, sqrt(2)]",
                },
            ));
        }
        if let MaxRangeRule::Clear(limit) = self.max_range {
            if limit.is_nan() || limit <= 0.0 {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "max_range",
                        value: limit,
                        rule: "a clearing length must be > 0",
                    },
                ));
            }
        }
        check_min_visits(self.min_visits)?;
        Ok(self)
    }
}

fn check_radius(radius: f64) -> Result<()> {
    if radius.is_finite() && radius > 0.0 {
        Ok(())
    } else {
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "person_radius",
                value: radius,
                rule: "must be finite and > 0",
            },
        ))
    }
}

fn check_min_visits(min_visits: u32) -> Result<()> {
    if min_visits >= 1 {
        Ok(())
    } else {
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "min_visits",
                value: f64::from(min_visits),
                rule: "must be >= 1",
            },
        ))
    }
}

/// `Err(GeometryMismatch)` unless `found` lies on the cells of `expected`.
pub(crate) fn check_geometry(
    what: &'static str,
    expected: &GridGeometry,
    found: &GridGeometry,
) -> Result<()> {
    if expected.same_cells(found, GridGeometry::SAME_CELLS_TOLERANCE) {
        Ok(())
    } else {
        Err(AffordanceError::GeometryMismatch {
            what,
            expected: Box::new(*expected),
            found: Box::new(*found),
        })
    }
}

/// What counting tracked positions did: every position given lands in exactly one of
/// `counted`, `non_finite` and `outside`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HitStats {
    /// Positions whose disc covered at least one cell centre of the grid.
    pub counted: usize,
    /// Positions with a NaN or infinite coordinate, skipped.
    pub non_finite: usize,
    /// Finite positions whose disc covers no cell centre of the grid: outside the map (or,
    /// with a radius under half the diagonal of a cell, between centres).
    pub outside: usize,
    /// Cell hits added (a position adds one per cell of its disc).
    pub cell_hits: usize,
}

impl HitStats {
    /// Number of positions given.
    pub fn positions(&self) -> usize {
        self.counted + self.non_finite + self.outside
    }
}

/// Counts human hits per cell (seed 000 III-B's "number of humans"): each tracked position
/// adds one to every cell whose centre lies strictly closer than the radius.
///
/// ```
/// use haunts_affordance::density::HitCounter;
/// use haunts_occupancy::{Cell, GridGeometry};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(0.1, Point2::origin(), 10, 10).unwrap();
/// let mut hits = HitCounter::new(g, 0.12).unwrap();
/// // At the centre of cell (5, 5): itself and its four edge neighbours (0.1 m away).
/// assert_eq!(hits.add(Point2::new(0.55, 0.55)), 5);
/// assert_eq!(hits.counts()[Cell::new(6, 5)], 1);
/// assert_eq!(hits.counts()[Cell::new(6, 6)], 0); // a diagonal neighbour is 0.141 m away
/// assert_eq!(hits.add(Point2::new(f64::NAN, 0.0)), 0);
/// assert_eq!(hits.stats().non_finite, 1);
/// ```
///
/// Complexity: O((2·radius / resolution + 3)²) per position.
///
/// With the `serde` feature it is saved as its counts, radius and stats; loading checks the
/// radius as [`HitCounter::new`] does.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "HitCounterFields"))]
pub struct HitCounter {
    counts: Grid<u32>,
    radius: f64,
    stats: HitStats,
}

impl HitCounter {
    /// A counter over `geometry` with a person disc of `radius` metres, all counts zero.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming `person_radius` unless the radius is
    /// finite and > 0.
    pub fn new(geometry: GridGeometry, radius: f64) -> Result<Self> {
        check_radius(radius)?;
        Ok(Self {
            counts: Grid::filled(geometry, 0),
            radius,
            stats: HitStats::default(),
        })
    }

    /// Counts one tracked position (world frame); returns the number of cells it hit.
    /// Non-finite positions are skipped and counted in [`HitStats::non_finite`].
    pub fn add(&mut self, p: Point2<f64>) -> usize {
        if !(p.x.is_finite() && p.y.is_finite()) {
            self.stats.non_finite += 1;
            return 0;
        }
        let geometry = *self.counts.geometry();
        let res = geometry.resolution();
        let (Some((c0, c1)), Some((r0, r1))) = (
            candidate_range(
                p.x - geometry.origin().x,
                res,
                geometry.width(),
                self.radius,
            ),
            candidate_range(
                p.y - geometry.origin().y,
                res,
                geometry.height(),
                self.radius,
            ),
        ) else {
            self.stats.outside += 1;
            return 0;
        };
        let r2 = self.radius * self.radius;
        let w = geometry.width();
        let data = self.counts.data_mut();
        let mut n = 0;
        for row in r0..=r1 {
            for col in c0..=c1 {
                let centre = geometry.cell_center(Cell::new(col, row));
                if within(centre, p, r2) {
                    let i = row * w + col;
                    data[i] = data[i].saturating_add(1);
                    n += 1;
                }
            }
        }
        if n == 0 {
            self.stats.outside += 1;
        } else {
            self.stats.counted += 1;
            self.stats.cell_hits += n;
        }
        n
    }

    /// Counts every position of `positions` (e.g. `tracks.iter().map(|t| t.position)` after
    /// each tracker update); returns the number of cell hits added.
    pub fn add_all(&mut self, positions: impl IntoIterator<Item = Point2<f64>>) -> usize {
        positions.into_iter().map(|p| self.add(p)).sum()
    }

    /// Counts every sample of a trajectory (world frame); returns the number of cell hits.
    pub fn add_trajectory(&mut self, trajectory: &Trajectory) -> usize {
        self.add_all(trajectory.samples.iter().map(|(_, p)| *p))
    }

    /// Radius of the person disc, metres.
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// What counting did so far.
    pub fn stats(&self) -> HitStats {
        self.stats
    }
    /// The hit counts.
    pub fn counts(&self) -> &Grid<u32> {
        &self.counts
    }
    /// The hit counts, consuming the counter.
    pub fn into_counts(self) -> Grid<u32> {
        self.counts
    }
}

/// Whether the cell centre `c` lies strictly closer than √`r2` to `p`: the one predicate the
/// counter and its tests share.
#[inline]
pub(crate) fn within(c: Point2<f64>, p: Point2<f64>, r2: f64) -> bool {
    let (dx, dy) = (c.x - p.x, c.y - p.y);
    dx * dx + dy * dy < r2
}

/// The indices of the `n` cells of side `res` along one axis whose centres may lie within
/// `radius` of coordinate `x` (relative to the grid's origin; one cell of slack on each side,
/// so that the exact predicate decides), clamped to the grid; `None` when no cell can.
fn candidate_range(x: f64, res: f64, n: usize, radius: f64) -> Option<(usize, usize)> {
    // The centre of cell i lies at (i + 0.5)·res.
    let lo = ((x - radius) / res - 0.5).floor() - 1.0;
    let hi = ((x + radius) / res - 0.5).ceil() + 1.0;
    let last = (n - 1) as f64;
    if !(hi >= 0.0 && lo <= last) {
        return None;
    }
    // Both are finite here and clamped into [0, last], so the casts are exact.
    Some((lo.max(0.0) as usize, hi.min(last) as usize))
}

/// What building a day's density did: the tracked positions and the scans.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DayStats {
    /// The tracked positions.
    pub hits: HitStats,
    /// The scans that were raycast.
    pub scans: ScanStats,
    /// Scans skipped because their sensor pose was NaN or infinite.
    pub non_finite_poses: usize,
}

/// One day's affordance density (seed 000 III-B): human hits / laser visits per cell.
///
/// Implements [`DensityMap`]: `density_at(p)` is `hits / visits` of the cell holding `p`,
/// `None` outside the grid or where the cell had fewer than `min_visits` visits.
///
/// ```
/// use haunts_affordance::{density::DailyDensity, DensityMap};
/// use haunts_occupancy::{Grid, GridGeometry};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(1.0, Point2::origin(), 3, 1).unwrap();
/// let hits = Grid::from_vec(g, vec![2, 0, 5]).unwrap();
/// let visits = Grid::from_vec(g, vec![4, 3, 0]).unwrap();
/// let day = DailyDensity::new(hits, visits, 1).unwrap();
/// assert_eq!(day.density_at(Point2::new(0.5, 0.5)), Some(0.5));
/// assert_eq!(day.density_at(Point2::new(1.5, 0.5)), Some(0.0));
/// assert_eq!(day.density_at(Point2::new(2.5, 0.5)), None); // never visited
/// assert_eq!(day.density_at(Point2::new(3.5, 0.5)), None); // outside
/// ```
///
/// With the `serde` feature it is saved as its hit and visit grids and `min_visits`; loading
/// checks them as [`DailyDensity::new`] does.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "DailyDensityFields"))]
pub struct DailyDensity {
    hits: Grid<u32>,
    visits: Grid<u32>,
    min_visits: u32,
}

impl DailyDensity {
    /// A day from its hit and visit counts, both on the same cells.
    ///
    /// # Errors
    /// [`AffordanceError::GeometryMismatch`] (`what` = `"visits"`) when the grids lie on
    /// different cells; [`AffordanceError::InvalidParameter`] for `min_visits` = 0.
    pub fn new(hits: Grid<u32>, visits: Grid<u32>, min_visits: u32) -> Result<Self> {
        check_min_visits(min_visits)?;
        check_geometry("visits", hits.geometry(), visits.geometry())?;
        Ok(Self {
            hits,
            visits,
            min_visits,
        })
    }

    /// A day from raw data: the visits of every scan (`sensor(item)` gives its scan and the
    /// sensor's world pose; raycast in parallel with the `rayon` feature) and the hits of
    /// every tracked world position, on `geometry`.
    ///
    /// Scans with a NaN or infinite pose and non-finite positions are skipped and counted in
    /// the returned [`DayStats`].
    ///
    /// # Errors
    /// As [`DensityParams::check`].
    ///
    /// # Complexity
    /// O(cells crossed by all beams + positions · (2r / res)² + cells).
    pub fn from_day<T: Sync>(
        geometry: GridGeometry,
        scans: &[T],
        sensor: impl Fn(&T) -> (&LaserScan, &Pose2) + Sync,
        positions: impl IntoIterator<Item = Point2<f64>>,
        params: &DensityParams,
    ) -> Result<(Self, DayStats)> {
        let params = params.check()?;
        let mut hits = HitCounter::new(geometry, params.person_radius)?;
        hits.add_all(positions);
        let usable: Vec<&T> = scans
            .iter()
            .filter(|item| pose_is_finite(sensor(item).1))
            .collect();
        let mut visits = VisitCounter::new(geometry, params.visit_rule)?;
        let scan_stats = visits.add_scans(&usable, |item| sensor(item), params.max_range)?;
        let stats = DayStats {
            hits: hits.stats(),
            scans: scan_stats,
            non_finite_poses: scans.len() - usable.len(),
        };
        let day = Self::new(hits.into_counts(), visits.into_counts(), params.min_visits)?;
        Ok((day, stats))
    }

    /// Where the counts lie.
    pub fn geometry(&self) -> &GridGeometry {
        self.hits.geometry()
    }
    /// Human hits per cell.
    pub fn hits(&self) -> &Grid<u32> {
        &self.hits
    }
    /// Laser visits per cell.
    pub fn visits(&self) -> &Grid<u32> {
        &self.visits
    }
    /// Fewest visits for a known density.
    pub fn min_visits(&self) -> u32 {
        self.min_visits
    }
    /// The density of every cell, NaN where unknown (equal to
    /// `self.rasterise(self.geometry())`, computed directly).
    pub fn density_grid(&self) -> Grid<f64> {
        ratio_grid(&self.hits, &self.visits, u64::from(self.min_visits))
    }
    /// Number of cells whose density is known.
    pub fn known_cells(&self) -> usize {
        let min = self.min_visits;
        self.visits.data().iter().filter(|v| **v >= min).count()
    }
}

impl DensityMap for DailyDensity {
    fn density_at(&self, p: Point2<f64>) -> Option<f64> {
        let i = self
            .geometry()
            .world_to_cell(p)
            .and_then(|c| self.geometry().index(c))?;
        ratio(self.hits.data()[i], self.visits.data()[i], self.min_visits)
    }
}

/// `hits / visits`, or `None` below `min` visits.
fn ratio<H: Into<u64>, V: Into<u64>>(hits: H, visits: V, min: impl Into<u64>) -> Option<f64> {
    let (h, v) = (hits.into(), visits.into());
    (v >= min.into()).then(|| h as f64 / v as f64)
}

fn ratio_grid<H: Copy + Into<u64>, V: Copy + Into<u64>>(
    hits: &Grid<H>,
    visits: &Grid<V>,
    min: u64,
) -> Grid<f64> {
    let mut out = Grid::filled(*hits.geometry(), f64::NAN);
    for ((o, h), v) in out
        .data_mut()
        .iter_mut()
        .zip(hits.data())
        .zip(visits.data())
    {
        if let Some(d) = ratio(*h, *v, min) {
            *o = d;
        }
    }
    out
}

/// The cumulative density over many days (seed 000 III-B): Σ hits / Σ visits per cell.
///
/// Sums are 64-bit, so they never saturate in practice. Every day must lie on the
/// accumulator's cells: a day on other cells is an [`AffordanceError::GeometryMismatch`] and
/// adds nothing (no resampling, see the [module docs](crate::density)).
///
/// ```
/// use haunts_affordance::{density::{CumulativeDensity, DailyDensity}, DensityMap};
/// use haunts_occupancy::{Grid, GridGeometry};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(1.0, Point2::origin(), 2, 1).unwrap();
/// let day = |h: Vec<u32>, v: Vec<u32>| {
///     DailyDensity::new(Grid::from_vec(g, h).unwrap(), Grid::from_vec(g, v).unwrap(), 1).unwrap()
/// };
/// let mut all = CumulativeDensity::new(g, 1).unwrap();
/// all.add(&day(vec![1, 0], vec![1, 0])).unwrap();
/// all.add(&day(vec![0, 3], vec![3, 4])).unwrap();
/// assert_eq!(all.density_at(Point2::new(0.5, 0.5)), Some(0.25)); // (1 + 0) / (1 + 3)
/// assert_eq!(all.density_at(Point2::new(1.5, 0.5)), Some(0.75));
/// assert_eq!(all.days(), 2);
/// ```
///
/// With the `serde` feature it is saved as its sums, day count and `min_visits`; loading
/// checks them as [`CumulativeDensity::from_sums`] does.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "CumulativeDensityFields"))]
pub struct CumulativeDensity {
    hits: Grid<u64>,
    visits: Grid<u64>,
    days: u32,
    min_visits: u32,
}

impl CumulativeDensity {
    /// An empty accumulator over `geometry` (every density unknown).
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] for `min_visits` = 0.
    pub fn new(geometry: GridGeometry, min_visits: u32) -> Result<Self> {
        check_min_visits(min_visits)?;
        Ok(Self {
            hits: Grid::filled(geometry, 0),
            visits: Grid::filled(geometry, 0),
            days: 0,
            min_visits,
        })
    }

    /// An accumulator from its sums (e.g. read back from storage).
    ///
    /// # Errors
    /// [`AffordanceError::GeometryMismatch`] (`what` = `"visits"`) when the grids lie on
    /// different cells; [`AffordanceError::InvalidParameter`] for `min_visits` = 0.
    pub fn from_sums(
        hits: Grid<u64>,
        visits: Grid<u64>,
        days: u32,
        min_visits: u32,
    ) -> Result<Self> {
        check_min_visits(min_visits)?;
        check_geometry("visits", hits.geometry(), visits.geometry())?;
        Ok(Self {
            hits,
            visits,
            days,
            min_visits,
        })
    }

    /// Adds one day.
    ///
    /// # Errors
    /// [`AffordanceError::GeometryMismatch`] (`what` = `"day"`) when the day lies on other
    /// cells; nothing is added.
    pub fn add(&mut self, day: &DailyDensity) -> Result<()> {
        self.add_counts(day.hits(), day.visits())
    }

    /// Adds one day given as hit and visit counts.
    ///
    /// # Errors
    /// [`AffordanceError::GeometryMismatch`] (`what` = `"day hits"` or `"day visits"`) when
    /// a grid lies on other cells; nothing is added.
    pub fn add_counts(&mut self, hits: &Grid<u32>, visits: &Grid<u32>) -> Result<()> {
        check_geometry("day hits", self.geometry(), hits.geometry())?;
        check_geometry("day visits", self.geometry(), visits.geometry())?;
        for (s, h) in self.hits.data_mut().iter_mut().zip(hits.data()) {
            *s = s.saturating_add(u64::from(*h));
        }
        for (s, v) in self.visits.data_mut().iter_mut().zip(visits.data()) {
            *s = s.saturating_add(u64::from(*v));
        }
        self.days = self.days.saturating_add(1);
        Ok(())
    }

    /// Where the sums lie.
    pub fn geometry(&self) -> &GridGeometry {
        self.hits.geometry()
    }
    /// Σ hits per cell.
    pub fn hits(&self) -> &Grid<u64> {
        &self.hits
    }
    /// Σ visits per cell.
    pub fn visits(&self) -> &Grid<u64> {
        &self.visits
    }
    /// Number of days added.
    pub fn days(&self) -> u32 {
        self.days
    }
    /// Fewest visits for a known density.
    pub fn min_visits(&self) -> u32 {
        self.min_visits
    }
    /// The density of every cell, NaN where unknown (equal to
    /// `self.rasterise(self.geometry())`, computed directly).
    pub fn density_grid(&self) -> Grid<f64> {
        ratio_grid(&self.hits, &self.visits, u64::from(self.min_visits))
    }
}

impl DensityMap for CumulativeDensity {
    fn density_at(&self, p: Point2<f64>) -> Option<f64> {
        let i = self
            .geometry()
            .world_to_cell(p)
            .and_then(|c| self.geometry().index(c))?;
        ratio(self.hits.data()[i], self.visits.data()[i], self.min_visits)
    }
}

/// The fields of a [`HitCounter`] as deserialised, before the radius is checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct HitCounterFields {
    counts: Grid<u32>,
    radius: f64,
    stats: HitStats,
}

#[cfg(feature = "serde")]
impl TryFrom<HitCounterFields> for HitCounter {
    type Error = AffordanceError;
    fn try_from(f: HitCounterFields) -> Result<Self> {
        check_radius(f.radius)?;
        Ok(Self {
            counts: f.counts,
            radius: f.radius,
            stats: f.stats,
        })
    }
}

/// The fields of a [`DailyDensity`] as deserialised, before [`DailyDensity::new`] checks them.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct DailyDensityFields {
    hits: Grid<u32>,
    visits: Grid<u32>,
    min_visits: u32,
}

#[cfg(feature = "serde")]
impl TryFrom<DailyDensityFields> for DailyDensity {
    type Error = AffordanceError;
    fn try_from(f: DailyDensityFields) -> Result<Self> {
        Self::new(f.hits, f.visits, f.min_visits)
    }
}

/// The fields of a [`CumulativeDensity`] as deserialised, before
/// [`CumulativeDensity::from_sums`] checks them.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct CumulativeDensityFields {
    hits: Grid<u64>,
    visits: Grid<u64>,
    days: u32,
    min_visits: u32,
}

#[cfg(feature = "serde")]
impl TryFrom<CumulativeDensityFields> for CumulativeDensity {
    type Error = AffordanceError;
    fn try_from(f: CumulativeDensityFields) -> Result<Self> {
        Self::from_sums(f.hits, f.visits, f.days, f.min_visits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidate_range_covers_the_disc_and_clamps() {
        // A position far outside on either side has no candidates.
        assert_eq!(candidate_range(-5.0, 0.1, 10, 0.25), None);
        assert_eq!(candidate_range(50.0, 0.1, 10, 0.25), None);
        assert_eq!(candidate_range(1e300, 0.1, 10, 0.25), None);
        assert_eq!(candidate_range(-1e300, 0.1, 10, 0.25), None);
        // Near the border it is clamped to the grid.
        assert_eq!(candidate_range(0.0, 0.1, 10, 0.25), Some((0, 3)));
        let (lo, hi) = candidate_range(0.55, 0.1, 10, 0.25).unwrap();
        assert!(lo <= 3 && hi >= 7, "{lo}..{hi}");
    }

    #[test]
    fn a_disc_just_outside_the_grid_still_hits_the_border_cells() {
        let g = GridGeometry::new(0.1, Point2::origin(), 4, 4).unwrap();
        let mut hits = HitCounter::new(g, 0.25).unwrap();
        // 0.1 m left of the grid: the centres of column 0 lie 0.15 m away.
        assert!(hits.add(Point2::new(-0.1, 0.2)) > 0);
        assert!(hits.counts()[Cell::new(0, 1)] == 1);
        assert_eq!(hits.stats().counted, 1);
    }
}
