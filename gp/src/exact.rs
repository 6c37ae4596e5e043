//! Exact Gaussian-process regression: [`GpRegression`] (the builder) → [`ExactGp`] (the fitted
//! model), with the log marginal likelihood and its gradient.
//!
//! With K = k(X, X) + σn² I = L Lᵀ, centred targets r = y − m and α = K⁻¹ r (Rasmussen &
//! Williams, Algorithm 2.1):
//! - mean at x*: m + k*ᵀ α;
//! - latent variance at x*: k(x*, x*) − ‖L⁻¹ k*‖² (clamped at 0: it is never negative);
//! - log p(y | X) = −½ rᵀα − Σ ln L_ii − (n/2) ln 2π;
//! - ∂ log p / ∂θ_j = ½ tr((ααᵀ − K⁻¹) ∂K/∂θ_j), for the kernel's log hyperparameters and
//!   then log σn².

use faer::Mat;

use crate::error::{GpError, Result};
use crate::grid::{Grid2, GridMode, GridPrediction, Posterior, predict_grid};
use crate::kernel::{Kernel, check_points};
use crate::linalg::{
    Factor, JitterPolicy, cholesky_with_jitter, col, fill_covariance_lower, fill_cross, map_range,
};

/// ln(2π).
const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// Test points per block of a prediction: the n × block cross-covariance is the largest
/// matrix a prediction holds (5000 training points × 1024 = 41 MB).
const DEFAULT_CHUNK: usize = 1024;

/// The prior mean of a GP.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Mean {
    /// m(x) = 0 (scikit-learn's default, `normalize_y=False`).
    #[default]
    Zero,
    /// m(x) = c.
    Constant(f64),
    /// m(x) = the mean of the training targets (scikit-learn's `normalize_y` without the
    /// scaling).
    Data,
}

/// Exact GP regression, configured then [`fit`](GpRegression::fit) to data.
///
/// With the `serde` feature the configuration (de)serialises as is (the kernel tagged with
/// its type, see [`Kernel`]); like a configuration built by hand, it is checked by `fit`.
///
/// # Example
/// ```
/// use haunts_gp::{GpRegression, Mean, Rbf};
///
/// // y = x² at five points of R¹.
/// let x = [-2.0, -1.0, 0.0, 1.0, 2.0];
/// let y: Vec<f64> = x.iter().map(|v| v * v).collect();
/// let gp = GpRegression::new(Rbf::new(4.0, 1.0)?)
///     .with_noise(1e-6)
///     .with_mean(Mean::Data)
///     .fit(&x, 1, &y)?;
/// let p = gp.predict(&[0.5, 1.0])?;
/// assert!((p.mean[1] - 1.0).abs() < 1e-3); // interpolates the data
/// assert!(p.variance[1] < 1e-5 && p.variance[0] > p.variance[1]);
/// assert!(gp.log_marginal_likelihood().is_finite());
/// # Ok::<(), haunts_gp::GpError>(())
/// ```
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct GpRegression {
    kernel: Box<dyn Kernel>,
    noise: f64,
    mean: Mean,
    jitter: JitterPolicy,
    #[cfg_attr(feature = "serde", serde(rename = "chunk_size"))]
    chunk: usize,
}

impl GpRegression {
    /// A GP with this kernel, noise variance 1e-10 (scikit-learn's default `alpha`), zero mean,
    /// the default [`JitterPolicy`] and prediction blocks of 1024 points.
    pub fn new(kernel: impl Kernel + 'static) -> Self {
        Self::from_box(Box::new(kernel))
    }

    /// As [`new`](GpRegression::new) with a boxed kernel.
    pub fn from_box(kernel: Box<dyn Kernel>) -> Self {
        Self {
            kernel,
            noise: 1e-10,
            mean: Mean::Zero,
            jitter: JitterPolicy::default(),
            chunk: DEFAULT_CHUNK,
        }
    }

