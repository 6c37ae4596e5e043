//! Raycasting on grids: exact traversal with the length of the beam in each cell
//! (Amanatides–Woo, on a fixed-point parameter), visit counting with seed 000's half-cell
//! rule, and Bresenham lines.

use nalgebra::Point2;

use crate::scan::BeamDirections;
use crate::{Cell, Grid, GridGeometry, LaserScan, MaxRangeRule, OccupancyError, Pose2, Result};

/// The cells a segment crosses, in order, each with the length (metres) of the segment
/// inside it: the grid traversal of Amanatides & Woo (1987).
///
/// The segment is clipped to the grid first; cells crossed for zero length (a segment
/// through a corner) are skipped. The lengths sum to the length of the clipped segment.
///
/// The segment's parameter `t ∈ [0, 1]` is stepped in fixed point (`t = 1` is 2⁶²
/// units; the first crossing of each axis and the step between crossings are rounded to
/// the unit once, then summed exactly): a 100 m beam is resolved to 2·10⁻¹⁷ m, finer than
/// floating-point sums of the crossings near the beam's end, and the number of cells is
/// known before the first step, so stepping needs no end or edge tests. A length is a whole
/// number of units times the metres per unit; a cell's "length at least `x`" is decided on
/// the units.
///
/// ```
/// use haunts_occupancy::{raycast::Traversal, Cell, GridGeometry};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(1.0, Point2::origin(), 4, 4).unwrap();
/// let cells: Vec<_> = Traversal::new(&g, Point2::new(0.5, 0.5), Point2::new(2.5, 0.5)).collect();
/// assert_eq!(cells.iter().map(|c| c.0).collect::<Vec<_>>(),
///            [Cell::new(0, 0), Cell::new(1, 0), Cell::new(2, 0)]);
/// approx::assert_relative_eq!(cells[1].1, 1.0);
/// ```
///
/// Complexity: O(number of cells crossed).
#[derive(Debug, Clone)]
pub struct Traversal {
    /// Row-major index of the current cell.
    index: i64,
    /// Cells still to step through, those crossed for zero length included.
    steps_left: u64,
    /// What crossing a column (row) boundary adds to `index`: ±1 (±width) or 0.
    index_step_col: i64,
    index_step_row: i64,
    /// Where the traversal is, and where it stops (the clipped segment's end, or where it
    /// would leave the grid if rounding put that first), in fixed-point units.
    t: u64,
    t_stop: u64,
    /// Amanatides–Woo's `t_max` along each axis (the next crossing) and `t_delta` (the
    /// parameter between crossings), in units, capped at [`T_CAP`].
    cross_col: u64,
    cross_row: u64,
    t_delta_col: u64,
    t_delta_row: u64,
    /// Metres per unit of the parameter.
    metres_per_unit: f64,
    width: usize,
}

/// The fixed-point parameter's scale: `t = 1`, the segment's end, is 2⁶² units.
pub(crate) const T_ONE: f64 = (1u64 << 62) as f64;
/// Crossings and steps past the segment's end are capped here, one unit past `t = 1`: any
/// crossing beyond the end ends a traversal alike, and the sums stepping makes stay below
/// 2⁶⁴ (a crossing before the end, below 2⁶², plus a capped step, plus one more).
pub(crate) const T_CAP: u64 = (1 << 62) + 1;

/// Parameter `t ≥ 0` (a point of the segment, a crossing or a step between crossings) in
/// fixed-point units, rounded to nearest, at least `min`; `t ≥ 1` (the segment's end and
/// beyond, +inf included) becomes [`T_CAP`].
pub(crate) fn fixed(t: f64, min: u64) -> u64 {
    let units = t * T_ONE;
    if units >= T_CAP as f64 {
        T_CAP
    } else {
        // `as` saturates: a NaN or negative `t` (never passed) would give 0.
        ((units + 0.5) as u64).max(min)
    }
}

/// The fewest units of a segment with `metres_per_unit` that hold at least `min_length`
/// metres, and at least one: a cell is visited when its units reach this (`units · metres
/// per unit ≥ min_length`, and a positive length).
pub(crate) fn units_for(min_length: f64, metres_per_unit: f64) -> u64 {
    let units = min_length / metres_per_unit;
    // `as` saturates (+inf for a segment of length zero: nothing is visited) and truncates;
    // one more unit where it cut a fraction: ⌈units⌉ without libm's `ceil`.
    let whole = units as u64;
    let whole = if (whole as f64) < units {
        whole.saturating_add(1)
    } else {
        whole
    };
    whole.max(1)
}

