//! Trains the learned leg detector's random forest from labelled laser scans and writes the
//! model: how `haunts-tracking`'s shipped model is made, and how to make one for another
//! laser.
//!
//! `cargo run --release --example train_leg_detector -- [DIR] [--out FILE] [--trees N]
//!  [--depth D|none] [--seed S] [--min-leaf N]`
//!
//! `DIR` (default `../shared/data/leg_tracker/training/text`) holds one recording per
//! `NAME.scans.txt.gz` (the `scans.txt` format of the leg_tracker benchmarks), with
//! `NAME.legs.txt` labels (`scan_line x y n idx…`; `n` may be 0: the label's position is
//! what counts) or, without one, a recording of rooms without people (every cluster a
//! non-leg). The model is written to `FILE` (default `leg_forest.bin`); with the defaults
//! on the shared training set it is byte for byte `tracking/models/leg_forest.bin`
//! (`tracking/tests/shipped_model.rs` checks it). The last line printed is one JSON object:
//! rows, legs, the cross-validated ROC AUC (5 folds inside the training set), the operating
//! point with its precision and recall, the model's size.

use haunts::tracking::detect::forest::train::{ForestParams, train_from_dir};
use haunts::tracking::detect::training::SampleParams;

mod common;

const USAGE: &str = "usage: train_leg_detector [DIR] [--out FILE] [--trees N] [--depth D|none] \
                     [--seed S] [--min-leaf N]";

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut dir = String::from("../shared/data/leg_tracker/training/text");
    let mut out = String::from("leg_forest.bin");
    let mut params = ForestParams::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = args.next().ok_or(USAGE)?,
            "--trees" => params.trees = args.next().ok_or(USAGE)?.parse()?,
            "--depth" => {
                let d = args.next().ok_or(USAGE)?;
                params.max_depth = if d == "none" { None } else { Some(d.parse()?) };
            }
            "--seed" => params.seed = args.next().ok_or(USAGE)?.parse()?,
            "--min-leaf" => params.min_samples_leaf = args.next().ok_or(USAGE)?.parse()?,
            _ if !a.starts_with("--") => dir = a,
            _ => return Err(USAGE.into()),
        }
    }
    let trained = train_from_dir(&dir, &SampleParams::default(), &params)?;
    let bytes = trained.forest.to_bytes();
    std::fs::write(&out, &bytes)?;
    let cv = &trained.cross_validation;
    let legs = trained.samples.legs.iter().filter(|&&l| l).count();
    eprintln!(
        "{} recordings ({} malformed lines skipped), {} rows ({legs} legs, {} labels matched no \
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
    );
    Ok(())
}
