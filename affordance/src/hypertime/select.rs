//! Choosing the hypertime model's periods (FreMEn on the residual of the model) and its number
//! of clusters, both by held-out likelihood.

use super::gk::{BLOCK, GkParams};
use super::model::{Fitted, HypertimeParams, Tuning, fit_once, log_add_exp, map_slice};
use super::projection::{DAY, TimedPoint};
use crate::{AffordanceError, Result};

/// How a search holds data out: time is cut into blocks of `block` seconds and every
/// `every`-th block (the last of each run of `every`) is held out. Whole blocks, not single
/// detections, are held out because detections a second apart are near copies of each other.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldOut {
    /// Block length, seconds (> 0).
    pub block: f64,
    /// One block in `every` is held out (≥ 2).
    pub every: usize,
}

impl Default for HoldOut {
    /// Blocks of 10 minutes, one in five held out.
    fn default() -> Self {
        Self {
            block: 600.0,
            every: 5,
        }
    }
}

impl HoldOut {
    /// The rules, checked: `block` finite and > 0, `every ≥ 2`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if !(self.block.is_finite() && self.block > 0.0) {
            return Err(AffordanceError::InvalidParameter {
                name: "block",
                value: self.block,
                rule: "must be finite and > 0 s",
            });
        }
        if self.every < 2 {
            return Err(AffordanceError::InvalidParameter {
                name: "every",
                value: self.every as f64,
                rule: "must be >= 2",
            });
        }
        Ok(self)
    }

    /// `(kept, held out)`, each in input order.
    ///
    /// # Errors
    /// [`AffordanceError::EmptyHoldOut`] if either side is empty.
    pub fn split(&self, points: &[TimedPoint]) -> Result<(Vec<TimedPoint>, Vec<TimedPoint>)> {
        let every = self.every as f64;
        let (held, kept): (Vec<TimedPoint>, Vec<TimedPoint>) = points
            .iter()
            .partition(|p| (p.time / self.block).floor().rem_euclid(every) == every - 1.0);
        if held.is_empty() || kept.is_empty() {
            return Err(AffordanceError::EmptyHoldOut {
                points: points.len(),
            });
        }
        Ok((kept, held))
    }
}

/// FreMEn period selection (Krajník et al., "FreMEn", IEEE T-RO 2017, applied as seed 001's
/// outlook proposes): starting from the validated periods, repeatedly take the candidate
/// period at which the spectrum of the current model's residual has the largest amplitude,
/// and keep it while it passes the [`CycleValidation`] (the training data span at least
/// `min_cycles` of its cycles and leaving whole cycles out, the likelihood rises by more than
/// the margin). Candidates the data cannot validate (fewer cycles) are not tried.
///
/// **The residual.** Detections are events, not a sampled state, so the signal is *where*
/// people are: each detection `j` is labelled with the cluster `c(j)` of its largest
/// membership in the starting model (spatial cells when it starts without periods). The
/// current model predicts, at `tⱼ`, the distribution of labels `qⱼ = Σₗ wₗ(tⱼ) aₗ`, with
/// `wₗ(t)` its component weights at `t` and `aₗ` the share of cluster `l`'s membership
/// falling on each label. The residual is `rⱼ = e_{c(j)} − qⱼ` (for the model without periods,
/// the label indicators minus their mean, FreMEn's first step) and the amplitude at period
/// `T` is `|(1/n) Σⱼ rⱼ e^{−2πi tⱼ/T}|` (Euclidean norm over labels).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodSearch {
    /// Candidate periods, seconds (each finite, > 0).
    pub candidates: Vec<f64>,
    /// At most this many periods are added.
    pub max_periods: usize,
}

impl Default for PeriodSearch {
    /// FreMEn's usual candidates `T = 1 day / k`, `k = 1…24` (a day down to an hour); up to 3
    /// periods.
    fn default() -> Self {
        Self {
            candidates: (1..=24).map(|k| DAY / k as f64).collect(),
            max_periods: 3,
        }
    }
}

impl PeriodSearch {
    /// The rules, checked: finite positive candidates.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if let Some(&bad) = self
            .candidates
            .iter()
            .find(|p| !(p.is_finite() && **p > 0.0))
        {
            return Err(AffordanceError::InvalidParameter {
                name: "candidates",
                value: bad,
                rule: "every candidate period must be finite and > 0 s",
            });
        }
        Ok(self)
    }
}

