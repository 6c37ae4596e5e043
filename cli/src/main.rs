//! `haunts`: robot recordings → day artifacts → a layout library → maps a planner reads.
//!
//! ```text
//! haunts sim --days 4 -o bags/                 # simulated days as ROS 2 MCAP bags
//! haunts day bags/day_000.mcap -o days/000.haunts
//! haunts merge days/*.haunts -o library.haunts
//! haunts maps library.haunts -o maps/
//! haunts replay bags/day_000.mcap -o live.mcap --library library.haunts
//! haunts node --library library.haunts --use-sim-time &   # ROS 2 over DDS
//! haunts replay bags/day_000.mcap --dds
//! ```
//!
//! Each command prints one JSON object on its last line of standard output; notes go to
//! standard error. A failure exits with status 1; `haunts day --like` whose day did not
//! register onto the library exits with status 3, its day written in its own frame. See the
//! crate README for the fleet (array job) recipe.

mod commands;
mod ros2;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Where and when people are around a robot, from its recordings.
#[derive(Debug, Parser)]
#[command(name = "haunts", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Parsed once per run: the size of its largest variant costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand)]
enum Command {
    /// One recording (a ROS 1 `.bag`, a ROS 2 `.mcap`, or a `leg_tracker` text folder) → a
    /// day artifact: its map, tracks and density (with `--like`, registered into a library's
    /// frame; a day that does not register exits with status 3).
    Day(commands::DayArgs),
    /// Day artifacts → the layout library (created, or extended when it exists), days in
    /// order of their first scan; a day already in the library is skipped, a day on other
    /// cells is registered onto it, or refused when it does not register; the library is
    /// saved once, atomically.
    Merge(commands::MergeArgs),
    /// A layout library → per layout, ROS map files of its composite and of its affordance
    /// costmap, a picture, and an MCAP of them for Foxglove or RViz.
    Maps(commands::MapsArgs),
    /// Simulated days of the built-in office → ROS 2 MCAP bags (ground truth on its own
    /// topics), to try the whole chain on files.
    Sim(commands::SimArgs),
    /// A recording through a live session, message by message in log-time order → an MCAP
    /// of what a robot node would publish (the people after each scan; with `--library`,
    /// the costmaps), its latency, memory and, with ground truth, its CLEAR MOT.
    Replay(commands::ReplayArgs),
    /// The live session as a ROS 2 node over DDS (no ROS install): scans, odometry and tf
    /// in; the people after each scan out, and a layout of the library served to Nav2 (a
    /// static map, the costmap, a speed-filter mask); at SIGINT or SIGTERM the day is merged
    /// into the library.
    Node(ros2::NodeArgs),
}

/// The exit status of `haunts day --like` when the day did not register onto the library:
/// its artifact is written in its own frame and its JSON says why, but a script must not
/// merge it as if it had been aligned (`haunts merge` would refuse it anyway).
const NOT_ALIGNED: u8 = 3;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Day(a) => commands::day(&a),
        Command::Merge(a) => commands::merge(&a),
        Command::Maps(a) => commands::maps(&a),
        Command::Sim(a) => commands::sim(&a),
        Command::Replay(a) => commands::replay(&a),
        Command::Node(a) => ros2::node(&a),
    };
    match result {
        Ok(report) => {
            // No non-finite number and no silent null: left out, named in `left_out`.
            println!("{}", haunts::json::finite(report.clone()));
            if report.get("refused").is_some_and(|r| r.is_string()) {
                ExitCode::from(NOT_ALIGNED)
            } else {
                ExitCode::SUCCESS
            }
        }
        Err(e) => {
            eprintln!("haunts: {e}");
            ExitCode::FAILURE
        }
    }
}
