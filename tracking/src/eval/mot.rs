//! CLEAR MOT metrics (Bernardin & Stiefelhagen 2008): MOTA, MOTP, misses, false positives and
//! identity switches of tracks against ground truth, frame by frame.
//!
//! Per frame, correspondences of the previous frames are kept while they stay within the
//! match threshold, the remaining objects and hypotheses are paired by an optimal assignment
//! (Kuhn–Munkres, gated), and a pairing that contradicts an earlier one is
//! an identity switch. Two conventions are implemented ([`Convention`]):
//!
//! - [`Convention::MotMetrics`] (the default) is the `motmetrics` Python package
//!   (`MOTAccumulator.update`, v1.4.0), which follows the paper; the test
//!   `tests/motmetrics_fixture.rs` checks every count, MOTA and MOTP against it.
//! - [`Convention::LegTrackerBenchmarks`] is `clear_mot.py` of
//!   `angusleigh/leg_tracker_benchmarks`, with which the `leg_tracker` papers' numbers were
//!   computed.
//!
//! They differ in three details:
//!
//! | | `MotMetrics` | `LegTrackerBenchmarks` |
//! |---|---|---|
//! | a pair matches when its distance is | `≤` threshold | `<` threshold |
//! | the assignment of the remaining pairs | gated: only pairs within the threshold are candidates (most matches, then least total distance) | ungated Munkres over all distances, then pairs beyond the threshold are dropped |
//! | an identity switch is | a truth object matched to another hypothesis than the last one it was matched to | that, **or** a hypothesis matched to another truth object than its last one, or a new hypothesis taking over a truth object still remembered with another |
//!
//! The memory of correspondences also differs: `motmetrics` remembers, per truth object, the
//! last hypothesis it was matched to, forever; `clear_mot.py` keeps a one-to-one table of
//! the latest pairs, dropping an old pair when either side is matched anew.
//!
//! Both count `MOTA = 1 − (misses + false positives + switches) / ground truth objects` and
//! `MOTP = Σ distances of matched pairs / matched pairs` (metres; switch pairs are matched
//! pairs).

use std::collections::{BTreeMap, HashMap, HashSet};

use nalgebra::Point2;

use crate::track::assign::min_cost_assignment;
use crate::{PersonPosition, Result, TrackingError};

/// The objects present at one instant: `(id, position in metres)`.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Frame {
    /// The frame's time, seconds (informational: frames are paired by index).
    pub time: f64,
    /// The objects, each id at most once.
    pub objects: Vec<(u64, Point2<f64>)>,
}

impl Frame {
    /// A frame at `time` with these objects.
    pub fn new(time: f64, objects: Vec<(u64, Point2<f64>)>) -> Self {
        Self { time, objects }
    }
}

/// Which implementation's details [`clear_mot`] follows (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Convention {
    /// The `motmetrics` Python package (and the paper): gated assignment, `≤` threshold,
    /// switches counted per truth object.
    #[default]
    MotMetrics,
    /// `clear_mot.py` of `leg_tracker_benchmarks`: ungated assignment, `<` threshold,
    /// switches counted on either side.
    LegTrackerBenchmarks,
}

/// Parameters of [`clear_mot`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ClearMotParams {
    /// The largest distance of a truth object and a hypothesis that can match, metres.
    /// Default 0.75 m (`clear_mot.py`'s `max_match_threshold`).
    pub match_threshold: f64,
    /// Whose conventions to follow. Default [`Convention::MotMetrics`].
    pub convention: Convention,
}

impl Default for ClearMotParams {
    fn default() -> Self {
        Self {
            match_threshold: 0.75,
            convention: Convention::MotMetrics,
        }
    }
}

impl ClearMotParams {
    /// Sets the match threshold, metres.
    pub fn with_match_threshold(mut self, metres: f64) -> Self {
        self.match_threshold = metres;
        self
    }

    /// Sets the convention.
    pub fn with_convention(mut self, convention: Convention) -> Self {
        self.convention = convention;
        self
    }

    /// The parameters, after checking that the threshold is finite and > 0.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] naming `match_threshold`.
    pub fn check(self) -> Result<Self> {
        haunts_core::positive("match_threshold", self.match_threshold)?;
        Ok(self)
    }
}

