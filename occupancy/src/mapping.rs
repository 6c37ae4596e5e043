//! Occupancy mapping from scans with known poses: the log-odds inverse sensor model, with
//! per-cell hit and visit counts kept beside it.

use crate::raycast::{ScanStats, Traversal, VisitRule, units_for};
use crate::scan::BeamDirections;
use crate::{
    Grid, GridGeometry, LaserScan, MaxRangeRule, OccupancyError, OccupancyGrid, Pose2, Result,
    UNKNOWN,
};

/// Parameters of the inverse sensor model (probabilities; the mapper works in log-odds).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct MapperParams {
    /// Probability that the cell holding a beam's endpoint is occupied (> 0.5).
    pub p_hit: f64,
    /// Probability that a cell a beam passed through is occupied (< 0.5).
    pub p_miss: f64,
    /// Lower clamp of a cell's probability (keeps maps able to change).
    pub p_min: f64,
    /// Upper clamp of a cell's probability.
    pub p_max: f64,
    /// What max-range readings do.
    pub max_range: MaxRangeRule,
    /// When a beam counts as visiting a cell (for the visit counts).
    pub visit_rule: VisitRule,
}

impl Default for MapperParams {
    /// `p_hit` 0.7, `p_miss` 0.4, clamped to [0.12, 0.97] (the values of common 2-D SLAM
    /// mappers), max-range readings clearing to 5 m, and seed 000's half-cell visit rule.
    fn default() -> Self {
        Self {
            p_hit: 0.7,
            p_miss: 0.4,
            p_min: 0.12,
            p_max: 0.97,
            max_range: MaxRangeRule::default(),
            visit_rule: VisitRule::default(),
        }
    }
}

impl MapperParams {
    /// The parameters, after checking `0 < p_min < p_miss < 0.5 < p_hit < p_max < 1`.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        let rules = [
            (
                "p_min",
                self.p_min,
                self.p_min > 0.0 && self.p_min < self.p_miss,
                "must be in (0, p_miss)",
            ),
            ("p_miss", self.p_miss, self.p_miss < 0.5, "must be < 0.5"),
            (
                "p_hit",
                self.p_hit,
                self.p_hit > 0.5 && self.p_hit < self.p_max,
                "must be in (0.5, p_max)",
            ),
            ("p_max", self.p_max, self.p_max < 1.0, "must be < 1"),
        ];
        for (name, value, ok, rule) in rules {
            if !ok {
                return Err(OccupancyError::InvalidParameter(
                    haunts_core::InvalidParameter { name, value, rule },
                ));
            }
        }
        if let MaxRangeRule::Clear(limit) = self.max_range {
            if !(limit.is_finite() && limit >= 0.0) {
                return Err(OccupancyError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "max_range",
                        value: limit,
                        rule: "clearing limit must be finite and >= 0",
                    },
                ));
            }
        }
        self.visit_rule.check()?;
        Ok(self)
    }
}

fn log_odds(p: f64) -> f32 {
    (p / (1.0 - p)).ln() as f32
}

/// Builds an occupancy grid from scans taken at known poses.
///
/// Each beam lowers the log-odds of the cells it passes through and raises that of the cell
/// holding its endpoint (a hit); log-odds are clamped. Hits (endpoints per cell) and visits
/// (beams crossing at least half a cell side, seed 000 III-B) are counted too.
///
/// ```
/// use haunts_occupancy::{mapping::{MapperParams, OccupancyMapper}, CellState, GridGeometry, LaserScan, Pose2};
/// use nalgebra::{Point2, Vector2};
/// let g = GridGeometry::new(0.1, Point2::new(-1.0, -1.0), 30, 20).unwrap();
/// let mut mapper = OccupancyMapper::new(g, MapperParams::default()).unwrap();
/// // A wall 1.5 m ahead of a sensor at the origin.
/// let scan = LaserScan::new(0.0, -0.2, 0.01, 0.0, 10.0, vec![1.5; 41], vec![]).unwrap();
/// for _ in 0..5 {
///     mapper.insert(&scan, &Pose2::identity()).unwrap();
/// }
/// let map = mapper.occupancy_grid();
/// assert_eq!(map.state(g.world_to_cell(Point2::new(1.52, 0.0)).unwrap()), Some(CellState::Occupied));
/// assert_eq!(map.state(g.world_to_cell(Point2::new(0.75, 0.0)).unwrap()), Some(CellState::Free));
/// assert_eq!(map.state(g.world_to_cell(Point2::new(-0.5, 0.5)).unwrap()), Some(CellState::Unknown));
/// ```
#[derive(Debug, Clone)]
pub struct OccupancyMapper {
    params: MapperParams,
    log_odds: Grid<f32>,
    touched: Vec<bool>,
    hits: Grid<u32>,
    visits: Grid<u32>,
    l_hit: f32,
    l_miss: f32,
    l_min: f32,
    l_max: f32,
    min_visit_length: f64,
    /// The last scan's beam directions (a cache).
    directions: BeamDirections,
}

