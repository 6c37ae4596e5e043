//! The distance-field difference of two maps (seed 000 III-C): how far each occupied cell of
//! one day lies from the nearest occupied cell of another day.

use haunts_occupancy::{DistanceField, distance_transform};
use haunts_occupancy::{Grid, GridGeometry, OccupancyGrid};

use crate::error::{Result, SimilarityError, rule};

/// A length given in cells or in metres, turned into cells at a map's resolution.
///
/// Seed 000 states its constants in cells of 0.05 m; `Metres` keeps them meaningful at other
/// resolutions. A conversion within 10⁻⁹ (relative) of an integer snaps to it, so that
/// `Metres(0.5)` at 0.05 m is exactly the seed's 10 cells despite decimal round-off.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Length {
    /// A number of cells, whatever the resolution.
    Cells(f64),
    /// Metres, divided by the resolution.
    Metres(f64),
}

impl Length {
    /// The length in cells of side `resolution` metres.
    ///
    /// ```
    /// use haunts_similarity::Length;
    /// assert_eq!(Length::Metres(0.5).cells(0.05), 10.0);
    /// assert_eq!(Length::Cells(10.0).cells(0.1), 10.0);
    /// ```
    pub fn cells(self, resolution: f64) -> f64 {
        match self {
            Self::Cells(c) => c,
            Self::Metres(m) => snap(m / resolution),
        }
    }
    fn value(self) -> f64 {
        match self {
            Self::Cells(v) | Self::Metres(v) => v,
        }
    }
}

/// `x`, or the nearest integer when `x` is within 10⁻⁹ (relative) of it.
pub(crate) fn snap(x: f64) -> f64 {
    let r = x.round();
    if (x - r).abs() <= 1e-9 * x.abs().max(1.0) {
        r
    } else {
        x
    }
}

/// Parameters of the distance-field difference.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct DifferenceParams {
    /// `ct`: only distances strictly greater than this are summed. Seed 000 uses 10 cells of
    /// 0.05 m, hence the default `Metres(0.5)`.
    pub cutoff: Length,
}

impl Default for DifferenceParams {
    fn default() -> Self {
        Self {
            cutoff: Length::Metres(0.5),
        }
    }
}

impl DifferenceParams {
    /// Sets the cutoff `ct`.
    pub fn with_cutoff(mut self, cutoff: Length) -> Self {
        self.cutoff = cutoff;
        self
    }

    /// The parameters after checking that the cutoff is finite and ≥ 0.
    ///
    /// # Errors
    /// [`SimilarityError::InvalidParameter`] naming `cutoff`.
    pub fn check(self) -> Result<Self> {
        let v = self.cutoff.value();
        rule(
            "cutoff",
            v,
            v.is_finite() && v >= 0.0,
            "must be finite and >= 0",
        )?;
        Ok(self)
    }
}

/// How the two directed differences of a pair of maps are combined into one number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Symmetrisation {
    /// The larger one: two maps are close only when each is close to the other (default).
    #[default]
    Max,
    /// The mean of the two.
    Mean,
    /// The smaller one.
    Min,
    /// The sum of the two.
    Sum,
}

impl Symmetrisation {
    /// The combination of `a` and `b` (symmetric in its arguments).
    pub fn combine(self, a: f64, b: f64) -> f64 {
        match self {
            Self::Max => a.max(b),
            Self::Mean => 0.5 * (a + b),
            Self::Min => a.min(b),
            Self::Sum => a + b,
        }
    }
}

/// A map ready for comparison: its distance field (`dmapX`) and its occupied cells
/// (`bmapX`), each computed once.
#[derive(Debug, Clone)]
pub struct PreparedMap {
    field: DistanceField,
    /// Row-major indices of the occupied cells, ascending.
    occupied: Vec<u32>,
}

impl PreparedMap {
    /// Prepares `map`: thresholds it to occupied cells with its own
    /// [`StateThresholds`](haunts_occupancy::StateThresholds) and computes the exact distance
    /// transform.
    ///
    /// # Errors
    /// [`SimilarityError::EmptyMap`] (index 0) when no cell is occupied;
    /// [`SimilarityError::Occupancy`] when the grid is too large for the distance transform.
    ///
    /// # Complexity
    /// O(width · height).
    pub fn new(map: &OccupancyGrid) -> Result<Self> {
        Self::from_mask(&map.occupied_mask())
    }

    /// Prepares an obstacle mask directly (`true` = occupied).
    ///
    /// # Errors
    /// As [`PreparedMap::new`].
    pub fn from_mask(mask: &Grid<bool>) -> Result<Self> {
        let occupied: Vec<u32> = mask
            .data()
            .iter()
            .enumerate()
            .filter(|(_, o)| **o)
            .map(|(i, _)| i as u32) // GridGeometry guarantees indices fit u32
            .collect();
        if occupied.is_empty() {
            return Err(SimilarityError::EmptyMap { index: 0 });
        }
        let field = distance_transform(mask)?;
        Ok(Self { field, occupied })
    }

