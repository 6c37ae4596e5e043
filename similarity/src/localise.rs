//! A keyframe localiser: odometry (or a constant-velocity guess) between keyframes, each
//! keyframe scan matched by [`icp`] against the map built so far from the earlier keyframes
//! (those that saw new ground: a keyframe revisiting a mapped one is matched, not drawn).
//!
//! This is the scan matching of seed 000's daily loop (the robot starts each day at its
//! dock, whose pose is the reference frame; every later pose is corrected against that
//! day's growing map), made an owned, streaming object: a robot node feeds it one scan at a
//! time and keeps it for the day.

use haunts_occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts_occupancy::{Grid, GridGeometry, LaserScan, OccupancyGrid, Pose2, pose_is_finite};
use nalgebra::Point2;
use std::collections::HashMap;

use crate::error::rule;
use crate::{IcpParams, IcpTarget, Result, icp};

/// A laser's range counted for the ICP target's window at most, metres (a scan reporting an
/// absurd `range_max` still gets a bounded window).
const MAX_REACH: f64 = 60.0;

/// Parameters of a [`Localiser`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct LocaliserParams {
    /// Cell size of the map scans are matched against, metres (default 0.05).
    pub resolution: f64,
    /// A new keyframe once the robot has moved this far since the last, metres (default
    /// 0.75).
    pub keyframe_distance: f64,
    /// … or turned this much, radians (default 0.4).
    pub keyframe_angle: f64,
    /// The ICP target is rebuilt from the growing map every this many keyframes added to it
    /// (default 10).
    pub refresh_every: usize,
    /// A keyframe within this distance, metres, of a keyframe already in the map, and within
    /// `keyframe_angle` of its heading, is matched but not added to the map (default 0.75,
    /// the keyframe spacing; 0 adds every keyframe). A robot patrolling one route is matched
    /// against the map of its first pass instead of a map that grows, and costs more to
    /// rebuild, with every lap: on the simulated office this halves a day's localisation
    /// time at no loss of accuracy (BENCHMARKS.md, issue 19). Nothing a scan sees is lost
    /// for long: a keyframe turned or moved away from every mapped one is added. Saved
    /// parameters without it read as 0, as they behaved.
    #[cfg_attr(feature = "serde", serde(default))]
    pub revisit_distance: f64,
    /// ICP itself (default: the crate's, correspondences within 0.3 m).
    pub icp: IcpParams,
    /// A match is kept only if at least this fraction of the scan's points lies near the map
    /// (default 0.6); otherwise the scan keeps its predicted pose.
    pub min_fitness: f64,
    /// … and if it moves the prediction by at most this much, metres (default 0.3).
    pub max_correction: f64,
    /// Whether keyframes are matched at all (default `true`). With `false` every pose is its
    /// prediction — the odometry, or the first scan's frame without odometry — and
    /// keyframes are still chosen by the spacing rules: a day tracked in the odometry frame,
    /// as `leg_tracker` tracks, or a recording whose poses are already corrected.
    pub matching: bool,
}

impl Default for LocaliserParams {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            keyframe_distance: 0.75,
            keyframe_angle: 0.4,
            refresh_every: 10,
            revisit_distance: 0.75,
            icp: IcpParams::default().with_max_correspondence_distance(0.3),
            min_fitness: 0.6,
            max_correction: 0.3,
            matching: true,
        }
    }
}

impl LocaliserParams {
    /// Sets the matching map's cell size, metres.
    pub fn with_resolution(mut self, metres: f64) -> Self {
        self.resolution = metres;
        self
    }

    /// Sets how far (metres) or how much (radians) the robot moves between keyframes.
    pub fn with_keyframe_spacing(mut self, distance: f64, angle: f64) -> Self {
        self.keyframe_distance = distance;
        self.keyframe_angle = angle;
        self
    }

    /// Sets how near, metres, a keyframe to one in the map is not added to it
    /// ([`LocaliserParams::revisit_distance`]; 0 adds every keyframe).
    pub fn with_revisit_distance(mut self, metres: f64) -> Self {
        self.revisit_distance = metres;
        self
    }

    /// Sets how often (in keyframes added to the map) the ICP target is rebuilt.
    pub fn with_refresh_every(mut self, keyframes: usize) -> Self {
        self.refresh_every = keyframes;
        self
    }

    /// Sets ICP's parameters.
    pub fn with_icp(mut self, icp: IcpParams) -> Self {
        self.icp = icp;
        self
    }

