//! One suite for every `Planner`, and A* against Dijkstra and the `pathfinding` crate.

mod common;

use common::reference::{check_path_and_cost, pathfinding_astar, random_costmap};
use haunts_occupancy::{Cell, Grid, GridGeometry};
use haunts_planning::{
    AStar, ActivityAwareAStar, ActivityAwareParams, ActivityCostAStar, ActivityCostParams, Costmap,
    Dijkstra, Endpoint, LETHAL_OBSTACLE, NO_INFORMATION, Planner, PlanningError, SearchParams,
    StraightLine, UnknownPolicy,
};
use nalgebra::Point2;
use proptest::prelude::*;

const W: f64 = 2.0; // SearchParams::default().cost_weight

/// Every planner of the crate, with activity that changes nothing (zero activity, or none
/// above θ), so all of them follow the default cost model.
fn every_planner(geometry: GridGeometry) -> Vec<(&'static str, Box<dyn Planner>)> {
    let quiet = Grid::filled(geometry, 0.0);
    vec![
        ("A*", Box::new(AStar::default())),
        ("Dijkstra", Box::new(Dijkstra::default())),
        (
            "activity-aware A*",
            Box::new(
                ActivityAwareAStar::new(quiet.clone(), ActivityAwareParams::default()).unwrap(),
            ),
        ),
        (
            "activity-cost A*",
            Box::new(ActivityCostAStar::new(quiet, ActivityCostParams::default()).unwrap()),
        ),
        ("straight line", Box::new(StraightLine::default())),
    ]
}

/// 12 × 8 cells of 0.5 m: a wall at column 5 (rows 0..=5), an unknown cell at (9, 1), a cost
/// of 100 at (2, 2), and a closed box around (10, 6).
fn room() -> Costmap {
    let g = GridGeometry::new(0.5, Point2::new(-1.0, 2.0), 12, 8).unwrap();
    Costmap::new(Grid::from_fn(g, |c| {
        let boxed = (9..=11).contains(&c.col) && (5..=7).contains(&c.row) && c != Cell::new(10, 6);
        if (c.col == 5 && c.row <= 5) || boxed {
            LETHAL_OBSTACLE
        } else if c == Cell::new(9, 1) {
            NO_INFORMATION
        } else if c == Cell::new(2, 2) {
            100
        } else {
            0
        }
    }))
}

#[test]
fn every_planner_rejects_bad_endpoints_with_typed_errors() {
    let costmap = room();
    for (name, planner) in every_planner(*costmap.geometry()) {
        let plan = |s, g| planner.plan(&costmap, s, g);
        let free = Cell::new(0, 0);
        assert!(
            matches!(
                plan(Cell::new(12, 0), free),
                Err(PlanningError::CellOutsideMap {
                    endpoint: Endpoint::Start,
                    width: 12,
                    height: 8,
                    ..
                })
            ),
            "{name}"
        );
        assert!(
            matches!(
                plan(free, Cell::new(5, 3)),
                Err(PlanningError::InObstacle {
                    endpoint: Endpoint::Goal,
                    cost: LETHAL_OBSTACLE,
                    ..
                })
            ),
            "{name}: goal in a wall"
        );
        assert!(
            matches!(
                plan(Cell::new(9, 1), free),
                Err(PlanningError::InUnknown {
                    endpoint: Endpoint::Start,
                    ..
                })
            ),
            "{name}: start in unknown space"
        );
        assert!(
            matches!(
                planner.plan_world(&costmap, Point2::new(-1.1, 2.1), Point2::new(0.0, 3.0)),
                Err(PlanningError::PointOutsideMap {
                    endpoint: Endpoint::Start,
                    ..
                })
            ),
            "{name}"
        );
        let same = plan(free, free).unwrap();
        assert_eq!(
            (same.cells(), same.cost(), same.length()),
            (&[free][..], 0.0, 0.0)
        );
    }
}

