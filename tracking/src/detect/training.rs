//! Labelled scans for training a leg classifier: scans with the positions of their labelled
//! legs, or scans of rooms without people, turned into feature rows.
//!
//! The input is what `leg_tracker`'s training tools record — a scan and the centroids of its
//! leg clusters (a `geometry_msgs/PoseArray` in the laser frame), or scans where every
//! cluster is a non-leg — whatever the file it came from: the text copies of its training
//! bags (`positive_K.legs.txt` beside `positive_K.scans.txt.gz`, read by the `train`
//! feature's `train_from_dir`),
//! or a user's own bags. In a scan with labels, the clusters that no label matches are
//! *unlabelled*, not negatives (the labellers marked only the legs in a window of the
//! laser's view); only scans marked [`ScanLabels::NoPeople`] give negatives.
//!
//! Feature `train`: these are the inputs of [`crate::detect::forest::train`].

use std::io::Read;
use std::path::Path;

use haunts_occupancy::LaserScan;
use nalgebra::Point2;

use crate::detect::cluster::{ClusterParams, clusters};
use crate::detect::features::{FEATURES, cluster_features};
use crate::io::lines::{Fields, Parsed, SkipReason, parse_lines, read_path};
use crate::{Result, read_scans};

/// What is known of the clusters of one scan.
#[derive(Debug, Clone, PartialEq)]
pub enum ScanLabels {
    /// The centroids of the scan's leg clusters (sensor frame, metres); the other clusters
    /// are unlabelled.
    Legs(Vec<Point2<f64>>),
    /// Nobody was in view: every cluster is a non-leg.
    NoPeople,
}

/// One scan with its labels.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledScan {
    /// The scan.
    pub scan: LaserScan,
    /// Its labels.
    pub labels: ScanLabels,
}

/// One line of a `legs.txt` label file: a labelled leg of one scan.
#[derive(Debug, Clone, PartialEq)]
pub struct LegLabel {
    /// 0-based data line of the scan in the scans file.
    pub scan_line: usize,
    /// The labelled centroid, sensor frame, metres.
    pub position: Point2<f64>,
    /// The beams of the cluster with that centroid, as the converter found them (empty when
    /// it found none).
    pub indices: Vec<usize>,
}

/// Reads a `legs.txt` label file (plain or gzipped): per line `scan_line x y n idx_1 … idx_n`.
///
/// # Errors
/// [`crate::TrackingError::Io`] when the file cannot be read.
pub fn read_leg_labels(path: impl AsRef<Path>) -> Result<Parsed<LegLabel>> {
    read_path(path.as_ref(), leg_labels)
}

fn leg_labels(reader: &mut dyn Read) -> std::io::Result<Parsed<LegLabel>> {
    parse_lines(reader, 0, |text, _| {
        let f = Fields::whitespace(text);
        f.at_least(4)?;
        let index = |i: usize| {
            f.integer(i)
                .and_then(|v| usize::try_from(v).map_err(|_| SkipReason::BadInteger { field: i }))
        };
        let scan_line = index(0)?;
        let position = Point2::new(f.finite(1)?, f.finite(2)?);
        let n = index(3)?;
        f.exactly(4 + n)?;
        let indices = (4..4 + n).map(index).collect::<Result<Vec<_>, _>>()?;
        Ok(LegLabel {
            scan_line,
            position,
            indices,
        })
    })
}

/// Reads the scans of `scans` and, when `legs` is given, the labels of that file (every
/// scan becomes [`ScanLabels::Legs`], with the labels whose `scan_line` is its index among
/// the scans read); without `legs`, every scan is [`ScanLabels::NoPeople`]. Returns the
/// scans and the number of malformed lines skipped over both files (a skipped scan line
/// would shift the labels: check it is 0).
///
/// # Errors
/// [`crate::TrackingError::Io`] when a file cannot be read.
pub(crate) fn read_labelled_scans(
    scans: impl AsRef<Path>,
    legs: Option<&Path>,
) -> Result<(Vec<LabelledScan>, usize)> {
    let parsed = read_scans(scans)?;
    let mut skipped = parsed.skipped;
    let mut out: Vec<LabelledScan> = parsed
        .records
        .into_iter()
        .map(|s| LabelledScan {
            scan: s.scan,
            labels: if legs.is_some() {
                ScanLabels::Legs(Vec::new())
            } else {
                ScanLabels::NoPeople
            },
        })
        .collect();
    if let Some(legs) = legs {
        let labels = read_leg_labels(legs)?;
        skipped += labels.skipped;
        for label in labels.records {
            match out.get_mut(label.scan_line).map(|s| &mut s.labels) {
                Some(ScanLabels::Legs(v)) => v.push(label.position),
                _ => skipped += 1,
            }
        }
    }
    Ok((out, skipped))
}