    /// Sets the acceptance rules of a match: the fraction of points near the map, and the
    /// largest correction, metres.
    pub fn with_acceptance(mut self, min_fitness: f64, max_correction: f64) -> Self {
        self.min_fitness = min_fitness;
        self.max_correction = max_correction;
        self
    }

    /// Sets whether keyframes are matched ([`LocaliserParams::matching`]).
    pub fn with_matching(mut self, matching: bool) -> Self {
        self.matching = matching;
        self
    }

    /// Whether a motion `step` is far enough for a new keyframe (either spacing rule).
    fn spaced(&self, step: &Pose2) -> bool {
        step.translation.vector.norm() >= self.keyframe_distance
            || step.rotation.angle().abs() >= self.keyframe_angle
    }

    /// The parameters after checking every rule.
    ///
    /// # Errors
    /// [`crate::SimilarityError::InvalidParameter`] naming the parameter; ICP's own errors.
    pub fn check(self) -> Result<Self> {
        for (name, v) in [
            ("localiser.resolution", self.resolution),
            ("localiser.keyframe_distance", self.keyframe_distance),
            ("localiser.keyframe_angle", self.keyframe_angle),
            ("localiser.max_correction", self.max_correction),
        ] {
            rule(name, v, v.is_finite() && v > 0.0, "must be finite and > 0")?;
        }
        rule(
            "localiser.revisit_distance",
            self.revisit_distance,
            self.revisit_distance.is_finite() && self.revisit_distance >= 0.0,
            "must be finite and >= 0",
        )?;
        rule(
            "localiser.refresh_every",
            self.refresh_every as f64,
            self.refresh_every >= 1,
            "must be >= 1",
        )?;
        rule(
            "localiser.min_fitness",
            self.min_fitness,
            (0.0..=1.0).contains(&self.min_fitness),
            "must be in [0, 1]",
        )?;
        self.icp.check()?;
        Ok(self)
    }
}

/// The localiser's answer for one scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Localised {
    /// The scan's corrected sensor pose, in the frame of the first scan's pose.
    pub pose: Pose2,
    /// Whether the scan became a keyframe (matched, and added to the map unless it revisits
    /// a mapped one: [`LocaliserParams::revisit_distance`]).
    pub keyframe: bool,
    /// Whether the keyframe's match was refused (it kept its predicted pose).
    pub refused: bool,
}