/// What to do with a given period ([`HypertimeParams::periods`]) that the validation rejects
/// or cannot check.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GivenPeriods {
    /// Keep every given period unchecked (seed 001: the daily period is chosen a priori).
    Trust,
    /// Validate those the data can check (dropping the rejected ones) and keep those spanning
    /// fewer than `min_cycles` cycles as given (default: one day of training data cannot check
    /// a daily period, and on the real people data the daily period trained on one day still
    /// predicts the next better than the static model, `BENCHMARKS.md`).
    KeepUnverifiable,
    /// Keep a given period only if it is validated.
    Validate,
}

/// Validation of periods across cycles: a period `T` is accepted only when the training data
/// fall in at least `min_cycles` of its cycles (distinct `⌊t / T⌋`; for a day, UTC days) and
/// the likelihood of whole held-out cycles rises by more than `margin` nats per detection when
/// `T` is added. The cycles, in order, are dealt round robin into
/// `F = min(max_folds, cycles)` folds (leave-one-cycle-out when there are at most `max_folds`
/// cycles); each fold is scored by the models, with and without `T`, fitted on the others,
/// and the gain is the difference of the mean log-likelihoods over all held-out detections.
/// A pattern seen in one cycle only cannot pass: the held-out cycle must show it again.
/// The margin and folds are chosen a priori (never on test data).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleValidation {
    /// Minimum gain of held-out mean log-likelihood, nats per detection (finite, `≥ 0`,
    /// default 0.02).
    pub margin: f64,
    /// Cycles the data must span (`≥ 2`, default 2).
    pub min_cycles: usize,
    /// At most this many folds (`≥ 2`, default 3: each fold costs two fits).
    pub max_folds: usize,
    /// What happens to the given periods (default [`GivenPeriods::KeepUnverifiable`]).
    pub given: GivenPeriods,
}

impl Default for CycleValidation {
    /// A margin of 0.02 nats, two cycles, three folds, given periods kept when unverifiable.
    fn default() -> Self {
        Self {
            margin: 0.02,
            min_cycles: 2,
            max_folds: 3,
            given: GivenPeriods::KeepUnverifiable,
        }
    }
}

impl CycleValidation {
    /// Sets the margin, nats per detection.
    pub fn with_margin(mut self, margin: f64) -> Self {
        self.margin = margin;
        self
    }
    /// Sets the policy for given periods.
    pub fn with_given(mut self, given: GivenPeriods) -> Self {
        self.given = given;
        self
    }
    /// The rules, checked: `margin` finite and `≥ 0`, `min_cycles ≥ 2`, `max_folds ≥ 2`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return Err(AffordanceError::InvalidParameter {
                name: "margin",
                value: self.margin,
                rule: "must be finite and >= 0",
            });
        }
        for (name, value) in [
            ("min_cycles", self.min_cycles),
            ("max_folds", self.max_folds),
        ] {
            if value < 2 {
                return Err(AffordanceError::InvalidParameter {
                    name,
                    value: value as f64,
                    rule: "must be >= 2",
                });
            }
        }
        Ok(self)
    }
}

/// The choice of the spatial floor and of the background's weight: the model is fitted on
/// the kept blocks of the training data and, for every floor and weight, scored on the
/// held-out blocks; the best pair wins (the first in the lists' order on ties). Only the
/// training data are used. When the split leaves too little to fit, the values of
/// [`HypertimeParams::spatial_floor`] and [`Background::weight`](super::Background::weight)
/// are used and the report says so.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// Candidate floors, metres (finite, `≥ 0`; default 0.05, 0.1, 0.2, 0.3, 0.5: from
    /// below to well above the decimetre of a laser person detector).
    pub floors: Vec<f64>,
    /// Candidate background weights in `[0, 1)` (default 0, 0.001, 0.003, 0.01, 0.03, 0.1,
    /// 0.3).
    pub weights: Vec<f64>,
    /// The held-out split (default one-hour blocks, one in three held out: longer than the
    /// search's ten minutes, so that held-out blocks can show places the kept ones did not).
    pub holdout: HoldOut,
}

impl Default for Calibration {
    /// See the fields.
    fn default() -> Self {
        Self {
            floors: vec![0.05, 0.1, 0.2, 0.3, 0.5],
            weights: vec![0.0, 0.001, 0.003, 0.01, 0.03, 0.1, 0.3],
            holdout: HoldOut {
                block: 3600.0,
                every: 3,
            },
        }
    }
}

