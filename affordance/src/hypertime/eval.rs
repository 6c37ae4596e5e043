//! Scoring a model on test detections with a spatial normalisation common to every model: the
//! density at each detection divided by the model's mass over one grid.

use std::collections::BTreeMap;

use haunts_occupancy::GridGeometry;
use haunts_occupancy::budget::check_work;

use super::model::HypertimeModel;
use super::projection::TimedPoint;
use crate::parallel::map_slice;
use crate::{AffordanceError, Result};

/// The work-budget units of one component's density at one point
/// ([`haunts_occupancy::budget`]: a unit is about a nanosecond of one core; a density of a
/// fitted model measured 50–70 ns per component, conditional Gaussian and log-sum-exp).
pub const DENSITY_UNITS: (&str, f64) = ("units per density", 64.0);

/// The result of [`grid_log_likelihood`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridLogLikelihood {
    /// Sum of `ln p̂(xⱼ, yⱼ | tⱼ)` over the detections used.
    pub sum: f64,
    /// Detections used (finite and inside the grid).
    pub used: usize,
    /// Finite detections outside the grid (not scored).
    pub outside: usize,
    /// Detections with a non-finite time or coordinate (not scored).
    pub skipped: usize,
}

impl GridLogLikelihood {
    /// The mean log-likelihood per detection used, or `None` if none was.
    pub fn mean(&self) -> Option<f64> {
        (self.used > 0).then(|| self.sum / self.used as f64)
    }
}

/// Scores `model` on `test` with the grid `geometry` as the common spatial support:
/// `p̂(x, y | t) = p(x, y | t') / Σ_cells p(cell centre | t')·a` (`a` the cell area), `t'` the
/// detection's time rounded to a multiple of `time_step` seconds (one normaliser per step;
/// a model without periods has one normaliser). Every model scored on the same grid thus
/// spreads exactly one unit of probability over the same region, so their log-likelihoods
/// compare fairly: mass a model puts outside the region is not counted in its favour.
/// Parallel over time steps with the `rayon` feature; the sum is taken in input order.
///
/// # Errors
/// [`AffordanceError::InvalidParameter`] if `time_step` is not finite and > 0;
/// [`haunts_occupancy::OccupancyError::WorkTooLarge`] (in [`AffordanceError::Occupancy`])
/// when time steps × cells × (components + 1) × [`DENSITY_UNITS`] exceeds the work budget
/// ([`haunts_occupancy::budget`]), checked before any density is evaluated.
///
/// # Complexity
/// `O(cells · clusters)` per distinct time step, plus `O(clusters)` per detection.
///
/// ```
/// use haunts_affordance::hypertime::{grid_log_likelihood, HypertimeModel, HypertimeParams, TimedPoint};
/// use haunts_occupancy::GridGeometry;
/// use nalgebra::Point2;
/// let points: Vec<TimedPoint> = (0..200)
///     .map(|i| TimedPoint::new(i as f64 * 60.0, (i % 10) as f64 * 0.3, (i % 7) as f64 * 0.3))
///     .collect();
/// let model = HypertimeModel::fit(&points, &HypertimeParams::default().with_clusters(3))?;
/// let grid = GridGeometry::new(0.25, Point2::new(-1.0, -1.0), 20, 16)?;
/// let score = grid_log_likelihood(&model, &points, &grid, 60.0)?;
/// assert_eq!((score.used, score.outside), (200, 0));
/// // Better than a uniform density over the grid's 20 m².
/// assert!(score.mean().unwrap() > -(20.0f64).ln());
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
pub fn grid_log_likelihood(
    model: &HypertimeModel,
    test: &[TimedPoint],
    geometry: &GridGeometry,
    time_step: f64,
) -> Result<GridLogLikelihood> {
    Ok(scored(model, test, geometry, time_step)?.0)
}

