//! Evaluation of a detector and a tracker on a recorded `leg_tracker` sequence, scored with
//! CLEAR MOT in the ground truth's frame: the glue that the `eval_tracking` example and the
//! real-data tests share.
//!
//! For each scan (in bag order): detect in the laser frame (with
//! [`EvalParams::static_map`], after mapping the scan and dropping the legs on static
//! objects, see [`crate::detect::static_map`]), move the detections to the
//! odometry frame with the robot's pose at the scan's header stamp (when `odom.txt` is
//! there; otherwise track in the laser frame), update the tracker at that stamp, and map the
//! reported tracks back to the laser frame of that scan, where the ground truth is
//! annotated (see [`crate::io::frames`]). Ground truth belongs to the last scan before it
//! ([`crate::eval::mot::truth_frames_for_scans`]).
//!
//! [`Scoring::Online`] scores the tracks reported after each scan; [`Scoring::Trajectories`]
//! scores the day's trajectories instead, in which a track counts from its birth rather than
//! from its confirmation (what a map of where people were is built from).
//!
//! # What the ground truth covers
//! `leg_tracker_benchmarks` scores only people within a bearing window of the laser, the
//! field of view its annotators covered: `clear_mot.py` with `constrain_to_specific_angle`
//! drops ground truth **and** tracks whose bearing `atan2(y, x)` in the laser frame is
//! outside `[min_angle, max_angle]`; its launch files for `general_tracking_moving` use
//! −80° to 12°. [`EvalParams::leg_tracker_benchmarks`] does the same. People outside the
//! window (or never annotated) are neither misses nor false positives there.

use std::path::Path;

use nalgebra::{Isometry2, Point2};

use crate::detect::static_map::StaticMapParams;
use crate::detect::{Detector, rule};
use crate::eval::mot::{
    ClearMot, ClearMotParams, Convention, Frame, clear_mot, truth_frames_for_scans,
};
use crate::io::frames::{OdomClock, odometry_history, static_chain};
use crate::io::leg_tracker::{OdomPose, PersonPosition, StampedScan, StaticTransform};
use crate::track::online::OnlineTracker;
use crate::track::{Track, Tracker};
use crate::{
    Result, Trajectory, read_ground_truth, read_odometry, read_scans, read_static_transforms,
};

/// A recorded sequence: the text export of a `leg_tracker` benchmark bag.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Sequence {
    /// The scans, in file (bag) order.
    pub scans: Vec<StampedScan>,
    /// Odometry poses of the robot base; empty when the sequence has none.
    pub odometry: Vec<OdomPose>,
    /// Static transforms (the laser's pose on the robot); empty when there are none.
    pub static_transforms: Vec<StaticTransform>,
    /// Annotated people, in the laser frame.
    pub ground_truth: Vec<PersonPosition>,
    /// Malformed lines skipped over all files.
    pub skipped_lines: usize,
}

impl Sequence {
    /// Reads `scans.txt` and `ground_truth_people.txt` from `dir`, and `odom.txt` and
    /// `static_tf.txt` when they exist (each plain or gzipped).
    ///
    /// # Errors
    /// [`crate::TrackingError::Io`] when a file that exists (or one of the two required
    /// ones) cannot be read.
    pub fn read(dir: impl AsRef<Path>) -> Result<Self> {
        let dir = dir.as_ref();
        let scans = read_scans(dir.join("scans.txt"))?;
        let truth = read_ground_truth(dir.join("ground_truth_people.txt"))?;
        let mut skipped_lines = scans.skipped + truth.skipped;
        let mut odometry = Vec::new();
        if dir.join("odom.txt").exists() {
            let parsed = read_odometry(dir.join("odom.txt"))?;
            skipped_lines += parsed.skipped;
            odometry = parsed.records;
        }
        let mut static_transforms = Vec::new();
        if dir.join("static_tf.txt").exists() {
            let parsed = read_static_transforms(dir.join("static_tf.txt"))?;
            skipped_lines += parsed.skipped;
            static_transforms = parsed.records;
        }
        Ok(Self {
            scans: scans.records,
            odometry,
            static_transforms,
            ground_truth: truth.records,
            skipped_lines,
        })
    }
}