impl Calibration {
    /// The rules, checked: at least one floor and one weight, floors finite and `≥ 0`,
    /// weights in `[0, 1)`, the split's rules.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if self.floors.is_empty() || self.weights.is_empty() {
            return Err(AffordanceError::InvalidParameter {
                name: "calibration",
                value: 0.0,
                rule: "needs at least one floor and one weight",
            });
        }
        if let Some(&bad) = self.floors.iter().find(|f| !(f.is_finite() && **f >= 0.0)) {
            return Err(AffordanceError::InvalidParameter {
                name: "floors",
                value: bad,
                rule: "every floor must be finite and >= 0 m",
            });
        }
        if let Some(&bad) = self.weights.iter().find(|w| !(0.0..1.0).contains(*w)) {
            return Err(AffordanceError::InvalidParameter {
                name: "weights",
                value: bad,
                rule: "every weight must be in [0, 1)",
            });
        }
        self.holdout.check()?;
        Ok(self)
    }
}

/// The choice of `k` by held-out likelihood: each candidate is fitted on the kept part and
/// scored on the held-out part; the best score wins (the smaller `k` on ties).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct ClusterSearch {
    /// Candidate numbers of clusters (those above the number of kept points are skipped).
    pub candidates: Vec<usize>,
    /// The held-out split.
    pub holdout: HoldOut,
}

impl Default for ClusterSearch {
    /// `k ∈ {5, 10, 20, 30, 40, 60}` and the default [`HoldOut`].
    fn default() -> Self {
        Self {
            candidates: vec![5, 10, 20, 30, 40, 60],
            holdout: HoldOut::default(),
        }
    }
}

impl ClusterSearch {
    /// The rules, checked: at least one candidate, all ≥ 1, the split's rules.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if self.candidates.is_empty() || self.candidates.contains(&0) {
            return Err(AffordanceError::InvalidParameter {
                name: "candidates",
                value: 0.0,
                rule: "needs at least one candidate, each >= 1",
            });
        }
        self.holdout.check()?;
        Ok(self)
    }
}

/// One period checked by the [`CycleValidation`]: a given period, or one the
/// [`PeriodSearch`] proposed.
///
/// With the `serde` feature, a non-finite amplitude or score is written as `"inf"`, `"-inf"`
/// or `"NaN"` in human-readable formats, a missing one as `null`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodStep {
    /// The period, seconds.
    pub period: f64,
    /// Its amplitude in the residual spectrum (`None` for a given period).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub amplitude: Option<f64>,
    /// Cycles of it that hold training data (distinct `⌊t / T⌋`: for a day, UTC days).
    pub cycles: usize,
    /// Held-out (left-out cycles) mean log-likelihood without it (`None` when not checked).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub without_loglik: Option<f64>,
    /// Held-out mean log-likelihood with it (`None` when not checked).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub heldout_loglik: Option<f64>,
    /// Whether it passed the validation.
    pub accepted: bool,
    /// Whether the model kept it (accepted, or given and kept by [`GivenPeriods`]).
    pub kept: bool,
}

/// What the calibration chose (see [`Calibration`]).
///
/// With the `serde` feature, a non-finite score is written as a string.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationReport {
    /// The floor chosen, metres.
    pub floor: f64,
    /// The background weight chosen.
    pub weight: f64,
    /// Its held-out mean log-likelihood (`None` when the split left too little to fit and
    /// the parameters' values were used).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub heldout_loglik: Option<f64>,
    /// Held-out detections it was scored on.
    pub heldout: usize,
}

/// What the searches did.
///
/// With the `serde` feature, a non-finite score is written as `"inf"`, `"-inf"` or `"NaN"`
/// in human-readable formats.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Selection {
    /// The calibration of the floor and the background's weight (`None` without it).
    #[cfg_attr(feature = "serde", serde(default))]
    pub calibration: Option<CalibrationReport>,
    /// Every period checked, given ones first, then the search's, in order.
    pub period_steps: Vec<PeriodStep>,
    /// `(k, held-out mean log-likelihood)` of each candidate tried.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_support::lenient_pairs"))]
    pub cluster_scores: Vec<(usize, f64)>,
}

