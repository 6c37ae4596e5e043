//! The learned leg detector's training data from robot logs (feature `train`): labelled
//! scans read from ROS 1 bags or MCAP files through `haunts-bag`, and the forest trained on
//! them with `haunts-tracking`'s [`train_from_recordings`].
//!
//! A log is read the way `leg_tracker`'s training tools record one: every
//! `sensor_msgs/LaserScan` topic is a recording; a `geometry_msgs/PoseArray` topic holds
//! the labels, each message the centroids (laser frame) of the leg clusters of **the scan
//! that follows it**. A log without a `PoseArray` topic is of rooms without people: every
//! cluster of its scans is a non-leg. The shipped forest ([`LegForest::shipped`]) is
//! [`train_from_recordings`] of the recordings of `leg_tracker`'s training bags, in
//! file-name order, with the default parameters, byte for byte (`tests/train_from_bags.rs`).
//!
//! ```no_run
//! use haunts::tracking::detect::forest::train::{ForestParams, train_from_recordings};
//! use haunts::tracking::detect::training::SampleParams;
//!
//! let (mut recordings, mut skipped) = (Vec::new(), 0);
//! for bag in ["walkers.bag", "empty_rooms.mcap"] {
//!     let log = haunts::training::labelled_scans(bag, None)?;
//!     skipped += log.skipped;
//!     recordings.extend(log.recordings);
//! }
//! let trained = train_from_recordings(
//!     recordings, skipped, &SampleParams::default(), &ForestParams::default(),
//! )?;
//! std::fs::write("my_forest.bin", trained.forest.to_bytes()).expect("writable");
//! println!("cross-validated AUC {:.3}", trained.cross_validation.auc);
//! # Ok::<(), haunts::pipeline::PipelineError>(())
//! ```
//!
//! [`LegForest::shipped`]: haunts_tracking::detect::LegForest::shipped
//! [`train_from_recordings`]: haunts_tracking::detect::forest::train::train_from_recordings

use std::path::Path;

use haunts_bag::msg::{LaserScan, PoseArray};
use haunts_bag::{Bag, codec, convert};
use haunts_tracking::detect::training::{LabelledScan, Recording, ScanLabels};
use nalgebra::Point2;

use crate::pipeline::{PipelineError, Result};

/// The labelled scans of one log.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledLog {
    /// One recording per `LaserScan` topic, in topic-name order, named after the file's stem
    /// (`STEM_TOPIC` when it has several scan topics, the topic's slashes as underscores).
    pub recordings: Vec<Recording>,
    /// The labels' topic (`None`: a log of rooms without people).
    pub labels_topic: Option<String>,
    /// Messages skipped: undecodable, or scans that are not valid scans (a bad increment or
    /// range limits).
    pub skipped: usize,
    /// Scans of a labelled log with no label message since the scan before: they give no
    /// row (their clusters are unlabelled, as those a label does not name).
    pub unlabelled_scans: usize,
}

/// Reads the labelled scans of the log at `path`. `labels_topic` names the labels'
/// `PoseArray` topic; `None` takes the log's only one, or none (every scan a scan of rooms
/// without people).
///
/// # Errors
/// [`PipelineError::Bag`] when the log cannot be opened or read, or a named topic is missing
/// or of another type; [`PipelineError::LabelTopics`] when `labels_topic` is `None` and the
/// log has several `PoseArray` topics.
pub fn labelled_scans(path: impl AsRef<Path>, labels_topic: Option<&str>) -> Result<LabelledLog> {
    let path = path.as_ref();
    let bag = Bag::open(path)?;
    let labels = match labels_topic {
        Some(t) => {
            // Checks the topic's type (and a ROS 1 bag's MD5 sum) before anything is read.
            drop(bag.read::<PoseArray>(t)?);
            Some(t.to_owned())
        }
        None => match bag.topics_of::<PoseArray>().as_slice() {
            [] => None,
            [only] => Some(only.name.clone()),
            several => {
                return Err(PipelineError::LabelTopics {
                    path: path.to_path_buf(),
                    topics: several.iter().map(|t| t.name.clone()).collect(),
                });
            }
        },
    };
    let mut scan_topics: Vec<String> = bag
        .topics_of::<LaserScan>()
        .iter()
        .map(|t| t.name.clone())
        .collect();
    scan_topics.sort();
    let stem = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let name = |topic: &str| match scan_topics.len() {
        1 => stem.clone(),
        _ => format!("{stem}_{}", topic.trim_matches('/').replace('/', "_")),
    };
    let mut recordings: Vec<Recording> =
        scan_topics.iter().map(|t| (name(t), Vec::new())).collect();
    let mut topics: Vec<&str> = scan_topics.iter().map(String::as_str).collect();
    topics.extend(labels.as_deref());
    let mut log = LabelledLog {
        recordings: Vec::new(),
        labels_topic: labels.clone(),
        skipped: 0,
        unlabelled_scans: 0,
    };
    // The labels of the scan to come (leg_tracker's extractor writes them just before it).
    let mut pending: Option<Vec<Point2<f64>>> = None;
    for message in bag.messages(&topics)? {
        let message = message?;
        let encoding = bag.topic(&message.topic)?.encoding;
        if labels.as_deref() == Some(&*message.topic) {
            match codec::decode::<PoseArray>(encoding, &message.data) {
                Ok(m) => {
                    let legs = m
                        .poses
                        .iter()
                        .map(|p| Point2::new(p.position.x, p.position.y));
                    pending = Some(
                        legs.filter(|p| p.x.is_finite() && p.y.is_finite())
                            .collect(),
                    );
                }
                Err(_) => log.skipped += 1,
            }
            continue;
        }
        let Some(k) = scan_topics.iter().position(|t| **t == *message.topic) else {
            continue;
        };
        let Some(scan) = codec::decode::<LaserScan>(encoding, &message.data)
            .ok()
            .and_then(|m| convert::laser_scan(&m).ok())
        else {
            log.skipped += 1;
            continue;
        };
        let labels = match (&labels, pending.take()) {
            (None, _) => ScanLabels::NoPeople,
            (Some(_), Some(legs)) => ScanLabels::Legs(legs),
            (Some(_), None) => {
                log.unlabelled_scans += 1;
                ScanLabels::Legs(Vec::new())
            }
        };
        recordings[k].1.push(LabelledScan { scan, labels });
    }
    log.recordings = recordings;
    Ok(log)
}