/// Which instants are scored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum EvalFrames {
    /// Only scans with at least one annotation (before the bearing window is applied): the
    /// annotated times.
    #[default]
    Annotated,
    /// Every scan, as `clear_mot.py` does: tracks reported at scans nobody annotated count
    /// as false positives.
    EveryScan,
}

/// What is scored: the tracks a robot sees scan by scan, or the trajectories a map is built
/// from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Scoring {
    /// The tracks [`Tracker::tracks`] reports after each scan: only confirmed tracks, from
    /// the scan that confirmed them on (what a robot acting on people knows at the time, and
    /// what `leg_tracker_benchmarks` scores).
    #[default]
    Online,
    /// [`Tracker::trajectories`] after the whole sequence, each sample scored at the scan it
    /// was recorded at: a confirmed track counts from its birth, the detections before its
    /// confirmation included (what the density and activity maps of a day are built from).
    /// Positions are mapped to each scan's laser frame with that scan's pose. A tracker with
    /// a `max_history` cap keeps only its latest samples, so only those are scored.
    Trajectories,
}

/// Parameters of [`evaluate_sequence`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct EvalParams {
    /// Match threshold and conventions of the CLEAR MOT scores.
    pub clear_mot: ClearMotParams,
    /// Only ground truth and tracks whose bearing in the laser frame lies in `[min, max]`
    /// (radians) are scored; `None` scores everything.
    pub bearing_window: Option<(f64, f64)>,
    /// Which instants are scored.
    pub frames: EvalFrames,
    /// The robot's frame, which the static transforms connect the laser to.
    pub base_frame: String,
    /// The map of static objects whose legs are removed before pairing, unless a tracked
    /// person stands there (`None`: every leg is kept).
    pub static_map: Option<StaticMapParams>,
    /// The tracks scored at each instant.
    pub scoring: Scoring,
    /// Whether to keep every tentative track at the scored instants
    /// ([`EvalReport::tentative`]), to study what could confirm people sooner.
    pub record_tentative: bool,
}

impl Default for EvalParams {
    /// Every bearing, annotated times, the `motmetrics` conventions at 0.75 m, base frame
    /// `base_link`, online scoring, tentative tracks not recorded.
    fn default() -> Self {
        Self {
            clear_mot: ClearMotParams::default(),
            bearing_window: None,
            frames: EvalFrames::Annotated,
            base_frame: "base_link".into(),
            static_map: None,
            scoring: Scoring::Online,
            record_tentative: false,
        }
    }
}

impl EvalParams {
    /// The protocol of `leg_tracker_benchmarks` for its `general_tracking_moving` bags:
    /// bearings from −80° to 12° of the laser, `clear_mot.py`'s conventions at 0.75 m;
    /// scored at the annotated times.
    pub fn leg_tracker_benchmarks() -> Self {
        Self {
            clear_mot: ClearMotParams::default().with_convention(Convention::LegTrackerBenchmarks),
            bearing_window: Some((-80f64.to_radians(), 12f64.to_radians())),
            ..Self::default()
        }
    }

    /// Sets [`EvalParams::frames`].
    pub fn with_frames(mut self, frames: EvalFrames) -> Self {
        self.frames = frames;
        self
    }

    /// Sets [`EvalParams::static_map`].
    pub fn with_static_map(mut self, static_map: Option<StaticMapParams>) -> Self {
        self.static_map = static_map;
        self
    }

    /// Sets [`EvalParams::scoring`].
    pub fn with_scoring(mut self, scoring: Scoring) -> Self {
        self.scoring = scoring;
        self
    }

    /// Sets [`EvalParams::record_tentative`].
    pub fn with_record_tentative(mut self, record: bool) -> Self {
        self.record_tentative = record;
        self
    }

    /// Sets [`EvalParams::base_frame`] (e.g. `base_footprint`, read from a robot's
    /// configuration).
    pub fn with_base_frame(mut self, frame: impl Into<String>) -> Self {
        self.base_frame = frame.into();
        self
    }

