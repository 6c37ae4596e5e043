//! The GP behind the TA and confidence maps: exact or sparse by sample count, prediction on a
//! map's cells, and the maximum-likelihood length scale.

use haunts_gp::{
    Constrained, ExactGp, GpRegression, GridCheck, GridMode, Inducing, OptimiseOptions, Prediction,
    Rbf, SparseGp, SparseGpRegression, SparseMethod, chebyshev_interpolation,
};
use haunts_occupancy::budget::check_work;
use haunts_occupancy::{Grid, GridGeometry};
use nalgebra::Point2;

use super::grid2;
use super::params::RegressionParams;
use crate::Result;

/// A fitted GP of a TA or confidence map: exact up to
/// [`RegressionParams::exact_limit`] samples, sparse (VFE on a grid of inducing points, see
/// [`RegressionParams::inducing`]) above.
#[derive(Debug, Clone)]
pub enum GpModel {
    /// The exact GP.
    Exact(ExactGp),
    /// The VFE sparse GP.
    Sparse(SparseGp),
}

impl GpModel {
    /// Fits a zero-mean GP with kernel `Rbf(variance, lengthscale)` to flat 2-D points.
    pub(crate) fn fit(
        x: &[f64],
        y: &[f64],
        lengthscale: f64,
        params: &RegressionParams,
    ) -> Result<Self> {
        let kernel = Rbf::new(params.variance, lengthscale)?;
        let n = y.len();
        // The fits are not checked against the work budget: their size is bounded by
        // parameters (`exact_limit` samples for the exact GP, O(n³); `inducing` points for
        // the sparse one, linear in the samples), not by a product of data-sized factors.
        Ok(if n <= params.exact_limit {
            GpModel::Exact(
                GpRegression::new(kernel)
                    .with_noise(params.noise)
                    .fit(x, 2, y)?,
            )
        } else {
            let inducing = Inducing::Given(inducing_grid(x, lengthscale, params.inducing));
            GpModel::Sparse(
                SparseGpRegression::new(kernel, inducing)
                    .with_noise(params.noise)
                    .with_method(SparseMethod::Vfe)
                    .fit(x, 2, y)?,
            )
        })
    }

    /// Whether this is the sparse GP.
    pub fn is_sparse(&self) -> bool {
        matches!(self, GpModel::Sparse(_))
    }

    /// Posterior mean and latent variance at world points.
    ///
    /// # Errors
    /// [`GpError::NonFiniteInput`](haunts_gp::GpError::NonFiniteInput) (inside
    /// [`AffordanceError::Gp`](crate::AffordanceError::Gp)) for a NaN or infinite point.
    pub fn predict(&self, points: &[Point2<f64>]) -> Result<Prediction> {
        let xs: Vec<f64> = points.iter().flat_map(|p| [p.x, p.y]).collect();
        Ok(match self {
            GpModel::Exact(gp) => gp.predict(&xs)?,
            GpModel::Sparse(gp) => gp.predict(&xs)?,
        })
    }

    /// The points every prediction sums over: the training points of the exact GP, the
    /// inducing points of the sparse one.
    fn basis(&self) -> usize {
        match self {
            GpModel::Exact(gp) => gp.n(),
            GpModel::Sparse(gp) => gp.inducing_points().len() / 2,
        }
    }

    /// Checks the work of predicting at `cells` cell centres in `mode` against the work
    /// budget: each mean sums over the basis, each variance over its square; the fast mode
    /// predicts at (at most) `nodes` per axis and interpolates each cell from them.
    fn check_prediction(
        &self,
        what: &'static str,
        cells: usize,
        mode: GridMode,
        nodes: usize,
        variance: bool,
    ) -> Result<()> {
        let b = self.basis() as f64;
        let per_point = if variance { b * b } else { b };
        let per_point_name = if variance {
            "basis points²"
        } else {
            "basis points"
        };
        match mode {
            GridMode::Exact => {
                check_work(
                    what,
                    &[("cells", cells as f64), (per_point_name, per_point)],
                )?;
            }
            GridMode::Fast { .. } => {
                let nodes = (nodes * nodes) as f64;
                check_work(
                    what,
                    &[("Chebyshev nodes", nodes), (per_point_name, per_point)],
                )?;
                check_work(
                    what,
                    &[
                        ("cells", cells as f64),
                        ("node weights", if variance { nodes } else { nodes.sqrt() }),
                    ],
                )?;
            }
        }
        Ok(())
    }

