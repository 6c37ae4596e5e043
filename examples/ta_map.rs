//! Seed 002's target-activity map on pedestrian trajectories, and paths that avoid activity.
//!
//! `cargo run --release --example ta_map -- --trajectories <file> [--format eth|txy]
//!  [--map-xml <map.xml>|--no-map-xml] [--out DIR] [--resolution M] [--margin M]
//!  [--min-samples N] [--sensor-range M] [--noise V] [--fit-lengthscale]
//!  [--threshold A] [--start X,Y --goal X,Y]`
//!
//! Steps: read the trajectories (`eth`: an ETH/OpenTraj `obsmat.txt`; `txy`: whitespace
//! columns `time id x y`), malformed lines skipped and counted; samples far from the bulk of
//! all samples skipped and counted by the bounds rule every reader of coordinates uses
//! (`haunts::occupancy::bounds`: outside the box of the 0.1 %–99.9 % quantiles of x and y
//! grown on every side by 10 m plus the box's larger side), a trajectory left without samples
//! dropped, the first few named on standard error and all counted in the JSON's
//! `"skipped_rows": {"far": n, "non_finite": n}` (with the lines whose numbers are NaN or
//! infinite); the job fails only when no sample is usable; seed 002's dummy filter
//! (Algorithm 1) with α = `--min-samples` (default 5: the ETH annotations are at 2.5 Hz, so
//! 5 samples are 2 s; β = 1 m and γ = 0.3 m/s are the tracking crate's defaults); Algorithm 2
//! with 3 m cells; GP regression (RBF, σ² = 1, ℓ = 2 m or fitted, σn² = 1; the sparse GP
//! above 2000 samples); the TA map; the confidence map; then plain A* against seed 002's
//! activity-aware A* (and, third, A* with activity in the step cost) between two points on
//! either side of the busiest cell.
//!
//! **The occupancy map.** The ETH sequences come with no occupancy map. The example builds
//! one at `--resolution` (0.1 m) over the bounding box of the kept trajectories with
//! `--margin` (2 m) to spare: every cell free, except the obstacles of the sequence's
//! `map.xml` (OpenTraj's format: `<Line x1 y1 x2 y2>` walls drawn one cell wide and
//! `<Circle x y radius>` poles), read from beside the trajectory file unless `--map-xml`
//! names another or `--no-map-xml` leaves the map all free. Samples that fall on those
//! obstacles are reported (annotation noise near walls). A non-finite coordinate is an
//! error; a line far longer than the grid is clipped to it before it is drawn (a line to
//! 1e300 once saturated its step count and never finished).
//!
//! **The confidence map.** ETH is filmed by a static camera from a building: there is no
//! robot and no robot trajectory. The library's confidence map takes observer positions and
//! a sensor range; here the observer positions are every annotated sample (of kept and dropped
//! trajectories alike: the places the camera demonstrably saw), with `--sensor-range` (3 m
//! by default, one TA cell) as the length scale. High confidence therefore means "the
//! annotations cover this place", low means "nobody was ever annotated near here, so a low
//! activity there is not evidence of a quiet place".
//!
//! **The paths.** Unless `--start` and `--goal` are given, they lie on either side of the
//! busiest free cell (`max_activity_cell`), in straight sight of it, along x or along y: as
//! far as the nearer of the two sides allows (up to 10 m, and 1 m short of a wall or the
//! map's edge), moved to the nearest free cell. Of the two axes the one along the flow is
//! taken (the larger mean activity over the segment): seed 002's case 1, a busy spot between
//! start and goal with room to go around it. (Across a band of walkers, as the ETH flows
//! are, there is no way around and every planner crosses straight.) `--threshold` sets the
//! activity-aware A*'s θ: the seed's 5.5 by default, chosen for its levels of at most ≈ 8;
//! ETH's levels reach hundreds, so nearly every visited cell is above it. The activity-cost A*
//! charges `L · (1 + a / a_max)` per step of length L (weight `1 / a_max`): the seed's
//! normalisation put into the cost, where it keeps A* optimal.
//!
//! **Crossings.** One trip says little about a planner whose heuristic depends on where the
//! busy cells lie relative to the goal. The same three planners also run on `--crossings`
//! trips (default 12) across the busiest cell, one per direction over half a turn, from
//! `--crossing-radius` metres (default 5) on one side to as far on the other
//! (`haunts_planning::crossings`); their metrics are averaged, and `shape` counts the trips
//! on which a planner shows seed 002's Table 2 shape (lower mean and maximum activity than
//! plain A*, longer path).
//!
//! Writes into `--out` (default `out/ta_map`): `cells.png` (Algorithm 2's levels),
//! `ta_map.png` (the TA map on free cells, turbo colours), `confidence.png` (viridis, 0–1),
//! `paths.png` (the TA map with the plain path in black, the activity-aware path in white
//! and the activity-cost path in grey). The last line printed is one JSON object:
//! `{"plain":{"length":..,"activity_mean":..,"activity_var":..,"activity_max":..},
//! "activity_aware":{..},"activity_cost":{..},"crossings":{"trips":..,"no_path":..,"radius":..,
//! "plain":{..},"activity_aware":{..},"activity_cost":{..},"shape":{..}},"ta_map":{..},"skipped_rows":{..}}`
//! (the crossings' metrics are means over the trips), lengths in metres, activity in
//! targets per 3 m cell; `ta_map.seconds` is the wall time from reading the file to the TA
//! raster.

