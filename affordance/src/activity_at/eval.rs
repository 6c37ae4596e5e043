//! Scoring activity at a time against held-out detections, hour by hour: where (the
//! log-likelihood of the map at `t` normalised over a grid, against the time-independent map
//! and a uniform map) and how many (detections predicted in the hours the test robot
//! observed, against the time-independent rate).

use haunts_occupancy::GridGeometry;

use super::{ActivityAt, observation_windows};
use crate::hypertime::TimedPoint;
use crate::{AffordanceError, DensityMap, Result};

/// Parameters of [`evaluate_hours`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct HourlyParams {
    /// Length of a reported interval, seconds (default 3600).
    pub hour: f64,
    /// The map at `t` is rasterised once per step, at its middle, and scores the detections
    /// of the step, seconds (default 600; must divide `hour`).
    pub step: f64,
}

impl Default for HourlyParams {
    fn default() -> Self {
        Self {
            hour: 3600.0,
            step: 600.0,
        }
    }
}

impl HourlyParams {
    /// The rules, checked: `step` finite and `> 0`, `hour` a whole multiple of it.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        haunts_core::positive("step", self.step)?;
        let n = self.hour / self.step;
        if !(n.is_finite() && n >= 1.0 && (n - n.round()).abs() < 1e-9) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "hour",
                    value: self.hour,
                    rule: "must be a whole multiple of step",
                },
            ));
        }
        Ok(self)
    }
}

/// One interval of [`evaluate_hours`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HourScore {
    /// Start of the interval, UNIX seconds (a multiple of the interval).
    pub start: f64,
    /// Finite test detections in the interval.
    pub observed: usize,
    /// Of those, the ones scored: inside the grid, on a cell where both maps are positive.
    pub scored: usize,
    /// `Σ ln q_t(s)` over the scored detections, `q_t` the activity at `t` normalised over
    /// the grid's known cells (per m²).
    pub loglik_at: f64,
    /// The same for the time-independent map.
    pub loglik_static: f64,
    /// Seconds the test robot observed in the interval ([`observation_windows`] of the test
    /// detections, with the activity's `max_gap`).
    pub seconds: f64,
    /// Detections predicted in those seconds: `∫ (1 − c)·n̄ + c·n(t) dt`.
    pub predicted_at: f64,
    /// Detections predicted by the time-independent rate: `n̄ · seconds`.
    pub predicted_static: f64,
}

impl HourScore {
    /// Mean log-likelihood per scored detection at `t`, `None` if none was scored.
    pub fn mean_at(&self) -> Option<f64> {
        (self.scored > 0).then(|| self.loglik_at / self.scored as f64)
    }
    /// The same for the time-independent map.
    pub fn mean_static(&self) -> Option<f64> {
        (self.scored > 0).then(|| self.loglik_static / self.scored as f64)
    }
}

/// What [`evaluate_hours`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct HourlyEvaluation {
    /// Every interval with test detections or test observation, in time order.
    pub hours: Vec<HourScore>,
    /// The uniform map's log-likelihood, `−ln(known area)` per m².
    pub uniform: f64,
    /// Test detections outside the grid or on cells where a map is unknown or 0.
    pub unscored: usize,
}

impl HourlyEvaluation {
    /// Mean log-likelihood per scored detection over all intervals: `(at t, static)`, `None`
    /// if none was scored.
    pub fn mean(&self) -> Option<(f64, f64)> {
        let n: usize = self.hours.iter().map(|h| h.scored).sum();
        let at: f64 = self.hours.iter().map(|h| h.loglik_at).sum();
        let st: f64 = self.hours.iter().map(|h| h.loglik_static).sum();
        (n > 0).then(|| (at / n as f64, st / n as f64))
    }

    /// Root mean square of (predicted − observed) detections over the intervals the test
    /// robot observed: `(at t, static)`.
    pub fn count_rmse(&self) -> Option<(f64, f64)> {
        let h: Vec<&HourScore> = self.hours.iter().filter(|h| h.seconds > 0.0).collect();
        let rms = |f: fn(&HourScore) -> f64| {
            (h.iter()
                .map(|s| (f(s) - s.observed as f64).powi(2))
                .sum::<f64>()
                / h.len() as f64)
                .sqrt()
        };
        (!h.is_empty()).then(|| (rms(|s| s.predicted_at), rms(|s| s.predicted_static)))
    }
}

