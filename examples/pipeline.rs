//! The main job: `cargo run --release --example pipeline [-- --days 70 --out out/pipeline]`.
//!
//! Seed 000's layout-aware affordance loop, seed 001's hypertime model and seed 002's TA map
//! on days of the simulated office, each stage one call of [`haunts::pipeline::study`]:
//! the days (scan-matched, mapped, tracked, scored against the simulator's truth), the layout
//! library against the paper's clustering, each layout's affordance map at its own tables,
//! hypertime against its static baseline on held-out days, the TA map, plans across the
//! room (plain, activity-aware, and with the affordance map as a costmap layer), and the same
//! trip at 08:00 and at 12:30 with the affordance at each hour as the layer.
//!
//! Writes to the output folder: figures (PNG), `index.html` showing them with the figures as
//! a table, `run.mcap` (maps, costmaps, tracks, paths, hypertime by hour; for Foxglove), the
//! layout library, and the hypertime points (`time x y`, for the `hypertime` example). The
//! last line printed is one JSON object with the figures.

use std::path::PathBuf;
use std::time::Instant;

use haunts::affordance::{HypertimeParams, LayoutParams};
use haunts::figure::{MapFigure, Report};
use haunts::occupancy::picture::ColorMap;
use haunts::pipeline::results::ResultsMcap;
use haunts::pipeline::serve::{ServeParams, activity_along, percentile, serve_layout};
use haunts::pipeline::{DayProcessor, PipelineParams, study};
use haunts::planning::PathMetrics;
use haunts::sim::{PatrolParams, SimParams, Simulator};
use haunts::similarity::ClusterParams;
use haunts::tracking::eval::mot::ClearMot;
use nalgebra::Point2;
use serde_json::json;

mod common;

