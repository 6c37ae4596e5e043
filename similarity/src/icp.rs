//! Point-to-line ICP in 2-D against an occupancy map: scan-to-map and map-to-map alignment
//! from an initial guess, with robust weights (seed 000 aligns every daily map to a
//! reference).

use haunts_occupancy::{Cell, Grid, GridGeometry, OccupancyGrid, Pose2};
use haunts_occupancy::{DistanceField, distance_transform_with_nearest};
use nalgebra::{Matrix3, Point2, Vector2, Vector3};

use crate::error::{Result, SimilarityError, rule};

/// The robust loss whose iteratively-reweighted least squares ICP solves.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum RobustLoss {
    /// Plain least squares: every correspondence weighs 1.
    Squared,
    /// Huber: weight 1 up to `delta` metres of residual, `delta / |r|` beyond.
    Huber {
        /// The transition, metres.
        delta: f64,
    },
    /// Tukey's biweight: `(1 − (r/c)²)²` up to `c` metres, 0 beyond (outliers ignored).
    Tukey {
        /// The cutoff, metres.
        c: f64,
    },
}

impl RobustLoss {
    /// The IRLS weight of a residual `r` (metres).
    pub fn weight(self, r: f64) -> f64 {
        let a = r.abs();
        match self {
            Self::Squared => 1.0,
            Self::Huber { delta } => {
                if a <= delta {
                    1.0
                } else {
                    delta / a
                }
            }
            Self::Tukey { c } => {
                if a < c {
                    let u = 1.0 - (a / c).powi(2);
                    u * u
                } else {
                    0.0
                }
            }
        }
    }
    fn scale(self) -> Option<f64> {
        match self {
            Self::Squared => None,
            Self::Huber { delta } => Some(delta),
            Self::Tukey { c } => Some(c),
        }
    }
}

/// Parameters of ICP.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct IcpParams {
    /// Iteration budget (default 50).
    pub max_iterations: usize,
    /// A source point pairs with the nearest map point only within this distance, metres
    /// (default 0.5).
    pub max_correspondence_distance: f64,
    /// Robust loss (default Huber with δ = 0.05 m).
    pub loss: RobustLoss,
    /// Converged when an update moves less than this, metres (default 1e-5)…
    pub translation_tolerance: f64,
    /// …and turns less than this, radians (default 1e-6).
    pub rotation_tolerance: f64,
    /// Fewest correspondences to go on with (default 10).
    pub min_correspondences: usize,
}

impl Default for IcpParams {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            max_correspondence_distance: 0.5,
            loss: RobustLoss::Huber { delta: 0.05 },
            translation_tolerance: 1e-5,
            rotation_tolerance: 1e-6,
            min_correspondences: 10,
        }
    }
}

impl IcpParams {
    /// Sets the robust loss.
    pub fn with_loss(mut self, loss: RobustLoss) -> Self {
        self.loss = loss;
        self
    }
    /// Sets the correspondence distance, metres.
    pub fn with_max_correspondence_distance(mut self, d: f64) -> Self {
        self.max_correspondence_distance = d;
        self
    }
    /// Sets the iteration budget.
    pub fn with_max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }
    /// The parameters after checking each rule.
    ///
    /// # Errors
    /// [`SimilarityError::InvalidParameter`] naming the first parameter that is not finite
    /// and positive (tolerances may be 0), or a zero iteration budget, or fewer than 3
    /// correspondences required.
    pub fn check(self) -> Result<Self> {
        let d = self.max_correspondence_distance;
        rule(
            "max_correspondence_distance",
            d,
            d.is_finite() && d > 0.0,
            "must be finite and > 0",
        )?;
        for (name, v) in [
            ("translation_tolerance", self.translation_tolerance),
            ("rotation_tolerance", self.rotation_tolerance),
        ] {
            rule(
                name,
                v,
                v.is_finite() && v >= 0.0,
                "must be finite and >= 0",
            )?;
        }
        if let Some(s) = self.loss.scale() {
            rule(
                "loss scale",
                s,
                s.is_finite() && s > 0.0,
                "must be finite and > 0",
            )?;
        }
        let it = self.max_iterations as f64;
        rule("max_iterations", it, self.max_iterations > 0, "must be > 0")?;
        let m = self.min_correspondences as f64;
        rule(
            "min_correspondences",
            m,
            self.min_correspondences >= 3,
            "must be >= 3",
        )?;
        Ok(self)
    }
}