/// Crossings left along an axis the segment does not move on.
const NEVER_LEAVES: i64 = i64::MAX / 2;

/// How many scans a thread of [`VisitCounter::add_scans`] takes at a time.
#[cfg(feature = "rayon")]
const SCANS_PER_BATCH: usize = 8;

/// Where the traversal of a segment starts: the parameter interval `[t0, t1)` of the segment
/// clipped to the grid, the start cell, and per axis the step (±1 or 0), the first crossing
/// (`t_max`) and the parameter between crossings (`t_delta`).
pub(crate) struct Start {
    pub(crate) t0: f64,
    pub(crate) t1: f64,
    pub(crate) col: i64,
    pub(crate) row: i64,
    pub(crate) col_axis: (i64, f64, f64),
    pub(crate) row_axis: (i64, f64, f64),
    pub(crate) metres_per_t: f64,
}

impl Start {
    /// The start of segment `from`–`to` over `geometry`; `None` when the segment misses the
    /// grid, is degenerate after clipping, or has a non-finite point.
    pub(crate) fn new(geometry: &GridGeometry, from: Point2<f64>, to: Point2<f64>) -> Option<Self> {
        let (ax, ay) = geometry.world_to_grid(from);
        let (bx, by) = geometry.world_to_grid(to);
        let (dx, dy) = (bx - ax, by - ay);
        let (width, height) = (geometry.width() as i64, geometry.height() as i64);
        // Liang–Barsky clipping of a + t·d, t ∈ [0, 1], to [0, w] × [0, h].
        let (lo, hi) = clip(ax, dx, width as f64)?;
        let (lo2, hi2) = clip(ay, dy, height as f64)?;
        let (t0, t1) = (lo.max(lo2), hi.min(hi2));
        let metres_per_t = (to - from).norm();
        // A segment of no length crosses nothing (its parameter interval is not empty).
        if t0.partial_cmp(&t1) != Some(std::cmp::Ordering::Less) || metres_per_t == 0.0 {
            return None;
        }
        let start_cell = |a: f64, d: f64, n: i64| {
            let p = a + t0 * d;
            // ⌊p⌋ without `f64::floor`, a libm call on x86-64's baseline: `p` lies in
            // [0, n] up to rounding, where truncation and one correction are exact.
            let mut c = p as i64;
            if c as f64 > p {
                c -= 1;
            }
            if d < 0.0 && c as f64 == p {
                c -= 1;
            }
            c.clamp(0, n - 1)
        };
        let (col, row) = (start_cell(ax, dx, width), start_cell(ay, dy, height));
        // t_max > 0: the start cell's far side lies strictly ahead of `a` (a ≤ p < c + 1
        // moving up, c < p ≤ a moving down, and beyond the clamps likewise).
        let axis = |a: f64, d: f64, c: i64| -> (i64, f64, f64) {
            if d > 0.0 {
                (1, ((c + 1) as f64 - a) / d, 1.0 / d)
            } else if d < 0.0 {
                (-1, (c as f64 - a) / d, -1.0 / d)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        Some(Self {
            t0,
            t1,
            col,
            row,
            col_axis: axis(ax, dx, col),
            row_axis: axis(ay, dy, row),
            metres_per_t,
        })
    }
}

impl Traversal {
    /// The traversal of segment `from`–`to` (world coordinates) over `geometry`. Non-finite
    /// points give an empty traversal.
    pub fn new(geometry: &GridGeometry, from: Point2<f64>, to: Point2<f64>) -> Self {
        let Some(start) = Start::new(geometry, from, to) else {
            return Self {
                index: 0,
                steps_left: 0,
                index_step_col: 0,
                index_step_row: 0,
                t: 0,
                t_stop: 0,
                cross_col: T_CAP,
                cross_row: T_CAP,
                t_delta_col: T_CAP,
                t_delta_row: T_CAP,
                metres_per_unit: 0.0,
                width: geometry.width(),
            };
        };
        Self::from_start(geometry, &start)
    }

    /// The traversal from a segment's [`Start`] over `geometry`.
    fn from_start(geometry: &GridGeometry, start: &Start) -> Self {
        let width = geometry.width() as i64;
        let (step_col, t_max_col, t_delta_col) = start.col_axis;
        let (step_row, t_max_row, t_delta_row) = start.row_axis;
        // Crossings left before leaving the grid along an axis: to the far side moving up,
        // to column (row) 0 moving down.
        let left = |step: i64, c: i64, n: i64| match step {
            1 => n - 1 - c,
            -1 => c,
            _ => NEVER_LEAVES,
        };
        let (t0, t1) = (fixed(start.t0, 0), fixed(start.t1, 0));
        // No crossing before the start: rounding can put the start cell's far side a hair
        // behind a clipped segment's entry, and the parameter must never step back.
        let (cross_col, cross_row) = (fixed(t_max_col, t0), fixed(t_max_row, t0));
        // At least one unit between crossings, so that counting them below never divides
        // by zero (a step rounds to zero only on a segment over 2⁶² cells long).
        let (t_delta_col, t_delta_row) = (fixed(t_delta_col, 1), fixed(t_delta_row, 1));
        // The crossing that would leave the grid along an axis: the traversal stops there
        // if rounding puts it before the clipped end.
        let leaves = |cross: u64, delta: u64, left: i64| {
            cross.saturating_add(delta.saturating_mul(left.max(0) as u64))
        };
        let t_stop = t1
            .min(leaves(
                cross_col,
                t_delta_col,
                left(step_col, start.col, width),
            ))
            .min(leaves(
                cross_row,
                t_delta_row,
                left(step_row, start.row, geometry.height() as i64),
            ));
        // One cell to start with, then one more at every crossing before the stop (exact
        // sums: crossing k is `cross + k·delta`).
        let crossings = |cross: u64, delta: u64| {
            if cross >= t_stop {
                0
            } else {
                (t_stop - cross - 1) / delta + 1
            }
        };
        let steps_left = if t0 < t_stop {
            1 + crossings(cross_col, t_delta_col) + crossings(cross_row, t_delta_row)
        } else {
            0
        };
        Self {
            index: start.row * width + start.col,
            steps_left,
            index_step_col: step_col,
            index_step_row: step_row * width,
            t: t0,
            t_stop,
            cross_col,
            cross_row,
            t_delta_col,
            t_delta_row,
            metres_per_unit: start.metres_per_t / T_ONE,
            width: geometry.width(),
        }
    }

    /// Metres per unit of the fixed-point parameter.
    pub(crate) fn metres_per_unit(&self) -> f64 {
        self.metres_per_unit
    }

    /// The row-major index of the next cell crossed and the units of the parameter inside
    /// it (zero through a corner), advancing: Amanatides–Woo's step, one crossing at a
    /// time (at a corner the column's first, and the row's follows through the corner
    /// cell for zero units).
    #[inline(always)]
    fn step(&mut self) -> Option<(usize, u64)> {
        if self.steps_left == 0 {
            return None;
        }
        self.steps_left -= 1;
        let index = self.index as usize;
        let (cross_col, cross_row) = (self.cross_col, self.cross_row);
        // Which axis crosses next, as a select and an all-ones mask rather than a branch:
        // it is data dependent, and a mispredicted branch costs more than a step.
        let row = cross_row < cross_col;
        let mask_row = 0u64.wrapping_sub(u64::from(row));
        let t_next = if row { cross_row } else { cross_col };
        // Only the last step ends before its crossing.
        let t_exit = t_next.min(self.t_stop);
        let units = t_exit - self.t;
        self.index += if row {
            self.index_step_row
        } else {
            self.index_step_col
        };
        self.cross_col = cross_col + (self.t_delta_col & !mask_row);
        self.cross_row = cross_row + (self.t_delta_row & mask_row);
        self.t = t_exit;
        Some((index, units))
    }

    /// Runs the traversal to its end, calling `f` with the row-major index of every cell
    /// stepped through and the units of the parameter inside it (times
    /// [`Self::metres_per_unit`] for metres): the iterator's cells, and besides them the
    /// cells crossed for zero units (through a corner), which callers skip.
    #[inline(always)]
    pub(crate) fn for_each_index(mut self, mut f: impl FnMut(usize, u64)) {
        while let Some((index, units)) = self.step() {
            f(index, units);
        }
    }
}

/// The parameter interval where `a + t·d` lies in `[0, n]`, intersected with `[0, 1]`.
fn clip(a: f64, d: f64, n: f64) -> Option<(f64, f64)> {
    if !(a.is_finite() && d.is_finite()) {
        return None;
    }
    if d == 0.0 {
        return (0.0..=n).contains(&a).then_some((0.0, 1.0));
    }
    let (t_a, t_b) = ((0.0 - a) / d, (n - a) / d);
    let (lo, hi) = if t_a < t_b { (t_a, t_b) } else { (t_b, t_a) };
    Some((lo.max(0.0), hi.min(1.0)))
}

impl Iterator for Traversal {
    type Item = (Cell, f64);

    fn next(&mut self) -> Option<(Cell, f64)> {
        while let Some((index, units)) = self.step() {
            if units > 0 {
                let length = units as f64 * self.metres_per_unit;
                return Some((Cell::new(index % self.width, index / self.width), length));
            }
        }
        None
    }
}

/// Seed 000's rule for "the laser visited a cell": the beam crossed at least
/// `min_fraction` of a cell side inside it (0.5: "at least 0.25 cm, half the side of the
/// cell" — the paper's 5 cm cells make that 2.5 cm, which is what we read it as).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VisitRule {
    /// Fraction of the cell side a beam must cross inside a cell to visit it.
    pub min_fraction: f64,
}

impl Default for VisitRule {
    fn default() -> Self {
        Self { min_fraction: 0.5 }
    }
}

impl VisitRule {
    /// The rule, after checking `0 <= min_fraction <= √2` (no cell holds a longer chord).
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`].
    pub fn check(self) -> Result<Self> {
        if !(0.0..=std::f64::consts::SQRT_2).contains(&self.min_fraction) {
            return Err(OccupancyError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "min_fraction",
                    value: self.min_fraction,
                    rule: "must be in [0, sqrt(2)]",
                },
            ));
        }
        Ok(self)
    }
}

/// What adding a scan did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ScanStats {
    /// Beams that became rays (hits, and max-range readings when they clear).
    pub rays: usize,
    /// Beams without information (NaN, -inf, zero, too short), or max-range beams ignored.
    pub skipped_beams: usize,
    /// Cells counted (a cell crossed by several rays counts once per ray).
    pub cell_visits: usize,
}

/// Counts, per cell, the laser beams that visited it (seed 000 III-B's "number of visits").
///
/// ```
/// use haunts_occupancy::{raycast::{VisitCounter, VisitRule}, Cell, GridGeometry};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(0.1, Point2::origin(), 10, 10).unwrap();
/// let mut visits = VisitCounter::new(g, VisitRule::default()).unwrap();
/// // Crosses column 0 to 4 of row 0 fully, and only 0.02 m (less than half) of column 5.
/// visits.add_ray(Point2::new(0.0, 0.05), Point2::new(0.52, 0.05));
/// assert_eq!(visits.counts()[Cell::new(4, 0)], 1);
/// assert_eq!(visits.counts()[Cell::new(5, 0)], 0);
/// ```
#[derive(Debug, Clone)]
pub struct VisitCounter {
    counts: Grid<u32>,
    min_length: f64,
    /// The last scan's beam directions (a cache: not part of the counter's value).
    directions: BeamDirections,
}

impl PartialEq for VisitCounter {
    fn eq(&self, other: &Self) -> bool {
        self.counts == other.counts && self.min_length == other.min_length
    }
}

impl VisitCounter {
    /// A counter over `geometry`, all counts zero.
    ///
    /// # Errors
    /// As [`VisitRule::check`].
    pub fn new(geometry: GridGeometry, rule: VisitRule) -> Result<Self> {
        let rule = rule.check()?;
        Ok(Self {
            counts: Grid::filled(geometry, 0),
            min_length: rule.min_fraction * geometry.resolution(),
            directions: BeamDirections::default(),
        })
    }