    /// The same map with only its occupied cells inside `mask` counted as its structure (its
    /// distance field unchanged): measured against another map, structure lying where that
    /// map observed nothing is then no evidence of a difference. May count no cell.
    ///
    /// # Errors
    /// [`SimilarityError::GeometryMismatch`] (index 1) when `mask` lies on other cells.
    ///
    /// # Example
    /// ```
    /// use haunts_occupancy::{Grid, GridGeometry};
    /// use haunts_similarity::PreparedMap;
    /// let g = GridGeometry::new(1.0, nalgebra::Point2::origin(), 4, 1).unwrap();
    /// let map = PreparedMap::from_mask(&Grid::from_fn(g, |c| c.col % 2 == 0)).unwrap();
    /// let left = map.within(&Grid::from_fn(g, |c| c.col < 2)).unwrap();
    /// assert_eq!(left.occupied_indices(), &[0]);
    /// ```
    pub fn within(&self, mask: &Grid<bool>) -> Result<Self> {
        check_same(1, self.geometry(), mask.geometry())?;
        let inside = mask.data();
        let occupied = self
            .occupied
            .iter()
            .copied()
            .filter(|&i| inside[i as usize])
            .collect();
        Ok(Self {
            field: self.field.clone(),
            occupied,
        })
    }

    /// Where the map lies.
    pub fn geometry(&self) -> &GridGeometry {
        self.field.geometry()
    }
    /// The distance field `dmapX`, in cells.
    pub fn field(&self) -> &DistanceField {
        &self.field
    }
    /// Number of occupied cells.
    pub fn occupied_count(&self) -> usize {
        self.occupied.len()
    }
    /// Row-major indices of the occupied cells, ascending.
    pub fn occupied_indices(&self) -> &[u32] {
        &self.occupied
    }
}

/// Smallest integer `s` with `√s > ct`: squared distances at or above it are summed.
///
/// Squared distances are `u32`, so a cutoff of 2¹⁶ cells or more sums none of them: it
/// answers `u32::MAX + 1` at once (the search below would overflow on a huge, valid cutoff).
pub(crate) fn min_squared_above(ct: f64) -> u64 {
    if ct >= 65_536.0 {
        return u64::from(u32::MAX) + 1;
    }
    let mut s = (ct * ct).floor().max(0.0) as u64;
    while s > 0 && ((s - 1) as f64).sqrt() > ct {
        s -= 1;
    }
    while (s as f64).sqrt() <= ct {
        s += 1;
    }
    s
}

/// Σ √d² over `cells` of `field` with `d² ≥ min_sq`, in the order of `cells`.
pub(crate) fn sum_above(field: &DistanceField, cells: &[u32], min_sq: u64) -> f64 {
    let sq = field.squared_cells();
    let mut sum = 0.0;
    for &i in cells {
        let d2 = sq[i as usize];
        if u64::from(d2) >= min_sq {
            sum += f64::from(d2).sqrt();
        }
    }
    sum
}

pub(crate) fn check_same(
    index: usize,
    expected: &GridGeometry,
    found: &GridGeometry,
) -> Result<()> {
    if expected.same_cells(found, GridGeometry::SAME_CELLS_TOLERANCE) {
        Ok(())
    } else {
        Err(SimilarityError::GeometryMismatch {
            index,
            expected: Box::new(*expected),
            found: Box::new(*found),
        })
    }
}

/// `cmapXmapY` (seed 000 III-C): the sum, over the occupied cells of `y`, of the distance in
/// cells to the nearest occupied cell of `x`, counting only distances greater than `ct`.
///
/// It is zero when every wall of day `y` lies within `ct` of a wall of day `x`, and grows with
/// the length of moved structure times how far it moved (units: cells², i.e. m² / res²). It
/// is asymmetric: structure added in `y` counts here, structure removed from `x` counts in
/// `directed_difference(y, x)`.
///
/// # Errors
/// [`SimilarityError::GeometryMismatch`] (index 1) when the maps do not share cells;
/// [`SimilarityError::InvalidParameter`] for a bad cutoff.
///
/// # Complexity
/// O(occupied cells of `y`).
///
/// # Example
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry};
/// use haunts_similarity::{directed_difference, DifferenceParams, Length, PreparedMap};
/// let g = GridGeometry::new(0.05, nalgebra::Point2::origin(), 40, 40).unwrap();
/// // A wall along column 5 on day x, moved to column 25 on day y (20 cells away).
/// let x = PreparedMap::from_mask(&Grid::from_fn(g, |c| c.col == 5)).unwrap();
/// let y = PreparedMap::from_mask(&Grid::from_fn(g, |c| c.col == 25)).unwrap();
/// let params = DifferenceParams::default().with_cutoff(Length::Cells(10.0));
/// approx::assert_relative_eq!(directed_difference(&x, &y, &params).unwrap(), 40.0 * 20.0);
/// assert_eq!(directed_difference(&x, &x, &params).unwrap(), 0.0);
/// ```
pub fn directed_difference(
    x: &PreparedMap,
    y: &PreparedMap,
    params: &DifferenceParams,
) -> Result<f64> {
    let params = params.check()?;
    check_same(1, x.geometry(), y.geometry())?;
    let ct = params.cutoff.cells(x.geometry().resolution());
    Ok(sum_above(&x.field, &y.occupied, min_squared_above(ct)))
}

