//! How many detections per second of observation at each time of day: the rate of people
//! `n(t)`, from detections and the windows in which the robot was observing.

use std::collections::BTreeMap;

use crate::hypertime::{Blocks, DAY, TimedPoint};
use crate::{AffordanceError, Result};

/// Width of the time-of-day bins of [`DailyRate`]'s tables, seconds (nominal: the period is
/// divided into a whole number of bins of about this width).
const BIN: f64 = 60.0;

/// An observation window, `[start, end]` in UNIX seconds.
type Window = (f64, f64);

/// The kernel is cut at this many standard deviations (`exp(−8) ≈ 3·10⁻⁴` of its peak).
const CUT: f64 = 4.0;

/// The spans of time in which the robot observed, from its detections alone: sorted
/// detection times are split where two consecutive ones are more than `max_gap` seconds
/// apart, and each run `[first, last]` is one window. Non-finite times are left out.
///
/// A robot that saw nobody for longer than `max_gap` while it was observing loses that span
/// (it reads as "not observed"); a robot that was off for less than `max_gap` between two
/// detections has that span counted as observed. Choose `max_gap` between the longest quiet
/// spell of an observing robot and the shortest pause between its sessions.
pub fn observation_windows(points: &[TimedPoint], max_gap: f64) -> Vec<(f64, f64)> {
    let mut times: Vec<f64> = points
        .iter()
        .filter(|p| p.is_finite())
        .map(|p| p.time)
        .collect();
    times.sort_by(f64::total_cmp);
    let mut windows: Vec<(f64, f64)> = Vec::new();
    for t in times {
        match windows.last_mut() {
            Some((_, end)) if t - *end <= max_gap => *end = t,
            _ => windows.push((t, t)),
        }
    }
    windows
}

/// The daily rate of detections: counts and observed seconds folded onto the time of day and
/// smoothed by a Gaussian over the time of day, `n(t) = C(t) / X(t)` with
///
/// * `C(t) = Σⱼ K(t − tⱼ)`, the detections near `t` (over every day of the data),
/// * `X(t) = Σ_w ∫_w K(t − u) du`, the seconds of observation near `t` (over every
///   observation window `w`, [`observation_windows`]),
/// * `K(δ) = exp(−δ²/2σ²)`, `δ` the difference of the times of day taken the short way round
///   the period, cut at `4σ`.
///
/// Both are tables of one-minute bins over the period; `X(t)` counts seconds, so
/// `X(t) ≈ D·σ√(2π)` where `D` days were observed all around `t`, and `0` far from any
/// observation. Without smoothing (`σ = 0`) `C` and `X` are the raw counts and seconds of
/// `t`'s bin.
#[derive(Debug, Clone, PartialEq)]
pub struct DailyRate {
    period: f64,
    bin: f64,
    counts: Vec<f64>,
    exposure: Vec<f64>,
    detections: usize,
    observed: f64,
}