/// [`grid_log_likelihood`] with the value of every detection (`None` where not scored).
fn scored(
    model: &HypertimeModel,
    test: &[TimedPoint],
    geometry: &GridGeometry,
    time_step: f64,
) -> Result<(GridLogLikelihood, Vec<Option<f64>>)> {
    if !(time_step.is_finite() && time_step > 0.0) {
        return Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "time_step",
                value: time_step,
                rule: "must be finite and > 0 s",
            },
        ));
    }
    let timeless = model.periods().is_empty();
    let mut result = GridLogLikelihood {
        sum: 0.0,
        used: 0,
        outside: 0,
        skipped: 0,
    };
    let mut by_step: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
    for (i, p) in test.iter().enumerate() {
        if !p.is_finite() {
            result.skipped += 1;
        } else if geometry.world_to_cell(p.position).is_none() {
            result.outside += 1;
        } else {
            let step = if timeless {
                0
            } else {
                (p.time / time_step).round() as i64
            };
            by_step.entry(step).or_default().push(i);
        }
    }
    let steps: Vec<(i64, Vec<usize>)> = by_step.into_iter().collect();
    // Every component at every cell for every step: refused before it starts when one far
    // detection or a tiny cell makes the grid, or many distinct times the steps, absurd.
    check_work(
        "hypertime scoring",
        &[
            ("time steps", steps.len() as f64),
            ("cells", geometry.len() as f64),
            ("components", model.components().len() as f64 + 1.0),
            DENSITY_UNITS,
        ],
    )?;
    let area = geometry.resolution() * geometry.resolution();
    let scored: Vec<Vec<(usize, f64)>> = map_slice(&steps, |(step, indices)| {
        let snapshot = model.at(*step as f64 * time_step);
        let mass: f64 = (0..geometry.len())
            .filter_map(|c| geometry.cell_at(c))
            .filter_map(|cell| crate::DensityMap::density_at(&snapshot, geometry.cell_center(cell)))
            .sum::<f64>()
            * area;
        let log_mass = mass.ln();
        indices
            .iter()
            .map(|&i| {
                let v = snapshot
                    .log_density_at(test[i].position)
                    .map_or(f64::NEG_INFINITY, |l| l - log_mass);
                (i, v)
            })
            .collect()
    });
    let mut values = vec![None; test.len()];
    for (i, v) in scored.into_iter().flatten() {
        values[i] = Some(v);
    }
    for v in values.iter().flatten() {
        result.sum += v;
        result.used += 1;
    }
    Ok((result, values))
}

/// Parameters of [`evaluate`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct EvaluationParams {
    /// The time step of the grid normalisation, seconds (see [`grid_log_likelihood`];
    /// default 60).
    pub time_step: f64,
    /// Side of the cells over which counts are compared, metres (default 1).
    pub count_cell: f64,
    /// Length of the intervals over which counts are compared, seconds (default 600).
    pub count_interval: f64,
    /// Share of the count cells, the densest at each interval, whose hits are counted
    /// (in `(0, 1]`, default 0.1: a uniform guess hits 10 % of the detections).
    pub top_share: f64,
    /// A detection scoring below this is counted as badly predicted, nats (default −20).
    pub low: f64,
}

impl Default for EvaluationParams {
    /// See the fields.
    fn default() -> Self {
        Self {
            time_step: 60.0,
            count_cell: 1.0,
            count_interval: 600.0,
            top_share: 0.1,
            low: -20.0,
        }
    }
}

impl EvaluationParams {
    /// Sets the time step of the grid normalisation, seconds.
    pub fn with_time_step(mut self, seconds: f64) -> Self {
        self.time_step = seconds;
        self
    }
    /// Sets the count cells' side (metres) and intervals (seconds).
    pub fn with_counts(mut self, cell: f64, interval: f64) -> Self {
        (self.count_cell, self.count_interval) = (cell, interval);
        self
    }

    /// The rules, checked: finite positive steps, cells and intervals, `top_share` in
    /// `(0, 1]`, `low` finite.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        for (name, value) in [
            ("time_step", self.time_step),
            ("count_cell", self.count_cell),
            ("count_interval", self.count_interval),
        ] {
            haunts_core::positive(name, value)?;
        }
        haunts_core::fraction("top_share", self.top_share)?;
        if !self.low.is_finite() {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "low",
                    value: self.low,
                    rule: "must be finite",
                },
            ));
        }
        Ok(self)
    }
}