    /// Sets [`EvalParams::bearing_window`].
    pub fn with_bearing_window(mut self, window: Option<(f64, f64)>) -> Self {
        self.bearing_window = window;
        self
    }

    /// The parameters, if the window is finite with `min ≤ max` and the CLEAR MOT
    /// parameters are valid.
    ///
    /// # Errors
    /// [`crate::TrackingError::InvalidParameter`] naming `bearing_window` or the CLEAR MOT
    /// parameter.
    pub fn check(self) -> Result<Self> {
        if let Some((lo, hi)) = self.bearing_window {
            rule(
                lo.is_finite() && hi.is_finite() && lo <= hi,
                "bearing_window",
                hi - lo,
                "must be finite with min <= max",
            )?;
        }
        self.clear_mot.check()?;
        if let Some(m) = self.static_map {
            m.check()?;
        }
        Ok(self)
    }
}

/// The frame the tracker worked in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum TrackingFrame {
    /// The odometry frame (`odom.txt` was given).
    Odometry,
    /// The laser frame of each scan (no odometry: a moving robot moves the people too).
    Sensor,
}

/// What [`evaluate_sequence`] measured.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct EvalReport {
    /// The CLEAR MOT scores.
    pub scores: ClearMot,
    /// Scans read.
    pub scans: usize,
    /// Scans the tracker skipped: header stamp earlier than the previous one, or outside
    /// the odometry's time span. They report no tracks.
    pub skipped_scans: usize,
    /// Instants scored.
    pub frames: usize,
    /// Ground-truth records scored nowhere: earlier than the first scan, or belonging to a
    /// scan that is missing (see [`truth_frames_for_scans`]).
    pub unassigned_truth: usize,
    /// Detections over all scans.
    pub detections: usize,
    /// Resets of the tracker on time jumps.
    pub resets: usize,
    /// The frame the tracker worked in.
    pub tracking_frame: TrackingFrame,
    /// Laser frames placed at the robot's origin because odometry was given without static
    /// transforms (no `static_tf.txt`): their mount was assumed, not known, and an offset
    /// laser then moves the people it sees as the robot turns. Empty when every mount was
    /// known or no odometry was used.
    pub mounts_assumed: Vec<String>,
    /// Scored annotated people whom no scored track came within the match threshold of,
    /// while a tentative track ([`Tracker::tentative`]) did: people the tracker was
    /// following but had not confirmed (nearly all the online misses on the `leg_tracker`
    /// bag).
    pub followed_tentatively: usize,
    /// The tentative tracks at the scored instants, within the bearing window, when
    /// [`EvalParams::record_tentative`] is set (otherwise empty).
    pub tentative: Vec<TentativeSample>,
}

/// A tentative track at a scored instant (see [`EvalParams::record_tentative`]): what the
/// tracker knew of it then, and whether it was on an annotated person.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TentativeSample {
    /// Index of the scan in [`Sequence::scans`].
    pub scan: usize,
    /// The scan's bag time, seconds.
    pub time: f64,
    /// The track's id.
    pub id: u64,
    /// Position in the scan's laser frame, metres.
    pub position: Point2<f64>,
    /// Whether an annotated person stood within the match threshold of it.
    pub person: bool,
    /// Updates in which a detection supported the track.
    pub hits: usize,
    /// Seconds since the track was born.
    pub age: f64,
    /// The farthest the track got from where it was born, metres (in the tracking frame).
    pub travel: f64,
    /// Estimated speed, m/s.
    pub speed: f64,
    /// Standard deviation of the position, metres: the root of half the covariance's trace.
    pub position_std: f64,
}