use std::path::{Path, PathBuf};
use std::time::Instant;

use haunts::affordance::ta::{ConfidenceMap, RegressionParams, TaMap, TaParams};
use haunts::occupancy::picture::{ColorMap, render_overlay};
use haunts::occupancy::{Cell, FREE, Grid, GridGeometry, OCCUPIED, UNKNOWN};
use haunts::planning::{
    AStar, ActivityAwareAStar, ActivityAwareParams, ActivityCostAStar, ActivityCostParams, Costmap,
    INSCRIBED_INFLATED_OBSTACLE, LayeredCostmap, Path as PlannedPath, PathMetrics, Planner,
    SEED_THRESHOLD, StaticLayer, crossings, max_activity_cell,
};
use haunts::tracking::track::dummy::{DummyFilterParams, filter_dummies};
use nalgebra::{Point2, Vector2};

mod common;
use common::trajectories::{self, Format};

const USAGE: &str = "usage: ta_map --trajectories <file> [--format eth|txy] \
                     [--map-xml <file>|--no-map-xml] [--out DIR] [--resolution M] \
                     [--margin M] [--min-samples N] [--sensor-range M] [--noise V] \
                     [--fit-lengthscale] [--threshold A] [--start X,Y --goal X,Y] \
                     [--crossings N] [--crossing-radius M]";

/// Farthest the automatic start and goal lie from the busiest cell, metres.
const REACH: f64 = 10.0;

type Error = Box<dyn std::error::Error>;

#[derive(Debug)]
struct Args {
    trajectories: PathBuf,
    format: Format,
    map_xml: Option<PathBuf>,
    out: PathBuf,
    resolution: f64,
    margin: f64,
    min_samples: usize,
    sensor_range: f64,
    noise: f64,
    fit_lengthscale: bool,
    threshold: f64,
    start: Option<Point2<f64>>,
    goal: Option<Point2<f64>>,
    crossings: usize,
    crossing_radius: f64,
}

fn point(s: &str) -> Result<Point2<f64>, Error> {
    let v: Vec<f64> = s
        .split(',')
        .map(|c| c.trim().parse())
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y] => Ok(Point2::new(x, y)),
        _ => Err(format!("expected X,Y, found `{s}`").into()),
    }
}

fn parse_args() -> Result<Args, Error> {
    let mut args = std::env::args().skip(1);
    let (mut trajectories, mut format) = (None, Format::Eth);
    let (mut map_xml, mut no_map_xml) = (None, false);
    let mut out = PathBuf::from("out/ta_map");
    let (mut resolution, mut margin, mut min_samples, mut sensor_range) = (0.1, 2.0, 5, 3.0);
    let mut fit_lengthscale = false;
    let mut noise = 1.0;
    let mut threshold = SEED_THRESHOLD;
    let (mut start, mut goal) = (None, None);
    let (mut crossings, mut crossing_radius) = (12, 5.0);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(USAGE);
        match a.as_str() {
            "--trajectories" => trajectories = Some(PathBuf::from(value()?)),
            "--format" => format = Format::parse(&value()?)?,
            "--map-xml" => map_xml = Some(PathBuf::from(value()?)),
            "--no-map-xml" => no_map_xml = true,
            "--out" => out = value()?.into(),
            "--resolution" => resolution = value()?.parse()?,
            "--margin" => margin = value()?.parse()?,
            "--min-samples" => min_samples = value()?.parse()?,
            "--sensor-range" => sensor_range = value()?.parse()?,
            "--noise" => noise = value()?.parse()?,
            "--fit-lengthscale" => fit_lengthscale = true,
            "--threshold" => threshold = value()?.parse()?,
            "--start" => start = Some(point(&value()?)?),
            "--goal" => goal = Some(point(&value()?)?),
            "--crossings" => crossings = value()?.parse()?,
            "--crossing-radius" => crossing_radius = value()?.parse()?,
            _ => return Err(USAGE.into()),
        }
    }
    let trajectories = trajectories.ok_or(USAGE)?;
    if start.is_some() != goal.is_some() {
        return Err("give both --start and --goal, or neither".into());
    }
    let map_xml = trajectories::map_xml_beside(&trajectories, map_xml, no_map_xml);
    Ok(Args {
        trajectories,
        format,
        map_xml,
        out,
        resolution,
        margin,
        min_samples,
        sensor_range,
        noise,
        fit_lengthscale,
        threshold,
        start,
        goal,
        crossings,
        crossing_radius,
    })
}

