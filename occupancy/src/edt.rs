//! Exact Euclidean distance transform (Felzenszwalb & Huttenlocher 2012), with the nearest
//! obstacle of every cell.

use crate::{Cell, Grid, GridGeometry, OccupancyError, Result};

/// Distances from every cell to the nearest obstacle cell of a mask.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceField {
    geometry: GridGeometry,
    squared: Vec<u32>,
    nearest: Option<Vec<u32>>,
}

impl DistanceField {
    /// Where the field lies.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// Squared distances in cells², row-major (row 0 at the bottom). Exact integers.
    pub fn squared_cells(&self) -> &[u32] {
        &self.squared
    }
    /// Per cell, row-major, the row-major index of its nearest obstacle cell, when computed
    /// with [`distance_transform_with_nearest`]: [`DistanceField::nearest`] without the
    /// division that turns an index into a cell.
    pub fn nearest_indices(&self) -> Option<&[u32]> {
        self.nearest.as_deref()
    }
    /// Distance from `cell` to the nearest obstacle, in cells (`None` outside the grid).
    pub fn distance_cells(&self, cell: Cell) -> Option<f64> {
        self.geometry
            .index(cell)
            .map(|i| f64::from(self.squared[i]).sqrt())
    }
    /// Distance from `cell` to the nearest obstacle, in metres.
    pub fn distance_metres(&self, cell: Cell) -> Option<f64> {
        self.distance_cells(cell)
            .map(|d| d * self.geometry.resolution())
    }
    /// The nearest obstacle cell of `cell`, when computed with
    /// [`distance_transform_with_nearest`] (ties broken by the lower column, then the lower row).
    pub fn nearest(&self, cell: Cell) -> Option<Cell> {
        let i = self.geometry.index(cell)?;
        self.nearest
            .as_ref()
            .and_then(|n| self.geometry.cell_at(n[i] as usize))
    }
    /// Distances in cells as a grid.
    pub fn cells_grid(&self) -> Grid<f64> {
        self.scaled_grid(1.0)
    }
    /// Distances in metres as a grid.
    pub fn metres_grid(&self) -> Grid<f64> {
        self.scaled_grid(self.geometry.resolution())
    }
    fn scaled_grid(&self, scale: f64) -> Grid<f64> {
        let mut i = 0;
        Grid::from_fn(self.geometry, |_| {
            let d = f64::from(self.squared[i]).sqrt() * scale;
            i += 1;
            d
        })
    }
}

/// The exact Euclidean distance transform of `mask` (`true` = obstacle): for every cell the
/// distance to the nearest obstacle cell centre, as `scipy.ndimage.distance_transform_edt`
/// computes for `~mask` (Felzenszwalb & Huttenlocher 2012).
///
/// Two separable passes: a vertical pass finds, per column, the distance to the nearest
/// obstacle in that column; a horizontal pass takes, per row, the lower envelope of the
/// parabolas `(x − q)² + g(q)²`. Squared distances are integers and computed exactly (the
/// parabolas' crossings are compared on cross-multiplied integers, never divided). Both
/// passes run block of rows by block of rows, the vertical one starting from each column's
/// nearest obstacles below and above the block (found by a first sweep over the mask), so a
/// block's rows are still in cache for the horizontal pass and no intermediate grid is
/// stored; with the `rayon` feature the blocks run in parallel, with the same result.
///
/// # Errors
/// [`OccupancyError::EmptyMask`] when no cell is an obstacle (distances are undefined);
/// [`OccupancyError::BadGridSize`] when squared distances could exceed `u32`
/// (`(w−1)² + (h−1)² > 2³² − 1`, sides beyond ≈ 46 000 cells).
///
/// # Complexity
/// O(width · height) time and memory.
///
/// # Example
/// ```
/// use haunts_occupancy::{distance_transform, Cell, Grid, GridGeometry};
/// let g = GridGeometry::new(0.5, nalgebra::Point2::origin(), 5, 4).unwrap();
/// let mask = Grid::from_fn(g, |c| c == Cell::new(0, 0));
/// let field = distance_transform(&mask).unwrap();
/// approx::assert_relative_eq!(field.distance_cells(Cell::new(3, 4 - 1)).unwrap(), 18f64.sqrt());
/// approx::assert_relative_eq!(field.distance_metres(Cell::new(4, 0)).unwrap(), 2.0);
/// ```
pub fn distance_transform(mask: &Grid<bool>) -> Result<DistanceField> {
    transform(mask, false)
}

/// [`distance_transform`], also recording each cell's nearest obstacle cell.
///
/// # Errors
/// As [`distance_transform`].
pub fn distance_transform_with_nearest(mask: &Grid<bool>) -> Result<DistanceField> {
    transform(mask, true)
}