/// A named recording of labelled scans (what [`read_training_dir`] reads and
/// [`crate::detect::forest::train::train_from_recordings`] takes).
pub type Recording = (String, Vec<LabelledScan>);

/// The labelled scans of a folder of text copies, one recording per scans file, in file-name
/// order: every `NAME.scans.txt.gz` (or `NAME.scans.txt`) with its `NAME.legs.txt` labels
/// when there is one ([`ScanLabels::Legs`]), else a recording without people
/// ([`ScanLabels::NoPeople`]). The layout of `leg_tracker/training/text`; write a user's
/// own scans the same way to retrain the detector for another laser. Returns the
/// recordings' names with their scans, and the malformed lines skipped.
///
/// # Errors
/// [`crate::TrackingError::Io`] when the folder or a file cannot be read.
pub fn read_training_dir(dir: impl AsRef<Path>) -> Result<(Vec<Recording>, usize)> {
    let dir = dir.as_ref();
    let entries = std::fs::read_dir(dir).map_err(|e| crate::error::io_error(dir, e))?;
    let mut names: Vec<String> = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".scans.txt.gz") || n.ends_with(".scans.txt"))
        .collect();
    names.sort();
    let mut out = Vec::with_capacity(names.len());
    let mut skipped = 0;
    for name in names {
        let stem = name
            .trim_end_matches(".gz")
            .trim_end_matches(".scans.txt")
            .to_owned();
        let legs = dir.join(format!("{stem}.legs.txt"));
        let (scans, s) = read_labelled_scans(dir.join(&name), legs.exists().then_some(&*legs))?;
        skipped += s;
        out.push((stem, scans));
    }
    Ok((out, skipped))
}

/// How labelled scans become feature rows.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct SampleParams {
    /// The clustering (it must be the one the labels were made with).
    pub cluster: ClusterParams,
    /// A label marks the cluster whose centroid is nearest to it, if within this, metres
    /// (`leg_tracker`'s `train_leg_detector`: 0.1).
    pub match_distance: f64,
    /// Clusters farther from the laser than this are left out, metres (the detector
    /// ignores them too).
    pub max_range: f64,
}

impl Default for SampleParams {
    /// `leg_tracker`'s clustering (0.13 m, 3 points), labels matched within 0.1 m, clusters
    /// within 10 m.
    fn default() -> Self {
        Self {
            cluster: ClusterParams::default(),
            match_distance: 0.1,
            max_range: 10.0,
        }
    }
}

impl SampleParams {
    /// Sets [`SampleParams::cluster`].
    pub fn with_cluster(mut self, v: ClusterParams) -> Self {
        self.cluster = v;
        self
    }
    /// Sets [`SampleParams::match_distance`].
    pub fn with_match_distance(mut self, v: f64) -> Self {
        self.match_distance = v;
        self
    }
    /// Sets [`SampleParams::max_range`].
    pub fn with_max_range(mut self, v: f64) -> Self {
        self.max_range = v;
        self
    }

    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`crate::TrackingError::InvalidParameter`] naming `match_distance` or `max_range`
    /// (finite and > 0) or the clustering's parameter.
    pub fn check(self) -> Result<Self> {
        self.cluster.check()?;
        for (name, v) in [
            ("match_distance", self.match_distance),
            ("max_range", self.max_range),
        ] {
            haunts_core::positive(name, v)?;
        }
        Ok(self)
    }
}

/// Feature rows with their labels and where they came from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Samples {
    /// One feature row per cluster ([`crate::detect::features::cluster_features`]).
    pub features: Vec<[f64; FEATURES]>,
    /// Whether each row is a leg.
    pub legs: Vec<bool>,
    /// Which recording (the index given to [`Samples::add`]) and which scan of it each row
    /// came from: cross-validation keeps neighbouring scans of one recording together.
    pub origin: Vec<(usize, usize)>,
    /// The index of each row's cluster among its scan's clusters (`clusters` of the scan with
    /// [`SampleParams::cluster`]): what a caller needs to find the row's beams again.
    pub cluster: Vec<usize>,
    /// Labels that matched no cluster.
    pub unmatched_labels: usize,
}

