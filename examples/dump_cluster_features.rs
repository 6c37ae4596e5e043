//! Writes our 16 cluster features (`haunts::tracking::detect::features`) as CSV, with the
//! beams of each cluster, so that a peer can compute other features of the very same
//! clusters (`benches/peers/leg_features_transfer.py`, issue 17).
//!
//! - `dump_cluster_features -- training <training/text dir> OUT.csv`: every row of
//!   `Samples` (`SampleParams::default()`): recording, scan, label, centroid, beam indices,
//!   the 16 features. Each row's cluster is found again from `Samples::cluster` (its index
//!   among its scan's clusters), so its beams are known, and its features are checked to
//!   equal the row's, value for value.
//! - `dump_cluster_features -- eval <sequence dir> OUT.csv`: the clusters of
//!   `examples/cluster_quality.rs`' protocol (clusters within 10 m at the annotated scans,
//!   bearing within −80°..12°; a leg when an annotated person is within 0.25 m of the
//!   centroid), with the shipped forest's probability.
//!
//! `cargo run --release --example dump_cluster_features -- training DIR OUT.csv`

use std::io::Write;

use haunts::tracking::detect::ForestDetector;
use haunts::tracking::detect::features::{FEATURE_NAMES, cluster_features};
use haunts::tracking::detect::training::{SampleParams, Samples, read_training_dir};
use haunts::tracking::detect::{Cluster, clusters};
use haunts::tracking::eval::mot::truth_frames_for_scans;
use haunts::tracking::eval::sequence::Sequence;

mod common;

fn main() -> std::process::ExitCode {
    common::report(run())
}

fn header() -> String {
    format!(
        "recording,scan,leg,cx,cy,indices,{},probability",
        FEATURE_NAMES.join(",")
    )
}

fn row(rec: &str, scan: usize, leg: bool, c: &Cluster, f: &[f64], p: f64) -> String {
    let centroid = c.centroid();
    let idx: Vec<String> = c.indices.iter().map(|i| i.to_string()).collect();
    let feats: Vec<String> = f.iter().map(|v| format!("{v:e}")).collect();
    format!(
        "{rec},{scan},{},{:e},{:e},{},{},{p:e}",
        u8::from(leg),
        centroid.x,
        centroid.y,
        idx.join(" "),
        feats.join(",")
    )
}

fn training(dir: &str, out: &mut impl Write) -> Result<(), Box<dyn std::error::Error>> {
    let (recordings, skipped) = read_training_dir(dir)?;
    if skipped != 0 {
        return Err(format!("{skipped} malformed lines: scan numbers would shift").into());
    }
    let params = SampleParams::default();
    let mut samples = Samples::default();
    writeln!(out, "{}", header())?;
    for (k, (name, scans)) in recordings.iter().enumerate() {
        let first = samples.len();
        samples.add(k, scans, &params)?;
        // Each new row's cluster, found again by its index among its scan's clusters.
        let mut found: Option<(usize, Vec<Cluster>)> = None;
        for r in first..samples.len() {
            let (s, i) = (samples.origin[r].1, samples.cluster[r]);
            if found.as_ref().is_none_or(|f| f.0 != s) {
                found = Some((s, clusters(&scans[s].scan, &params.cluster)?));
            }
            let c = found
                .as_ref()
                .and_then(|f| f.1.get(i))
                .ok_or("a row's cluster index beyond its scan's clusters")?;
            let f = samples.features[r];
            if cluster_features(&scans[s].scan, c) != f {
                return Err(format!("row {r}: the features differ from Samples::add's").into());
            }
            writeln!(out, "{}", row(name, s, samples.legs[r], c, &f, f64::NAN))?;
        }
    }
    eprintln!(
        "{} rows ({} legs) of {} recordings, identical to Samples::add's",
        samples.len(),
        samples.legs.iter().filter(|&&l| l).count(),
        recordings.len()
    );
    Ok(())
}

fn eval(dir: &str, out: &mut impl Write) -> Result<(), Box<dyn std::error::Error>> {
    let sequence = Sequence::read(dir)?;
    if sequence.skipped_lines != 0 {
        return Err(format!("{} malformed lines", sequence.skipped_lines).into());
    }
    let detector = ForestDetector::shipped()?;
    let times: Vec<f64> = sequence.scans.iter().map(|s| s.bag_time).collect();
    let truth = truth_frames_for_scans(&times, &sequence.ground_truth)?;
    let window = (-80f64.to_radians(), 12f64.to_radians());
    writeln!(out, "{}", header())?;
    let (mut n, mut legs) = (0, 0);
    for (k, (s, frame)) in sequence.scans.iter().zip(&truth.frames).enumerate() {
        if frame.objects.is_empty() {
            continue;
        }
        for c in detector.scored(&s.scan)? {
            let bearing = c.centroid.y.atan2(c.centroid.x);
            if !(window.0..=window.1).contains(&bearing) {
                continue;
            }
            let leg = frame
                .objects
                .iter()
                .any(|o| (o.1 - c.centroid).norm() < 0.25);
            let f = cluster_features(&s.scan, &c.cluster);
            writeln!(
                out,
                "{}",
                row("moving_1", k, leg, &c.cluster, &f, c.probability)
            )?;
            n += 1;
            legs += usize::from(leg);
        }
    }
    eprintln!("{n} clusters, {legs} legs");
    Ok(())
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: dump_cluster_features training|eval <dir> <out.csv>";
    let (mode, dir, path) = match args.as_slice() {
        [_, m, d, p] => (m.as_str(), d.as_str(), p.as_str()),
        _ => return Err(usage.into()),
    };
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    match mode {
        "training" => training(dir, &mut out)?,
        "eval" => eval(dir, &mut out)?,
        _ => return Err(usage.into()),
    }
    out.flush()?;
    Ok(())
}