impl OccupancyMapper {
    /// An empty map (every cell unknown) over `geometry`.
    ///
    /// # Errors
    /// As [`MapperParams::check`].
    pub fn new(geometry: GridGeometry, params: MapperParams) -> Result<Self> {
        let params = params.check()?;
        Ok(Self {
            params,
            log_odds: Grid::filled(geometry, 0.0),
            touched: vec![false; geometry.len()],
            hits: Grid::filled(geometry, 0),
            visits: Grid::filled(geometry, 0),
            l_hit: log_odds(params.p_hit),
            l_miss: log_odds(params.p_miss),
            l_min: log_odds(params.p_min),
            l_max: log_odds(params.p_max),
            min_visit_length: params.visit_rule.min_fraction * geometry.resolution(),
            directions: BeamDirections::default(),
        })
    }

    /// Adds one scan taken by a sensor at `sensor_pose` (world frame).
    ///
    /// # Errors
    /// [`OccupancyError::NonFinitePose`] for a NaN or infinite pose; the map is unchanged.
    pub fn insert(&mut self, scan: &LaserScan, sensor_pose: &Pose2) -> Result<ScanStats> {
        if !crate::pose_is_finite(sensor_pose) {
            return Err(OccupancyError::NonFinitePose {
                what: format!("scan at t = {}", scan.stamp),
            });
        }
        let geometry = *self.log_odds.geometry();
        let w = geometry.width();
        let (l_hit, l_miss, l_min, l_max) = (self.l_hit, self.l_miss, self.l_min, self.l_max);
        let min_visit_length = self.min_visit_length;
        // The grids borrowed once for the whole scan (not re-borrowed through `self` at
        // every cell), and plain selects for the clamps: log-odds are never NaN.
        let lo = self.log_odds.data_mut();
        // The other grids cut to the log-odds' length (`new` gives all four the same
        // geometry, so the cuts are whole), so that the one bounds check against `n` at
        // every step serves all of them.
        let n = lo.len();
        let visits = &mut self.visits.data_mut()[..n];
        let hits = &mut self.hits.data_mut()[..n];
        let touched = &mut self.touched[..n];
        let mut stats = ScanStats::default();
        let mut cell_visits = 0;
        let directions = self.directions.of(scan);
        for ray in scan.rays_along(sensor_pose, self.params.max_range, directions) {
            stats.rays += 1;
            // The endpoint's index, or `usize::MAX` (no cell) for a clearing ray or an
            // endpoint outside the grid.
            let end = if ray.hit {
                geometry
                    .world_to_cell(ray.to)
                    .map_or(usize::MAX, |c| c.row * w + c.col)
            } else {
                usize::MAX
            };
            let traversal = Traversal::new(&geometry, ray.from, ray.to);
            let visit_units = units_for(min_visit_length, traversal.metres_per_unit());
            traversal.for_each_index(|i, units| {
                if i >= n || units == 0 {
                    return;
                }
                // Added as 0 or 1 without a branch: see `VisitCounter::add_ray`.
                let visited = units >= visit_units;
                visits[i] += u32::from(visited);
                cell_visits += usize::from(visited);
                touched[i] = true;
                if i != end {
                    let missed = lo[i] + l_miss;
                    lo[i] = if missed > l_min { missed } else { l_min };
                }
            });
            if end < n {
                let hit = lo[end] + l_hit;
                lo[end] = if hit < l_max { hit } else { l_max };
                touched[end] = true;
                hits[end] += 1;
            }
        }
        stats.cell_visits = cell_visits;
        stats.skipped_beams = scan.len() - stats.rays;
        Ok(stats)
    }

