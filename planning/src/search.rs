//! The search engines every grid planner runs: A* and Dijkstra on an 8-connected grid, over
//! dense arrays indexed by cell.
//!
//! Costs are in cells inside the engines (a straight step is 1, a diagonal one √2, each times
//! the entered cell's factor); planners multiply by the resolution to report metres. The
//! arrays start zeroed (cheap to allocate), so "not reached" is zero: a cost of +0.0 (every
//! reached cell but the root costs more), a link of 0 (links hold the linked cell's index plus
//! one, and the root links to itself). The sign bit of a cost marks a cell already expanded.
//! The 8-neighbourhood is a macro so that the work on each neighbour is inlined.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::f64::consts::SQRT_2;

/// A cell being searched: its row-major index, column and row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct At {
    pub(crate) index: usize,
    pub(crate) col: usize,
    pub(crate) row: usize,
}

/// An open list: cells keyed by `f`, popped smallest first.
pub(crate) trait Queue {
    /// Adds cell `index` with key `f` and heuristic `h` (for tie-breaking).
    fn push(&mut self, f: f64, h: f64, index: usize);
    /// Removes a cell of smallest key.
    fn pop(&mut self) -> Option<usize>;
}

/// A binary min-heap, for any keys. A key packs, from the most significant bits, `f` as bits
/// (for non-negative floats, bit order is numeric order), the heuristic as `f32` bits (among
/// equal `f`, the cell with the largest `g` comes first) and the cell's index (so the order is
/// deterministic).
#[derive(Debug, Default)]
pub(crate) struct Heap {
    keys: BinaryHeap<Reverse<u128>>,
}

impl Queue for Heap {
    fn push(&mut self, f: f64, h: f64, index: usize) {
        let key = (u128::from(f.to_bits()) << 64)
            | (u128::from((h as f32).to_bits()) << 32)
            | index as u128;
        self.keys.push(Reverse(key));
    }

    fn pop(&mut self) -> Option<usize> {
        self.keys
            .pop()
            .map(|Reverse(key)| (key & u128::from(u32::MAX)) as usize)
    }
}

/// A radix heap (Ahuja, Mehlhorn, Orlin & Tarjan 1990), for monotone keys: no key pushed is
/// smaller than the last popped, as with Dijkstra and with A* under a consistent heuristic.
/// Bucket `b > 0` holds keys whose highest bit differing from the last popped key is bit
/// `b − 1`; bucket 0 holds keys equal to it and pops last in, first out, so among equal `f`
/// the most recently reached cell comes first (deterministically). Pushes and pops cost no
/// comparisons between keys; each key moves down at most 63 buckets.
///
/// A key below the last popped one (a rounding error of a consistent heuristic, at most an
/// ulp or so) is raised to it. Keys are the bits of non-negative floats, so bit 63 is always 0
/// and 64 buckets suffice.
#[derive(Debug)]
pub(crate) struct Radix {
    last: u64,
    /// Bit `b` set when bucket `b` is not empty.
    occupied: u64,
    buckets: [Vec<(u64, u32)>; 64],
    /// The smallest key of each non-empty bucket.
    least: [u64; 64],
}

impl Default for Radix {
    fn default() -> Self {
        Self {
            last: 0,
            occupied: 0,
            buckets: std::array::from_fn(|_| Vec::new()),
            least: [u64::MAX; 64],
        }
    }
}

impl Radix {
    fn bucket(key: u64, last: u64) -> usize {
        // Both keys are below 2⁶³, so their difference's highest bit is at most 62.
        (u64::BITS - (key ^ last).leading_zeros()) as usize & 63
    }

    fn put(&mut self, key: u64, index: u32) {
        let b = Self::bucket(key, self.last);
        self.buckets[b].push((key, index));
        self.least[b] = self.least[b].min(key);
        self.occupied |= 1 << b;
    }
}

impl Queue for Radix {
    fn push(&mut self, f: f64, _h: f64, index: usize) {
        self.put(f.to_bits().max(self.last), index as u32);
    }

    fn pop(&mut self) -> Option<usize> {
        if self.occupied & 1 == 0 {
            if self.occupied == 0 {
                return None;
            }
            let b = self.occupied.trailing_zeros() as usize;
            self.occupied &= !(1 << b);
            let mut moved = std::mem::take(&mut self.buckets[b]);
            self.last = std::mem::replace(&mut self.least[b], u64::MAX);
            for &(key, index) in &moved {
                self.put(key, index);
            }
            moved.clear();
            self.buckets[b] = moved;
        }
        let (_, index) = self.buckets[0].pop()?;
        // Bucket 0 holds keys equal to `last` only; its `least` is never read.
        if self.buckets[0].is_empty() {
            self.occupied &= !1;
        }
        Some(index as usize)
    }
}

