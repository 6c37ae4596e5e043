//! The main job: `cargo run --release --example pipeline [-- --days 6 --out out/pipeline]`.
//!
//! Until the simulator and the people pipeline exist (issues 7 and 8), this runs the
//! geometric part of seed 000's daily loop on built-in data: a small office whose tables
//! move between two layouts, a robot patrolling it with a noisy laser, and per day an
//! occupancy map with laser visit counts; the clustering of days into layouts (the paper's
//! greedy threshold method and complete linkage, scored against the true layouts); the
//! composite over all days, its static structure (checked against the true walls) and its
//! distance field. Pictures go to the output folder; the last line printed is one JSON
//! object with the figures.

use std::path::PathBuf;
use std::time::Instant;

use haunts::occupancy::composite::GeometricComposite;
use haunts::occupancy::edt::distance_transform;
use haunts::occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts::occupancy::picture::{ColorMap, render_occupancy, render_overlay, render_scalar};
use haunts::occupancy::raycast::Traversal;
use haunts::occupancy::{Cell, Grid, GridGeometry, LaserScan, OccupancyGrid, Pose2};
use haunts::similarity::{
    ClusterParams, DifferenceParams, agreement, complete_linkage_layouts, greedy_layouts,
    similarity_matrix,
};
use nalgebra::{Point2, Vector2};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

const RESOLUTION: f64 = 0.05;

/// The true office of one layout: walls (static) and tables (moved between layouts).
fn office(geometry: GridGeometry, layout: usize) -> (Grid<bool>, Grid<bool>) {
    let walls = Grid::from_fn(geometry, |c| {
        let p = geometry.cell_center(c);
        let outer = p.x < 0.2 || p.x > 19.8 || p.y < 0.2 || p.y > 11.8;
        // An inner wall at x = 8 m with a door between y = 5 and 6.5 m.
        let inner = (7.9..8.1).contains(&p.x) && !(5.0..6.5).contains(&p.y);
        outer || inner
    });
    let tables: &[(f64, f64)] = if layout == 0 {
        &[(12.0, 3.0), (12.0, 9.0), (16.0, 6.0)]
    } else {
        &[(11.0, 6.0), (15.0, 3.0), (15.0, 9.0)]
    };
    let furniture = Grid::from_fn(geometry, |c| {
        let p = geometry.cell_center(c);
        tables
            .iter()
            .any(|&(x, y)| (p.x - x).abs() < 0.8 && (p.y - y).abs() < 0.5)
    });
    (walls, furniture)
}