impl Samples {
    /// Adds the labelled clusters of one recording's scans (in time order), as recording
    /// number `recording`: in a [`ScanLabels::Legs`] scan, the cluster nearest to each label
    /// (within `match_distance`) is a leg and the others are left out; in a
    /// [`ScanLabels::NoPeople`] scan every cluster is a non-leg.
    ///
    /// # Errors
    /// As [`SampleParams::check`].
    ///
    /// # Complexity
    /// O(b + c·l) per scan of `b` beams, `c` clusters and `l` labels.
    pub fn add(
        &mut self,
        recording: usize,
        scans: &[LabelledScan],
        params: &SampleParams,
    ) -> Result<()> {
        let params = params.check()?;
        for (k, s) in scans.iter().enumerate() {
            let found = clusters(&s.scan, &params.cluster)?;
            let centroids: Vec<Point2<f64>> = found.iter().map(|c| c.centroid()).collect();
            let near = |c: &Point2<f64>| c.coords.norm() <= params.max_range;
            match &s.labels {
                ScanLabels::NoPeople => {
                    for (i, (c, centroid)) in found.iter().zip(&centroids).enumerate() {
                        if near(centroid) {
                            self.push(cluster_features(&s.scan, c), false, (recording, k), i);
                        }
                    }
                }
                ScanLabels::Legs(labels) => {
                    let mut taken = vec![false; found.len()];
                    for label in labels {
                        let best = centroids
                            .iter()
                            .enumerate()
                            .filter(|(i, _)| !taken[*i])
                            .map(|(i, c)| (i, (c - label).norm()))
                            .min_by(|a, b| a.1.total_cmp(&b.1));
                        match best {
                            Some((i, d)) if d <= params.match_distance => {
                                taken[i] = true;
                                if near(&centroids[i]) {
                                    let f = cluster_features(&s.scan, &found[i]);
                                    self.push(f, true, (recording, k), i);
                                }
                            }
                            _ => self.unmatched_labels += 1,
                        }
                    }
                }
            }
        }
        Ok(())
    }

    fn push(&mut self, f: [f64; FEATURES], leg: bool, origin: (usize, usize), cluster: usize) {
        self.features.push(f);
        self.legs.push(leg);
        self.origin.push(origin);
        self.cluster.push(cluster);
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.features.len()
    }

    /// Whether there is no row.
    pub fn is_empty(&self) -> bool {
        self.features.is_empty()
    }

    /// The rows whose index `keep` accepts.
    pub fn subset(&self, keep: impl Fn(usize) -> bool) -> Self {
        let mut out = Self::default();
        for i in (0..self.len()).filter(|&i| keep(i)) {
            out.push(
                self.features[i],
                self.legs[i],
                self.origin[i],
                self.cluster[i],
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::io::lines::read_reader;

    #[test]
    fn label_lines_are_read_and_bad_ones_skipped() {
        let text = "# header\n0 1.5 0.25 3 10 11 12\n1 2.0 0.0 0\n2 1.0 1.0 2 5\nx 1 1 0\n";
        let parsed = read_reader(text.as_bytes(), leg_labels).unwrap();
        assert_eq!(parsed.records.len(), 2);
        assert_eq!(parsed.records[0].indices, vec![10, 11, 12]);
        assert_eq!(parsed.records[1].scan_line, 1);
        assert!(parsed.records[1].indices.is_empty());
        assert_eq!(parsed.skipped, 2);
    }

    #[test]
    fn labels_pick_the_nearest_cluster_and_leave_the_rest_out() {
        // Two clusters at 2 m and 3 m; a label near the first; a scan with nobody.
        let ranges = vec![2.0, 2.0, 2.0, 0.0, 3.0, 3.0, 3.0, 3.0];
        let scan = LaserScan::new(0.0, 0.0, 0.01, 0.03, 11.0, ranges, vec![]).unwrap();
        let c = clusters(&scan, &ClusterParams::default()).unwrap();
        let label = c[0].centroid() + nalgebra::Vector2::new(0.05, 0.0);
        let scans = [
            LabelledScan {
                scan: scan.clone(),
                labels: ScanLabels::Legs(vec![label, Point2::new(9.0, 9.0)]),
            },
            LabelledScan {
                scan,
                labels: ScanLabels::NoPeople,
            },
        ];
        let mut s = Samples::default();
        s.add(4, &scans, &SampleParams::default()).unwrap();
        assert_eq!(s.legs, vec![true, false, false]);
        assert_eq!(s.origin, vec![(4, 0), (4, 1), (4, 1)]);
        assert_eq!(s.cluster, vec![0, 0, 1]);
        assert_eq!(s.unmatched_labels, 1);
        assert_eq!(s.features[0][0], 3.0);
    }
}