/// CLEAR MOT scores of a sequence.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ClearMot {
    /// Multiple object tracking accuracy, `1 − (misses + false_positives + id_switches) /
    /// ground_truth`; at most 1, unbounded below. With no ground truth objects the
    /// denominator is taken as 1 (so 1.0 without false positives).
    pub mota: f64,
    /// Multiple object tracking precision: mean distance of the matched pairs, metres; 0.0
    /// when nothing matched (`matches == 0`).
    pub motp: f64,
    /// Matched pairs that contradict an earlier correspondence (included in `matches`).
    pub id_switches: usize,
    /// Hypotheses matched to no truth object.
    pub false_positives: usize,
    /// Truth objects matched to no hypothesis.
    pub misses: usize,
    /// Matched pairs, switches included (`motmetrics`' `num_detections`); `matches + misses
    /// == ground_truth`.
    pub matches: usize,
    /// Truth objects over all frames.
    pub ground_truth: usize,
    /// Hypotheses over all frames; `matches + false_positives == hypotheses`.
    pub hypotheses: usize,
    /// Frames evaluated.
    pub frames: usize,
}

impl ClearMot {
    /// The scores of several sequences pooled as one: counts summed, MOTA from the sums
    /// (not a mean of ratios, which would weigh a day with few people as much as a busy
    /// one), MOTP the mean distance over all matches. An empty iterator gives the scores of
    /// no frames (MOTA 1, MOTP 0).
    ///
    /// # Example
    /// ```
    /// use haunts_tracking::eval::mot::ClearMot;
    /// let day = |misses, matches, motp| ClearMot {
    ///     mota: 1.0 - misses as f64 / (misses + matches) as f64,
    ///     motp,
    ///     id_switches: 0,
    ///     false_positives: 0,
    ///     misses,
    ///     matches,
    ///     ground_truth: misses + matches,
    ///     hypotheses: matches,
    ///     frames: 10,
    /// };
    /// let pooled = ClearMot::pooled([day(1, 1, 0.1), day(0, 8, 0.2)]);
    /// assert_eq!((pooled.ground_truth, pooled.frames), (10, 20));
    /// approx::assert_relative_eq!(pooled.mota, 0.9); // the mean of ratios would say 0.75
    /// approx::assert_relative_eq!(pooled.motp, (0.1 + 8.0 * 0.2) / 9.0, epsilon = 1e-12);
    /// ```
    pub fn pooled(scores: impl IntoIterator<Item = ClearMot>) -> ClearMot {
        let mut sum = ClearMot::counting(0);
        let mut distance = 0.0;
        for s in scores {
            sum.id_switches += s.id_switches;
            sum.false_positives += s.false_positives;
            sum.misses += s.misses;
            sum.matches += s.matches;
            sum.ground_truth += s.ground_truth;
            sum.hypotheses += s.hypotheses;
            sum.frames += s.frames;
            distance += s.motp * s.matches as f64;
        }
        sum.with_ratios(distance)
    }

    /// Zero counts over `frames` frames (the ratios are set by [`ClearMot::with_ratios`]).
    fn counting(frames: usize) -> Self {
        ClearMot {
            mota: 1.0,
            motp: 0.0,
            id_switches: 0,
            false_positives: 0,
            misses: 0,
            matches: 0,
            ground_truth: 0,
            hypotheses: 0,
            frames,
        }
    }

    /// The counts with MOTA from them and MOTP from the matches' summed distance.
    fn with_ratios(mut self, distance_sum: f64) -> Self {
        let errors = self.misses + self.false_positives + self.id_switches;
        self.mota = 1.0 - errors as f64 / self.ground_truth.max(1) as f64;
        self.motp = if self.matches > 0 {
            distance_sum / self.matches as f64
        } else {
            0.0
        };
        self
    }
}

/// Checks a frame's positions and ids.
fn check_frame(frame: &Frame, side: &'static str, index: usize) -> Result<()> {
    let mut ids = HashSet::with_capacity(frame.objects.len());
    for &(id, p) in &frame.objects {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return Err(TrackingError::InvalidObject {
                side,
                frame: index,
                id,
                rule: "position is not finite",
            });
        }
        if !ids.insert(id) {
            return Err(TrackingError::InvalidObject {
                side,
                frame: index,
                id,
                rule: "id appears more than once in the frame",
            });
        }
    }
    Ok(())
}

/// The correspondences remembered between frames.
enum Memory {
    /// Per truth id, the hypothesis id it was last matched to (motmetrics' `m`).
    PerTruth(HashMap<u64, u64>),
    /// The latest pairs, hypothesis id → truth id, one-to-one (`prev_matched_ids`).
    OneToOne(HashMap<u64, u64>),
}

