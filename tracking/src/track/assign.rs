//! Gated minimum-cost assignment (Kuhn–Munkres): the matching step of the global-nearest-
//! neighbour tracker and of the CLEAR MOT metrics.
//!
//! The convention is the one of `motmetrics` (`lap.add_expensive_edges`) and of scipy's
//! `linear_sum_assignment` used with a "large constant" for forbidden pairs: forbidden pairs
//! get a cost so large that any assignment with fewer forbidden pairs is cheaper, the full
//! problem is solved, and the forbidden pairs of the solution are dropped. The result is
//! therefore **the largest possible number of allowed matches, and among those the one of
//! least total cost** (with costs ≥ 0 a plain "least total cost" would be the empty
//! matching, which is never what a tracker wants).

use pathfinding::kuhn_munkres::kuhn_munkres_min;
use pathfinding::matrix::Matrix;

use crate::{Result, TrackingError};

/// Resolution of the fixed-point costs handed to the integer Kuhn–Munkres solver: the span
/// of the allowed costs (largest − smallest) is divided into this many steps (fewer for
/// matrices so large that the sums could overflow an `i64`, see [`min_cost_assignment`]).
pub(crate) const FIXED_POINT_STEPS: i64 = 1_000_000_000;

/// Minimum-cost assignment of rows to columns of a row-major `rows × cols` cost matrix,
/// ignoring pairs whose cost is `> max_cost` or not finite (those are never matched).
///
/// Returns the matched `(row, col)` pairs sorted by row: among the assignments that use only
/// allowed pairs, one that has **the most matches**, and among those **the least total
/// cost** — what scipy's `linear_sum_assignment` returns on the matrix where forbidden
/// entries are replaced by a large constant, once those matches are dropped (the CLEAR MOT
/// and global-nearest-neighbour convention; `motmetrics` does exactly this). A pair whose
/// cost equals `max_cost` is allowed. `max_cost = f64::INFINITY` allows every finite cost;
/// costs may be negative.
///
/// Costs are solved in fixed point: each allowed cost `c` becomes the integer
/// `round((c − lo) / (hi − lo) · S)`, where `lo`/`hi` are the least/greatest allowed costs
/// and `S` is [`FIXED_POINT_STEPS`] (10⁹), lowered to `(i64::MAX / 8) / (k² + 1)` for
/// `k = min(rows, cols)` so large that sums could overflow. The total cost of the result is
/// therefore within `k · (hi − lo) / S` of the optimum; ties (and near-ties below that
/// resolution) are broken deterministically.
///
/// Rows and columns with no allowed pair are left out before solving, so gating keeps large
/// sparse problems small.
///
/// # Errors
/// - [`TrackingError::MatrixShape`] when `cost.len() != rows * cols`.
/// - [`TrackingError::InvalidParameter`] when `max_cost` is NaN.
///
/// # Complexity
/// `O(rows · cols)` to gate, then `O(r² · c)` for the `r ≤ c` rows and columns that have at
/// least one allowed pair.
pub(crate) fn min_cost_assignment(
    cost: &[f64],
    rows: usize,
    cols: usize,
    max_cost: f64,
) -> Result<Vec<(usize, usize)>> {
    if rows.checked_mul(cols) != Some(cost.len()) {
        return Err(TrackingError::MatrixShape {
            len: cost.len(),
            rows,
            cols,
        });
    }
    if max_cost.is_nan() {
        return Err(TrackingError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "max_cost",
                value: max_cost,
                rule: "must not be NaN",
            },
        ));
    }
    let allowed = |c: f64| c.is_finite() && c <= max_cost;
    let at = |r: usize, c: usize| cost[r * cols + c];

    // Keep only rows and columns with at least one allowed pair.
    let mut live_cols = vec![false; cols];
    let mut live_rows = Vec::new();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for r in 0..rows {
        let mut any = false;
        for (c, live) in live_cols.iter_mut().enumerate() {
            let v = at(r, c);
            if allowed(v) {
                any = true;
                *live = true;
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        if any {
            live_rows.push(r);
        }
    }
    let live_cols: Vec<usize> = (0..cols).filter(|&c| live_cols[c]).collect();
    if live_rows.is_empty() {
        return Ok(Vec::new());
    }

    // The solver needs rows ≤ columns: put the smaller side on the rows.
    let transposed = live_rows.len() > live_cols.len();
    let (side_a, side_b) = if transposed {
        (&live_cols, &live_rows)
    } else {
        (&live_rows, &live_cols)
    };
    let original = |a: usize, b: usize| {
        if transposed {
            (side_b[b], side_a[a])
        } else {
            (side_a[a], side_b[b])
        }
    };

    let k = side_a.len();
    let k_sq = u128::try_from(k).unwrap_or(u128::MAX).saturating_pow(2);
    let limit = (i64::MAX / 8) as u128 / k_sq.saturating_add(1);
    let steps = i64::try_from(limit.min(FIXED_POINT_STEPS as u128))
        .unwrap_or(FIXED_POINT_STEPS)
        .max(1);
    // Any assignment with one forbidden pair more costs more than any with one fewer:
    // forbidden > k · steps (the largest possible sum of allowed costs).
    let forbidden = (i64::try_from(k).unwrap_or(i64::MAX))
        .saturating_mul(steps)
        .saturating_add(1);
    // Halves never overflow, even for costs near ±f64::MAX.
    let half_span = hi * 0.5 - lo * 0.5;
    let weights = Matrix::from_fn(k, side_b.len(), |(a, b)| {
        let (r, c) = original(a, b);
        let v = at(r, c);
        if !allowed(v) {
            forbidden
        } else if half_span > 0.0 {
            let t = ((v * 0.5 - lo * 0.5) / half_span).clamp(0.0, 1.0);
            // t ∈ [0, 1] and steps ≤ 10⁹: the product fits an i64 exactly.
            (t * steps as f64).round() as i64
        } else {
            0
        }
    });
    let (_, assignment) = kuhn_munkres_min(&weights);

    let mut pairs: Vec<(usize, usize)> = assignment
        .into_iter()
        .enumerate()
        .map(|(a, b)| original(a, b))
        .filter(|&(r, c)| allowed(at(r, c)))
        .collect();
    pairs.sort_unstable();
    Ok(pairs)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use proptest::prelude::*;

    use super::*;

    /// The reference: every injective map of the smaller side into the larger one, scored by
    /// (number of allowed pairs, total allowed cost). Returns the best (count, cost).
    fn brute_force(cost: &[f64], rows: usize, cols: usize, max_cost: f64) -> (usize, f64) {
        let allowed = |c: f64| c.is_finite() && c <= max_cost;
        let (small, large) = (rows.min(cols), rows.max(cols));
        let at = |s: usize, l: usize| {
            if rows <= cols {
                cost[s * cols + l]
            } else {
                cost[l * cols + s]
            }
        };
        let mut best = (0usize, 0.0f64);
        let mut used = vec![false; large];
        fn walk(
            s: usize,
            small: usize,
            used: &mut [bool],
            count: usize,
            total: f64,
            score: &dyn Fn(usize, usize) -> Option<f64>,
            best: &mut (usize, f64),
        ) {
            if s == small {
                if count > best.0 || (count == best.0 && total < best.1) {
                    *best = (count, total);
                }
                return;
            }
            for l in 0..used.len() {
                if used[l] {
                    continue;
                }
                used[l] = true;
                match score(s, l) {
                    Some(c) => walk(s + 1, small, used, count + 1, total + c, score, best),
                    None => walk(s + 1, small, used, count, total, score, best),
                }
                used[l] = false;
            }
        }
        let score = |s: usize, l: usize| {
            let c = at(s, l);
            allowed(c).then_some(c)
        };
        if small > 0 {
            walk(0, small, &mut used, 0, 0.0, &score, &mut best);
        }
        best
    }

    #[test]
    fn optimal_not_greedy_and_gated() {
        // Greedy would take (0, 0) at cost 1 and then pay 9; the optimum pays 2 + 2.
        let cost = [1.0, 2.0, 2.0, 9.0];
        assert_eq!(
            min_cost_assignment(&cost, 2, 2, f64::INFINITY).unwrap(),
            vec![(0, 1), (1, 0)]
        );
        // Gated at 5: row 1 can only take column 0, so row 0 gets column 1 (two matches beat
        // one cheaper match); row 2 has no allowed pair (NaN and 7 > 5) and stays unmatched.
        let cost = [1.0, 3.0, 4.0, 6.0, f64::NAN, 7.0];
        assert_eq!(
            min_cost_assignment(&cost, 3, 2, 5.0).unwrap(),
            vec![(0, 1), (1, 0)]
        );
    }

    #[test]
    fn shape_and_nan_threshold_are_errors() {
        assert!(matches!(
            min_cost_assignment(&[1.0; 5], 2, 3, 1.0),
            Err(TrackingError::MatrixShape {
                len: 5,
                rows: 2,
                cols: 3
            })
        ));
        assert!(matches!(
            min_cost_assignment(&[], usize::MAX, 2, 1.0),
            Err(TrackingError::MatrixShape { .. })
        ));
        assert!(matches!(
            min_cost_assignment(&[1.0], 1, 1, f64::NAN),
            Err(TrackingError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "max_cost",
                    ..
                }
            ))
        ));
    }

    #[test]
    fn empty_and_fully_forbidden_matrices_match_nothing() {
        assert!(min_cost_assignment(&[], 0, 4, 1.0).unwrap().is_empty());
        assert!(min_cost_assignment(&[], 3, 0, 1.0).unwrap().is_empty());
        let cost = [f64::NAN, f64::INFINITY, 2.0, f64::NEG_INFINITY];
        assert!(min_cost_assignment(&cost, 2, 2, 1.0).unwrap().is_empty());
        assert!(
            min_cost_assignment(&[0.0], 1, 1, f64::NEG_INFINITY)
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn the_threshold_itself_is_allowed() {
        assert_eq!(
            min_cost_assignment(&[0.75], 1, 1, 0.75).unwrap(),
            vec![(0, 0)]
        );
        assert!(
            min_cost_assignment(&[0.75 + 1e-12], 1, 1, 0.75)
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn more_rows_than_columns_are_transposed_back() {
        // Column 0 is best for row 2, column 1 for row 0; row 1 is left out.
        let cost = [5.0, 1.0, 4.0, 4.0, 1.0, 5.0];
        assert_eq!(
            min_cost_assignment(&cost, 3, 2, f64::INFINITY).unwrap(),
            vec![(0, 1), (2, 0)]
        );
    }

    #[test]
    fn huge_and_tiny_costs_do_not_overflow() {
        let cost = [f64::MAX, -f64::MAX, -f64::MAX, f64::MAX];
        assert_eq!(
            min_cost_assignment(&cost, 2, 2, f64::INFINITY).unwrap(),
            vec![(0, 1), (1, 0)]
        );
        let cost = [1e-300, 2e-300, 3e-300, 1e-300];
        assert_eq!(
            min_cost_assignment(&cost, 2, 2, 1.0).unwrap(),
            vec![(0, 0), (1, 1)]
        );
    }

    #[test]
    fn a_large_sparse_problem_is_solved_by_its_live_part() {
        // 300 × 300, only the anti-diagonal allowed: the answer is that anti-diagonal.
        let n = 300;
        let mut cost = vec![f64::NAN; n * n];
        for r in 0..n {
            cost[r * n + (n - 1 - r)] = r as f64;
        }
        let pairs = min_cost_assignment(&cost, n, n, f64::INFINITY).unwrap();
        assert_eq!(pairs.len(), n);
        assert!(pairs.iter().all(|&(r, c)| c == n - 1 - r));
    }

    fn entry() -> impl Strategy<Value = f64> {
        prop_oneof![
            6 => -3.0f64..10.0,
            1 => Just(f64::NAN),
            1 => Just(f64::INFINITY),
            1 => (0u8..4).prop_map(f64::from),
        ]
    }

    proptest! {
        #[test]
        fn matches_a_brute_force_reference(
            (rows, cols, cost) in (0usize..6, 0usize..6).prop_flat_map(|(r, c)| {
                (Just(r), Just(c), proptest::collection::vec(entry(), r * c))
            }),
            max_cost in prop_oneof![Just(f64::INFINITY), 0.0f64..10.0],
        ) {
            let pairs = min_cost_assignment(&cost, rows, cols, max_cost).unwrap();
            // Sorted by row, rows and columns used once, only allowed pairs.
            prop_assert!(pairs.windows(2).all(|w| w[0].0 < w[1].0));
            let mut used = vec![false; cols];
            for &(r, c) in &pairs {
                prop_assert!(r < rows && c < cols && !used[c]);
                used[c] = true;
                let v = cost[r * cols + c];
                prop_assert!(v.is_finite() && v <= max_cost);
            }
            let total: f64 = pairs.iter().map(|&(r, c)| cost[r * cols + c]).sum();
            let (count, best) = brute_force(&cost, rows, cols, max_cost);
            prop_assert_eq!(pairs.len(), count);
            // Fixed point: within k · span / 10⁹ of the optimum (span ≤ 13 here).
            prop_assert!((total - best).abs() <= 1e-6, "total {} best {}", total, best);
        }
    }
}