/// For the neighbours of cell `$at` on a `$w × $h` grid that may be stepped to, given each
/// cell's step `$factor` (a function; infinite: not enterable), runs `$visit` with
/// `$j` (the neighbour), `$length` (of the step) and `$f` (the neighbour's factor) bound:
/// orthogonal neighbours when enterable, diagonal ones when enterable and both cells they pass
/// between are (no corner cutting). Each factor is computed once. A macro rather than a
/// function taking a closure, so that the visit is inlined at each of its eight sites.
macro_rules! for_each_neighbour {
    ($at:expr, $w:expr, $h:expr, $factor:expr, |$j:ident, $length:ident, $f:ident| $visit:block) => {{
        const BLOCKED: f64 = f64::INFINITY;
        let At {
            index: i,
            col: c,
            row: r,
        } = $at;
        let (w, h) = ($w, $h);
        let factor = &$factor;
        let left = if c > 0 { factor(i - 1) } else { BLOCKED };
        let right = if c + 1 < w { factor(i + 1) } else { BLOCKED };
        let down = if r > 0 { factor(i - w) } else { BLOCKED };
        let up = if r + 1 < h { factor(i + w) } else { BLOCKED };
        macro_rules! visit {
            ($index:expr, $col:expr, $row:expr, $len:expr, $factor_of:expr) => {{
                let $f: f64 = $factor_of;
                if $f < BLOCKED {
                    let $j = At {
                        index: $index,
                        col: $col,
                        row: $row,
                    };
                    let $length: f64 = $len;
                    $visit
                }
            }};
        }
        if down < BLOCKED {
            if left < BLOCKED {
                visit!(i - w - 1, c - 1, r - 1, SQRT_2, factor(i - w - 1));
            }
            if right < BLOCKED {
                visit!(i - w + 1, c + 1, r - 1, SQRT_2, factor(i - w + 1));
            }
        }
        if up < BLOCKED {
            if left < BLOCKED {
                visit!(i + w - 1, c - 1, r + 1, SQRT_2, factor(i + w - 1));
            }
            if right < BLOCKED {
                visit!(i + w + 1, c + 1, r + 1, SQRT_2, factor(i + w + 1));
            }
        }
        visit!(i - 1, c - 1, r, 1.0, left);
        visit!(i + 1, c + 1, r, 1.0, right);
        visit!(i - w, c, r - 1, 1.0, down);
        visit!(i + w, c, r + 1, 1.0, up);
    }};
}

/// The octile distance from `(col, row)` to `(to_col, to_row)`, in cells: the length of the
/// shortest 8-connected path on an empty grid.
#[inline(always)]
pub(crate) fn octile(col: usize, row: usize, to_col: usize, to_row: usize) -> f64 {
    // Via u32 (grids have fewer than 2³² cells): one instruction to convert.
    let dx = f64::from(col.abs_diff(to_col) as u32);
    let dy = f64::from(row.abs_diff(to_row) as u32);
    dx.max(dy) + (SQRT_2 - 1.0) * dx.min(dy)
}

/// A path found by an engine: row-major cell indices from start to goal, and its cost in cells.
pub(crate) struct Found {
    pub(crate) cells: Vec<u32>,
    pub(crate) cost: f64,
}

/// The row-major cell of index `index` on a grid `w` wide (32-bit division: grids have at
/// most `u32::MAX` cells).
fn at(index: usize, w: usize) -> At {
    let (i, w32) = (index as u32, w as u32);
    At {
        index,
        col: (i % w32) as usize,
        row: (i / w32) as usize,
    }
}

/// A* from `start` to `goal` on a `w × h` grid where entering cell `i` multiplies the step
/// length by `factor(i)` (infinite: not enterable), guided by `heuristic(cell)` (cells).
///
/// A cell found again with a smaller `g` is re-opened, so an inconsistent heuristic still
/// gives a valid (if not optimal) path. `Err(explored)` when the goal cannot be reached.
#[cfg(test)]
pub(crate) fn astar(
    w: usize,
    h: usize,
    factor: impl Fn(usize) -> f64,
    heuristic: impl Fn(At) -> f64,
    ends: (usize, usize),
    open: impl Queue,
) -> Result<Found, usize> {
    astar_with_extra(w, h, factor, no_extra, heuristic, ends, open)
}