const FAR: u32 = u32::MAX;

fn transform(mask: &Grid<bool>, with_nearest: bool) -> Result<DistanceField> {
    transform_in_blocks(mask, with_nearest, ROWS_PER_TASK)
}

/// Rows per parallel task: each task runs the vertical pass of its rows (from the summaries
/// of the other blocks) and then the horizontal pass, while its rows are in cache.
const ROWS_PER_TASK: usize = 32;

fn transform_in_blocks(
    mask: &Grid<bool>,
    with_nearest: bool,
    rows_per_task: usize,
) -> Result<DistanceField> {
    let geometry = *mask.geometry();
    let (w, h) = (geometry.width(), geometry.height());
    let diag = ((w - 1) as u64).pow(2) + ((h - 1) as u64).pow(2);
    if diag > u64::from(u32::MAX - 1) {
        return Err(OccupancyError::BadGridSize {
            width: w,
            height: h,
        });
    }
    if !mask.data().contains(&true) {
        return Err(OccupancyError::EmptyMask);
    }
    let columns = ColumnObstacles::new(mask.data(), w, h, rows_per_task);
    let mut squared = vec![0u32; w * h];
    let mut nearest = with_nearest.then(|| vec![0u32; w * h]);
    let block = w * rows_per_task;
    let mut nearest_blocks = nearest.as_deref_mut().map(|n| n.chunks_mut(block));
    let tasks: Vec<_> = squared
        .chunks_mut(block)
        .enumerate()
        .map(|(b, out)| (b, out, nearest_blocks.as_mut().and_then(Iterator::next)))
        .collect();
    in_parallel(tasks, |(b, out, nearest)| {
        let first_row = b * rows_per_task;
        let rows = first_row..first_row + out.len() / w;
        let mask = &mask.data()[rows.start * w..rows.end * w];
        block_transform(mask, w, rows, &columns, b, out, nearest);
    });
    Ok(DistanceField {
        geometry,
        squared,
        nearest,
    })
}

/// `f` over every task, in parallel with the `rayon` feature; results in task order.
fn in_parallel<T: Send, R: Send>(tasks: Vec<T>, f: impl Fn(T) -> R + Sync + Send) -> Vec<R> {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        tasks.into_par_iter().map(f).collect()
    }
    #[cfg(not(feature = "rayon"))]
    tasks.into_iter().map(f).collect()
}

/// No obstacle: the row of `below` / `above` when a column has none on that side.
const NONE: u32 = u32::MAX;

/// Per block of rows and column, the nearest obstacle row below the block and above it.
struct ColumnObstacles {
    w: usize,
    /// Block-major: the highest obstacle row under block `b`'s first row (`NONE` if none).
    below: Vec<u32>,
    /// Block-major: the lowest obstacle row past block `b`'s last row (`NONE` if none).
    above: Vec<u32>,
}

impl ColumnObstacles {
    fn new(mask: &[bool], w: usize, h: usize, rows_per_task: usize) -> Self {
        // Per block, its own lowest and highest obstacle row of every column.
        let blocks = in_parallel((0..h).step_by(rows_per_task).collect(), |first| {
            let (mut lowest, mut highest) = (vec![NONE; w], vec![NONE; w]);
            for r in (first..(first + rows_per_task).min(h)).rev() {
                for (l, &m) in lowest.iter_mut().zip(&mask[r * w..(r + 1) * w]) {
                    *l = if m { r as u32 } else { *l };
                }
            }
            for r in first..(first + rows_per_task).min(h) {
                for (u, &m) in highest.iter_mut().zip(&mask[r * w..(r + 1) * w]) {
                    *u = if m { r as u32 } else { *u };
                }
            }
            (lowest, highest)
        });
        let n = blocks.len();
        let (mut below, mut above) = (vec![NONE; n * w], vec![NONE; n * w]);
        for b in 1..n {
            let (done, rest) = below.split_at_mut(b * w);
            let prev = &done[(b - 1) * w..];
            for ((out, &p), &hi) in rest[..w].iter_mut().zip(prev).zip(&blocks[b - 1].1) {
                *out = if hi == NONE { p } else { hi };
            }
        }
        for b in (0..n.saturating_sub(1)).rev() {
            let (head, tail) = above.split_at_mut((b + 1) * w);
            let next = &tail[..w];
            for ((out, &p), &lo) in head[b * w..].iter_mut().zip(next).zip(&blocks[b + 1].0) {
                *out = if lo == NONE { p } else { lo };
            }
        }
        Self { w, below, above }
    }
}