    /// Counts the cells segment `from`–`to` visits; returns how many.
    pub fn add_ray(&mut self, from: Point2<f64>, to: Point2<f64>) -> usize {
        let traversal = Traversal::new(self.counts.geometry(), from, to);
        let threshold = units_for(self.min_length, traversal.metres_per_unit());
        let data = self.counts.data_mut();
        let mut n = 0;
        // Every cell's count is rewritten, by 0 or 1: whether a beam visits a cell is data
        // dependent, and a branch on it is mispredicted at diagonal rays' short cells.
        traversal.for_each_index(|index, units| {
            let visited = units >= threshold;
            if let Some(count) = data.get_mut(index) {
                *count = count.saturating_add(u32::from(visited));
                n += usize::from(visited);
            }
        });
        n
    }

    /// Counts every ray of `scan` taken by a sensor at `sensor_pose`.
    ///
    /// # Errors
    /// [`OccupancyError::NonFinitePose`] for a NaN or infinite pose (nothing is counted).
    pub fn add_scan(
        &mut self,
        scan: &LaserScan,
        sensor_pose: &Pose2,
        max_range: MaxRangeRule,
    ) -> Result<ScanStats> {
        if !crate::pose_is_finite(sensor_pose) {
            return Err(OccupancyError::NonFinitePose {
                what: format!("scan at t = {}", scan.stamp),
            });
        }
        let mut directions = std::mem::take(&mut self.directions);
        let mut stats = ScanStats::default();
        for ray in scan.rays_along(sensor_pose, max_range, directions.of(scan)) {
            stats.rays += 1;
            stats.cell_visits += self.add_ray(ray.from, ray.to);
        }
        self.directions = directions;
        stats.skipped_beams = scan.len() - stats.rays;
        Ok(stats)
    }