/// Keyframe scan matching against the map the localiser builds as it goes.
///
/// Each scan's pose is predicted from the last keyframe: by the odometry step since that
/// keyframe ([`Localiser::update`]), or, for a recording without odometry, by the motion of
/// the last two poses continued ([`Localiser::update_without_odometry`], a constant-velocity
/// model: between two scans of a 10 Hz laser a robot's motion barely changes). Once the
/// prediction has moved [`LocaliserParams::keyframe_distance`] or turned
/// [`LocaliserParams::keyframe_angle`] from the last keyframe (without odometry: every scan
/// is matched, since the prediction alone cannot tell), the scan is matched by ICP against
/// the map of the earlier keyframes. The match is refused — the scan keeps its prediction,
/// and the refusal is counted — when ICP fails, fits less than
/// [`LocaliserParams::min_fitness`] of the scan, or moves the prediction by more than
/// [`LocaliserParams::max_correction`]. Without odometry a refused scan is matched against
/// the scan before it under the same rules, and keeps the prediction only if that fails too.
/// A keyframe is then drawn into the map unless it revisits a keyframe already there
/// ([`LocaliserParams::revisit_distance`]): a patrolling robot's later laps are matched
/// against the map of its first, and cost no raycasting or target rebuilds.
///
/// # Example
/// ```
/// use haunts_occupancy::{GridGeometry, LaserScan, Pose2};
/// use haunts_similarity::{Localiser, LocaliserParams};
/// use nalgebra::{Point2, Vector2};
///
/// // A robot in a 6 m × 4 m room, laser at its origin, 360 beams.
/// let room = |pose: &Pose2, stamp: f64| {
///     let n = 360;
///     let inc = std::f64::consts::TAU / n as f64;
///     let ranges = (0..n)
///         .map(|i| {
///             let a = pose.rotation.angle() - std::f64::consts::PI + i as f64 * inc;
///             let (o, d) = (pose.translation.vector, Vector2::new(a.cos(), a.sin()));
///             // Distance to the walls x = ±3, y = ±2.
///             [(3.0 - o.x) / d.x, (-3.0 - o.x) / d.x, (2.0 - o.y) / d.y, (-2.0 - o.y) / d.y]
///                 .into_iter()
///                 .filter(|t| *t > 0.0)
///                 .fold(f64::INFINITY, f64::min)
///         })
///         .collect();
///     LaserScan::new(stamp, -std::f64::consts::PI, inc, 0.05, 10.0, ranges, vec![])
/// };
/// let geometry = GridGeometry::new(0.05, Point2::new(-4.0, -3.0), 160, 120)?;
/// let mut localiser = Localiser::new(geometry, LocaliserParams::default())?;
/// for k in 0..20 {
///     let truth = Pose2::new(Vector2::new(-1.5 + 0.15 * k as f64, 0.0), 0.0);
///     // Odometry that overestimates the distance travelled by 10 % (0.29 m at the end).
///     let odom = Pose2::new(Vector2::new(-1.5 + 0.165 * k as f64, 0.0), 0.0);
///     let scan = room(&truth, k as f64 * 0.1)?;
///     let out = localiser.update(&scan, &odom)?;
///     // Keyframes are matched; scans between them follow odometry from the last keyframe.
///     if out.keyframe {
///         let error = (out.pose.translation.vector - truth.translation.vector).norm();
///         assert!(error < 0.05, "corrected error {error} at scan {k}");
///     }
/// }
/// assert!(localiser.keyframes() >= 4);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct Localiser {
    params: LocaliserParams,
    mapper: OccupancyMapper,
    target: Option<IcpTarget>,
    /// Keyframes in the map when the target was built, where the robot was, and the
    /// window of the map's cells it covers (first and last column and row).
    target_keyframes: usize,
    target_centre: Point2<f64>,
    target_window: [usize; 4],
    /// The last keyframe: its odometry pose (if any) and its corrected pose.
    last_keyframe: Option<(Pose2, Pose2)>,
    /// The last two corrected poses (for the constant-velocity prediction).
    recent: [Option<Pose2>; 2],
    /// The scan before, for a recording without odometry.
    previous: PreviousScan,
    /// The poses of the keyframes added to the map, and how many.
    mapped: MappedPoses,
    keyframes: usize,
    refused: usize,
    points: Vec<Point2<f64>>,
}

impl Localiser {
    /// A localiser whose matching map covers `geometry` at the params' resolution (poses
    /// outside it are still corrected; scans there add nothing to the map).
    ///
    /// # Errors
    /// Bad parameters; [`haunts_occupancy::OccupancyError`] when the geometry cannot be
    /// resampled to the params' resolution.
    pub fn new(geometry: GridGeometry, params: LocaliserParams) -> Result<Self> {
        let params = params.check()?;
        let fine = geometry.with_resolution(params.resolution)?;
        Ok(Self {
            params,
            mapper: OccupancyMapper::new(fine, MapperParams::default())?,
            target: None,
            target_keyframes: 0,
            target_centre: Point2::origin(),
            target_window: [0; 4],
            last_keyframe: None,
            recent: [None, None],
            previous: PreviousScan::default(),
            mapped: MappedPoses::new(params.revisit_distance, params.keyframe_angle),
            keyframes: 0,
            refused: 0,
            points: Vec::new(),
        })
    }

    /// Corrects the pose of `scan` given the sensor's odometry pose `odom` at its stamp.
    /// The first scan keeps its odometry pose: the frame of the corrected poses is that of
    /// the odometry at the first scan.
    ///
    /// # Errors
    /// A non-finite `odom` ([`haunts_occupancy::OccupancyError`] from the mapper); the
    /// mapper's errors for a malformed scan.
    pub fn update(&mut self, scan: &LaserScan, odom: &Pose2) -> Result<Localised> {
        if !pose_is_finite(odom) {
            return Err(haunts_occupancy::OccupancyError::NonFinitePose {
                what: format!("odometry at scan stamp {}", scan.stamp),
            }
            .into());
        }
        let Some((odom_kf, pose_kf)) = self.last_keyframe else {
            return self.first(scan, *odom, *odom);
        };
        let step = odom_kf.inverse() * odom;
        // Without matching the pose is the odometry itself (not recomposed, so bit for bit).
        let predicted = if self.params.matching {
            pose_kf * step
        } else {
            *odom
        };
        let moved = self.params.spaced(&step);
        if !moved {
            return Ok(self.plain(predicted));
        }
        let (pose, refused) = self.match_scan(scan, &predicted);
        self.keyframe(scan, *odom, pose, refused)
    }