/// A map prepared as an ICP target: nearest occupied cell of every cell (exact EDT) and the
/// line normal of every occupied cell.
#[derive(Debug, Clone)]
pub struct IcpTarget {
    field: DistanceField,
    /// Per cell, where it is in `occupied` (occupied cells), `u32::MAX` elsewhere: four
    /// bytes a cell to fill at every rebuild rather than a normal's 24.
    slots: Vec<u32>,
    /// Centre and unit normal of each occupied cell, in row-major order; the normal is
    /// `None` where the neighbourhood is not line-like (corners, isolated cells): those
    /// pair point-to-point. The centre is kept so that a look-up never divides an index
    /// into a cell.
    occupied: Vec<(Point2<f64>, Option<Vector2<f64>>)>,
}

/// Radius, in cells, of the neighbourhood whose principal axis gives a cell's normal.
const NORMAL_RADIUS: i64 = 2;

impl IcpTarget {
    /// Prepares the occupied cells of `map`.
    ///
    /// # Errors
    /// [`SimilarityError::EmptyMap`] when no cell is occupied.
    ///
    /// # Complexity
    /// O(cells).
    pub fn new(map: &OccupancyGrid) -> Result<Self> {
        Self::from_mask(&map.occupied_mask())
    }

    /// Prepares an obstacle mask (`true` = occupied).
    ///
    /// # Errors
    /// As [`IcpTarget::new`].
    pub fn from_mask(mask: &Grid<bool>) -> Result<Self> {
        if !mask.data().contains(&true) {
            return Err(SimilarityError::EmptyMap { index: 0 });
        }
        let field = distance_transform_with_nearest(mask)?;
        let g = *mask.geometry();
        // Normals at the occupied cells only (a few in a hundred).
        let mut slots = vec![u32::MAX; mask.data().len()];
        let mut occupied = Vec::new();
        for ((c, _), slot) in mask.cells().zip(&mut slots).filter(|((_, o), _)| **o) {
            // A grid holds fewer than 2³² cells (the cell budget).
            *slot = u32::try_from(occupied.len()).unwrap_or(u32::MAX);
            occupied.push((g.cell_center(c), line_normal(mask, &g, c)));
        }
        Ok(Self {
            field,
            slots,
            occupied,
        })
    }

    /// Where the target lies.
    pub fn geometry(&self) -> &GridGeometry {
        self.field.geometry()
    }

    /// The nearest occupied cell centre to `p` and its normal, if `p` is on the grid.
    fn nearest(&self, p: Point2<f64>) -> Option<(Point2<f64>, Option<Vector2<f64>>)> {
        let g = self.field.geometry();
        let i = g.index(g.world_to_cell(p)?)?;
        let nearest = *self.field.nearest_indices()?.get(i)?;
        let slot = *self.slots.get(nearest as usize)?;
        self.occupied.get(slot as usize).copied()
    }
}

/// The normal of the line through the occupied neighbours of `c`, when they are line-like
/// (smallest eigenvalue of their scatter under a fifth of the largest).
fn line_normal(mask: &Grid<bool>, g: &GridGeometry, c: Cell) -> Option<Vector2<f64>> {
    // The neighbours in a fixed array (no allocation per occupied cell of every rebuilt
    // target), in the same order as ever.
    const SIDE: usize = 2 * NORMAL_RADIUS as usize + 1;
    let mut found = [Vector2::zeros(); SIDE * SIDE];
    let mut len = 0;
    for dr in -NORMAL_RADIUS..=NORMAL_RADIUS {
        for dc in -NORMAL_RADIUS..=NORMAL_RADIUS {
            if let Some(n) = g.checked_cell(c.col as i64 + dc, c.row as i64 + dr) {
                if mask[n] {
                    found[len] = Vector2::new(dc as f64, dr as f64);
                    len += 1;
                }
            }
        }
    }
    let pts = &found[..len];
    if pts.len() < 3 {
        return None;
    }
    let mean = pts.iter().sum::<Vector2<f64>>() / pts.len() as f64;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let d = p - mean;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let tr = sxx + syy;
    let disc = ((sxx - syy).powi(2) / 4.0 + sxy * sxy).sqrt();
    let (big, small) = (tr / 2.0 + disc, tr / 2.0 - disc);
    if small > 0.2 * big || big <= 0.0 {
        return None;
    }
    // Eigenvector of the small eigenvalue.
    let v = if sxy.abs() > 1e-12 {
        Vector2::new(sxy, small - sxx)
    } else if sxx < syy {
        Vector2::new(1.0, 0.0)
    } else {
        Vector2::new(0.0, 1.0)
    };
    Some(v.normalize())
}

