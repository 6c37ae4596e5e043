//! A recording driven through a [`LiveSession`] message by message, in log-time order, as a
//! robot would deliver it: what `haunts replay` runs, and how a live session is checked
//! against the offline evaluation of the same file.
//!
//! The bag is streamed ([`Bag::messages`]: one chunk at a time), never read whole. Its topics
//! are those [`Bag::recording`] would read (named, or chosen automatically), plus the
//! annotated people (`leg_tracker/msg/Person`) when there are some: they are kept, with the
//! scans' arrival times, to score the session's people with the offline evaluation's own
//! scoring ([`score_hypotheses`]).

use std::time::Instant;

use haunts_bag::msg::{self, Person as PersonMsg};
use haunts_bag::{Bag, BagError, RecordingOptions, RecordingTopics};
use haunts_tracking::PersonPosition;
use haunts_tracking::detect::Detector;
use haunts_tracking::eval::mot::Frame;
use haunts_tracking::eval::sequence::{EvalFrames, EvalParams, Scored, score_hypotheses};
use haunts_tracking::track::Tracker;
use nalgebra::Point2;

use super::{LiveParams, LiveSession, ScanPeople, messages};
use crate::pipeline::{PipelineError, Result};

/// A bag opened for replay: the topics it is read from and what was chosen.
#[derive(Debug, Clone)]
pub struct Replay {
    bag: Bag,
    topics: RecordingTopics,
    ground_truth: Option<String>,
    base_frame: String,
    fixed_frame: String,
    notes: Vec<String>,
}

/// What a replay read and the session made of it.
#[derive(Debug, Clone, Default)]
pub struct Replayed {
    /// The arrival (log) time of every scan pushed, in order.
    pub scan_times: Vec<f64>,
    /// After each scan pushed, the people the session reported, in that scan's own frame
    /// (empty for a scan dropped): the hypotheses of the offline evaluation's scoring.
    pub hypotheses: Vec<Frame>,
    /// The annotated people of the ground-truth topic, by log time.
    pub ground_truth: Vec<PersonPosition>,
    /// Seconds each tracked scan took: the push of the message that let it be tracked.
    pub latency: Vec<f64>,
    /// Messages that did not decode or convert (each skipped).
    pub undecodable: usize,
    /// Messages read.
    pub messages: usize,
    /// The log time from the first message to the last, seconds.
    pub span: f64,
    /// The session's count of scans when the replay began (its scans' indices start there).
    first_index: usize,
}

impl Replayed {
    /// The session's people scored against the ground truth by the offline evaluation's
    /// protocol (`leg_tracker_benchmarks`, as `eval_tracking` scores): at every scan and at
    /// the annotated scans. `None` without ground truth.
    ///
    /// # Errors
    /// [`haunts_tracking::TrackingError::NothingScored`] when nobody annotated is scored.
    pub fn scores(&self, params: &EvalParams) -> Result<Option<(Scored, Scored)>> {
        if self.ground_truth.is_empty() {
            return Ok(None);
        }
        let score = |frames| {
            score_hypotheses(
                &self.scan_times,
                &self.ground_truth,
                &self.hypotheses,
                &params.clone().with_frames(frames),
            )
        };
        Ok(Some((
            score(EvalFrames::EveryScan)?,
            score(EvalFrames::Annotated)?,
        )))
    }
}

impl Replay {
    /// `bag` to replay from the topics `options` names or chooses, and the ground truth from
    /// `ground_truth` (default: the only `leg_tracker/msg/Person` topic, if any).
    ///
    /// # Errors
    /// The choice of topics ([`Bag::recording_topics`]); a named ground-truth topic the bag
    /// does not have; several ground-truth topics and none named.
    pub fn new(bag: Bag, options: &RecordingOptions, ground_truth: Option<&str>) -> Result<Self> {
        let (topics, mut notes) = bag.recording_topics(options)?;
        let ground_truth = ground_truth_topic(&bag, ground_truth)?;
        // The frames of the first odometry message: the fixed frame, and the base frame
        // unless named (as a recording's), else `odom` and `base_link`.
        let first = match &topics.odom {
            Some(odom) => bag
                .read::<msg::Odometry>(odom)?
                .find_map(|m| m.ok())
                .map(|(_, m)| (m.header.frame_id, m.child_frame_id)),
            None => None,
        };
        let named = |f: Option<String>, default: &str| {
            f.filter(|f| !f.is_empty())
                .unwrap_or_else(|| default.to_owned())
        };
        let (fixed, child) = first.unzip();
        let fixed_frame = named(fixed, "odom");
        let base_frame = named(options.base_frame.clone().or(child), "base_link");
        notes.push(format!(
            "fixed frame {fixed_frame}, base frame {base_frame}"
        ));
        Ok(Self {
            bag,
            topics,
            ground_truth,
            base_frame,
            fixed_frame,
            notes,
        })
    }

