//! A processed day against ground truth: the simulator's, or a bag's annotated people.
//!
//! Scoring is kept apart from [`DayProcessor`](super::DayProcessor), which never sees ground
//! truth: the same [`DayOutput`] is scored here, and nothing here feeds back into it.

use haunts_occupancy::Pose2;
use haunts_sim::{Day, FurnitureKind, PersonTruth};
use haunts_tracking::PersonPosition;
use haunts_tracking::eval::mot::{ClearMot, Frame, clear_mot, truth_frames_for_scans};
use haunts_tracking::eval::sequence::{EvalFrames, EvalParams, protocol_frames};
use nalgebra::Point2;

use super::{DayOutput, PipelineError, PipelineParams, Result};

/// How well the localisation did against the true poses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseErrors {
    /// RMS position error of raw odometry, metres.
    pub odometry_rms: f64,
    /// RMS position error of the corrected poses, metres.
    pub corrected_rms: f64,
    /// Largest position error of the corrected poses, metres.
    pub corrected_max: f64,
}

/// A simulated day's scores.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulatedScore {
    /// CLEAR MOT of the tracks against the people the laser saw, every processed scan.
    pub mot: ClearMot,
    /// Localisation errors over the processed scans.
    pub pose_errors: PoseErrors,
}

/// Scores the day `output` made of the simulated `day` (processed from
/// [`Day::to_recording`]): CLEAR MOT at every scan against the people the laser saw — at
/// least [`PipelineParams::visible_beams`] beams returned from their legs; a track nearer
/// to one of the others (within the match threshold) than to any visible person is *don't
/// care*, neither a match nor a false positive —, and the pose errors of odometry and of the
/// corrected poses. Everything is compared in the day's own frame, its odometry frame: the
/// truth is moved there from the world by [`Day::odometry_frame`] (a day of
/// [`SimParams::random_start`](haunts_sim::SimParams::random_start) is scored as any other).
///
/// # Errors
/// [`PipelineError::DayLengths`] when a scan of `output` has no counterpart in `day` (the
/// output of another day); CLEAR MOT's parameter errors.
pub fn simulated(output: &DayOutput, day: &Day, params: &PipelineParams) -> Result<SimulatedScore> {
    let n = day.scans.len();
    for (what, len) in [
        ("odometry", day.odometry.len()),
        ("poses", day.poses.len()),
        ("people", day.people.len()),
    ] {
        if len != n || output.poses.iter().any(|p| p.index >= len) {
            return Err(PipelineError::DayLengths {
                day: day.index,
                what,
                len,
                scans: output.poses.last().map_or(0, |p| p.index + 1),
            });
        }
    }
    let into = day.odometry_frame.inverse();
    let moved = into != Pose2::identity();
    let (mut truth, mut hypotheses) = (Vec::new(), Vec::new());
    for (pose, report) in output.poses.iter().zip(&output.reports) {
        let (mut visible, mut ignored) =
            visible_people(&day.people[pose.index], params.visible_beams);
        if moved {
            visible.iter_mut().for_each(|v| v.1 = into * v.1);
            ignored.iter_mut().for_each(|p| *p = into * *p);
        }
        let nearest = |set: &mut dyn Iterator<Item = Point2<f64>>, p: &Point2<f64>| {
            set.map(|q| (q - p).norm()).fold(f64::INFINITY, f64::min)
        };
        let cares = |p: &Point2<f64>| {
            let ignored = nearest(&mut ignored.iter().copied(), p);
            ignored > params.mot.match_threshold
                || nearest(&mut visible.iter().map(|v| v.1), p) <= ignored
        };
        hypotheses.push(Frame::new(
            pose.stamp,
            report
                .tracks
                .iter()
                .copied()
                .filter(|t| cares(&t.1))
                .collect(),
        ));
        truth.push(Frame::new(pose.stamp, visible));
    }
    let at =
        |series: &[Pose2]| -> Vec<Pose2> { output.poses.iter().map(|p| series[p.index]).collect() };
    let corrected: Vec<Pose2> = output.poses.iter().map(|p| p.pose).collect();
    let mut true_poses = at(&day.poses);
    if moved {
        true_poses.iter_mut().for_each(|p| *p = into * *p);
    }
    Ok(SimulatedScore {
        mot: clear_mot(&truth, &hypotheses, &params.mot)?,
        pose_errors: pose_errors(&at(&day.odometry), &corrected, &true_poses),
    })
}

/// The centres of a simulated day's tables and sofas, where visitors gather (true, for
/// scoring affordance maps with [`super::density_near`]).
pub(crate) fn tables_and_sofas(day: &Day) -> Vec<Point2<f64>> {
    day.furniture
        .iter()
        .filter(|f| matches!(f.kind, FurnitureKind::Table | FurnitureKind::Sofa))
        .map(|f| f.center)
        .collect()
}

