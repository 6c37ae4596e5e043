//! Exact Euclidean distance transform (Felzenszwalb & Huttenlocher 2012), with the nearest
//! obstacle of every cell.
//!
//! Two separable passes: a vertical pass finds, per column, the distance to the nearest
//! obstacle in that column; a horizontal pass takes, per row, the lower envelope of the
//! parabolas `(x − q)² + g(q)²`. Squared distances are integers and computed exactly. With
//! the `rayon` feature the first pass runs over column strips and the second over blocks of
//! rows in parallel, with the same result.

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
    /// [`distance_transform_with_nearest`] (ties broken by the lower row, then column).
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
/// computes for `~mask`.
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
/// use haunts_occupancy::{edt::distance_transform, Cell, Grid, GridGeometry};
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
    let strip_width = w.div_ceil(STRIPS).max(MIN_STRIP_WIDTH);
    let strips = in_parallel((0..w).step_by(strip_width).collect(), |start| {
        vertical_pass(
            mask.data(),
            w,
            h,
            start..(start + strip_width).min(w),
            with_nearest,
        )
    });
    let mut squared = vec![0u32; w * h];
    let mut nearest = with_nearest.then(|| vec![0u32; w * h]);
    horizontal_pass(&strips, &mut squared, nearest.as_deref_mut(), w);
    Ok(DistanceField {
        geometry,
        squared,
        nearest,
    })
}

/// Column strips of the vertical pass (a few per thread, for balance).
const STRIPS: usize = 16;
/// Narrowest strip: wide enough for the row sweeps to vectorise.
const MIN_STRIP_WIDTH: usize = 64;
/// Rows per parallel task of the horizontal pass.
const ROWS_PER_TASK: usize = 32;

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

/// The vertical pass over some columns, stored strip-major (`h` rows of `cols.len()`).
struct Strip {
    cols: std::ops::Range<usize>,
    /// Per cell, the distance in rows to the nearest obstacle of its column (`FAR` if none).
    g: Vec<u32>,
    /// Per cell, that obstacle's row, when nearest obstacles are wanted.
    rows: Option<Vec<u32>>,
}

/// Sweeps the rows of the strip `cols` down and up, so the inner loops vectorise.
fn vertical_pass(
    mask: &[bool],
    w: usize,
    h: usize,
    cols: std::ops::Range<usize>,
    with_rows: bool,
) -> Strip {
    let sw = cols.len();
    let mut g = vec![FAR; sw * h];
    let mut rows = with_rows.then(|| vec![0u32; sw * h]);
    for r in 0..h {
        let m = &mask[r * w + cols.start..r * w + cols.end];
        let (done, rest) = g.split_at_mut(r * sw);
        let prev = done.get(done.len().saturating_sub(sw)..).filter(|_| r > 0);
        for (c, (&o, cur)) in m.iter().zip(&mut rest[..sw]).enumerate() {
            *cur = if o {
                0
            } else {
                prev.map_or(FAR, |p| p[c].saturating_add(1))
            };
        }
        if let Some(rows) = rows.as_mut() {
            let (done, rest) = rows.split_at_mut(r * sw);
            let prev = done.get(done.len().saturating_sub(sw)..).filter(|_| r > 0);
            for (c, (&o, out)) in m.iter().zip(&mut rest[..sw]).enumerate() {
                *out = if o {
                    r as u32
                } else {
                    prev.map_or(0, |p| p[c])
                };
            }
        }
    }
    for r in (0..h.saturating_sub(1)).rev() {
        let (head, tail) = g.split_at_mut((r + 1) * sw);
        let cur = &mut head[r * sw..];
        let below = &tail[..sw];
        match rows.as_mut() {
            None => {
                for (c, &b) in cur.iter_mut().zip(below) {
                    *c = (*c).min(b.saturating_add(1));
                }
            }
            Some(rows) => {
                let (rows_head, rows_tail) = rows.split_at_mut((r + 1) * sw);
                let rows_cur = rows_head[r * sw..].iter_mut().zip(&rows_tail[..sw]);
                for ((c, &b), (row, &row_below)) in cur.iter_mut().zip(below).zip(rows_cur) {
                    let up = b.saturating_add(1);
                    if up < *c {
                        *c = up;
                        *row = row_below;
                    }
                }
            }
        }
    }
    Strip { cols, g, rows }
}

