//! The `leg_tracker` text export and a [`Recording`] are two views of the same data: a
//! [`Sequence`] read from text becomes a recording ([`Sequence::to_recording`]), and a
//! recording read from a bag becomes a sequence to evaluate ([`Sequence::from_recording`]),
//! so the same scores come out of the text folder, the ROS 1 bag and its MCAP twin.

use haunts_occupancy::recording::{RecordedScan, Recording, ScanList};
use haunts_occupancy::{Link, TransformTree};

use crate::eval::sequence::Sequence;
use crate::io::frames::{OdomClock, odometry_history};
use crate::{OdomPose, PersonPosition, Result, StampedScan, StaticTransform};

impl Sequence {
    /// The sequence of a recording, with its annotated people: every scan that reads (the
    /// others counted in `skipped_lines`), the odometry samples (indexed by their header
    /// stamps, as `odom.txt` is read), and the static links of its transform tree.
    ///
    /// # Errors
    /// The recording's own error when its scans cannot be read at all.
    pub fn from_recording(
        recording: &Recording,
        ground_truth: Vec<PersonPosition>,
    ) -> Result<Self> {
        let mut scans = Vec::with_capacity(recording.scan_count_hint().unwrap_or(0));
        let mut skipped_lines = 0;
        for (i, scan) in recording.scans()?.enumerate() {
            match scan {
                Ok(s) => scans.push(StampedScan {
                    bag_time: s.received,
                    frame: s.frame,
                    scan: s.scan,
                    line: i + 1,
                }),
                Err(_) => skipped_lines += 1,
            }
        }
        let odometry = recording.odometry().map_or_else(Vec::new, |h| {
            h.samples()
                .enumerate()
                .map(|(i, (t, pose))| OdomPose {
                    bag_time: t,
                    stamp: t,
                    pose: *pose,
                    line: i + 1,
                })
                .collect()
        });
        let tree = recording.transforms();
        let static_transforms = tree
            .frames()
            .into_iter()
            .filter_map(|child| match tree.parent(child) {
                Some((parent, Link::Static(transform))) => Some(StaticTransform {
                    parent: parent.to_owned(),
                    child: child.to_owned(),
                    transform: *transform,
                    line: 0,
                }),
                _ => None,
            })
            .collect();
        Ok(Self {
            scans,
            odometry,
            static_transforms,
            ground_truth,
            skipped_lines,
        })
    }

    /// The recording of this sequence: its scans, its odometry (by header stamp) from
    /// `odom_frame` to `base_frame`, and its static transforms (ground truth is left out).
    ///
    /// # Errors
    /// Conflicting static transforms; odometry without a finite sample.
    pub fn to_recording(&self, odom_frame: &str, base_frame: &str) -> Result<Recording> {
        let scans = ScanList(
            self.scans
                .iter()
                .map(|s| RecordedScan {
                    scan: s.scan.clone(),
                    frame: s.frame.clone(),
                    received: s.bag_time,
                })
                .collect(),
        );
        let mut tree = TransformTree::new();
        for tf in &self.static_transforms {
            tree.add_static(&tf.parent, &tf.child, tf.transform)?;
        }
        let recording = Recording::new(scans).with_transforms(tree);
        Ok(if self.odometry.is_empty() {
            recording.with_base_frame(base_frame)
        } else {
            let history = odometry_history(&self.odometry, OdomClock::HeaderStamp)?;
            recording.with_odometry(history, odom_frame, base_frame)
        })
    }
}
