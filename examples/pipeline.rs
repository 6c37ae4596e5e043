//! The main job: `cargo run --release --example pipeline [-- --days 70 --out out/pipeline]`.
//!
//! Seed 000's layout-aware affordance loop, seed 001's hypertime model and seed 002's TA map
//! on days of the simulated office, each stage one call of [`haunts::pipeline::study`]:
//! the days (scan-matched, mapped, tracked, scored against the simulator's truth), the layout
//! library against the paper's clustering, each layout's affordance map at its own tables,
//! hypertime against its static baseline on held-out days, the TA map, plans across the
//! room (plain, activity-aware, and with the affordance map as a costmap layer), and the same
//! trip at 08:00 and at 12:30 with the affordance at each hour as the layer. With
//! `--random-start` each day starts at its own random pose and is registered onto the
//! layouts of the days before it first ([`study::align_days`]); the JSON adds
//! `alignment_error` and `refused_days`.
//!
//! Writes to the output folder ([`Study::write`]): figures (PNG), `index.html` showing them
//! with the figures as a table, `run.mcap` (maps, costmaps, tracks, paths, hypertime by
//! hour; for Foxglove), the layout library, and the hypertime points (`time x y`, for the
//! `hypertime` example). The last line printed is one JSON object with the figures
//! ([`haunts::pipeline::study::Summary`]).

use std::path::PathBuf;
use std::time::Instant;

use haunts::affordance::{HypertimeParams, LayoutParams, RegisterParams};
use haunts::pipeline::study::{self, SimulatedDay, Study};
use haunts::pipeline::{DayProcessor, PipelineParams};
use haunts::sim::{PatrolParams, SimParams, Simulator};
use haunts::similarity::ClusterParams;
use nalgebra::Point2;

mod common;

const USAGE: &str = "usage: pipeline [--days N] [--out DIR] [--seed S] [--random-start]";

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let start = Instant::now();
    let (mut days, mut out, mut seed) = (70usize, PathBuf::from("out/pipeline"), 1u64);
    let mut random_start = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--random-start" {
            random_start = true;
            continue;
        }
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
    let mut clock = Instant::now();
    let mut stage = |name: &str| {
        eprintln!("stage {name}: {:.2} s", clock.elapsed().as_secs_f64());
        clock = Instant::now();
    };

    // Days: five 3-minute patrols a day, every two hours from 8:30.
    let patrol = PatrolParams::sessions(8.5 * 3600.0, 180.0, 7200.0, 5);
    // With --random-start each day starts at its own random point of the patrol, its
    // odometry at zero there: days are processed on their own grids and registered onto the
    // layouts of the days before them, as `haunts day --like` does.
    let sim = Simulator::new(
        SimParams::default()
            .with_seed(seed)
            .with_patrol(patrol)
            .with_random_start(random_start),
    )?;
    let params = PipelineParams::default();
    let processor = DayProcessor::new(sim.geometry(), params)?;
    let geometry = *processor.geometry();
    let progress = |n| eprint!("\rdays {n}/{days}");
    let results = if random_start {
        study::simulate_days_on_own_grids(&sim, &params, 12.0, 0..days, progress)?
    } else {
        study::simulate_days(&sim, &processor, 0..days, progress)?
    };
    eprintln!();
    stage("days (simulated and processed)");

    // Layouts: composite maps keep what 35 % of a layout's days saw (chairs moved by 12 cm
    // fill a cell on fewer than half the days); densities need 30 visits a cell
    // (BENCHMARKS.md). Then each layout's affordance at its own tables and sofas.
    let layout_params = LayoutParams::default()
        .with_min_visits(30)
        .with_composite_min_fraction(0.35);
    let (results, alignment) = if random_start {
        let (kept, alignment) =
            study::align_days(results, geometry, layout_params, &RegisterParams::default())?;
        // Each kept day drawn again, directly onto the office's cells.
        let mut kept = kept;
        study::reprocess_aligned(&mut kept, &alignment, &processor, |i| {
            Ok(sim.day(i)?.to_recording()?)
        })?;
        stage("alignment");
        (kept, Some(alignment))
    } else {
        (results, None)
    };
    let layouts = study::layouts(&results, geometry, layout_params, &ClusterParams::default())?;
    let own_tables = study::own_tables(&layouts.library, &results);
    stage("layouts");

    // Hypertime: every fifth day is held out (test days share their layouts with training days).
    let held_out = |d: &SimulatedDay| d.index % 5 == 4;
    let hypertime = study::hypertime(
        &results,
        &layouts.labels,
        &HypertimeParams::default(),
        &geometry.with_resolution(0.25)?,
        600.0,
        40_000,
        held_out,
    )?;
    stage("hypertime fits");

    // The TA map, and plans across the room on the most frequent layout; then the same trip
    // at 08:00 and 12:30, the layout's affordance at each hour.
    let ta = study::ta_map(&results, geometry, sim.params().laser.range_max)?;
    let busiest = layouts.most_frequent().ok_or("no layout")?;
    let (from, to) = (Point2::new(1.0, 4.8), Point2::new(14.2, 5.0));
    let plans = study::plans(busiest, &ta.activity, from, to)?;
    let timed = study::plans_at_times(
        &results,
        &layouts.labels,
        held_out,
        busiest,
        &hypertime,
        &[8.0, 12.5],
        from,
        to,
    )?;
    stage("TA map and plans");

    let study = Study {
        days: results,
        layouts,
        own_tables,
        hypertime,
        ta,
        plans,
        timed,
        alignment,
    };
    let title = format!("haunts: {days} simulated days (seed {seed})");
    let summary = study.write(&out, title, start)?;
    stage("figures and MCAP");
    // A JSON value's keys are sorted.
    println!("{}", haunts::json::finite(serde_json::to_value(&summary)?));
    Ok(())
}
