//! `haunts`: robot recordings → day artifacts → a layout library → maps a planner reads.
//!
//! ```text
//! haunts sim --days 4 -o bags/                 # simulated days as ROS 2 MCAP bags
//! haunts day bags/day_000.mcap -o days/000.haunts
//! haunts merge days/*.haunts -o library.haunts
//! haunts maps library.haunts -o maps/
//! ```
//!
//! Each command prints one JSON object on its last line of standard output; notes go to
//! standard error. See the crate README for the fleet (array job) recipe.

mod commands;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Where and when people are around a robot, from its recordings.
#[derive(Debug, Parser)]
#[command(name = "haunts", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// One recording (a ROS 1 `.bag`, a ROS 2 `.mcap`, or a `leg_tracker` text folder) → a
    /// day artifact: its map, tracks and density.
    Day(commands::DayArgs),
    /// Day artifacts → the layout library (created, or extended when it exists), days in
    /// order of their first scan; a day already in the library is skipped, a day on other
    /// cells is refused; the library is saved once, atomically.
    Merge(commands::MergeArgs),
    /// A layout library → per layout, ROS map files of its composite and of its affordance
    /// costmap, a picture, and an MCAP of them for Foxglove or RViz.
    Maps(commands::MapsArgs),
    /// Simulated days of the built-in office → ROS 2 MCAP bags (ground truth on its own
    /// topics), to try the whole chain on files.
    Sim(commands::SimArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Day(a) => commands::day(&a),
        Command::Merge(a) => commands::merge(&a),
        Command::Maps(a) => commands::maps(&a),
        Command::Sim(a) => commands::sim(&a),
    };
    match result {
        Ok(report) => {
            println!("{report}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("haunts: {e}");
            ExitCode::FAILURE
        }
    }
}