impl Selection {
    /// Whether no period passed the validation (the model then has only the given periods
    /// kept unverified, or none: the static model).
    pub fn no_period_validated(&self) -> bool {
        !self.period_steps.iter().any(|s| s.accepted)
    }
}

/// Runs the calibration, the validation of the given periods and the searches that
/// `params` asks for; returns the periods, the clustering parameters, the floor and
/// background weight, and what was tried.
pub(crate) fn choose(
    points: &[TimedPoint],
    params: &HypertimeParams,
) -> Result<(Vec<f64>, GkParams, Tuning, Selection)> {
    let mut selection = Selection::default();
    let mut gk = params.gk;
    let (mut tuning, report) = calibrate(points, &params.periods, &gk, params)?;
    selection.calibration = report;
    let validation = params.validation;
    let cycles = |period: f64| cycles_of(points, period).len();
    let mut periods: Vec<f64> = Vec::new();
    for &period in &params.periods {
        let cycles = cycles(period);
        let checkable = cycles >= validation.min_cycles;
        let mut step = PeriodStep {
            period,
            amplitude: None,
            cycles,
            without_loglik: None,
            heldout_loglik: None,
            accepted: false,
            kept: false,
        };
        if validation.given != GivenPeriods::Trust && checkable {
            let (without, with) = cycle_scores(points, &periods, period, &gk, params, tuning)?;
            step.without_loglik = Some(without);
            step.heldout_loglik = Some(with);
            step.accepted = with > without + validation.margin;
        }
        step.kept = match validation.given {
            GivenPeriods::Trust => true,
            GivenPeriods::KeepUnverifiable => step.accepted || !checkable,
            GivenPeriods::Validate => step.accepted,
        };
        if step.kept {
            periods.push(period);
        }
        selection.period_steps.push(step);
    }
    if let Some(search) = &params.period_search {
        let mut current = fit_once(points, periods.clone(), &gk, params, tuning)?;
        let labels = current.clustering.hard_labels();
        let mut added = 0;
        while added < search.max_periods {
            let candidates: Vec<f64> = search
                .candidates
                .iter()
                .copied()
                .filter(|&c| !periods.contains(&c) && cycles(c) >= validation.min_cycles)
                .collect();
            let amplitudes = residual_spectrum(&current, points, &labels, gk.clusters, &candidates);
            let Some((period, amplitude)) = candidates.iter().zip(&amplitudes).fold(
                None,
                |best: Option<(f64, f64)>, (&p, &a)| match best {
                    Some((_, b)) if b >= a => best,
                    _ => Some((p, a)),
                },
            ) else {
                break;
            };
            let (without, with) = cycle_scores(points, &periods, period, &gk, params, tuning)?;
            let accepted = with > without + validation.margin;
            selection.period_steps.push(PeriodStep {
                period,
                amplitude: Some(amplitude),
                cycles: cycles(period),
                without_loglik: Some(without),
                heldout_loglik: Some(with),
                accepted,
                kept: accepted,
            });
            if !accepted {
                break;
            }
            periods.push(period);
            current = fit_once(points, periods.clone(), &gk, params, tuning)?;
            added += 1;
        }
    }
    if let Some(search) = &params.cluster_search {
        // Whole cycles of the longest validated period are held out when there is one;
        // otherwise the search's blocks.
        let longest = selection
            .period_steps
            .iter()
            .filter(|s| s.accepted)
            .map(|s| s.period)
            .fold(None, |a: Option<f64>, p| Some(a.map_or(p, |a| a.max(p))));
        let folds: Vec<(Vec<TimedPoint>, Vec<TimedPoint>)> = match longest {
            Some(period) => cycle_folds(points, period, validation.max_folds),
            None => vec![search.holdout.split(points)?],
        };
        let smallest_kept = folds.iter().map(|(k, _)| k.len()).min().unwrap_or(0);
        let mut candidates: Vec<usize> = search
            .candidates
            .iter()
            .copied()
            .filter(|&k| k <= smallest_kept)
            .collect();
        candidates.sort_unstable();
        candidates.dedup();
        if candidates.is_empty() {
            return Err(AffordanceError::TooFewPoints {
                points: smallest_kept,
                clusters: search.candidates.iter().copied().min().unwrap_or(1),
            });
        }
        let mut best: Option<(usize, f64)> = None;
        for k in candidates {
            let score = folds_score(&folds, &periods, &gk.with_clusters(k), params, tuning)?;
            selection.cluster_scores.push((k, score));
            if best.is_none_or(|(_, b)| score > b) {
                best = Some((k, score));
            }
        }
        if let Some((k, _)) = best {
            gk.clusters = k;
        }
    }
    if periods != params.periods || gk.clusters != params.gk.clusters {
        let (t, report) = calibrate(points, &periods, &gk, params)?;
        tuning = t;
        selection.calibration = report;
    }
    Ok((periods, gk, tuning, selection))
}

