//! Detects and tracks people in a recorded `leg_tracker` sequence and scores the tracks with
//! CLEAR MOT against its ground truth.
//!
//! `cargo run --release --example eval_tracking -- <dir|file.bag|file.mcap> [--tracker pf|kf]
//!  [--frames annotated|every] [--window MIN,MAX|none] [--static-map on|off]
//!  [--score online|trajectories] [--tentative FILE] [--base-frame NAME]
//!  [--scan-topic T] [--odom-topic T] [--ground-truth-topic T]`
//!
//! The recording is a folder of text files — `scans.txt` and `ground_truth_people.txt`, and
//! optionally `odom.txt` and `static_tf.txt` — or a ROS 1 bag or ROS 2 MCAP file, whose topics
//! are chosen automatically (the only `LaserScan` topic, the only `Odometry` topic, `/tf` and
//! `/tf_static`, the only `leg_tracker/msg/Person` topic; the choices are printed) or named
//! by the topic flags. The text folder, `general_tracking_moving_1.bag` and its MCAP twin give
//! the same scores. Without odometry the tracker works in the laser frame; `--base-frame`
//! names the robot frame the odometry moves and the static transforms lead to (default
//! `base_link`, or the odometry's child frame in a bag). The scores follow `leg_tracker_benchmarks`: people and tracks are scored
//! only within the bearing window of the laser (default −80°,12°, the window of its
//! `general_tracking_moving` launch files; `--window none` scores every bearing), with
//! `clear_mot.py`'s conventions at 0.75 m, at the annotated scans (`--frames every` scores
//! every scan, as `clear_mot.py` does).
//! Legs on static objects (cells of an online occupancy grid in the odometry frame that
//! have been occupied for 1.5 s while no tracked person stood there) are removed before
//! pairing, as `leg_tracker`'s local map does; `--static-map off` keeps them.
//! `--score trajectories` scores the trajectories the tracker leaves at the end (a track
//! from its birth, before it was confirmed too: what a day's maps are built from) instead of
//! the tracks it reports scan by scan.
//! `--tentative FILE` writes the tentative (not yet confirmed) tracks at the scored scans as
//! CSV, one row per track and scan, with whether an annotated person stood within the match
//! threshold; `benches/peers/confirmation_oracle.py` reads it.
//! `followed_tentatively` counts the annotated people no scored track matched while a
//! tentative track was within the match threshold (see `EvalReport::followed_tentatively`).
//! The last line printed is one JSON object; `seconds` is the wall time of detection,
//! tracking and scoring (reading the files excluded).

use std::time::Instant;

use haunts::tracking::detector::{LegDetector, LegDetectorParams};
use haunts::tracking::kalman::{KalmanParams, KalmanTracker};
use haunts::tracking::particle::{ParticleParams, ParticleTracker};
use haunts::tracking::tracker::Tracker;
use haunts::tracking::tracker::eval::{
    EvalFrames, EvalParams, Scoring, TrackingFrame, evaluate_sequence,
};
use haunts::tracking::tracker::static_map::StaticMapParams;

mod common;