    /// Posterior means at flat 2-D points (the exact GP skips the variance).
    fn means(&self, xs: &[f64]) -> Result<Vec<f64>> {
        Ok(match self {
            GpModel::Exact(gp) => gp.predict_mean(xs)?,
            GpModel::Sparse(gp) => gp.predict(xs)?.mean,
        })
    }

    /// The posterior mean at every cell centre of `geometry` (the TA map's raster), without
    /// the variance the gp crate's grid prediction computes too.
    ///
    /// [`GridMode::Exact`]: every cell through the model. [`GridMode::Fast`]: the mean is
    /// predicted exactly at a tensor grid of Chebyshev nodes (p per axis) and interpolated
    /// barycentrically along each axis, `raster = U · M · Vᵀ`. The mean is a sum of RBFs, so
    /// the error decays geometrically in p; p starts at `⌈2.5 · extent / ℓ⌉ + 8` per axis (at
    /// most 128) and grows by half until the largest difference from the exact mean at
    /// `check_points` cells spread over the map is at most `tolerance · max(1, max |mean|)`
    /// (or p reaches 128; the measured error is reported either way). An axis with no more
    /// cells than nodes uses its cell centres as nodes (exact along it).
    pub(crate) fn mean_raster(
        &self,
        geometry: &GridGeometry,
        lengthscale: f64,
        mode: GridMode,
    ) -> Result<(Grid<f64>, Option<MeanCheck>)> {
        self.check_prediction("GP mean raster", geometry.len(), mode, MAX_NODES, false)?;
        let grid = grid2(geometry);
        let (tolerance, check_points) = match mode {
            GridMode::Exact => {
                let mean = self.means(&grid.points())?;
                return Ok((Grid::from_vec(*geometry, mean)?, None));
            }
            GridMode::Fast {
                tolerance,
                check_points,
            } => (tolerance, check_points),
        };
        haunts_core::positive("grid_mode.tolerance", tolerance)?;
        let axes = [grid.axis(0), grid.axis(1)];
        let mut p = axes.clone().map(|lines| {
            let extent =
                lines.last().copied().unwrap_or(0.0) - lines.first().copied().unwrap_or(0.0);
            ((2.5 * extent / lengthscale).ceil() as usize + 8).min(MAX_NODES)
        });
        let (nx, ny) = (axes[0].len(), axes[1].len());
        // Cells where the interpolation is compared with the exact mean.
        let total = nx * ny;
        let checked: Vec<usize> = (0..check_points.min(total))
            .map(|k| (k * total) / check_points.min(total).max(1) + (k * 7919) % nx.max(1))
            .map(|i| i.min(total - 1))
            .collect();
        let exact_checked = self.means(
            &checked
                .iter()
                .flat_map(|&i| {
                    [
                        grid.origin[0] + (i % nx) as f64 * grid.step[0],
                        grid.origin[1] + (i / nx) as f64 * grid.step[1],
                    ]
                })
                .collect::<Vec<f64>>(),
        )?;
        loop {
            let (n0, u) = chebyshev_interpolation(&axes[0], p[0]);
            let (n1, v) = chebyshev_interpolation(&axes[1], p[1]);
            let (p0, p1) = (n0.len(), n1.len());
            let nodes: Vec<f64> = n1
                .iter()
                .flat_map(|y| n0.iter().flat_map(move |x| [*x, *y]))
                .collect();
            // M[a + p0·b] = mean at (n0[a], n1[b]).
            let m = self.means(&nodes)?;
            // T[b][i] = Σ_a U[i][a] M[a, b]; raster[i + nx·j] = Σ_b T[b][i] V[j][b].
            let mut t = vec![0.0; p1 * nx];
            for b in 0..p1 {
                let row = &m[b * p0..(b + 1) * p0];
                for (i, ui) in u.iter().enumerate() {
                    t[b * nx + i] = ui.iter().zip(row).map(|(a, c)| a * c).sum();
                }
            }
            let mut raster = vec![0.0; nx * ny];
            for (j, vj) in v.iter().enumerate() {
                let out = &mut raster[j * nx..(j + 1) * nx];
                for (b, &w) in vj.iter().enumerate() {
                    if w != 0.0 {
                        for (o, tv) in out.iter_mut().zip(&t[b * nx..(b + 1) * nx]) {
                            *o += w * tv;
                        }
                    }
                }
            }
            let error = checked
                .iter()
                .zip(&exact_checked)
                .map(|(&i, e)| (raster[i] - e).abs())
                .fold(0.0, f64::max);
            let scale = m.iter().fold(1.0f64, |a, v| a.max(v.abs()));
            let exact_axes = p0 == nx && p1 == ny;
            if error <= tolerance * scale || exact_axes || p[0].max(p[1]) >= MAX_NODES {
                let check = MeanCheck {
                    points: checked.len(),
                    nodes: [p0, p1],
                    max_mean_error: error,
                };
                return Ok((Grid::from_vec(*geometry, raster)?, Some(check)));
            }
            p = p.map(|q| (q + q / 2).min(MAX_NODES));
        }
    }

