//! Activity-aware planning on the synthetic hall (seed 002, section 5.4 and Table 2).

mod common;

use common::reference::check_path;
use common::scene::{Scene, hall};
use haunts_occupancy::{Cell, Grid};
use haunts_planning::{
    AStar, ActivityAwareAStar, ActivityAwareParams, ActivityCostAStar, ActivityCostParams, Costmap,
    LETHAL_OBSTACLE, PathMetrics, Planner, PlanningError, SearchParams, crossings,
    max_activity_cell,
};

const WEIGHT: f64 = 2.0; // SearchParams::default().cost_weight
const W_A: f64 = 0.2; // the activity weight of the step-cost planner, as in the example

fn metrics(planner: &dyn Planner, scene: &Scene, start: Cell, goal: Cell) -> PathMetrics {
    let path = planner.plan(&scene.costmap, start, goal).unwrap();
    check_path(&path, &scene.costmap, WEIGHT);
    path.metrics(&scene.activity).unwrap()
}

fn planners(activity: &Grid<f64>) -> (AStar, ActivityAwareAStar, ActivityCostAStar) {
    (
        AStar::default(),
        ActivityAwareAStar::new(activity.clone(), ActivityAwareParams::default()).unwrap(),
        ActivityCostAStar::new(
            activity.clone(),
            ActivityCostParams::default().with_activity_weight(W_A),
        )
        .unwrap(),
    )
}

#[test]
fn case_1_activity_aware_paths_meet_less_activity_and_are_longer() {
    let scene = hall().unwrap();
    let (plain, aware, cost) = planners(&scene.activity);
    let (start, goal) = scene.case1;
    let p = metrics(&plain, &scene, start, goal);
    let a = metrics(&aware, &scene, start, goal);
    let c = metrics(&cost, &scene, start, goal);
    // The plain path crosses the busiest area; the seed's heuristic keeps below θ.
    assert!(p.activity_max > 7.0, "{p:?}");
    assert!(a.activity_max <= 5.5, "{a:?}");
    for m in [a, c] {
        assert!(m.activity_mean < p.activity_mean, "{m:?} vs {p:?}");
        assert!(m.activity_variance < p.activity_variance, "{m:?} vs {p:?}");
        assert!(m.activity_max < p.activity_max, "{m:?} vs {p:?}");
        assert!(m.length > p.length, "{m:?} vs {p:?}");
    }
}

#[test]
fn case_2_reaches_the_peak_with_less_activity_on_the_way() {
    let scene = hall().unwrap();
    let (plain, aware, cost) = planners(&scene.activity);
    let peak = max_activity_cell(&scene.activity, &scene.costmap).unwrap();
    let top = scene.activity[peak];
    assert!(
        scene
            .activity
            .cells()
            .all(|(c, &a)| a <= top || scene.costmap.cost(c).unwrap() >= 253)
    );
    let start = scene.case2_start;
    let p = metrics(&plain, &scene, start, peak);
    let a = metrics(&aware, &scene, start, peak);
    let c = metrics(&cost, &scene, start, peak);
    for m in [p, a, c] {
        assert_eq!(m.activity_max, top); // the goal is the peak, as in the seed
    }
    for m in [a, c] {
        assert!(m.activity_mean < p.activity_mean, "{m:?} vs {p:?}");
        assert!(m.activity_variance < p.activity_variance, "{m:?} vs {p:?}");
        assert!(m.length >= p.length - 1e-9, "{m:?} vs {p:?}");
    }
}

/// The step-cost planner is optimal for its trade-off: no other planner's path is cheaper
/// under it, while the seed's heuristic, being inadmissible, has no such guarantee.
#[test]
fn step_cost_paths_are_optimal_for_their_trade_off() {
    let scene = hall().unwrap();
    let (plain, aware, cost) = planners(&scene.activity);
    let priced = |cells: &[Cell]| -> f64 {
        let r = scene.costmap.geometry().resolution();
        cells
            .windows(2)
            .map(|p| {
                let (a, b) = (p[0], p[1]);
                let l = if a.col != b.col && a.row != b.row {
                    2f64.sqrt()
                } else {
                    1.0
                };
                let c = f64::from(scene.costmap.cost(b).unwrap());
                l * r * (1.0 + WEIGHT * c / 252.0 + W_A * scene.activity[b].max(0.0))
            })
            .sum()
    };
    for (start, goal) in [scene.case1, (scene.case2_start, scene.case1.1)] {
        let best = cost.plan(&scene.costmap, start, goal).unwrap();
        approx::assert_relative_eq!(best.cost(), priced(best.cells()), max_relative = 1e-12);
        for other in [&plain as &dyn Planner, &aware] {
            let path = other.plan(&scene.costmap, start, goal).unwrap();
            assert!(best.cost() <= priced(path.cells()) + 1e-9);
        }
    }
}