/// Both passes over the rows `rows` (mask rows `mask`, output rows `out`): the vertical pass
/// sweeps up from the obstacles below the block (storing each cell's distance down to its
/// column's nearest obstacle in `out`, and that obstacle's row in `nearest`), then down from
/// the obstacles above it, row by row, each row then taking its horizontal pass.
fn block_transform(
    mask: &[bool],
    w: usize,
    rows: std::ops::Range<usize>,
    columns: &ColumnObstacles,
    b: usize,
    out: &mut [u32],
    mut nearest: Option<&mut [u32]>,
) {
    let mut last = columns.below[b * columns.w..(b + 1) * columns.w].to_vec();
    for (k, r) in rows.clone().enumerate() {
        let m = &mask[k * w..(k + 1) * w];
        let r32 = r as u32;
        for ((l, o), &m) in last.iter_mut().zip(&mut out[k * w..(k + 1) * w]).zip(m) {
            *l = if m { r32 } else { *l };
            *o = if *l == NONE { FAR } else { r32 - *l };
        }
        if let Some(n) = nearest.as_deref_mut() {
            n[k * w..(k + 1) * w].copy_from_slice(&last);
        }
    }
    let mut next = columns.above[b * columns.w..(b + 1) * columns.w].to_vec();
    let mut g = vec![FAR; w];
    let mut g_rows = vec![0u32; if nearest.is_some() { w } else { 0 }];
    let mut chosen = g_rows.clone();
    let mut envelope = Envelope::new(w);
    for (k, r) in rows.enumerate().rev() {
        let m = &mask[k * w..(k + 1) * w];
        let r32 = r as u32;
        let out_row = &mut out[k * w..(k + 1) * w];
        for ((nx, gv), (&m, &down)) in next.iter_mut().zip(&mut g).zip(m.iter().zip(&*out_row)) {
            *nx = if m { r32 } else { *nx };
            let up = if *nx == NONE { FAR } else { *nx - r32 };
            // Ties go to the obstacle below (the lower row).
            *gv = down.min(up);
        }
        match nearest.as_deref_mut() {
            None => envelope.row(&g, out_row, None),
            Some(n) => {
                let n_row = &mut n[k * w..(k + 1) * w];
                for (((gr, &below), &above), &gv) in
                    g_rows.iter_mut().zip(&*n_row).zip(&next).zip(&g)
                {
                    let down = if below == NONE { FAR } else { r32 - below };
                    *gr = if down == gv { below } else { above };
                }
                envelope.row(&g, out_row, Some(&mut chosen));
                for (n, &v) in n_row.iter_mut().zip(&chosen) {
                    *n = g_rows[v as usize] * w as u32 + v;
                }
            }
        }
    }
}

/// Scratch space for the lower envelope of one row's parabolas.
struct Envelope {
    /// The envelope's sites (columns), left to right.
    sites: Vec<i64>,
    /// `f(site) = g(site)² + site²`.
    f: Vec<i64>,
}

impl Envelope {
    fn new(w: usize) -> Self {
        Self {
            sites: Vec::with_capacity(w),
            f: Vec::with_capacity(w),
        }
    }