/// The outcome of ICP.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct IcpResult {
    /// Pose of the source frame in the target map's frame.
    pub pose: Pose2,
    /// Iterations run.
    pub iterations: usize,
    /// Correspondences within reach at the final pose.
    pub correspondences: usize,
    /// Fitness: fraction of source points with a correspondence within reach at the final
    /// pose (1 = every point lies near the map).
    pub fitness: f64,
    /// RMS point-to-line (or point-to-point) residual of those correspondences, metres.
    pub inlier_rms: f64,
}

/// The pose that aligns `points` (in the source frame, e.g. a scan's endpoints in the sensor
/// frame) with the occupied cells of `target`, starting from `initial`.
///
/// Each iteration pairs every transformed point with the nearest occupied cell of the map
/// (an O(1) look-up in the exact distance transform), keeps pairs within
/// `max_correspondence_distance`, and takes one Gauss–Newton step of the robustly weighted
/// point-to-line error `Σ w(r)·(n·(T·p − q))²` (point-to-point where the map is not
/// line-like), with weights from [`RobustLoss`]. It stops when a step moves less than both
/// tolerances.
///
/// # Errors
/// [`SimilarityError::NoCorrespondences`] when fewer than `min_correspondences` pairs are in
/// reach; [`SimilarityError::Degenerate`] when the pairs do not constrain all three degrees of
/// freedom (e.g. a single straight wall); [`SimilarityError::NotConverged`] with the last
/// estimate; [`SimilarityError::NonFinitePoint`] for a NaN point (index in `points`);
/// [`SimilarityError::InvalidParameter`] for bad parameters.
///
/// # Complexity
/// O(iterations · points).
///
/// # Example
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry, Pose2};
/// use haunts_similarity::{icp, IcpParams, IcpTarget};
/// use nalgebra::{Point2, Vector2};
/// // Two walls meeting in a corner, and points on them seen from a sensor at `truth`.
/// let g = GridGeometry::new(0.05, Point2::origin(), 100, 100).unwrap();
/// let target = IcpTarget::from_mask(&Grid::from_fn(g, |c| c.col == 10 || c.row == 10)).unwrap();
/// let truth = Pose2::new(Vector2::new(2.0, 2.0), 0.5);
/// let world: Vec<Point2<f64>> = (12..90)
///     .flat_map(|i| [g.cell_center(Cell::new(10, i)), g.cell_center(Cell::new(i, 10))])
///     .collect();
/// let scan: Vec<_> = world.iter().map(|p| truth.inverse() * p).collect();
/// let guess = truth * Pose2::new(Vector2::new(0.1, -0.1), 0.05);
/// let r = icp(&target, &scan, &guess, &IcpParams::default()).unwrap();
/// approx::assert_relative_eq!(r.pose, truth, epsilon = 1e-6);
/// assert_eq!(r.fitness, 1.0);
/// ```
pub fn icp(
    target: &IcpTarget,
    points: &[Point2<f64>],
    initial: &Pose2,
    params: &IcpParams,
) -> Result<IcpResult> {
    let params = params.check()?;
    if let Some(index) = points
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(SimilarityError::NonFinitePoint {
            what: "source",
            index,
        });
    }
    let mut pose = *initial;
    for iteration in 0..params.max_iterations {
        let (h, b, found, _) = normal_equations(target, points, &pose, &params, true);
        if found < params.min_correspondences {
            return Err(SimilarityError::NoCorrespondences {
                iteration,
                found,
                needed: params.min_correspondences,
            });
        }
        let delta = h
            .cholesky()
            .map(|c| c.solve(&(-b)))
            .ok_or(SimilarityError::Degenerate {
                reason: "the correspondences do not constrain rotation and both translations",
            })?;
        if !delta.iter().all(|v| v.is_finite()) {
            return Err(SimilarityError::Degenerate {
                reason: "the ICP step is not finite",
            });
        }
        pose = Pose2::new(Vector2::new(delta[1], delta[2]), delta[0]) * pose;
        let done = delta[0].abs() < params.rotation_tolerance
            && delta[1].hypot(delta[2]) < params.translation_tolerance;
        if done {
            return Ok(summary(target, points, pose, iteration + 1, &params));
        }
    }
    Err(SimilarityError::NotConverged {
        partial: Box::new(summary(
            target,
            points,
            pose,
            params.max_iterations,
            &params,
        )),
    })
}