/// Runs `detector` and `tracker` over `sequence` and scores the tracks against its ground
/// truth with CLEAR MOT (see the [module docs](self)).
///
/// The tracker should be fresh: its time must not be past the first scan's stamp.
///
/// # Errors
/// - [`crate::TrackingError::InvalidParameter`] for bad parameters.
/// - [`crate::TrackingError::NoTransformChain`] / [`crate::TrackingError::ConflictingTransform`]
///   when static transforms are given but do not connect the scans' frame to
///   `base_frame`.
/// - [`crate::TrackingError::NotSorted`] when the scans' bag times are not in order.
/// - [`crate::TrackingError::NothingScored`] when no annotated person is scored (no scans,
///   no ground truth, none of it on a scan read or within the bearing window): a score of
///   tracks against nothing would read as perfect.
/// - The detector's and the tracker's errors.
pub fn evaluate_sequence(
    sequence: &Sequence,
    detector: &dyn Detector,
    tracker: &mut dyn Tracker,
    params: &EvalParams,
) -> Result<EvalReport> {
    let params = params.clone().check()?;
    let scans = &sequence.scans;
    let bag_times: Vec<f64> = scans.iter().map(|s| s.bag_time).collect();
    let truth = truth_frames_for_scans(&bag_times, &sequence.ground_truth)?;
    let history = if sequence.odometry.is_empty() {
        None
    } else {
        Some(odometry_history(
            &sequence.odometry,
            OdomClock::HeaderStamp,
        )?)
    };
    // The laser's pose on the robot, per frame name (scans may come from several lasers).
    let mut mounts: Vec<(String, Isometry2<f64>)> = Vec::new();
    let mut mounts_assumed: Vec<String> = Vec::new();
    let mut hypotheses: Vec<Frame> = Vec::with_capacity(scans.len());
    let (mut detections, mut skipped_scans) = (0, 0);
    let mut last_stamp = f64::NEG_INFINITY;
    let mut online = OnlineTracker::new(detector, &mut *tracker, params.static_map)?;
    // (stamp, index into `hypotheses`, sensor pose) of every scan the tracker took.
    let mut taken: Vec<(f64, usize, Isometry2<f64>)> = Vec::with_capacity(scans.len());
    // The tentative tracks after each scan, in its laser frame (empty for skipped scans).
    let mut tentative: Vec<Vec<TentativeSample>> = Vec::with_capacity(scans.len());
    for s in scans {
        let t = s.scan.stamp;
        let sensor = match &history {
            None => Some(Isometry2::identity()),
            Some(h) => {
                let known = mounts.iter().find(|(f, _)| *f == s.frame).map(|m| m.1);
                let m = match known {
                    Some(m) => m,
                    None if sequence.static_transforms.is_empty() => {
                        mounts_assumed.push(s.frame.clone());
                        mounts.push((s.frame.clone(), Isometry2::identity()));
                        Isometry2::identity()
                    }
                    None => {
                        let m = static_chain(
                            &sequence.static_transforms,
                            &s.frame,
                            &params.base_frame,
                        )?;
                        mounts.push((s.frame.clone(), m));
                        m
                    }
                };
                h.sensor_pose_at(t, &m).ok()
            }
        };
        let Some(sensor) = sensor.filter(|_| t >= last_stamp) else {
            skipped_scans += 1;
            hypotheses.push(Frame::new(s.bag_time, Vec::new()));
            tentative.push(Vec::new());
            continue;
        };
        last_stamp = t;
        taken.push((t, hypotheses.len(), sensor));
        let step = online.step(&s.scan, &sensor)?;
        detections += step.detections;
        // Scored on the trajectories, the frames are filled once the run is over.
        let objects = match params.scoring {
            Scoring::Online => step
                .lists
                .reported()
                .iter()
                .map(|tr| (tr.id, sensor.inverse_transform_point(&tr.position)))
                .collect(),
            Scoring::Trajectories => Vec::new(),
        };
        tentative.push(
            step.lists
                .tentative()
                .iter()
                .map(|tr| sample(hypotheses.len(), s.bag_time, tr, &sensor))
                .collect(),
        );
        hypotheses.push(Frame::new(s.bag_time, objects));
    }

    if params.scoring == Scoring::Trajectories {
        score_trajectories(&online.lists().trajectories(), &taken, &mut hypotheses);
    }

    let scored = score_truth_frames(&truth, &hypotheses, &params, sequence.ground_truth.len())?;
    let mut followed_tentatively = 0;
    let mut recorded = Vec::new();
    let reach = params.clear_mot.match_threshold;
    let near = |a: &Point2<f64>, b: &Point2<f64>| (a - b).norm() < reach;
    for (k, t, h) in protocol_frames(&truth.frames, &hypotheses, &params) {
        let tentative = tentative[k]
            .iter()
            .filter(|u| in_window(params.bearing_window, &u.position));
        followed_tentatively += t
            .objects
            .iter()
            .filter(|o| {
                !h.objects.iter().any(|q| near(&q.1, &o.1))
                    && tentative.clone().any(|u| near(&u.position, &o.1))
            })
            .count();
        if params.record_tentative {
            recorded.extend(tentative.map(|u| TentativeSample {
                person: t.objects.iter().any(|o| near(&u.position, &o.1)),
                ..*u
            }));
        }
    }
    Ok(EvalReport {
        scores: scored.scores,
        scans: scans.len(),
        skipped_scans,
        frames: scored.frames,
        unassigned_truth: scored.unassigned_truth,
        detections,
        resets: tracker.resets(),
        tracking_frame: if history.is_some() {
            TrackingFrame::Odometry
        } else {
            TrackingFrame::Sensor
        },
        mounts_assumed,
        followed_tentatively,
        tentative: recorded,
    })
}

