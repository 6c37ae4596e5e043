//! Fits seed 001's hypertime model to days of people detections and scores it on a test day
//! against the time-independent baseline (the same clustering without the time dimensions).
//!
//! `cargo run --release --example hypertime -- [--cols T,X,Y] [--delimiter C|ws]
//!  --train <file>... [--cols …] [--delimiter …] --test <file> [--out DIR] [--clusters K]
//!  [--periods T1,T2,…|auto] [--auto-k] [--seed S] [--grid METRES] [--time-step SECONDS]
//!  [--no-background] [--no-calibration] [--trust-periods] [--moments fuzzy|membership]`
//!
//! Columns are 0-based indices of the UNIX time and of x, y in metres (default `0,1,2`);
//! fields are separated by whitespace unless `--delimiter` says otherwise (`ws` goes back to
//! whitespace). `--cols` and `--delimiter` apply to the files named after them, so training
//! and test files of different formats work in one run. Malformed lines are skipped and
//! counted (`skipped`).
//!
//! **One bad row is skipped, not fatal.** In each file, a detection far from the bulk of that
//! file's detections is skipped and counted by the bounds rule every reader of coordinates
//! uses (`haunts::occupancy::bounds`): far means outside the box of the 0.1 %–99.9 %
//! quantiles of x and y grown on every side by 10 m plus the box's larger side (so a glitch at
//! x = 10⁷ m among real detections goes, a sparse corridor of the site stays). Far rows and
//! lines with a NaN or infinite number are counted in the JSON's
//! `"skipped_rows": {"far": n, "non_finite": n}`, the first few named on standard error; the
//! job fails only when a file has no usable detection left.
//!
//! Both models are scored over one grid (`--grid` cells, default 0.25 m) bounding the
//! *training* detections with 1 m to spare: each model's density is divided by its mass over
//! that grid at the detection's time rounded to `--time-step` seconds (default 60); test
//! detections outside it are counted (`outside_training_area`), not scored. A grid over the
//! cell budget (`haunts::occupancy::budget`, 2²⁸ cells: a tiny `--grid`) is refused before
//! fitting, the error naming its extent. Reported beside
//! the mean log-likelihood: the median, the share below −20 nats, the uniform reference
//! `−ln(grid area)`, the RMSE of counts over 1 m × 10 min cells (and the uniform density's)
//! and the share of detections in the densest 10 % of the cells of their 10 minutes
//! (`haunts_affordance::hypertime::evaluate`).
//!
//! `--periods` defaults to one day (seed 001); `auto` chooses them with FreMEn, `--auto-k`
//! chooses k (for each model on its own). Every period is validated on held-out whole days of
//! the training data (`CycleValidation`): a searched period needs two cycles spread over two
//! days and a gain on the held-out days (one training day validates no period, so `auto`
//! is then the static model); a given period the data cannot check (one day of training for
//! a daily period) is kept unless `--validate-periods`, and `--trust-periods` skips the check. The
//! spatial floor and the background's weight are chosen on held-out hours of the training
//! data (`--no-calibration`: 0.1 m and 0.01; `--no-background`: none). Nothing is chosen on
//! the test file.
//!
//! Writes `strip.png` into `--out` (default `out/hypertime`): the predicted density every
//! full hour of the test day's span (at most 48), left to right, then the baseline, on one
//! colour scale (viridis of the square root of the density), over the training and test
//! detections at 0.1 m cells. The strip is optional: where that would be over the work
//! budget (a test day recorded over a much wider area) it is drawn with coarser cells
//! (`haunts::occupancy::budget::fit_grid`), and says so on standard error and in the JSON's
//! `"strip": {"resolution": m, "hours": n, "note": text}` (`note` only when coarsened); the
//! scores are the same.
//! The last line printed is one JSON object; `seconds` is the wall time of fitting and scoring.

use std::path::PathBuf;
use std::time::Instant;

use haunts::affordance::DensityMap;
use haunts::affordance::hypertime::{
    ClusterSearch, DetectionColumns, Evaluation, EvaluationParams, GivenPeriods, HypertimeModel,
    HypertimeParams, Moments, PeriodSearch, TimedPoint, evaluate_with_training, read_detections,
    time_units_note,
};
use haunts::occupancy::bounds::{BoundsRule, RowCounts};
use haunts::occupancy::picture::{ColorMap, render_scalar};
use haunts::occupancy::{Grid, GridGeometry};
use haunts::tracking::Delimiter;

mod common;