/// No extra step cost: `-0.0`, the one zero the compiler may drop from `f + extra` (adding
/// `+0.0` would turn a `-0.0` into `+0.0`), so the plain planners pay nothing for it (a
/// function item, inlined at each use).
#[inline(always)]
pub(crate) fn no_extra(_from: usize, _to: usize) -> f64 {
    -0.0
}

/// [`astar`] with an extra factor `extra(i, j)` added to `factor(j)` on each step from `i` to
/// its neighbour `j` (a direction-dependent cost; ≥ 0 keeps an admissible heuristic so).
pub(crate) fn astar_with_extra(
    w: usize,
    h: usize,
    factor: impl Fn(usize) -> f64,
    extra: impl Fn(usize, usize) -> f64,
    heuristic: impl Fn(At) -> f64,
    (start, goal): (usize, usize),
    mut open: impl Queue,
) -> Result<Found, usize> {
    let n = w * h;
    // `g` of every reached cell; its sign bit is set once the cell is expanded (closed).
    let mut g = vec![0.0f64; n];
    let mut parent = vec![0u32; n];
    parent[start] = start as u32 + 1;
    let h0 = heuristic(at(start, w));
    open.push(h0, h0, start);
    let mut explored = 1;
    while let Some(i) = open.pop() {
        if g[i].is_sign_negative() {
            continue; // a stale entry: `i` was expanded from a cheaper one
        }
        let gi = g[i];
        g[i] = -gi;
        if i == goal {
            return Ok(Found {
                cells: walk(&parent, goal),
                cost: gi,
            });
        }
        let link = i as u32 + 1;
        for_each_neighbour!(at(i, w), w, h, factor, |j, length, f| {
            let gj = gi + length * (f + extra(i, j.index));
            let old = g[j.index];
            // +0.0 marks a cell not reached yet (every other `g` but the start's is > 0);
            // `abs` re-opens a closed cell reached more cheaply (inconsistent heuristics).
            let unseen = old.to_bits() == 0;
            if unseen || gj < old.abs() {
                explored += usize::from(unseen);
                g[j.index] = gj;
                parent[j.index] = link;
                let hj = heuristic(j);
                open.push(gj + hj, hj, j.index);
            }
        });
    }
    Err(explored)
}

/// The cells from the root of `links` (the cell linking to itself) to `end`.
fn walk(links: &[u32], end: usize) -> Vec<u32> {
    let mut cells = vec![end as u32];
    let mut at = end;
    while links[at] as usize != at + 1 {
        at = links[at] as usize - 1;
        cells.push(at as u32);
    }
    cells.reverse();
    cells
}

/// A cost-to-go field: per cell the cheapest cost to the goal (cells) and the next cell on
/// that path, as a link (index + 1; 0 = not reached; the goal links to itself).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Field {
    pub(crate) cost: Vec<f64>,
    pub(crate) next: Vec<u32>,
}

impl Field {
    /// The cost of cell `i` to the goal, if reached.
    pub(crate) fn cost(&self, i: usize) -> Option<f64> {
        (self.next[i] != 0).then(|| self.cost[i])
    }
    /// The path from `start` along the links to the goal, if `start` was reached.
    pub(crate) fn path(&self, start: usize) -> Option<Vec<u32>> {
        if self.next[start] == 0 {
            return None;
        }
        let mut cells = vec![start as u32];
        let mut at = start;
        while self.next[at] as usize != at + 1 {
            at = self.next[at] as usize - 1;
            cells.push(at as u32);
        }
        Some(cells)
    }
    /// Number of cells reached.
    pub(crate) fn reached(&self) -> usize {
        self.next.iter().filter(|&&n| n != 0).count()
    }
}