/// The result of [`evaluate`]: the likelihood of the test detections and the count errors
/// the people-presence literature reports (FreMEn, WHyTe), all over one grid that the caller
/// bounds by the training data or the map, never by the test set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// The grid log-likelihood (sum, detections used, outside the grid, skipped).
    pub loglik: GridLogLikelihood,
    /// Median log-likelihood of the detections used (`None` if none was).
    pub median: Option<f64>,
    /// Share of the detections used scoring below [`EvaluationParams::low`] (0 if none).
    pub share_low: f64,
    /// The uniform reference: `−ln(area of the grid)`, the mean log-likelihood of a density
    /// spread evenly over the known area.
    pub uniform_loglik: f64,
    /// RMSE between observed and predicted counts of detections over the space–time cells
    /// (count cells × intervals holding at least one detection used), the predicted count
    /// being the interval's number of detections times the model's share of the grid's mass
    /// in the cell at the interval's middle (`None` without any detection used).
    pub count_rmse: Option<f64>,
    /// The same RMSE for the uniform density (the reference for `count_rmse`).
    pub uniform_count_rmse: Option<f64>,
    /// Share of the detections used that fall in the `top_share` densest count cells of their
    /// interval (`None` without any detection used).
    pub top_hit_rate: Option<f64>,
    /// Space–time cells compared.
    pub count_cells: usize,
    /// Where the likelihood comes from: the detections used in cells of the grid the
    /// training data visited and in the others ([`evaluate_with_training`]; `None` from
    /// [`evaluate`]).
    pub visits: Option<VisitSplit>,
}

impl Evaluation {
    /// Mean log-likelihood per detection used.
    pub fn mean(&self) -> Option<f64> {
        self.loglik.mean()
    }
}

/// The test detections used, split by whether their cell of the scoring grid holds a
/// training detection: where a model's loss comes from (a model over-confident where
/// yesterday's people walked, or blind where they did not).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VisitSplit {
    /// In cells the training data visited.
    pub visited: VisitPart,
    /// In cells it did not.
    pub unvisited: VisitPart,
}

/// One side of a [`VisitSplit`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VisitPart {
    /// Detections used on this side.
    pub detections: usize,
    /// Their share of the detections used (0 when none was used).
    pub share: f64,
    /// Sum of their log-likelihoods, nats.
    pub sum: f64,
}

impl VisitPart {
    /// Mean log-likelihood per detection on this side (`None` without any).
    pub fn mean(&self) -> Option<f64> {
        (self.detections > 0).then(|| self.sum / self.detections as f64)
    }
}

/// [`evaluate`], with the [`VisitSplit`] of the test detections by the cells of `geometry`
/// that `train` visited.
///
/// # Errors
/// As [`evaluate`].
///
/// ```
/// use haunts_affordance::hypertime::{evaluate_with_training, EvaluationParams, HypertimeModel, HypertimeParams, TimedPoint};
/// use haunts_occupancy::GridGeometry;
/// use nalgebra::Point2;
/// let train: Vec<TimedPoint> = (0..300)
///     .map(|i| TimedPoint::new(i as f64 * 20.0, 0.1 + (i % 9) as f64 * 0.1, 0.1 + (i % 8) as f64 * 0.1))
///     .collect();
/// // A test day with one detection in three where nobody was seen.
/// let test: Vec<TimedPoint> = (0..300)
///     .map(|i| if i % 3 == 0 { TimedPoint::new(i as f64 * 20.0, 3.5, 3.5) } else { train[i] })
///     .collect();
/// let model = HypertimeModel::fit(&train, &HypertimeParams::default().with_clusters(3))?;
/// let grid = GridGeometry::new(0.25, Point2::origin(), 16, 16)?;
/// let e = evaluate_with_training(&model, &train, &test, &grid, &EvaluationParams::default())?;
/// let v = e.visits.unwrap();
/// assert_eq!((v.visited.detections, v.unvisited.detections), (200, 100));
/// assert!(v.unvisited.mean().unwrap() < v.visited.mean().unwrap());
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
pub fn evaluate_with_training(
    model: &HypertimeModel,
    train: &[TimedPoint],
    test: &[TimedPoint],
    geometry: &GridGeometry,
    params: &EvaluationParams,
) -> Result<Evaluation> {
    evaluate_inner(model, Some(train), test, geometry, params)
}