/// With θ above every activity the seed's heuristic is the octile distance: plain A*'s cost
/// (and, where the shortest path is unique as in case 1, plain A*'s path).
#[test]
fn a_threshold_above_the_peak_gives_plain_a_star() {
    let scene = hall().unwrap();
    let high = ActivityAwareAStar::new(
        scene.activity.clone(),
        ActivityAwareParams::default().with_threshold(100.0),
    )
    .unwrap();
    let plain = AStar::new(SearchParams::default()).unwrap();
    let (start, goal) = scene.case1;
    let a = high.plan(&scene.costmap, start, goal).unwrap();
    let p = plain.plan(&scene.costmap, start, goal).unwrap();
    assert_eq!(a, p);
    assert_eq!(p.cells().len(), goal.col - start.col + 1); // the straight line
    let (start, goal) = (scene.case2_start, scene.case1.1);
    let a = high.plan(&scene.costmap, start, goal).unwrap();
    let p = plain.plan(&scene.costmap, start, goal).unwrap();
    approx::assert_relative_eq!(a.cost(), p.cost(), max_relative = 1e-12);
}

/// The step-cost planner against `pathfinding`'s Dijkstra on random grids and activities:
/// the same optimal cost under `L·(1 + 2·c/252 + w·max(a, 0))`.
mod against_pathfinding {
    use super::common::reference::{SCALE, factor};
    use haunts_occupancy::{Cell, Grid, GridGeometry};
    use haunts_planning::{ActivityCostAStar, ActivityCostParams, Costmap, Planner, PlanningError};
    use proptest::prelude::*;

    fn reference(
        costs: &[u8],
        activity: &[f64],
        w: usize,
        w_a: f64,
        s: usize,
        t: usize,
    ) -> Option<f64> {
        let h = costs.len() / w;
        let enterable = |c: i64, r: i64| {
            (c >= 0 && r >= 0 && (c as usize) < w && (r as usize) < h)
                .then(|| r as usize * w + c as usize)
                .filter(|&j| factor(costs[j], 2.0).is_some())
        };
        let successors = |&i: &usize| {
            let (c, r) = ((i % w) as i64, (i / w) as i64);
            let mut out = Vec::new();
            for (dc, dr) in [
                (-1, 0),
                (1, 0),
                (0, -1),
                (0, 1),
                (-1, -1),
                (1, -1),
                (-1, 1),
                (1, 1),
            ] {
                let Some(j) = enterable(c + dc, r + dr) else {
                    continue;
                };
                let diagonal = dc != 0 && dr != 0;
                if diagonal && (enterable(c + dc, r).is_none() || enterable(c, r + dr).is_none()) {
                    continue;
                }
                let length = if diagonal { 2f64.sqrt() } else { 1.0 };
                let f = factor(costs[j], 2.0).unwrap_or(f64::INFINITY) + w_a * activity[j].max(0.0);
                out.push((j, (length * f * SCALE).round() as u64));
            }
            out
        };
        pathfinding::directed::dijkstra::dijkstra(&s, successors, |&i| i == t)
            .map(|(_, cost)| cost as f64 / SCALE)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn step_cost_a_star_is_optimal(
            (w, h, cells) in (2usize..20, 2usize..20).prop_flat_map(|(w, h)| {
                (Just(w), Just(h), proptest::collection::vec((0.0f64..1.0, 0u8..=252, -1.0f64..8.0), w * h))
            }),
            w_a in 0.0f64..3.0,
            (s, t) in (0usize..400, 0usize..400),
        ) {
            let (s, t) = (s % (w * h), t % (w * h));
            let g = GridGeometry::new(1.0, nalgebra::Point2::origin(), w, h).unwrap();
            let costs: Vec<u8> = cells.iter().map(|&(r, c, _)| if r < 0.25 { 254 } else { c }).collect();
            let activity: Vec<f64> = cells.iter().map(|&(_, _, a)| a).collect();
            let costmap = Costmap::new(Grid::from_vec(g, costs.clone()).unwrap());
            let planner = ActivityCostAStar::new(
                Grid::from_vec(g, activity.clone()).unwrap(),
                ActivityCostParams::default().with_activity_weight(w_a),
            ).unwrap();
            let ours = planner.plan(&costmap, Cell::new(s % w, s / w), Cell::new(t % w, t / w));
            match (ours, reference(&costs, &activity, w, w_a, s, t)) {
                (Ok(path), Some(cost)) => {
                    let tolerance = path.cells().len() as f64 / 1e9 + 1e-9 * cost;
                    prop_assert!((path.cost() - cost).abs() <= tolerance, "{} vs {}", path.cost(), cost);
                }
                (Err(PlanningError::Unreachable { .. }), None) => {}
                (Err(PlanningError::InObstacle { .. }), _) => prop_assert!(costs[s] == 254 || costs[t] == 254),
                (ours, theirs) => prop_assert!(false, "{:?} vs {:?}", ours, theirs),
            }
        }
    }
}

