//! A* on a 2000 × 2000 grid with 25 % random lethal cells, corner to corner, side by side with
//! `pathfinding::directed::astar::astar` on the same grid and cost model (fixed-point costs,
//! since its costs must be `Ord`). Both must find the same path cost, checked before timing.
//!
//! Two cost models: uniform (free or lethal) and weighted (free cells of random cost 0..=200,
//! step cost `L·(1 + 2·c/252)`, where the octile heuristic guides far less).

#[path = "../tests/common/reference.rs"]
mod reference;

use criterion::{Criterion, criterion_group, criterion_main};
use haunts_occupancy::Cell;
use haunts_planning::{AStar, Planner, SearchParams};
use reference::{Reference, random_costmap};
use std::hint::black_box;

const SIDE: usize = 2000;
const RESOLUTION: f64 = 0.05;

fn astar(c: &mut Criterion) {
    let mut group = c.benchmark_group("astar_2000");
    group.sample_size(10);
    for (name, weighted, weight) in [("uniform", false, 0.0), ("weighted", true, 2.0)] {
        let costmap = random_costmap(2024, SIDE, SIDE, RESOLUTION, 0.25, weighted);
        let planner = AStar::new(SearchParams::default().with_cost_weight(weight)).expect("params");
        let (start, goal) = (Cell::new(0, 0), Cell::new(SIDE - 1, SIDE - 1));
        let reference = Reference::new(costmap.data(), SIDE, weight);
        let goal_index = SIDE * SIDE - 1;

        let ours = planner.plan(&costmap, start, goal).expect("a path exists");
        let (theirs, steps) = reference.astar(0, goal_index).expect("a path exists");
        let ours_cells = ours.cost() / RESOLUTION;
        let tolerance = (steps + ours.cells().len()) as f64 / reference::SCALE + 1e-9 * ours_cells;
        assert!(
            (ours_cells - theirs).abs() <= tolerance,
            "{name}: haunts {ours_cells} vs pathfinding {theirs} cells"
        );
        eprintln!(
            "{name}: path cost {ours_cells:.6} cells (pathfinding {theirs:.6}), {} cells long",
            ours.cells().len()
        );

        group.bench_function(format!("{name}/haunts"), |b| {
            b.iter(|| planner.plan(black_box(&costmap), start, goal))
        });
        group.bench_function(format!("{name}/pathfinding"), |b| {
            b.iter(|| reference.astar(black_box(0), goal_index))
        });
    }
    group.finish();
}

criterion_group!(benches, astar);
criterion_main!(benches);