/// How far from `from` along `dir` (a unit step) the way stays free, at most `REACH` and
/// 1 m short of the map's edge or of the first obstacle.
fn room(costmap: &Costmap, from: Point2<f64>, dir: Vector2<f64>) -> f64 {
    let step = 0.5 * costmap.geometry().resolution();
    let mut d = 0.0;
    while d < REACH + 1.0 {
        let next = d + step;
        if costmap
            .cost_at_world(from + dir * next)
            .is_none_or(|c| c >= INSCRIBED_INFLATED_OBSTACLE)
        {
            break;
        }
        d = next;
    }
    (d - 1.0).clamp(0.0, REACH)
}

/// Start and goal on either side of `busiest`, in sight of it: along x or along y, as far as
/// the nearer of the two sides allows; of the two axes, the one along the flow (the larger
/// mean activity over the segment), so that there is a way around the busy spot.
fn across(costmap: &Costmap, activity: &Grid<f64>, busiest: Cell) -> Result<(Cell, Cell), Error> {
    let g = costmap.geometry();
    let centre = g.cell_center(busiest);
    let mut best: Option<(f64, Cell, Cell)> = None;
    for dir in [Vector2::new(1.0, 0.0), Vector2::new(0.0, 1.0)] {
        let reach = room(costmap, centre, -dir).min(room(costmap, centre, dir));
        if reach < 1.0 {
            continue;
        }
        let (Some(a), Some(b)) = (
            costmap.nearest_free(centre - dir * reach, 2.0),
            costmap.nearest_free(centre + dir * reach, 2.0),
        ) else {
            continue;
        };
        let steps = (2.0 * reach / g.resolution()).round() as usize;
        let along = (0..=steps)
            .filter_map(|k| {
                let p = centre - dir * reach + dir * (k as f64 * g.resolution());
                activity.at_world(p).copied()
            })
            .sum::<f64>()
            / (steps + 1) as f64;
        if best.is_none_or(|(q, _, _)| along > q) {
            best = Some((along, a, b));
        }
    }
    let (_, start, goal) = best.ok_or("no room for a start and a goal around the busiest cell")?;
    Ok((start, goal))
}

/// Seed 002's Table 2 shape: `q` has a lower mean and a lower maximum activity than `plain`,
/// and is longer.
fn shows_shape(plain: &PathMetrics, q: &PathMetrics) -> bool {
    q.activity_mean < plain.activity_mean
        && q.activity_max < plain.activity_max
        && q.length > plain.length
}

fn json(m: &PathMetrics) -> String {
    format!(
        "{{\"length\":{:.4},\"activity_mean\":{:.4},\"activity_var\":{:.4},\"activity_max\":{:.4}}}",
        m.length, m.activity_mean, m.activity_variance, m.activity_max
    )
}

