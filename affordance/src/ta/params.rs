//! Parameters of the TA map and of the confidence map.

use haunts_gp::GridMode;

use crate::{AffordanceError, Result};

/// How the GP of a TA or confidence map is set up and evaluated (shared by [`TaParams`] and
/// [`ConfidenceMap::fit`](super::ConfidenceMap::fit)).
///
/// With the `serde` feature the grid mode is written as `"Exact"` or
/// `{"Fast": {"tolerance": 1e-10, "check_points": 64}}`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct RegressionParams {
    /// σ²: the RBF kernel's signal variance (the prior variance). Default 1 (seed 002, §5).
    pub variance: f64,
    /// σn²: the observation noise variance. Default 1, GPy's default for `GPRegression`, the
    /// framework of seed 002 (which does not state it). Must be > 0.
    pub noise: f64,
    /// Most samples for the exact GP (O(n³) time, O(n²) memory); above it a VFE sparse GP
    /// takes every sample (O(n·m²) time). Default 2000 (an exact fit of 2000 points takes
    /// ≈ 0.1 s).
    pub exact_limit: usize,
    /// m: the most inducing points of the sparse GP. They are the nodes of a regular grid of
    /// spacing ℓ/2 over the samples' bounding box that have a sample within 4 spacings (2ℓ,
    /// where the posterior's tails end); when more than m such nodes exist the spacing grows
    /// until at most m remain. Default 1000 (seq_eth, 8555 samples over ≈ 20 m × 15 m, gets
    /// 359). On seq_eth the sparse mean is then within 0.8 targets of the exact GP's
    /// everywhere (peak 306); placing them by k-means++ instead costs 0.6 s more.
    pub inducing: usize,
    /// How the posterior is evaluated on the map's cells. Default [`GridMode::fast`]
    /// (tolerance 1e-10, error measured at 64 cells). The TA map needs only the mean: its
    /// fast mode interpolates the mean predicted at Chebyshev nodes (see
    /// [`TaMap::grid_check`](super::TaMap::grid_check)); the confidence map needs the
    /// variance and uses the gp crate's grid prediction in the same mode.
    pub grid_mode: GridMode,
}

impl Default for RegressionParams {
    fn default() -> Self {
        Self {
            variance: 1.0,
            noise: 1.0,
            exact_limit: 2000,
            inducing: 1000,
            grid_mode: GridMode::fast(),
        }
    }
}

impl RegressionParams {
    /// Sets σ², the prior variance.
    pub fn with_variance(mut self, variance: f64) -> Self {
        self.variance = variance;
        self
    }
    /// Sets σn², the noise variance.
    pub fn with_noise(mut self, noise: f64) -> Self {
        self.noise = noise;
        self
    }
    /// Sets the most samples for the exact GP (0: always sparse).
    pub fn with_exact_limit(mut self, samples: usize) -> Self {
        self.exact_limit = samples;
        self
    }
    /// Sets the number of inducing points of the sparse GP.
    pub fn with_inducing(mut self, m: usize) -> Self {
        self.inducing = m;
        self
    }
    /// Sets how the posterior is evaluated on grids.
    pub fn with_grid_mode(mut self, mode: GridMode) -> Self {
        self.grid_mode = mode;
        self
    }

    /// The parameters, after checking σ² and σn² finite and > 0 and `inducing >= 1`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        haunts_core::positive("variance", self.variance)?;
        haunts_core::positive("noise", self.noise)?;
        haunts_core::at_least_one("inducing", self.inducing)?;
        Ok(self)
    }
}

/// Parameters of the TA map (seed 002, §4.3 and §5).
///
/// ```
/// use haunts_affordance::ta::TaParams;
/// let p = TaParams::default();
/// assert_eq!((p.cell_size, p.lengthscale, p.regression.variance), (3.0, 2.0, 1.0));
/// assert!(TaParams::default().with_cell_size(0.0).check().is_err());
/// ```
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct TaParams {
    /// k: side of the grid cells of Algorithm 2, metres. Default 3 m (seed 002, §5).
    pub cell_size: f64,
    /// ℓ: the RBF length scale, metres (the start of the search when fitted). Default 2 m
    /// (seed 002's Library case; 2.5 m for its Square).
    pub lengthscale: f64,
    /// `Some((low, high))`: fit ℓ within these bounds (metres) by maximising the exact log
    /// marginal likelihood (L-BFGS, σ² and σn² fixed) on an evenly strided subset of at most
    /// `regression.exact_limit` samples; `None` (default): ℓ as given.
    pub fit_lengthscale: Option<(f64, f64)>,
    /// The GP's set-up.
    pub regression: RegressionParams,
}

impl Default for TaParams {
    fn default() -> Self {
        Self {
            cell_size: 3.0,
            lengthscale: 2.0,
            fit_lengthscale: None,
            regression: RegressionParams::default(),
        }
    }
}

impl TaParams {
    /// Sets k, the grid-cell side, metres.
    pub fn with_cell_size(mut self, metres: f64) -> Self {
        self.cell_size = metres;
        self
    }
    /// Sets ℓ, metres.
    pub fn with_lengthscale(mut self, metres: f64) -> Self {
        self.lengthscale = metres;
        self
    }
    /// Fits ℓ within `(low, high)` metres.
    pub fn with_fitted_lengthscale(mut self, low: f64, high: f64) -> Self {
        self.fit_lengthscale = Some((low, high));
        self
    }
    /// Sets the GP's set-up.
    pub fn with_regression(mut self, regression: RegressionParams) -> Self {
        self.regression = regression;
        self
    }

    /// The parameters, after checking k and ℓ finite and > 0, fitting bounds `0 < low <
    /// high` (finite), and the regression parameters.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        haunts_core::positive("cell_size", self.cell_size)?;
        haunts_core::positive("lengthscale", self.lengthscale)?;
        if let Some((low, high)) = self.fit_lengthscale {
            haunts_core::positive("fit_lengthscale.low", low)?;
            if !(high.is_finite() && high > low) {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "fit_lengthscale.high",
                        value: high,
                        rule: "must be finite and > low",
                    },
                ));
            }
        }
        self.regression.check()?;
        Ok(self)
    }
}