/// `mapXmapY` (seed 000 III-C) as a grid: at each occupied cell of `y`, the distance in cells
/// to the nearest occupied cell of `x`; zero elsewhere. No cutoff is applied.
///
/// # Errors
/// [`SimilarityError::GeometryMismatch`] (index 1) when the maps do not share cells.
pub fn difference_grid(x: &PreparedMap, y: &PreparedMap) -> Result<Grid<f64>> {
    check_same(1, x.geometry(), y.geometry())?;
    let mut out = Grid::filled(*x.geometry(), 0.0);
    let sq = x.field.squared_cells();
    for &i in &y.occupied {
        out.data_mut()[i as usize] = f64::from(sq[i as usize]).sqrt();
    }
    Ok(out)
}

/// Both directed differences of a pair of maps.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PairDifference {
    /// `cmapXmapY`: occupied cells of `y` measured in the distance field of `x`.
    pub x_to_y: f64,
    /// `cmapYmapX`: occupied cells of `x` measured in the distance field of `y`.
    pub y_to_x: f64,
}

/// Both directed differences of two occupancy maps on the same geometry.
///
/// # Errors
/// [`SimilarityError::GeometryMismatch`] when the geometries differ (index 1: the second map);
/// [`SimilarityError::EmptyMap`] naming the map (0 or 1) that has no occupied cell;
/// [`SimilarityError::InvalidParameter`] for a bad cutoff.
///
/// # Complexity
/// O(width · height) for the two distance fields.
pub fn compare(
    x: &OccupancyGrid,
    y: &OccupancyGrid,
    params: &DifferenceParams,
) -> Result<PairDifference> {
    let params = params.check()?;
    check_same(1, x.geometry(), y.geometry())?;
    let px = PreparedMap::new(x)?;
    let py = PreparedMap::new(y).map_err(|e| match e {
        SimilarityError::EmptyMap { .. } => SimilarityError::EmptyMap { index: 1 },
        e => e,
    })?;
    Ok(PairDifference {
        x_to_y: directed_difference(&px, &py, &params)?,
        y_to_x: directed_difference(&py, &px, &params)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use haunts_occupancy::{Cell, OCCUPIED};
    use nalgebra::Point2;
    use proptest::prelude::*;

    fn geom(w: usize, h: usize) -> GridGeometry {
        GridGeometry::new(0.05, Point2::origin(), w, h).unwrap()
    }

    #[test]
    fn min_squared_above_matches_definition() {
        for ct in [0.0, 0.5, 1.0, 1.5, 2.0, 9.99, 10.0, 10.0001, 37.3] {
            let s = min_squared_above(ct);
            assert!((s as f64).sqrt() > ct, "{ct}");
            assert!(s == 0 || ((s - 1) as f64).sqrt() <= ct, "{ct}");
        }
        assert_eq!(min_squared_above(10.0), 101);
        assert_eq!(min_squared_above(0.0), 1);
        // Regression: a huge cutoff (valid: finite) overflowed the search; no u32 squared
        // distance is above it.
        assert_eq!(
            min_squared_above(65_535.5),
            65_535.5f64.powi(2).floor() as u64 + 1
        );
        for ct in [65_536.0, 1e12, 1e300] {
            assert_eq!(min_squared_above(ct), u64::from(u32::MAX) + 1);
        }
    }

    #[test]
    fn cutoff_is_strict_as_in_the_seed() {
        // A single occupied cell moved by exactly 10 cells does not count at ct = 10, but does
        // at ct = 9.9.
        let g = geom(30, 5);
        let x = PreparedMap::from_mask(&Grid::from_fn(g, |c| c == Cell::new(2, 2))).unwrap();
        let y = PreparedMap::from_mask(&Grid::from_fn(g, |c| c == Cell::new(12, 2))).unwrap();
        let at = |ct| {
            directed_difference(
                &x,
                &y,
                &DifferenceParams::default().with_cutoff(Length::Cells(ct)),
            )
            .unwrap()
        };
        assert_eq!(at(10.0), 0.0);
        assert_eq!(at(9.9), 10.0);
        // Metres(0.5) at 0.05 m is exactly ct = 10.
        assert_eq!(
            directed_difference(&x, &y, &DifferenceParams::default()).unwrap(),
            0.0
        );
    }

    #[test]
    fn asymmetric_when_structure_is_added() {
        // y = x plus a far block: x→y sees the block, y→x sees nothing.
        let g = geom(60, 60);
        let wall = |c: Cell| c.col == 3;
        let x = PreparedMap::from_mask(&Grid::from_fn(g, wall)).unwrap();
        let y = PreparedMap::from_mask(&Grid::from_fn(g, |c| {
            wall(c) || (c.col == 50 && (10..20).contains(&c.row))
        }))
        .unwrap();
        let p = DifferenceParams::default();
        assert_relative_eq_f(directed_difference(&x, &y, &p).unwrap(), 47.0 * 10.0);
        assert_eq!(directed_difference(&y, &x, &p).unwrap(), 0.0);
        let grid = difference_grid(&x, &y).unwrap();
        assert_eq!(grid[Cell::new(50, 12)], 47.0);
        assert_eq!(grid[Cell::new(3, 12)], 0.0);
        assert_eq!(grid[Cell::new(20, 12)], 0.0);
    }

    fn assert_relative_eq_f(a: f64, b: f64) {
        approx::assert_relative_eq!(a, b, max_relative = 1e-12);
    }

    #[test]
    fn typed_errors_for_bad_input() {
        let g = geom(10, 10);
        let empty = OccupancyGrid::unknown(g);
        let mut one = OccupancyGrid::unknown(g);
        one.set(Cell::new(1, 1), OCCUPIED);
        let p = DifferenceParams::default();
        assert!(matches!(
            compare(&empty, &one, &p),
            Err(SimilarityError::EmptyMap { index: 0 })
        ));
        assert!(matches!(
            compare(&one, &empty, &p),
            Err(SimilarityError::EmptyMap { index: 1 })
        ));
        let other = OccupancyGrid::unknown(geom(10, 11));
        assert!(matches!(
            compare(&one, &other, &p),
            Err(SimilarityError::GeometryMismatch { index: 1, .. })
        ));
        let shifted = OccupancyGrid::unknown(
            GridGeometry::new(0.05, Point2::new(0.05, 0.0), 10, 10).unwrap(),
        );
        assert!(matches!(
            compare(&one, &shifted, &p),
            Err(SimilarityError::GeometryMismatch { .. })
        ));
        for bad in [f64::NAN, -1.0, f64::INFINITY] {
            assert!(matches!(
                compare(
                    &one,
                    &one,
                    &DifferenceParams::default().with_cutoff(Length::Cells(bad))
                ),
                Err(SimilarityError::InvalidParameter(
                    haunts_core::InvalidParameter { name: "cutoff", .. }
                ))
            ));
        }
    }

    /// Plain reference: brute-force nearest occupied cell for every occupied cell of y.
    fn brute(xm: &Grid<bool>, ym: &Grid<bool>, ct: f64) -> f64 {
        let occ = |m: &Grid<bool>| {
            m.cells()
                .filter(|(_, o)| **o)
                .map(|(c, _)| c)
                .collect::<Vec<_>>()
        };
        let (xs, ys) = (occ(xm), occ(ym));
        let mut sum = 0.0;
        for b in ys {
            let d = xs
                .iter()
                .map(|a| {
                    let dc = a.col as f64 - b.col as f64;
                    let dr = a.row as f64 - b.row as f64;
                    (dc * dc + dr * dr).sqrt()
                })
                .fold(f64::INFINITY, f64::min);
            if d > ct {
                sum += d;
            }
        }
        sum
    }

    proptest! {
        #[test]
        fn equals_brute_force(
            w in 1usize..20, h in 1usize..20,
            bits_x in proptest::collection::vec(proptest::bool::weighted(0.1), 400),
            bits_y in proptest::collection::vec(proptest::bool::weighted(0.1), 400),
            ct in 0.0f64..8.0,
        ) {
            let g = geom(w, h);
            let mut xm = Grid::from_fn(g, |c| bits_x[c.row * 20 + c.col]);
            let ym = Grid::from_fn(g, |c| bits_y[c.row * 20 + c.col]);
            xm.data_mut()[0] = true;
            prop_assume!(ym.data().contains(&true));
            let x = PreparedMap::from_mask(&xm).unwrap();
            let y = PreparedMap::from_mask(&ym).unwrap();
            let got = directed_difference(&x, &y, &DifferenceParams::default().with_cutoff(Length::Cells(ct))).unwrap();
            let want = brute(&xm, &ym, ct);
            prop_assert!((got - want).abs() <= 1e-9 * want.max(1.0), "{got} vs {want}");
        }
    }
}
