//! Detects and tracks people in a recorded `leg_tracker` sequence and scores the tracks with
//! CLEAR MOT against its ground truth.
//!
//! `cargo run --release --example eval_tracking -- <dir|file.bag|file.mcap> [--tracker pf|kf]
//!  [--detector geometric|forest] [--window MIN,MAX|none] [--static-map on|off]
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
//! `base_link`, or the odometry's child frame in a bag). The scores follow
//! `leg_tracker_benchmarks`: people and tracks are scored
//! only within the bearing window of the laser (default −80°,12°, the window of its
//! `general_tracking_moving` launch files; `--window none` scores every bearing), with
//! `clear_mot.py`'s conventions at 0.75 m, under both protocols: at every scan, as
//! `clear_mot.py` does (a track reported at a scan nobody annotated is a false positive:
//! `mota_every_scan`, the headline figure), and at the annotated scans only
//! (`mota_annotated`).
//! `--detector forest` runs the learned leg detector (the forest shipped in
//! haunts-tracking, trained on leg_tracker's training set, never on the bag scored here),
//! with the trackers' births and confirmation at the forest's cross-validated operating
//! point (a track is confirmed once the running average of its detections' leg
//! probabilities reaches it); `--detector geometric` (the default: it scores better on the
//! evaluation bag, see BENCHMARKS.md) the seed-000 geometric detector with the trackers'
//! default rules.
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
//! The last line printed is one JSON object: both protocols' MOTA, MOTP, misses, false
//! positives, identity switches and objects; `seconds` is the wall time of detection,
//! tracking and scoring of one run (reading the files excluded), `real_time_factor` the
//! bag's duration over it; `skipped_lines` (malformed lines of the files), `skipped_scans`
//! (scans the tracker could not place) and `unassigned_truth` (annotations on no scan read)
//! are always there, and `mount_assumed` whether a laser was placed at the robot's origin
//! for want of `static_tf.txt` (odometry given, no static transforms). A run with no annotated person to score (an empty or garbage
//! `scans.txt`, empty ground truth) is an error with a failing exit code, never a perfect
//! score; so is ground truth none of whose times lies within the scans' span (± 1 s), as
//! times in milliseconds or frame numbers would.

use std::time::Instant;

use haunts::tracking::detect::static_map::StaticMapParams;
use haunts::tracking::detect::{Detector, ForestDetector, LegDetector, LegDetectorParams};
use haunts::tracking::eval::mot::ClearMot;
use haunts::tracking::eval::sequence::{
    EvalFrames, EvalParams, Scoring, TrackingFrame, evaluate_sequence,
};
use haunts::tracking::track::Tracker;
use haunts::tracking::track::kalman::{KalmanParams, KalmanTracker};
use haunts::tracking::track::particle::{ParticleParams, ParticleTracker};

mod common;