    /// The session's parameters this recording needs (the rest as `params`): its base frame,
    /// tracking in the odometry frame when it has odometry, sensors at the base's origin when
    /// it has no transform topic (as the offline evaluation assumes then).
    pub fn params(&self, params: LiveParams) -> LiveParams {
        params
            .with_base_frame(self.base_frame.clone())
            .with_fixed_frame(self.fixed_frame.clone())
            .with_odometry(self.topics.odom.is_some())
            .with_mount_at_base(self.topics.tf.is_empty())
    }

    /// The frame the people are tracked in: the first odometry message's frame (`odom` when
    /// there is none: the people are then in each scan's own frame, [`ScanPeople::frame`]).
    pub fn fixed_frame(&self) -> &str {
        &self.fixed_frame
    }

    /// The topics read.
    pub fn topics(&self) -> &RecordingTopics {
        &self.topics
    }

    /// The ground-truth topic, when there is one.
    pub fn ground_truth_topic(&self) -> Option<&str> {
        self.ground_truth.as_deref()
    }

    /// What was chosen.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The bag.
    pub fn bag(&self) -> &Bag {
        &self.bag
    }

    /// Streams the bag through `session`, calling `on_scan` with each tracked scan (to
    /// publish it), and ends the stream ([`LiveSession::finish`]).
    ///
    /// # Errors
    /// The file's errors that end a read ([`Bag::messages`]), and `on_scan`'s.
    pub fn run<D: Detector, T: Tracker>(
        &self,
        session: &mut LiveSession<D, T>,
        on_scan: impl FnMut(&ScanPeople) -> Result<()>,
    ) -> Result<Replayed> {
        self.run_looped(session, 1, on_scan)
    }

    /// [`Replay::run`] with the recording played `loops` times in a row, each pass's times
    /// (arrival times, scan and odometry stamps, annotations) after the one before by the
    /// recording's span and a second: to see that a long session's memory stays flat.
    ///
    /// # Errors
    /// As [`Replay::run`].
    pub fn run_looped<D: Detector, T: Tracker>(
        &self,
        session: &mut LiveSession<D, T>,
        loops: usize,
        mut on_scan: impl FnMut(&ScanPeople) -> Result<()>,
    ) -> Result<Replayed> {
        let mut out = Replayed {
            first_index: session.scans(),
            ..Replayed::default()
        };
        let (mut first, mut last) = (f64::INFINITY, f64::NEG_INFINITY);
        for pass in 0..loops {
            let offset = if pass == 0 {
                0.0
            } else {
                pass as f64 * (last - first + 1.0)
            };
            let (f, l) = self.pass(session, offset, &mut out, &mut on_scan)?;
            if pass == 0 {
                (first, last) = (f, l);
            }
        }
        let start = Instant::now();
        let tracked = session.finish();
        let seconds = start.elapsed().as_secs_f64();
        for scan in &tracked {
            out.record(scan, seconds);
            on_scan(scan)?;
        }
        out.span = if first <= last {
            (last - first + 1.0) * loops as f64 - 1.0
        } else {
            0.0
        };
        Ok(out)
    }