/// [`icp`] of the occupied cell centres of `source` (a map in its own frame) against
/// `target`: map-to-map alignment.
///
/// # Errors
/// As [`icp`]; [`SimilarityError::EmptyMap`] (index 1) when `source` has no occupied cell.
pub fn icp_map_to_map(
    target: &IcpTarget,
    source: &OccupancyGrid,
    initial: &Pose2,
    params: &IcpParams,
) -> Result<IcpResult> {
    let g = source.geometry();
    let points: Vec<Point2<f64>> = source
        .occupied_mask()
        .cells()
        .filter(|(_, o)| **o)
        .map(|(c, _)| g.cell_center(c))
        .collect();
    if points.is_empty() {
        return Err(SimilarityError::EmptyMap { index: 1 });
    }
    icp(target, &points, initial, params)
}

fn summary(
    target: &IcpTarget,
    points: &[Point2<f64>],
    pose: Pose2,
    iterations: usize,
    params: &IcpParams,
) -> IcpResult {
    let (_, _, found, sse) = normal_equations(target, points, &pose, params, false);
    IcpResult {
        pose,
        iterations,
        correspondences: found,
        fitness: if points.is_empty() {
            0.0
        } else {
            found as f64 / points.len() as f64
        },
        inlier_rms: if found == 0 {
            0.0
        } else {
            (sse / found as f64).sqrt()
        },
    }
}