    /// The mapper of posed scans read twice from `scans` (a closure that starts them over):
    /// once for the bounds of every sensor position and beam endpoint (plus `margin` metres),
    /// once to insert them, so the scans are never held in memory together. Scans whose pose
    /// is not finite are skipped and counted in the second value.
    ///
    /// # Errors
    /// What [`GridGeometry::bounding`] and [`OccupancyMapper::new`] reject (no finite point,
    /// a bad resolution or margin). A pose or beam endpoint far from the rest, or a
    /// resolution too fine for the area, is [`OccupancyError::GridTooLarge`] naming the
    /// extent, before the map is allocated (the mapper keeps 13 bytes per cell).
    ///
    /// # Complexity
    /// Two passes over the scans; `O(beams · cells crossed)` for the second.
    ///
    /// # Example
    /// ```
    /// use haunts_occupancy::mapping::{MapperParams, OccupancyMapper};
    /// use haunts_occupancy::{LaserScan, Pose2};
    ///
    /// let scan = LaserScan::new(0.0, -0.2, 0.01, 0.0, 10.0, vec![1.5; 41], vec![])?;
    /// let posed = || (0..3).map(|i| (scan.clone(), Pose2::translation(0.1 * f64::from(i), 0.0)));
    /// let (mapper, skipped) = OccupancyMapper::from_posed_scans(posed, 0.05, 0.5, MapperParams::default())?;
    /// assert_eq!(skipped, 0);
    /// assert!(mapper.geometry().width() > 30);
    /// # Ok::<(), haunts_occupancy::OccupancyError>(())
    /// ```
    pub fn from_posed_scans<I>(
        mut scans: impl FnMut() -> I,
        resolution: f64,
        margin: f64,
        params: MapperParams,
    ) -> Result<(Self, usize)>
    where
        I: Iterator<Item = (LaserScan, Pose2)>,
    {
        let points = scans()
            .filter(|(_, pose)| crate::pose_is_finite(pose))
            .flat_map(|(scan, pose)| {
                let ends: Vec<_> = scan.endpoints().map(|p| pose * p).collect();
                ends.into_iter()
                    .chain(std::iter::once(pose * nalgebra::Point2::origin()))
            });
        let geometry = GridGeometry::bounding(points, resolution, margin)?;
        let mut mapper = Self::new(geometry, params)?;
        let mut skipped = 0;
        for (scan, pose) in scans() {
            if mapper.insert(&scan, &pose).is_err() {
                skipped += 1;
            }
        }
        Ok((mapper, skipped))
    }

    /// Where the map lies.
    pub fn geometry(&self) -> &GridGeometry {
        self.log_odds.geometry()
    }
    /// Log-odds of occupancy per cell (0 = unknown prior).
    pub fn log_odds(&self) -> &Grid<f32> {
        &self.log_odds
    }
    /// Beam endpoints per cell.
    pub fn hits(&self) -> &Grid<u32> {
        &self.hits
    }
    /// Beams that visited each cell (half-cell rule).
    pub fn visits(&self) -> &Grid<u32> {
        &self.visits
    }