fn save(picture: haunts::occupancy::picture::Picture, dir: &Path, name: &str) -> Result<(), Error> {
    let path = dir.join(name);
    picture.save_png(&path)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

fn run(args: &Args) -> Result<(), Error> {
    let clock = Instant::now();
    let (parsed, rows) = trajectories::read(&args.trajectories, args.format)?;
    let all = parsed.records;
    let filter = DummyFilterParams::default().with_min_samples(args.min_samples);
    let report = filter_dummies(all.clone(), &filter)?;
    let kept = report.kept;
    if kept.is_empty() {
        return Err(format!(
            "no trajectory passed the dummy filter ({} read, {} dropped)",
            all.len(),
            report.dropped.len()
        )
        .into());
    }
    let kept_points: Vec<Point2<f64>> = kept
        .iter()
        .flat_map(|t| t.samples.iter().map(|s| s.1))
        .collect();
    let geometry =
        GridGeometry::bounding(kept_points.iter().copied(), args.resolution, args.margin)?;
    let mut params =
        TaParams::default().with_regression(RegressionParams::default().with_noise(args.noise));
    if args.fit_lengthscale {
        params = params.with_fitted_lengthscale(0.5, 20.0);
    }
    let ta = TaMap::fit(&kept, geometry, &params)?;
    let ta_seconds = clock.elapsed().as_secs_f64();
    let activity = ta.raster();
    eprintln!(
        "{} trajectories, {} kept by the dummy filter (α = {}, β = {} m, γ = {} m/s), {} dropped; \
         {} samples on a {}×{} map at {} m",
        all.len(),
        kept.len(),
        filter.min_samples,
        filter.min_displacement,
        filter.min_mean_speed,
        report.dropped.len(),
        ta.training().len(),
        geometry.width(),
        geometry.height(),
        geometry.resolution()
    );
    let levels = ta.cells().levels();
    let top = levels.data().iter().copied().fold(0.0, f64::max);
    let peak = activity
        .data()
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    eprintln!(
        "Algorithm 2: {}×{} cells of {} m, busiest {top} targets; GP: {} on {} samples, ℓ = {:.3} m, \
         peak {peak:.2}; fast grid error {:?}; TA map in {ta_seconds:.3} s (read + filter + fit + raster)",
        levels.width(),
        levels.height(),
        params.cell_size,
        if ta.model().is_sparse() {
            "sparse (VFE)"
        } else {
            "exact"
        },
        ta.training().len(),
        ta.lengthscale(),
        ta.grid_check().map(|c| c.max_mean_error)
    );

    // The occupancy map: free, with the obstacles of map.xml.
    let map = trajectories::scene_occupancy(geometry, args.map_xml.as_deref(), &kept_points)?;

    // Confidence: the annotated positions are the observer (see the module docs).
    let observers: Vec<Point2<f64>> = all
        .iter()
        .flat_map(|t| t.samples.iter().map(|s| s.1))
        .collect();
    let confidence = ConfidenceMap::fit(
        &observers,
        geometry,
        args.sensor_range,
        &RegressionParams::default(),
    )?;
    let covered = confidence
        .raster()
        .data()
        .iter()
        .filter(|v| **v > 0.5)
        .count();
    eprintln!(
        "confidence: {} observer positions ({} skipped), range {} m, {:.0} % of cells above 0.5",
        confidence.observers(),
        confidence.skipped(),
        args.sensor_range,
        100.0 * covered as f64 / geometry.len() as f64
    );

    // Planning.
    let costmap = LayeredCostmap::new(geometry)
        .with_layer(StaticLayer::new(&map, false))
        .build()?;
    let busiest = max_activity_cell(activity, &costmap)?;
    let (start, goal) = match (args.start, args.goal) {
        (Some(s), Some(g)) => (
            costmap
                .nearest_free(s, 2.0)
                .ok_or("no free cell near --start")?,
            costmap
                .nearest_free(g, 2.0)
                .ok_or("no free cell near --goal")?,
        ),
        _ => across(&costmap, activity, busiest)?,
    };
    let a_max = activity
        .data()
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    eprintln!(
        "busiest cell at {} (activity {:.2}); start {}, goal {}",
        geometry.cell_center(busiest),
        activity[busiest],
        geometry.cell_center(start),
        geometry.cell_center(goal)
    );
    // Plain A*, the seed's activity-aware A* and the activity-cost A*.
    let weight = if a_max > 0.0 { 1.0 / a_max } else { 0.0 };
    let aware_planner = ActivityAwareAStar::new(
        activity.clone(),
        ActivityAwareParams::default().with_threshold(args.threshold),
    )?;
    let cost_planner = ActivityCostAStar::new(
        activity.clone(),
        ActivityCostParams::default().with_activity_weight(weight),
    )?;
    let planners: [&dyn Planner; 3] = [&AStar::default(), &aware_planner, &cost_planner];
    let [plain, aware, cost] = planners.map(|p| p.plan(&costmap, start, goal));
    let (plain, aware, cost) = (plain?, aware?, cost?);
    let [mp, ma, mc] = [&plain, &aware, &cost].map(|p: &PlannedPath| p.metrics(activity));
    let (mp, ma, mc) = (mp?, ma?, mc?);

    // The same three planners on trips across the busiest cell from every direction.
    let zero = PathMetrics {
        length: 0.0,
        activity_mean: 0.0,
        activity_variance: 0.0,
        activity_max: 0.0,
    };
    let mut sums = [zero; 3];
    let (mut trips, mut no_path, mut shape) = (0usize, 0usize, [0usize; 2]);
    for (s, g) in crossings(&costmap, busiest, args.crossing_radius, args.crossings)? {
        let paths: Result<Vec<PlannedPath>, _> =
            planners.iter().map(|p| p.plan(&costmap, s, g)).collect();
        let Ok(paths) = paths else {
            no_path += 1;
            continue;
        };
        let m: Vec<PathMetrics> = paths
            .iter()
            .map(|p| p.metrics(activity))
            .collect::<Result<_, _>>()?;
        for (sum, m) in sums.iter_mut().zip(&m) {
            sum.length += m.length;
            sum.activity_mean += m.activity_mean;
            sum.activity_variance += m.activity_variance;
            sum.activity_max += m.activity_max;
        }
        for (count, q) in shape.iter_mut().zip(&m[1..]) {
            *count += usize::from(shows_shape(&m[0], q));
        }
        trips += 1;
        eprintln!(
            "crossing {} → {}: plain {:.2} m {:.1}/{:.1}, activity-aware {:.2} m {:.1}/{:.1}, \
             activity-cost {:.2} m {:.1}/{:.1} (length, mean/max activity)",
            geometry.cell_center(s),
            geometry.cell_center(g),
            m[0].length,
            m[0].activity_mean,
            m[0].activity_max,
            m[1].length,
            m[1].activity_mean,
            m[1].activity_max,
            m[2].length,
            m[2].activity_mean,
            m[2].activity_max
        );
    }
    let mean_of = |sum: &PathMetrics| {
        let n = trips.max(1) as f64;
        json(&PathMetrics {
            length: sum.length / n,
            activity_mean: sum.activity_mean / n,
            activity_variance: sum.activity_variance / n,
            activity_max: sum.activity_max / n,
        })
    };
    let crossings_json = format!(
        "{{\"trips\":{trips},\"no_path\":{no_path},\"radius\":{:.2},\"plain\":{},\"activity_aware\":{},\
         \"activity_cost\":{},\"shape\":{{\"activity_aware\":{},\"activity_cost\":{}}}}}",
        args.crossing_radius,
        mean_of(&sums[0]),
        mean_of(&sums[1]),
        mean_of(&sums[2]),
        shape[0],
        shape[1]
    );
    eprintln!(
        "{trips} crossings of the busiest cell ({no_path} without a path): the expected shape \
         (lower mean and max activity, longer) on {} for the activity-aware A*, {} for the \
         activity-cost A*",
        shape[0], shape[1]
    );

    // Pictures.
    std::fs::create_dir_all(&args.out)?;
    let cells = Grid::from_fn(geometry, |c| {
        levels
            .at_world(geometry.cell_center(c))
            .copied()
            .unwrap_or(f64::NAN)
    });
    save(
        render_overlay(&map, &cells, ColorMap::Turbo, None)?,
        &args.out,
        "cells.png",
    )?;
    save(
        render_overlay(&map, activity, ColorMap::Turbo, None)?,
        &args.out,
        "ta_map.png",
    )?;
    save(
        render_overlay(
            &map,
            confidence.raster(),
            ColorMap::Viridis,
            Some((0.0, 1.0)),
        )?,
        &args.out,
        "confidence.png",
    )?;
    let range = Some((
        activity
            .data()
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min),
        a_max,
    ));
    let mut drawn = map.clone();
    let mut layer = activity.clone();
    for &c in cost.cells() {
        drawn.set(c, UNKNOWN);
    }
    for &c in plain.cells() {
        drawn.set(c, OCCUPIED);
    }
    for &c in aware.cells() {
        if let Some(v) = layer.get_mut(c) {
            *v = f64::NAN;
        }
        drawn.set(c, FREE);
    }
    save(
        render_overlay(&drawn, &layer, ColorMap::Turbo, range)?,
        &args.out,
        "paths.png",
    )?;

    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{\"plain\":{},\"activity_aware\":{},\"activity_cost\":{},\"crossings\":{crossings_json},\
         \"ta_map\":{{\"trajectories\":{},\"kept\":{},\"samples\":{},\"sparse\":{},\"lengthscale\":{:.4},\
         \"peak\":{:.4},\"seconds\":{:.4}}},\"skipped_rows\":{}}}",
            json(&mp),
            json(&ma),
            json(&mc),
            all.len(),
            kept.len(),
            ta.training().len(),
            ta.model().is_sparse(),
            ta.lengthscale(),
            peak,
            ta_seconds,
            rows.json()
        ))
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    common::report(parse_args().and_then(|args| run(&args)))
}
