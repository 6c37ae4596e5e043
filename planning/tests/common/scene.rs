//! A synthetic hall in the spirit of seed 002's library experiment (section 5.4): walls,
//! shelves, and a target-activity map with a busy area between the two ends of the hall.
//! Shared by the activity tests and the `activity_table` example.
#![allow(dead_code)]

use haunts_occupancy::{Cell, Grid, GridGeometry, OCCUPIED, OccupancyGrid};
use haunts_planning::{
    Costmap, InflationLayer, InflationParams, LayeredCostmap, PlanningError, StaticLayer,
};
use nalgebra::Point2;

/// A hall of 60 m × 30 m at 0.25 m per cell, its costmap and activity map.
pub struct Scene {
    /// Walls and shelves, inflated (static + inflation layers).
    pub costmap: Costmap,
    /// Target activity per cell (0 … ≈ 7.8, as the seed's library TA map).
    pub activity: Grid<f64>,
    /// Case 1: from the west end to the east end, the busiest area in between.
    pub case1: (Cell, Cell),
    /// Case 2: the start; the goal is the cell of maximum activity.
    pub case2_start: Cell,
}

/// (x, y, peak, σ) of the activity blobs, in metres: the main area of the hall (peak 7.8) and
/// two busy spots above θ = 5.5, one of them on the way from case 2's start to the peak.
const BLOBS: [(f64, f64, f64, f64); 4] = [
    (30.0, 15.0, 7.8, 4.0),
    (23.9, 21.1, 6.8, 2.5),
    (45.0, 7.0, 6.0, 2.5),
    (12.0, 8.0, 3.0, 3.0),
];

/// Shelves as (x0, y0, x1, y1) in metres.
const SHELVES: [(f64, f64, f64, f64); 4] = [
    (8.0, 18.0, 9.0, 27.0),
    (50.0, 3.0, 51.0, 12.0),
    (38.0, 20.0, 46.0, 21.0),
    (16.0, 3.0, 24.0, 4.0),
];

/// The hall: walls around, four shelves, four activity blobs, inflated with a 0.25 m robot.
pub fn hall() -> Result<Scene, PlanningError> {
    let geometry = GridGeometry::new(0.25, Point2::origin(), 240, 120)?;
    let inside = |p: Point2<f64>, (x0, y0, x1, y1): (f64, f64, f64, f64)| {
        p.x >= x0 && p.x < x1 && p.y >= y0 && p.y < y1
    };
    let values = Grid::from_fn(geometry, |c| {
        let p = geometry.cell_center(c);
        let border = c.col == 0 || c.row == 0 || c.col == 239 || c.row == 119;
        if border || SHELVES.iter().any(|&s| inside(p, s)) {
            OCCUPIED
        } else {
            0
        }
    });
    let map = OccupancyGrid::from_grid(values)?;
    let stack = LayeredCostmap::new(geometry)
        .with_layer(StaticLayer::new(&map, true))
        .with_layer(InflationLayer::new(
            InflationParams::default()
                .with_inscribed_radius(0.25)
                .with_inflation_radius(0.75),
        )?);
    let activity = Grid::from_fn(geometry, |c| {
        let p = geometry.cell_center(c);
        BLOBS
            .iter()
            .map(|&(x, y, peak, s)| {
                let d2 = (p.x - x).powi(2) + (p.y - y).powi(2);
                peak * (-d2 / (2.0 * s * s)).exp()
            })
            .sum::<f64>()
    });
    let cell = |x: f64, y: f64| {
        geometry
            .world_to_cell(Point2::new(x, y))
            .unwrap_or(Cell::new(1, 1))
    };
    Ok(Scene {
        costmap: stack.build()?,
        activity,
        // Along one row: the straight line through the peak is the only shortest path.
        case1: (cell(3.0, 15.1), cell(57.0, 15.1)),
        // On the diagonal through the second busy spot to the peak: again the only shortest.
        case2_start: cell(17.9, 27.1),
    })
}