    /// Corrects the pose of `scan` for a recording without odometry: predicted by the
    /// constant-velocity model, matched against the map at every scan, a keyframe once it
    /// has moved far enough from the last one. The first scan's pose is the identity.
    ///
    /// A scan whose map match is refused (a robot entering ground its map does not hold
    /// yet) is matched against the scan before it instead, from the same prediction and
    /// under the same acceptance rules, and keeps the prediction only if that fails too: the
    /// laser's own odometry stands in for the wheels'. Without it, a run of refusals would
    /// leave the poses to the constant-velocity guess, which drifts (BENCHMARKS.md: on the
    /// moving `leg_tracker` bag without its odometry, 94 of 117 keyframe matches refused).
    ///
    /// # Errors
    /// The mapper's errors for a malformed scan.
    pub fn update_without_odometry(&mut self, scan: &LaserScan) -> Result<Localised> {
        let Some((_, pose_kf)) = self.last_keyframe else {
            let out = self.first(scan, Pose2::identity(), Pose2::identity());
            self.previous.remember(scan, Pose2::identity());
            return out;
        };
        if !self.params.matching {
            return Ok(self.plain(pose_kf));
        }
        let predicted = match self.recent {
            [Some(before), Some(last)] => renormalised(last * (before.inverse() * last)),
            [_, Some(last)] => last,
            _ => pose_kf,
        };
        let (mut pose, refused) = self.match_scan(scan, &predicted);
        if refused {
            // `match_scan` left the scan's endpoints in `self.points`.
            if let Some(p) = self
                .previous
                .matched(&self.points, &predicted, &self.params)
            {
                pose = p;
            }
        }
        self.previous.remember(scan, pose);
        let step = pose_kf.inverse() * pose;
        let moved = self.params.spaced(&step);
        if moved {
            self.keyframe(scan, pose, pose, refused)
        } else {
            Ok(self.plain(pose))
        }
    }

    /// Keyframes so far.
    pub fn keyframes(&self) -> usize {
        self.keyframes
    }

    /// Keyframe matches refused so far.
    pub fn refused(&self) -> usize {
        self.refused
    }

    /// The matching map built so far (at [`LocaliserParams::resolution`]).
    pub fn map(&self) -> OccupancyGrid {
        self.mapper.occupancy_grid()
    }

    /// The parameters.
    pub fn params(&self) -> &LocaliserParams {
        &self.params
    }

    fn first(&mut self, scan: &LaserScan, odom: Pose2, pose: Pose2) -> Result<Localised> {
        self.keyframe(scan, odom, pose, false)
    }

    fn plain(&mut self, pose: Pose2) -> Localised {
        self.recent = [self.recent[1], Some(pose)];
        Localised {
            pose,
            keyframe: false,
            refused: false,
        }
    }

    fn keyframe(
        &mut self,
        scan: &LaserScan,
        odom: Pose2,
        pose: Pose2,
        refused: bool,
    ) -> Result<Localised> {
        if !self.mapped.covers(&pose) {
            self.mapper.insert(scan, &pose)?;
            self.mapped.add(pose);
        }
        self.keyframes += 1;
        self.refused += usize::from(refused);
        self.last_keyframe = Some((odom, pose));
        self.recent = [self.recent[1], Some(pose)];
        Ok(Localised {
            pose,
            keyframe: true,
            refused,
        })
    }

    /// ICP of `scan` from `predicted` against the map of the earlier keyframes: the accepted
    /// pose, or the prediction and `true` (refused). The target is rebuilt every
    /// [`LocaliserParams::refresh_every`] keyframes, when the robot has left the middle of
    /// its window, and once more before a refusal when it is older than the last keyframe: a
    /// robot entering ground its stale target does not hold (a new room) is matched against
    /// the map as it is now, while a robot patrolling known ground pays for few rebuilds.
    ///
    /// The target covers only a window around the robot: the laser's range plus the ground
    /// the robot covers between two rebuilds (`refresh_every · keyframe_distance`) on every
    /// side. A scan sees nothing beyond its range, so the match is the same as against the
    /// whole map, and the distance transform of a building-sized map is not recomputed.
    fn match_scan(&mut self, scan: &LaserScan, predicted: &Pose2) -> (Pose2, bool) {
        if !self.params.matching {
            return (*predicted, false);
        }
        let travel = self.params.keyframe_distance * self.params.refresh_every as f64;
        let reach = scan.range_max.min(MAX_REACH) + travel;
        let here: Point2<f64> = predicted.translation.vector.into();
        let due = self.mapped.len() >= self.target_keyframes + self.params.refresh_every
            || (here - self.target_centre).norm() > travel;
        if self.target.is_none() || due {
            self.rebuild_target(here, reach);
        }
        self.points.clear();
        self.points.extend(scan.endpoints());
        if let Some(pose) = self.try_match(predicted) {
            return (pose, false);
        }
        if self.target_keyframes != self.mapped.len() {
            self.rebuild_target(here, reach);
            if let Some(pose) = self.try_match(predicted) {
                return (pose, false);
            }
        }
        (*predicted, true)
    }