/// The weighted Gauss–Newton system at `pose`, the number of pairs in reach and the
/// (unweighted) sum of squared residuals.
fn normal_equations(
    target: &IcpTarget,
    points: &[Point2<f64>],
    pose: &Pose2,
    params: &IcpParams,
    weighted: bool,
) -> (Matrix3<f64>, Vector3<f64>, usize, f64) {
    let mut h = Matrix3::zeros();
    let mut b = Vector3::zeros();
    let mut found = 0;
    let mut sse = 0.0;
    let reach = params.max_correspondence_distance;
    for p in points {
        let pw = pose * p;
        let Some((q, normal)) = target.nearest(pw) else {
            continue;
        };
        let d = pw - q;
        if d.norm() > reach {
            continue;
        }
        found += 1;
        let perp = Vector2::new(-pw.y, pw.x);
        let mut add = |n: Vector2<f64>| {
            let r = n.dot(&d);
            sse += r * r;
            if weighted {
                let w = params.loss.weight(r);
                let j = Vector3::new(n.dot(&perp), n.x, n.y);
                h += w * j * j.transpose();
                b += w * r * j;
            }
        };
        match normal {
            Some(n) => add(n),
            None => {
                add(Vector2::x());
                add(Vector2::y());
            }
        }
    }
    (h, b, found, sse)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use haunts_occupancy::OCCUPIED;

    /// A 6 m × 5 m room at 0.05 m with an inner wall and an L-shaped cupboard.
    fn room() -> OccupancyGrid {
        let g = GridGeometry::new(0.05, Point2::new(-1.0, -1.0), 120, 100).unwrap();
        let mut m = OccupancyGrid::unknown(g);
        for c in (0..g.len()).filter_map(|i| g.cell_at(i)) {
            let wall = c.col == 0 || c.col == 119 || c.row == 0 || c.row == 99;
            let inner = c.col == 60 && c.row < 60;
            let cupboard = (c.row == 80 && (20..45).contains(&c.col))
                || (c.col == 20 && (65..80).contains(&c.row));
            if wall || inner || cupboard {
                m.set(c, OCCUPIED);
            }
        }
        m
    }

    fn occupied_points(m: &OccupancyGrid) -> Vec<Point2<f64>> {
        let g = m.geometry();
        m.occupied_mask()
            .cells()
            .filter(|(_, o)| **o)
            .map(|(c, _)| g.cell_center(c))
            .collect()
    }

    #[test]
    fn recovers_a_known_pose_from_a_wrong_guess() {
        let map = room();
        let target = IcpTarget::new(&map).unwrap();
        let truth = Pose2::new(Vector2::new(0.3, -0.2), 0.08);
        // The map's points seen from a sensor at `truth`: source = truth⁻¹ · world.
        let scan: Vec<_> = occupied_points(&map)
            .iter()
            .map(|p| truth.inverse() * p)
            .collect();
        for loss in [
            RobustLoss::Squared,
            RobustLoss::Huber { delta: 0.05 },
            RobustLoss::Tukey { c: 0.3 },
        ] {
            let params = IcpParams::default().with_loss(loss);
            let guess = Pose2::new(Vector2::new(0.45, -0.05), 0.03);
            let r = icp(&target, &scan, &guess, &params).unwrap();
            assert_relative_eq!(
                r.pose.translation.vector,
                truth.translation.vector,
                epsilon = 1e-3
            );
            assert_relative_eq!(r.pose.rotation.angle(), 0.08, epsilon = 1e-4);
            assert!(r.fitness > 0.99, "{r:?}");
            assert!(r.inlier_rms < 0.01, "{r:?}");
        }
    }

    #[test]
    fn map_to_map_with_outliers() {
        let map = room();
        let target = IcpTarget::new(&map).unwrap();
        let truth = Pose2::new(Vector2::new(-0.1, 0.15), -0.05);
        let g = *map.geometry();
        // The source map: the room moved by truth⁻¹ plus clutter absent from the target.
        let mut source = OccupancyGrid::unknown(g);
        for p in occupied_points(&map) {
            if let Some(c) = g.world_to_cell(truth.inverse() * p) {
                source.set(c, OCCUPIED);
            }
        }
        for col in 80..100 {
            source.set(Cell::new(col, 30), OCCUPIED);
        }
        let params = IcpParams::default().with_loss(RobustLoss::Tukey { c: 0.2 });
        let r = icp_map_to_map(&target, &source, &Pose2::identity(), &params).unwrap();
        assert_relative_eq!(
            r.pose.translation.vector,
            truth.translation.vector,
            epsilon = 0.025
        );
        assert_relative_eq!(
            r.pose.rotation.angle(),
            -0.05,
            epsilon = 0.2f64.to_radians()
        );
        assert!(r.fitness < 1.0 && r.fitness > 0.9, "{r:?}");
    }

    #[test]
    fn typed_errors() {
        let map = room();
        let target = IcpTarget::new(&map).unwrap();
        let pts = occupied_points(&map);
        // Far from the map: nothing within reach.
        let far = Pose2::new(Vector2::new(50.0, 0.0), 0.0);
        assert!(matches!(
            icp(&target, &pts, &far, &IcpParams::default()),
            Err(SimilarityError::NoCorrespondences { iteration: 0, .. })
        ));
        // A single straight wall does not fix the translation along it.
        let g = *map.geometry();
        let wall = IcpTarget::from_mask(&Grid::from_fn(g, |c| c.row == 50)).unwrap();
        let line: Vec<_> = (10..40)
            .map(|i| Point2::new(i as f64 * 0.05, 1.525))
            .collect();
        assert!(matches!(
            icp(&wall, &line, &Pose2::identity(), &IcpParams::default()),
            Err(SimilarityError::Degenerate { .. })
        ));
        let r = icp(
            &target,
            &pts,
            &Pose2::new(Vector2::new(0.2, 0.0), 0.0),
            &IcpParams::default().with_max_iterations(1),
        );
        match r {
            Err(SimilarityError::NotConverged { partial }) => assert_eq!(partial.iterations, 1),
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            IcpTarget::new(&OccupancyGrid::unknown(g)),
            Err(SimilarityError::EmptyMap { .. })
        ));
        assert!(matches!(
            icp(
                &target,
                &[Point2::new(f64::NAN, 0.0)],
                &Pose2::identity(),
                &IcpParams::default()
            ),
            Err(SimilarityError::NonFinitePoint { index: 0, .. })
        ));
        assert!(matches!(
            IcpParams::default()
                .with_max_correspondence_distance(-1.0)
                .check(),
            Err(SimilarityError::InvalidParameter(
                haunts_core::InvalidParameter { .. }
            ))
        ));
        assert_eq!(RobustLoss::Tukey { c: 1.0 }.weight(2.0), 0.0);
        assert_eq!(RobustLoss::Huber { delta: 1.0 }.weight(-4.0), 0.25);
    }
}
