//! An online local occupancy grid in the fixed (odometry or world) frame that tells static
//! objects from people: what `leg_tracker` does with its local map.
//!
//! Posts, table and chair legs look like legs to a geometric leg detector. What gives them
//! away is time: the robot sees them in the same cells of the fixed frame, scan after scan,
//! for as long as they are in view. [`StaticMap`] maps every scan with
//! [`haunts_occupancy::mapping::OccupancyMapper`] (the log-odds inverse sensor model and its
//! exact raycasting), and remembers for each occupied cell *since when* it has been
//! occupied. A point whose neighbourhood holds a cell occupied for at least
//! [`StaticMapParams::static_time`] seconds is on a static object.
//!
//! The beams that end on people already tracked are left out of the map (`leg_tracker`
//! maps "everything except tracked humans"), so a person who stops walking, or stands still
//! after being recognised, never becomes static; people recognised before
//! `static_time` has passed stay people.
//!
//! The map is kept in square tiles created around the sensor as it moves and dropped when
//! it is far away, so memory stays bounded on long runs while places seen a few seconds
//! ago are remembered.

use std::collections::HashMap;

use haunts_occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts_occupancy::{Grid, GridGeometry, LaserScan, Pose2, Reading};
use nalgebra::Point2;

use crate::detect::rule;
use crate::{Result, TrackingError};

/// Parameters of a [`StaticMap`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct StaticMapParams {
    /// Side of a cell, metres (about half a leg's width: legs and posts fill one to three
    /// cells).
    pub resolution: f64,
    /// The map covers at least this distance around the sensor, metres, and is kept up to
    /// twice as far; only hits this close start a cell's clock.
    pub range: f64,
    /// A cell occupied without interruption for at least this long, seconds, holds a static
    /// object.
    pub static_time: f64,
    /// A point is static when a static cell lies within this distance, metres (the leg
    /// detector puts a leg's centre about a radius behind its surface, and odometry drifts
    /// by a few centimetres over the seconds a static object is seen).
    pub query_radius: f64,
    /// Beams ending within this distance of a tracked person are not mapped, metres (about
    /// the space a person's legs take).
    pub person_clearance: f64,
    /// A cell whose occupancy probability exceeds this is occupied (ROS: 0.65).
    pub occupied: f64,
    /// The inverse sensor model.
    pub mapper: MapperParams,
}

impl Default for StaticMapParams {
    /// 5 cm cells mapped within 8 m; static after 1.5 s occupied (ten scans at 7.5 Hz;
    /// people who stand still are usually recognised by a leg pair within that time), within
    /// 10 cm; people's
    /// beams left out within 0.4 m; occupied above p = 0.65 with the default inverse sensor
    /// model (`p_hit` 0.7, `p_miss` 0.4).
    fn default() -> Self {
        Self {
            resolution: 0.05,
            range: 8.0,
            static_time: 1.5,
            query_radius: 0.1,
            person_clearance: 0.4,
            occupied: 0.65,
            mapper: MapperParams::default(),
        }
    }
}

impl StaticMapParams {
    /// Sets [`StaticMapParams::resolution`].
    pub fn with_resolution(mut self, v: f64) -> Self {
        self.resolution = v;
        self
    }
    /// Sets [`StaticMapParams::range`].
    pub fn with_range(mut self, v: f64) -> Self {
        self.range = v;
        self
    }
    /// Sets [`StaticMapParams::static_time`].
    pub fn with_static_time(mut self, v: f64) -> Self {
        self.static_time = v;
        self
    }
    /// Sets [`StaticMapParams::query_radius`].
    pub fn with_query_radius(mut self, v: f64) -> Self {
        self.query_radius = v;
        self
    }
    /// Sets [`StaticMapParams::person_clearance`].
    pub fn with_person_clearance(mut self, v: f64) -> Self {
        self.person_clearance = v;
        self
    }
    /// Sets [`StaticMapParams::occupied`].
    pub fn with_occupied(mut self, v: f64) -> Self {
        self.occupied = v;
        self
    }
    /// Sets [`StaticMapParams::mapper`].
    pub fn with_mapper(mut self, v: MapperParams) -> Self {
        self.mapper = v;
        self
    }

    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] naming the first parameter that breaks its rule:
    /// `resolution`, `range` and `static_time` finite and > 0; `query_radius` and
    /// `person_clearance` finite and ≥ 0; `occupied` in `(0, 1)`; and the inverse sensor
    /// model's rules ([`MapperParams::check`]).
    pub fn check(self) -> Result<Self> {
        for (name, v) in [
            ("resolution", self.resolution),
            ("range", self.range),
            ("static_time", self.static_time),
        ] {
            haunts_core::positive(name, v)?;
        }
        for (name, v) in [
            ("query_radius", self.query_radius),
            ("person_clearance", self.person_clearance),
        ] {
            rule(
                v.is_finite() && v >= 0.0,
                name,
                v,
                "must be finite and >= 0",
            )?;
        }
        rule(
            self.occupied > 0.0 && self.occupied < 1.0,
            "occupied",
            self.occupied,
            "must be in (0, 1)",
        )?;
        self.mapper.check().map_err(occupancy_error)?;
        // Tiles hold `TILE_CELLS²` cells; a tile must be a real area.
        rule(
            self.resolution * TILE_CELLS as f64 <= 1e6,
            "resolution",
            self.resolution,
            "must be <= 1e6 / 256 m",
        )?;
        Ok(self)
    }
}