/// Scores `model` on `test` over `geometry` (see [`Evaluation`]): the grid log-likelihood of
/// [`grid_log_likelihood`], its median and share of badly predicted detections beside the
/// mean, the uniform reference `−ln(area)`, the count RMSE over space–time cells and the hit
/// rate of the densest cells. Detections outside `geometry` are counted
/// (`loglik.outside`), not scored.
///
/// # Errors
/// [`AffordanceError::InvalidParameter`] for bad parameters;
/// [`haunts_occupancy::OccupancyError::GridTooLarge`] (in [`AffordanceError::Occupancy`]) for
/// count cells so small that their grid over `geometry` exceeds the cell budget;
/// [`haunts_occupancy::OccupancyError::WorkTooLarge`] when the scoring (see
/// [`grid_log_likelihood`]) or the counts (intervals × cells × (components + 1)) exceed the
/// work budget (× [`DENSITY_UNITS`]), each checked before it starts.
///
/// # Complexity
/// [`grid_log_likelihood`]'s, plus `O(cells · clusters)` per count interval.
///
/// ```
/// use haunts_affordance::hypertime::{evaluate, EvaluationParams, HypertimeModel, HypertimeParams, TimedPoint};
/// use haunts_occupancy::GridGeometry;
/// use nalgebra::Point2;
/// // Everybody stands in the lower-left square metre of a 4 m × 4 m grid.
/// let points: Vec<TimedPoint> = (0..300)
///     .map(|i| TimedPoint::new(i as f64 * 20.0, 0.1 + (i % 9) as f64 * 0.1, 0.1 + (i % 8) as f64 * 0.1))
///     .collect();
/// let model = HypertimeModel::fit(&points, &HypertimeParams::default().with_clusters(3))?;
/// let grid = GridGeometry::new(0.25, Point2::origin(), 16, 16)?;
/// let e = evaluate(&model, &points, &grid, &EvaluationParams::default())?;
/// approx::assert_relative_eq!(e.uniform_loglik, -(16.0f64).ln());
/// assert!(e.mean().unwrap() > e.uniform_loglik);
/// assert!(e.top_hit_rate.unwrap() > 0.9); // the densest cell (1 of 16) holds them all
/// assert!(e.count_rmse.unwrap() < e.uniform_count_rmse.unwrap());
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
pub fn evaluate(
    model: &HypertimeModel,
    test: &[TimedPoint],
    geometry: &GridGeometry,
    params: &EvaluationParams,
) -> Result<Evaluation> {
    evaluate_inner(model, None, test, geometry, params)
}