const USAGE: &str = "usage: pipeline [--days N] [--out DIR] [--seed S]";

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let start = Instant::now();
    let (mut days, mut out, mut seed) = (70usize, PathBuf::from("out/pipeline"), 1u64);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let value = args.next().ok_or(USAGE)?;
        match a.as_str() {
            "--days" => days = value.parse()?,
            "--out" => out = value.into(),
            "--seed" => seed = value.parse()?,
            _ => return Err(format!("unknown argument {a}; {USAGE}").into()),
        }
    }
    if !(5..=10_000).contains(&days) {
        return Err(format!(
            "--days must be in 5..=10000 (every fifth day is a test day; days are kept in memory); {USAGE}"
        )
        .into());
    }
    std::fs::create_dir_all(&out)?;
    let mut figures = Report::new(format!("haunts: {days} simulated days (seed {seed})"));
    let save = |figure: MapFigure<'_>, file: &str| -> Result<(), Box<dyn std::error::Error>> {
        figure.save(out.join(file))?;
        Ok(())
    };

    // Five 3-minute patrols a day, every two hours from 8:30.
    let patrol = PatrolParams::sessions(8.5 * 3600.0, 180.0, 7200.0, 5);
    let sim = Simulator::new(SimParams::default().with_seed(seed).with_patrol(patrol))?;
    let processor = DayProcessor::new(sim.geometry(), PipelineParams::default())?;
    let geometry = *processor.geometry();
    let mut clock = Instant::now();
    let mut stage = |name: &str| {
        eprintln!("stage {name}: {:.2} s", clock.elapsed().as_secs_f64());
        clock = Instant::now();
    };
    let results =
        study::simulate_days(&sim, &processor, 0..days, |n| eprint!("\rdays {n}/{days}"))?;
    eprintln!();
    stage("days (simulated and processed)");
    let mot = ClearMot::pooled(results.iter().map(|r| r.score.mot));
    let mean =
        |f: fn(&study::SimulatedDay) -> f64| results.iter().map(f).sum::<f64>() / days as f64;

    // Composite maps keep what 35 % of a layout's days saw (chairs moved by 12 cm fill a
    // cell on fewer than half the days); densities need 30 visits a cell (BENCHMARKS.md).
    let layout_params = LayoutParams::default()
        .with_min_visits(30)
        .with_composite_min_fraction(0.35);
    let layouts = study::layouts(&results, geometry, layout_params, &ClusterParams::default())?;
    layouts.library.save(out.join("layouts.haunts"))?;
    let own = study::own_tables(&layouts.library, &results);
    stage("layouts");
    let mut mcap = ResultsMcap::create(out.join("run.mcap"))?;
    for layout in layouts.library.layouts() {
        let (id, served) = (
            layout.id().0,
            serve_layout(layout, &ServeParams::default())?,
        );
        mcap.layout(id, &served, 0.0)?;
        let file = format!("layout_{id}_affordance.png");
        let title = format!("Layout {id}: affordance ({} days)", layout.days().len());
        save(served.figure(title), &file)?;
        figures = figures.figure(file, format!("Layout {id}'s affordance map (human hits / visits, colour to its 99th percentile) over its composite map"));
    }

    stage("layout figures");
    // Hypertime: every fifth day is held out (test days share their layouts with training days).
    let held_out = |d: &study::SimulatedDay| d.index % 5 == 4;
    let score_grid = geometry.with_resolution(0.25)?;
    let hyper = study::hypertime(
        &results,
        &layouts.labels,
        &HypertimeParams::default(),
        &score_grid,
        600.0,
        40_000,
        held_out,
    )?;
    stage("hypertime fits");
    study::write_points(out.join("hypertime_train.txt"), &hyper.train)?;
    study::write_points(out.join("hypertime_test.txt"), &hyper.test)?;
    let busiest = layouts.most_frequent().ok_or("no layout")?;
    let walls = busiest.composite().static_map(0.5)?;
    let hourly = hyper.hourly(&geometry, 8..19);
    for (hour, time, density) in &hourly.hours {
        mcap.scalar("/hypertime", *time, density, hourly.top)?;
        if hour % 2 == 0 {
            let file = format!("hypertime_{hour:02}h.png");
            let title = format!("Hypertime at {hour:02}:00");
            save(
                MapFigure::new(title)
                    .walls(&walls)
                    .scalar(density, "people density (1/m²)", ColorMap::Turbo)
                    .range(0.0, hourly.top),
                &file,
            )?;
            let caption = format!(
                "Seed 001's hypertime density at {hour:02}:00, fitted on the training days"
            );
            figures = figures.figure(file, caption);
        }
    }
    stage("hypertime figures");
    // The TA map, and plans across the room on the most frequent layout.
    let ta = study::ta_map(&results, geometry, sim.params().laser.range_max)?;
    let plans = study::plans(
        busiest,
        &ta.activity,
        Point2::new(1.0, 4.8),
        Point2::new(14.2, 5.0),
    )?;
    // The same trip at 08:00 and 12:30, the busiest layout's affordance at each hour.
    let timed = study::plans_at_times(
        &results,
        &layouts.labels,
        held_out,
        busiest,
        &hyper,
        &[8.0, 12.5],
        Point2::new(1.0, 4.8),
        Point2::new(14.2, 5.0),
    )?;
    let (eight, lunch) = (&timed.plans[0], &timed.plans[1]);
    save(
        lunch
            .served
            .figure("The same trip planned at 08:00 and at 12:30, over the 12:30 activity")
            .path("planned at 08:00", &eight.plans.with_path)
            .path("planned at 12:30", &lunch.plans.with_path),
        "plans_at_times.png",
    )?;
    figures = figures.figure("plans_at_times.png", "A* with the busiest layout's affordance at 08:00 and at 12:30 as a costmap layer (the affordance modulated by the daily rhythm validated on held-out training days)");
    stage("TA map and plans");
    let tracks = results.iter().flat_map(|r| &r.output.trajectories);
    save(
        MapFigure::new("TA map and plans across the room")
            .walls(&plans.map)
            .scalar(&ta.activity, "distinct people per session", ColorMap::Turbo)
            .path("plain A*", &plans.plain.points)
            .path("activity-aware A*", &plans.aware.points),
        "ta_map.png",
    )?;
    save(
        MapFigure::new("TA confidence")
            .walls(&plans.map)
            .scalar(&ta.confidence, "confidence", ColorMap::Viridis)
            .range(0.0, 1.0),
        "ta_confidence.png",
    )?;
    save(
        MapFigure::new(format!(
            "Layout {}: plans with its affordance layer, and the day-0 tracks",
            busiest.id().0
        ))
        .walls(&plans.map)
        .tracks(
            results[0]
                .output
                .trajectories
                .iter()
                .map(|t| t.samples.iter().map(|s| s.1)),
        )
        .path("A* without the layer", &plans.layer.without_path)
        .path("A* with the layer", &plans.layer.with_path),
        "plans.png",
    )?;
    figures = figures
        .figure("ta_map.png", format!("Seed 002's TA map of the {} kept tracks, with plain and activity-aware A* (θ = {:.3})", ta.kept, plans.threshold))
        .figure("ta_confidence.png", "The TA map's confidence, from the robot's keyframes")
        .figure("plans.png", "Seed 000's use: A* on the busiest layout without and with its affordance map as a costmap layer");
    mcap.tracks("/tracks", &tracks.cloned().collect::<Vec<_>>())?;
    for (topic, plan) in [
        ("/plan/plain", &plans.plain.points),
        ("/plan/activity_aware", &plans.aware.points),
        ("/plan/without_layer", &plans.layer.without_path),
        ("/plan/with_layer", &plans.layer.with_path),
        ("/plan/at_08_00", &eight.plans.with_path),
        ("/plan/at_12_30", &lunch.plans.with_path),
    ] {
        mcap.path(topic, 0.0, plan)?;
    }
    mcap.scalar(
        "/ta/activity",
        0.0,
        &ta.activity,
        percentile(&ta.activity, 0.99).unwrap_or(1.0),
    )?;
    mcap.finish()?;

    stage("figures and MCAP");
    let metrics = |m: &PathMetrics| json!({"length": m.length, "activity_mean": m.activity_mean, "activity_var": m.activity_variance, "activity_max": m.activity_max});
    let ll = |s: &study::HypertimeScore| (s.hypertime_ll.mean(), s.static_ll.mean());
    let (by_h, by_s, by_n) = hyper
        .by_layout
        .iter()
        .fold((0.0, 0.0, 0), |(h, s, n), (_, l)| {
            (
                h + l.hypertime_ll.sum,
                s + l.static_ll.sum,
                n + l.hypertime_ll.used,
            )
        });
    let summary = json!({
        "days": days, "layouts_true": layouts.true_layouts(), "layouts_found": layouts.library.layouts().len(),
        "layout_pairwise_accuracy_paper": layouts.paper.rand_index, "layout_ari_paper": layouts.paper.adjusted_rand_index,
        "layout_pairwise_accuracy": layouts.ours.rand_index, "layout_ari": layouts.ours.adjusted_rand_index,
        "layout_pairwise_accuracy_complete_linkage": layouts.linkage.rand_index,
        "affordance_own_tables": format!("{}/{}", own.iter().filter(|o| o.own > o.other).count(), own.len()),
        "mota": mot.mota, "motp": mot.motp,
        "odometry_rms": mean(|r| r.score.pose_errors.odometry_rms), "corrected_rms": mean(|r| r.score.pose_errors.corrected_rms),
        "hypertime_loglik": ll(&hyper.all).0, "static_loglik": ll(&hyper.all).1, "train": hyper.train.len(), "test": hyper.test.len(),
        "by_layout_hypertime_loglik": by_h / f64::from(by_n.max(1) as u32), "by_layout_static_loglik": by_s / f64::from(by_n.max(1) as u32), "by_layout_test": by_n,
        "per_layout": hyper.by_layout.iter().map(|(id, l)| json!({"layout": id, "test": l.hypertime_ll.used, "hypertime_loglik": ll(l).0,
            "static_loglik": ll(l).1, "periods_s": l.hypertime.periods(), "period_validated": !l.hypertime.report().selection.no_period_validated()})).collect::<Vec<_>>(),
        "ta_trajectories": ta.kept, "activity_threshold": plans.threshold, "plain": metrics(&plans.plain.metrics), "activity_aware": metrics(&plans.aware.metrics),
        "affordance_layer_without": metrics(&plans.layer.without_layer), "affordance_layer_with": metrics(&plans.layer.with_layer),
        "rhythm_periods_s": timed.periods, "rate_rhythm": timed.rate_check.map(|c| json!({"days": c.days, "rmse": c.rhythm_rmse, "flat_rmse": c.flat_rmse, "mean_count": c.mean_count, "validated": c.accepted})),
        "plans_at_times": timed.plans.iter().map(|p| json!({"hour": (p.time - hyper.midnight()) / 3600.0, "without_layer": metrics(&p.plans.without_layer), "with_layer": metrics(&p.plans.with_layer),
            "activity_at_12_30_along_it": activity_along(&p.plans.with_path, &lunch.served.density).0})).collect::<Vec<_>>(),
        "out": out.display().to_string(), "seconds": start.elapsed().as_secs_f64(),
    });
    common::json_rows("", &summary)
        .into_iter()
        .fold(figures, |f, (k, v)| f.row(k, v))
        .write(&out)?;
    println!("{summary}");
    Ok(())
}