/// The CLEAR MOT scores of tracks made elsewhere, by [`evaluate_sequence`]'s own scoring
/// step: a live session's reports, say, scored exactly as the offline evaluation scores its
/// own.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Scored {
    /// The CLEAR MOT scores.
    pub scores: ClearMot,
    /// Instants scored.
    pub frames: usize,
    /// Ground-truth records scored nowhere (see [`EvalReport::unassigned_truth`]).
    pub unassigned_truth: usize,
}

/// Scores `hypotheses` (one frame per scan, in scan order: the tracks reported after that
/// scan, positions in its laser frame, an empty frame for a scan that was skipped) against
/// `ground_truth` with the protocol of `params`; `bag_times` are the scans' bag times. This
/// is the scoring [`evaluate_sequence`] does after its tracking loop.
///
/// # Errors
/// [`crate::TrackingError::NotSorted`] when `bag_times` are not in order;
/// [`crate::TrackingError::NothingScored`] when no annotated person is scored; bad
/// parameters.
pub fn score_hypotheses(
    bag_times: &[f64],
    ground_truth: &[PersonPosition],
    hypotheses: &[Frame],
    params: &EvalParams,
) -> Result<Scored> {
    let params = params.clone().check()?;
    let truth = truth_frames_for_scans(bag_times, ground_truth)?;
    score_truth_frames(&truth, hypotheses, &params, ground_truth.len())
}

/// [`score_hypotheses`] on ground truth already grouped by scan.
fn score_truth_frames(
    truth: &crate::eval::mot::ScanTruth,
    hypotheses: &[Frame],
    params: &EvalParams,
    annotations: usize,
) -> Result<Scored> {
    let (scored_truth, scored_hyps): (Vec<Frame>, Vec<Frame>) =
        protocol_frames(&truth.frames, hypotheses, params)
            .map(|(_, t, h)| (t, h))
            .unzip();
    let scores = clear_mot(&scored_truth, &scored_hyps, &params.clear_mot)?;
    if scores.ground_truth == 0 {
        return Err(crate::TrackingError::NothingScored {
            scans: hypotheses.len(),
            frames: scored_truth.len(),
            annotations,
            unassigned: truth.unassigned,
        });
    }
    Ok(Scored {
        scores,
        frames: scored_truth.len(),
        unassigned_truth: truth.unassigned,
    })
}

/// Whether `p` (laser frame) lies within the bearing window (`None`: everywhere).
fn in_window(window: Option<(f64, f64)>, p: &Point2<f64>) -> bool {
    window.is_none_or(|(lo, hi)| (lo..=hi).contains(&p.y.atan2(p.x)))
}