const USAGE: &str = "usage: hypertime [--cols T,X,Y] [--delimiter C|ws] --train <file>... \
                     [--cols T,X,Y] [--delimiter C|ws] --test <file> [--out DIR] \
                     [--clusters K] [--periods T1,T2|auto] [--auto-k] \
                     [--time-radius METRES|spread] [--seed S] [--grid METRES] \
                     [--time-step SECONDS] [--no-background] [--no-calibration] \
                     [--trust-periods|--validate-periods] [--moments fuzzy|membership]   (--cols and --delimiter apply to \
                     the files after them)";

/// Resolution of the pictures, metres.
const PICTURE_RESOLUTION: f64 = 0.1;
/// Most hours the strip shows.
const MAX_HOURS: usize = 48;
/// Transparent columns between two frames of the strip.
const GAP: usize = 6;

struct Args {
    /// Each file with the format it is read with.
    train: Vec<(PathBuf, DetectionColumns)>,
    test: (PathBuf, DetectionColumns),
    out: PathBuf,
    params: HypertimeParams,
    grid: f64,
    time_step: f64,
}

fn parse_args() -> Result<Args, Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).peekable();
    let (mut train, mut test) = (Vec::new(), None);
    let mut columns = DetectionColumns::default();
    let mut out = PathBuf::from("out/hypertime");
    let mut params = HypertimeParams::default();
    let (mut grid, mut time_step) = (0.25, 60.0);
    while let Some(a) = args.next() {
        if a == "--train" {
            while let Some(file) = args.next_if(|f| !f.starts_with("--")) {
                train.push((PathBuf::from(file), columns));
            }
            continue;
        }
        let mut value = || args.next().ok_or(USAGE);
        match a.as_str() {
            "--test" => test = Some((PathBuf::from(value()?), columns)),
            "--cols" => {
                let v: Vec<usize> = value()?
                    .split(',')
                    .map(|c| c.trim().parse())
                    .collect::<Result<_, _>>()?;
                let [t, x, y] = v[..] else {
                    return Err(USAGE.into());
                };
                columns = columns.with_columns(t, x, y).check()?;
            }
            "--delimiter" => {
                let v = value()?;
                let mut chars = v.chars();
                columns = columns.with_delimiter(match (chars.next(), chars.next()) {
                    _ if v == "ws" => Delimiter::Whitespace,
                    (Some(c), None) => Delimiter::Char(c),
                    _ => return Err("--delimiter takes one character, or ws".into()),
                });
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
            "--no-background" => params = params.with_background(None),
            "--no-calibration" => params = params.with_calibration(None),
            "--moments" => {
                params = params.with_moments(match value()?.as_str() {
                    "fuzzy" => Moments::Fuzzy,
                    "membership" => Moments::Membership,
                    _ => return Err("--moments takes fuzzy or membership".into()),
                })
            }
            "--trust-periods" => {
                let v = params.validation.with_given(GivenPeriods::Trust);
                params = params.with_validation(v);
            }
            "--validate-periods" => {
                let v = params.validation.with_given(GivenPeriods::Validate);
                params = params.with_validation(v);
            }
            "--seed" => params.gk.seed = value()?.parse()?,
            "--grid" => grid = value()?.parse()?,
            "--time-step" => time_step = value()?.parse()?,
            _ => return Err(USAGE.into()),
        }
    }
    if train.is_empty() {
        return Err(USAGE.into());
    }
    Ok(Args {
        train,
        test: test.ok_or(USAGE)?,
        out,
        params,
        grid,
        time_step,
    })
}

/// One file's detections: malformed lines skipped and counted, then far and non-finite
/// positions by the bounds rule (`haunts::occupancy::bounds`), each reported on standard
/// error.
fn read(
    path: &PathBuf,
    columns: &DetectionColumns,
) -> Result<FileRows, Box<dyn std::error::Error>> {
    let parsed = read_detections(path, columns)?;
    common::report_malformed(path, &parsed);
    let kept = BoundsRule::default().split("detections", parsed.records, |p| p.position)?;
    for line in kept.skipped.describe(|i| format!("detection {i}")) {
        eprintln!("{}: {line}", path.display());
    }
    let mut rows = kept.skipped.counts;
    rows.non_finite += parsed.non_finite;
    let note = time_units_note(&kept.rows);
    if let Some(note) = &note {
        eprintln!("warning: {}: {note}", path.display());
    }
    Ok(FileRows {
        points: kept.rows,
        malformed: parsed.skipped,
        rows,
        unit_warning: usize::from(note.is_some()),
    })
}