    /// The map as ROS occupancy values: `round(100·p)` where a beam touched the cell, −1
    /// elsewhere; states are read with the default thresholds (≥ 65 occupied, ≤ 25 free).
    pub fn occupancy_grid(&self) -> OccupancyGrid {
        let value = |l: f32| {
            let p = 1.0 - 1.0 / (1.0 + f64::from(l).exp());
            (100.0 * p).round() as i8
        };
        // The last log-odds converted and its value: neighbouring cells mostly hold the
        // same log-odds (free space sits at the `p_min` clamp), and `exp` is the cost.
        let mut last = (0.0f32, value(0.0));
        let values = self
            .log_odds
            .data()
            .iter()
            .zip(&self.touched)
            .map(|(&l, &t)| {
                if !t {
                    return UNKNOWN;
                }
                if l.to_bits() != last.0.to_bits() {
                    last = (l, value(l));
                }
                last.1
            })
            .collect();
        let values = Grid::from_vec(*self.geometry(), values);
        // Values are in 0..=100 by construction.
        values
            .and_then(OccupancyGrid::from_grid)
            .unwrap_or_else(|_| OccupancyGrid::unknown(*self.geometry()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mapper against a plain one on the plain traversal (`raycast::reference`):
    /// log-odds bit for bit, hits, visits and touched cells.
    #[test]
    fn mapping_equals_a_plain_mapper_on_the_plain_traversal() {
        use crate::raycast::reference;
        for (resolution, origin) in [
            (0.05, (-2.0, -1.5)),
            (0.1, (-2.03, -1.49)),
            (0.25, (-2.0, -1.5)),
        ] {
            let g = GridGeometry::new(
                resolution,
                nalgebra::Point2::new(origin.0, origin.1),
                80,
                60,
            )
            .unwrap();
            let params = MapperParams::default();
            let mut fast = OccupancyMapper::new(g, params).unwrap();
            let mut lo = vec![0f32; g.len()];
            let (mut hits, mut visits, mut touched) = (
                vec![0u32; g.len()],
                vec![0u32; g.len()],
                vec![false; g.len()],
            );
            let (l_hit, l_miss) = (log_odds(params.p_hit), log_odds(params.p_miss));
            let (l_min, l_max) = (log_odds(params.p_min), log_odds(params.p_max));
            let min_length = 0.5 * resolution;
            for i in 0..60 {
                // Beams from grid corners and from anywhere, some at 45°, some leaving the map.
                let ranges = (0..120)
                    .map(|b| {
                        if b % 29 == 0 {
                            f64::NAN
                        } else {
                            0.3 + 0.071 * f64::from((b * 13 + i) % 70)
                        }
                    })
                    .collect();
                let scan = LaserScan::new(
                    0.0,
                    -std::f64::consts::PI,
                    std::f64::consts::PI / 60.0,
                    0.1,
                    6.0,
                    ranges,
                    vec![],
                )
                .unwrap();
                let at = if i % 2 == 0 {
                    0.25 * f64::from(i % 8)
                } else {
                    0.137 * f64::from(i % 11)
                };
                let pose = Pose2::new(
                    nalgebra::Vector2::new(at - 1.0, 0.5 * at - 0.5),
                    std::f64::consts::FRAC_PI_4 * f64::from(i % 3),
                );
                let stats = fast.insert(&scan, &pose).unwrap();
                let mut cell_visits = 0;
                for ray in scan.rays(&pose, params.max_range) {
                    let end = ray
                        .hit
                        .then(|| g.world_to_cell(ray.to))
                        .flatten()
                        .map(|c| c.row * g.width() + c.col);
                    let (steps, metres_per_unit) = reference::steps(&g, ray.from, ray.to);
                    let min_units = units_for(min_length, metres_per_unit);
                    for (c, r, units) in steps {
                        let k = r * g.width() + c;
                        if units > 0 {
                            if units >= min_units {
                                visits[k] += 1;
                                cell_visits += 1;
                            }
                            touched[k] = true;
                            if end != Some(k) {
                                lo[k] = (lo[k] + l_miss).max(l_min);
                            }
                        }
                    }
                    if let Some(k) = end {
                        lo[k] = (lo[k] + l_hit).min(l_max);
                        touched[k] = true;
                        hits[k] += 1;
                    }
                }
                assert_eq!(stats.cell_visits, cell_visits);
            }
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(fast.log_odds().data()), bits(&lo), "{resolution}");
            assert_eq!(fast.hits().data(), &hits[..]);
            assert_eq!(fast.visits().data(), &visits[..]);
            assert_eq!(fast.touched, touched);
            assert!(visits.iter().filter(|&&v| v > 0).count() > 500);
            // The ROS values, cell by cell from the plain conversion (no reuse of the last
            // cell's value).
            let plain: Vec<i8> = lo
                .iter()
                .zip(&touched)
                .map(|(&l, &t)| {
                    let p = 1.0 - 1.0 / (1.0 + f64::from(l).exp());
                    if t {
                        (100.0 * p).round() as i8
                    } else {
                        UNKNOWN
                    }
                })
                .collect();
            let values = fast.occupancy_grid();
            assert_eq!(values.values().data(), &plain[..], "{resolution}");
            let distinct: std::collections::BTreeSet<i8> = plain.iter().copied().collect();
            assert!(distinct.len() >= 4, "{distinct:?}");
        }
    }

    #[test]
    fn parameters_are_checked() {
        let bad = [
            MapperParams {
                p_hit: 0.4,
                ..Default::default()
            },
            MapperParams {
                p_miss: 0.6,
                ..Default::default()
            },
            MapperParams {
                p_min: 0.0,
                ..Default::default()
            },
            MapperParams {
                p_max: 1.0,
                ..Default::default()
            },
            MapperParams {
                p_hit: f64::NAN,
                ..Default::default()
            },
            MapperParams {
                max_range: MaxRangeRule::Clear(f64::INFINITY),
                ..Default::default()
            },
        ];
        for p in bad {
            assert!(p.check().is_err(), "{p:?}");
        }
    }

    #[test]
    fn a_far_pose_or_a_tiny_resolution_is_refused_before_allocating() {
        let scan = LaserScan::new(0.0, -1.5, 0.01, 0.0, 30.0, vec![20.0; 301], vec![]).unwrap();
        let poses = [Pose2::identity(), Pose2::translation(1.0e5, 0.0)];
        let posed = || poses.iter().map(|p| (scan.clone(), *p));
        match OccupancyMapper::from_posed_scans(posed, 0.05, 1.0, MapperParams::default()) {
            Err(OccupancyError::GridTooLarge { width, to, .. }) => {
                assert!(width > 2.0e6, "{width}");
                assert!(to[0] > 1.0e5, "{to:?}");
            }
            other => panic!("expected GridTooLarge, got {:?}", other.map(|_| ())),
        }
        // A 22 m × 42 m area at 1 mm: 9·10⁸ cells, over the 2²⁸ default.
        let near = || poses[..1].iter().map(|p| (scan.clone(), *p));
        assert!(matches!(
            OccupancyMapper::from_posed_scans(near, 0.001, 1.0, MapperParams::default()),
            Err(OccupancyError::GridTooLarge { resolution, .. }) if resolution == 0.001
        ));
        let (mapper, _) =
            OccupancyMapper::from_posed_scans(near, 0.05, 1.0, MapperParams::default()).unwrap();
        assert!(mapper.geometry().len() < 1 << 20);
    }

    #[test]
    fn log_odds_are_clamped_and_a_nan_pose_changes_nothing() {
        let g = GridGeometry::new(0.1, nalgebra::Point2::new(-1.0, -1.0), 20, 20).unwrap();
        let mut m = OccupancyMapper::new(g, MapperParams::default()).unwrap();
        let scan = LaserScan::new(0.0, 0.0, 0.1, 0.0, 5.0, vec![0.55], vec![]).unwrap();
        for _ in 0..100 {
            m.insert(&scan, &Pose2::identity()).unwrap();
        }
        let end = g.world_to_cell(nalgebra::Point2::new(0.55, 0.0)).unwrap();
        assert_eq!(m.log_odds()[end], log_odds(0.97));
        assert_eq!(m.hits()[end], 100);
        let before = m.log_odds().clone();
        let nan = Pose2::new(nalgebra::Vector2::new(f64::NAN, 0.0), 0.0);
        assert!(m.insert(&scan, &nan).is_err());
        assert_eq!(m.log_odds(), &before);
    }
}
