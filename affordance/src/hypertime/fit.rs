//! One fit of the hypertime model for fixed periods and `k`: projection, standardisation,
//! clustering, the clusters' moments and the mixture assembled from them.

use nalgebra::{DMatrix, DVector, Point2};

use super::gk::{self, GkClustering, GkParams};
use super::model::{
    BackgroundDensity, Component, FitReport, HypertimeModel, UniformDensity, conditional,
};
use super::params::{HypertimeParams, Moments, Selection};
use super::projection::{Projected, Projection, TimedPoint};
use crate::parallel::map_slice;
use crate::{AffordanceError, Result};

/// Per-dimension centring and scaling of the hypertime coordinates.
#[derive(Debug, Clone)]
struct Standardise {
    shift: Vec<f64>,
    scale: Vec<f64>,
}

impl Standardise {
    /// Centres every dimension; scales `(x, y)` together by the root of their mean variance (1
    /// when that is 0), and each `(cos, sin)` pair the same way or, with `time_radius = r`
    /// metres, by the plane's scale over `r` (a circle of `r` metres).
    fn fit(p: &Projected, time_radius: Option<f64>) -> Self {
        let (dim, n) = (p.dim, p.len() as f64);
        let mut shift = vec![0.0; dim];
        for row in p.rows.chunks_exact(dim) {
            shift.iter_mut().zip(row).for_each(|(s, v)| *s += v);
        }
        shift.iter_mut().for_each(|s| *s /= n);
        let mut var = vec![0.0; dim];
        for row in p.rows.chunks_exact(dim) {
            for ((v, x), m) in var.iter_mut().zip(row).zip(&shift) {
                *v += (x - m) * (x - m);
            }
        }
        var.iter_mut().for_each(|v| *v /= n);
        let mut scale = vec![1.0; dim];
        for g in 0..dim / 2 {
            let s = (0.5 * (var[2 * g] + var[2 * g + 1])).sqrt();
            let size = shift[2 * g].abs().max(shift[2 * g + 1].abs()).max(1.0);
            let s = if s > 1e-9 * size { s } else { 1.0 };
            let s = match time_radius {
                Some(r) if g > 0 => scale[0] / r,
                _ => s,
            };
            scale[2 * g] = s;
            scale[2 * g + 1] = s;
        }
        Self { shift, scale }
    }

    fn apply(&self, rows: &[f64]) -> Vec<f64> {
        let dim = self.shift.len();
        let mut out = rows.to_vec();
        for row in out.chunks_exact_mut(dim) {
            for ((x, m), s) in row.iter_mut().zip(&self.shift).zip(&self.scale) {
                *x = (*x - m) / s;
            }
        }
        out
    }
}

/// What one fit produces beside the model: the clustering, the clusters' moments and the
/// positions, so that the model can be rebuilt with another floor or background weight.
pub(crate) struct Fitted {
    pub(crate) model: HypertimeModel,
    pub(crate) clustering: GkClustering,
    /// Weight, mean and membership-weighted covariance of every cluster, hypertime
    /// coordinates, before the smoothing kernel and the floor.
    moments: Vec<Component>,
    positions: Vec<Point2<f64>>,
}

/// The spatial floor (metres), background weight and uniform weight a model is built with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Tuning {
    pub(crate) floor: f64,
    pub(crate) background: f64,
    pub(crate) uniform: f64,
}

impl Tuning {
    /// The values of `params` as they stand (no calibration).
    pub(crate) fn of(params: &HypertimeParams) -> Self {
        Self {
            floor: params.spatial_floor,
            background: params.background.map_or(0.0, |b| b.weight),
            uniform: params.uniform.map_or(0.0, |u| u.weight),
        }
    }
}

impl Fitted {
    /// The same clustering built into a model with `tuning`.
    ///
    /// # Errors
    /// [`AffordanceError::DegenerateCovariance`] if a component's covariance is not positive
    /// definite.
    pub(crate) fn retune(
        &self,
        params: &HypertimeParams,
        tuning: Tuning,
    ) -> Result<HypertimeModel> {
        assemble(
            self.model.projection.clone(),
            &self.moments,
            &self.positions,
            params,
            tuning,
            self.model.report.clone(),
        )
    }

    /// The training positions.
    pub(crate) fn positions(&self) -> &[Point2<f64>] {
        &self.positions
    }
}

/// Projects, standardises, clusters and builds the model for fixed periods and `k`; the
/// smoothing and convergence policy come from `params`, the floor and background weight from
/// `tuning`.
pub(crate) fn fit_once(
    points: &[TimedPoint],
    periods: Vec<f64>,
    gk: &GkParams,
    params: &HypertimeParams,
    tuning: Tuning,
) -> Result<Fitted> {
    let projection = Projection::new(periods)?;
    let projected = projection.project(points);
    if projected.len() < gk.clusters || projected.is_empty() {
        return Err(AffordanceError::TooFewPoints {
            points: projected.len(),
            clusters: gk.clusters,
        });
    }
    let dim = projected.dim;
    let standardise = Standardise::fit(&projected, params.time_radius);
    let rows = standardise.apply(&projected.rows);
    let (clustering, converged) = match gk.fit(&rows, dim) {
        Ok(c) => (c, true),
        Err(AffordanceError::NotConverged { partial, .. }) if !params.require_convergence => {
            (*partial, false)
        }
        Err(e) => return Err(e),
    };
    let exponent = match params.moments {
        Moments::Fuzzy => gk.fuzzifier,
        Moments::Membership => 1.0,
    };
    let moments = moments(&clustering, &rows, &standardise, exponent)?;
    let positions: Vec<Point2<f64>> = projected
        .rows
        .chunks_exact(dim)
        .map(|r| Point2::new(r[0], r[1]))
        .collect();
    let report = FitReport {
        points: projected.len(),
        skipped: projected.skipped,
        iterations: clustering.iterations(),
        converged,
        change: clustering.change(),
        objective: clustering.objective(),
        spatial_floor: tuning.floor,
        background_weight: 0.0,
        uniform_weight: 0.0,
        selection: Selection::default(),
    };
    let model = assemble(projection, &moments, &positions, params, tuning, report)?;
    Ok(Fitted {
        model,
        clustering,
        moments,
        positions,
    })
}