/// CLEAR MOT of `hypotheses` against `truth`: `hypotheses[i]` holds the tracks reported for
/// the instant of `truth[i]` (both in the same coordinate frame; a frame with no truth
/// objects still counts its hypotheses as false positives).
///
/// # Errors
/// - [`TrackingError::InvalidParameter`] for a bad threshold.
/// - [`TrackingError::LengthMismatch`] when the two slices differ in length.
/// - [`TrackingError::InvalidObject`] for a non-finite position or an id repeated within a
///   frame.
///
/// # Complexity
/// `O(Σ n_i · m_i · min(n_i, m_i))` for `n_i` truth objects and `m_i` hypotheses in frame
/// `i` (less with gating).
///
/// # Example
/// ```
/// use haunts_tracking::eval::mot::{ClearMotParams, Frame, clear_mot};
/// use nalgebra::Point2;
///
/// let truth = vec![
///     Frame::new(0.0, vec![(1, Point2::new(0.0, 0.0)), (2, Point2::new(5.0, 0.0))]),
///     Frame::new(0.1, vec![(1, Point2::new(0.1, 0.0)), (2, Point2::new(5.0, 0.1))]),
/// ];
/// let tracks = vec![
///     // Person 2 missed, a false positive far away.
///     Frame::new(0.0, vec![(7, Point2::new(0.2, 0.0)), (8, Point2::new(9.0, 9.0))]),
///     // Person 1 now followed by track 9: an identity switch; person 2 missed again.
///     Frame::new(0.1, vec![(9, Point2::new(0.1, 0.4))]),
/// ];
/// let scores = clear_mot(&truth, &tracks, &ClearMotParams::default())?;
/// assert_eq!((scores.matches, scores.id_switches), (2, 1));
/// assert_eq!((scores.misses, scores.false_positives, scores.ground_truth), (2, 1, 4));
/// approx::assert_relative_eq!(scores.mota, 1.0 - (2.0 + 1.0 + 1.0) / 4.0);
/// approx::assert_relative_eq!(scores.motp, (0.2 + 0.4) / 2.0, epsilon = 1e-12);
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
pub fn clear_mot(
    truth: &[Frame],
    hypotheses: &[Frame],
    params: &ClearMotParams,
) -> Result<ClearMot> {
    let params = params.check()?;
    if truth.len() != hypotheses.len() {
        return Err(TrackingError::LengthMismatch {
            first: "truth",
            first_len: truth.len(),
            second: "hypotheses",
            second_len: hypotheses.len(),
        });
    }
    for (i, (t, h)) in truth.iter().zip(hypotheses).enumerate() {
        check_frame(t, "truth", i)?;
        check_frame(h, "hypotheses", i)?;
    }

    let threshold = params.match_threshold;
    let (inclusive, mut memory) = match params.convention {
        Convention::MotMetrics => (true, Memory::PerTruth(HashMap::new())),
        Convention::LegTrackerBenchmarks => (false, Memory::OneToOne(HashMap::new())),
    };
    let within = |d: f64| {
        if inclusive {
            d <= threshold
        } else {
            d < threshold
        }
    };

    let mut scores = ClearMot::counting(truth.len());
    let mut distance_sum = 0.0;

    for (gt, hyp) in truth.iter().zip(hypotheses) {
        let (n, m) = (gt.objects.len(), hyp.objects.len());
        let dist = |i: usize, j: usize| (gt.objects[i].1 - hyp.objects[j].1).norm();
        let mut gt_taken = vec![false; n];
        let mut hyp_taken = vec![false; m];
        // (truth index, hypothesis index) of this frame's matches.
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        // The first `kept` pairs continue remembered correspondences (step 1).
        let mut kept = 0;

        if n > 0 && m > 0 {
            // 1. Keep the remembered correspondences that are still within the threshold.
            match &memory {
                Memory::PerTruth(last) => {
                    for (i, (o, _)) in gt.objects.iter().enumerate() {
                        let Some(&h) = last.get(o) else {
                            continue;
                        };
                        let found = (0..m).find(|&j| !hyp_taken[j] && hyp.objects[j].0 == h);
                        if let Some(j) = found {
                            if within(dist(i, j)) {
                                gt_taken[i] = true;
                                hyp_taken[j] = true;
                                pairs.push((i, j));
                            }
                        }
                    }
                }
                Memory::OneToOne(prev) => {
                    let gt_index: HashMap<u64, usize> = gt
                        .objects
                        .iter()
                        .enumerate()
                        .map(|(i, o)| (o.0, i))
                        .collect();
                    for (j, &(h, _)) in hyp.objects.iter().enumerate() {
                        let Some(&i) = prev.get(&h).and_then(|g| gt_index.get(g)) else {
                            continue;
                        };
                        if within(dist(i, j)) {
                            gt_taken[i] = true;
                            hyp_taken[j] = true;
                            pairs.push((i, j));
                        }
                    }
                }
            }

            kept = pairs.len();

            // 2. Optimal assignment of the rest.
            let free_rows: Vec<usize> = (0..n).filter(|&i| !gt_taken[i]).collect();
            let free_cols: Vec<usize> = (0..m).filter(|&j| !hyp_taken[j]).collect();
            let mut cost = Vec::with_capacity(free_rows.len() * free_cols.len());
            for &i in &free_rows {
                for &j in &free_cols {
                    let d = dist(i, j);
                    // Gated (motmetrics): only candidates within the threshold.
                    cost.push(if inclusive && !within(d) { f64::NAN } else { d });
                }
            }
            let solved =
                min_cost_assignment(&cost, free_rows.len(), free_cols.len(), f64::INFINITY)?;
            for (a, b) in solved {
                let (i, j) = (free_rows[a], free_cols[b]);
                if within(dist(i, j)) {
                    pairs.push((i, j));
                }
            }
        }

        // 3. Classify and remember.
        match &mut memory {
            Memory::PerTruth(last) => {
                for (k, &(i, j)) in pairs.iter().enumerate() {
                    let (o, h) = (gt.objects[i].0, hyp.objects[j].0);
                    // Kept correspondences (step 1) are never switches.
                    if k >= kept && last.get(&o).is_some_and(|&before| before != h) {
                        scores.id_switches += 1;
                    }
                    last.insert(o, h);
                }
            }
            Memory::OneToOne(prev) => {
                let remembered: HashSet<u64> = prev.values().copied().collect();
                for &(i, j) in &pairs {
                    let (o, h) = (gt.objects[i].0, hyp.objects[j].0);
                    let switch = match prev.get(&h) {
                        Some(&before) => before != o,
                        None => remembered.contains(&o),
                    };
                    if switch {
                        scores.id_switches += 1;
                    }
                }
                let matched_h: HashSet<u64> =
                    pairs.iter().map(|&(_, j)| hyp.objects[j].0).collect();
                let matched_o: HashSet<u64> = pairs.iter().map(|&(i, _)| gt.objects[i].0).collect();
                prev.retain(|h, o| !matched_h.contains(h) && !matched_o.contains(o));
                for &(i, j) in &pairs {
                    prev.insert(hyp.objects[j].0, gt.objects[i].0);
                }
            }
        }

        distance_sum += pairs.iter().map(|&(i, j)| dist(i, j)).sum::<f64>();
        scores.matches += pairs.len();
        scores.misses += n - pairs.len();
        scores.false_positives += m - pairs.len();
        scores.ground_truth += n;
        scores.hypotheses += m;
    }

    Ok(scores.with_ratios(distance_sum))
}

