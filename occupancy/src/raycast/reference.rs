//! The plain Amanatides–Woo traversal as it was before the integer-masked step (commit
//! 3c879cc): float compares and sums one crossing at a time. The fast [`Traversal`] and
//! everything built on it must give the same cells and bit-identical lengths.
//!
//! [`Traversal`]: super::Traversal

use super::Start;
use crate::GridGeometry;
use nalgebra::Point2;

/// Every step of segment `from`–`to` over `geometry`: `(col, row, length)`, zero lengths
/// (through a corner) included. The start (clipping, start cell, first crossings) is the
/// fast traversal's own [`Start`]: only the stepping is the reference's.
pub(crate) fn steps(
    g: &GridGeometry,
    from: Point2<f64>,
    to: Point2<f64>,
) -> Vec<(usize, usize, f64)> {
    let Some(start) = Start::new(g, from, to) else {
        return vec![];
    };
    let (width, height) = (g.width() as i64, g.height() as i64);
    let (mut col, mut row) = (start.col, start.row);
    let (step_col, mut t_max_col, t_delta_col) = start.col_axis;
    let (step_row, mut t_max_row, t_delta_row) = start.row_axis;
    let (t1, metres_per_t) = (start.t1, start.metres_per_t);
    let mut t = start.t0;
    let mut out = vec![];
    while t < t1 && (0..width).contains(&col) && (0..height).contains(&row) {
        let t_next = t_max_col.min(t_max_row);
        let t_exit = t_next.min(t1);
        out.push((col as usize, row as usize, (t_exit - t) * metres_per_t));
        if t_max_col == t_next {
            col += step_col;
            t_max_col += t_delta_col;
        }
        if t_max_row == t_next {
            row += step_row;
            t_max_row += t_delta_row;
        }
        t = t_exit;
    }
    out
}