/// Every cluster's weight `πᵢ = Σⱼ uᵢⱼᵉ / Σₗⱼ uₗⱼᵉ`, mean (its prototype) and covariance
/// weighted like its weight, `Cᵢ = Σⱼ uᵢⱼᵉ (xⱼ − cᵢ)(xⱼ − cᵢ)ᵀ / Σⱼ uᵢⱼᵉ` (see [`Moments`]),
/// mapped back to hypertime coordinates, unregularised (the floor and the smoothing kernel
/// are added by [`assemble`]; a ridge of 10⁻⁹ of the standardised unit keeps a cluster on one
/// point proper). Summed blockwise in block order (the same on any number of threads).
fn moments(
    clustering: &GkClustering,
    rows: &[f64],
    standardise: &Standardise,
    exponent: f64,
) -> Result<Vec<Component>> {
    let (k, d) = (clustering.clusters(), clustering.dim());
    let centres = clustering.centres();
    let memberships = clustering.memberships();
    let blocks: Vec<(&[f64], &[f64])> = rows
        .chunks(gk::BLOCK * d)
        .zip(memberships.chunks(gk::BLOCK * k))
        .collect();
    let parts: Vec<Vec<f64>> = map_slice(&blocks, |(x, u)| {
        let mut acc = vec![0.0; k * (d * d + 1)];
        let mut v = vec![0.0; d];
        for (x, u) in x.chunks_exact(d).zip(u.chunks_exact(k)) {
            for (i, &w) in u.iter().enumerate() {
                let w = if exponent == 1.0 {
                    w
                } else if exponent == 2.0 {
                    w * w
                } else {
                    w.powf(exponent)
                };
                let c = &centres[i * d..(i + 1) * d];
                v.iter_mut()
                    .zip(x.iter().zip(c))
                    .for_each(|(o, (a, b))| *o = a - b);
                let a = &mut acc[i * (d * d + 1)..(i + 1) * (d * d + 1)];
                a[0] += w;
                for r in 0..d {
                    let wr = w * v[r];
                    for q in 0..d {
                        a[1 + r * d + q] += wr * v[q];
                    }
                }
            }
        }
        acc
    });
    let mut acc = vec![0.0; k * (d * d + 1)];
    for part in &parts {
        acc.iter_mut().zip(part).for_each(|(a, b)| *a += b);
    }
    let n: f64 = (0..k).map(|i| acc[i * (d * d + 1)]).sum();
    let scale = DMatrix::from_diagonal(&DVector::from_column_slice(&standardise.scale));
    let shift = DVector::from_column_slice(&standardise.shift);
    (0..k)
        .map(|i| {
            let a = &acc[i * (d * d + 1)..(i + 1) * (d * d + 1)];
            let centre = clustering
                .centre(i)
                .ok_or(AffordanceError::DegenerateCovariance { cluster: i })?;
            let total = a[0];
            let mut c = if total > 0.0 {
                DMatrix::from_row_slice(d, d, &a[1..]) / total
            } else {
                DMatrix::identity(d, d)
            };
            for r in 0..d {
                c[(r, r)] += 1e-9;
            }
            let covariance = &scale * c * &scale;
            Ok(Component {
                weight: total / n,
                mean: &shift + &scale * DVector::from_column_slice(centre),
                covariance: (&covariance + covariance.transpose()) * 0.5,
            })
        })
        .collect()
}

/// The model of `moments` with the smoothing kernel of `params`, the floor and background
/// weight of `tuning` and the background over `positions`.
fn assemble(
    projection: Projection,
    moments: &[Component],
    positions: &[Point2<f64>],
    params: &HypertimeParams,
    tuning: Tuning,
    mut report: FitReport,
) -> Result<HypertimeModel> {
    // The kernel's variance along each dimension, hypertime coordinates: the floor and the
    // smoothing in the plane, the smoothing along each time circle.
    let plane = params.space_smoothing.powi(2) + tuning.floor.powi(2);
    let mut kernel = vec![plane; 2];
    for period in projection.periods() {
        let arc = std::f64::consts::TAU * params.time_smoothing / period;
        kernel.extend([arc * arc; 2]);
    }
    let components: Vec<Component> = moments
        .iter()
        .map(|m| {
            let mut c = m.clone();
            for (i, v) in kernel.iter().enumerate() {
                c.covariance[(i, i)] += v;
            }
            c
        })
        .collect();
    let conditionals = components
        .iter()
        .enumerate()
        .map(|(i, c)| conditional(c, i))
        .collect::<Result<Vec<_>>>()?;
    let background = match params.background {
        Some(b) if tuning.background > 0.0 => {
            BackgroundDensity::over(positions, tuning.floor, b.with_weight(tuning.background))
        }
        _ => None,
    };
    let uniform = match params.uniform {
        Some(u) if tuning.uniform > 0.0 => {
            UniformDensity::over(positions, u.with_weight(tuning.uniform))
        }
        _ => None,
    };
    report.spatial_floor = tuning.floor;
    report.background_weight = background.map_or(0.0, |b| b.weight);
    report.uniform_weight = uniform.map_or(0.0, |u| u.weight);
    Ok(HypertimeModel {
        projection,
        components,
        conditionals,
        background,
        uniform,
        report,
    })
}