    /// The target over the map's cells within `reach` of `centre` (all of them in a map
    /// smaller than the window).
    fn rebuild_target(&mut self, centre: Point2<f64>, reach: f64) {
        let g = *self.mapper.geometry();
        let r = g.resolution();
        let (o, w, h) = (g.origin(), g.width() as f64, g.height() as f64);
        // The window's first and last columns and rows, clamped to the map.
        let span = |lo: f64, origin: f64, n: f64| {
            let a = ((lo - reach - origin) / r).floor().clamp(0.0, n);
            let b = ((lo + reach - origin) / r).ceil().clamp(0.0, n);
            (a as usize, b as usize)
        };
        let (c0, c1) = span(centre.x, o.x, w);
        let (r0, r1) = span(centre.y, o.y, h);
        // The same cells of an unchanged map give the same target: a robot that moved
        // within a map its window covers whole (an office) keeps it.
        if self.target.is_some()
            && self.target_keyframes == self.mapped.len()
            && self.target_window == [c0, c1, r0, r1]
        {
            self.target_centre = centre;
            return;
        }
        let map = self.mapper.occupancy_grid();
        let window = (c1 > c0 && r1 > r0)
            .then(|| {
                let origin = Point2::new(o.x + c0 as f64 * r, o.y + r0 as f64 * r);
                GridGeometry::new(r, origin, c1 - c0, r1 - r0).ok()
            })
            .flatten();
        self.target = window.and_then(|wg| {
            let occupied = map.occupied_mask();
            // A map within the window (the usual case indoors) is the mask as it is.
            let mask = if wg == g {
                occupied
            } else {
                Grid::from_fn(wg, |c| {
                    occupied.data()[(c.row + r0) * g.width() + c.col + c0]
                })
            };
            IcpTarget::from_mask(&mask).ok()
        });
        self.target_keyframes = self.mapped.len();
        self.target_centre = centre;
        self.target_window = [c0, c1, r0, r1];
    }

    /// ICP of the scan's points from `predicted`, if the match passes the acceptance rules.
    fn try_match(&self, predicted: &Pose2) -> Option<Pose2> {
        let p = &self.params;
        self.target
            .as_ref()
            .and_then(|t| icp(t, &self.points, predicted, &p.icp).ok())
            .filter(|r| {
                r.fitness >= p.min_fitness
                    && (r.pose.translation.vector - predicted.translation.vector).norm()
                        <= p.max_correction
                    && pose_is_finite(&r.pose)
            })
            .map(|r| renormalised(r.pose))
    }
}

/// `pose` with its rotation made unit again: composing poses step after step (the
/// constant-velocity prediction) lets rounding grow the rotation's norm without bound.
fn renormalised(pose: Pose2) -> Pose2 {
    Pose2::new(pose.translation.vector, pose.rotation.angle())
}

/// The poses of the keyframes in the map, hashed by square cells of the revisit distance's
/// side, so that whether a pose revisits one looks at the 3 × 3 cells around it.
#[derive(Debug)]
struct MappedPoses {
    distance: f64,
    angle: f64,
    cells: HashMap<(i64, i64), Vec<Pose2>>,
    len: usize,
}

impl MappedPoses {
    fn new(distance: f64, angle: f64) -> Self {
        Self {
            distance,
            angle,
            cells: HashMap::new(),
            len: 0,
        }
    }

    /// The cell of `pose`, when poses are kept (a positive distance; `as` saturates far
    /// away).
    fn cell(&self, pose: &Pose2) -> Option<(i64, i64)> {
        let t = pose.translation.vector / self.distance;
        (self.distance > 0.0).then(|| (t.x.floor() as i64, t.y.floor() as i64))
    }