/// Per row, squared distances from the strips' column distances; with `nearest`, also the
/// flat index of each cell's nearest obstacle.
fn horizontal_pass(strips: &[Strip], out: &mut [u32], nearest: Option<&mut [u32]>, w: usize) {
    let block = w * ROWS_PER_TASK;
    let mut nearest_blocks = nearest.map(|n| n.chunks_mut(block));
    let tasks: Vec<_> = out
        .chunks_mut(block)
        .enumerate()
        .map(|(i, o)| {
            (
                i * ROWS_PER_TASK,
                o,
                nearest_blocks.as_mut().and_then(Iterator::next),
            )
        })
        .collect();
    in_parallel(tasks, |(first_row, out_block, nearest_block)| {
        let mut envelope = Envelope::new(w);
        let mut g = vec![FAR; w];
        let wanted = nearest_block.is_some();
        let mut chosen = vec![0u32; if wanted { w } else { 0 }];
        let mut g_rows = wanted.then(|| vec![0u32; w]);
        let mut nearest_rows = nearest_block.map(|n| n.chunks_mut(w));
        for (k, out_row) in out_block.chunks_mut(w).enumerate() {
            let r = first_row + k;
            for s in strips {
                let sw = s.cols.len();
                g[s.cols.clone()].copy_from_slice(&s.g[r * sw..(r + 1) * sw]);
                if let (Some(dst), Some(src)) = (g_rows.as_mut(), s.rows.as_ref()) {
                    dst[s.cols.clone()].copy_from_slice(&src[r * sw..(r + 1) * sw]);
                }
            }
            match (
                nearest_rows.as_mut().and_then(Iterator::next),
                g_rows.as_ref(),
            ) {
                (Some(n), Some(rows)) => {
                    envelope.row(&g, out_row, Some(&mut chosen));
                    for (n, &v) in n.iter_mut().zip(&chosen) {
                        *n = rows[v as usize] * w as u32 + v;
                    }
                }
                _ => envelope.row(&g, out_row, None),
            }
        }
    });
}

/// Scratch space for the lower envelope of one row's parabolas.
struct Envelope {
    sites: Vec<usize>,
    bounds: Vec<f64>,
}

impl Envelope {
    fn new(w: usize) -> Self {
        Self {
            sites: Vec::with_capacity(w),
            bounds: Vec::with_capacity(w + 1),
        }
    }

    /// Squared distances of one row from its column distances `g` (`FAR` = no obstacle in
    /// that column); with `chosen`, the column of each cell's nearest obstacle.
    fn row(&mut self, g: &[u32], out: &mut [u32], mut chosen: Option<&mut [u32]>) {
        let f = |q: usize| {
            let d = f64::from(g[q]);
            d * d + (q * q) as f64
        };
        self.sites.clear();
        self.bounds.clear();
        for q in (0..g.len()).filter(|&q| g[q] != FAR) {
            let fq = f(q);
            // Pop parabolas hidden by q's; the first site's bound is -inf, so it stays.
            while let (Some(&v), Some(&bound)) = (self.sites.last(), self.bounds.last()) {
                let s = (fq - f(v)) / (2.0 * (q - v) as f64);
                if s > bound {
                    self.bounds.push(s);
                    break;
                }
                self.sites.pop();
                self.bounds.pop();
            }
            if self.sites.is_empty() {
                self.bounds.push(f64::NEG_INFINITY);
            }
            self.sites.push(q);
        }
        // The mask is not empty, so every row has at least one site.
        let last = self.sites.len().saturating_sub(1);
        let mut k = 0;
        for (q, o) in out.iter_mut().enumerate() {
            while k < last && self.bounds[k + 1] < q as f64 {
                k += 1;
            }
            let v = self.sites[k];
            let gv = u64::from(g[v]);
            *o = ((q.abs_diff(v) as u64).pow(2) + gv * gv) as u32;
            if let Some(c) = chosen.as_deref_mut() {
                c[q] = v as u32;
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
                prop_assert_eq!(d2, reference[mask.geometry().index(cell).unwrap()]);
            }
            prop_assert!(plain.nearest(Cell::new(0, 0)).is_none());
        }
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