const USAGE: &str = "usage: eval_tracking <dir|file.bag|file.mcap> [--tracker pf|kf] \
                     [--detector geometric|forest] [--window MIN,MAX|none] [--static-map on|off] \
                     [--score online|trajectories] [--tentative FILE] [--base-frame NAME] \
                     [--scan-topic T] [--odom-topic T] [--ground-truth-topic T]";

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut dir, mut kind) = (None, String::from("pf"));
    let mut detector_kind = String::from("geometric");
    let mut tentative_csv: Option<String> = None;
    let mut topics = common::recorded::Topics::default();
    let mut params =
        EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()));
    while let Some(a) = args.next() {
        match a.as_str() {
            "--tracker" => kind = args.next().ok_or(USAGE)?,
            "--detector" => detector_kind = args.next().ok_or(USAGE)?,
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
    // Annotation times in other units (milliseconds, frame numbers) lie outside the scans'
    // span and would all fall to one scan: refused rather than scored.
    let (first, last) = sequence
        .scans
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |r, s| {
            (r.0.min(s.bag_time), r.1.max(s.bag_time))
        });
    let within = |t: f64| (first - 1.0..=last + 1.0).contains(&t);
    if first <= last
        && !sequence.ground_truth.is_empty()
        && !sequence.ground_truth.iter().any(|p| within(p.bag_time))
    {
        return Err(format!(
            "no ground-truth time lies within the scans' span {first:.3}..{last:.3} s (± 1 s): \
             times must be bag times in seconds, not milliseconds or frame numbers"
        )
        .into());
    }
    // The learned detector's operating point drives births and confirmation; the geometric
    // detector keeps the trackers' default rules (leg pairs or a walk).
    let (detector, operating_point): (Box<dyn Detector>, Option<f64>) = match detector_kind.as_str()
    {
        "forest" => {
            let d = ForestDetector::shipped()?;
            let p = d.min_probability();
            (Box::new(d), Some(p))
        }
        "geometric" => (
            Box::new(LegDetector::new(LegDetectorParams::default())?),
            None,
        ),
        _ => return Err(USAGE.into()),
    };
    let tracker = || -> Result<Box<dyn Tracker>, Box<dyn std::error::Error>> {
        Ok(match (kind.as_str(), operating_point) {
            ("pf", None) => Box::new(ParticleTracker::new(ParticleParams::default())?),
            ("pf", Some(p)) => Box::new(ParticleTracker::new(
                ParticleParams::default()
                    .with_birth_threshold(p)
                    .with_confirm_mean_confidence(Some(p)),
            )?),
            ("kf", None) => Box::new(KalmanTracker::new(KalmanParams::default())?),
            ("kf", Some(p)) => Box::new(KalmanTracker::new(
                KalmanParams::default()
                    .with_min_birth_confidence(p)
                    .with_confirm_mean_confidence(Some(p)),
            )?),
            _ => return Err(USAGE.into()),
        })
    };

    let start = Instant::now();
    let every = params.clone().with_frames(EvalFrames::EveryScan);
    let report_every =
        evaluate_sequence(&sequence, detector.as_ref(), tracker()?.as_mut(), &every)?;
    let seconds = start.elapsed().as_secs_f64();
    let annotated = params.clone().with_frames(EvalFrames::Annotated);
    let report = evaluate_sequence(
        &sequence,
        detector.as_ref(),
        tracker()?.as_mut(),
        &annotated,
    )?;

    if !report.mounts_assumed.is_empty() {
        eprintln!(
            "warning: no static transforms: laser frame(s) {} assumed at the robot's origin",
            report.mounts_assumed.join(", ")
        );
    }
    let (s, e) = (&report.scores, &report_every.scores);
    let span = match (sequence.scans.first(), sequence.scans.last()) {
        (Some(a), Some(b)) => b.bag_time - a.bag_time,
        _ => 0.0,
    };
    eprintln!(
        "{} scans over {span:.1} s ({} skipped), {} detections, {} frames annotated, tracking \
         in the {} frame, {} resets; every scan: MOTA {:.3}, MOTP {:.3} m; annotated scans: \
         {} matches, MOTA {:.3}, MOTP {:.3} m, {} people followed only by a tentative track; \
         {:.0}× real time",
        report.scans,
        report.skipped_scans,
        report.detections,
        report.frames,
        match report.tracking_frame {
            TrackingFrame::Odometry => "odometry",
            TrackingFrame::Sensor => "laser",
        },
        report.resets,
        e.mota,
        e.motp,
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
    let scores = |c: &ClearMot| {
        format!(
            "{{\"mota\":{:.4},\"motp\":{:.4},\"misses\":{},\"false_positives\":{},\
             \"id_switches\":{},\"objects\":{}}}",
            c.mota, c.motp, c.misses, c.false_positives, c.id_switches, c.ground_truth
        )
    };
    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{\"tracker\":\"{kind}\",\"detector\":\"{detector_kind}\",\"scoring\":\"{}\",\
         \"mota_every_scan\":{},\"mota_annotated\":{},\"scans\":{},\"skipped_lines\":{},\
         \"skipped_scans\":{},\"unassigned_truth\":{},\"mount_assumed\":{},\"seconds\":{:.4},\
         \"real_time_factor\":{:.1},\"followed_tentatively\":{}}}",
            match params.scoring {
                Scoring::Online => "online",
                Scoring::Trajectories => "trajectories",
            },
            scores(e),
            scores(s),
            report.scans,
            sequence.skipped_lines,
            report.skipped_scans,
            report.unassigned_truth,
            !report.mounts_assumed.is_empty(),
            seconds,
            span / seconds.max(1e-9),
            report.followed_tentatively
        ))
    );
    Ok(())
}