#[test]
fn every_planner_returns_valid_paths_or_unreachable() {
    let costmap = room();
    let shortest = AStar::default()
        .plan(&costmap, Cell::new(0, 0), Cell::new(11, 0))
        .unwrap();
    for (name, planner) in every_planner(*costmap.geometry()) {
        // Around the wall: only the straight line fails.
        match planner.plan(&costmap, Cell::new(0, 0), Cell::new(11, 0)) {
            Ok(path) => {
                check_path_and_cost(&path, &costmap, W);
                assert_eq!(path.start(), Cell::new(0, 0));
                assert_eq!(path.goal(), Cell::new(11, 0));
                approx::assert_relative_eq!(path.cost(), shortest.cost(), max_relative = 1e-12);
            }
            Err(PlanningError::Unreachable { .. }) => assert_eq!(name, "straight line"),
            Err(e) => panic!("{name}: {e}"),
        }
        // Into the closed box: no planner gets there.
        assert!(
            matches!(
                planner.plan(&costmap, Cell::new(0, 0), Cell::new(10, 6)),
                Err(PlanningError::Unreachable {
                    goal: Cell { col: 10, row: 6 },
                    ..
                })
            ),
            "{name}"
        );
    }
}

#[test]
fn unknown_cells_follow_the_policy() {
    // A corridor one cell high whose middle cell is unknown.
    let g = GridGeometry::new(1.0, Point2::origin(), 5, 1).unwrap();
    let costmap = Costmap::new(Grid::from_vec(g, vec![0, 0, NO_INFORMATION, 0, 0]).unwrap());
    let (s, t) = (Cell::new(0, 0), Cell::new(4, 0));
    assert!(matches!(
        AStar::default().plan(&costmap, s, t),
        Err(PlanningError::Unreachable { explored: 2, .. })
    ));
    let allow = SearchParams::default()
        .with_cost_weight(1.0)
        .with_unknown(UnknownPolicy::Allow(126));
    let path = AStar::new(allow).unwrap().plan(&costmap, s, t).unwrap();
    assert_eq!(path.cost(), 4.5); // three free steps and one at factor 1.5
    assert_eq!(
        Dijkstra::new(allow)
            .unwrap()
            .plan(&costmap, s, t)
            .unwrap()
            .cost(),
        4.5
    );
}

#[test]
fn costs_steer_paths_and_a_zero_weight_ignores_them() {
    // A 3-row strip whose middle row is expensive.
    let g = GridGeometry::new(1.0, Point2::origin(), 6, 3).unwrap();
    let costmap = Costmap::new(Grid::from_fn(g, |c| if c.row == 1 { 252 } else { 0 }));
    let (s, t) = (Cell::new(0, 1), Cell::new(5, 1));
    let weighted = AStar::default().plan(&costmap, s, t).unwrap();
    assert!(weighted.cells()[1..5].iter().all(|c| c.row != 1));
    let flat = AStar::new(SearchParams::default().with_cost_weight(0.0))
        .unwrap()
        .plan(&costmap, s, t)
        .unwrap();
    assert_eq!(flat.cells().len(), 6);
    assert_eq!(flat.cost(), 5.0);
}

#[test]
fn the_cost_to_go_field_serves_many_starts() {
    let costmap = room();
    let goal = Cell::new(11, 0);
    let field = Dijkstra::default().cost_to_go(&costmap, goal).unwrap();
    let astar = AStar::default();
    for start in [
        Cell::new(0, 0),
        Cell::new(0, 7),
        Cell::new(4, 4),
        Cell::new(8, 2),
    ] {
        let expected = astar.plan(&costmap, start, goal).unwrap().cost();
        let path = field.path_from(start).unwrap();
        check_path_and_cost(&path, &costmap, W);
        approx::assert_relative_eq!(path.cost(), expected, max_relative = 1e-12);
        approx::assert_relative_eq!(field.cost(start).unwrap(), expected, max_relative = 1e-12);
    }
    assert_eq!(field.cost(Cell::new(10, 6)), None);
    assert!(field.grid()[Cell::new(5, 0)].is_infinite());
    assert!(matches!(
        field.path_from(Cell::new(10, 6)),
        Err(PlanningError::Unreachable { .. })
    ));
}

#[test]
fn a_star_matches_pathfinding_on_a_weighted_grid() {
    let costmap = random_costmap(7, 120, 90, 0.05, 0.25, true);
    let (w, h) = (120, 90);
    let (s, t) = (Cell::new(0, 0), Cell::new(w - 1, h - 1));
    let ours = AStar::default().plan(&costmap, s, t).unwrap();
    check_path_and_cost(&ours, &costmap, W);
    let (reference, steps) = pathfinding_astar(costmap.data(), w, W, 0, w * h - 1).unwrap();
    let ours_cells = ours.cost() / 0.05;
    assert!((ours_cells - reference).abs() <= (steps + ours.cells().len()) as f64 / 4e9 + 1e-9);
}

