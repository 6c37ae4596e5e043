//! Scoring tracks against ground truth: CLEAR MOT ([`mot`]) and the evaluation of a
//! detector and a tracker on a recorded sequence under the anchor's protocols
//! ([`sequence`]).

pub mod mot;
pub mod sequence;

pub use mot::{
    ClearMot, ClearMotParams, Convention, Frame, ScanTruth, clear_mot, group_by_time,
    truth_frames_for_scans,
};
pub use sequence::{
    EvalFrames, EvalParams, EvalReport, Scoring, Sequence, TentativeSample, TrackingFrame,
    evaluate_sequence, protocol_frames,
};