    /// Mean and variance at every cell centre of `geometry`, and the measured error of the
    /// fast mode.
    pub(crate) fn rasters(
        &self,
        geometry: &GridGeometry,
        params: &RegressionParams,
    ) -> Result<(Grid<f64>, Grid<f64>, Option<GridCheck>)> {
        // The gp crate's ladder of Chebyshev nodes ends at 64 per axis.
        self.check_prediction(
            "GP mean and variance raster",
            geometry.len(),
            params.grid_mode,
            64,
            true,
        )?;
        let grid = grid2(geometry);
        let p = match self {
            GpModel::Exact(gp) => gp.predict_grid(&grid, params.grid_mode)?,
            GpModel::Sparse(gp) => gp.predict_grid(&grid, params.grid_mode)?,
        };
        Ok((
            Grid::from_vec(*geometry, p.mean)?,
            Grid::from_vec(*geometry, p.variance)?,
            p.checked,
        ))
    }
}

/// Most Chebyshev nodes per axis of [`GpModel::mean_raster`].
const MAX_NODES: usize = 128;

/// The measured accuracy of a TA map's fast raster (see [`TaMap::grid_check`](super::TaMap::grid_check)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanCheck {
    /// Cells at which the raster was compared with the exact posterior mean.
    pub points: usize,
    /// Chebyshev nodes per axis used (the cell count of an axis that needed none).
    pub nodes: [usize; 2],
    /// Largest |raster − exact mean| at those cells.
    pub max_mean_error: f64,
}

