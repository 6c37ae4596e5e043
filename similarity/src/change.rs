//! Local change detection: which square regions of a map changed between two days, by the
//! same distance-field measure per region (seed 000's future work).

use haunts_occupancy::{Cell, GridGeometry};
use nalgebra::Point2;

use crate::cluster::LayoutThreshold;
use crate::difference::{
    DifferenceParams, Length, PreparedMap, Symmetrisation, check_same, min_squared_above, snap,
};
use crate::error::{Result, rule};

/// Parameters of local change detection.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ChangeParams {
    /// Side of a square region (default 1 m; rounded to whole cells, at least 1).
    pub region: Length,
    /// The per-cell measure (`ct`).
    pub difference: DifferenceParams,
    /// A region changed when its combined difference is non-zero and at least this (default
    /// 0.1 m²: e.g. 20 cm of wall moved by 0.5 m, or 40 cells of 0.05 m moved by 10 cells).
    /// [`LayoutThreshold::PerOccupiedCell`] divides by the occupied cells of the measured map
    /// inside the region.
    pub threshold: LayoutThreshold,
    /// How the two directions are combined (default: the larger, so that both added and
    /// removed structure count).
    pub symmetrisation: Symmetrisation,
}

impl Default for ChangeParams {
    fn default() -> Self {
        Self {
            region: Length::Metres(1.0),
            difference: DifferenceParams::default(),
            threshold: LayoutThreshold::SquareMetres(0.1),
            symmetrisation: Symmetrisation::Max,
        }
    }
}

impl ChangeParams {
    /// Sets the region side.
    pub fn with_region(mut self, region: Length) -> Self {
        self.region = region;
        self
    }
    /// Sets the threshold.
    pub fn with_threshold(mut self, threshold: LayoutThreshold) -> Self {
        self.threshold = threshold;
        self
    }
    /// The parameters after checking each rule.
    ///
    /// # Errors
    /// [`crate::SimilarityError::InvalidParameter`] for a region side that is not finite and
    /// positive, a bad cutoff or a bad threshold.
    pub fn check(self) -> Result<Self> {
        let r = match self.region {
            Length::Cells(v) | Length::Metres(v) => v,
        };
        rule(
            "region",
            r,
            r.is_finite() && r > 0.0,
            "must be finite and > 0",
        )?;
        self.difference.check()?;
        crate::ClusterParams::default()
            .with_threshold(self.threshold)
            .check()?;
        Ok(self)
    }
}

/// The difference inside one region.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RegionChange {
    /// Region column (regions counted from the grid's lower-left corner).
    pub col: usize,
    /// Region row.
    pub row: usize,
    /// `cmapXmapY` restricted to the occupied cells of `y` in the region, cells².
    pub x_to_y: f64,
    /// `cmapYmapX` restricted to the occupied cells of `x` in the region, cells².
    pub y_to_x: f64,
    /// Whether the region counts as changed.
    pub changed: bool,
}

/// Every region's difference between two maps.
///
/// With the `serde` feature it (de)serialises as `geometry`, `side` (cells) and `regions`,
/// and deserialising checks that the regions tile the grid in row-major order.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "RegionChangesFields"))]
pub struct RegionChanges {
    geometry: GridGeometry,
    side: usize,
    /// `geometry.width().div_ceil(side)`, not serialised.
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    cols: usize,
    regions: Vec<RegionChange>,
}

impl RegionChanges {
    /// Side of a region, in cells.
    pub fn region_cells(&self) -> usize {
        self.side
    }
    /// Regions per row of regions.
    pub fn cols(&self) -> usize {
        self.cols
    }
    /// Every region, row-major from the lower-left one.
    pub fn regions(&self) -> &[RegionChange] {
        &self.regions
    }
    /// The regions that changed.
    pub fn changed(&self) -> impl Iterator<Item = &RegionChange> + '_ {
        self.regions.iter().filter(|r| r.changed)
    }
    /// The world rectangle (lower-left, upper-right corners) of region `(col, row)`, clipped to
    /// the grid.
    pub fn bounds(&self, col: usize, row: usize) -> (Point2<f64>, Point2<f64>) {
        let g = &self.geometry;
        let lo = g.cell_center(Cell::new(
            col.saturating_mul(self.side),
            row.saturating_mul(self.side),
        )) - nalgebra::Vector2::repeat(0.5 * g.resolution());
        let hi = Point2::new(
            (lo.x + (self.side as f64) * g.resolution()).min(g.upper_corner().x),
            (lo.y + (self.side as f64) * g.resolution()).min(g.upper_corner().y),
        );
        (lo, hi)
    }
}

