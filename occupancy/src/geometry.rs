//! Where a grid lies in the world: resolution, origin and size, and the world ↔ cell maps.

use nalgebra::{Isometry2, Point2};

use crate::{OccupancyError, Result};

/// A robot or sensor pose in the plane: rotation then translation, metres and radians.
pub type Pose2 = Isometry2<f64>;

/// A cell of a grid: column (x index) and row (y index, row 0 at the bottom).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    /// Column, counted from the left (x grows with it).
    pub col: usize,
    /// Row, counted from the bottom (y grows with it).
    pub row: usize,
}

impl Cell {
    /// The cell at column `col` and row `row`.
    pub const fn new(col: usize, row: usize) -> Self {
        Self { col, row }
    }
}

/// The placement of a grid in the world, as in ROS `nav_msgs/MapMetaData`.
///
/// `origin` is the world position of the lower-left corner of cell `(0, 0)`; cell `(c, r)`
/// covers `[origin.x + c·res, origin.x + (c+1)·res) × [origin.y + r·res, origin.y + (r+1)·res)`.
/// Data laid out on this geometry is row-major with row 0 at the bottom.
///
/// ```
/// use haunts_occupancy::{Cell, GridGeometry};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(0.5, Point2::new(-1.0, -1.0), 4, 4).unwrap();
/// assert_eq!(g.world_to_cell(Point2::new(0.1, -0.9)), Some(Cell::new(2, 0)));
/// assert_eq!(g.world_to_cell(Point2::new(1.0, 0.0)), None); // the upper bound is open
/// approx::assert_relative_eq!(g.cell_center(Cell::new(2, 0)), Point2::new(0.25, -0.75));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "GridGeometryFields"))]
pub struct GridGeometry {
    resolution: f64,
    origin: Point2<f64>,
    width: usize,
    height: usize,
}

impl GridGeometry {
    /// A geometry of `width × height` cells of side `resolution` metres.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidGeometry`] when the resolution is not finite and positive or
    /// above [`GridGeometry::MAX_RESOLUTION`], or the origin is not finite or farther than
    /// [`GridGeometry::MAX_ORIGIN`] from zero; [`OccupancyError::BadGridSize`] when a side is zero;
    /// [`OccupancyError::GridTooLarge`] when `width · height` exceeds the cell budget
    /// ([`crate::budget`], 2²⁸ cells unless raised).
    pub fn new(resolution: f64, origin: Point2<f64>, width: usize, height: usize) -> Result<Self> {
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(OccupancyError::InvalidGeometry {
                field: "resolution",
                value: resolution,
                expected: "finite and > 0",
            });
        }
        if resolution > Self::MAX_RESOLUTION {
            return Err(OccupancyError::InvalidGeometry {
                field: "resolution",
                value: resolution,
                expected: "at most 1000 m (GridGeometry::MAX_RESOLUTION)",
            });
        }
        for (field, value) in [("origin.x", origin.x), ("origin.y", origin.y)] {
            if !value.is_finite() {
                return Err(OccupancyError::InvalidGeometry {
                    field,
                    value,
                    expected: "finite",
                });
            }
            if value.abs() > Self::MAX_ORIGIN {
                return Err(OccupancyError::InvalidGeometry {
                    field,
                    value,
                    expected: "within ±1e8 m (GridGeometry::MAX_ORIGIN)",
                });
            }
        }
        if width == 0 || height == 0 {
            return Err(OccupancyError::BadGridSize { width, height });
        }
        let (w, h) = (width as f64, height as f64);
        let far = origin + nalgebra::Vector2::new(w, h) * resolution;
        crate::budget::check_extent(w, h, resolution, origin, far)?;