    /// The observation noise variance σn² (≥ 0; checked by [`fit`](GpRegression::fit)).
    pub fn with_noise(mut self, variance: f64) -> Self {
        self.noise = variance;
        self
    }

    /// The prior mean.
    pub fn with_mean(mut self, mean: Mean) -> Self {
        self.mean = mean;
        self
    }

    /// The jitter policy of the Cholesky factorisation.
    pub fn with_jitter(mut self, policy: JitterPolicy) -> Self {
        self.jitter = policy;
        self
    }

    /// Test points per prediction block (≥ 1): bounds the memory of predictions to
    /// n × `chunk` numbers.
    pub fn with_chunk_size(mut self, chunk: usize) -> Self {
        self.chunk = chunk;
        self
    }

    /// The kernel.
    pub fn kernel(&self) -> &dyn Kernel {
        self.kernel.as_ref()
    }

    /// The noise variance.
    pub fn noise_variance(&self) -> f64 {
        self.noise
    }

    /// Replaces the kernel (used by the optimiser).
    pub(crate) fn with_kernel(mut self, kernel: Box<dyn Kernel>) -> Self {
        self.kernel = kernel;
        self
    }

    /// Fits the GP to the points `x` (flat row-major, `dim` numbers per point) and targets `y`.
    ///
    /// # Errors
    /// [`GpError::InvalidParameter`] for a negative or non-finite noise, a zero chunk size, a
    /// bad jitter policy or a non-finite constant mean; [`GpError::NoData`];
    /// [`GpError::LengthMismatch`]; point errors of [`check_points`];
    /// [`GpError::NonFiniteTarget`]; [`GpError::NotPositiveDefinite`] if the jitter policy is
    /// exhausted (e.g. duplicate points without noise and `JitterPolicy::none()`).
    pub fn fit(&self, x: &[f64], dim: usize, y: &[f64]) -> Result<ExactGp> {
        let (n, offset) = self.check_data(x, dim, y)?;
        let factor = cholesky_with_jitter(
            n,
            |m| fill_covariance_lower(self.kernel.as_ref(), x, dim, self.noise, m),
            &self.jitter,
        )?;
        let r: Vec<f64> = y.iter().map(|v| v - offset).collect();
        let alpha = factor.solve_vec(&r);
        let data_fit: f64 = r.iter().zip(&alpha).map(|(a, b)| a * b).sum();
        let lml = -0.5 * data_fit - 0.5 * factor.log_det() - 0.5 * n as f64 * LN_2PI;
        Ok(ExactGp {
            kernel: self.kernel.clone(),
            x: x.to_vec(),
            dim,
            y: y.to_vec(),
            mean: self.mean,
            offset,
            noise: self.noise,
            policy: self.jitter,
            chunk: self.chunk,
            factor,
            alpha,
            lml,
        })
    }

    /// Checks parameters and data; returns n and the prior mean's value.
    pub(crate) fn check_data(&self, x: &[f64], dim: usize, y: &[f64]) -> Result<(usize, f64)> {
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return Err(GpError::invalid("noise", self.noise, "finite and >= 0"));
        }
        if self.chunk == 0 {
            return Err(GpError::invalid("chunk_size", 0.0, ">= 1"));
        }
        self.jitter.check()?;
        let n = check_points(self.kernel.as_ref(), x, dim)?;
        if n == 0 {
            return Err(GpError::NoData);
        }
        if y.len() != n {
            return Err(GpError::LengthMismatch {
                points: n,
                targets: y.len(),
            });
        }
        if let Some(index) = y.iter().position(|v| !v.is_finite()) {
            return Err(GpError::NonFiniteTarget { index });
        }
        let offset = match self.mean {
            Mean::Zero => 0.0,
            Mean::Constant(c) if c.is_finite() => c,
            Mean::Constant(c) => return Err(GpError::invalid("mean", c, "finite")),
            Mean::Data => y.iter().sum::<f64>() / n as f64,
        };
        Ok((n, offset))
    }
}