impl DailyRate {
    /// The rate of `points` over a period of `period` seconds (a day: [`DAY`]) observed in
    /// `windows` (UNIX seconds, `[start, end]`), smoothed by `smoothing` seconds. Non-finite
    /// points are left out; windows may cross midnight and span several periods.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`]: a period that is not finite and ≥ 2 minutes, a
    /// smoothing that is not finite and `≥ 0`, a window with a non-finite or reversed end.
    ///
    /// # Complexity
    /// `O(n + observed seconds / 60 + bins · σ / 60)`.
    pub fn fit(
        points: &[TimedPoint],
        windows: &[(f64, f64)],
        period: f64,
        smoothing: f64,
    ) -> Result<Self> {
        if !(period.is_finite() && period >= 2.0 * BIN) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "period",
                    value: period,
                    rule: "must be finite and >= 120 s",
                },
            ));
        }
        haunts_core::non_negative("smoothing", smoothing)?;
        let n = (period / BIN).round().max(2.0) as usize;
        let bin = period / n as f64;
        let index = |t: f64| ((t.rem_euclid(period) / bin) as usize).min(n - 1);
        let mut counts = vec![0.0; n];
        let mut detections = 0;
        for p in points.iter().filter(|p| p.is_finite()) {
            counts[index(p.time)] += 1.0;
            detections += 1;
        }
        let mut exposure = vec![0.0; n];
        let mut observed = 0.0;
        for &(a, b) in windows {
            if !(a.is_finite() && b.is_finite() && a <= b) {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "window",
                        value: if a.is_finite() { b } else { a },
                        rule: "ends must be finite, start <= end",
                    },
                ));
            }
            observed += b - a;
            // Walk the window bin by bin (bin edges at multiples of `bin` from UNIX 0).
            let mut u = a;
            while u < b {
                let edge = ((u / bin).floor() + 1.0) * bin;
                let next = edge.min(b);
                exposure[index(u)] += next - u;
                u = next;
            }
        }
        let smooth = |raw: &[f64]| -> Vec<f64> {
            if smoothing == 0.0 {
                return raw.to_vec();
            }
            let half = ((CUT * smoothing / bin).ceil() as usize).min(n / 2);
            let weights: Vec<f64> = (0..=half)
                .map(|k| {
                    let d = k as f64 * bin / smoothing;
                    (-0.5 * d * d).exp()
                })
                .collect();
            (0..n)
                .map(|i| {
                    let mut s = weights[0] * raw[i];
                    for (k, w) in weights.iter().enumerate().skip(1) {
                        // Both sides, except the one bin opposite when 2k = n.
                        s += w * raw[(i + k) % n];
                        if 2 * k != n {
                            s += w * raw[(i + n - k) % n];
                        }
                    }
                    s
                })
                .collect()
        };
        Ok(Self {
            period,
            bin,
            counts: smooth(&counts),
            exposure: smooth(&exposure),
            detections,
            observed,
        })
    }

    fn bin_of(&self, t: f64) -> Option<usize> {
        t.is_finite()
            .then(|| ((t.rem_euclid(self.period) / self.bin) as usize).min(self.counts.len() - 1))
    }

    /// The period, seconds.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// `C(t)`: the detections near the time of day of `t` (0 at a non-finite `t`).
    pub(crate) fn detections_near(&self, t: f64) -> f64 {
        self.bin_of(t).map_or(0.0, |i| self.counts[i])
    }

    /// `X(t)`: the seconds of observation near the time of day of `t` (0 at a non-finite
    /// `t`).
    pub fn exposure_near(&self, t: f64) -> f64 {
        self.bin_of(t).map_or(0.0, |i| self.exposure[i])
    }

    /// `n(t) = C(t) / X(t)`, detections per second at the time of day of `t`, or `None`
    /// where nothing was observed near it.
    pub fn rate(&self, t: f64) -> Option<f64> {
        let x = self.exposure_near(t);
        (x > 0.0).then(|| self.detections_near(t) / x)
    }

    /// `n̄ = N / X`, detections per second of observation over all the data, or `None`
    /// without observation: the time-independent rate.
    pub(crate) fn mean_rate(&self) -> Option<f64> {
        (self.observed > 0.0).then(|| self.detections as f64 / self.observed)
    }

    /// The number of finite detections counted.
    pub fn detections(&self) -> usize {
        self.detections
    }

    /// The seconds observed, over all windows.
    pub fn observed(&self) -> f64 {
        self.observed
    }
}

/// Whether a rhythm of the rate over the time of day recurs from day to day
/// ([`DailyRate::check_across_days`]): detections predicted per interval of held-out days by
/// the rhythm `n(t)` of the other days, against their flat rate `n̄`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateCheck {
    /// Days (blocks of the period, from its quietest time) holding detections.
    pub days: usize,
    /// Root mean square of (predicted − observed) detections per observed interval of the
    /// held-out days, the rhythm's prediction (NaN with fewer than two days).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub rhythm_rmse: f64,
    /// The same for the flat rate.
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub flat_rmse: f64,
    /// The mean detections per held-out interval (NaN with fewer than two days): their
    /// Poisson variance is the error a flat rate has with no rhythm to find.
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub mean_count: f64,
    /// Whether the rhythm predicted better by the margin (`rhythm_rmse < (1 − margin) ·
    /// flat_rmse`) where the flat rate errs beyond counting noise (`flat_rmse² >
    /// mean_count`), two days at least.
    pub accepted: bool,
}

