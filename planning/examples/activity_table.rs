//! Seed 002's Table 2, reproduced in shape on a synthetic hall: activity along the path (mean,
//! variance, maximum) and path length, for plain A*, A* with the seed's activity-aware
//! heuristic, and A* with activity in the step cost.
//!
//! Case 1: from one end of the hall to the other, the busiest area in between.
//! Case 2: to the cell of maximum activity, past another busy spot.
//!
//! Run with `cargo run -p haunts-planning --example activity_table`.

#[path = "../tests/common/scene.rs"]
mod scene;

use haunts_occupancy::Cell;
use haunts_planning::{
    AStar, ActivityAwareAStar, ActivityAwareParams, ActivityCostAStar, ActivityCostParams,
    PathMetrics, Planner, PlanningError, max_activity_cell,
};

/// A row of the table: its label and the metric it shows.
type Row = (&'static str, fn(&PathMetrics) -> f64);

fn main() -> Result<(), PlanningError> {
    let hall = scene::hall()?;
    let planners: [(&str, Box<dyn Planner>); 3] = [
        ("plain A*", Box::new(AStar::default())),
        (
            "seed h'(n)",
            Box::new(ActivityAwareAStar::new(
                hall.activity.clone(),
                ActivityAwareParams::default(),
            )?),
        ),
        (
            "step cost",
            Box::new(ActivityCostAStar::new(
                hall.activity.clone(),
                ActivityCostParams::default().with_activity_weight(0.2),
            )?),
        ),
    ];
    let peak = max_activity_cell(&hall.activity, &hall.costmap)?;
    let g = hall.costmap.geometry();
    let at = |c: Cell| g.cell_center(c);
    println!(
        "Synthetic hall {} m × {} m at {} m per cell; activity peak {:.3} at ({:.2}, {:.2}) m",
        g.width() as f64 * g.resolution(),
        g.height() as f64 * g.resolution(),
        g.resolution(),
        hall.activity[peak],
        at(peak).x,
        at(peak).y,
    );
    println!("seed h'(n): θ = 5.5; step cost: L·(1 + 2·c/252 + 0.2·a)");
    println!();
    println!(
        "{:<8} {:<20} {:>12} {:>12} {:>12}",
        "", "metric", planners[0].0, planners[1].0, planners[2].0
    );
    let cases = [
        ("Case 1", hall.case1.0, hall.case1.1),
        ("Case 2", hall.case2_start, peak),
    ];
    for (name, start, goal) in cases {
        let metrics = planners
            .iter()
            .map(|(_, p)| p.plan(&hall.costmap, start, goal)?.metrics(&hall.activity))
            .collect::<Result<Vec<PathMetrics>, _>>()?;
        let rows: [Row; 4] = [
            ("activity mean", |m| m.activity_mean),
            ("activity variance", |m| m.activity_variance),
            ("activity max", |m| m.activity_max),
            ("length of path (m)", |m| m.length),
        ];
        for (k, (label, value)) in rows.iter().enumerate() {
            let head = if k == 0 { name } else { "" };
            print!("{head:<8} {label:<20}");
            for m in &metrics {
                print!(" {:>12.3}", value(m));
            }
            println!();
        }
    }
    Ok(())
}