fn occupancy_error(e: haunts_occupancy::OccupancyError) -> TrackingError {
    match e {
        haunts_occupancy::OccupancyError::InvalidParameter(haunts_core::InvalidParameter {
            name,
            value,
            rule,
        }) => TrackingError::InvalidParameter(haunts_core::InvalidParameter { name, value, rule }),
        source => TrackingError::Occupancy { source },
    }
}

/// Cells along a tile's side.
const TILE_CELLS: usize = 256;

/// One square of the map.
#[derive(Debug, Clone)]
struct Tile {
    mapper: OccupancyMapper,
    /// When each cell last became occupied (NaN: never, or free since).
    since: Grid<f64>,
}

/// The online local occupancy grid of static objects (see the [module docs](self)).
///
/// # Example
/// ```
/// use haunts_occupancy::{LaserScan, Pose2};
/// use haunts_tracking::detect::static_map::{StaticMap, StaticMapParams};
/// use nalgebra::Point2;
///
/// let mut map = StaticMap::new(StaticMapParams::default().with_static_time(1.0))?;
/// // A post 2 m ahead, seen at 10 Hz from a robot standing still.
/// let scan = |t: f64| LaserScan::new(t, -0.1, 0.01, 0.05, 20.0, vec![2.0; 21], vec![]);
/// for k in 0..8 {
///     map.insert(&scan(k as f64 * 0.1)?, &Pose2::identity(), &[])?;
/// }
/// assert!(!map.is_static(&Point2::new(2.05, 0.0)));
/// for k in 8..15 {
///     map.insert(&scan(k as f64 * 0.1)?, &Pose2::identity(), &[])?;
/// }
/// assert!(map.is_static(&Point2::new(2.05, 0.0)));
/// assert!(!map.is_static(&Point2::new(1.0, 0.0)));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct StaticMap {
    params: StaticMapParams,
    tiles: HashMap<(i64, i64), Tile>,
    /// Log-odds above which a cell is occupied.
    occupied: f32,
    /// The time of the latest scan.
    now: Option<f64>,
    /// Scratch: the hits of the current scan with their log-odds before it.
    hits: Vec<(Point2<f64>, f32)>,
}

