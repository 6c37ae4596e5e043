//! Choosing the hypertime model's periods (FreMEn on the residual of the model) and its number
//! of clusters, both by held-out likelihood.

use super::fit::{Fitted, Tuning, fit_once};
use super::gk::{BLOCK, GkParams};
use super::model::{HypertimeModel, UniformDensity, log_add_exp};
use super::params::{CalibrationReport, GivenPeriods, HypertimeParams, PeriodStep, Selection};
use super::projection::TimedPoint;
use crate::parallel::{join, map_slice};
use crate::{AffordanceError, Result};

impl HypertimeModel {
    /// Fits the model to detections (seed 001): projects them to hypertime (non-finite ones are
    /// skipped and counted), clusters them with [`GkParams::fit`], builds the mixture and its
    /// conditionals (see the type's docs). With a period or cluster search, those run first on
    /// a held-out split of `points` and the final model is fitted on all of them.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] for bad parameters;
    /// [`AffordanceError::TooFewPoints`] when fewer finite points than clusters remain;
    /// [`AffordanceError::EmptyHoldOut`] when a search's split leaves one side empty; the
    /// the clustering's errors ([`AffordanceError::NotConverged`] only with
    /// [`require_convergence`](HypertimeParams::require_convergence); it carries the clustering
    /// in the standardised space it ran in).
    ///
    /// # Complexity
    /// One clustering (`O(n·k·d²)` per iteration), plus one per period tried and per `k`
    /// candidate with the searches; with the `rayon` feature the folds of a validation, its
    /// two sides and the `k` candidates are fitted side by side (the result is the same).
    ///
    /// ```
    /// use haunts_affordance::hypertime::{HypertimeModel, HypertimeParams, TimedPoint};
    /// use haunts_affordance::DensityMap;
    /// use nalgebra::Point2;
    /// // Mornings at (0, 0), afternoons at (10, 0), over three days.
    /// let mut points = Vec::new();
    /// for day in 0..3 {
    ///     for i in 0..60 {
    ///         let t = day as f64 * 86_400.0 + 9.0 * 3600.0 + i as f64 * 60.0;
    ///         let jitter = (i % 7) as f64 * 0.1;
    ///         points.push(TimedPoint::new(t, jitter, jitter));
    ///         points.push(TimedPoint::new(t + 5.0 * 3600.0, 10.0 + jitter, jitter));
    ///     }
    /// }
    /// let params = HypertimeParams::default().with_clusters(4);
    /// let model = HypertimeModel::fit(&points, &params)?;
    /// let morning = model.at(9.5 * 3600.0);
    /// let here = morning.density_at(Point2::new(0.3, 0.3)).unwrap();
    /// let there = morning.density_at(Point2::new(10.3, 0.3)).unwrap();
    /// // The background keeps a little density everywhere, so "not there" is a ratio, not 0.
    /// assert!(here > 10.0 * there);
    /// assert!(model.report().selection.period_steps[0].accepted); // three days: validated
    /// # Ok::<(), haunts_affordance::AffordanceError>(())
    /// ```
    pub fn fit(points: &[TimedPoint], params: &HypertimeParams) -> Result<Self> {
        let params = params.clone().check()?;
        let finite: Vec<TimedPoint> = points.iter().copied().filter(|p| p.is_finite()).collect();
        let skipped = points.len() - finite.len();
        let (periods, gk, tuning, selection) = super::select::choose(&finite, &params)?;
        let mut fitted = fit_once(&finite, periods, &gk, &params, tuning)?;
        fitted.model.report.skipped = skipped;
        fitted.model.report.selection = selection;
        Ok(fitted.model)
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
    let blocks = |period: f64| Blocks::of(points, validation.block.max(period)).count();
    let checkable = |period: f64| cycles(period) >= validation.min_cycles && blocks(period) >= 2;
    let mut periods: Vec<f64> = Vec::new();
    for &period in &params.periods {
        let checkable = checkable(period);
        let mut step = PeriodStep {
            period,
            amplitude: None,
            cycles: cycles(period),
            blocks: blocks(period),
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
    // No starting fit when no candidate can be checked (one day of training data).
    let search = params
        .period_search
        .as_ref()
        .filter(|s| s.candidates.iter().any(|&c| checkable(c)));
    if let Some(search) = search {
        let mut current = fit_once(points, periods.clone(), &gk, params, tuning)?;
        let labels = current.clustering.hard_labels();
        let mut added = 0;
        while added < search.max_periods {
            let candidates: Vec<f64> = search
                .candidates
                .iter()
                .copied()
                .filter(|&c| !periods.contains(&c) && checkable(c))
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
                blocks: blocks(period),
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
        // Whole blocks (of at least the longest validated period) are held out when the
        // data span two; otherwise the search's split.
        let longest = selection
            .period_steps
            .iter()
            .filter(|s| s.accepted)
            .map(|s| s.period)
            .fold(validation.block, f64::max);
        let folds = block_folds(points, longest, validation.max_folds);
        let folds = if folds.is_empty() {
            vec![search.holdout.split(points)?]
        } else {
            folds
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
        // Every candidate's folds side by side; chosen in increasing k as before.
        let scores = map_slice(&candidates, |&k| {
            folds_score(&folds, &periods, &gk.with_clusters(k), params, tuning)
        });
        let mut best: Option<(usize, f64)> = None;
        for (k, score) in candidates.into_iter().zip(scores) {
            let score = score?;
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

/// The held-out blocks of [`CycleValidation`](super::CycleValidation): time cut into blocks of `length` seconds
/// starting at the quietest time of `length` in the data. Also the held-out days of the rate
/// check ([`DailyRate::check_across_days`](crate::activity_at::DailyRate::check_across_days)).
pub(crate) struct Blocks {
    length: f64,
    offset: f64,
    /// The distinct blocks holding points, in increasing order.
    ids: Vec<i64>,
}

impl Blocks {
    /// Bins of the data folded onto the block length, to find its quietest time.
    const BINS: usize = 96;

    /// The blocks of `length` seconds (finite, `> 0`) of `points` (finite times).
    pub(crate) fn of(points: &[TimedPoint], length: f64) -> Self {
        let bin = length / Self::BINS as f64;
        let mut counts = [0usize; Self::BINS];
        for p in points {
            counts[((p.time.rem_euclid(length) / bin) as usize).min(Self::BINS - 1)] += 1;
        }
        // The middle of the longest circular run of empty bins, else of the emptiest bin.
        let (mut best, mut run) = ((0usize, 0usize), 0usize);
        for i in 0..2 * Self::BINS {
            run = if counts[i % Self::BINS] == 0 {
                run + 1
            } else {
                0
            };
            if run > best.1 && run <= Self::BINS {
                best = (i, run);
            }
        }
        let middle = if best.1 > 0 {
            (best.0 + 1) as f64 - best.1 as f64 / 2.0
        } else {
            let (i, _) =
                counts.iter().enumerate().fold(
                    (0, usize::MAX),
                    |b, (i, &c)| if c < b.1 { (i, c) } else { b },
                );
            i as f64 + 0.5
        };
        let offset = (middle * bin).rem_euclid(length);
        let mut blocks = Self {
            length,
            offset,
            ids: Vec::new(),
        };
        let mut ids: Vec<i64> = points.iter().map(|p| blocks.id(p)).collect();
        ids.sort_unstable();
        ids.dedup();
        blocks.ids = ids;
        blocks
    }

    fn id(&self, p: &TimedPoint) -> i64 {
        self.id_at(p.time)
    }

    /// The block of time `t`.
    pub(crate) fn id_at(&self, t: f64) -> i64 {
        ((t - self.offset) / self.length).floor() as i64
    }

    /// The blocks holding points, in increasing order.
    pub(crate) fn ids(&self) -> &[i64] {
        &self.ids
    }

    fn count(&self) -> usize {
        self.ids.len()
    }
}

/// The folds of whole blocks of `length` seconds (see
/// [`CycleValidation`](super::CycleValidation)): `(kept, held out)` each, in input order;
/// none when the data lie in one block.
fn block_folds(
    points: &[TimedPoint],
    length: f64,
    max_folds: usize,
) -> Vec<(Vec<TimedPoint>, Vec<TimedPoint>)> {
    let blocks = Blocks::of(points, length);
    if blocks.count() < 2 {
        return Vec::new();
    }
    let folds = blocks.count().min(max_folds);
    let fold_of = |p: &TimedPoint| blocks.ids.binary_search(&blocks.id(p)).unwrap_or(0) % folds;
    (0..folds)
        .map(|f| {
            points
                .iter()
                .partition::<Vec<TimedPoint>, _>(|p| fold_of(p) != f)
        })
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
    // The folds' fits side by side (each the same on any thread: a small fold's passes
    // alone leave threads idle between iterations), summed in fold order.
    let scored = map_slice(folds, |(kept, held)| -> Result<Option<(f64, usize)>> {
        let model = fit_once(kept, periods.to_vec(), gk, params, tuning)?.model;
        Ok(model.mean_log_likelihood(held))
    });
    let (mut sum, mut n) = (0.0, 0usize);
    for fold in scored {
        if let Some((mean, count)) = fold? {
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

/// Left-out-block mean log-likelihoods of the model with `periods` and with `periods` plus
/// `period`, on the folds of blocks of `max(block, period)`. A fold too small to fit scores
/// −∞ for both.
fn cycle_scores(
    points: &[TimedPoint],
    periods: &[f64],
    period: f64,
    gk: &GkParams,
    params: &HypertimeParams,
    tuning: Tuning,
) -> Result<(f64, f64)> {
    let validation = params.validation;
    let folds = block_folds(points, validation.block.max(period), validation.max_folds);
    let mut with = periods.to_vec();
    with.push(period);
    let score = |p: &[f64]| match folds_score(&folds, p, gk, params, tuning) {
        Err(AffordanceError::TooFewPoints { .. }) => Ok(f64::NEG_INFINITY),
        other => other,
    };
    // Both sides at once (their folds' fits side by side).
    let (without, with) = join(|| score(periods), || score(&with));
    Ok((without?, with?))
}

/// The floor, background weight and uniform weight (see [`Calibration`]) for the model with
/// `periods` and `gk`: the floor and the background's weight on the interleaved blocks of
/// `points`, then (with [`Calibration::later`]) the uniform weight on their later part; or
/// all three on the blocks.
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
        uniform_weight: t.uniform,
        heldout_loglik: None,
        heldout: 0,
        uniform_heldout_loglik: None,
        uniform_heldout: 0,
    };
    let weights: Vec<f64> = if params.background.is_some() {
        calibration.weights.clone()
    } else {
        vec![0.0]
    };
    let uniform_weights: Vec<f64> = if params.uniform.is_some() {
        calibration.uniform_weights.clone()
    } else {
        vec![0.0]
    };
    // Stage 1: floor and β on the blocks (and u with them without a later split).
    let jointly = calibration.later.is_none();
    let first = heldout_choice(
        &calibration.holdout.split(points),
        periods,
        gk,
        params,
        fallback,
        (&calibration.floors, &weights),
        if jointly { &uniform_weights } else { &[0.0] },
    )?;
    let Some((mut tuning, score, heldout)) = first else {
        return Ok((fallback, Some(unfitted(fallback))));
    };
    let mut report = CalibrationReport {
        floor: tuning.floor,
        weight: tuning.background,
        uniform_weight: tuning.uniform,
        heldout_loglik: Some(score),
        heldout,
        uniform_heldout_loglik: None,
        uniform_heldout: 0,
    };
    // Stage 2: u on the later part, the floor and β as chosen.
    if !jointly && uniform_weights.len() > 1 {
        let second = heldout_choice(
            &calibration.split(points),
            periods,
            gk,
            params,
            tuning,
            (&[tuning.floor], &[tuning.background]),
            &uniform_weights,
        )?;
        if let Some((t, score, heldout)) = second {
            tuning = t;
            report.uniform_weight = t.uniform;
            report.uniform_heldout_loglik = Some(score);
            report.uniform_heldout = heldout;
        }
    }
    Ok((tuning, Some(report)))
}

/// The best `(floor, β, u)` of the candidates by the held-out mean log-likelihood of `split`
/// (the model fitted on its kept side with `fit_tuning`, then rebuilt for every floor), with
/// its score and the held-out count; `None` when the split or the fit leaves nothing to score.
#[allow(clippy::too_many_arguments)]
fn heldout_choice(
    split: &Result<(Vec<TimedPoint>, Vec<TimedPoint>)>,
    periods: &[f64],
    gk: &GkParams,
    params: &HypertimeParams,
    fit_tuning: Tuning,
    (floors, weights): (&[f64], &[f64]),
    uniform_weights: &[f64],
) -> Result<Option<(Tuning, f64, usize)>> {
    let Ok((kept, held)) = split else {
        return Ok(None);
    };
    let fitted = match fit_once(kept, periods.to_vec(), gk, params, fit_tuning) {
        Ok(f) => f,
        Err(AffordanceError::TooFewPoints { .. }) => return Ok(None),
        Err(e) => return Err(e),
    };
    // The uniform density over the kept part's area: the same for every floor.
    let uniform = params
        .uniform
        .and_then(|u| UniformDensity::over(fitted.positions(), u.with_weight(0.5)));
    let mut best: Option<(Tuning, f64)> = None;
    for &floor in floors {
        // The mixture alone, the background alone and the uniform alone, each at weight 1.
        let mixture = fitted.retune(
            params,
            Tuning {
                floor,
                background: 0.0,
                uniform: 0.0,
            },
        )?;
        let background = params.background.and_then(|b| {
            super::model::BackgroundDensity::over(fitted.positions(), floor, b.with_weight(0.5))
        });
        let parts: Vec<Option<[f64; 3]>> = map_slice(held, |p| {
            let m = mixture.log_density(p)?;
            let b = background.map_or(f64::NEG_INFINITY, |b| {
                b.log_value(p.position) // ln t_ν(p)
            });
            let u = uniform.map_or(f64::NEG_INFINITY, |u| u.log_value(p.position));
            Some([m, b, u])
        });
        for &u in uniform_weights {
            let (rest, lu) = ((-u).ln_1p(), u.ln());
            for &w in weights {
                let (lm, lb) = (rest + (-w).ln_1p(), rest + w.ln());
                let (sum, n) = parts
                    .iter()
                    .flatten()
                    .fold((0.0, 0usize), |(s, n), [m, b, x]| {
                        let v = log_add_exp(log_add_exp(lm + m, lb + b), lu + x);
                        (s + v, n + 1)
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
                            uniform: u,
                        },
                        score,
                    ));
                }
            }
        }
    }
    Ok(best.map(|(t, score)| (t, score, held.len())))
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
