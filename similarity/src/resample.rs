//! Putting maps of different extents on one grid, so that they can be compared cell by cell.

use haunts_occupancy::{Grid, GridGeometry, OccupancyGrid, Pose2, UNKNOWN};
use nalgebra::Point2;

use crate::difference::snap;
use crate::error::{Result, SimilarityError};

fn same_resolution(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a
}

/// The smallest geometry covering every given geometry, at their common resolution, with its
/// origin at the lowest-left origin.
///
/// # Errors
/// [`SimilarityError::TooFew`] for no geometry; [`SimilarityError::ResolutionMismatch`] when
/// the resolutions differ (resampling across resolutions would erase thin walls, so it is
/// refused rather than done silently); [`SimilarityError::Occupancy`] when the union is too
/// large for a grid.
///
/// # Example
/// ```
/// use haunts_occupancy::GridGeometry;
/// use nalgebra::Point2;
/// let a = GridGeometry::new(0.1, Point2::new(0.0, 0.0), 10, 10).unwrap();
/// let b = GridGeometry::new(0.1, Point2::new(-1.0, 0.5), 5, 20).unwrap();
/// let u = haunts_similarity::common_geometry(&[a, b]).unwrap();
/// assert_eq!((u.width(), u.height()), (20, 25));
/// approx::assert_relative_eq!(u.origin(), Point2::new(-1.0, 0.0));
/// ```
pub fn common_geometry(geometries: &[GridGeometry]) -> Result<GridGeometry> {
    let first = geometries.first().ok_or(SimilarityError::TooFew {
        what: "geometries",
        found: 0,
        needed: 1,
    })?;
    let res = first.resolution();
    let mut lo = first.origin();
    let mut hi = first.upper_corner();
    for (index, g) in geometries.iter().enumerate() {
        if !same_resolution(res, g.resolution()) {
            return Err(SimilarityError::ResolutionMismatch {
                index,
                expected: res,
                found: g.resolution(),
            });
        }
        lo = lo.inf(&g.origin());
        hi = hi.sup(&g.upper_corner());
    }
    let cells = |span: f64| snap(span / res).ceil() as usize;
    Ok(GridGeometry::new(
        res,
        lo,
        cells(hi.x - lo.x),
        cells(hi.y - lo.y),
    )?)
}

/// `map` sampled onto `target`: each target cell takes the value of the map cell holding its
/// centre, or unknown outside the map. The map's state thresholds are kept.
///
/// When the two lattices are aligned (origins differ by whole cells) this is an exact shift;
/// otherwise every cell moves by less than half a cell.
///
/// # Errors
/// [`SimilarityError::ResolutionMismatch`] (index 0) when the resolutions differ.
///
/// # Complexity
/// O(cells of `target`).
pub fn resample(map: &OccupancyGrid, target: &GridGeometry) -> Result<OccupancyGrid> {
    resample_posed(map, target, &Pose2::identity())
}

/// `map`, whose frame lies at `pose` in `target`'s frame (the transform of a registration:
/// map frame → target frame), sampled onto `target` by nearest neighbour: each target cell
/// takes the value of the map cell holding `pose⁻¹ ·` its centre, or unknown outside the map.
/// The map's state thresholds are kept. With the identity pose this is [`resample`].
///
/// # Errors
/// [`SimilarityError::ResolutionMismatch`] (index 0) when the resolutions differ.
///
/// # Complexity
/// O(cells of `target`).
pub fn resample_posed(
    map: &OccupancyGrid,
    target: &GridGeometry,
    pose: &Pose2,
) -> Result<OccupancyGrid> {
    let values = resample_grid(map.values(), target, pose, UNKNOWN)?;
    Ok(OccupancyGrid::from_grid(values)?.with_thresholds(map.thresholds())?)
}

