//! Fits seed 001's hypertime model to days of people detections and scores it on a test day
//! against the time-independent baseline (the same clustering without the time dimensions).
//!
//! `cargo run --release --example hypertime -- --train <file>... --test <file> --cols T,X,Y
//!  [--delimiter ','] [--out DIR] [--clusters K] [--periods T1,T2,…|auto] [--auto-k]
//!  [--seed S] [--grid METRES] [--time-step SECONDS]`
//!
//! Columns are 0-based indices of the UNIX time and of x, y in metres; fields are separated by
//! whitespace unless `--delimiter` says otherwise; malformed lines are skipped and counted.
//! Both models are scored by the mean log-likelihood per test detection with one spatial
//! normalisation: each model's density is divided by its mass over a common grid (`--grid`
//! cells, default 0.25 m, bounding every detection with 1 m to spare), at the detection's time
//! rounded to `--time-step` seconds (default 60). `--periods` defaults to one day (seed
//! 001); `auto` chooses them with FreMEn, `--auto-k` chooses k by held-out likelihood (for
//! each model on its own). Both searches hold out interleaved 10-minute blocks of the training
//! data, so with a single training day they cannot tell a rhythm that repeats across days from
//! one that happened once.
//!
//! Writes `strip.png` into `--out` (default `out/hypertime`): the predicted density every
//! full hour of the test day's span, left to right, then the baseline, on one colour scale
//! (viridis of the square root of the density).
//! The last line printed is one JSON object; `seconds` is the wall time of fitting and scoring.

use std::path::PathBuf;
use std::time::Instant;

use haunts::affordance::DensityMap;
use haunts::affordance::hypertime::{
    ClusterSearch, DetectionColumns, HypertimeModel, HypertimeParams, PeriodSearch, TimedPoint,
    grid_log_likelihood, read_detections,
};
use haunts::occupancy::picture::{ColorMap, render_scalar};
use haunts::occupancy::{Grid, GridGeometry};
use haunts::tracking::Delimiter;

mod common;

const USAGE: &str = "usage: hypertime --train <file>... --test <file> --cols T,X,Y \
                     [--delimiter C] [--out DIR] [--clusters K] [--periods T1,T2|auto] \
                     [--auto-k] [--time-radius METRES|spread] [--seed S] [--grid METRES] \
                     [--time-step SECONDS]";

/// Resolution of the pictures, metres.
const PICTURE_RESOLUTION: f64 = 0.1;
/// Transparent columns between two frames of the strip.
const GAP: usize = 6;

struct Args {
    train: Vec<PathBuf>,
    test: PathBuf,
    columns: DetectionColumns,
    out: PathBuf,
    params: HypertimeParams,
    grid: f64,
    time_step: f64,
}

fn parse_args() -> Result<Args, Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).peekable();
    let (mut train, mut test, mut cols) = (Vec::new(), None, None);
    let mut delimiter = Delimiter::Whitespace;
    let mut out = PathBuf::from("out/hypertime");
    let mut params = HypertimeParams::default();
    let (mut grid, mut time_step) = (0.25, 60.0);
    while let Some(a) = args.next() {
        if a == "--train" {
            while let Some(file) = args.next_if(|f| !f.starts_with("--")) {
                train.push(PathBuf::from(file));
            }
            continue;
        }
        let mut value = || args.next().ok_or(USAGE);
        match a.as_str() {
            "--test" => test = Some(PathBuf::from(value()?)),
            "--cols" => {
                let v: Vec<usize> = value()?
                    .split(',')
                    .map(|c| c.trim().parse())
                    .collect::<Result<_, _>>()?;
                let [t, x, y] = v[..] else {
                    return Err(USAGE.into());
                };
                cols = Some((t, x, y));
            }
            "--delimiter" => {
                let v = value()?;
                let mut chars = v.chars();
                delimiter = match (chars.next(), chars.next()) {
                    (Some(c), None) => Delimiter::Char(c),
                    _ => return Err("--delimiter takes one character".into()),
                };
            }
            "--out" => out = value()?.into(),
            "--clusters" => params = params.with_clusters(value()?.parse()?),
            "--periods" => {
                let v = value()?;
                params = if v == "auto" {
                    params
                        .with_periods(Vec::new())
                        .with_period_search(Some(PeriodSearch::default()))
                } else {
                    params.with_periods(
                        v.split(',')
                            .map(|p| p.trim().parse())
                            .collect::<Result<_, _>>()?,
                    )
                };
            }
            "--auto-k" => params = params.with_cluster_search(Some(ClusterSearch::default())),
            "--time-radius" => {
                let v = value()?;
                params = params.with_time_radius(if v == "spread" {
                    None
                } else {
                    Some(v.parse()?)
                });
            }
            "--seed" => params.gk.seed = value()?.parse()?,
            "--grid" => grid = value()?.parse()?,
            "--time-step" => time_step = value()?.parse()?,
            _ => return Err(USAGE.into()),
        }
    }
    let (t, x, y) = cols.ok_or(USAGE)?;
    if train.is_empty() {
        return Err(USAGE.into());
    }
    Ok(Args {
        train,
        test: test.ok_or(USAGE)?,
        columns: DetectionColumns::default()
            .with_columns(t, x, y)
            .with_delimiter(delimiter),
        out,
        params,
        grid,
        time_step,
    })
}