/// The frames a protocol scores, as `(index, truth, hypotheses)`: `truth[k]` and
/// `hypotheses[k]` belong to scan `k` (positions in that scan's laser frame); frames with
/// nobody annotated are left out under [`EvalFrames::Annotated`], and objects outside the
/// bearing window are dropped. Frames beyond the shorter slice are ignored.
///
/// This is the scoring step of [`evaluate_sequence`], for tracks made elsewhere (a day of
/// the facade's daily loop, say): give the result to [`clear_mot`].
///
/// # Example
/// ```
/// use haunts_tracking::eval::mot::{Frame, clear_mot};
/// use haunts_tracking::eval::sequence::{EvalFrames, EvalParams, protocol_frames};
/// use nalgebra::Point2;
///
/// let truth = vec![
///     Frame::new(0.0, vec![(1, Point2::new(2.0, -1.0))]),
///     Frame::new(0.1, vec![]),
/// ];
/// // A track at both scans: a false positive at the second under the every-scan rule.
/// let tracks = vec![
///     Frame::new(0.0, vec![(7, Point2::new(2.1, -1.0))]),
///     Frame::new(0.1, vec![(7, Point2::new(2.1, -1.0))]),
/// ];
/// let params = EvalParams::leg_tracker_benchmarks().with_frames(EvalFrames::EveryScan);
/// let (t, h): (Vec<_>, Vec<_>) =
///     protocol_frames(&truth, &tracks, &params).map(|(_, t, h)| (t, h)).unzip();
/// let mot = clear_mot(&t, &h, &params.clear_mot)?;
/// assert_eq!((mot.matches, mot.false_positives), (1, 1));
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
pub fn protocol_frames<'a>(
    truth: &'a [Frame],
    hypotheses: &'a [Frame],
    params: &'a EvalParams,
) -> impl Iterator<Item = (usize, Frame, Frame)> + 'a {
    let keep = move |f: &Frame| {
        Frame::new(
            f.time,
            f.objects
                .iter()
                .copied()
                .filter(|o| in_window(params.bearing_window, &o.1))
                .collect(),
        )
    };
    truth
        .iter()
        .zip(hypotheses)
        .enumerate()
        .filter(move |(_, (t, _))| params.frames == EvalFrames::EveryScan || !t.objects.is_empty())
        .map(move |(k, (t, h))| (k, keep(t), keep(h)))
}

/// `track`, tentative after scan `scan` (bag time `time`) taken from `sensor`, in that
/// scan's laser frame; `person` is left false.
fn sample(scan: usize, time: f64, track: &Track, sensor: &Isometry2<f64>) -> TentativeSample {
    let born = track.history.first().map_or(track.position, |h| h.1);
    TentativeSample {
        scan,
        time,
        id: track.id,
        position: sensor.inverse_transform_point(&track.position),
        person: false,
        hits: track.hits,
        age: track.age,
        travel: track
            .history
            .iter()
            .map(|h| (h.1 - born).norm())
            .fold(0.0, f64::max),
        speed: track.velocity.norm(),
        position_std: (0.5 * track.covariance.trace()).max(0.0).sqrt(),
    }
}

/// Fills the (empty) hypotheses with the samples of `trajectories`: each sample goes to the
/// scan whose stamp it was recorded at (`taken` is in stamp order; of scans with equal
/// stamps, the first, which takes one sample per track), in that scan's laser frame.
fn score_trajectories(
    trajectories: &[Trajectory],
    taken: &[(f64, usize, Isometry2<f64>)],
    hypotheses: &mut [Frame],
) {
    for trajectory in trajectories {
        for &(t, p) in &trajectory.samples {
            let k = taken.partition_point(|s| s.0 < t);
            if let Some(&(stamp, i, sensor)) = taken.get(k) {
                let frame = &hypotheses[i];
                if stamp == t && !frame.objects.iter().any(|o| o.0 == trajectory.id) {
                    hypotheses[i]
                        .objects
                        .push((trajectory.id, sensor.inverse_transform_point(&p)));
                }
            }
        }
    }
}