/// Posterior mean and latent variance at a set of test points.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Prediction {
    /// Posterior mean, one per test point.
    pub mean: Vec<f64>,
    /// Posterior variance of the latent function (without the observation noise), ≥ 0.
    pub variance: Vec<f64>,
}

/// A fitted exact GP (see [`GpRegression`]).
///
/// # Serialisation
/// With the `serde` feature a model is written as what defines it: its configuration (the
/// kernel with its hyperparameters, the noise, the prior [`Mean`], the [`JitterPolicy`], the
/// chunk size) and its data (`dim`, the training points and targets), never the Cholesky
/// factor nor the weights α. Reading one fits it again with [`GpRegression::fit`]: loading
/// costs a factorisation (O(n³), as the fit) and gives the same factor, jitter and weights,
/// so the loaded model predicts as the saved one did; data that the fit refuses (points and
/// targets of different lengths, non-finite values, a matrix not positive definite with the
/// stored jitter policy) make the read fail with that error.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "ExactGpFields"))]
pub struct ExactGp {
    kernel: Box<dyn Kernel>,
    x: Vec<f64>,
    dim: usize,
    /// The training targets.
    y: Vec<f64>,
    /// The prior mean as configured (`offset` is its value).
    mean: Mean,
    offset: f64,
    noise: f64,
    /// The jitter policy of the fit (`factor.jitter` is the jitter it settled on).
    policy: JitterPolicy,
    chunk: usize,
    factor: Factor,
    alpha: Vec<f64>,
    lml: f64,
}

/// What an [`ExactGp`] is written as: [`ExactGpFields`] by reference.
#[cfg(feature = "serde")]
#[derive(serde::Serialize)]
struct ExactGpRef<'a> {
    kernel: &'a dyn Kernel,
    noise: f64,
    mean: Mean,
    jitter: JitterPolicy,
    chunk_size: usize,
    dim: usize,
    points: &'a [f64],
    targets: &'a [f64],
}

/// The fields of an [`ExactGp`] as deserialised, before [`GpRegression::fit`] checks them and
/// factorises.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct ExactGpFields {
    kernel: Box<dyn Kernel>,
    noise: f64,
    mean: Mean,
    jitter: JitterPolicy,
    chunk_size: usize,
    dim: usize,
    points: Vec<f64>,
    targets: Vec<f64>,
}

#[cfg(feature = "serde")]
impl serde::Serialize for ExactGp {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        ExactGpRef {
            kernel: self.kernel.as_ref(),
            noise: self.noise,
            mean: self.mean,
            jitter: self.policy,
            chunk_size: self.chunk,
            dim: self.dim,
            points: &self.x,
            targets: &self.y,
        }
        .serialize(serializer)
    }
}

#[cfg(feature = "serde")]
impl TryFrom<ExactGpFields> for ExactGp {
    type Error = GpError;
    fn try_from(f: ExactGpFields) -> Result<Self> {
        GpRegression::from_box(f.kernel)
            .with_noise(f.noise)
            .with_mean(f.mean)
            .with_jitter(f.jitter)
            .with_chunk_size(f.chunk_size)
            .fit(&f.points, f.dim, &f.targets)
    }
}

impl ExactGp {
    /// The number of training points.
    pub fn n(&self) -> usize {
        self.alpha.len()
    }

    /// The dimension of the points.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The kernel.
    pub fn kernel(&self) -> &dyn Kernel {
        self.kernel.as_ref()
    }

    /// The observation noise variance σn².
    pub fn noise(&self) -> f64 {
        self.noise
    }

    /// The prior mean's value (0, the constant, or the data mean).
    pub fn prior_mean(&self) -> f64 {
        self.offset
    }

    /// The prior mean as configured ([`ExactGp::prior_mean`] is its value).
    pub fn mean_rule(&self) -> Mean {
        self.mean
    }