/// Random grids: `(width, height, costs)`, with lethal cells, some unknown cells and, when
/// `weighted`, costs below lethal.
fn grids(weighted: bool) -> impl Strategy<Value = (usize, usize, Vec<u8>)> {
    (1usize..30, 1usize..30, 0.0f64..0.45).prop_flat_map(move |(w, h, lethal)| {
        let cell = (0.0f64..1.0, 0u8..=252).prop_map(move |(r, c)| {
            if r < lethal {
                LETHAL_OBSTACLE
            } else if r < lethal + 0.03 {
                NO_INFORMATION
            } else if weighted {
                c
            } else {
                0
            }
        });
        (Just(w), Just(h), proptest::collection::vec(cell, w * h))
    })
}

fn endpoints(w: usize, h: usize) -> impl Strategy<Value = (usize, usize)> {
    (0..w * h, 0..w * h)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Uniform costs (free or lethal): A*, Dijkstra and `pathfinding`'s A* agree on the cost,
    /// and agree on whether the goal is reachable.
    #[test]
    fn uniform_a_star_equals_dijkstra_and_pathfinding(
        ((w, h, costs), (s, t)) in grids(false).prop_flat_map(|g| { let e = endpoints(g.0, g.1); (Just(g), e) })
    ) {
        agree(w, h, costs, s, t, 0.0)?;
    }

    /// Weighted costs: the same agreement under the step cost `L·(1 + 2·c/252)`.
    #[test]
    fn weighted_a_star_equals_dijkstra_and_pathfinding(
        ((w, h, costs), (s, t)) in grids(true).prop_flat_map(|g| { let e = endpoints(g.0, g.1); (Just(g), e) })
    ) {
        agree(w, h, costs, s, t, W)?;
    }
}

fn agree(
    w: usize,
    h: usize,
    costs: Vec<u8>,
    s: usize,
    t: usize,
    weight: f64,
) -> Result<(), TestCaseError> {
    let g = GridGeometry::new(1.0, Point2::origin(), w, h).unwrap();
    let costmap = Costmap::new(Grid::from_vec(g, costs).unwrap());
    let (start, goal) = (Cell::new(s % w, s / w), Cell::new(t % w, t / w));
    let params = SearchParams::default().with_cost_weight(weight);
    let astar = AStar::new(params).unwrap().plan(&costmap, start, goal);
    let dijkstra = Dijkstra::new(params).unwrap().plan(&costmap, start, goal);
    let blocked = |c: Cell| costmap.cost(c).unwrap() > 252;
    if blocked(start) || blocked(goal) {
        let rejected = matches!(
            astar,
            Err(PlanningError::InObstacle { .. } | PlanningError::InUnknown { .. })
        );
        prop_assert!(rejected, "astar: {:?}", astar);
        let rejected = matches!(
            dijkstra,
            Err(PlanningError::InObstacle { .. } | PlanningError::InUnknown { .. })
        );
        prop_assert!(rejected, "dijkstra: {:?}", dijkstra);
        return Ok(());
    }
    let reference = pathfinding_astar(costmap.data(), w, weight, s, t);
    match (astar, dijkstra, reference) {
        (Ok(a), Ok(d), Some((r, steps))) => {
            let cost = check_path_and_cost(&a, &costmap, weight);
            check_path_and_cost(&d, &costmap, weight);
            prop_assert!(
                (cost - d.cost()).abs() <= 1e-9 * cost.max(1.0),
                "{} vs {}",
                cost,
                d.cost()
            );
            let tolerance = (steps + a.cells().len()) as f64 / 4e9 + 1e-9 * cost.max(1.0);
            prop_assert!(
                (cost - r).abs() <= tolerance,
                "{} vs pathfinding {}",
                cost,
                r
            );
        }
        (Err(PlanningError::Unreachable { .. }), Err(PlanningError::Unreachable { .. }), None) => {}
        (a, d, r) => prop_assert!(false, "disagree: {:?} / {:?} / {:?}", a, d, r),
    }
    Ok(())
}
