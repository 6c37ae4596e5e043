//! The cost model written out independently of the crate, the `pathfinding` crate's A* on it,
//! a path checker, and seeded random grids. Shared by the tests and the A* bench.
#![allow(dead_code)]

use haunts_occupancy::{Cell, Grid, GridGeometry};
use haunts_planning::{Costmap, Path};
use std::f64::consts::SQRT_2;

/// Fixed-point scale of the `pathfinding` costs (its costs must be `Ord`): 2³² per cell.
pub const SCALE: f64 = 4_294_967_296.0;

/// The step-length factor of entering a cell of cost `c` (`None`: never entered), for
/// `cost_weight` `w` and unknown cells forbidden, written from the documented formula.
pub fn factor(c: u8, w: f64) -> Option<f64> {
    (c <= 252).then(|| 1.0 + w * f64::from(c) / 252.0)
}

/// The octile distance in cells.
pub fn octile(a: usize, b: usize, width: usize) -> f64 {
    let dx = (a % width).abs_diff(b % width) as f64;
    let dy = (a / width).abs_diff(b / width) as f64;
    dx.max(dy) + (SQRT_2 - 1.0) * dx.min(dy)
}

/// `pathfinding::directed::astar::astar` on a grid with the crate's cost model, step costs in
/// fixed point (its costs must be `Ord`) looked up in per-cost tables as the crate does.
pub struct Reference<'a> {
    costs: &'a [u8],
    width: usize,
    height: usize,
    /// Fixed-point cost of a straight (0) and a diagonal (1) step into a cell of each cost.
    step: [[Option<u64>; 256]; 2],
}

impl<'a> Reference<'a> {
    pub fn new(costs: &'a [u8], width: usize, w: f64) -> Self {
        let mut step = [[None; 256]; 2];
        for c in 0..=255u8 {
            let f = factor(c, w);
            step[0][usize::from(c)] = f.map(|f| (f * SCALE).round() as u64);
            step[1][usize::from(c)] = f.map(|f| (SQRT_2 * f * SCALE).round() as u64);
        }
        Self {
            costs,
            width,
            height: costs.len() / width,
            step,
        }
    }

    fn enterable(&self, c: i64, r: i64) -> Option<usize> {
        let inside = c >= 0 && r >= 0 && (c as usize) < self.width && (r as usize) < self.height;
        let j = inside.then(|| r as usize * self.width + c as usize)?;
        self.step[0][usize::from(self.costs[j])].map(|_| j)
    }

    /// The 8-connected moves out of `i` with their fixed-point costs, no corner cutting.
    fn successors(&self, i: usize) -> impl Iterator<Item = (usize, u64)> + '_ {
        const MOVES: [(i64, i64); 8] = [
            (-1, 0),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (1, -1),
            (-1, 1),
            (1, 1),
        ];
        let (c, r) = ((i % self.width) as i64, (i / self.width) as i64);
        MOVES.iter().filter_map(move |&(dc, dr)| {
            let j = self.enterable(c + dc, r + dr)?;
            let diagonal = dc != 0 && dr != 0;
            let corner_cut =
                self.enterable(c + dc, r).is_none() || self.enterable(c, r + dr).is_none();
            if diagonal && corner_cut {
                return None;
            }
            self.step[usize::from(diagonal)][usize::from(self.costs[j])].map(|cost| (j, cost))
        })
    }

    /// The optimal path's cost in cells (to the fixed-point scale) and its number of steps,
    /// or `None` when the goal cannot be reached.
    pub fn astar(&self, start: usize, goal: usize) -> Option<(f64, usize)> {
        let (path, cost) = pathfinding::directed::astar::astar(
            &start,
            |&i| self.successors(i),
            // Slightly shrunk so that rounded step costs never make it overestimate.
            |&i| (octile(i, goal, self.width) * SCALE * (1.0 - 1e-9)) as u64,
            |&i| i == goal,
        )?;
        Some((cost as f64 / SCALE, path.len() - 1))
    }
}

/// [`Reference::astar`] in one call.
pub fn pathfinding_astar(
    costs: &[u8],
    width: usize,
    w: f64,
    start: usize,
    goal: usize,
) -> Option<(f64, usize)> {
    Reference::new(costs, width, w).astar(start, goal)
}

/// Asserts that `path` is a valid path on `costmap` under the cost model with weight `w` and
/// unknown cells forbidden (8-connected steps, enterable cells, no corner cut), and returns
/// its cost under that model recomputed, in metres.
pub fn check_path(path: &Path, costmap: &Costmap, w: f64) -> f64 {
    let g = costmap.geometry();
    let cells = path.cells();
    assert!(!cells.is_empty());
    let enterable = |c: Cell| factor(costmap.cost(c).expect("inside"), w).is_some();
    assert!(enterable(cells[0]), "start {:?} is not enterable", cells[0]);
    let mut cost = 0.0;
    for pair in cells.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (dc, dr) = (a.col.abs_diff(b.col), a.row.abs_diff(b.row));
        assert!(
            dc <= 1 && dr <= 1 && dc + dr > 0,
            "{a:?} → {b:?} is not a step"
        );
        assert!(enterable(b), "{b:?} is not enterable");
        if dc + dr == 2 {
            assert!(
                enterable(Cell::new(b.col, a.row)) && enterable(Cell::new(a.col, b.row)),
                "{a:?} → {b:?} cuts a corner"
            );
        }
        let length = if dc + dr == 2 { SQRT_2 } else { 1.0 };
        cost += length * factor(costmap.cost(b).expect("inside"), w).expect("enterable");
    }
    cost * g.resolution()
}

/// [`check_path`], also asserting that the path's reported cost is the recomputed one.
pub fn check_path_and_cost(path: &Path, costmap: &Costmap, w: f64) -> f64 {
    let cost = check_path(path, costmap, w);
    approx::assert_relative_eq!(path.cost(), cost, max_relative = 1e-12, epsilon = 1e-12);
    cost
}

/// SplitMix64: a tiny seeded generator, so the grids are the same on every machine.
pub struct SplitMix(pub u64);

impl SplitMix {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A `width × height` costmap (resolution `resolution`) with a fraction `lethal` of lethal
/// cells and, when `weighted`, random costs 0..=200 elsewhere; the 3 × 3 blocks at the
/// corners are kept free, so that corner-to-corner paths usually exist.
pub fn random_costmap(
    seed: u64,
    width: usize,
    height: usize,
    resolution: f64,
    lethal: f64,
    weighted: bool,
) -> Costmap {
    let mut rng = SplitMix(seed);
    let g = GridGeometry::new(resolution, nalgebra::Point2::origin(), width, height)
        .expect("a valid geometry");
    let near = |a: usize, b: usize| a.abs_diff(b) <= 2;
    let corner = |c: Cell| {
        (near(c.col, 0) || near(c.col, width - 1)) && (near(c.row, 0) || near(c.row, height - 1))
    };
    Costmap::new(Grid::from_fn(g, |c| {
        let r = rng.unit();
        let cost = if weighted {
            (rng.next_u64() % 201) as u8
        } else {
            0
        };
        if corner(c) {
            0
        } else if r < lethal {
            254
        } else {
            cost
        }
    }))
}
