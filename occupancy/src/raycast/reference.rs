//! Plain traversals the fast [`Traversal`] is checked against:
//! - [`steps`]: Amanatides–Woo on the same fixed-point parameter, stepped the plain way
//!   (compare the crossings, step one, stop at the segment's end or the grid's edge), with
//!   no count of the cells made in advance. The fast traversal must give the same cells
//!   with positive length and the same units in each;
//! - [`float_steps`]: Amanatides–Woo on a floating-point parameter, as the traversal was
//!   before it stepped in fixed point (commit 3c879cc). Its lengths agree with the fixed
//!   point's to rounding, and its cells wherever a cell's length is not at rounding's scale.
//!
//! [`Traversal`]: super::Traversal

use super::{Start, T_CAP, T_ONE, fixed};
use crate::GridGeometry;
use nalgebra::Point2;

/// Every step of segment `from`–`to` over `geometry`: `(col, row, units)`, zero units
/// (through a corner) included, and the metres per unit. The start (clipping, start cell,
/// first crossings) is the fast traversal's own [`Start`] and its rounding to units.
pub(crate) fn steps(
    g: &GridGeometry,
    from: Point2<f64>,
    to: Point2<f64>,
) -> (Vec<(usize, usize, u64)>, f64) {
    let Some(start) = Start::new(g, from, to) else {
        return (vec![], 0.0);
    };
    let (width, height) = (g.width() as i64, g.height() as i64);
    let (mut col, mut row) = (start.col, start.row);
    let (step_col, t_max_col, t_delta_col) = start.col_axis;
    let (step_row, t_max_row, t_delta_row) = start.row_axis;
    let (mut t, t1) = (fixed(start.t0, 0), fixed(start.t1, 0));
    let (mut cross_col, mut cross_row) = (fixed(t_max_col, t), fixed(t_max_row, t));
    let (delta_col, delta_row) = (fixed(t_delta_col, 1), fixed(t_delta_row, 1));
    let mut out = vec![];
    while t < t1 && (0..width).contains(&col) && (0..height).contains(&row) {
        let t_next = cross_col.min(cross_row);
        let t_exit = t_next.min(t1);
        out.push((col as usize, row as usize, t_exit - t));
        if cross_row < cross_col {
            row += step_row;
            cross_row = cross_row.saturating_add(delta_row).min(2 * T_CAP);
        } else {
            col += step_col;
            cross_col = cross_col.saturating_add(delta_col).min(2 * T_CAP);
        }
        t = t_exit;
    }
    (out, start.metres_per_t / T_ONE)
}

/// Every step of the floating-point traversal: `(col, row, length in metres)`, zero lengths
/// included; both axes step together at a corner.
pub(crate) fn float_steps(
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