/// The distinct cycles `⌊t / T⌋` of `period` that hold points, in increasing order.
fn cycles_of(points: &[TimedPoint], period: f64) -> Vec<i64> {
    let mut c: Vec<i64> = points
        .iter()
        .map(|p| (p.time / period).floor() as i64)
        .collect();
    c.sort_unstable();
    c.dedup();
    c
}

/// The folds of whole cycles of `period` (see [`CycleValidation`]): `(kept, held out)`
/// each, in input order; folds with an empty side are left out.
fn cycle_folds(
    points: &[TimedPoint],
    period: f64,
    max_folds: usize,
) -> Vec<(Vec<TimedPoint>, Vec<TimedPoint>)> {
    let cycles = cycles_of(points, period);
    let folds = cycles.len().clamp(1, max_folds);
    let fold_of = |p: &TimedPoint| {
        let c = (p.time / period).floor() as i64;
        cycles.binary_search(&c).unwrap_or(0) % folds
    };
    (0..folds)
        .map(|f| {
            points
                .iter()
                .partition::<Vec<TimedPoint>, _>(|p| fold_of(p) != f)
        })
        .filter(|(kept, held)| !kept.is_empty() && !held.is_empty())
        .collect()
}

/// The mean log-likelihood over all held-out detections of the folds, each fold scored by
/// the model fitted on its kept side.
fn folds_score(
    folds: &[(Vec<TimedPoint>, Vec<TimedPoint>)],
    periods: &[f64],
    gk: &GkParams,
    params: &HypertimeParams,
    tuning: Tuning,
) -> Result<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for (kept, held) in folds {
        let model = fit_once(kept, periods.to_vec(), gk, params, tuning)?.model;
        if let Some((mean, count)) = model.mean_log_likelihood(held) {
            sum += mean * count as f64;
            n += count;
        }
    }
    Ok(if n > 0 {
        sum / n as f64
    } else {
        f64::NEG_INFINITY
    })
}

/// Left-out-cycle mean log-likelihoods of the model with `periods` and with `periods` plus
/// `period`, on the folds of `period`'s cycles. A fold too small to fit scores −∞ for both.
fn cycle_scores(
    points: &[TimedPoint],
    periods: &[f64],
    period: f64,
    gk: &GkParams,
    params: &HypertimeParams,
    tuning: Tuning,
) -> Result<(f64, f64)> {
    let folds = cycle_folds(points, period, params.validation.max_folds);
    let mut with = periods.to_vec();
    with.push(period);
    let score = |p: &[f64]| match folds_score(&folds, p, gk, params, tuning) {
        Err(AffordanceError::TooFewPoints { .. }) => Ok(f64::NEG_INFINITY),
        other => other,
    };
    Ok((score(periods)?, score(&with)?))
}