impl DailyRate {
    /// Leave-one-day-out check of the rhythm: for each day (a block of `period` seconds
    /// starting at the data's quietest time of day, as the hypertime periods'
    /// [`CycleValidation`](crate::hypertime::CycleValidation) cuts them), the rate is fitted on
    /// the other days' detections and windows (a window belongs to the day of its middle) and
    /// predicts the detections of each `interval` seconds the held-out day was observed:
    /// `∫ n(u) du` over its observed seconds (`n̄` where the other days never observed that
    /// time), against `n̄ × seconds`. Accepted when the rhythm's RMSE over all held-out
    /// intervals is below `(1 − margin)` times the flat rate's (`margin` in `[0, 1)`: a
    /// rhythm that barely beats a flat rate is noise the next day) and the flat rate's mean
    /// square error exceeds the mean count per interval (the variance of Poisson counts: a
    /// flat rate that errs no more than counting noise leaves no rhythm to find, and a rhythm
    /// that beats it fits artefacts, such as the last minute of a window). A single day
    /// cannot be checked and is not accepted.
    ///
    /// # Errors
    /// As [`DailyRate::fit`]; `interval` not finite and `> 0`; `margin` outside `[0, 1)`.
    ///
    /// # Complexity
    /// One [`DailyRate::fit`] per day.
    pub fn check_across_days(
        points: &[TimedPoint],
        windows: &[(f64, f64)],
        period: f64,
        smoothing: f64,
        interval: f64,
        margin: f64,
    ) -> Result<RateCheck> {
        if !(interval.is_finite() && interval > 0.0) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "interval",
                    value: interval,
                    rule: "must be finite and > 0 s",
                },
            ));
        }
        if !(0.0..1.0).contains(&margin) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "margin",
                    value: margin,
                    rule: "must be in [0, 1)",
                },
            ));
        }
        Self::fit(&[], windows, period, smoothing)?; // the parameters' and windows' errors
        let points: Vec<TimedPoint> = points.iter().copied().filter(|p| p.is_finite()).collect();
        let blocks = Blocks::of(&points, period);
        let day_of_window = |w: &(f64, f64)| blocks.id_at(0.5 * (w.0 + w.1));
        let (mut rhythm, mut flat, mut count, mut n) = (0.0, 0.0, 0.0, 0usize);
        if blocks.ids().len() >= 2 {
            for &day in blocks.ids() {
                let (held, kept): (Vec<TimedPoint>, Vec<TimedPoint>) =
                    points.iter().partition(|p| blocks.id_at(p.time) == day);
                let (held_w, kept_w): (Vec<Window>, Vec<Window>) =
                    windows.iter().partition(|w| day_of_window(w) == day);
                let rate = Self::fit(&kept, &kept_w, period, smoothing)?;
                let mean = rate.mean_rate().unwrap_or(0.0);
                // (observed, rhythm's prediction, flat prediction) per observed interval.
                let mut by_interval: BTreeMap<i64, (f64, f64, f64)> = BTreeMap::new();
                let key = |t: f64| (t / interval).floor() as i64;
                for &(a, b) in &held_w {
                    let mut u = a;
                    while u < b {
                        let next = (((u / BIN).floor() + 1.0) * BIN).min(b);
                        let mid = 0.5 * (u + next);
                        let e = by_interval.entry(key(mid)).or_default();
                        e.1 += rate.rate(mid).unwrap_or(mean) * (next - u);
                        e.2 += mean * (next - u);
                        u = next;
                    }
                }
                for p in &held {
                    if let Some(e) = by_interval.get_mut(&key(p.time)) {
                        e.0 += 1.0;
                    }
                }
                for (observed, r, f) in by_interval.values() {
                    rhythm += (r - observed).powi(2);
                    flat += (f - observed).powi(2);
                    count += observed;
                    n += 1;
                }
            }
        }
        let mean = |s: f64| if n > 0 { s / n as f64 } else { f64::NAN };
        let (rhythm_rmse, flat_rmse) = (mean(rhythm).sqrt(), mean(flat).sqrt());
        let mean_count = mean(count);
        Ok(RateCheck {
            days: blocks.ids().len(),
            rhythm_rmse,
            flat_rmse,
            mean_count,
            accepted: rhythm_rmse < (1.0 - margin) * flat_rmse && mean(flat) > mean_count,
        })
    }
}

