//! Scoring a model on test detections with a spatial normalisation common to every model: the
//! density at each detection divided by the model's mass over one grid.

use std::collections::BTreeMap;

use haunts_occupancy::GridGeometry;

use super::model::{HypertimeModel, map_slice};
use super::projection::TimedPoint;
use crate::{AffordanceError, Result};

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
/// [`AffordanceError::InvalidParameter`] if `time_step` is not finite and > 0.
///
/// # Complexity
/// `O(cells · clusters)` per distinct time step, plus `O(clusters)` per detection.
pub fn grid_log_likelihood(
    model: &HypertimeModel,
    test: &[TimedPoint],
    geometry: &GridGeometry,
    time_step: f64,
) -> Result<GridLogLikelihood> {
    if !(time_step.is_finite() && time_step > 0.0) {
        return Err(AffordanceError::InvalidParameter {
            name: "time_step",
            value: time_step,
            rule: "must be finite and > 0 s",
        });
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
    for v in values.into_iter().flatten() {
        result.sum += v;
        result.used += 1;
    }
    Ok(result)
}
