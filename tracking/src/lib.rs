#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// The `nalgebra` this crate's API is built on (points, poses, vectors), so that a caller
/// whose own `Cargo.toml` pins another version can name the exact types:
/// `use haunts_tracking::nalgebra::Point2`.
pub use nalgebra;

pub mod detect;
mod error;
pub mod eval;
pub mod io;
pub mod track;

pub use detect::{
    Cluster, ClusterParams, Detection, Detector, FixedDetector, ForestDetector,
    ForestDetectorParams, Leg, LegDetector, LegDetectorParams, LegForest, RecurringObjects,
    RecurringParams, ScoredCluster, StaticMap, StaticMapParams, cluster_features, clusters,
};
#[cfg(feature = "train")]
pub use detect::{ForestParams, LabelledScan, LegLabel, ScanLabels, train_forest};
pub use error::{Result, TrackingError};
pub use eval::{
    ClearMot, ClearMotParams, Convention, EvalFrames, EvalParams, EvalReport, Scoring, Sequence,
    TrackingFrame, clear_mot, evaluate_sequence, protocol_frames, truth_frames_for_scans,
};
pub use io::{
    DelimitedOptions, Delimiter, EthOptions, KEEP_SKIPPED, OdomClock, OdomPose, Parsed,
    PersonPosition, SceneMap, SkipReason, SkippedLine, StampedScan, StaticTransform, Trajectory,
    keep_near, odometry_history, parse_delimited, parse_eth, parse_ground_truth, parse_odometry,
    parse_scans, parse_scene_map, parse_static_transforms, read_delimited, read_eth,
    read_ground_truth, read_odometry, read_scans, read_static_transforms, static_chain,
};
pub use track::{
    CombinationParams, DetectionTracker, DummyFilterParams, DummyReport, KalmanParams,
    KalmanTracker, OnlineTracker, ParticleParams, ParticleTracker, Track, TrackLists, Tracker,
    filter_dummies,
};