    /// Counts the rays of many scans, `sensor(item)` giving each item's scan and sensor
    /// pose; in parallel with the `rayon` feature (each thread counts into its own grid,
    /// then the counts are added: the result is the same with any number of threads).
    ///
    /// # Errors
    /// [`OccupancyError::NonFinitePose`] for the first item with a NaN or infinite pose;
    /// nothing is counted then.
    pub fn add_scans<T: Sync>(
        &mut self,
        items: &[T],
        sensor: impl Fn(&T) -> (&LaserScan, &Pose2) + Sync,
        max_range: MaxRangeRule,
    ) -> Result<ScanStats> {
        if let Some((scan, _)) = items
            .iter()
            .map(&sensor)
            .find(|(_, p)| !crate::pose_is_finite(p))
        {
            return Err(OccupancyError::NonFinitePose {
                what: format!("scan at t = {}", scan.stamp),
            });
        }
        let count = |counter: &mut VisitCounter, chunk: &[T], stats: &mut ScanStats| {
            let mut directions = std::mem::take(&mut counter.directions);
            for (scan, pose) in chunk.iter().map(&sensor) {
                for ray in scan.rays_along(pose, max_range, directions.of(scan)) {
                    stats.rays += 1;
                    stats.cell_visits += counter.add_ray(ray.from, ray.to);
                }
                stats.skipped_beams += scan.len();
            }
            counter.directions = directions;
        };
        let mut stats = ScanStats::default();
        #[cfg(feature = "rayon")]
        {
            let threads = rayon::current_num_threads().max(1);
            if threads > 1 && items.len() > SCANS_PER_BATCH {
                // Every thread takes batches of scans from a shared cursor until none are
                // left, counting into its own grid (this counter's for the calling thread,
                // zeroed grids for the others, allocated when they take their first batch);
                // then the grids are added, row blocks in parallel. Batches rather than one
                // chunk per thread: scans differ in length (the Intel log's first half has
                // 17 % more cell steps than its second), and a thread that finishes early
                // takes more. The counts are sums: the same whichever thread counted what.
                let cursor = std::sync::atomic::AtomicUsize::new(0);
                let take = || {
                    let at =
                        cursor.fetch_add(SCANS_PER_BATCH, std::sync::atomic::Ordering::Relaxed);
                    items.get(at..items.len().min(at + SCANS_PER_BATCH))
                };
                let geometry = *self.counts.geometry();
                let min_length = self.min_length;
                // Spawned tasks rather than `rayon::broadcast`, which would wait for every
                // thread of the pool, also those busy with other work when this runs inside
                // a parallel task.
                let parts = std::sync::Mutex::new(Vec::new());
                rayon::scope(|scope| {
                    for _ in 1..threads {
                        scope.spawn(|_| {
                            let Some(batch) = take() else { return };
                            let mut local = VisitCounter {
                                counts: Grid::filled(geometry, 0),
                                min_length,
                                directions: BeamDirections::default(),
                            };
                            let mut stats = ScanStats::default();
                            count(&mut local, batch, &mut stats);
                            while let Some(batch) = take() {
                                count(&mut local, batch, &mut stats);
                            }
                            parts
                                .lock()
                                .unwrap_or_else(std::sync::PoisonError::into_inner)
                                .push((local, stats));
                        });
                    }
                    while let Some(batch) = take() {
                        count(self, batch, &mut stats);
                    }
                });
                let parts = parts
                    .into_inner()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                for (part, part_stats) in parts {
                    self.merge(&part)?;
                    stats.rays += part_stats.rays;
                    stats.skipped_beams += part_stats.skipped_beams;
                    stats.cell_visits += part_stats.cell_visits;
                }
                stats.skipped_beams -= stats.rays;
                return Ok(stats);
            }
        }
        count(self, items, &mut stats);
        stats.skipped_beams -= stats.rays;
        Ok(stats)
    }