        Ok(Self {
            resolution,
            origin,
            width,
            height,
        })
    }

    /// The smallest geometry of the given resolution that holds every finite point with
    /// `margin` metres to spare, its origin snapped to a multiple of the resolution.
    ///
    /// # Errors
    /// As [`GridGeometry::new`]; [`OccupancyError::BadGridSize`] when no point is finite;
    /// [`OccupancyError::GridTooLarge`] when the box of the points (one far outlier is
    /// enough) needs more cells than the budget allows, whatever its size: the sides are
    /// computed in floating point and checked before they are converted.
    pub fn bounding(
        points: impl IntoIterator<Item = Point2<f64>>,
        resolution: f64,
        margin: f64,
    ) -> Result<Self> {
        let mut lo = Point2::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        for p in points
            .into_iter()
            .filter(|p| p.x.is_finite() && p.y.is_finite())
        {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(OccupancyError::InvalidGeometry {
                field: "resolution",
                value: resolution,
                expected: "finite and > 0",
            });
        }
        haunts_core::non_negative("margin", margin)?;
        if lo.x > hi.x {
            return Err(OccupancyError::BadGridSize {
                width: 0,
                height: 0,
            });
        }
        let origin = Point2::new(
            ((lo.x - margin) / resolution).floor() * resolution,
            ((lo.y - margin) / resolution).floor() * resolution,
        );
        // Sides in f64, checked against the budget before any conversion: a point at 1e300
        // is a typed error naming it, not a side wrapped or saturated to nonsense.
        let far = Point2::new(hi.x + margin, hi.y + margin);
        let cells = |span: f64| (span / resolution).floor() + 1.0;
        let (width, height) = crate::budget::check_extent(
            cells(far.x - origin.x),
            cells(far.y - origin.y),
            resolution,
            origin,
            far,
        )?;
        Self::new(resolution, origin, width, height)
    }

    /// Side of a cell in metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }
    /// World position of the lower-left corner of cell `(0, 0)`.
    pub fn origin(&self) -> Point2<f64> {
        self.origin
    }
    /// Number of columns.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Number of rows.
    pub fn height(&self) -> usize {
        self.height
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.width * self.height
    }
    /// Always false: a geometry has at least one cell.
    pub fn is_empty(&self) -> bool {
        false
    }
    /// World position of the upper-right corner of the grid.
    pub fn upper_corner(&self) -> Point2<f64> {
        self.origin
            + nalgebra::Vector2::new(self.width as f64, self.height as f64) * self.resolution
    }

    /// The same area with cells of `resolution` metres: the same origin, and as many cells as
    /// cover the area (the last row and column may reach beyond it).
    ///
    /// # Errors
    /// As [`GridGeometry::new`] (a resolution that is not finite and > 0; more cells than the
    /// budget, [`OccupancyError::GridTooLarge`]).
    pub fn with_resolution(&self, resolution: f64) -> Result<Self> {
        // A millionth of a cell of slack, so that rounding (0.05 × 3 / 0.15) adds no cell.
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(OccupancyError::InvalidGeometry {
                field: "resolution",
                value: resolution,
                expected: "finite and > 0",
            });
        }
        let cells = |n: usize| (n as f64 * self.resolution / resolution - 1e-6).ceil();
        let (width, height) = crate::budget::check_extent(
            cells(self.width),
            cells(self.height),
            resolution,
            self.origin,
            self.upper_corner(),
        )?;
        Self::new(resolution, self.origin, width, height)
    }

    /// The cell holding world point `p` (floor semantics), or `None` outside the grid or for a
    /// non-finite point.
    pub fn world_to_cell(&self, p: Point2<f64>) -> Option<Cell> {
        let (c, r) = self.world_to_grid(p);
        // Without `f64::floor` (a libm call on x86-64's baseline): for x ≥ 0, ⌊x⌋ ≥ 0, and
        // ⌊x⌋ < n ⇔ x < n for an integer n; truncating a non-negative x is ⌊x⌋. NaN fails
        // the comparisons.
        (c >= 0.0 && r >= 0.0 && c < self.width as f64 && r < self.height as f64)
            .then(|| Cell::new(c as usize, r as usize))
    }

    /// Continuous grid coordinates of `p`: cell `(c, r)` covers `[c, c+1) × [r, r+1)`.
    pub fn world_to_grid(&self, p: Point2<f64>) -> (f64, f64) {
        (
            (p.x - self.origin.x) / self.resolution,
            (p.y - self.origin.y) / self.resolution,
        )
    }

    /// World position of the centre of `cell` (which need not lie inside the grid).
    pub fn cell_center(&self, cell: Cell) -> Point2<f64> {
        Point2::new(
            self.origin.x + (cell.col as f64 + 0.5) * self.resolution,
            self.origin.y + (cell.row as f64 + 0.5) * self.resolution,
        )
    }

    /// The cell at signed coordinates, or `None` outside the grid.
    pub fn checked_cell(&self, col: i64, row: i64) -> Option<Cell> {
        (col >= 0
            && row >= 0
            && (col as u64) < self.width as u64
            && (row as u64) < self.height as u64)
            .then(|| Cell::new(col as usize, row as usize))
    }

    /// Whether `cell` lies inside the grid.
    pub fn contains(&self, cell: Cell) -> bool {
        cell.col < self.width && cell.row < self.height
    }

    /// Row-major index of `cell` (row 0 first), or `None` outside the grid.
    pub fn index(&self, cell: Cell) -> Option<usize> {
        self.contains(cell)
            .then(|| cell.row * self.width + cell.col)
    }

    /// The cell at row-major index `index`, or `None` past the end.
    pub fn cell_at(&self, index: usize) -> Option<Cell> {
        (index < self.len()).then(|| Cell::new(index % self.width, index / self.width))
    }

    /// The widest cell a geometry may have, metres: 1 km. A cell wider than a kilometre is no
    /// map of a site but a corrupt or mistyped number (a library whose resolution read 1e308
    /// once sent `haunts maps` into a loop over an infinite extent).
    pub const MAX_RESOLUTION: f64 = 1000.0;

    /// The farthest an origin may lie from zero on either axis, metres: 10⁸ m, beyond any
    /// frame on Earth (UTM northings reach 10⁷ m). Farther, a cell's corner `origin + i ·
    /// resolution` loses the cell to floating-point round-off (at 10³⁰⁰, adding 0.1 m changes
    /// nothing and every cell lies at one point); at 10⁸ m the round-off is 1.5·10⁻⁸ m.
    pub const MAX_ORIGIN: f64 = 1e8;

    /// The tolerance, in cell sides, within which the crates take two origins as the same
    /// ([`GridGeometry::same_cells`]): 10⁻⁶ of a cell absorbs the decimal round-off of map
    /// files and JSON, and is far below any real misalignment.
    pub const SAME_CELLS_TOLERANCE: f64 = 1e-6;

    /// Whether two geometries describe the same cells, with origins equal within `tolerance`
    /// of a cell side (to absorb decimal round-off in map files; the crates use
    /// [`GridGeometry::SAME_CELLS_TOLERANCE`]).
    pub fn same_cells(&self, other: &Self, tolerance: f64) -> bool {
        let tol = tolerance * self.resolution;
        self.width == other.width
            && self.height == other.height
            && (self.resolution - other.resolution).abs() <= 1e-9 * self.resolution
            && (self.origin - other.origin).abs().max() <= tol
    }
}