/// The fields of a [`RegionChanges`] as deserialised, before the tiling is checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct RegionChangesFields {
    geometry: GridGeometry,
    side: usize,
    regions: Vec<RegionChange>,
}

#[cfg(feature = "serde")]
impl TryFrom<RegionChangesFields> for RegionChanges {
    type Error = crate::SimilarityError;
    fn try_from(f: RegionChangesFields) -> Result<Self> {
        let g = f.geometry;
        rule("side", f.side as f64, f.side >= 1, "must be >= 1")?;
        let cols = g.width().div_ceil(f.side);
        let rows = g.height().div_ceil(f.side);
        if f.regions.len() != cols * rows {
            return Err(crate::SimilarityError::LengthMismatch {
                what: "regions vs regions of the grid",
                left: f.regions.len(),
                right: cols * rows,
            });
        }
        for (k, r) in f.regions.iter().enumerate() {
            rule(
                "regions.col",
                r.col as f64,
                r.col == k % cols,
                "must be the region's column in row-major order",
            )?;
            rule(
                "regions.row",
                r.row as f64,
                r.row == k / cols,
                "must be the region's row in row-major order",
            )?;
            for (name, v) in [("regions.x_to_y", r.x_to_y), ("regions.y_to_x", r.y_to_x)] {
                rule(
                    name,
                    v,
                    v.is_finite() && v >= 0.0,
                    "must be finite and >= 0",
                )?;
            }
        }
        Ok(Self {
            geometry: g,
            side: f.side,
            cols,
            regions: f.regions,
        })
    }
}