    /// The jitter policy of the fit ([`ExactGp::jitter`] is the jitter it settled on).
    pub fn jitter_policy(&self) -> JitterPolicy {
        self.policy
    }

    /// The absolute jitter added to the diagonal of K (0 when none was needed).
    pub fn jitter(&self) -> f64 {
        self.factor.jitter
    }

    /// The training points (flat, row-major).
    pub fn points(&self) -> &[f64] {
        &self.x
    }

    /// The training targets, one per point.
    pub fn targets(&self) -> &[f64] {
        &self.y
    }

    /// log p(y | X, θ, σn²), including the jitter's effect if any was added.
    pub fn log_marginal_likelihood(&self) -> f64 {
        self.lml
    }

    /// ∂ log p(y | X) / ∂(log θ): the kernel's log hyperparameters in its order, then log σn².
    ///
    /// # Complexity
    /// The inverse of K (≈ n³ flops) and n²/2 kernel gradient evaluations, parallel by column.
    pub fn log_marginal_likelihood_gradient(&self) -> Vec<f64> {
        let n = self.n();
        let p = self.kernel.n_params();
        let kinv = self.factor.inverse_lower();
        let alpha = &self.alpha;
        let x = &self.x;
        let dim = self.dim;
        let kernel = self.kernel.as_ref();
        // Per column j, Σ_{i ≥ j} w_ij W_ij ∂K_ij (w = 2 off the diagonal), then W_jj alone.
        let column = |j: usize| {
            let mut g = vec![0.0; p + 1];
            let mut d = vec![0.0; p];
            let b = &x[j * dim..(j + 1) * dim];
            let kc = col(kinv.as_ref(), j);
            for i in j..n {
                let w = alpha[i] * alpha[j] - kc[i];
                let w = if i == j { w } else { 2.0 * w };
                kernel.gradient(&x[i * dim..(i + 1) * dim], b, &mut d);
                for (gk, dk) in g.iter_mut().zip(&d) {
                    *gk += w * dk;
                }
            }
            g[p] = alpha[j] * alpha[j] - kc[j];
            g
        };
        let partial = map_range(n, column);
        let mut g = vec![0.0; p + 1];
        for part in &partial {
            for (a, b) in g.iter_mut().zip(part) {
                *a += b;
            }
        }
        for v in &mut g[..p] {
            *v *= 0.5;
        }
        g[p] *= 0.5 * self.noise;
        g
    }

    /// Posterior mean at the test points `xs` (flat, `dim` per point).
    ///
    /// # Errors
    /// Point errors of [`check_points`].
    pub fn predict_mean(&self, xs: &[f64]) -> Result<Vec<f64>> {
        Ok(self.predict_blocks(xs, false)?.mean)
    }

    /// Posterior latent variance at the test points `xs` (flat, `dim` per point).
    ///
    /// # Errors
    /// Point errors of [`check_points`].
    pub fn predict_variance(&self, xs: &[f64]) -> Result<Vec<f64>> {
        Ok(self.predict_blocks(xs, true)?.variance)
    }

    /// Posterior mean and latent variance at the test points `xs`, sharing the
    /// cross-covariances. Blocks of `chunk_size` test points bound the memory; each block's
    /// kernel values, products and triangular solve run in parallel.
    ///
    /// # Errors
    /// Point errors of [`check_points`].
    pub fn predict(&self, xs: &[f64]) -> Result<Prediction> {
        self.predict_blocks(xs, true)
    }