/// Ground-truth records grouped into frames by equal time (`bag_time`), frames sorted by
/// time, records within a frame in input order. The `ground_truth_people.txt` of the
/// `leg_tracker` benchmarks holds one line per person per annotated scan, all lines of a scan
/// with the same time. Instants with nobody annotated get no frame: to evaluate every scan
/// (as `clear_mot.py` does) use [`truth_frames_for_scans`].
///
/// # Example
/// ```
/// use haunts_tracking::eval::mot::group_by_time;
/// use haunts_tracking::parse_ground_truth;
///
/// let text = "2.0 1 1.0 1.0\n1.0 1 0.0 0.0\n2.0 2 3.0 3.0\n";
/// let frames = group_by_time(&parse_ground_truth(text.as_bytes())?.records);
/// assert_eq!(frames.len(), 2);
/// assert_eq!((frames[0].time, frames[0].objects.len()), (1.0, 1));
/// assert_eq!(frames[1].objects.iter().map(|o| o.0).collect::<Vec<_>>(), vec![1, 2]);
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
pub fn group_by_time(records: &[PersonPosition]) -> Vec<Frame> {
    let mut by_time: BTreeMap<u64, Frame> = BTreeMap::new();
    for r in records {
        // Order-preserving key of an f64 (records hold finite times; −0 becomes +0).
        let time = r.bag_time + 0.0;
        let bits = time.to_bits();
        let key = if time.is_sign_negative() {
            !bits
        } else {
            bits | (1 << 63)
        };
        by_time
            .entry(key)
            .or_insert_with(|| Frame::new(time, Vec::new()))
            .objects
            .push((r.id, r.position));
    }
    by_time.into_values().collect()
}