/// Any grid whose frame lies at `pose` in `target`'s frame, sampled onto `target` by nearest
/// neighbour (as [`resample_posed`]), `outside` where the target cell's centre falls outside
/// the grid. Counts (a day's hits and visits) move with their cells: under a rotation a few
/// source cells are taken twice and a few not at all, so a sum is kept only approximately,
/// but a ratio of two counts resampled alike is the ratio of one source cell.
///
/// # Errors
/// [`SimilarityError::ResolutionMismatch`] (index 0) when the resolutions differ.
///
/// # Complexity
/// O(cells of `target`).
pub fn resample_grid<T: Clone>(
    grid: &Grid<T>,
    target: &GridGeometry,
    pose: &Pose2,
    outside: T,
) -> Result<Grid<T>> {
    let g = grid.geometry();
    if !same_resolution(target.resolution(), g.resolution()) {
        return Err(SimilarityError::ResolutionMismatch {
            index: 0,
            expected: target.resolution(),
            found: g.resolution(),
        });
    }
    let back = pose.inverse();
    Ok(Grid::from_fn(*target, |c| {
        let p: Point2<f64> = back * target.cell_center(c);
        g.world_to_cell(p)
            .and_then(|src| grid.get(src).cloned())
            .unwrap_or_else(|| outside.clone())
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use haunts_occupancy::{Cell, OCCUPIED};

    #[test]
    fn resampling_onto_the_union_is_an_exact_shift() {
        let a = GridGeometry::new(0.05, Point2::new(1.0, 2.0), 8, 6).unwrap();
        let b = GridGeometry::new(0.05, Point2::new(0.5, 2.25), 4, 4).unwrap();
        let u = common_geometry(&[a, b]).unwrap();
        assert_eq!((u.width(), u.height()), (18, 9));
        let mut m = OccupancyGrid::unknown(a);
        m.set(Cell::new(3, 4), OCCUPIED);
        m.set(Cell::new(0, 0), 0);
        let r = resample(&m, &u).unwrap();
        assert_eq!(r.value(Cell::new(13, 4)), Some(OCCUPIED));
        assert_eq!(r.value(Cell::new(10, 0)), Some(0));
        assert_eq!(r.counts(), (1, 1, 18 * 9 - 2));
        // And back again.
        assert_eq!(resample(&r, &a).unwrap(), m);
    }

    #[test]
    fn different_resolutions_are_refused() {
        let a = GridGeometry::new(0.05, Point2::origin(), 8, 6).unwrap();
        let b = GridGeometry::new(0.1, Point2::origin(), 8, 6).unwrap();
        assert!(matches!(
            common_geometry(&[a, b]),
            Err(SimilarityError::ResolutionMismatch { index: 1, .. })
        ));
        assert!(matches!(
            resample(&OccupancyGrid::unknown(a), &b),
            Err(SimilarityError::ResolutionMismatch { index: 0, .. })
        ));
        assert!(matches!(
            common_geometry(&[]),
            Err(SimilarityError::TooFew { .. })
        ));
    }

    #[test]
    fn a_posed_resample_turns_cells_with_the_pose() {
        // A quarter turn about the origin and a shift of 1 m: cell centres land on cell
        // centres, so every value moves exactly.
        let g = GridGeometry::new(0.1, Point2::new(0.0, 0.0), 10, 6).unwrap();
        let t = GridGeometry::new(0.1, Point2::new(-1.0, -1.0), 30, 30).unwrap();
        let grid = Grid::from_fn(g, |c| (c.col * 100 + c.row) as i32);
        let pose = Pose2::new(
            nalgebra::Vector2::new(1.0, 0.0),
            std::f64::consts::FRAC_PI_2,
        );
        let r = resample_grid(&grid, &t, &pose, -1).unwrap();
        for (c, &v) in grid.cells() {
            let p = pose * g.cell_center(c);
            let tc = t.world_to_cell(p).unwrap();
            assert_eq!(r[tc], v, "{c:?} -> {tc:?}");
        }
        assert_eq!(r.data().iter().filter(|&&v| v >= 0).count(), 60);
        // The identity is the plain resample.
        let mut m = OccupancyGrid::unknown(g);
        m.set(Cell::new(3, 4), OCCUPIED);
        assert_eq!(
            resample_posed(&m, &t, &Pose2::identity()).unwrap(),
            resample(&m, &t).unwrap()
        );
    }
}
