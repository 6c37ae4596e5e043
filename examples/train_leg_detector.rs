//! Trains the learned leg detector's random forest from labelled laser scans and writes the
//! model: how `haunts-tracking`'s shipped model is made, and how to make one for another
//! laser.
//!
//! `cargo run --release --features train --example train_leg_detector -- [DIR|FILE…]
//!  [--out FILE] [--labels-topic T] [--trees N] [--depth D|none] [--seed S] [--min-leaf N]`
//!
//! The labelled scans are robot logs or text:
//! - ROS 1 bags / MCAP files (`FILE…`, or every `.bag` and `.mcap` of `DIR`, in file-name
//!   order; default `DIR`: `../shared/data/leg_tracker/training/bags`), read through
//!   `haunts-bag` (`haunts::training`): every `sensor_msgs/LaserScan` topic is a recording;
//!   the `geometry_msgs/PoseArray` topic (`--labels-topic`, or the log's only one) holds the
//!   leg centroids of the scan that follows each message, as `leg_tracker`'s
//!   `extract_positive_training_clusters` records them; a log without one is of rooms
//!   without people (every cluster a non-leg).
//! - A folder of text copies: one recording per `NAME.scans.txt.gz` (the `scans.txt` format
//!   of the leg_tracker benchmarks), with `NAME.legs.txt` labels (`scan_line x y n idx…`;
//!   `n` may be 0: the label's position is what counts) or, without one, a recording of
//!   rooms without people.
//!
//! The model is written to `FILE` (default `leg_forest.bin`); with the defaults on the shared
//! training bags it is byte for byte `tracking/models/leg_forest.bin`
//! (`tests/train_from_bags.rs` checks it; the text copies give the same rows up to their
//! rounding, so a slightly different model). The last line printed is one JSON object:
//! rows, legs, the cross-validated ROC AUC (5 folds inside the training set), the operating
//! point with its precision and recall, the model's size.

use std::path::{Path, PathBuf};

use haunts::tracking::detect::forest::train::{
    ForestParams, Trained, train_from_dir, train_from_recordings,
};
use haunts::tracking::detect::training::SampleParams;

mod common;

const USAGE: &str = "usage: train_leg_detector [DIR|FILE…] [--out FILE] [--labels-topic T] \
                     [--trees N] [--depth D|none] [--seed S] [--min-leaf N]";

/// Whether `path` is a robot log the bag reader takes.
fn is_log(path: &Path) -> bool {
    matches!(
        path.extension().and_then(|e| e.to_str()),
        Some("bag" | "mcap")
    )
}

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut inputs: Vec<PathBuf> = Vec::new();
    let mut out = String::from("leg_forest.bin");
    let mut labels_topic: Option<String> = None;
    let mut params = ForestParams::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = args.next().ok_or(USAGE)?,
            "--labels-topic" => labels_topic = Some(args.next().ok_or(USAGE)?),
            "--trees" => params.trees = args.next().ok_or(USAGE)?.parse()?,
            "--depth" => {
                let d = args.next().ok_or(USAGE)?;
                params.max_depth = if d == "none" { None } else { Some(d.parse()?) };
            }
            "--seed" => params.seed = args.next().ok_or(USAGE)?.parse()?,
            "--min-leaf" => params.min_samples_leaf = args.next().ok_or(USAGE)?.parse()?,
            _ if !a.starts_with("--") => inputs.push(a.into()),
            _ => return Err(USAGE.into()),
        }
    }
    if inputs.is_empty() {
        inputs.push("../shared/data/leg_tracker/training/bags".into());
    }
    let logs: Vec<PathBuf> = match inputs.as_slice() {
        [dir] if dir.is_dir() => {
            let mut logs: Vec<PathBuf> = std::fs::read_dir(dir)
                .map_err(|e| format!("{}: {e}", dir.display()))?
                .filter_map(|e| Some(e.ok()?.path()))
                .filter(|p| is_log(p))
                .collect();
            logs.sort();
            logs
        }
        files => files.to_vec(),
    };
    let trained: Trained = match inputs.as_slice() {
        [dir] if dir.is_dir() && logs.is_empty() => {
            train_from_dir(dir, &SampleParams::default(), &params)?
        }
        _ => {
            if let Some(p) = logs.iter().find(|p| !is_log(p)) {
                return Err(format!("{}: not a .bag or .mcap file\n{USAGE}", p.display()).into());
            }
            let (mut recordings, mut skipped) = (Vec::new(), 0);
            for log in &logs {
                let l = haunts::training::labelled_scans(log, labels_topic.as_deref())?;
                let scans: usize = l.recordings.iter().map(|r| r.1.len()).sum();
                eprintln!(
                    "{}: {} recording(s), {scans} scans, labels {}, {} skipped, {} scans \
                     without labels",
                    log.display(),
                    l.recordings.len(),
                    l.labels_topic
                        .as_deref()
                        .unwrap_or("none (rooms without people)"),
                    l.skipped,
                    l.unlabelled_scans,
                );
                skipped += l.skipped;
                recordings.extend(l.recordings);
            }
            train_from_recordings(recordings, skipped, &SampleParams::default(), &params)?
        }
    };
    let bytes = trained.forest.to_bytes();
    std::fs::write(&out, &bytes)?;
    let cv = &trained.cross_validation;
    let legs = trained.samples.legs.iter().filter(|&&l| l).count();
    eprintln!(
        "{} recordings ({} malformed lines or messages skipped), {} rows ({legs} legs, {} labels matched no \
         cluster); cross-validated AUC {:.4}, operating point {:.3} (precision {:.3}, recall \
         {:.3}); {} trees, {} nodes, {} bytes written to {out}",
        trained.recordings.len(),
        trained.skipped_lines,
        trained.samples.len(),
        trained.samples.unmatched_labels,
        cv.auc,
        cv.threshold,
        cv.precision,
        cv.recall,
        trained.forest.trees(),
        trained.forest.nodes(),
        bytes.len(),
    );
    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{\"rows\":{},\"legs\":{legs},\"cv_auc\":{:.4},\"threshold\":{},\"cv_precision\":{:.4},\
         \"cv_recall\":{:.4},\"trees\":{},\"nodes\":{},\"bytes\":{}}}",
            trained.samples.len(),
            cv.auc,
            cv.threshold,
            cv.precision,
            cv.recall,
            trained.forest.trees(),
            trained.forest.nodes(),
            bytes.len()
        ))
    );
    Ok(())
}