/// Divides the grid into square regions and measures, in each, the distance-field difference
/// of the occupied cells that fall inside it (distances are taken in the whole other map, so a
/// wall that moved across a region border is measured correctly).
///
/// # Errors
/// [`crate::SimilarityError::GeometryMismatch`] when the maps do not share cells;
/// [`crate::SimilarityError::InvalidParameter`] for bad parameters.
///
/// # Complexity
/// O(occupied cells of both maps + regions).
///
/// # Example
/// ```
/// use haunts_occupancy::{Grid, GridGeometry};
/// use haunts_similarity::{local_changes, ChangeParams, PreparedMap};
/// let g = GridGeometry::new(0.05, nalgebra::Point2::origin(), 80, 80).unwrap(); // 4 m × 4 m
/// let wall = |c: haunts_occupancy::Cell| c.row == 0;
/// let x = PreparedMap::from_mask(&Grid::from_fn(g, |c| wall(c) || (c.col == 10 && c.row < 60))).unwrap();
/// let y = PreparedMap::from_mask(&Grid::from_fn(g, |c| wall(c) || (c.col == 70 && c.row < 60))).unwrap();
/// let changes = local_changes(&x, &y, &ChangeParams::default()).unwrap();
/// // A cabinet moved from x = 0.5 m to x = 3.5 m: the regions of columns 0 and 3 changed.
/// let cols: std::collections::BTreeSet<usize> = changes.changed().map(|r| r.col).collect();
/// assert_eq!(cols.into_iter().collect::<Vec<_>>(), vec![0, 3]);
/// ```
pub fn local_changes(
    x: &PreparedMap,
    y: &PreparedMap,
    params: &ChangeParams,
) -> Result<RegionChanges> {
    let params = params.check()?;
    check_same(1, x.geometry(), y.geometry())?;
    let g = *x.geometry();
    let res = g.resolution();
    let side = (params.region.cells(res).round() as usize).max(1);
    let cols = g.width().div_ceil(side);
    let rows = g.height().div_ceil(side);
    let min_sq = min_squared_above(params.difference.cutoff.cells(res));
    let region_of = |i: u32| {
        let i = i as usize;
        (i / g.width() / side) * cols + (i % g.width()) / side
    };
    // Per region: (sum, occupied count) in each direction.
    let tally = |field: &PreparedMap, measured: &PreparedMap| {
        let mut sums = vec![(0.0f64, 0usize); cols * rows];
        let sq = field.field().squared_cells();
        for &i in measured.occupied_indices() {
            let slot = &mut sums[region_of(i)];
            slot.1 += 1;
            let d2 = sq[i as usize];
            if u64::from(d2) >= min_sq {
                slot.0 += f64::from(d2).sqrt();
            }
        }
        sums
    };
    let xy = tally(x, y);
    let yx = tally(y, x);
    let res2 = res * res;
    let (limit, scale): (f64, Box<dyn Fn(f64, usize) -> f64>) = match params.threshold {
        LayoutThreshold::Cells(v) => (v, Box::new(|s, _| s)),
        LayoutThreshold::SquareMetres(v) => (snap(v / res2), Box::new(|s, _| s)),
        LayoutThreshold::PerOccupiedCell(v) => (v, Box::new(|s, n| s / n.max(1) as f64)),
    };
    let regions = (0..cols * rows)
        .map(|k| {
            let (a, b) = (xy[k], yx[k]);
            let combined = params
                .symmetrisation
                .combine(scale(a.0, a.1), scale(b.0, b.1));
            RegionChange {
                col: k % cols,
                row: k / cols,
                x_to_y: a.0,
                y_to_x: b.0,
                changed: combined > 0.0 && combined >= limit,
            }
        })
        .collect();
    Ok(RegionChanges {
        geometry: g,
        side,
        cols,
        regions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SimilarityError;
    use haunts_occupancy::Grid;

    fn geom() -> GridGeometry {
        GridGeometry::new(0.05, Point2::new(-2.0, 1.0), 100, 60).unwrap()
    }

    #[test]
    fn only_the_regions_where_furniture_moved_change() {
        let g = geom();
        let walls = |c: Cell| c.col == 0 || c.row == 0 || c.col == 99 || c.row == 59;
        // A table at cols 25..35, row 30 moves to row 45 (15 cells); a shelf at col 70 stays.
        let table = |row: usize| move |c: Cell| c.row == row && (25..35).contains(&c.col);
        let shelf = |c: Cell| c.col == 70 && (10..30).contains(&c.row);
        let x = PreparedMap::from_mask(&Grid::from_fn(g, |c| walls(c) || table(30)(c) || shelf(c)))
            .unwrap();
        let y = PreparedMap::from_mask(&Grid::from_fn(g, |c| walls(c) || table(45)(c) || shelf(c)))
            .unwrap();
        let changes = local_changes(&x, &y, &ChangeParams::default()).unwrap();
        assert_eq!(changes.region_cells(), 20);
        assert_eq!(changes.cols(), 5);
        assert_eq!(changes.regions().len(), 15);
        let changed: Vec<(usize, usize)> = changes.changed().map(|r| (r.col, r.row)).collect();
        // Old place: region (1, 1) (rows 20..40); new place: region (1, 2) (rows 40..60).
        assert_eq!(changed, vec![(1, 1), (1, 2)]);
        let old = changes.regions()[5 + 1];
        assert_eq!(old.x_to_y, 0.0);
        assert_eq!(old.y_to_x, 10.0 * 15.0); // table cells of x, 15 cells from y's table
        let (lo, hi) = changes.bounds(1, 2);
        approx::assert_relative_eq!(lo, Point2::new(-1.0, 3.0), epsilon = 1e-12);
        approx::assert_relative_eq!(hi, Point2::new(0.0, 4.0), epsilon = 1e-12);
    }

    #[test]
    fn identical_maps_change_nowhere_and_bad_input_is_typed() {
        let g = geom();
        let m = PreparedMap::from_mask(&Grid::from_fn(g, |c| c.row == 3)).unwrap();
        let changes = local_changes(&m, &m, &ChangeParams::default()).unwrap();
        assert_eq!(changes.changed().count(), 0);
        assert!(matches!(
            local_changes(
                &m,
                &m,
                &ChangeParams::default().with_region(Length::Metres(0.0))
            ),
            Err(SimilarityError::InvalidParameter(
                haunts_core::InvalidParameter { name: "region", .. }
            ))
        ));
        let other = PreparedMap::from_mask(&Grid::from_fn(
            GridGeometry::new(0.05, Point2::origin(), 100, 60).unwrap(),
            |c| c.row == 3,
        ))
        .unwrap();
        assert!(matches!(
            local_changes(&m, &other, &ChangeParams::default()),
            Err(SimilarityError::GeometryMismatch { .. })
        ));
    }
}
