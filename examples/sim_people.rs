//! The simulated office's people as a trajectory file, and its walls as a ROS map: what the
//! `flow_map` example reads (issue 53's simulator figures).
//!
//! `cargo run --release --example sim_people -- --days N [--seed S] --out DIR`
//!
//! Writes `DIR/people.txt`, whitespace columns `time id x y` (`flow_map --format txy`): every
//! visit of every day (the simulator's ground truth, the people the robot never saw
//! included), sampled every 0.4 s (ETH's 2.5 Hz) while the person walks inside the office's
//! area, one trajectory (id) per walk between two stops, ids unique across days; and `DIR/office.yaml` + `.pgm`, day 0's true occupancy (walls
//! and furniture) for `flow_map --map`. The last line printed is one JSON object:
//! `{"days":..,"visits":..,"samples":..,"people":"..","map":".."}`.

use std::io::Write;
use std::path::PathBuf;

use haunts::occupancy::{MapSaveOptions, save_map};
use haunts::sim::{SimParams, Simulator};

mod common;

const USAGE: &str = "usage: sim_people --days N [--seed S] --out DIR";

/// Seconds between samples: ETH's 2.5 Hz.
const STEP: f64 = 0.4;

type Error = Box<dyn std::error::Error>;

fn run() -> Result<(), Error> {
    let mut args = std::env::args().skip(1);
    let (mut days, mut seed, mut out): (usize, u64, Option<PathBuf>) = (10, 1, None);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(USAGE);
        match a.as_str() {
            "--days" => days = value()?.parse()?,
            "--seed" => seed = value()?.parse()?,
            "--out" => out = Some(PathBuf::from(value()?)),
            _ => return Err(USAGE.into()),
        }
    }
    let out = out.ok_or(USAGE)?;
    if !(1..=366).contains(&days) {
        return Err(format!("--days {days} must be from 1 to 366").into());
    }
    std::fs::create_dir_all(&out)?;
    let sim = Simulator::new(SimParams::default().with_seed(seed))?;
    let area = sim.geometry();
    let people = out.join("people.txt");
    let mut file = std::io::BufWriter::new(std::fs::File::create(&people)?);
    let (mut visits, mut samples) = (0usize, 0usize);
    for index in 0..days {
        let day = sim.day(index)?;
        if index == 0 {
            save_map(
                out.join("office.yaml"),
                &day.truth,
                &MapSaveOptions::default(),
            )?;
        }
        for visit in &day.visits {
            visits += 1;
            // One trajectory per walk between stops (a person seated for an hour is no
            // walker, and seed 002's dummy filter would drop the whole visit for its low
            // mean speed): a new id after every sample standing still.
            let mut walk = 0u64;
            let mut walking = false;
            let mut t = visit.arrival();
            while t <= visit.departure() {
                match visit.at(t) {
                    Some(p) if p.velocity.norm() > 0.0 => {
                        if area.world_to_cell(p.position).is_some() {
                            let id = (index as u64 * 1_000_000 + visit.id) * 100 + walk;
                            writeln!(file, "{t:.3} {id} {:.4} {:.4}", p.position.x, p.position.y)?;
                            samples += 1;
                            walking = true;
                        }
                    }
                    _ => {
                        if walking {
                            walk += 1;
                            walking = false;
                        }
                    }
                }
                t += STEP;
            }
        }
    }
    file.flush()?;
    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{\"days\":{days},\"visits\":{visits},\"samples\":{samples},\"people\":\"{}\",\"map\":\"{}\"}}",
            people.display(),
            out.join("office.yaml").display()
        ))
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    common::report(run())
}
