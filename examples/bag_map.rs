//! Builds the occupancy map of a robot log — a ROS 1 bag or a ROS 2 MCAP file with laser scans
//! and odometry — and writes it as a ROS map (YAML + PGM) and a PNG picture, as `carmen_map`
//! does for CARMEN logs.
//!
//! `cargo run --release --example bag_map -- <file.bag|file.mcap> [--resolution 0.05]
//!  [--out DIR] [--scan-topic T] [--odom-topic T] [--base-frame F]`
//!
//! Topics are chosen automatically (the only `LaserScan` and `Odometry` topics, `/tf` and
//! `/tf_static`; the choices are printed) or named. Each scan is placed at the pose of its
//! laser in the odometry frame at its stamp (odometry · mount): the map is as good as the
//! odometry (scan matching comes with the daily loop). The last line printed is one JSON object.

use std::cell::Cell;
use std::path::PathBuf;
use std::time::Instant;

use haunts::bag::{Bag, RecordingOptions};
use haunts::occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts::occupancy::{MapSaveOptions, picture, save_map};

mod common;

const USAGE: &str = "usage: bag_map <file.bag|file.mcap> [--resolution R] [--out DIR] \
                     [--scan-topic T] [--odom-topic T] [--base-frame F]";

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut path, mut resolution, mut out) = (None, 0.05, PathBuf::from("out"));
    let mut options = RecordingOptions::new();
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(USAGE);
        match a.as_str() {
            "--resolution" => resolution = value()?.parse()?,
            "--out" => out = value()?.into(),
            "--scan-topic" => options = options.with_scan_topic(value()?),
            "--odom-topic" => options = options.with_odom_topic(value()?),
            "--base-frame" => options = options.with_base_frame(value()?),
            _ if path.is_none() && !a.starts_with("--") => path = Some(PathBuf::from(a)),
            _ => return Err(USAGE.into()),
        }
    }
    let path = path.ok_or(USAGE)?;
    let start = Instant::now();
    let recording = Bag::open(&path)?.recording(&options)?;
    for note in recording.notes() {
        eprintln!("note: {note}");
    }
    if recording.odometry().is_none() {
        return Err("the recording has no odometry: a map needs the laser's poses".into());
    }
    // Scans that do not read, or whose pose the odometry or transforms do not cover, are
    // skipped and counted.
    let (scans, unposed, unread) = (Cell::new(0usize), Cell::new(0usize), Cell::new(0usize));
    let bump = |c: &Cell<usize>| c.set(c.get() + 1);
    let posed = || {
        for c in [&scans, &unposed, &unread] {
            c.set(0);
        }
        let all = recording.scans().into_iter().flatten();
        all.filter_map(|s| match s {
            Ok(s) => match recording.sensor_pose_at(&s.frame, s.scan.stamp) {
                Ok(pose) => {
                    bump(&scans);
                    Some((s.scan, pose))
                }
                Err(_) => {
                    bump(&unposed);
                    None
                }
            },
            Err(_) => {
                bump(&unread);
                None
            }
        })
    };
    let (mapper, _) =
        OccupancyMapper::from_posed_scans(posed, resolution, 1.0, MapperParams::default())?;
    let map = mapper.occupancy_grid();
    std::fs::create_dir_all(&out)?;
    let stem = path
        .file_stem()
        .and_then(|n| n.to_str())
        .unwrap_or("map")
        .to_owned();
    let yaml = out.join(format!("{stem}.yaml"));
    save_map(&yaml, &map, &MapSaveOptions::default())?;
    picture::render_occupancy(&map).save_png(out.join(format!("{stem}.png")))?;
    let (free, occupied, unknown) = map.counts();
    let g = mapper.geometry();
    eprintln!("map written to {}", yaml.display());
    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{\"scans\":{},\"scans_without_pose\":{},\"scans_unread\":{},\
         \"width\":{},\"height\":{},\"free\":{free},\"occupied\":{occupied},\"unknown\":{unknown},\
         \"seconds\":{:.3}}}",
            scans.get(),
            unposed.get(),
            unread.get(),
            g.width(),
            g.height(),
            start.elapsed().as_secs_f64()
        ))
    );
    Ok(())
}