    /// Squared distances of one row from its column distances `g` (`FAR` = no obstacle in
    /// that column); with `chosen`, the column of each cell's nearest obstacle.
    ///
    /// The parabolas of sites `u < v` cross at `s(u, v) = (f(v) − f(u)) / (2(v − u))`; every
    /// comparison of crossings is done on the cross-multiplied integers, so it is exact (and
    /// there is no division).
    fn row(&mut self, g: &[u32], out: &mut [u32], mut chosen: Option<&mut [u32]>) {
        self.sites.clear();
        self.f.clear();
        for (q, &gq) in g.iter().enumerate() {
            if gq == FAR {
                continue;
            }
            let q = q as i64;
            let fq = i64::from(gq) * i64::from(gq) + q * q;
            // Pop v while the parabola of q hides it: s(v, q) <= s(u, v).
            while let (&[.., u, v], &[.., fu, fv]) = (&self.sites[..], &self.f[..]) {
                if (fq - fv) * (v - u) > (fv - fu) * (q - v) {
                    break;
                }
                self.sites.pop();
                self.f.pop();
            }
            self.sites.push(q);
            self.f.push(fq);
        }
        // The mask is not empty, so every row has at least one site.
        let last = self.sites.len().saturating_sub(1);
        let mut k = 0;
        for (q, o) in out.iter_mut().enumerate() {
            let q = q as i64;
            // Move right while s(k, k + 1) < q (at a tie the left site stays).
            while k < last
                && self.f[k + 1] - self.f[k] < 2 * q * (self.sites[k + 1] - self.sites[k])
            {
                k += 1;
            }
            let v = self.sites[k];
            *o = ((q - v) * (q - v) + self.f[k] - v * v) as u32;
            if let Some(c) = chosen.as_deref_mut() {
                c[q as usize] = v as u32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;
    use proptest::prelude::*;

    /// Plain reference: the minimum over every obstacle cell.
    fn brute_force(mask: &Grid<bool>) -> Vec<u32> {
        let obstacles: Vec<Cell> = mask.cells().filter(|(_, m)| **m).map(|(c, _)| c).collect();
        mask.cells()
            .map(|(c, _)| {
                obstacles
                    .iter()
                    .map(|o| (c.col.abs_diff(o.col).pow(2) + c.row.abs_diff(o.row).pow(2)) as u32)
                    .min()
                    .unwrap()
            })
            .collect()
    }

    fn mask() -> impl Strategy<Value = Grid<bool>> {
        (1usize..200, 1usize..30, 0.0f64..0.3).prop_flat_map(|(w, h, density)| {
            proptest::collection::vec(proptest::bool::weighted(density.max(0.001)), w * h)
                .prop_filter_map("needs an obstacle", move |v| {
                    let g = GridGeometry::new(0.1, Point2::origin(), w, h).unwrap();
                    v.contains(&true).then(|| Grid::from_vec(g, v).unwrap())
                })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        // Widths past 64 columns split the vertical pass into several strips.
        #[test]
        fn equals_brute_force_and_nearest_is_an_obstacle_at_that_distance(mask in mask()) {
            let reference = brute_force(&mask);
            let plain = distance_transform(&mask).unwrap();
            prop_assert_eq!(plain.squared_cells(), &reference[..]);
            let with = distance_transform_with_nearest(&mask).unwrap();
            prop_assert_eq!(with.squared_cells(), &reference[..]);
            for (cell, _) in mask.cells() {
                let n = with.nearest(cell).unwrap();
                prop_assert!(mask[n], "nearest {:?} of {:?} is not an obstacle", n, cell);
                let d2 = (cell.col.abs_diff(n.col).pow(2) + cell.row.abs_diff(n.row).pow(2)) as u32;
                let i = mask.geometry().index(cell).unwrap();
                prop_assert_eq!(d2, reference[i]);
                let flat = with.nearest_indices().unwrap()[i] as usize;
                prop_assert_eq!(Some(flat), mask.geometry().index(n));
            }
            prop_assert!(plain.nearest(Cell::new(0, 0)).is_none());
            prop_assert!(plain.nearest_indices().is_none());
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        // Blocks of a few rows: the vertical pass crosses block boundaries both ways.
        #[test]
        fn small_blocks_give_the_same_field(mask in mask(), rows in 1usize..8) {
            let whole = distance_transform_with_nearest(&mask).unwrap();
            let blocks = transform_in_blocks(&mask, true, rows).unwrap();
            prop_assert_eq!(&blocks, &whole);
            let plain = transform_in_blocks(&mask, false, rows).unwrap();
            prop_assert_eq!(plain.squared_cells(), whole.squared_cells());
        }
    }

    #[test]
    fn ties_go_to_the_lower_column_then_the_lower_row() {
        // Cell (1, 1) is 1 from all four obstacles around it.
        let g = GridGeometry::new(0.1, Point2::origin(), 3, 3).unwrap();
        let mask = Grid::from_fn(g, |c| (c.col + c.row) % 2 == 1);
        let field = distance_transform_with_nearest(&mask).unwrap();
        assert_eq!(field.nearest(Cell::new(1, 1)), Some(Cell::new(0, 1)));
        // Two obstacles in its own column only.
        let mask = Grid::from_fn(g, |c| c.col == 1 && c.row != 1);
        let field = distance_transform_with_nearest(&mask).unwrap();
        assert_eq!(field.nearest(Cell::new(1, 1)), Some(Cell::new(1, 0)));
    }

    #[test]
    fn empty_mask_is_an_error() {
        let g = GridGeometry::new(0.1, Point2::origin(), 3, 3).unwrap();
        assert!(matches!(
            distance_transform(&Grid::filled(g, false)),
            Err(OccupancyError::EmptyMask)
        ));
    }

    #[test]
    fn metres_scale_with_resolution() {
        let g = GridGeometry::new(0.05, Point2::origin(), 4, 1).unwrap();
        let f = distance_transform(&Grid::from_fn(g, |c| c.col == 0)).unwrap();
        assert_eq!(
            f.metres_grid().data(),
            &[0.0, 0.05, 0.1, 0.15000000000000002]
        );
        assert_eq!(f.cells_grid().data(), &[0.0, 1.0, 2.0, 3.0]);
    }
}
