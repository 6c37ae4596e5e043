//! Builds an occupancy map from a CARMEN log with corrected poses and writes it as a ROS map
//! (YAML + PGM) and a PNG picture.
//!
//! `cargo run --release --example carmen_map -- <log[.gz]> [--resolution 0.05] [--out DIR]`
//! (`--resolution` in metres, above 0 and at most 100)
//!
//! Malformed lines are skipped and counted (`skipped_lines`). A laser message whose pose lies
//! far from the bulk of the log's laser poses is skipped and counted by the bounds rule every
//! reader of coordinates uses (`haunts::occupancy::bounds`: outside the box of the
//! 0.1 %–99.9 % quantiles of x and y grown on every side by 10 m plus the box's larger side),
//! the first few named on standard error; the JSON's `"skipped_rows": {"far": n,
//! "non_finite": n}` counts them with the lines whose pose or stamp is NaN or infinite. The
//! map is built from the rest; the job fails only when no laser pose is usable.

use std::path::PathBuf;
use std::time::Instant;

use haunts::occupancy::bounds::BoundsRule;
use haunts::occupancy::carmen::{CarmenOptions, read_carmen};
use haunts::occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts::occupancy::{MapSaveOptions, picture, save_map};

mod common;

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut log_path = None;
    let (mut resolution, mut out) = (0.05, PathBuf::from("out"));
    while let Some(a) = args.next() {
        match a.as_str() {
            "--resolution" => {
                resolution = args.next().ok_or("--resolution needs a value")?.parse()?
            }
            "--out" => out = args.next().ok_or("--out needs a value")?.into(),
            _ => log_path = Some(PathBuf::from(a)),
        }
    }
    let log_path = log_path.ok_or("usage: carmen_map <log[.gz]> [--resolution R] [--out DIR]")?;
    // A cell wider than a building maps nothing (1e300 once gave a 2 × 2 map and exit 0).
    if !(resolution > 0.0 && resolution <= 100.0) {
        return Err(
            format!("--resolution {resolution:e} m must be above 0 and at most 100 m").into(),
        );
    }
    let start = Instant::now();
    let mut log = read_carmen(&log_path, &CarmenOptions::default())?;
    for s in &log.first_skipped {
        eprintln!("skipped line {} ({}): {:?}", s.line, s.message, s.reason);
    }
    // One far laser pose (a glitch at 10⁵ m) is skipped, not a map over the cell budget.
    let lines: Vec<usize> = log.scans.iter().map(|s| s.line).collect();
    let kept = BoundsRule::default().split("laser poses", std::mem::take(&mut log.scans), |s| {
        s.laser_pose.translation.vector.into()
    })?;
    for line in kept
        .skipped
        .describe(|i| format!("line {} (laser pose)", lines[i]))
    {
        eprintln!("{line}");
    }
    let mut rows = kept.skipped.counts;
    rows.non_finite += log.non_finite;
    log.scans = kept.rows;
    let posed = || log.scans.iter().map(|s| (s.scan.clone(), s.laser_pose));
    let (mapper, _) =
        OccupancyMapper::from_posed_scans(posed, resolution, 1.0, MapperParams::default())?;
    let geometry = *mapper.geometry();
    let map = mapper.occupancy_grid();
    std::fs::create_dir_all(&out)?;
    let stem = log_path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("map")
        .split('.')
        .next()
        .unwrap_or("map")
        .to_owned();
    save_map(
        out.join(format!("{stem}.yaml")),
        &map,
        &MapSaveOptions::default(),
    )?;
    picture::render_occupancy(&map).save_png(out.join(format!("{stem}.png")))?;
    let (free, occupied, unknown) = map.counts();
    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{\"scans\":{},\"skipped_lines\":{},\"skipped_rows\":{},\"width\":{},\"height\":{},\"free\":{free},\"occupied\":{occupied},\"unknown\":{unknown},\"seconds\":{:.3}}}",
            log.scans.len(),
            log.skipped,
            rows.json(),
            geometry.width(),
            geometry.height(),
            start.elapsed().as_secs_f64()
        ))
    );
    Ok(())
}