    /// Whether a mapped keyframe lies within the distance of `pose` and the angle of its
    /// heading.
    fn covers(&self, pose: &Pose2) -> bool {
        let Some((i, j)) = self.cell(pose) else {
            return false;
        };
        let near = |q: &Pose2| {
            (q.translation.vector - pose.translation.vector).norm() < self.distance
                && (q.rotation.inverse() * pose.rotation).angle().abs() < self.angle
        };
        (i.saturating_sub(1)..=i.saturating_add(1)).any(|a| {
            (j.saturating_sub(1)..=j.saturating_add(1))
                .any(|b| self.cells.get(&(a, b)).is_some_and(|v| v.iter().any(near)))
        })
    }

    fn add(&mut self, pose: Pose2) {
        if let Some(cell) = self.cell(&pose) {
            self.cells.entry(cell).or_default().push(pose);
        }
        self.len += 1;
    }

    /// Keyframes added to the map.
    fn len(&self) -> usize {
        self.len
    }
}

/// The scan before the current one and its pose: the fallback of
/// [`Localiser::update_without_odometry`] when the map match is refused.
#[derive(Debug, Default)]
struct PreviousScan {
    /// Its endpoints in its own sensor frame, and its pose (`None` before the first scan).
    points: Vec<Point2<f64>>,
    pose: Option<Pose2>,
}

impl PreviousScan {
    /// Keeps `scan`'s endpoints within [`MAX_REACH`] of the sensor (a scan reporting absurd
    /// ranges still gets a bounded target) and its pose.
    fn remember(&mut self, scan: &LaserScan, pose: Pose2) {
        self.points.clear();
        self.points
            .extend(scan.endpoints().filter(|p| p.coords.norm() <= MAX_REACH));
        self.pose = Some(pose);
    }