/// Inducing points for flat 2-D samples `x`: the nodes of a regular grid over the samples'
/// bounding box, spacing ℓ/2, that have a sample within `REACH` spacings per axis; when more
/// than `m` remain, the spacing grows until at most `m` do. Never empty for non-empty `x`.
pub(crate) fn inducing_grid(x: &[f64], lengthscale: f64, m: usize) -> Vec<f64> {
    /// Nodes this many spacings (ℓ/2 each) around a sample are kept: the posterior's tails
    /// reach about 2ℓ past the data.
    const REACH: i64 = 4;
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in x.chunks_exact(2) {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    if !(lo[0] <= hi[0] && lo[1] <= hi[1]) {
        return Vec::new();
    }
    let m = m.max(1);
    // At most 2001 nodes per axis before thinning, whatever ℓ.
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let mut spacing = (0.5 * lengthscale).max(extent / 2000.0);
    loop {
        let nx = ((hi[0] - lo[0]) / spacing).floor() as usize + 1;
        let ny = ((hi[1] - lo[1]) / spacing).floor() as usize + 1;
        // Nodes centred on the box; a node (i, j) is kept when a sample falls within REACH
        // spacings of it along both axes.
        let ox = 0.5 * (lo[0] + hi[0]) - 0.5 * (nx - 1) as f64 * spacing;
        let oy = 0.5 * (lo[1] + hi[1]) - 0.5 * (ny - 1) as f64 * spacing;
        let mut near = vec![false; nx * ny];
        for p in x.chunks_exact(2) {
            let i = ((p[0] - ox) / spacing).round() as i64;
            let j = ((p[1] - oy) / spacing).round() as i64;
            for dj in -REACH..=REACH {
                for di in -REACH..=REACH {
                    let (a, b) = (i + di, j + dj);
                    if a >= 0 && b >= 0 && (a as usize) < nx && (b as usize) < ny {
                        near[b as usize * nx + a as usize] = true;
                    }
                }
            }
        }
        let kept = near.iter().filter(|k| **k).count();
        if kept <= m || (nx == 1 && ny == 1) {
            let mut z = Vec::with_capacity(2 * kept);
            for (k, _) in near.iter().enumerate().filter(|(_, k)| **k) {
                z.push(ox + (k % nx) as f64 * spacing);
                z.push(oy + (k / nx) as f64 * spacing);
            }
            return z;
        }
        spacing *= (kept as f64 / m as f64).sqrt().max(1.05);
    }
}

/// The length scale maximising the exact log marginal likelihood (σ², σn² fixed) on an evenly
/// strided subset of at most `max(exact_limit, 2)` samples, starting from `start` clamped into
/// `bounds`.
pub(crate) fn fit_lengthscale(
    x: &[f64],
    y: &[f64],
    start: f64,
    bounds: (f64, f64),
    params: &RegressionParams,
) -> Result<f64> {
    let n = y.len();
    let keep = params.exact_limit.max(2).min(n);

    let (xs, ys): (Vec<f64>, Vec<f64>) = if keep < n {
        let idx: Vec<usize> = (0..keep).map(|i| i * n / keep).collect();
        (
            idx.iter().flat_map(|&i| [x[2 * i], x[2 * i + 1]]).collect(),
            idx.iter().map(|&i| y[i]).collect(),
        )
    } else {
        (x.to_vec(), y.to_vec())
    };
    // σ² held, ℓ alone optimised within `bounds`.
    let kernel = Constrained::new(Box::new(Rbf::new(
        params.variance,
        start.clamp(bounds.0, bounds.1),
    )?))
    .hold("variance")?
    .bound("length_scale", bounds.0, bounds.1)?;
    let options = {
        let mut p = OptimiseOptions::default();
        p.optimise_noise = false;
        p.warm_start_subset = 0;
        p
    };
    let (_, report) = GpRegression::new(kernel)
        .with_noise(params.noise)
        .fit_optimised(&xs, 2, &ys, &options)?;
    let log_l = report.log_params.first().copied().unwrap_or(start.ln());
    Ok(log_l.exp().clamp(bounds.0, bounds.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inducing_grid_covers_the_samples_within_its_budget() {
        // Two clusters 40 m apart: the empty space between them gets no inducing point.
        let mut x = Vec::new();
        for i in 0..400 {
            let (a, b) = ((i % 20) as f64 * 0.25, (i / 20) as f64 * 0.25);
            x.extend([a, b, 40.0 + a, b]);
        }
        let z = inducing_grid(&x, 2.0, 1000);
        let n = z.len() / 2;
        assert!(n > 0 && n <= 1000);
        // Spacing 1 m over two 4.75 m squares and 4 m around them: at most 14 × 14 each.
        assert!(n <= 2 * 14 * 14, "{n}");
        assert!(z.chunks(2).all(|p| p[0] < 9.0 || p[0] > 31.0));
        // Every sample has an inducing point within half a spacing per axis.
        for p in x.chunks(2) {
            assert!(
                z.chunks(2)
                    .any(|q| (p[0] - q[0]).abs() <= 0.5 && (p[1] - q[1]).abs() <= 0.5)
            );
        }
        // A budget below the natural count widens the spacing.
        let few = inducing_grid(&x, 2.0, 20);
        assert!(!few.is_empty() && few.len() / 2 <= 20, "{}", few.len() / 2);
        assert!(inducing_grid(&[], 2.0, 10).is_empty());
    }
}