impl Default for DailyRate {
    /// Nothing observed over a day.
    fn default() -> Self {
        let n = (DAY / BIN) as usize;
        Self {
            period: DAY,
            bin: BIN,
            counts: vec![0.0; n],
            exposure: vec![0.0; n],
            detections: 0,
            observed: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t: f64) -> TimedPoint {
        TimedPoint::new(t, 0.0, 0.0)
    }

    #[test]
    fn windows_split_at_gaps_and_skip_non_finite() {
        let points = [
            at(10.0),
            at(0.0),
            at(5.0),
            at(f64::NAN),
            at(100.0),
            at(104.0),
        ];
        assert_eq!(
            observation_windows(&points, 20.0),
            vec![(0.0, 10.0), (100.0, 104.0)]
        );
    }

    #[test]
    fn unsmoothed_rate_is_counts_over_seconds() {
        // Two days observed 10:00–11:00; 360 detections at 10:30 each day (0.1 per second).
        let h = 3600.0;
        let mut points = Vec::new();
        for day in 0..2 {
            let t0 = day as f64 * DAY + 10.0 * h;
            points.extend((0..360).map(|i| at(t0 + 0.5 * h + i as f64 * 0.1)));
        }
        let windows = [(10.0 * h, 11.0 * h), (DAY + 10.0 * h, DAY + 11.0 * h)];
        let r = DailyRate::fit(&points, &windows, DAY, 0.0).unwrap();
        approx::assert_relative_eq!(r.exposure_near(10.2 * h), 120.0, max_relative = 1e-9);
        approx::assert_relative_eq!(r.detections_near(10.5 * h), 720.0);
        approx::assert_relative_eq!(r.rate(10.5 * h).unwrap(), 6.0);
        assert_eq!(r.rate(3.0 * h), None);
        approx::assert_relative_eq!(r.mean_rate().unwrap(), 720.0 / 7200.0);
    }

    #[test]
    fn smoothed_exposure_of_a_whole_day_is_sigma_root_two_pi() {
        let sigma = 1800.0;
        let r = DailyRate::fit(&[], &[(0.0, DAY)], DAY, sigma).unwrap();
        let expected = sigma * (std::f64::consts::TAU).sqrt();
        // Riemann sum of the cut Gaussian in 1-minute bins.
        approx::assert_relative_eq!(r.exposure_near(5.0 * 3600.0), expected, max_relative = 1e-3);
        approx::assert_relative_eq!(
            r.exposure_near(23.9 * 3600.0),
            expected,
            max_relative = 1e-3
        );
    }

    /// Two days observed 10:00–12:00 with `a` detections in the first hour and `b` in the
    /// second on day 0, and `c`, `d` on day 1, spread evenly.
    fn two_days(counts: [[usize; 2]; 2]) -> (Vec<TimedPoint>, Vec<(f64, f64)>) {
        let h = 3600.0;
        let mut points = Vec::new();
        let mut windows = Vec::new();
        for (day, hours) in counts.iter().enumerate() {
            let t0 = day as f64 * DAY + 10.0 * h;
            windows.push((t0, t0 + 2.0 * h));
            for (k, &n) in hours.iter().enumerate() {
                let start = t0 + k as f64 * h;
                points.extend((0..n).map(|i| at(start + (i as f64 + 0.5) * h / n as f64)));
            }
        }
        (points, windows)
    }

    #[test]
    fn a_rhythm_that_recurs_is_accepted_by_hand_computed_errors() {
        // Each day 100 then 20: the other day's rhythm predicts 100 and 20 exactly; the flat
        // rate predicts 60 and 60 (errors 40).
        let (points, windows) = two_days([[100, 20], [100, 20]]);
        let check = DailyRate::check_across_days(&points, &windows, DAY, 0.0, 3600.0, 0.1).unwrap();
        assert_eq!(check.days, 2);
        approx::assert_abs_diff_eq!(check.rhythm_rmse, 0.0, epsilon = 1e-9);
        approx::assert_relative_eq!(check.flat_rmse, 40.0, max_relative = 1e-12);
        approx::assert_relative_eq!(check.mean_count, 60.0, max_relative = 1e-12);
        assert!(check.accepted);
        // The same rhythm within counting noise (10 and 8 a day, flat error 1, MSE 1 < 9) is
        // not accepted.
        let (points, windows) = two_days([[10, 8], [10, 8]]);
        let check = DailyRate::check_across_days(&points, &windows, DAY, 0.0, 3600.0, 0.1).unwrap();
        approx::assert_relative_eq!(check.flat_rmse, 1.0, max_relative = 1e-12);
        assert!(check.rhythm_rmse < 1e-9 && !check.accepted, "{check:?}");
    }

    #[test]
    fn a_rhythm_that_reverses_from_day_to_day_is_rejected() {
        // 100 then 20 on day 0, 20 then 100 on day 1: the other day's rhythm is wrong by 80
        // each hour, the flat rate by 40.
        let (points, windows) = two_days([[100, 20], [20, 100]]);
        let check = DailyRate::check_across_days(&points, &windows, DAY, 0.0, 3600.0, 0.1).unwrap();
        approx::assert_relative_eq!(check.rhythm_rmse, 80.0, max_relative = 1e-12);
        approx::assert_relative_eq!(check.flat_rmse, 40.0, max_relative = 1e-12);
        assert!(!check.accepted);
        // One day cannot be checked.
        let (points, windows) = two_days([[100, 20], [0, 0]]);
        let check =
            DailyRate::check_across_days(&points, &windows[..1], DAY, 0.0, 3600.0, 0.1).unwrap();
        assert_eq!(check.days, 1);
        assert!(check.rhythm_rmse.is_nan() && !check.accepted);
        assert!(DailyRate::check_across_days(&points, &windows, DAY, 0.0, 0.0, 0.1).is_err());
    }

    #[test]
    fn bad_input_is_typed() {
        assert!(DailyRate::fit(&[], &[], f64::NAN, 0.0).is_err());
        assert!(DailyRate::fit(&[], &[], DAY, -1.0).is_err());
        assert!(DailyRate::fit(&[], &[(2.0, 1.0)], DAY, 0.0).is_err());
    }
}