fn evaluate_inner(
    model: &HypertimeModel,
    train: Option<&[TimedPoint]>,
    test: &[TimedPoint],
    geometry: &GridGeometry,
    params: &EvaluationParams,
) -> Result<Evaluation> {
    let params = params.check()?;
    let (loglik, values) = scored(model, test, geometry, params.time_step)?;
    let visits = train.map(|train| visit_split(train, test, &values, geometry));
    let mut used: Vec<f64> = values.iter().flatten().copied().collect();
    used.sort_by(f64::total_cmp);
    let median = (!used.is_empty()).then(|| {
        let n = used.len();
        if n % 2 == 1 {
            used[n / 2]
        } else {
            0.5 * (used[n / 2 - 1] + used[n / 2])
        }
    });
    let share_low = if used.is_empty() {
        0.0
    } else {
        used.iter().filter(|v| **v < params.low).count() as f64 / used.len() as f64
    };
    let res = geometry.resolution();
    let area = geometry.len() as f64 * res * res;

    // Count cells: squares of `count_cell` from the grid's origin; each fine cell belongs to
    // the count cell of its centre.
    // Checked against the cell budget before the per-interval grids are allocated: a tiny
    // `count_cell` is a typed error naming the extent, not billions of cells.
    let (cols, rows) = haunts_occupancy::budget::check_extent(
        ((geometry.width() as f64 * res) / params.count_cell)
            .ceil()
            .max(1.0),
        ((geometry.height() as f64 * res) / params.count_cell)
            .ceil()
            .max(1.0),
        params.count_cell,
        geometry.origin(),
        geometry.upper_corner(),
    )?;
    let count_of = |p: nalgebra::Point2<f64>| {
        let c = ((p.x - geometry.origin().x) / params.count_cell).floor();
        let r = ((p.y - geometry.origin().y) / params.count_cell).floor();
        (c >= 0.0 && r >= 0.0 && (c as usize) < cols && (r as usize) < rows)
            .then(|| r as usize * cols + c as usize)
    };
    let fine: Vec<(nalgebra::Point2<f64>, Option<usize>)> = (0..geometry.len())
        .filter_map(|c| geometry.cell_at(c))
        .map(|cell| {
            let p = geometry.cell_center(cell);
            (p, count_of(p))
        })
        .collect();
    // The uniform density's share of each count cell.
    let mut uniform = vec![0.0; cols * rows];
    for (_, c) in &fine {
        if let Some(c) = c {
            uniform[*c] += 1.0 / fine.len() as f64;
        }
    }
    let mut by_interval: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
    for (i, v) in values.iter().enumerate() {
        if v.is_some() {
            let k = (test[i].time / params.count_interval).floor() as i64;
            by_interval.entry(k).or_default().push(i);
        }
    }
    let intervals: Vec<(i64, Vec<usize>)> = by_interval.into_iter().collect();
    check_work(
        "hypertime count evaluation",
        &[
            ("intervals", intervals.len() as f64),
            ("cells", geometry.len() as f64),
            ("components", model.components().len() as f64 + 1.0),
            DENSITY_UNITS,
        ],
    )?;
    let top = ((params.top_share * (cols * rows) as f64).ceil() as usize).clamp(1, cols * rows);
    // Per interval: (Σ squared count error, Σ uniform squared error, hits).
    let parts: Vec<(f64, f64, usize)> = map_slice(&intervals, |(k, indices)| {
        let snapshot = model.at((*k as f64 + 0.5) * params.count_interval);
        let mut share = vec![0.0; cols * rows];
        let mut total = 0.0;
        for (p, c) in &fine {
            let d = crate::DensityMap::density_at(&snapshot, *p).unwrap_or(0.0);
            total += d;
            if let Some(c) = c {
                share[*c] += d;
            }
        }
        if total > 0.0 {
            share.iter_mut().for_each(|s| *s /= total);
        }
        let mut observed = vec![0.0; cols * rows];
        for &i in indices {
            if let Some(c) = count_of(test[i].position) {
                observed[c] += 1.0;
            }
        }
        let n = indices.len() as f64;
        let (mut err, mut uerr) = (0.0, 0.0);
        for ((o, s), u) in observed.iter().zip(&share).zip(&uniform) {
            err += (o - n * s).powi(2);
            uerr += (o - n * u).powi(2);
        }
        let mut order: Vec<usize> = (0..cols * rows).collect();
        order.sort_by(|a, b| share[*b].total_cmp(&share[*a]).then(a.cmp(b)));
        let hits = order[..top].iter().map(|&c| observed[c]).sum::<f64>() as usize;
        (err, uerr, hits)
    });
    let cells = intervals.len() * cols * rows;
    let (err, uerr, hits) = parts
        .iter()
        .fold((0.0, 0.0, 0usize), |(a, b, h), (e, u, x)| {
            (a + e, b + u, h + x)
        });
    let any = loglik.used > 0 && cells > 0;
    Ok(Evaluation {
        loglik,
        median,
        share_low,
        uniform_loglik: -area.ln(),
        count_rmse: any.then(|| (err / cells as f64).sqrt()),
        uniform_count_rmse: any.then(|| (uerr / cells as f64).sqrt()),
        top_hit_rate: any.then(|| hits as f64 / loglik.used as f64),
        count_cells: cells,
        visits,
    })
}

/// The [`VisitSplit`] of the scored `values` of `test` by the cells of `geometry` holding a
/// detection of `train`.
fn visit_split(
    train: &[TimedPoint],
    test: &[TimedPoint],
    values: &[Option<f64>],
    geometry: &GridGeometry,
) -> VisitSplit {
    let mut seen = vec![false; geometry.len()];
    let index =
        |p: nalgebra::Point2<f64>| geometry.world_to_cell(p).and_then(|c| geometry.index(c));
    for p in train {
        if let Some(i) = index(p.position) {
            seen[i] = true;
        }
    }
    let mut split = VisitSplit::default();
    for (p, v) in test.iter().zip(values) {
        let Some(v) = v else { continue };
        let visited = index(p.position).is_some_and(|i| seen[i]);
        let part = if visited {
            &mut split.visited
        } else {
            &mut split.unvisited
        };
        part.detections += 1;
        part.sum += v;
    }
    let used = (split.visited.detections + split.unvisited.detections) as f64;
    if used > 0.0 {
        split.visited.share = split.visited.detections as f64 / used;
        split.unvisited.share = split.unvisited.detections as f64 / used;
    }
    split
}