    fn predict_blocks(&self, xs: &[f64], with_variance: bool) -> Result<Prediction> {
        let m = check_points(self.kernel.as_ref(), xs, self.dim)?;
        let n = self.n();
        let dim = self.dim;
        let mut out = Prediction {
            mean: Vec::with_capacity(m),
            variance: if with_variance {
                Vec::with_capacity(m)
            } else {
                Vec::new()
            },
        };
        let mut ks = Mat::<f64>::zeros(n, self.chunk.min(m.max(1)));
        // Saturating: a chunk size read from a file may be as large as `usize` allows (one
        // block then holds every point), and `chunk · dim` must not overflow.
        for block in xs.chunks(self.chunk.saturating_mul(dim)) {
            let b = block.len() / dim;
            fill_cross(
                self.kernel.as_ref(),
                &self.x,
                block,
                dim,
                ks.as_mut().subcols_mut(0, b),
            );
            let kb = ks.as_ref().subcols(0, b);
            out.mean.extend((0..b).map(|j| {
                self.offset
                    + col(kb, j)
                        .iter()
                        .zip(&self.alpha)
                        .map(|(k, a)| k * a)
                        .sum::<f64>()
            }));
            if with_variance {
                self.factor.solve_lower(ks.as_mut().subcols_mut(0, b));
                let vb = ks.as_ref().subcols(0, b);
                // Squared column norms ‖L⁻¹ k*‖², one column per test point.
                let reduction = map_range(b, |j| col(vb, j).iter().map(|v| v * v).sum::<f64>());
                out.variance.extend(
                    block
                        .chunks_exact(dim)
                        .zip(&reduction)
                        .map(|(p, r)| (self.kernel.value(p, p) - r).max(0.0)),
                );
            }
        }
        Ok(out)
    }
}

impl ExactGp {
    /// Mean and variance on a regular 2-D grid, exactly or by the fast Chebyshev mode (see
    /// [`crate::grid`](crate::GridMode) and the README for the error bound and measurements).
    ///
    /// # Errors
    /// [`GpError::DimensionMismatch`] unless the points are 2-D; bad grids or tolerances are
    /// [`GpError::InvalidParameter`].
    ///
    /// # Example
    /// ```
    /// use haunts_gp::{Grid2, GridMode, GpRegression, Rbf};
    /// let x = [0.0, 0.0, 1.0, 2.0, 3.0, 1.0, 2.0, 3.0];
    /// let gp = GpRegression::new(Rbf::new(1.0, 1.5)?).with_noise(0.01).fit(&x, 2, &[1.0, 0.5, -0.2, 0.3])?;
    /// let grid = Grid2 { origin: [0.0, 0.0], step: [0.1, 0.1], shape: [40, 40] };
    /// let exact = gp.predict_grid(&grid, GridMode::Exact)?;
    /// let fast = gp.predict_grid(&grid, GridMode::fast())?;
    /// for (a, b) in exact.mean.iter().zip(&fast.mean) {
    ///     assert!((a - b).abs() < 1e-8);
    /// }
    /// assert!(fast.checked.unwrap().max_relative_variance_error < 1e-8);
    /// # Ok::<(), haunts_gp::GpError>(())
    /// ```
    pub fn predict_grid(&self, grid: &Grid2, mode: GridMode) -> Result<GridPrediction> {
        predict_grid(self, grid, mode)
    }
}

impl Posterior for ExactGp {
    fn kernel(&self) -> &dyn Kernel {
        self.kernel.as_ref()
    }
    fn dim(&self) -> usize {
        self.dim
    }
    fn basis(&self) -> &[f64] {
        &self.x
    }
    fn weights(&self) -> &[f64] {
        &self.alpha
    }
    fn offset(&self) -> f64 {
        self.offset
    }
    fn reduction(&self, mut f: Mat<f64>) -> Mat<f64> {
        self.factor.solve_lower(f.as_mut());
        gram(f.as_ref())
    }
    fn exact(&self, xs: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        let p = self.predict(xs)?;
        Ok((p.mean, p.variance))
    }
}

/// `VᵀV`, in parallel.
pub(crate) fn gram(v: faer::MatRef<'_, f64>) -> Mat<f64> {
    let mut s = Mat::<f64>::zeros(v.ncols(), v.ncols());
    faer::linalg::matmul::matmul(
        s.as_mut(),
        faer::Accum::Replace,
        v.transpose(),
        v,
        1.0,
        crate::linalg::par(),
    );
    s
}
