//! Days from random start poses brought into one frame before the layout library: each day
//! registered onto the layouts of the days before it, as `haunts day --like` and `haunts
//! merge` do, and scored against the simulator's truth.

use haunts_affordance::Registration;
use haunts_affordance::{AffordanceError, LayoutLibrary, LayoutParams, RegisterParams};
use haunts_occupancy::{GridGeometry, Pose2};

use haunts_occupancy::recording::Recording;
#[cfg(feature = "rayon")]
use rayon::prelude::*;

use super::SimulatedDay;
use crate::pipeline::{DayOutput, DayProcessor, Result, moved_recording};

/// One day's registration, and its error against the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignedDay {
    /// The day's index.
    pub index: usize,
    /// The transform found: the day's frame in the first day's.
    pub registration: Registration,
    /// Its distance from the true transform, metres.
    pub error_m: f64,
    /// Its angle from the true transform, degrees.
    pub error_deg: f64,
}

/// A day whose registration was refused (left out of the study: never merged misaligned).
#[derive(Debug, Clone, PartialEq)]
pub struct RefusedDay {
    /// The day's index.
    pub index: usize,
    /// Why.
    pub reason: String,
}

/// What [`align_days`] did with every day after the first.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AlignmentStudy {
    /// The days registered, in day order.
    pub aligned: Vec<AlignedDay>,
    /// The days refused.
    pub refused: Vec<RefusedDay>,
}

/// The median and largest errors of the registrations against the truth.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct AlignmentErrors {
    /// Median distance, metres.
    pub median_m: f64,
    /// Largest distance, metres.
    pub max_m: f64,
    /// Median angle, degrees.
    pub median_deg: f64,
    /// Largest angle, degrees.
    pub max_deg: f64,
}

impl AlignmentStudy {
    /// The errors of the registered days (`None` when none was registered).
    pub fn errors(&self) -> Option<AlignmentErrors> {
        let stats = |f: fn(&AlignedDay) -> f64| {
            let mut v: Vec<f64> = self.aligned.iter().map(f).collect();
            let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            haunts_core::median(&mut v).map(|m| (m, max))
        };
        let (median_m, max_m) = stats(|d| d.error_m)?;
        let (median_deg, max_deg) = stats(|d| d.error_deg)?;
        Some(AlignmentErrors {
            median_m,
            max_m,
            median_deg,
            max_deg,
        })
    }
}

/// Days processed each in its own frame (days of
/// [`SimParams::random_start`](haunts_sim::SimParams::random_start) on their own grids,
/// [`simulate_days_on_own_grids`](super::simulate_days_on_own_grids)) brought into one frame: in day order, each registered onto a layout library of the days
/// before it ([`LayoutLibrary::register`] under `register`, the library under `params` on
/// the first day's own cells, in its frame) and added to it, or refused and left out.
///
/// The returned days lie on `geometry` in the office's frame: the library's frame is the
/// first day's own, and to score against the simulator's truth and plan the office's trips
/// every kept day is then moved by the first day's true start ([`SimulatedDay::start`]):
/// one rigid transform for all days, which leaves what was registered, the days' places
/// relative to one another, untouched. Each day is resampled once, from its own frame.
///
/// # Errors
/// The library's errors (bad parameters); a day whose registration fails for any reason is
/// refused, not an error.
pub fn align_days(
    days: Vec<SimulatedDay>,
    geometry: GridGeometry,
    params: LayoutParams,
    register: &RegisterParams,
) -> Result<(Vec<SimulatedDay>, AlignmentStudy)> {
    let mut study = AlignmentStudy::default();
    let Some(first) = days.first() else {
        return Ok((days, study));
    };
    let (own, office) = (*first.output.map.geometry(), first.start);
    let mut library = LayoutLibrary::new(own, params)?;
    let mut kept = Vec::with_capacity(days.len());
    for (k, mut day) in days.into_iter().enumerate() {
        let label = format!("day {:02}", day.index);
        let pose = if k == 0 {
            library.ingest(label, &day.output.map, &day.output.density)?;
            Pose2::identity()
        } else {
            let r = match library.register(&day.output.map, register) {
                Ok(r) => r,
                Err(e) => {
                    let reason = match e {
                        AffordanceError::NotRegistered { refusal } => refusal.to_string(),
                        e => e.to_string(),
                    };
                    study.refused.push(RefusedDay {
                        index: day.index,
                        reason,
                    });
                    continue;
                }
            };
            let truth = office.inverse() * day.start;
            let p = r.pose();
            study.aligned.push(AlignedDay {
                index: day.index,
                registration: r,
                error_m: (p.translation.vector - truth.translation.vector).norm(),
                error_deg: p.rotation.angle_to(&truth.rotation).abs().to_degrees(),
            });
            let (moved, _) = day.output.moved(&p, &own)?;
            library.ingest(label, &moved.map, &moved.density)?;
            p
        };
        day.output = day.output.moved(&(office * pose), &geometry)?.0;
        kept.push(day);
    }
    Ok((kept, study))
}

/// The days [`align_days`] kept, each processed again from its recording with its odometry
/// moved into the output frame ([`moved_recording`]: the first day by its true start, every
/// other by that and its registration) on `processor`'s grid, the `geometry` given to
/// [`align_days`]: each day drawn once onto the office's cells rather than resampled there.
/// `recording(index)` gives day `index`'s recording again (for simulated days,
/// `sim.day(index)?.to_recording()`); each day keeps its score, computed in its own frame.
/// In parallel with the `rayon` feature.
///
/// # Errors
/// `recording`'s errors; the daily loop's.
pub fn reprocess_aligned(
    days: &mut [SimulatedDay],
    alignment: &AlignmentStudy,
    processor: &DayProcessor,
    recording: impl Fn(usize) -> Result<Recording> + Sync,
) -> Result<()> {
    let Some(office) = days.first().map(|d| d.start) else {
        return Ok(());
    };
    let pose = |index: usize| {
        alignment
            .aligned
            .iter()
            .find(|a| a.index == index)
            .map_or(office, |a| office * a.registration.pose())
    };
    let again = |d: &SimulatedDay| -> Result<DayOutput> {
        processor.process(&moved_recording(recording(d.index)?, &pose(d.index))?)
    };
    #[cfg(feature = "rayon")]
    let outputs: Vec<Result<DayOutput>> = days.par_iter().map(again).collect();
    #[cfg(not(feature = "rayon"))]
    let outputs: Vec<Result<DayOutput>> = days.iter().map(again).collect();
    for (d, output) in days.iter_mut().zip(outputs) {
        d.output = output?;
    }
    Ok(())
}