    /// Adds another counter's counts (same geometry) to this one, saturating (in row blocks
    /// in parallel with the `rayon` feature: the same sums).
    ///
    /// # Errors
    /// [`OccupancyError::GeometryMismatch`].
    pub fn merge(&mut self, other: &VisitCounter) -> Result<()> {
        if self.counts.geometry() != other.counts.geometry() {
            return Err(OccupancyError::GeometryMismatch {
                expected: Box::new(*self.counts.geometry()),
                found: Box::new(*other.counts.geometry()),
            });
        }
        let add = |a: &mut [u32], b: &[u32]| {
            for (x, y) in a.iter_mut().zip(b) {
                *x = x.saturating_add(*y);
            }
        };
        #[cfg(feature = "rayon")]
        {
            use rayon::prelude::*;
            // Row blocks of 64 in parallel (the sums do not depend on the split).
            let block = 64 * self.counts.geometry().width().max(1);
            self.counts
                .data_mut()
                .par_chunks_mut(block)
                .zip(other.counts.data().par_chunks(block))
                .for_each(|(a, b)| add(a, b));
        }
        #[cfg(not(feature = "rayon"))]
        add(self.counts.data_mut(), other.counts.data());
        Ok(())
    }

    /// The visit counts.
    pub fn counts(&self) -> &Grid<u32> {
        &self.counts
    }
    /// The visit counts, consuming the counter.
    pub fn into_counts(self) -> Grid<u32> {
        self.counts
    }
}

/// The cells of the Bresenham line from `a` to `b`, both included, in order: the 8-connected
/// line ROS costmaps raytrace with. Coordinates may lie outside any grid.
///
/// ```
/// use haunts_occupancy::raycast::bresenham;
/// assert_eq!(bresenham((0, 0), (3, 1)).collect::<Vec<_>>(), [(0, 0), (1, 0), (2, 1), (3, 1)]);
/// ```
pub fn bresenham(a: (i64, i64), b: (i64, i64)) -> impl Iterator<Item = (i64, i64)> {
    let (dx, dy) = ((b.0 - a.0).abs(), -(b.1 - a.1).abs());
    let (sx, sy) = ((b.0 - a.0).signum(), (b.1 - a.1).signum());
    let mut state = Some((a, dx + dy));
    std::iter::from_fn(move || {
        let ((x, y), err) = state?;
        state = if (x, y) == b {
            None
        } else {
            let e2 = 2 * err;
            let (mut nx, mut ny, mut nerr) = (x, y, err);
            if e2 >= dy {
                nerr += dy;
                nx += sx;
            }
            if e2 <= dx {
                nerr += dx;
                ny += sy;
            }
            Some(((nx, ny), nerr))
        };
        Some((x, y))
    })
}

/// The grid cells of the Bresenham line between the cells holding two world points,
/// clipped to the grid first (so far-away points cost nothing).
pub fn bresenham_cells(
    geometry: &GridGeometry,
    from: Point2<f64>,
    to: Point2<f64>,
) -> impl Iterator<Item = Cell> + '_ {
    let (ax, ay) = geometry.world_to_grid(from);
    let (bx, by) = geometry.world_to_grid(to);
    let (w, h) = (geometry.width() as f64, geometry.height() as f64);
    let clipped = clip(ax, bx - ax, w).and_then(|(lo, hi)| {
        let (lo2, hi2) = clip(ay, by - ay, h)?;
        let (t0, t1) = (lo.max(lo2), hi.min(hi2));
        (t0 <= t1).then_some((t0, t1))
    });
    let line = clipped.map(|(t0, t1)| {
        let cell = |t: f64| {
            let (x, y) = (ax + t * (bx - ax), ay + t * (by - ay));
            (
                (x.floor() as i64).clamp(0, geometry.width() as i64 - 1),
                (y.floor() as i64).clamp(0, geometry.height() as i64 - 1),
            )
        };
        bresenham(cell(t0), cell(t1))
    });
    line.into_iter()
        .flatten()
        .filter_map(|(c, r)| geometry.checked_cell(c, r))
}

#[cfg(test)]
pub(crate) mod reference;
#[cfg(test)]
mod tests;