/// Crossings of the busiest cell from every side: the trips of a sweep end on free cells
/// about a radius from it, opposite each other; a side that is walled off drops its
/// direction, and bad parameters are named.
#[test]
fn crossings_run_through_a_cell_from_every_free_side() {
    let scene = hall().unwrap();
    let peak = max_activity_cell(&scene.activity, &scene.costmap).unwrap();
    let g = *scene.costmap.geometry();
    let centre = g.cell_center(peak);
    let trips = crossings(&scene.costmap, peak, 4.0, 8).unwrap();
    assert!(!trips.is_empty() && trips.len() <= 8);
    for &(a, b) in &trips {
        for end in [a, b] {
            assert!(
                scene.costmap.cost(end).unwrap() < haunts_planning::INSCRIBED_INFLATED_OBSTACLE
            );
            let d = (g.cell_center(end) - centre).norm();
            assert!((d - 4.0).abs() <= 2.0 + 1e-9, "{d}");
        }
        // Opposite sides: the segment passes within half the radius of the centre.
        let (pa, pb) = (g.cell_center(a), g.cell_center(b));
        let t = ((centre - pa).dot(&(pb - pa)) / (pb - pa).norm_squared()).clamp(0.0, 1.0);
        assert!((pa + (pb - pa) * t - centre).norm() <= 2.0, "{a:?} {b:?}");
    }
    // A cell in a corridor one cell wide along x: the directions whose ends lie more than
    // half the radius off the corridor (45°, 90°, 135°) are dropped; 22.5° and 157.5° (1.5 m
    // off) snap onto it.
    let corridor = Costmap::new(Grid::from_fn(g, |c| {
        if c.row == 60 { 0 } else { LETHAL_OBSTACLE }
    }));
    let along = crossings(&corridor, Cell::new(120, 60), 4.0, 8).unwrap();
    assert_eq!(along.len(), 3, "{along:?}");
    assert_eq!(along[0], (Cell::new(104, 60), Cell::new(136, 60)));
    assert!(along.iter().all(|(a, b)| a.row == 60 && b.row == 60));
    for (radius, directions, name) in [
        (0.0, 4, "radius"),
        (f64::NAN, 4, "radius"),
        (1.0, 0, "directions"),
        (1.0, usize::MAX, "directions"),
    ] {
        let err = crossings(&scene.costmap, peak, radius, directions).unwrap_err();
        assert!(
            matches!(err, PlanningError::InvalidParameter(haunts_core::InvalidParameter { name: n, .. }) if n == name),
            "{err:?}"
        );
    }
    assert_eq!(
        scene
            .costmap
            .nearest_free(nalgebra::Point2::new(f64::NAN, 1.0), 5.0),
        None
    );
}