/// The floor and background weight (see [`Calibration`]) for the model with `periods` and
/// `gk`, chosen on held-out blocks of `points`.
fn calibrate(
    points: &[TimedPoint],
    periods: &[f64],
    gk: &GkParams,
    params: &HypertimeParams,
) -> Result<(Tuning, Option<CalibrationReport>)> {
    let fallback = Tuning::of(params);
    let Some(calibration) = &params.calibration else {
        return Ok((fallback, None));
    };
    let unfitted = |t: Tuning| CalibrationReport {
        floor: t.floor,
        weight: t.background,
        heldout_loglik: None,
        heldout: 0,
    };
    let Ok((kept, held)) = calibration.holdout.split(points) else {
        return Ok((fallback, Some(unfitted(fallback))));
    };
    let fitted = match fit_once(&kept, periods.to_vec(), gk, params, fallback) {
        Ok(f) => f,
        Err(AffordanceError::TooFewPoints { .. }) => {
            return Ok((fallback, Some(unfitted(fallback))));
        }
        Err(e) => return Err(e),
    };
    let weights: Vec<f64> = if params.background.is_some() {
        calibration.weights.clone()
    } else {
        vec![0.0]
    };
    let mut best: Option<(Tuning, f64)> = None;
    for &floor in &calibration.floors {
        // The mixture alone and the background alone (weight 1 − 0 and 1 in log terms).
        let mixture = fitted.retune(
            params,
            Tuning {
                floor,
                background: 0.0,
            },
        )?;
        let background = params.background.and_then(|b| {
            super::model::BackgroundDensity::over(fitted.positions(), floor, b.with_weight(0.5))
        });
        let parts: Vec<Option<(f64, f64)>> = map_slice(&held, |p| {
            let m = mixture.log_density(p)?;
            let b = background.map_or(f64::NEG_INFINITY, |b| {
                b.log_value(p.position) // ln t_ν(p)
            });
            Some((m, b))
        });
        for &w in &weights {
            let (lm, lb) = ((-w).ln_1p(), w.ln());
            let (sum, n) = parts
                .iter()
                .flatten()
                .fold((0.0, 0usize), |(s, n), (m, b)| {
                    (s + log_add_exp(lm + m, lb + b), n + 1)
                });
            if n == 0 {
                continue;
            }
            let score = sum / n as f64;
            if best.is_none_or(|(_, b)| score > b) {
                best = Some((
                    Tuning {
                        floor,
                        background: w,
                    },
                    score,
                ));
            }
        }
    }
    Ok(match best {
        Some((t, score)) => (
            t,
            Some(CalibrationReport {
                floor: t.floor,
                weight: t.background,
                heldout_loglik: Some(score),
                heldout: held.len(),
            }),
        ),
        None => (fallback, Some(unfitted(fallback))),
    })
}

/// The amplitude of the residual spectrum (see [`PeriodSearch`]) at each candidate period.
fn residual_spectrum(
    current: &Fitted,
    points: &[TimedPoint],
    labels: &[usize],
    n_labels: usize,
    candidates: &[f64],
) -> Vec<f64> {
    let clustering = &current.clustering;
    let k = clustering.clusters();
    // a[l][i]: the share of cluster l's membership that falls on label i.
    let mut share = vec![0.0; k * n_labels];
    let mut totals = vec![0.0; k];
    for (u, &label) in clustering.memberships().chunks_exact(k).zip(labels) {
        for (l, &v) in u.iter().enumerate() {
            share[l * n_labels + label] += v;
            totals[l] += v;
        }
    }
    for (l, t) in totals.iter().enumerate() {
        if *t > 0.0 {
            share[l * n_labels..(l + 1) * n_labels]
                .iter_mut()
                .for_each(|s| *s /= t);
        }
    }
    // q_j: the predicted label distribution at each detection's time.
    let predicted: Vec<Vec<f64>> = map_slice(points, |p| {
        let mut q = vec![0.0; n_labels];
        let snapshot = current.model.at(p.time);
        for (l, (w, _)) in snapshot.weights().iter().enumerate() {
            if *w > 0.0 {
                for (qi, a) in q.iter_mut().zip(&share[l * n_labels..(l + 1) * n_labels]) {
                    *qi += w * a;
                }
            }
        }
        q
    });
    let n = points.len() as f64;
    map_slice(candidates, |&period| {
        // Blockwise complex sums per label, added in block order.
        let mut re = vec![0.0; n_labels];
        let mut im = vec![0.0; n_labels];
        for (pts, (qs, ls)) in points
            .chunks(BLOCK)
            .zip(predicted.chunks(BLOCK).zip(labels.chunks(BLOCK)))
        {
            let mut bre = vec![0.0; n_labels];
            let mut bim = vec![0.0; n_labels];
            for (p, (q, &label)) in pts.iter().zip(qs.iter().zip(ls)) {
                let phase = std::f64::consts::TAU * (p.time.rem_euclid(period) / period);
                let (s, c) = phase.sin_cos();
                for (i, qi) in q.iter().enumerate() {
                    let r = if i == label { 1.0 - qi } else { -qi };
                    bre[i] += r * c;
                    bim[i] -= r * s;
                }
            }
            re.iter_mut().zip(&bre).for_each(|(a, b)| *a += b);
            im.iter_mut().zip(&bim).for_each(|(a, b)| *a += b);
        }
        re.iter()
            .zip(&im)
            .map(|(a, b)| a * a + b * b)
            .sum::<f64>()
            .sqrt()
            / n
    })
}
