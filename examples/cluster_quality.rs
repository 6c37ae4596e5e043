//! Per-cluster quality of the leg classifiers on a recorded `leg_tracker` sequence: every
//! cluster of `leg_tracker`'s clustering at an annotated scan, within the bearing window
//! (−80°, 12°), is a leg when an annotated person stands within 0.25 m of its centroid. For
//! the learned forest (shipped, trained on leg_tracker's training set only) and for the
//! geometric detector's rules (chord < 0.3 m and not a straight piece wider than 0.13 m;
//! and the one-feature rule "narrower is likelier a leg"), the ROC AUC and the precision
//! and recall at the operating point.
//!
//! `cargo run --release --example cluster_quality -- <dir>`; the last line printed is one
//! JSON object.

use haunts::tracking::detect::forest::quality::{precision_recall, roc_auc};
use haunts::tracking::detect::{ForestDetector, LegDetectorParams};
use haunts::tracking::eval::mot::truth_frames_for_scans;
use haunts::tracking::eval::sequence::Sequence;

mod common;

fn main() -> std::process::ExitCode {
    common::report(run())
}

/// Whether the geometric detector's cluster rules accept these points (beam order).
fn geometric(points: &[nalgebra::Point2<f64>], p: &LegDetectorParams) -> bool {
    let (Some(a), Some(b)) = (points.first(), points.last()) else {
        return false;
    };
    let length = (b - a).norm();
    let n = points.len() as f64;
    let c = points
        .iter()
        .fold(nalgebra::Vector2::zeros(), |s, q| s + q.coords)
        / n;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for q in points {
        let d = q.coords - c;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let h = 0.5 * (sxx + syy);
    let r = (0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy).sqrt();
    let ratio = if h + r > 0.0 {
        (h - r).max(0.0) / (h + r)
    } else {
        0.0
    };
    length < p.max_cluster_length
        && !(length > p.straight_length && ratio < p.straight_eigenvalue_ratio)
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args()
        .nth(1)
        .ok_or("usage: cluster_quality <dir>")?;
    let sequence = Sequence::read(&dir)?;
    let detector = ForestDetector::shipped()?;
    let rules = LegDetectorParams::default();
    let times: Vec<f64> = sequence.scans.iter().map(|s| s.bag_time).collect();
    let truth = truth_frames_for_scans(&times, &sequence.ground_truth)?;
    let window = (-80f64.to_radians(), 12f64.to_radians());
    let (mut forest, mut geo, mut narrow, mut legs) = (vec![], vec![], vec![], vec![]);
    let mut range = vec![];
    for (s, frame) in sequence.scans.iter().zip(&truth.frames) {
        if frame.objects.is_empty() {
            continue;
        }
        for c in detector.scored(&s.scan)? {
            let bearing = c.centroid.y.atan2(c.centroid.x);
            if !(window.0..=window.1).contains(&bearing) {
                continue;
            }
            let points = &c.cluster.points;
            range.push(c.centroid.coords.norm());
            forest.push(c.probability);
            geo.push(f64::from(u8::from(geometric(points, &rules))));
            narrow.push(match (points.first(), points.last()) {
                (Some(a), Some(b)) => -(b - a).norm(),
                _ => f64::NEG_INFINITY,
            });
            legs.push(
                frame
                    .objects
                    .iter()
                    .any(|o| (o.1 - c.centroid).norm() < 0.25),
            );
        }
    }
    let n_legs = legs.iter().filter(|&&l| l).count();
    // Where the forest's misses are: recall by range (leg_tracker labelled legs within 5 m).
    for (lo, hi) in [(0.0, 3.0), (3.0, 5.0), (5.0, 10.0)] {
        let band = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .zip(&range)
                .filter(|(_, r)| (lo..hi).contains(*r))
                .map(|(x, _)| *x)
                .collect()
        };
        let in_band: Vec<bool> = legs
            .iter()
            .zip(&range)
            .filter(|(_, r)| (lo..hi).contains(*r))
            .map(|(l, _)| *l)
            .collect();
        let (f, g) = (band(&forest), band(&geo));
        eprintln!(
            "  {lo}–{hi} m: {} clusters, {} legs; forest AUC {:.3}, recall {:.3}; geometric recall {:.3}",
            in_band.len(),
            in_band.iter().filter(|&&l| l).count(),
            roc_auc(&f, &in_band),
            precision_recall(&f, &in_band, detector.min_probability()).1,
            precision_recall(&g, &in_band, 1.0).1,
        );
    }
    let (fp, fr) = precision_recall(&forest, &legs, detector.min_probability());
    let (gp, gr) = precision_recall(&geo, &legs, 1.0);
    let (auc_f, auc_g, auc_w) = (
        roc_auc(&forest, &legs),
        roc_auc(&geo, &legs),
        roc_auc(&narrow, &legs),
    );
    eprintln!(
        "{} clusters at annotated scans in the window, {n_legs} within 0.25 m of a person; \
         forest: AUC {auc_f:.3}, at p ≥ {:.2} precision {fp:.3} recall {fr:.3}; geometric \
         rules: AUC {auc_g:.3}, precision {gp:.3} recall {gr:.3}; width alone: AUC {auc_w:.3}",
        legs.len(),
        detector.min_probability()
    );
    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{\"clusters\":{},\"legs\":{n_legs},\"forest\":{{\"auc\":{auc_f:.4},\"threshold\":{},\
         \"precision\":{fp:.4},\"recall\":{fr:.4}}},\"geometric\":{{\"auc\":{auc_g:.4},\
         \"precision\":{gp:.4},\"recall\":{gr:.4}}},\"width_auc\":{auc_w:.4}}}",
            legs.len(),
            detector.min_probability()
        ))
    );
    Ok(())
}