/// The fields of a [`GridGeometry`] as deserialised, before [`GridGeometry::new`] checks them.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct GridGeometryFields {
    resolution: f64,
    origin: Point2<f64>,
    width: usize,
    height: usize,
}

#[cfg(feature = "serde")]
impl TryFrom<GridGeometryFields> for GridGeometry {
    type Error = OccupancyError;
    fn try_from(f: GridGeometryFields) -> Result<Self> {
        Self::new(f.resolution, f.origin, f.width, f.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn with_resolution_covers_the_same_area() {
        let g = GridGeometry::new(0.05, Point2::new(-2.0, 1.0), 400, 281).unwrap();
        let coarse = g.with_resolution(0.1).unwrap();
        assert_eq!((coarse.width(), coarse.height()), (200, 141));
        assert_eq!(coarse.origin(), g.origin());
        let back = coarse.with_resolution(0.05).unwrap();
        assert_eq!((back.width(), back.height()), (400, 282));
        let odd = GridGeometry::new(0.05, Point2::origin(), 3, 3).unwrap();
        assert_eq!(odd.with_resolution(0.15).unwrap().width(), 1);
        assert!(g.with_resolution(f64::NAN).is_err());
        assert!(g.with_resolution(0.0).is_err());
    }

    #[test]
    fn rejects_bad_parameters() {
        let o = Point2::origin();
        assert!(matches!(
            GridGeometry::new(-0.1, o, 2, 2),
            Err(OccupancyError::InvalidGeometry {
                field: "resolution",
                ..
            })
        ));
        assert!(matches!(
            GridGeometry::new(f64::NAN, o, 2, 2),
            Err(OccupancyError::InvalidGeometry { .. })
        ));
        assert!(matches!(
            GridGeometry::new(0.1, o, 0, 2),
            Err(OccupancyError::BadGridSize {
                width: 0,
                height: 2
            })
        ));
        assert!(matches!(
            GridGeometry::new(0.1, Point2::new(f64::INFINITY, 0.0), 2, 2),
            Err(OccupancyError::InvalidGeometry {
                field: "origin.x",
                ..
            })
        ));
        assert!(matches!(
            GridGeometry::new(0.1, o, usize::MAX, 2),
            Err(OccupancyError::GridTooLarge { budget, .. }) if budget == crate::budget::max_cells()
        ));
        // One past the default budget (tests never lower it).
        assert!(matches!(
            GridGeometry::new(0.1, o, 1 << 14, (1 << 14) + 1),
            Err(OccupancyError::GridTooLarge { .. })
        ));
        // Finite but absurd: cells wider than a kilometre.
        assert!(GridGeometry::new(GridGeometry::MAX_RESOLUTION, o, 2, 2).is_ok());
        // An origin as far as a UTM frame's is a map; one at 1e300 is a corrupt number.
        let utm = Point2::new(500_000.0, 5_000_000.0);
        assert!(GridGeometry::new(0.05, utm, 2, 2).is_ok());
        let edge = Point2::new(-GridGeometry::MAX_ORIGIN, GridGeometry::MAX_ORIGIN);
        assert!(GridGeometry::new(0.05, edge, 2, 2).is_ok());
        for far in [Point2::new(1e300, 0.0), Point2::new(0.0, -1.0000001e8)] {
            let e = GridGeometry::new(0.05, far, 2, 2).unwrap_err();
            assert!(e.to_string().contains("MAX_ORIGIN"), "{e}");
        }
        for r in [1000.001, 1e308] {
            assert!(matches!(
                GridGeometry::new(r, o, 2, 2),
                Err(OccupancyError::InvalidGeometry {
                    field: "resolution",
                    ..
                })
            ));
        }
    }

    #[test]
    fn bounding_of_a_far_point_is_too_large_not_wrapped() {
        // `as usize + 1` used to wrap or saturate here and report "a grid of 0×621 cells".
        let pts = [Point2::new(-1.0, -1.0), Point2::new(1e300, 30.0)];
        match GridGeometry::bounding(pts, 0.05, 0.0) {
            Err(e @ OccupancyError::GridTooLarge { .. }) => {
                let OccupancyError::GridTooLarge {
                    width,
                    height,
                    resolution,
                    to,
                    ..
                } = e
                else {
                    unreachable!()
                };
                assert!(width > 1e301, "width {width}");
                assert_eq!(height, 621.0);
                assert_eq!(resolution, 0.05);
                assert_eq!(to, [1e300, 30.0]);
                let message = e.to_string();
                assert!(message.contains("2e301 × 621 cells of 0.05 m"), "{message}");
            }
            other => panic!("expected GridTooLarge, got {other:?}"),
        }
        // At the edge of f64: the far side overflows to infinity, still the same error.
        let pts = [Point2::new(-f64::MAX, 0.0), Point2::new(f64::MAX, 0.0)];
        assert!(matches!(
            GridGeometry::bounding(pts, 0.05, 1.0),
            Err(OccupancyError::GridTooLarge { .. } | OccupancyError::InvalidGeometry { .. })
        ));
    }

    #[test]
    fn a_finer_resolution_over_the_budget_is_refused() {
        let g = GridGeometry::new(0.05, Point2::origin(), 600, 600).unwrap();
        assert_eq!(g.with_resolution(0.1).unwrap().width(), 300);
        assert!(matches!(
            g.with_resolution(0.0001),
            Err(OccupancyError::GridTooLarge { width, .. }) if width == 300_000.0
        ));
        assert!(matches!(
            g.with_resolution(f64::MIN_POSITIVE),
            Err(OccupancyError::GridTooLarge { .. })
        ));
        assert!(matches!(
            g.with_resolution(-1.0),
            Err(OccupancyError::InvalidGeometry { .. })
        ));
    }

    #[test]
    fn floor_semantics_and_bounds() {
        let g = GridGeometry::new(0.1, Point2::new(1.0, 2.0), 10, 5).unwrap();
        assert_eq!(
            g.world_to_cell(Point2::new(1.0, 2.0)),
            Some(Cell::new(0, 0))
        );
        assert_eq!(g.world_to_cell(Point2::new(0.9999, 2.0)), None);
        assert_eq!(
            g.world_to_cell(Point2::new(1.95, 2.45)),
            Some(Cell::new(9, 4))
        );
        assert_eq!(g.world_to_cell(Point2::new(2.0, 2.2)), None);
        assert_eq!(g.world_to_cell(Point2::new(f64::NAN, 2.2)), None);
        let c = Cell::new(3, 4);
        assert_eq!(g.world_to_cell(g.cell_center(c)), Some(c));
        assert_eq!(g.cell_at(g.index(c).unwrap()), Some(c));
        assert_eq!(g.index(Cell::new(10, 0)), None);
        assert_eq!(g.checked_cell(-1, 0), None);
    }

    /// `world_to_cell` against the plain definition with `floor`, at points on, just
    /// beside and far from every cell boundary, and at non-finite coordinates.
    #[test]
    fn cells_are_the_floors_of_grid_coordinates() {
        let g = GridGeometry::new(0.05, Point2::new(-0.35, 0.15), 12, 7).unwrap();
        let plain = |p: Point2<f64>| {
            let (c, r) = g.world_to_grid(p);
            let (c, r) = (c.floor(), r.floor());
            (c >= 0.0 && r >= 0.0 && c < 12.0 && r < 7.0).then(|| Cell::new(c as usize, r as usize))
        };
        let mut coords: Vec<f64> = vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1e300, 1e300];
        for k in -3..16 {
            let x = f64::from(k) * 0.05;
            coords.extend([x, x.next_up(), x.next_down(), x + 0.025, -0.0 + x]);
        }
        let mut compared = 0;
        for &u in &coords {
            for &v in &coords {
                let p = Point2::new(-0.35 + u, 0.15 + v);
                assert_eq!(g.world_to_cell(p), plain(p), "{p}");
                compared += usize::from(plain(p).is_some());
            }
        }
        assert!(compared > 2_000, "{compared}");
    }

    #[test]
    fn bounding_holds_every_point() {
        let pts = [
            Point2::new(-1.23, 4.5),
            Point2::new(3.0, -2.0),
            Point2::new(f64::NAN, 0.0),
        ];
        let g = GridGeometry::bounding(pts, 0.05, 0.2).unwrap();
        for p in &pts[..2] {
            assert!(g.world_to_cell(*p).is_some());
        }
        assert!(GridGeometry::bounding([Point2::new(f64::NAN, 0.0)], 0.05, 0.0).is_err());
    }
}
