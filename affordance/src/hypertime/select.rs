//! Choosing the hypertime model's periods (FreMEn on the residual of the model) and its number
//! of clusters, both by held-out likelihood.

use super::gk::{BLOCK, GkParams};
use super::model::{Fitted, HypertimeModel, HypertimeParams, fit_once, map_slice};
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
/// outlook proposes): starting from the given periods, repeatedly take the candidate period at
/// which the spectrum of the current model's residual has the largest amplitude, and keep it
/// while the held-out log-likelihood rises by more than `min_gain`.
///
/// **The residual.** Detections are events, not a sampled state, so the signal is *where*
/// people are: each kept detection `j` is labelled with the cluster `c(j)` of its largest
/// membership in the starting model (spatial cells when it starts without periods). The
/// current model predicts, at `tⱼ`, the distribution of labels `qⱼ = Σₗ wₗ(tⱼ) aₗ`, with
/// `wₗ(t)` its component weights at `t` and `aₗ` the share of cluster `l`'s membership
/// falling on each label. The residual is `rⱼ = e_{c(j)} − qⱼ` (for the model without periods,
/// the label indicators minus their mean, FreMEn's first step) and the amplitude at period
/// `T` is `|(1/n) Σⱼ rⱼ e^{−2πi tⱼ/T}|` (Euclidean norm over labels).
///
/// Held-out blocks are interleaved with kept ones, so a period is validated within the span
/// of the data: the data must cover several cycles of a period for the search to tell a
/// rhythm from a pattern that happened once (one day of data cannot confirm a daily period,
/// and may keep a shorter one that does not recur the next day).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodSearch {
    /// Candidate periods, seconds (each finite, > 0).
    pub candidates: Vec<f64>,
    /// At most this many periods are added.
    pub max_periods: usize,
    /// A period is kept only if the held-out mean log-likelihood rises by more than this
    /// (nats per detection, ≥ 0).
    pub min_gain: f64,
    /// The held-out split.
    pub holdout: HoldOut,
}

impl Default for PeriodSearch {
    /// FreMEn's usual candidates `T = 1 day / k`, `k = 1…24` (a day down to an hour); up to 3
    /// periods; any gain; the default [`HoldOut`].
    fn default() -> Self {
        Self {
            candidates: (1..=24).map(|k| DAY / k as f64).collect(),
            max_periods: 3,
            min_gain: 0.0,
            holdout: HoldOut::default(),
        }
    }
}

impl PeriodSearch {
    /// The rules, checked: finite positive candidates, `min_gain ≥ 0` finite, the split's rules.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(&self) -> Result<()> {
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
        if !(self.min_gain.is_finite() && self.min_gain >= 0.0) {
            return Err(AffordanceError::InvalidParameter {
                name: "min_gain",
                value: self.min_gain,
                rule: "must be finite and >= 0",
            });
        }
        self.holdout.check()?;
        Ok(())
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
    pub fn check(&self) -> Result<()> {
        if self.candidates.is_empty() || self.candidates.contains(&0) {
            return Err(AffordanceError::InvalidParameter {
                name: "candidates",
                value: 0.0,
                rule: "needs at least one candidate, each >= 1",
            });
        }
        self.holdout.check()?;
        Ok(())
    }
}

/// One period tried by the [`PeriodSearch`].
///
/// With the `serde` feature, a non-finite amplitude or score is written as `"inf"`, `"-inf"`
/// or `"NaN"` in human-readable formats.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodStep {
    /// The period, seconds.
    pub period: f64,
    /// Its amplitude in the residual spectrum.
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub amplitude: f64,
    /// Held-out mean log-likelihood of the model with it.
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub heldout_loglik: f64,
    /// Whether it was kept.
    pub accepted: bool,
}

/// What the searches did.
///
/// With the `serde` feature, a non-finite score is written as `"inf"`, `"-inf"` or `"NaN"`
/// in human-readable formats.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Selection {
    /// Held-out mean log-likelihood of the starting periods (period search only).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub start_loglik: Option<f64>,
    /// The periods tried, in order.
    pub period_steps: Vec<PeriodStep>,
    /// `(k, held-out mean log-likelihood)` of each candidate tried.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_support::lenient_pairs"))]
    pub cluster_scores: Vec<(usize, f64)>,
}

fn heldout(model: &HypertimeModel, held: &[TimedPoint]) -> f64 {
    model
        .mean_log_likelihood(held)
        .map_or(f64::NEG_INFINITY, |(m, _)| m)
}

/// Runs the searches that `params` asks for; returns the periods, the clustering parameters
/// and what was tried.
pub(crate) fn choose(
    points: &[TimedPoint],
    params: &HypertimeParams,
) -> Result<(Vec<f64>, GkParams, Selection)> {
    let mut selection = Selection::default();
    let mut periods = params.periods.clone();
    let mut gk = params.gk;
    if let Some(search) = &params.period_search {
        let (kept, held) = search.holdout.split(points)?;
        let mut current = fit_once(&kept, periods.clone(), &gk, params)?;
        let labels = current.clustering.hard_labels();
        let mut best = heldout(&current.model, &held);
        selection.start_loglik = Some(best);
        let mut added = 0;
        while added < search.max_periods {
            let candidates: Vec<f64> = search
                .candidates
                .iter()
                .copied()
                .filter(|c| !periods.contains(c))
                .collect();
            let amplitudes = residual_spectrum(&current, &kept, &labels, gk.clusters, &candidates);
            let Some((period, amplitude)) = candidates.iter().zip(&amplitudes).fold(
                None,
                |best: Option<(f64, f64)>, (&p, &a)| match best {
                    Some((_, b)) if b >= a => best,
                    _ => Some((p, a)),
                },
            ) else {
                break;
            };
            let mut trial_periods = periods.clone();
            trial_periods.push(period);
            let trial = fit_once(&kept, trial_periods.clone(), &gk, params)?;
            let score = heldout(&trial.model, &held);
            let accepted = score > best + search.min_gain;
            selection.period_steps.push(PeriodStep {
                period,
                amplitude,
                heldout_loglik: score,
                accepted,
            });
            if !accepted {
                break;
            }
            periods = trial_periods;
            current = trial;
            best = score;
            added += 1;
        }
    }
    if let Some(search) = &params.cluster_search {
        let (kept, held) = search.holdout.split(points)?;
        let mut candidates: Vec<usize> = search
            .candidates
            .iter()
            .copied()
            .filter(|&k| k <= kept.len())
            .collect();
        candidates.sort_unstable();
        candidates.dedup();
        if candidates.is_empty() {
            return Err(AffordanceError::TooFewPoints {
                points: kept.len(),
                clusters: search.candidates.iter().copied().min().unwrap_or(1),
            });
        }
        let mut best: Option<(usize, f64)> = None;
        for k in candidates {
            let fitted = fit_once(&kept, periods.clone(), &gk.with_clusters(k), params)?;
            let score = heldout(&fitted.model, &held);
            selection.cluster_scores.push((k, score));
            if best.is_none_or(|(_, b)| score > b) {
                best = Some((k, score));
            }
        }
        if let Some((k, _)) = best {
            gk.clusters = k;
        }
    }
    Ok((periods, gk, selection))
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