/// Ground truth assigned to scans: one frame per scan.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ScanTruth {
    /// `frames[k]` holds the annotations of scan `k`; its time is that scan's bag time.
    pub frames: Vec<Frame>,
    /// Records that belong to no scan read: earlier than (or at) the first scan's bag time,
    /// or repeating an id already annotated in the scan they fall to (their own scan is
    /// missing, as when its line was skipped).
    pub unassigned: usize,
}

/// One ground-truth frame per scan, as `clear_mot.py` pairs them: a record belongs to the
/// **last scan whose bag time is strictly before the record's** (the annotation tool stamps
/// an annotation halfway between the annotated scan and the next one). Scans with nobody
/// annotated get an empty frame, so tracks reported there count as false positives.
///
/// A scan missing from `scan_bag_times` (its line skipped as malformed) moves its records to
/// the scan before, where a person annotated in both would appear twice: taken in order of
/// bag time, a record whose id is already in its frame is counted in `unassigned` and left
/// out, so one skipped scan costs its own annotations only (a person annotated in the
/// missing scan alone is scored at the scan before).
///
/// A record later than the last scan by more than the scans' median interval has no scan
/// (an annotation made after the recording ended, or stamped in other units): it is counted
/// in `unassigned`, not piled onto the last scan.
///
/// `scan_bag_times` are the scans' bag times (`StampedScan::bag_time`) in file order.
/// Positions stay in the annotation's frame (`left_laser` at that scan's time, see
/// [`crate::io::frames`]).
///
/// # Errors
/// [`TrackingError::NotSorted`] when a scan time is not finite or earlier than the one
/// before it.
///
/// # Complexity
/// `O(s + r log s)` for `s` scans and `r` records.
///
/// # Example
/// ```
/// use haunts_tracking::eval::mot::truth_frames_for_scans;
/// use haunts_tracking::parse_ground_truth;
///
/// let scans = [10.0, 10.13, 10.27];
/// let truth = parse_ground_truth("10.065 1 2.0 0.5\n10.2 1 1.9 0.5\n10.2 4 3.0 0.0\n9.0 1 0 0\n".as_bytes())?;
/// let assigned = truth_frames_for_scans(&scans, &truth.records)?;
/// let counts: Vec<usize> = assigned.frames.iter().map(|f| f.objects.len()).collect();
/// assert_eq!(counts, vec![1, 2, 0]);
/// assert_eq!(assigned.unassigned, 1);
/// // Without the scan at 10.13 (its line skipped), person 1's second record would repeat
/// // the id in the first scan: left out and counted.
/// let assigned = truth_frames_for_scans(&[10.0, 10.27], &truth.records)?;
/// let counts: Vec<usize> = assigned.frames.iter().map(|f| f.objects.len()).collect();
/// assert_eq!((counts, assigned.unassigned), (vec![2, 0], 2));
/// // A record long after the last scan (here 1000 s; times in milliseconds look like this)
/// // belongs to no scan.
/// let late = parse_ground_truth("10.3 1 2.0 0.5\n1010.0 2 1.0 1.0\n".as_bytes())?;
/// let assigned = truth_frames_for_scans(&scans, &late.records)?;
/// assert_eq!((assigned.frames[2].objects.len(), assigned.unassigned), (1, 1));
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
pub fn truth_frames_for_scans(
    scan_bag_times: &[f64],
    records: &[PersonPosition],
) -> Result<ScanTruth> {
    for (index, &t) in scan_bag_times.iter().enumerate() {
        let earlier = index > 0 && t < scan_bag_times[index - 1];
        if !t.is_finite() || earlier {
            return Err(TrackingError::NotSorted {
                what: "scan bag times",
                index,
            });
        }
    }
    let mut frames: Vec<Frame> = scan_bag_times
        .iter()
        .map(|&t| Frame::new(t, Vec::new()))
        .collect();
    let mut unassigned = 0;
    // The last scan takes records up to one median interval after it.
    let mut intervals: Vec<f64> = scan_bag_times.windows(2).map(|w| w[1] - w[0]).collect();
    let reach = haunts_core::median(&mut intervals).unwrap_or(f64::INFINITY);
    let end = scan_bag_times
        .last()
        .map_or(f64::NEG_INFINITY, |t| t + reach);
    let mut order: Vec<&PersonPosition> = records.iter().collect();
    order.sort_by(|a, b| a.bag_time.total_cmp(&b.bag_time));
    for r in order {
        // Scans strictly before the record; the last of them is the annotated one.
        let before = scan_bag_times.partition_point(|&t| t < r.bag_time);
        match before.checked_sub(1) {
            Some(k)
                if (k + 1 < frames.len() || r.bag_time <= end)
                    && frames[k].objects.iter().all(|o| o.0 != r.id) =>
            {
                frames[k].objects.push((r.id, r.position));
            }
            _ => unassigned += 1,
        }
    }
    Ok(ScanTruth { frames, unassigned })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use approx::assert_relative_eq;
    use proptest::prelude::*;

    use super::*;

    fn frame(objects: &[(u64, f64, f64)]) -> Frame {
        Frame::new(
            0.0,
            objects
                .iter()
                .map(|&(id, x, y)| (id, Point2::new(x, y)))
                .collect(),
        )
    }

    fn run(truth: &[Frame], hyp: &[Frame], convention: Convention) -> ClearMot {
        clear_mot(
            truth,
            hyp,
            &ClearMotParams::default().with_convention(convention),
        )
        .unwrap()
    }

    const BOTH: [Convention; 2] = [Convention::MotMetrics, Convention::LegTrackerBenchmarks];

    #[test]
    fn perfect_tracks_score_one_and_zero() {
        let truth = vec![frame(&[(1, 0.0, 0.0), (2, 3.0, 0.0)]); 5];
        let hyp = vec![frame(&[(10, 0.0, 0.0), (20, 3.0, 0.0)]); 5];
        for c in BOTH {
            let s = run(&truth, &hyp, c);
            assert_eq!(
                (s.matches, s.misses, s.false_positives, s.id_switches),
                (10, 0, 0, 0)
            );
            assert_eq!((s.ground_truth, s.hypotheses, s.frames), (10, 10, 5));
            assert_relative_eq!(s.mota, 1.0);
            assert_relative_eq!(s.motp, 0.0);
        }
    }

    #[test]
    fn empty_sequences_and_frames_are_defined() {
        let s = run(&[], &[], Convention::MotMetrics);
        assert_eq!((s.mota, s.motp, s.frames), (1.0, 0.0, 0));
        // Two false positives and no ground truth: MOTA = 1 − 2 / 1.
        let s = run(
            &[frame(&[])],
            &[frame(&[(1, 0.0, 0.0), (2, 1.0, 0.0)])],
            Convention::MotMetrics,
        );
        assert_eq!((s.false_positives, s.matches), (2, 0));
        assert_relative_eq!(s.mota, -1.0);
        assert_relative_eq!(s.motp, 0.0);
        // Misses only.
        let s = run(
            &[frame(&[(1, 0.0, 0.0)])],
            &[frame(&[])],
            Convention::LegTrackerBenchmarks,
        );
        assert_eq!((s.misses, s.ground_truth), (1, 1));
        assert_relative_eq!(s.mota, 0.0);
    }

    #[test]
    fn the_threshold_is_inclusive_for_motmetrics_only() {
        let truth = [frame(&[(1, 0.0, 0.0)])];
        let hyp = [frame(&[(1, 0.75, 0.0)])];
        assert_eq!(run(&truth, &hyp, Convention::MotMetrics).matches, 1);
        assert_eq!(
            run(&truth, &hyp, Convention::LegTrackerBenchmarks).matches,
            0
        );
        let hyp = [frame(&[(1, 0.7500001, 0.0)])];
        assert_eq!(run(&truth, &hyp, Convention::MotMetrics).matches, 0);
    }

    #[test]
    fn a_kept_correspondence_beats_a_closer_newcomer() {
        // Frame 2: hypothesis 2 is closer to truth 1, but 1–1 is kept (still within 0.75 m).
        let truth = vec![frame(&[(1, 0.0, 0.0)]), frame(&[(1, 0.0, 0.0)])];
        let hyp = vec![
            frame(&[(1, 0.1, 0.0)]),
            frame(&[(1, 0.6, 0.0), (2, 0.05, 0.0)]),
        ];
        for c in BOTH {
            let s = run(&truth, &hyp, c);
            assert_eq!(
                (s.matches, s.id_switches, s.false_positives),
                (2, 0, 1),
                "{c:?}"
            );
            assert_relative_eq!(s.motp, 0.35, epsilon = 1e-12);
        }
    }

    #[test]
    fn gated_and_ungated_assignments_differ() {
        // Distances: (1,7) 0.7, (1,8) 2.2, (2,7) 0.5, (2,8) 1.0.
        let truth = [frame(&[(1, 0.0, 0.0), (2, 1.2, 0.0)])];
        let hyp = [frame(&[(7, 0.7, 0.0), (8, 2.2, 0.0)])];
        // Gated: the candidates (1,7) and (2,7) share hypothesis 7; the cheaper one wins.
        let gated = run(&truth, &hyp, Convention::MotMetrics);
        assert_eq!(gated.matches, 1);
        assert_relative_eq!(gated.motp, 0.5, epsilon = 1e-12);
        // Ungated: (1,7)+(2,8) = 1.7 beats (1,8)+(2,7) = 2.7, then (2,8) at 1.0 is dropped.
        let ungated = run(&truth, &hyp, Convention::LegTrackerBenchmarks);
        assert_eq!(ungated.matches, 1);
        assert_relative_eq!(ungated.motp, 0.7, epsilon = 1e-12);
    }

    #[test]
    fn switch_counting_follows_each_convention() {
        // Hypothesis 7 follows truth 1, then jumps to truth 2 (truth 1 missed), then back.
        let truth = vec![
            frame(&[(1, 0.0, 0.0), (2, 5.0, 0.0)]),
            frame(&[(1, 0.0, 0.0), (2, 5.0, 0.0)]),
            frame(&[(1, 0.0, 0.0), (2, 5.0, 0.0)]),
        ];
        let hyp = vec![
            frame(&[(7, 0.0, 0.0)]),
            frame(&[(7, 5.0, 0.0)]),
            frame(&[(7, 0.0, 0.0)]),
        ];
        // motmetrics: truth 2 had no hypothesis before → no switch; truth 1 returns to its
        // last hypothesis 7 → no switch.
        let s = run(&truth, &hyp, Convention::MotMetrics);
        assert_eq!((s.matches, s.id_switches, s.misses), (3, 0, 3));
        // clear_mot.py: hypothesis 7 changes truth object twice → two switches.
        let s = run(&truth, &hyp, Convention::LegTrackerBenchmarks);
        assert_eq!((s.matches, s.id_switches, s.misses), (3, 2, 3));
        assert_relative_eq!(s.mota, 1.0 - 5.0 / 6.0, epsilon = 1e-12);
    }

    #[test]
    fn a_new_hypothesis_on_a_tracked_object_is_a_switch_in_both() {
        let truth = vec![frame(&[(1, 0.0, 0.0)]); 3];
        let hyp = vec![
            frame(&[(7, 0.0, 0.0)]),
            frame(&[(8, 0.0, 0.0)]),
            frame(&[(8, 0.0, 0.0)]),
        ];
        for c in BOTH {
            let s = run(&truth, &hyp, c);
            assert_eq!((s.matches, s.id_switches), (3, 1), "{c:?}");
        }
    }

    #[test]
    fn motmetrics_remembers_a_pair_across_an_absence() {
        // Truth 1 matched to 7, absent in frame 2 (7 then matches truth 2), back in frame 3
        // with only hypothesis 8 near it: a switch against its memory of 7.
        let truth = vec![
            frame(&[(1, 0.0, 0.0)]),
            frame(&[(2, 9.0, 0.0)]),
            frame(&[(1, 0.0, 0.0)]),
        ];
        let hyp = vec![
            frame(&[(7, 0.0, 0.0)]),
            frame(&[(7, 9.0, 0.0)]),
            frame(&[(8, 0.0, 0.0)]),
        ];
        let s = run(&truth, &hyp, Convention::MotMetrics);
        assert_eq!(s.id_switches, 1);
        // clear_mot.py: 7→1 is replaced by 7→2 in frame 2, so truth 1 is forgotten, but 7→2
        // was a switch (7 changed object).
        let s = run(&truth, &hyp, Convention::LegTrackerBenchmarks);
        assert_eq!(s.id_switches, 1);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let ok = [frame(&[(1, 0.0, 0.0)])];
        assert!(matches!(
            clear_mot(&ok, &[], &ClearMotParams::default()),
            Err(TrackingError::LengthMismatch {
                first_len: 1,
                second_len: 0,
                ..
            })
        ));
        let dup = [frame(&[(1, 0.0, 0.0), (1, 1.0, 0.0)])];
        assert!(matches!(
            clear_mot(&ok, &dup, &ClearMotParams::default()),
            Err(TrackingError::InvalidObject {
                side: "hypotheses",
                frame: 0,
                id: 1,
                ..
            })
        ));
        let nan = [frame(&[(3, f64::NAN, 0.0)])];
        assert!(matches!(
            clear_mot(&nan, &ok, &ClearMotParams::default()),
            Err(TrackingError::InvalidObject {
                side: "truth",
                id: 3,
                ..
            })
        ));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                clear_mot(
                    &ok,
                    &ok,
                    &ClearMotParams::default().with_match_threshold(bad)
                ),
                Err(TrackingError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "match_threshold",
                        ..
                    }
                ))
            ));
        }
    }

    fn person(bag_time: f64, id: u64, x: f64) -> PersonPosition {
        PersonPosition {
            bag_time,
            id,
            position: Point2::new(x, 0.0),
            line: 0,
        }
    }

    #[test]
    fn records_go_to_the_last_scan_strictly_before_them() {
        let scans = [1.0, 2.0, 2.0, 3.0];
        let records = [
            person(1.0, 1, 0.0),
            person(1.5, 1, 1.0),
            person(2.0, 2, 2.0),
            person(2.5, 3, 3.0),
            // Within one median interval (1 s) after the last scan: the last scan's.
            person(3.9, 4, 4.0),
            // Long after it: no scan's.
            person(9.0, 5, 5.0),
        ];
        let s = truth_frames_for_scans(&scans, &records).unwrap();
        let ids: Vec<Vec<u64>> = s
            .frames
            .iter()
            .map(|f| f.objects.iter().map(|o| o.0).collect())
            .collect();
        assert_eq!(ids, vec![vec![1, 2], vec![], vec![3], vec![4]]);
        assert_eq!(s.unassigned, 2);
        assert_eq!(s.frames[3].time, 3.0);
        assert!(matches!(
            truth_frames_for_scans(&[1.0, 0.5], &records),
            Err(TrackingError::NotSorted { index: 1, .. })
        ));
        assert!(matches!(
            truth_frames_for_scans(&[f64::NAN], &records),
            Err(TrackingError::NotSorted { index: 0, .. })
        ));
    }

    #[test]
    fn grouping_by_time_sorts_negative_and_positive_times() {
        let records = [
            person(2.0, 1, 0.0),
            person(-1.0, 2, 0.0),
            person(-3.0, 3, 0.0),
            person(2.0, 4, 0.0),
            person(0.0, 5, 0.0),
            person(-0.0, 6, 0.0),
        ];
        let frames = group_by_time(&records);
        let times: Vec<f64> = frames.iter().map(|f| f.time).collect();
        assert_eq!(times, vec![-3.0, -1.0, 0.0, 2.0]);
        assert_eq!(
            frames[3].objects.iter().map(|o| o.0).collect::<Vec<_>>(),
            vec![1, 4]
        );
        assert_eq!(frames[2].objects.len(), 2);
    }

    proptest! {
        #[test]
        fn counts_are_consistent(
            seq in proptest::collection::vec(
                (
                    proptest::collection::btree_map(0u64..6, (-2.0f64..2.0, -2.0f64..2.0), 0..5),
                    proptest::collection::btree_map(0u64..6, (-2.0f64..2.0, -2.0f64..2.0), 0..5),
                ),
                0..12,
            ),
            leg in any::<bool>(),
        ) {
            let to_frame = |m: &BTreeMap<u64, (f64, f64)>| Frame::new(0.0, m.iter().map(|(&id, &(x, y))| (id, Point2::new(x, y))).collect());
            let truth: Vec<Frame> = seq.iter().map(|(t, _)| to_frame(t)).collect();
            let hyp: Vec<Frame> = seq.iter().map(|(_, h)| to_frame(h)).collect();
            let convention = if leg { Convention::LegTrackerBenchmarks } else { Convention::MotMetrics };
            let s = run(&truth, &hyp, convention);
            prop_assert_eq!(s.matches + s.misses, s.ground_truth);
            prop_assert_eq!(s.matches + s.false_positives, s.hypotheses);
            prop_assert!(s.id_switches <= s.matches);
            prop_assert!(s.motp >= 0.0 && s.motp <= 0.75);
            prop_assert!(s.mota <= 1.0);
            // Truth against itself is perfect.
            let own = run(&truth, &truth, convention);
            prop_assert_eq!((own.misses, own.false_positives, own.id_switches), (0, 0, 0));
        }
    }
}