/// A 360° scan from `pose` against the true occupancy, with range noise and dropouts.
fn simulate_scan(truth: &Grid<bool>, pose: &Pose2, stamp: f64, rng: &mut StdRng) -> LaserScan {
    let (beams, max_range) = (360, 12.0);
    let noise = Normal::new(0.0, 0.01).expect("valid sigma");
    let from = pose * Point2::origin();
    let ranges = (0..beams)
        .map(|b| {
            let angle = -std::f64::consts::PI + b as f64 * std::f64::consts::TAU / beams as f64;
            let to = pose * Point2::new(max_range * angle.cos(), max_range * angle.sin());
            let mut travelled = 0.0;
            for (cell, length) in Traversal::new(truth.geometry(), from, to) {
                if truth[cell] {
                    return if rng.random_bool(0.02) {
                        f64::NAN
                    } else {
                        travelled + noise.sample(rng)
                    };
                }
                travelled += length;
            }
            f64::INFINITY
        })
        .collect();
    LaserScan::new(
        stamp,
        -std::f64::consts::PI,
        std::f64::consts::TAU / beams as f64,
        0.05,
        max_range,
        ranges,
        vec![],
    )
    .expect("valid scan description")
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let start = Instant::now();
    let mut args = std::env::args().skip(1);
    let (mut days, mut out) = (8usize, PathBuf::from("out/pipeline"));
    while let Some(a) = args.next() {
        match a.as_str() {
            "--days" => days = args.next().ok_or("--days needs a value")?.parse()?,
            "--out" => out = args.next().ok_or("--out needs a value")?.into(),
            other => {
                return Err(format!(
                    "unknown argument {other}; usage: pipeline [--days N] [--out DIR]"
                )
                .into());
            }
        }
    }
    std::fs::create_dir_all(&out)?;
    let geometry = GridGeometry::new(RESOLUTION, Point2::origin(), 400, 240)?;
    let mut rng = StdRng::seed_from_u64(7);
    let mut composite = GeometricComposite::new(geometry);
    let waypoints = [
        (2.0, 2.0),
        (6.0, 10.0),
        (8.0, 5.75),
        (13.5, 6.0),
        (18.0, 10.5),
        (18.0, 1.5),
        (9.5, 1.5),
        (2.0, 2.0),
    ];
    let mut scans = 0;
    let mut visits_total = Grid::filled(geometry, 0u32);
    let (mut daily_maps, mut true_layouts) = (Vec::new(), Vec::new());
    for day in 0..days {
        let layout = (day / 2) % 2;
        let (walls, furniture) = office(geometry, layout);
        let truth = Grid::from_vec(
            geometry,
            walls
                .data()
                .iter()
                .zip(furniture.data())
                .map(|(a, b)| *a || *b)
                .collect(),
        )?;
        let mut mapper = OccupancyMapper::new(geometry, MapperParams::default())?;
        // Patrol: a scan every 0.25 m along the waypoints.
        for leg in waypoints.windows(2) {
            let (a, b): (Vector2<f64>, Vector2<f64>) = (
                Vector2::new(leg[0].0, leg[0].1),
                Vector2::new(leg[1].0, leg[1].1),
            );
            let steps = ((b - a).norm() / 0.25).ceil() as usize;
            let heading = (b - a).y.atan2((b - a).x);
            for s in 0..steps {
                let p = a + (b - a) * (s as f64 / steps as f64);
                let pose = Pose2::new(p, heading);
                let scan = simulate_scan(&truth, &pose, (day * 86_400 + scans) as f64, &mut rng);
                mapper.insert(&scan, &pose)?;
                scans += 1;
            }
        }
        for (t, v) in visits_total
            .data_mut()
            .iter_mut()
            .zip(mapper.visits().data())
        {
            *t += v;
        }
        let map = mapper.occupancy_grid();
        render_occupancy(&map).save_png(out.join(format!("day_{day:02}_map.png")))?;
        composite.add(&map)?;
        daily_maps.push(map);
        true_layouts.push(layout);
    }

    // Which days share a layout (seed 000 III-C/D): the paper's greedy threshold clustering
    // and complete linkage, both on the distance-field similarity matrix.
    let matrix = similarity_matrix(&daily_maps, &DifferenceParams::default())?;
    let params = ClusterParams::default();
    let paper = agreement(&greedy_layouts(&matrix, &params)?.labels, &true_layouts)?;
    let ours = agreement(
        &complete_linkage_layouts(&matrix, &params)?.labels,
        &true_layouts,
    )?;

    // Static structure: occupied on at least 90 % of days. Check it against the true walls.
    let static_cells = composite.static_structure(0.9)?;
    let (walls, _) = office(geometry, 0);
    let near_wall = distance_transform(&walls)?;
    let found = static_cells.data().iter().filter(|&&s| s).count();
    let on_walls = static_cells
        .cells()
        .filter(|(c, s)| **s && near_wall.distance_cells(*c).is_some_and(|d| d <= 1.5))
        .count();
    let precision = on_walls as f64 / found.max(1) as f64;
    // Recall: true wall surfaces (wall cells beside free space) found within 1.5 cells.
    let field = distance_transform(&static_cells)?;
    let surface = |c: Cell| {
        walls[c]
            && [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)]
                .iter()
                .any(|&(dc, dr)| {
                    let n = geometry.checked_cell(c.col as i64 + dc, c.row as i64 + dr);
                    n.is_some_and(|n| !walls[n])
                })
    };
    let surfaces: Vec<Cell> = walls
        .cells()
        .map(|(c, _)| c)
        .filter(|&c| surface(c))
        .collect();
    let recalled = surfaces
        .iter()
        .filter(|&&c| field.distance_cells(c).is_some_and(|d| d <= 1.5))
        .count();
    let recall = recalled as f64 / surfaces.len().max(1) as f64;
    // Tables of either layout must not be taken for static structure.
    let tables = [0, 1].map(|l| office(geometry, l).1);
    let table_cells = static_cells
        .cells()
        .filter(|(c, s)| **s && tables.iter().any(|t| t[*c]))
        .count();

    render_scalar(
        &composite.occupancy_frequency(),
        ColorMap::Viridis,
        Some((0.0, 1.0)),
    )
    .save_png(out.join("composite_frequency.png"))?;
    render_scalar(&field.metres_grid(), ColorMap::Turbo, None)
        .save_png(out.join("static_distance_m.png"))?;
    let visits = visits_total.map(|&v| if v == 0 { f64::NAN } else { f64::from(v).ln() });
    let base = OccupancyGrid::from_values(
        geometry,
        composite
            .static_structure(0.5)?
            .data()
            .iter()
            .map(|&s| if s { 100 } else { 0 })
            .collect(),
    )?;
    render_overlay(&base, &visits, ColorMap::Viridis, None)?
        .save_png(out.join("laser_visits_log.png"))?;

    println!(
        "{{\"days\":{days},\"scans\":{scans},\"cells\":{},\"static_cells\":{found},\"static_precision\":{precision:.4},\"static_recall\":{recall:.4},\"table_cells_in_static\":{table_cells},\"layout_pairwise_accuracy_paper\":{:.4},\"layout_pairwise_accuracy\":{:.4},\"layout_ari\":{:.4},\"out\":\"{}\",\"seconds\":{:.3}}}",
        geometry.len(),
        paper.rand_index,
        ours.rand_index,
        ours.adjusted_rand_index,
        out.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