/// What [`read`] found in one file.
struct FileRows {
    /// The detections kept.
    points: Vec<TimedPoint>,
    /// Malformed lines skipped.
    malformed: usize,
    /// Rows skipped by the bounds rule (and lines with a non-finite number), by reason.
    rows: RowCounts,
    /// 1 when the times do not look like UNIX seconds.
    unit_warning: usize,
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
    // Lines skipped, and files whose times do not look like UNIX seconds.
    let (mut skipped, mut unit_warnings, mut rows) = (0, 0, RowCounts::default());
    let mut add = |file: FileRows| {
        skipped += file.malformed;
        rows += file.rows;
        unit_warnings += file.unit_warning;
        file.points
    };
    for (path, columns) in &args.train {
        train.extend(add(read(path, columns)?));
    }
    let test = add(read(&args.test.0, &args.test.1)?);

    // The known area: the training detections' bounds (never the test set's), refused before
    // any fitting if over the cell budget.
    let grid = GridGeometry::bounding(train.iter().map(|p| p.position), args.grid, 1.0)?;
    let start = Instant::now();
    let model = HypertimeModel::fit(&train, &args.params)?;
    let baseline = HypertimeModel::fit(&train, &args.params.clone().without_time())?;
    let eval = EvaluationParams::default().with_time_step(args.time_step);
    let ht = evaluate_with_training(&model, &train, &test, &grid, &eval)?;
    let st = evaluate_with_training(&baseline, &train, &test, &grid, &eval)?;
    let seconds = start.elapsed().as_secs_f64();

    let selection = &model.report().selection;
    for step in &selection.period_steps {
        println!(
            "period {:.0} s ({}, {} cycles in {} held-out blocks of training): left-out blocks {} without, {} with: {}",
            step.period,
            step.amplitude
                .map_or("given".into(), |a| format!("amplitude {a:.4}")),
            step.cycles,
            step.blocks,
            step.without_loglik
                .map_or("not checked".into(), |v| format!("{v:.4}")),
            step.heldout_loglik
                .map_or("not checked".into(), |v| format!("{v:.4}")),
            match (step.accepted, step.kept) {
                (true, _) => "validated",
                (false, true) => "not validated, kept as given",
                (false, false) => "rejected",
            }
        );
    }
    if selection.no_period_validated() {
        println!(
            "no period was validated{}",
            if model.periods().is_empty() {
                ": the hypertime model is the static model"
            } else {
                " (the given periods are kept unverified)"
            }
        );
    }
    for (k, score) in &selection.cluster_scores {
        println!("k = {k}: held-out loglik {score:.4}");
    }
    for (name, m) in [("hypertime", &model), ("static", &baseline)] {
        let r = m.report();
        println!(
            "{name}: {} clusters, periods {:?} s, {}; spatial floor {} m, background weight {} \
             (chosen on held-out hours of the training data), uniform weight w = {} (chosen \
             on the training data's later part)",
            m.clusters(),
            m.periods(),
            if r.converged {
                format!("converged in {} iterations", r.iterations)
            } else {
                format!(
                    "{} iterations, last membership change {:.1e}",
                    r.iterations, r.change
                )
            },
            r.spatial_floor,
            r.background_weight,
            r.uniform_weight
        );
    }
    println!(
        "test: {} scored, {} outside the training area, {} skipped; uniform reference {:.4}",
        ht.loglik.used, ht.loglik.outside, ht.loglik.skipped, ht.uniform_loglik
    );
    for (name, e) in [("hypertime", &ht), ("static", &st)] {
        println!(
            "  {name}: mean {:.4}, median {:.4} nats, {:.1} % below -20; count RMSE {:.4} \
             (uniform {:.4}), top-10 % cells hit {:.1} %",
            e.mean().unwrap_or(f64::NAN),
            e.median.unwrap_or(f64::NAN),
            100.0 * e.share_low,
            e.count_rmse.unwrap_or(f64::NAN),
            e.uniform_count_rmse.unwrap_or(f64::NAN),
            100.0 * e.top_hit_rate.unwrap_or(f64::NAN)
        );
        if let Some(v) = &e.visits {
            for (side, part) in [("visited", &v.visited), ("not visited", &v.unvisited)] {
                println!(
                    "    in cells the training data {side}: {:.1} % of the detections, mean {}",
                    100.0 * part.share,
                    part.mean().map_or("-".into(), |m| format!("{m:.4} nats"))
                );
            }
        }
    }
    let positions: Vec<_> = train.iter().chain(&test).map(|p| p.position).collect();