/// A day's scores against a bag's annotated people under both protocols of
/// `leg_tracker_benchmarks`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnnotatedScore {
    /// Every scan scored, as `clear_mot.py` does: a track at a scan nobody annotated is a
    /// false positive (the headline figure).
    pub every_scan: ClearMot,
    /// Only the annotated scans scored (more lenient).
    pub annotated: ClearMot,
    /// Annotations earlier than the first scan, which belong to no scan.
    pub unassigned: usize,
    /// Scans that could not be read at all, so have no time to be scored at.
    pub unreadable: usize,
}

/// Scores the day `output` made of a recording against `truth`, people annotated in the
/// laser frame and stamped by the bag's clock (a `leg_tracker` benchmark bag's
/// `/people_tracked_ground_truth`, read by `haunts::recorded`). Each scan's tracks are
/// mapped into that scan's laser frame with its corrected pose, annotations go to scans as
/// [`truth_frames_for_scans`] assigns them, and skipped scans are scored with no track
/// (every annotated person there is a miss), as `evaluate_sequence` scores them.
/// `protocol`'s bearing window and CLEAR MOT conventions apply
/// ([`EvalParams::leg_tracker_benchmarks`] for the benchmark bags); its `frames` is ignored:
/// both rules are reported.
///
/// # Errors
/// [`PipelineError::NothingScored`] when no annotated person falls to a scored frame (no
/// ground truth, none of it at the day's scans or in the bearing window), where CLEAR MOT
/// would report a perfect MOTA of nothing; the tracking crate's errors for bad parameters or
/// unsorted scan times.
pub fn annotated(
    output: &DayOutput,
    truth: &[PersonPosition],
    protocol: &EvalParams,
) -> Result<AnnotatedScore> {
    let protocol = protocol.clone().check()?;
    // Every scan with a time, in recording order: (index, bag time, tracks in its laser frame).
    let mut scans: Vec<(usize, f64, Vec<Labelled>)> = output
        .poses
        .iter()
        .zip(&output.reports)
        .map(|(pose, report)| {
            let tracks = report
                .tracks
                .iter()
                .map(|&(id, p)| (id, pose.pose.inverse_transform_point(&p)))
                .collect();
            (pose.index, pose.received, tracks)
        })
        .collect();
    let mut unreadable = 0;
    for s in &output.skipped {
        match s.received {
            Some(t) => scans.push((s.index, t, Vec::new())),
            None => unreadable += 1,
        }
    }
    scans.sort_by_key(|s| s.0);
    let times: Vec<f64> = scans.iter().map(|s| s.1).collect();
    let frames = truth_frames_for_scans(&times, truth)?;
    let hypotheses: Vec<Frame> = scans
        .into_iter()
        .map(|(_, t, tracks)| Frame::new(t, tracks))
        .collect();
    let score = |rule: EvalFrames| -> Result<ClearMot> {
        let params = protocol.clone().with_frames(rule);
        let (t, h): (Vec<Frame>, Vec<Frame>) =
            protocol_frames(&frames.frames, &hypotheses, &params)
                .map(|(_, t, h)| (t, h))
                .unzip();
        Ok(clear_mot(&t, &h, &params.clear_mot)?)
    };
    let every_scan = score(EvalFrames::EveryScan)?;
    if every_scan.ground_truth == 0 {
        return Err(PipelineError::NothingScored {
            scans: times.len(),
            annotations: truth.len(),
            unassigned: frames.unassigned,
        });
    }
    Ok(AnnotatedScore {
        every_scan,
        annotated: score(EvalFrames::Annotated)?,
        unassigned: frames.unassigned,
        unreadable,
    })
}

/// A person's id and position.
type Labelled = (u64, Point2<f64>);

/// The true people of one scan that the laser saw — at least `visible_beams` beams returned
/// from their legs —, and the positions of the others.
fn visible_people(
    people: &[PersonTruth],
    visible_beams: usize,
) -> (Vec<Labelled>, Vec<Point2<f64>>) {
    let (mut visible, mut ignored) = (Vec::new(), Vec::new());
    for p in people {
        if p.beams >= visible_beams {
            visible.push((p.id, p.position));
        } else {
            ignored.push(p.position);
        }
    }
    (visible, ignored)
}

fn pose_errors(odometry: &[Pose2], corrected: &[Pose2], truth: &[Pose2]) -> PoseErrors {
    let error = |p: &Pose2, t: &Pose2| (p.translation.vector - t.translation.vector).norm();
    let rms = |poses: &[Pose2]| {
        let n = poses.len().max(1) as f64;
        (poses
            .iter()
            .zip(truth)
            .map(|(p, t)| error(p, t).powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
    };
    PoseErrors {
        odometry_rms: rms(odometry),
        corrected_rms: rms(corrected),
        corrected_max: corrected
            .iter()
            .zip(truth)
            .map(|(p, t)| error(p, t))
            .fold(0.0, f64::max),
    }
}