const USAGE: &str = "usage: eval_tracking <dir|file.bag|file.mcap> [--tracker pf|kf] \
                     [--frames annotated|every] [--window MIN,MAX|none] [--static-map on|off] \
                     [--score online|trajectories] [--tentative FILE] [--base-frame NAME] \
                     [--scan-topic T] [--odom-topic T] [--ground-truth-topic T]";

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut dir, mut kind) = (None, String::from("pf"));
    let mut tentative_csv: Option<String> = None;
    let mut topics = common::recorded::Topics::default();
    let mut params =
        EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()));
    while let Some(a) = args.next() {
        match a.as_str() {
            "--tracker" => kind = args.next().ok_or(USAGE)?,
            "--frames" => {
                params.frames = match args.next().as_deref() {
                    Some("annotated") => EvalFrames::Annotated,
                    Some("every") => EvalFrames::EveryScan,
                    _ => return Err(USAGE.into()),
                }
            }
            "--window" => {
                let w = args.next().ok_or(USAGE)?;
                params.bearing_window = if w == "none" {
                    None
                } else {
                    let (lo, hi) = w.split_once(',').ok_or(USAGE)?;
                    let (lo, hi): (f64, f64) = (lo.trim().parse()?, hi.trim().parse()?);
                    Some((lo.to_radians(), hi.to_radians()))
                };
            }
            "--static-map" => {
                params.static_map = match args.next().as_deref() {
                    Some("on") => Some(StaticMapParams::default()),
                    Some("off") => None,
                    _ => return Err(USAGE.into()),
                }
            }
            "--score" => {
                params.scoring = match args.next().as_deref() {
                    Some("online") => Scoring::Online,
                    Some("trajectories") => Scoring::Trajectories,
                    _ => return Err(USAGE.into()),
                }
            }
            "--base-frame" => {
                params.base_frame = args.next().ok_or(USAGE)?;
                topics.base_frame = Some(params.base_frame.clone());
            }
            "--scan-topic" | "--odom-topic" | "--ground-truth-topic" => {
                if topics.take(&a, &mut args) != Some(true) {
                    return Err(USAGE.into());
                }
            }
            "--tentative" => {
                tentative_csv = Some(args.next().ok_or(USAGE)?);
                params.record_tentative = true;
            }
            _ if dir.is_none() && !a.starts_with("--") => dir = Some(a),
            _ => return Err(USAGE.into()),
        }
    }
    let dir = dir.ok_or(USAGE)?;
    let sequence = common::recorded::read_sequence(&dir, &topics)?;
    if sequence.skipped_lines > 0 {
        eprintln!("skipped {} malformed lines", sequence.skipped_lines);
    }
    let detector = LegDetector::new(LegDetectorParams::default())?;
    let mut tracker: Box<dyn Tracker> = match kind.as_str() {
        "pf" => Box::new(ParticleTracker::new(ParticleParams::default())?),
        "kf" => Box::new(KalmanTracker::new(KalmanParams::default())?),
        _ => return Err(USAGE.into()),
    };

    let start = Instant::now();
    let report = evaluate_sequence(&sequence, &detector, tracker.as_mut(), &params)?;
    let seconds = start.elapsed().as_secs_f64();

    let s = &report.scores;
    let span = match (sequence.scans.first(), sequence.scans.last()) {
        (Some(a), Some(b)) => b.bag_time - a.bag_time,
        _ => 0.0,
    };
    eprintln!(
        "{} scans over {span:.1} s ({} skipped), {} detections, {} frames scored, tracking in \
         the {} frame, {} resets; {} matches, MOTA {:.3}, MOTP {:.3} m, {} people followed \
         only by a tentative track; {:.0}× real time",
        report.scans,
        report.skipped_scans,
        report.detections,
        report.frames,
        match report.tracking_frame {
            TrackingFrame::Odometry => "odometry",
            TrackingFrame::Sensor => "laser",
        },
        report.resets,
        s.matches,
        s.mota,
        s.motp,
        report.followed_tentatively,
        span / seconds.max(1e-9),
    );
    if let Some(path) = tentative_csv {
        let mut csv = String::from("scan,time,id,x,y,person,hits,age,travel,speed,position_std\n");
        for u in &report.tentative {
            csv.push_str(&format!(
                "{},{:.6},{},{:.4},{:.4},{},{},{:.4},{:.4},{:.4},{:.4}\n",
                u.scan,
                u.time,
                u.id,
                u.position.x,
                u.position.y,
                u8::from(u.person),
                u.hits,
                u.age,
                u.travel,
                u.speed,
                u.position_std
            ));
        }
        std::fs::write(&path, csv)?;
        eprintln!(
            "{} tentative samples written to {path}",
            report.tentative.len()
        );
    }
    println!(
        "{{\"tracker\":\"{kind}\",\"scoring\":\"{}\",\"mota\":{:.4},\"motp\":{:.4},\"id_switches\":{},\
         \"false_positives\":{},\"misses\":{},\"ground_truth\":{},\"scans\":{},\"seconds\":{:.4},\
         \"followed_tentatively\":{}}}",
        match params.scoring {
            Scoring::Online => "online",
            Scoring::Trajectories => "trajectories",
        },
        s.mota,
        s.motp,
        s.id_switches,
        s.false_positives,
        s.misses,
        s.ground_truth,
        report.scans,
        seconds,
        report.followed_tentatively
    );
    Ok(())
}