/// Dijkstra's algorithm backwards from `goal`: the cost-to-go field of every cell that can
/// reach it. With `stop_at`, stops once that cell's cost is final.
pub(crate) fn cost_to_go(
    w: usize,
    h: usize,
    factor: impl Fn(usize) -> f64,
    goal: usize,
    stop_at: Option<usize>,
) -> Field {
    let n = w * h;
    // As in `astar`, the sign bit marks settled cells; cleared before returning.
    let mut d = vec![0.0f64; n];
    let mut next = vec![0u32; n];
    let mut open = Radix::default();
    next[goal] = goal as u32 + 1;
    open.push(0.0, 0.0, goal);
    while let Some(u) = open.pop() {
        if d[u].is_sign_negative() {
            continue;
        }
        let du = d[u];
        d[u] = -du;
        if Some(u) == stop_at {
            break;
        }
        // Every step into `u` costs its length times `u`'s factor.
        let (fu, link) = (factor(u), u as u32 + 1);
        for_each_neighbour!(at(u, w), w, h, factor, |v, length, _f| {
            let dv = du + length * fu;
            let old = d[v.index];
            // +0.0 marks a cell not reached yet (every other cost but the goal's is > 0).
            if old.to_bits() == 0 || dv < old {
                d[v.index] = dv;
                next[v.index] = link;
                open.push(dv, 0.0, v.index);
            }
        });
    }
    for x in &mut d {
        *x = x.abs();
    }
    Field { cost: d, next }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_are_not_cut() {
        // 3×3, obstacle at (1, 0): from (0, 0) the diagonal to (1, 1) passes it.
        let factor = |j: usize| if j == 1 { f64::INFINITY } else { 2.0 };
        let mut seen = vec![];
        for_each_neighbour!(at(0, 3), 3, 3, factor, |j, l, f| {
            seen.push((j, l, f));
        });
        assert_eq!(seen, vec![(at(3, 3), 1.0, 2.0)]);
        let mut seen = vec![];
        for_each_neighbour!(at(4, 3), 3, 3, |_: usize| 1.0, |j, _l, _f| {
            seen.push(j);
        });
        assert!(seen.iter().all(|&j| j == at(j.index, 3)));
        let mut indices: Vec<usize> = seen.iter().map(|j| j.index).collect();
        indices.sort_unstable();
        assert_eq!(indices, vec![0, 1, 2, 3, 5, 6, 7, 8]);
    }

    #[test]
    fn heap_ties_pop_the_smaller_heuristic_then_the_smaller_index() {
        let mut heap = Heap::default();
        for (f, h, index) in [(2.0, 1.5, 7), (2.0, 0.5, 9), (1.0, 1.0, 3), (2.0, 0.5, 4)] {
            heap.push(f, h, index);
        }
        let order: Vec<usize> = std::iter::from_fn(|| heap.pop()).collect();
        assert_eq!(order, vec![3, 4, 9, 7]);
    }

    #[test]
    fn radix_ties_pop_last_in_first_out() {
        let mut radix = Radix::default();
        for (f, index) in [(2.0, 7), (2.0, 9), (1.0, 3), (2.0, 4)] {
            radix.push(f, 0.0, index);
        }
        let order: Vec<usize> = std::iter::from_fn(|| radix.pop()).collect();
        assert_eq!(order, vec![3, 4, 9, 7]);
    }

    proptest::proptest! {
        /// Monotone use, as in a search: every pop is a smallest key among those pushed and
        /// not yet popped.
        #[test]
        fn the_radix_heap_pops_a_smallest_key(
            rounds in proptest::collection::vec(proptest::collection::vec(0.0f64..50.0, 0..6), 1..60)
        ) {
            let mut radix = Radix::default();
            let (mut keys, mut outstanding) = (Vec::new(), Vec::new());
            let mut last = 0.0f64;
            for pushes in rounds {
                for step in pushes {
                    radix.push(last + step, 0.0, keys.len());
                    outstanding.push(keys.len());
                    keys.push(last + step);
                }
                let popped = radix.pop();
                proptest::prop_assert_eq!(popped.is_some(), !outstanding.is_empty());
                if let Some(i) = popped {
                    let min = outstanding.iter().map(|&j| keys[j]).fold(f64::INFINITY, f64::min);
                    proptest::prop_assert_eq!(keys[i], min);
                    outstanding.retain(|&j| j != i);
                    last = keys[i];
                }
            }
        }
    }

    #[test]
    fn an_enclosed_goal_is_unreachable_and_the_explored_cells_are_counted() {
        // 4×3 grid, column 2 blocked: from (0, 0) six cells can be reached.
        let factor = |i: usize| if i % 4 == 2 { f64::INFINITY } else { 1.0 };
        let result = astar(4, 3, factor, |_| 0.0, (0, 3), Radix::default());
        assert!(matches!(result, Err(6)));
        let field = cost_to_go(4, 3, factor, 3, None);
        assert_eq!(field.reached(), 3);
        assert_eq!(field.path(0), None);
        assert_eq!(field.path(11), Some(vec![11, 7, 3]));
        assert_eq!(field.cost(7), Some(1.0));
    }
}