    // The strip: every full hour of the test day's span (at most `MAX_HOURS`), then the
    // baseline; drawn coarser when a wide test area would put it over the budgets.
    let (lo, hi) = test
        .iter()
        .map(|p| p.time)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t), b.max(t))
        });
    let span = if lo <= hi {
        ((hi / 3600.0).ceil() - (lo / 3600.0).floor() + 1.0).min(MAX_HOURS as f64) as usize
    } else {
        0
    };
    let picture = haunts::occupancy::budget::fit_grid(
        &positions,
        PICTURE_RESOLUTION,
        1.0,
        "hourly strip",
        &[
            ("frames", span as f64 + 1.0),
            ("components", model.components().len() as f64 + 1.0),
            haunts::affordance::hypertime::DENSITY_UNITS,
        ],
    )?;
    let strip_note = (picture.resolution() > PICTURE_RESOLUTION).then(|| {
        format!(
            "the strip is drawn at {} m cells instead of {PICTURE_RESOLUTION} m: at \
             {PICTURE_RESOLUTION} m its {span} hours over this area would be over the budgets",
            picture.resolution()
        )
    });
    if let Some(note) = &strip_note {
        eprintln!("note: {note}");
    }
    let mut frames = Vec::new();
    let mut hours = Vec::new();
    if lo <= hi {
        let mut hour = (lo / 3600.0).floor();
        while hour <= (hi / 3600.0).ceil() && hours.len() < span {
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

    let periods: Vec<String> = model.periods().iter().map(|p| format!("{p}")).collect();
    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{\"hypertime\":{},\"static\":{},\"uniform_loglik\":{},\"periods_s\":[{}],\
         \"period_validated\":{},\"clusters\":{},\"train\":{},\"test\":{},\
         \"outside_training_area\":{},\"skipped\":{},\"skipped_rows\":{},\
         \"strip\":{{\"resolution\":{},\"hours\":{}{}}},\"time_units_warnings\":{},\"seconds\":{:.3}}}",
            metrics_json("hypertime", &ht, &model)?,
            metrics_json("static", &st, &baseline)?,
            number("uniform_loglik", Some(ht.uniform_loglik))?,
            periods.join(","),
            !selection.no_period_validated(),
            model.clusters(),
            model.report().points,
            ht.loglik.used,
            ht.loglik.outside,
            skipped,
            rows.json(),
            picture.resolution(),
            hours.len(),
            strip_note.map_or(String::new(), |n| format!(",\"note\":{n:?}")),
            unit_warnings,
            seconds
        ))
    );
    Ok(())
}

/// A finite number for the JSON, or an error naming the figure that is missing or not
/// finite (never a `null` with a successful exit).
fn number(name: &str, v: Option<f64>) -> Result<String, Box<dyn std::error::Error>> {
    match v {
        Some(v) if v.is_finite() => Ok(format!("{v:.6}")),
        Some(v) => {
            Err(format!("{name} is {v}: a test detection the model gives no density").into())
        }
        None => {
            Err(format!("{name}: no test detection inside the training area was scored").into())
        }
    }
}

/// One model's figures as a JSON object: the scores, the uniform reference beside them, the
/// split by visited cells (a side without detections has no `loglik`, never a null) and the
/// weights of the background and the uniform component.
fn metrics_json(
    name: &str,
    e: &Evaluation,
    model: &HypertimeModel,
) -> Result<String, Box<dyn std::error::Error>> {
    let side = |part: &haunts::affordance::hypertime::VisitPart| -> String {
        let loglik = part
            .mean()
            .filter(|m| m.is_finite())
            .map_or(String::new(), |m| format!(",\"loglik\":{m:.6}"));
        format!(
            "{{\"share\":{:.6},\"detections\":{}{loglik}}}",
            part.share, part.detections
        )
    };
    let visits = e.visits.as_ref().map_or(String::new(), |v| {
        format!(
            ",\"visited\":{},\"unvisited\":{}",
            side(&v.visited),
            side(&v.unvisited)
        )
    });
    let r = model.report();
    Ok(format!(
        "{{\"loglik\":{},\"median\":{},\"share_below_-20\":{:.6},\"count_rmse\":{},\
         \"uniform_count_rmse\":{},\"top_cells_hit_rate\":{},\"uniform_loglik\":{}{visits},\
         \"spatial_floor\":{},\"background_weight\":{},\"uniform_weight\":{}}}",
        number(&format!("{name} loglik"), e.mean())?,
        number(&format!("{name} median"), e.median)?,
        e.share_low,
        number(&format!("{name} count_rmse"), e.count_rmse)?,
        number(&format!("{name} uniform_count_rmse"), e.uniform_count_rmse)?,
        number(&format!("{name} top_cells_hit_rate"), e.top_hit_rate)?,
        number("uniform_loglik", Some(e.uniform_loglik))?,
        r.spatial_floor,
        r.background_weight,
        r.uniform_weight,
    ))
}