    /// The pose of the scan whose endpoints are `points` by ICP against this scan's, from
    /// `predicted`, if the match passes the localiser's acceptance rules. The target is this
    /// scan's endpoints rasterised over their bounding box (grown by the correspondence
    /// distance) at the localiser's resolution: built only when it is needed.
    fn matched(
        &self,
        points: &[Point2<f64>],
        predicted: &Pose2,
        params: &LocaliserParams,
    ) -> Option<Pose2> {
        let at = self.pose?;
        let reach = params.icp.max_correspondence_distance;
        let (lo, hi) = self.points.iter().fold(
            (
                Point2::new(f64::INFINITY, f64::INFINITY),
                Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
            ),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        );
        if !(lo.x <= hi.x && lo.y <= hi.y) {
            return None;
        }
        let r = params.resolution;
        let cells = |extent: f64| ((extent + 2.0 * reach) / r).ceil() as usize + 1;
        let origin = Point2::new(lo.x - reach, lo.y - reach);
        let g = GridGeometry::new(r, origin, cells(hi.x - lo.x), cells(hi.y - lo.y)).ok()?;
        let mut mask = Grid::filled(g, false);
        for p in &self.points {
            if let Some(c) = g.world_to_cell(*p) {
                mask[c] = true;
            }
        }
        let target = IcpTarget::from_mask(&mask).ok()?;
        let relative = at.inverse() * predicted;
        icp(&target, points, &relative, &params.icp)
            .ok()
            .filter(|m| {
                m.fitness >= params.min_fitness
                    && (m.pose.translation.vector - relative.translation.vector).norm()
                        <= params.max_correction
                    && pose_is_finite(&m.pose)
            })
            .map(|m| renormalised(at * m.pose))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use nalgebra::Vector2;

    use super::*;

    /// A scan of a 6 m × 4 m room with a pillar, from `pose`.
    fn room(pose: &Pose2, stamp: f64) -> LaserScan {
        let n = 360;
        let inc = std::f64::consts::TAU / n as f64;
        let o = pose.translation.vector;
        let ranges = (0..n)
            .map(|i| {
                let a = pose.rotation.angle() - std::f64::consts::PI + i as f64 * inc;
                let d = Vector2::new(a.cos(), a.sin());
                let walls = [
                    (3.0 - o.x) / d.x,
                    (-3.0 - o.x) / d.x,
                    (2.0 - o.y) / d.y,
                    (-2.0 - o.y) / d.y,
                ];
                // A pillar of radius 0.3 at (1, 1) breaks the room's symmetry.
                let c = Vector2::new(1.0, 1.0) - o;
                let b = c.dot(&d);
                let disc = b * b - (c.norm_squared() - 0.09);
                let pillar = if disc >= 0.0 { b - disc.sqrt() } else { -1.0 };
                walls
                    .into_iter()
                    .chain([pillar])
                    .filter(|t| *t > 0.0)
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        LaserScan::new(
            stamp,
            -std::f64::consts::PI,
            inc,
            0.05,
            10.0,
            ranges,
            vec![],
        )
        .unwrap()
    }

    fn geometry() -> GridGeometry {
        GridGeometry::new(0.05, Point2::new(-4.0, -3.0), 160, 120).unwrap()
    }

    fn truth(k: usize) -> Pose2 {
        Pose2::new(
            Vector2::new(-1.5 + 0.1 * k as f64, -0.5 + 0.03 * k as f64),
            0.02 * k as f64,
        )
    }

    #[test]
    fn odometry_drift_is_corrected_against_the_growing_map() {
        let mut localiser = Localiser::new(geometry(), LocaliserParams::default()).unwrap();
        let (mut odom_err, mut corrected_err) = (0.0f64, 0.0f64);
        for k in 0..30 {
            let t = truth(k);
            // Odometry that overestimates translation by 8 % and drifts in heading.
            let odom = Pose2::new(
                (t.translation.vector - truth(0).translation.vector) * 1.08
                    + truth(0).translation.vector,
                t.rotation.angle() + 0.002 * k as f64,
            );
            let out = localiser.update(&room(&t, k as f64 * 0.1), &odom).unwrap();
            odom_err = odom_err.max((odom.translation.vector - t.translation.vector).norm());
            // Between keyframes the pose follows odometry from the last keyframe.
            if out.keyframe {
                corrected_err =
                    corrected_err.max((out.pose.translation.vector - t.translation.vector).norm());
            }
        }
        assert!(odom_err > 0.2, "odometry drifted only {odom_err}");
        assert!(corrected_err < 0.06, "corrected error {corrected_err}");
        assert!(localiser.keyframes() >= 3);
        assert_eq!(localiser.refused(), 0);
    }

    /// Drives `truth(0..30)` and back with odometry 8 % long; the map after the way out, the
    /// map at the end, and the worst error of the way back's keyframes.
    fn out_and_back(
        params: LocaliserParams,
        turn_back: f64,
    ) -> (OccupancyGrid, OccupancyGrid, f64) {
        let mut localiser = Localiser::new(geometry(), params).unwrap();
        let (mut out_map, mut worst) = (None, 0.0f64);
        let path = (0..30).chain((0..30).rev());
        for (step, k) in path.enumerate() {
            let t = truth(k);
            let back = step >= 30;
            let heading = t.rotation.angle() + if back { turn_back } else { 0.0 };
            let t = Pose2::new(t.translation.vector, heading);
            let odom = Pose2::new(
                (t.translation.vector - truth(0).translation.vector) * 1.08
                    + truth(0).translation.vector,
                heading,
            );
            let out = localiser
                .update(&room(&t, step as f64 * 0.1), &odom)
                .unwrap();
            if step == 29 {
                out_map = Some(localiser.map());
            }
            if back && out.keyframe {
                worst = worst.max((out.pose.translation.vector - t.translation.vector).norm());
            }
        }
        (out_map.unwrap(), localiser.map(), worst)
    }

    #[test]
    fn a_revisiting_keyframe_is_matched_but_not_drawn() {
        // Back along the same poses: every keyframe revisits one of the way out, so the map
        // stays the way out's, and the way back is still corrected against it.
        let (out, end, worst) = out_and_back(LocaliserParams::default(), 0.0);
        assert_eq!(out, end);
        assert!(worst < 0.06, "worst error on the way back {worst}");
        // Every keyframe drawn: the way back changes the map.
        let all = LocaliserParams::default().with_revisit_distance(0.0);
        let (out, end, worst) = out_and_back(all, 0.0);
        assert_ne!(out, end);
        assert!(worst < 0.06, "worst error on the way back {worst}");
        // Turned by more than the keyframe angle, the same places are new views: drawn.
        let (out, end, _) = out_and_back(LocaliserParams::default(), 1.0);
        assert_ne!(out, end);
    }

    #[test]
    fn a_negative_or_infinite_revisit_distance_is_refused() {
        for bad in [-0.1, f64::INFINITY, f64::NAN] {
            let params = LocaliserParams::default().with_revisit_distance(bad);
            assert!(params.check().is_err(), "{bad}");
        }
    }

    #[test]
    fn without_odometry_a_refused_scan_is_placed_against_the_scan_before() {
        // The map covers only the room's left metre and a half: a scan fits it with less than
        // min_fitness of its points, so its map matches are refused. The robot speeds up, so
        // the constant-velocity guess alone falls behind; matched against the scan before,
        // the refused scans follow it.
        let narrow = GridGeometry::new(0.05, Point2::new(-4.0, -3.0), 50, 120).unwrap();
        let mut localiser = Localiser::new(narrow, LocaliserParams::default()).unwrap();
        let truth = |k: usize| {
            let k = k as f64;
            Pose2::new(
                Vector2::new(-1.5 + 0.04 * k + 0.0015 * k * k, -0.5 + 0.02 * k),
                0.01 * k,
            )
        };
        let start = truth(0);
        let mut worst = 0.0f64;
        for k in 0..24 {
            let t = truth(k);
            let out = localiser
                .update_without_odometry(&room(&t, k as f64 * 0.1))
                .unwrap();
            let expected = start.inverse() * t;
            worst = worst.max((out.pose.translation.vector - expected.translation.vector).norm());
        }
        // Without the scan before, the guess drifts by 1.8 m and the keyframes stop at one.
        assert!(worst < 0.08, "worst error {worst}");
        assert!(localiser.refused() >= 2, "{} refused", localiser.refused());
    }

    #[test]
    fn a_scan_with_absurd_ranges_still_gets_a_bounded_target() {
        // One beam a thousand kilometres away (a driver's garbage within its stated limits):
        // the fallback's target keeps to MAX_REACH and still places the scan.
        let t = truth(0);
        let good = room(&t, 0.0);
        let mut ranges = good.ranges.clone();
        ranges[10] = 1.0e6;
        let scan = LaserScan::new(
            0.0,
            good.angle_min,
            good.angle_increment,
            good.range_min,
            1.0e7,
            ranges,
            vec![],
        )
        .unwrap();
        let mut previous = PreviousScan::default();
        previous.remember(&scan, Pose2::identity());
        assert!(previous.points.iter().all(|p| p.coords.norm() <= MAX_REACH));
        let points: Vec<_> = good.endpoints().collect();
        let step = Pose2::new(Vector2::new(0.05, 0.0), 0.0);
        let placed = previous
            .matched(&points, &step, &LocaliserParams::default())
            .unwrap();
        assert!(placed.translation.vector.norm() < 0.03, "{placed}");
    }

    #[test]
    fn scan_matching_alone_follows_the_robot() {
        let mut localiser = Localiser::new(geometry(), LocaliserParams::default()).unwrap();
        let start = truth(0);
        let (mut worst, mut errors) = (0.0f64, Vec::new());
        for k in 0..30 {
            let t = truth(k);
            let out = localiser
                .update_without_odometry(&room(&t, k as f64 * 0.1))
                .unwrap();
            // Poses are relative to the first scan's.
            let expected = start.inverse() * t;
            let error = (out.pose.translation.vector - expected.translation.vector).norm();
            errors.push(error);
            worst = worst.max(error);
        }
        // Every scan is matched: errors stay at the map's cell scale, growing only where the
        // view changes most (the last metre, past the pillar).
        errors.sort_by(f64::total_cmp);
        assert!(
            errors[errors.len() / 2] < 0.04,
            "median error {}",
            errors[errors.len() / 2]
        );
        assert!(worst < 0.15, "scan matching alone drifted {worst}");
        assert!(localiser.keyframes() >= 3);
    }

    #[test]
    fn bad_parameters_and_poses_are_refused() {
        let bad = LocaliserParams::default().with_acceptance(1.5, 0.3);
        assert!(matches!(
            Localiser::new(geometry(), bad),
            Err(crate::SimilarityError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "localiser.min_fitness",
                    ..
                }
            ))
        ));
        let bad = LocaliserParams::default().with_refresh_every(0);
        assert!(Localiser::new(geometry(), bad).is_err());
        let mut localiser = Localiser::new(geometry(), LocaliserParams::default()).unwrap();
        let nan = Pose2::new(Vector2::new(f64::NAN, 0.0), 0.0);
        assert!(localiser.update(&room(&truth(0), 0.0), &nan).is_err());
        assert_eq!(localiser.keyframes(), 0);
    }
}