fn read(
    path: &PathBuf,
    columns: &DetectionColumns,
) -> Result<(Vec<TimedPoint>, usize), Box<dyn std::error::Error>> {
    let parsed = read_detections(path, columns)?;
    if parsed.skipped > 0 {
        eprintln!(
            "{}: skipped {} malformed lines",
            path.display(),
            parsed.skipped
        );
        for s in &parsed.first_skipped {
            eprintln!("  line {}: {}", s.line, s.reason);
        }
    }
    Ok((parsed.records, parsed.skipped))
}

/// The frames side by side (row 0 at the bottom), `GAP` transparent columns apart.
fn strip(frames: &[Grid<f64>]) -> Result<Grid<f64>, Box<dyn std::error::Error>> {
    let first = frames.first().ok_or("no frame")?.geometry();
    let (w, h) = (first.width(), first.height());
    let width = frames.len() * w + (frames.len() - 1) * GAP;
    let mut data = Vec::with_capacity(width * h);
    for row in 0..h {
        for (i, f) in frames.iter().enumerate() {
            if i > 0 {
                data.extend(std::iter::repeat_n(f64::NAN, GAP));
            }
            data.extend_from_slice(f.row(row));
        }
    }
    let geometry = GridGeometry::new(first.resolution(), first.origin(), width, h)?;
    Ok(Grid::from_vec(geometry, data)?)
}

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = parse_args()?;
    let mut train = Vec::new();
    let mut skipped = 0;
    for path in &args.train {
        let (points, s) = read(path, &args.columns)?;
        train.extend(points);
        skipped += s;
    }
    let (test, s) = read(&args.test, &args.columns)?;
    skipped += s;

    let start = Instant::now();
    let model = HypertimeModel::fit(&train, &args.params)?;
    let baseline = HypertimeModel::fit(&train, &args.params.clone().without_time())?;
    let positions = train.iter().chain(&test).map(|p| p.position);
    let grid = GridGeometry::bounding(positions.clone(), args.grid, 1.0)?;
    let ht = grid_log_likelihood(&model, &test, &grid, args.time_step)?;
    let st = grid_log_likelihood(&baseline, &test, &grid, args.time_step)?;
    let seconds = start.elapsed().as_secs_f64();

    let selection = &model.report().selection;
    if let Some(start) = selection.start_loglik {
        println!("period search: held-out loglik without new periods {start:.4}");
    }
    for step in &selection.period_steps {
        println!(
            "  period {:.0} s (amplitude {:.4}): held-out loglik {:.4} {}",
            step.period,
            step.amplitude,
            step.heldout_loglik,
            if step.accepted { "kept" } else { "rejected" }
        );
    }
    for (k, score) in &selection.cluster_scores {
        println!("k = {k}: held-out loglik {score:.4}");
    }
    let converged = |m: &HypertimeModel| {
        let r = m.report();
        if r.converged {
            format!("converged in {} iterations", r.iterations)
        } else {
            format!(
                "{} iterations, last membership change {:.1e}",
                r.iterations, r.change
            )
        }
    };
    println!(
        "hypertime: {} clusters, periods {:?} s, {}; baseline: {} clusters, {}",
        model.clusters(),
        model.periods(),
        converged(&model),
        baseline.clusters(),
        converged(&baseline)
    );
    println!(
        "test: {} scored, {} outside the grid; hypertime {:.4}, baseline {:.4} nats per detection",
        ht.used,
        ht.outside,
        ht.mean().unwrap_or(f64::NAN),
        st.mean().unwrap_or(f64::NAN)
    );

    // The strip: every full hour of the test day's span, then the baseline.
    let picture = GridGeometry::bounding(positions, PICTURE_RESOLUTION, 1.0)?;
    let (lo, hi) = test
        .iter()
        .map(|p| p.time)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t), b.max(t))
        });
    let mut frames = Vec::new();
    let mut hours = Vec::new();
    if lo <= hi {
        let mut hour = (lo / 3600.0).floor();
        while hour <= (hi / 3600.0).ceil() && hours.len() < 48 {
            frames.push(model.at(hour * 3600.0).rasterise(&picture));
            hours.push((hour as i64).rem_euclid(24));
            hour += 1.0;
        }
    }
    frames.push(baseline.at(0.0).rasterise(&picture));
    let max = frames
        .iter()
        .flat_map(|f| f.data().iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    std::fs::create_dir_all(&args.out)?;
    let path = args.out.join("strip.png");
    // Colour by the square root of the density, so that quiet places stay visible beside the
    // peaks.
    let shown = strip(&frames)?.map(|v| v.sqrt());
    render_scalar(
        &shown,
        ColorMap::Viridis,
        Some((0.0, max.sqrt().max(1e-12))),
    )
    .save_png(&path)?;
    println!(
        "wrote {}: hours {:?} (UTC), then the baseline; colour = √density, 0 to {max:.3} per m²",
        path.display(),
        hours
    );

    let json_number = |v: Option<f64>| match v {
        Some(v) if v.is_finite() => format!("{v:.6}"),
        _ => "null".into(),
    };
    let periods: Vec<String> = model.periods().iter().map(|p| format!("{p}")).collect();
    println!(
        "{{\"hypertime_loglik\":{},\"static_loglik\":{},\"periods_s\":[{}],\"clusters\":{},\"train\":{},\"test\":{},\"skipped\":{},\"seconds\":{:.3}}}",
        json_number(ht.mean()),
        json_number(st.mean()),
        periods.join(","),
        model.clusters(),
        model.report().points,
        ht.used,
        skipped,
        seconds
    );
    Ok(())
}
