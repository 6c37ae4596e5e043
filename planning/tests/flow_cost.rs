//! The flow-aware cost (issue 53): A* with a direction-dependent step cost against a plain
//! Dijkstra written here from the documented formula, on random maps (the cost is
//! admissible, so A* stays optimal); on two lanes walked in opposite directions, the plan
//! keeps to the lane going its way; bad costs are typed errors.

mod common;

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::f64::consts::{FRAC_PI_2, PI, SQRT_2};

use common::reference::{SplitMix, factor, random_costmap};
use haunts_occupancy::{Cell, Grid, GridGeometry};
use haunts_planning::{
    AStar, Costmap, DirectionalCost, FlowCostAStar, FlowCostParams, MOVES, Path, Planner,
    PlanningError, SearchParams, against_flow_share, move_between, move_heading,
};
use nalgebra::Point2;

/// An f64 ordered for the heap (costs here are finite and ≥ 0).
struct Key(f64);
impl PartialEq for Key {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other).is_eq()
    }
}
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Key {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The cost of one step from `a` into its neighbour `b` by move `k` under the module's
/// formula, in cells (`None`: not allowed: an obstacle, or a corner cut).
fn step_cost(
    costmap: &Costmap,
    flow: &DirectionalCost,
    activity: Option<&Grid<f64>>,
    (wc, wf, wa): (f64, f64, f64),
    a: Cell,
    k: usize,
) -> Option<(Cell, f64)> {
    let g = costmap.geometry();
    let (dc, dr) = MOVES[k];
    let b = g.checked_cell(a.col as i64 + i64::from(dc), a.row as i64 + i64::from(dr))?;
    let enterable = |c: Cell| factor(costmap.cost(c).expect("inside"), wc);
    let fb = enterable(b)?;
    if dc != 0 && dr != 0 {
        // No corner cutting: both cells passed between must be enterable.
        enterable(Cell::new(b.col, a.row))?;
        enterable(Cell::new(a.col, b.row))?;
    }
    let length = if dc != 0 && dr != 0 { SQRT_2 } else { 1.0 };
    let act = activity.map_or(0.0, |x| wa * x[b].max(0.0));
    Some((b, length * (fb + act + wf * flow.at(b, k).expect("inside"))))
}

/// Plain Dijkstra over every cell (no heuristic): the optimal cost in metres, or `None`.
fn dijkstra(
    costmap: &Costmap,
    flow: &DirectionalCost,
    activity: Option<&Grid<f64>>,
    weights: (f64, f64, f64),
    start: Cell,
    goal: Cell,
) -> Option<f64> {
    let g = *costmap.geometry();
    let mut best = vec![f64::INFINITY; g.len()];
    let mut heap = BinaryHeap::new();
    best[g.index(start)?] = 0.0;
    heap.push(Reverse((Key(0.0), g.index(start)?)));
    while let Some(Reverse((Key(d), i))) = heap.pop() {
        if d > best[i] {
            continue;
        }
        let a = g.cell_at(i)?;
        if a == goal {
            return Some(d * g.resolution());
        }
        for k in 0..8 {
            if let Some((b, c)) = step_cost(costmap, flow, activity, weights, a, k) {
                let j = g.index(b)?;
                if d + c < best[j] {
                    best[j] = d + c;
                    heap.push(Reverse((Key(d + c), j)));
                }
            }
        }
    }
    None
}

/// The cost of `path` recomputed step by step, metres (asserting every step is allowed).
fn recompute(
    path: &Path,
    costmap: &Costmap,
    flow: &DirectionalCost,
    activity: Option<&Grid<f64>>,
    weights: (f64, f64, f64),
) -> f64 {
    let mut total = 0.0;
    for pair in path.cells().windows(2) {
        let k = move_between(pair[0], pair[1]).expect("a step between neighbours");
        let (b, c) = step_cost(costmap, flow, activity, weights, pair[0], k)
            .unwrap_or_else(|| panic!("{:?} → {:?} is not allowed", pair[0], pair[1]));
        assert_eq!(b, pair[1]);
        total += c;
    }
    total * costmap.geometry().resolution()
}

#[test]
fn a_star_with_the_flow_cost_equals_dijkstra_on_random_maps() {
    let mut compared = 0;
    for seed in 0..80u64 {
        // Narrow grids too (one to three cells wide), where moves share index differences.
        let (w, h) = if seed >= 60 {
            (1 + (seed % 3) as usize, 6 + (seed % 7) as usize)
        } else {
            (8 + (seed % 13) as usize, 6 + (seed % 7) as usize)
        };
        let lethal = if seed >= 60 { 0.0 } else { 0.2 };
        let costmap = random_costmap(seed, w, h, 0.25, lethal, seed % 2 == 0);
        let g = *costmap.geometry();
        let mut rng = SplitMix(1000 + seed);
        // Random directional costs, some cells free of any, some with a lane's pattern.
        let flow = DirectionalCost::from_fn(g, |_, heading| {
            if rng.unit() < 0.3 {
                0.0
            } else {
                3.0 * rng.unit() * (1.0 + heading.cos()) / 2.0
            }
        })
        .unwrap();
        let activity = Grid::from_fn(g, |_| 2.0 * rng.unit() - 0.5);
        let (wc, wf, wa) = (
            [0.0, 2.0][seed as usize % 2],
            0.5 + rng.unit() * 2.0,
            [0.0, 0.7][(seed as usize / 2) % 2],
        );
        let params = FlowCostParams::default()
            .with_search(SearchParams::default().with_cost_weight(wc))
            .with_flow_weight(wf)
            .with_activity_weight(wa);
        let planner = FlowCostAStar::new(flow.clone(), params)
            .unwrap()
            .with_activity(activity.clone())
            .unwrap();
        let (start, goal) = (Cell::new(0, 0), Cell::new(w - 1, h - 1));
        let reference = dijkstra(&costmap, &flow, Some(&activity), (wc, wf, wa), start, goal);
        match (planner.plan(&costmap, start, goal), reference) {
            (Ok(path), Some(best)) => {
                approx::assert_relative_eq!(path.cost(), best, max_relative = 1e-12);
                let again = recompute(&path, &costmap, &flow, Some(&activity), (wc, wf, wa));
                approx::assert_relative_eq!(path.cost(), again, max_relative = 1e-12);
                compared += 1;
            }
            (Err(PlanningError::Unreachable { .. }), None) => {}
            (got, want) => panic!("seed {seed}: A* {got:?}, Dijkstra {want:?}"),
        }
    }
    assert!(compared >= 55, "only {compared} maps had a path");
}

#[test]
fn without_flow_it_is_a_star() {
    // A zero directional cost and no activity: the same path and cost as the plain A*.
    for seed in 0..20u64 {
        let costmap = random_costmap(seed, 15, 11, 0.1, 0.15, true);
        let g = *costmap.geometry();
        let zero = DirectionalCost::from_fn(g, |_, _| 0.0).unwrap();
        let aware = FlowCostAStar::new(zero, FlowCostParams::default()).unwrap();
        let (s, t) = (Cell::new(0, 0), Cell::new(14, 10));
        match (
            AStar::default().plan(&costmap, s, t),
            aware.plan(&costmap, s, t),
        ) {
            (Ok(a), Ok(b)) => {
                assert_eq!(a.cells(), b.cells(), "seed {seed}");
                assert_eq!(a.cost().to_bits(), b.cost().to_bits(), "seed {seed}");
            }
            (Err(_), Err(_)) => {}
            (a, b) => panic!("seed {seed}: {a:?} / {b:?}"),
        }
    }
}

/// A corridor 40 × 6 cells of 0.5 m: people walk east in the south lane (rows 0–2) and west
/// in the north lane (rows 3–5); the directional cost of a cell is how head-on a move meets
/// its lane's walkers, `max(0, −cos(move − lane))`.
fn two_lanes() -> (Costmap, DirectionalCost, impl Fn(Cell) -> Option<f64>) {
    let g = GridGeometry::new(0.5, Point2::origin(), 40, 6).unwrap();
    let lane = |c: Cell| if c.row < 3 { 0.0 } else { PI };
    let flow =
        DirectionalCost::from_fn(g, |c, heading| (-(heading - lane(c)).cos()).max(0.0)).unwrap();
    (Costmap::filled(g, 0), flow, move |c| Some(lane(c)))
}

#[test]
fn on_two_lanes_the_plan_keeps_to_its_lane() {
    let (costmap, flow, dominant) = two_lanes();
    let aware = FlowCostAStar::new(flow, FlowCostParams::default()).unwrap();
    // East along the north (westbound) lane's middle, and west along the south lane's.
    for (start, goal, own_lane) in [
        (Cell::new(0, 4), Cell::new(39, 4), 0..3),
        (Cell::new(39, 1), Cell::new(0, 1), 3..6),
    ] {
        let plain = AStar::default().plan(&costmap, start, goal).unwrap();
        let planned = aware.plan(&costmap, start, goal).unwrap();
        let plain_share = against_flow_share(&plain, &dominant);
        let share = against_flow_share(&planned, &dominant);
        assert!(plain_share > 0.95, "plain {plain_share}");
        // Only the crossings into and out of its lane go against anyone.
        assert!(share < 0.15, "{share}");
        let in_own = planned
            .cells()
            .iter()
            .filter(|c| own_lane.contains(&c.row))
            .count();
        assert!(in_own as f64 > 0.8 * planned.cells().len() as f64);
        // A few cells longer than the straight line, no more.
        assert!(planned.length() < plain.length() * 1.10);
        assert!(planned.length() > plain.length());
    }
}

#[test]
fn the_against_flow_share_counts_length_against_the_dominant_heading() {
    let g = GridGeometry::new(1.0, Point2::origin(), 4, 2).unwrap();
    let costmap = Costmap::filled(g, 0);
    let path = AStar::default()
        .plan(&costmap, Cell::new(0, 0), Cell::new(3, 0))
        .unwrap();
    // Three steps east into cells flowing west, north (90°: not against) and none.
    let dominant = |c: Cell| match c.col {
        1 => Some(PI),
        2 => Some(FRAC_PI_2),
        _ => None,
    };
    assert_eq!(against_flow_share(&path, dominant), 1.0 / 3.0);
    assert_eq!(move_between(Cell::new(1, 1), Cell::new(0, 0)), Some(5));
    assert_eq!(move_between(Cell::new(1, 1), Cell::new(3, 1)), None);
    assert!((move_heading(5) - 5.0 * PI / 4.0).abs() < 1e-15);
}

#[test]
fn bad_directional_costs_and_weights_are_typed_errors() {
    let g = GridGeometry::new(1.0, Point2::origin(), 3, 2).unwrap();
    for bad in [f64::NAN, -0.5, f64::INFINITY] {
        let e = DirectionalCost::from_fn(g, |c, h| if c.col == 2 && h > 3.0 { bad } else { 0.0 })
            .unwrap_err();
        assert!(
            matches!(e, PlanningError::InvalidDirectionalCost { cell, .. } if cell == Cell::new(2, 0)),
            "{e:?}"
        );
    }
    let short = DirectionalCost::new(g, vec![[0.0; 8]; 5]).unwrap_err();
    assert!(short.to_string().contains("cell count"), "{short}");
    let flow = DirectionalCost::new(g, vec![[0.0; 8]; 6]).unwrap();
    for params in [
        FlowCostParams::default().with_flow_weight(-1.0),
        FlowCostParams::default().with_activity_weight(f64::NAN),
    ] {
        assert!(matches!(
            FlowCostAStar::new(flow.clone(), params),
            Err(PlanningError::InvalidParameter(_))
        ));
    }
    // On another grid: a geometry mismatch, at planning and for an activity raster.
    let other = GridGeometry::new(0.5, Point2::origin(), 3, 2).unwrap();
    let planner = FlowCostAStar::new(flow, FlowCostParams::default()).unwrap();
    let e = planner
        .plan(&Costmap::filled(other, 0), Cell::new(0, 0), Cell::new(2, 1))
        .unwrap_err();
    assert!(matches!(e, PlanningError::GeometryMismatch { .. }), "{e:?}");
    let e = planner
        .clone()
        .with_activity(Grid::from_fn(other, |_| 0.0))
        .unwrap_err();
    assert!(matches!(e, PlanningError::GeometryMismatch { .. }), "{e:?}");
    let e = planner
        .with_activity(Grid::from_fn(g, |_| f64::NAN))
        .unwrap_err();
    assert!(
        matches!(e, PlanningError::NonFiniteActivity { .. }),
        "{e:?}"
    );
}