    /// One pass over the bag, every time moved by `offset` seconds; the first and last
    /// arrival times (unmoved).
    fn pass<D: Detector, T: Tracker>(
        &self,
        session: &mut LiveSession<D, T>,
        offset: f64,
        out: &mut Replayed,
        on_scan: &mut impl FnMut(&ScanPeople) -> Result<()>,
    ) -> Result<(f64, f64)> {
        let mut topics: Vec<&str> = vec![self.topics.scan.as_str()];
        topics.extend(self.topics.odom.as_deref());
        topics.extend(self.topics.tf.iter().map(String::as_str));
        topics.extend(self.ground_truth.as_deref());
        let (mut first, mut last) = (f64::INFINITY, f64::NEG_INFINITY);
        for message in self.bag.messages(&topics)? {
            let m = match message {
                Ok(m) => m,
                // A broken chunk is one item; the next chunks are still read.
                Err(_) => {
                    out.undecodable += 1;
                    continue;
                }
            };
            out.messages += 1;
            (first, last) = (first.min(m.log_seconds()), last.max(m.log_seconds()));
            let received = m.log_seconds() + offset;
            let start = Instant::now();
            let tracked = if *m.topic == *self.topics.scan {
                match self
                    .bag
                    .decode::<msg::LaserScan>(&m)
                    .map_err(|e| e.to_string())
                    .and_then(|s| messages::scan(&s))
                {
                    Ok((mut scan, frame)) => {
                        scan.stamp += offset;
                        out.scan_times.push(received);
                        out.hypotheses.push(Frame::new(received, Vec::new()));
                        session.push_scan(received, &frame, scan)
                    }
                    Err(_) => {
                        out.undecodable += 1;
                        continue;
                    }
                }
            } else if self.topics.odom.as_deref() == Some(&*m.topic) {
                let Ok(o) = self.bag.decode::<msg::Odometry>(&m) else {
                    out.undecodable += 1;
                    continue;
                };
                // A pose without a heading is dropped by the session as bad odometry.
                let (stamp, pose) = messages::odometry(&o);
                session.push_odom(received, stamp + offset, &pose)
            } else if self.ground_truth.as_deref() == Some(&*m.topic) {
                match self.bag.decode::<PersonMsg>(&m) {
                    Ok(person) => {
                        let line = out.ground_truth.len() + 1;
                        out.ground_truth
                            .push(person_position(received, &person, line));
                    }
                    Err(_) => out.undecodable += 1,
                }
                continue;
            } else {
                let Ok(tf) = self.bag.decode::<msg::TfMessage>(&m) else {
                    out.undecodable += 1;
                    continue;
                };
                let is_static = m.topic.ends_with("tf_static");
                let mut tracked = Vec::new();
                for t in messages::transforms(&tf) {
                    let stamp = t.stamp + if is_static { 0.0 } else { offset };
                    tracked.extend(session.push_tf(
                        received,
                        (&t.parent, &t.child),
                        stamp,
                        &t.pose,
                        is_static,
                    ));
                }
                tracked
            };
            let seconds = start.elapsed().as_secs_f64();
            for scan in &tracked {
                out.record(scan, seconds);
                on_scan(scan)?;
            }
        }
        Ok((first, last))
    }
}

/// The ground-truth topic of `bag`: `named` (checked), else the only
/// `leg_tracker/msg/Person` topic, if any.
///
/// # Errors
/// [`BagError::NoSuchTopic`] for a named topic the bag does not have;
/// [`BagError::TopicChoice`] for several ground-truth topics and none named.
pub fn ground_truth_topic(bag: &Bag, named: Option<&str>) -> Result<Option<String>> {
    Ok(match named {
        Some(t) => Some(bag.topic(t)?.name.clone()),
        None => match bag.topics_of::<PersonMsg>().as_slice() {
            [] => None,
            [only] => Some(only.name.clone()),
            several => {
                let names: Vec<&str> = several.iter().map(|t| t.name.as_str()).collect();
                return Err(PipelineError::Bag(BagError::TopicChoice {
                    path: bag.path().to_path_buf(),
                    what: format!(
                        "{} ground-truth topics: {}; name one (--ground-truth-topic)",
                        names.len(),
                        names.join(", ")
                    ),
                }));
            }
        },
    })
}

/// An annotated person (`leg_tracker/msg/Person`) logged at `log_seconds`, the `line`-th of
/// its topic (from 1), as the offline evaluation reads it.
pub fn person_position(log_seconds: f64, person: &PersonMsg, line: usize) -> PersonPosition {
    PersonPosition {
        bag_time: log_seconds,
        id: u64::from(person.id),
        position: Point2::new(person.pose.position.x, person.pose.position.y),
        line,
    }
}

/// The annotated people of `topic` (`leg_tracker/msg/Person`), by log time.
///
/// # Errors
/// The topic's errors ([`Bag::read`]); a message that does not decode.
pub fn ground_truth(bag: &Bag, topic: &str) -> Result<Vec<PersonPosition>> {
    let mut people = Vec::new();
    for m in bag.read::<PersonMsg>(topic)? {
        let (log_seconds, person) = m?;
        people.push(person_position(log_seconds, &person, people.len() + 1));
    }
    Ok(people)
}

impl Replayed {
    /// Keeps a tracked scan's people, in its own frame, and its latency.
    fn record(&mut self, scan: &ScanPeople, seconds: f64) {
        self.latency.push(seconds);
        let k = scan.index.checked_sub(self.first_index);
        if let Some(frame) = k.and_then(|k| self.hypotheses.get_mut(k)) {
            frame.objects = scan
                .people
                .iter()
                .map(|p| (p.id, scan.sensor.inverse_transform_point(&p.position)))
                .collect();
        }
    }
}