impl StaticMap {
    /// An empty map.
    ///
    /// # Errors
    /// As [`StaticMapParams::check`].
    pub fn new(params: StaticMapParams) -> Result<Self> {
        let params = params.check()?;
        Ok(Self {
            params,
            tiles: HashMap::new(),
            occupied: (params.occupied / (1.0 - params.occupied)).ln() as f32,
            now: None,
            hits: Vec::new(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &StaticMapParams {
        &self.params
    }

    /// Number of tiles held (each `256 × 256` cells).
    #[cfg(test)]
    fn tiles(&self) -> usize {
        self.tiles.len()
    }

    fn tile_side(&self) -> f64 {
        self.params.resolution * TILE_CELLS as f64
    }

    fn key(&self, p: &Point2<f64>) -> (i64, i64) {
        let side = self.tile_side();
        ((p.x / side).floor() as i64, (p.y / side).floor() as i64)
    }

    /// Log-odds of the cell holding `p`, if mapped.
    fn log_odds(&self, p: &Point2<f64>) -> Option<f32> {
        let tile = self.tiles.get(&self.key(p))?;
        let cell = tile.mapper.geometry().world_to_cell(*p)?;
        tile.mapper.log_odds().get(cell).copied()
    }

    /// Maps one scan taken at `scan.stamp` by a sensor at `sensor_pose` (fixed frame),
    /// leaving out the beams that end within `person_clearance` of any of `people` (fixed
    /// frame).
    ///
    /// # Errors
    /// [`TrackingError::NonFiniteTime`] or [`TrackingError::TimeWentBackwards`] for the
    /// scan's stamp, [`TrackingError::Occupancy`] for a non-finite pose; the map is then
    /// unchanged.
    ///
    /// # Complexity
    /// O(beams × cells crossed per beam).
    pub fn insert(
        &mut self,
        scan: &LaserScan,
        sensor_pose: &Pose2,
        people: &[Point2<f64>],
    ) -> Result<()> {
        let time = scan.stamp;
        if !time.is_finite() {
            return Err(TrackingError::NonFiniteTime { time });
        }
        if let Some(previous) = self.now.filter(|&p| time < p) {
            return Err(TrackingError::TimeWentBackwards { previous, time });
        }
        if !haunts_occupancy::pose_is_finite(sensor_pose) {
            return Err(TrackingError::Occupancy {
                source: haunts_occupancy::OccupancyError::NonFinitePose {
                    what: format!("scan at t = {time}"),
                },
            });
        }
        self.now = Some(time);
        let p = self.params;
        let origin = sensor_pose * Point2::origin();
        // The scan as mapped, without the beams that end on tracked people; only hits within
        // `range` may start a cell's clock.
        let clearance2 = p.person_clearance * p.person_clearance;
        let mut mapped = scan.clone();
        self.hits.clear();
        for (range, beam) in mapped.ranges.iter_mut().zip(scan.beams()) {
            let Reading::Hit(r) = beam.reading else {
                continue;
            };
            let end = sensor_pose * Point2::new(r * beam.angle.cos(), r * beam.angle.sin());
            let on_person = people
                .iter()
                .any(|q| (q - end).norm_squared() <= clearance2);
            if on_person {
                *range = f64::NAN;
            } else if r <= p.range {
                self.hits.push((end, 0.0));
            }
        }
        // Tiles within `range` of the sensor exist; those beyond twice that are dropped.
        let side = self.tile_side();
        let (lo, hi) = (
            self.key(&(origin - nalgebra::Vector2::new(p.range, p.range))),
            self.key(&(origin + nalgebra::Vector2::new(p.range, p.range))),
        );
        let keep = 2.0 * p.range + side;
        self.tiles.retain(|&(i, j), _| {
            let centre = Point2::new((i as f64 + 0.5) * side, (j as f64 + 0.5) * side);
            (centre - origin).norm() <= keep
        });
        for i in lo.0..=hi.0 {
            for j in lo.1..=hi.1 {
                if self.tiles.contains_key(&(i, j)) {
                    continue;
                }
                let geometry = GridGeometry::new(
                    p.resolution,
                    Point2::new(i as f64 * side, j as f64 * side),
                    TILE_CELLS,
                    TILE_CELLS,
                )
                .map_err(occupancy_error)?;
                let tile = Tile {
                    mapper: OccupancyMapper::new(geometry, p.mapper).map_err(occupancy_error)?,
                    since: Grid::filled(geometry, f64::NAN),
                };
                self.tiles.insert((i, j), tile);
            }
        }
        for k in 0..self.hits.len() {
            let before = self.log_odds(&self.hits[k].0).unwrap_or(0.0);
            self.hits[k].1 = before;
        }
        // Only the tiles the scan can reach see it (rays are clipped to each tile).
        let reach = scan.range_max.min(1e6);
        for (&(i, j), tile) in self.tiles.iter_mut() {
            let (x0, y0) = (i as f64 * side, j as f64 * side);
            let dx = (origin.x - (x0 + side).min(origin.x.max(x0))).abs();
            let dy = (origin.y - (y0 + side).min(origin.y.max(y0))).abs();
            if dx.hypot(dy) <= reach {
                tile.mapper
                    .insert(&mapped, sensor_pose)
                    .map_err(occupancy_error)?;
            }
        }
        // Cells that became occupied with this scan start their clock now; cells that are
        // no longer occupied lose it when they are next hit (see `static_age`).
        let threshold = self.occupied;
        for &(end, before) in &self.hits {
            let key = self.key(&end);
            let Some(tile) = self.tiles.get_mut(&key) else {
                continue;
            };
            let Some(cell) = tile.mapper.geometry().world_to_cell(end) else {
                continue;
            };
            let after = tile.mapper.log_odds()[cell];
            if after > threshold && (before <= threshold || tile.since[cell].is_nan()) {
                tile.since[cell] = time;
            }
        }
        Ok(())
    }

    /// How long the longest-occupied cell within `query_radius` of `p` has been occupied,
    /// seconds (0 when none is occupied).
    fn static_age(&self, p: &Point2<f64>) -> f64 {
        let Some(now) = self.now else {
            return 0.0;
        };
        let r = self.params.query_radius;
        let res = self.params.resolution;
        let steps = (r / res).ceil() as i64;
        let mut age: f64 = 0.0;
        for di in -steps..=steps {
            for dj in -steps..=steps {
                let q = Point2::new(p.x + di as f64 * res, p.y + dj as f64 * res);
                if (q - p).norm() > r + 0.5 * res {
                    continue;
                }
                let Some(tile) = self.tiles.get(&self.key(&q)) else {
                    continue;
                };
                let Some(cell) = tile.mapper.geometry().world_to_cell(q) else {
                    continue;
                };
                let since = tile.since[cell];
                if tile.mapper.log_odds()[cell] > self.occupied && since.is_finite() {
                    age = age.max(now - since);
                }
            }
        }
        age
    }

    /// Whether `p` (fixed frame) is on a static object: the longest-occupied cell within
    /// `query_radius` of `p` has been occupied for at least `static_time` seconds.
    pub fn is_static(&self, p: &Point2<f64>) -> bool {
        self.static_age(p) >= self.params.static_time
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    fn wall_scan(t: f64, range: f64) -> LaserScan {
        LaserScan::new(t, -0.2, 0.01, 0.05, 20.0, vec![range; 41], vec![]).unwrap()
    }

    #[test]
    fn every_bad_parameter_is_named() {
        let d = StaticMapParams::default();
        for (params, name) in [
            (d.with_resolution(0.0), "resolution"),
            (d.with_range(f64::NAN), "range"),
            (d.with_static_time(-1.0), "static_time"),
            (d.with_query_radius(-0.1), "query_radius"),
            (d.with_person_clearance(f64::INFINITY), "person_clearance"),
            (d.with_occupied(1.0), "occupied"),
            (
                d.with_mapper({
                    let mut p = MapperParams::default();
                    p.p_hit = 0.3;
                    p
                }),
                "p_hit",
            ),
        ] {
            assert!(
                matches!(
                    StaticMap::new(params),
                    Err(TrackingError::InvalidParameter(haunts_core::InvalidParameter { name: n, .. })) if n == name
                ),
                "{name}"
            );
        }
    }

    #[test]
    fn a_tracked_person_never_becomes_static() {
        let mut map = StaticMap::new(StaticMapParams::default().with_static_time(0.5)).unwrap();
        let person = [Point2::new(2.0, 0.0)];
        for k in 0..20 {
            map.insert(&wall_scan(k as f64 * 0.1, 2.0), &Pose2::identity(), &person)
                .unwrap();
        }
        assert!(!map.is_static(&Point2::new(2.0, 0.0)));
        assert_eq!(map.static_age(&Point2::new(2.0, 0.0)), 0.0);
        // The same object, untracked, is static after half a second.
        for k in 20..27 {
            map.insert(&wall_scan(k as f64 * 0.1, 2.0), &Pose2::identity(), &[])
                .unwrap();
        }
        assert!(map.is_static(&Point2::new(2.0, 0.0)));
    }

    #[test]
    fn an_object_that_leaves_restarts_its_clock() {
        let mut map = StaticMap::new(StaticMapParams::default().with_static_time(0.5)).unwrap();
        let pose = Pose2::identity();
        for k in 0..10 {
            map.insert(&wall_scan(k as f64 * 0.1, 2.0), &pose, &[])
                .unwrap();
        }
        assert!(map.is_static(&Point2::new(2.0, 0.0)));
        // Gone: the beams now reach 4 m and clear the cells where it stood.
        for k in 10..20 {
            map.insert(&wall_scan(k as f64 * 0.1, 4.0), &pose, &[])
                .unwrap();
        }
        assert!(!map.is_static(&Point2::new(2.0, 0.0)));
        // Back: young again.
        map.insert(&wall_scan(2.0, 2.0), &pose, &[]).unwrap();
        map.insert(&wall_scan(2.1, 2.0), &pose, &[]).unwrap();
        assert!(!map.is_static(&Point2::new(2.0, 0.0)));
    }

    #[test]
    fn tiles_far_behind_the_sensor_are_dropped_and_bad_input_changes_nothing() {
        let mut map = StaticMap::new(StaticMapParams::default().with_range(3.0)).unwrap();
        map.insert(&wall_scan(0.0, 2.0), &Pose2::identity(), &[])
            .unwrap();
        let near = map.tiles();
        assert!(near > 0);
        let far = Pose2::new(nalgebra::Vector2::new(100.0, 0.0), 0.0);
        map.insert(&wall_scan(0.1, 2.0), &far, &[]).unwrap();
        assert_eq!(map.tiles(), near);
        assert!(matches!(
            map.insert(&wall_scan(0.05, 2.0), &far, &[]),
            Err(TrackingError::TimeWentBackwards { .. })
        ));
        let nan = Pose2::new(nalgebra::Vector2::new(f64::NAN, 0.0), 0.0);
        assert!(matches!(
            map.insert(&wall_scan(0.2, 2.0), &nan, &[]),
            Err(TrackingError::Occupancy { .. })
        ));
    }
}