/// Scores `activity` on held-out detections `test`, interval by interval: the log-likelihood
/// of each detection under the activity at its step's middle and under the time-independent
/// map, both normalised over the known cells of `geometry` (bound it by the training data or
/// the map, not by the test set), and the detections predicted in the seconds the test robot
/// observed.
///
/// # Errors
/// [`AffordanceError::InvalidParameter`] for bad parameters; [`AffordanceError::NoUsableData`]
/// when the time-independent map knows no cell of `geometry` with a positive value.
///
/// # Complexity
/// One raster of `geometry` per step with test detections, plus one per interval of the rate.
pub fn evaluate_hours<M: DensityMap>(
    activity: &ActivityAt<M>,
    test: &[TimedPoint],
    geometry: &GridGeometry,
    params: &HourlyParams,
) -> Result<HourlyEvaluation> {
    let params = params.check()?;
    let raster = activity.on_grid(geometry);
    let cell_area = geometry.resolution() * geometry.resolution();
    let normaliser = |values: &[f64]| -> Option<(f64, f64)> {
        let (sum, known) = values
            .iter()
            .filter(|v| v.is_finite())
            .fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
        (sum > 0.0).then_some((sum * cell_area, known as f64 * cell_area))
    };
    let base = raster.base();
    let (base_total, area) = normaliser(base.data()).ok_or(AffordanceError::NoUsableData {
        what: "known cells of the time-independent map",
        given: geometry.len(),
        non_finite: 0,
        outside: 0,
    })?;
    let mut points: Vec<TimedPoint> = test.iter().copied().filter(|p| p.is_finite()).collect();
    points.sort_by(|a, b| a.time.total_cmp(&b.time));
    let windows = observation_windows(&points, activity.params.max_gap);
    let mut hours: Vec<HourScore> = Vec::new();
    let hour_of = |t: f64| (t / params.hour).floor() * params.hour;
    let slot = |h: &mut Vec<HourScore>, start: f64| -> usize {
        if h.last().is_none_or(|s| s.start != start) {
            h.push(HourScore {
                start,
                observed: 0,
                scored: 0,
                loglik_at: 0.0,
                loglik_static: 0.0,
                seconds: 0.0,
                predicted_at: 0.0,
                predicted_static: 0.0,
            });
        }
        h.len() - 1
    };
    // Where: one raster per step.
    let mut unscored = 0;
    let mut i = 0;
    while i < points.len() {
        let step_start = (points[i].time / params.step).floor() * params.step;
        let end = points[i..]
            .iter()
            .position(|p| p.time >= step_start + params.step)
            .map_or(points.len(), |k| i + k);
        let at = raster.at(step_start + 0.5 * params.step);
        let at_total = normaliser(at.data()).map_or(f64::NAN, |(s, _)| s);
        for p in &points[i..end] {
            let h = slot(&mut hours, hour_of(p.time));
            hours[h].observed += 1;
            let values = geometry
                .world_to_cell(p.position)
                .and_then(|c| Some((*at.get(c)?, *base.get(c)?)));
            match values {
                Some((a, b)) if a > 0.0 && b > 0.0 && at_total > 0.0 => {
                    hours[h].scored += 1;
                    hours[h].loglik_at += (a / at_total).ln();
                    hours[h].loglik_static += (b / base_total).ln();
                }
                _ => unscored += 1,
            }
        }
        i = end;
    }
    // How many: the rate over the seconds observed, minute by minute.
    let mean_rate = activity.rate.mean_rate().unwrap_or(0.0);
    for &(a, b) in &windows {
        let mut u = a;
        while u < b {
            let next = (((u / 60.0).floor() + 1.0) * 60.0).min(b);
            let mid = 0.5 * (u + next);
            let c = activity.confidence(mid);
            let n = activity.rate.rate(mid).unwrap_or(mean_rate);
            let h = hour_of(mid);
            let k = match hours.iter().position(|s| s.start == h) {
                Some(k) => k,
                None => {
                    let k = slot(&mut hours, h);
                    hours.sort_by(|x, y| x.start.total_cmp(&y.start));
                    hours.iter().position(|s| s.start == h).unwrap_or(k)
                }
            };
            let dt = next - u;
            hours[k].seconds += dt;
            hours[k].predicted_at += ((1.0 - c) * mean_rate + c * n) * dt;
            hours[k].predicted_static += mean_rate * dt;
            u = next;
        }
    }
    hours.sort_by(|x, y| x.start.total_cmp(&y.start));
    Ok(HourlyEvaluation {
        hours,
        uniform: -area.ln(),
        unscored,
    })
}
