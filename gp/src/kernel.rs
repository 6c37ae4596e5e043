//! The [`Kernel`] trait: a covariance function of two points in R^d with hyperparameters in
//! log space, and the covariance matrices built on it.

use std::any::Any;
use std::fmt::Debug;

use crate::error::{GpError, Result};

/// Cloning and downcasting of boxed kernels, implemented for every `Kernel + Clone` type (you
/// never implement it yourself: derive `Clone` on your kernel).
///
/// It lets `Box<dyn Kernel>` be `Clone`, which optimisers with restarts and the sum and
/// product kernels need, and lets a `&dyn Kernel` be downcast to its type.
pub trait KernelClone {
    /// A boxed copy of `self`.
    fn clone_box(&self) -> Box<dyn Kernel>;

    /// `self` as [`Any`], to downcast a `&dyn Kernel` (e.g. a fitted model's
    /// [`kernel`](crate::ExactGp::kernel)) to its type; the `serde` feature uses it to name
    /// the built-in kernels behind a `Box<dyn Kernel>`.
    ///
    /// ```
    /// use haunts_gp::{GpRegression, Rbf};
    /// let gp = GpRegression::new(Rbf::new(1.0, 2.0)?).fit(&[0.0, 1.0], 1, &[0.5, -0.5])?;
    /// let rbf = gp.kernel().as_any().downcast_ref::<Rbf>();
    /// assert_eq!(rbf.map(Rbf::length_scale), Some(2.0));
    /// # Ok::<(), haunts_gp::GpError>(())
    /// ```
    fn as_any(&self) -> &dyn Any;
}

impl<T> KernelClone for T
where
    T: 'static + Kernel + Clone,
{
    fn clone_box(&self) -> Box<dyn Kernel> {
        Box::new(self.clone())
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
}

impl Clone for Box<dyn Kernel> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// A covariance function k(a, b) of two points of R^d, with hyperparameters θ handled in log
/// space (an optimiser sees `log θ`, unbounded where θ > 0).
///
/// Object safe and `Send + Sync`: models hold a `Box<dyn Kernel>`. The required methods are
/// the evaluation [`value`](Kernel::value), the hyperparameters (get, set, bounds, names),
/// the gradient of `value` with respect to the log hyperparameters, and the input dimension;
/// [`try_value`](Kernel::try_value) and [`n_params`](Kernel::n_params) are provided, and the
/// matrices of a point set are the free functions [`covariance`] and [`cross_covariance`].
///
/// **Why `set_log_params(&mut self)` rather than an immutable `with_log_params` returning a
/// new box:** an optimiser sets hyperparameters thousands of times; updating in place costs
/// no allocation and keeps the kernel's type (a `Sum` stays a `Sum` the caller can inspect).
/// Callers that need the old kernel too clone it first (`Box<dyn Kernel>` is `Clone`).
///
/// # Contract
/// - `log_params`, `log_bounds`, `param_names` and the `out` of `gradient` have the same length,
///   [`n_params`](Kernel::n_params), in the same order.
/// - `gradient(a, b, out)` writes ∂k(a, b)/∂(log θ_j) into `out[j]`.
/// - `value` and `gradient` do not check their input (they sit in O(n²) loops): points of
///   different lengths, of a length other than `dim()`, or with NaN coordinates give an
///   unspecified number, never a panic. [`try_value`](Kernel::try_value), [`covariance`] and
///   [`cross_covariance`] check and return typed errors.
/// - `set_log_params` either accepts all values or changes nothing.
/// - Bounds are for optimisers: `set_log_params` does not enforce them (as in scikit-learn),
///   it only refuses values that are not finite or whose exponential is 0 or infinite.
///
/// # Serialisation
/// With the `serde` feature, `dyn Kernel` is `Serialize` and `Box<dyn Kernel>` is
/// `Deserialize` for the crate's kernels: a boxed kernel is written tagged with its type's
/// name (`{"Sum": {"k1": {"Rbf": {…}}, "k2": {"White": {…}}}}`), each kernel with its
/// hyperparameters in natural units, and read back through the kernel's constructor. The set
/// is closed (a trait object does not say how to rebuild itself): writing a kernel of another
/// type is an error naming it.
///
/// # Example: a user-defined kernel
/// See the crate documentation (the README) for a complete, tested example.
pub trait Kernel: KernelClone + Debug + Send + Sync {
    /// k(a, b). Unchecked: see the trait's contract.
    fn value(&self, a: &[f64], b: &[f64]) -> f64;

    /// The hyperparameters in log space, in the order of
    /// [`param_names`](Kernel::param_names).
    fn log_params(&self) -> Vec<f64>;

    /// Sets the hyperparameters from log-space values, in the order of
    /// [`log_params`](Kernel::log_params).
    ///
    /// # Errors
    /// [`GpError::WrongParameterCount`] if `p.len() != self.n_params()`;
    /// [`GpError::InvalidHyperparameter`] if a value is not finite or its exponential is 0 or
    /// infinite. On error the kernel is unchanged.
    fn set_log_params(&mut self, p: &[f64]) -> Result<()>;

    /// Bounds `(low, high)` of each log hyperparameter for optimisers.
    fn log_bounds(&self) -> Vec<(f64, f64)>;

    /// Names of the hyperparameters; combinators prefix their parts' names (`k1__`, `k2__`,
    /// as scikit-learn does).
    fn param_names(&self) -> Vec<String>;

    /// Writes ∂k(a, b)/∂(log θ_j) into `out[j]`. Unchecked: see the trait's contract.
    ///
    /// # Panics
    /// May panic if `out.len() != self.n_params()` (a programming error, not a data error).
    fn gradient(&self, a: &[f64], b: &[f64], out: &mut [f64]);

    /// The dimension of the points this kernel requires, or `None` if any dimension works
    /// (isotropic kernels). ARD kernels return the number of their length scales.
    fn dim(&self) -> Option<usize>;

    /// The index of a log hyperparameter that scales the whole kernel, if there is one: θ_i
    /// with k = θ_i · k̃ (k̃ free of θ_i), so ∂k/∂(log θ_i) = k(a, b) for every a and b (a
    /// variance σ², a constant). The default says there is none; the stationary kernels,
    /// [`crate::Constant`], [`crate::White`], [`crate::Scaled`] and a [`crate::Product`] with
    /// such a factor return theirs. The sparse GP's bound gradient uses it to skip that
    /// hyperparameter's O(n m²) products (its derivative matrices are the kernel matrices).
    fn scale_param(&self) -> Option<usize> {
        None
    }

    /// The number of hyperparameters. The default calls [`log_params`](Kernel::log_params);
    /// override it where that allocates needlessly.
    fn n_params(&self) -> usize {
        self.log_params().len()
    }

    /// k(a, b) after checking the points.
    ///
    /// # Errors
    /// [`GpError::DimensionMismatch`] if `a` and `b` differ in length or do not have the
    /// kernel's [`dim`](Kernel::dim); [`GpError::NonFiniteInput`] (index 0 for `a`, 1 for `b`)
    /// if a coordinate is NaN or infinite.
    fn try_value(&self, a: &[f64], b: &[f64]) -> Result<f64> {
        let expected = self.dim().unwrap_or(a.len());
        for found in [a.len(), b.len()] {
            if found != expected {
                return Err(GpError::DimensionMismatch { expected, found });
            }
        }
        for (index, x) in [a, b].into_iter().enumerate() {
            if !x.iter().all(|v| v.is_finite()) {
                return Err(GpError::NonFiniteInput { index });
            }
        }
        Ok(self.value(a, b))
    }
}

/// Checks a flat row-major array of points of dimension `dim` against a kernel and returns the
/// number of points.
///
/// # Errors
/// [`GpError::BadPointArray`] if `dim == 0` or `x.len()` is not a multiple of `dim`;
/// [`GpError::DimensionMismatch`] if the kernel requires another dimension;
/// [`GpError::NonFiniteInput`] for the first point with a NaN or infinite coordinate.
pub fn check_points(kernel: &dyn Kernel, x: &[f64], dim: usize) -> Result<usize> {
    if dim == 0 || x.len() % dim != 0 {
        return Err(GpError::BadPointArray { len: x.len(), dim });
    }
    if let Some(expected) = kernel.dim()
        && expected != dim
    {
        return Err(GpError::DimensionMismatch {
            expected,
            found: dim,
        });
    }
    if let Some(index) = x
        .chunks_exact(dim)
        .position(|p| !p.iter().all(|v| v.is_finite()))
    {
        return Err(GpError::NonFiniteInput { index });
    }
    Ok(x.len() / dim)
}

/// The covariance matrix K with K[i, j] = k(x_i, x_j) of the n points of `x` (flat, row-major,
/// `n × dim`), returned row-major as `n × n` numbers. Only the upper triangle is evaluated;
/// the result is exactly symmetric.
///
/// # Errors
/// As [`check_points`].
///
/// # Complexity
/// n(n + 1)/2 kernel evaluations; n² numbers of memory.
///
/// # Example
/// ```
/// use haunts_gp::{covariance, Rbf};
/// let k = Rbf::new(2.0, 1.0).unwrap();
/// let x = [0.0, 0.0, 1.0, 0.0]; // two points of R²
/// let m = covariance(&k, &x, 2).unwrap();
/// approx::assert_relative_eq!(m[1], 2.0 * (-0.5f64).exp(), max_relative = 1e-15);
/// assert_eq!(m[1], m[2]);
/// ```
pub fn covariance(kernel: &dyn Kernel, x: &[f64], dim: usize) -> Result<Vec<f64>> {
    let n = check_points(kernel, x, dim)?;
    let mut k = vec![0.0; n * n];
    for i in 0..n {
        let a = &x[i * dim..(i + 1) * dim];
        for j in i..n {
            let v = kernel.value(a, &x[j * dim..(j + 1) * dim]);
            k[i * n + j] = v;
            k[j * n + i] = v;
        }
    }
    Ok(k)
}

/// The cross-covariance K with K[i, j] = k(x1_i, x2_j) of the n1 points of `x1` and the n2
/// points of `x2` (both flat, row-major, of dimension `dim`), returned row-major as `n1 × n2`
/// numbers.
///
/// # Errors
/// As [`check_points`] for either array (a non-finite point's index is within its own array).
///
/// # Complexity
/// n1·n2 kernel evaluations and numbers of memory.
pub fn cross_covariance(
    kernel: &dyn Kernel,
    x1: &[f64],
    x2: &[f64],
    dim: usize,
) -> Result<Vec<f64>> {
    let n1 = check_points(kernel, x1, dim)?;
    let n2 = check_points(kernel, x2, dim)?;
    let mut k = Vec::with_capacity(n1 * n2);
    for a in x1.chunks_exact(dim) {
        k.extend(x2.chunks_exact(dim).map(|b| kernel.value(a, b)));
    }
    Ok(k)
}

/// Checks the length of a log-parameter slice.
pub(crate) fn check_count(expected: usize, p: &[f64]) -> Result<()> {
    if p.len() == expected {
        Ok(())
    } else {
        Err(GpError::WrongParameterCount {
            expected,
            found: p.len(),
        })
    }
}

/// Checks one log-space hyperparameter: finite, with a finite positive exponential.
pub(crate) fn check_log(name: &str, value: f64) -> Result<f64> {
    let e = value.exp();
    if value.is_finite() && e.is_finite() && e > 0.0 {
        Ok(value)
    } else {
        Err(GpError::InvalidHyperparameter {
            name: name.to_owned(),
            value,
            rule: "log value must be finite with a finite, positive exponential",
        })
    }
}

/// Checks one natural-space positive hyperparameter and returns its logarithm.
pub(crate) fn check_positive(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value.ln())
    } else {
        Err(GpError::InvalidHyperparameter {
            name: name.to_owned(),
            value,
            rule: "must be finite and > 0",
        })
    }
}

/// A positive hyperparameter kept in log space with its natural value cached. Kernels evaluate
/// with the natural value and optimisers see the log, so a kernel rebuilt from its natural
/// values (as deserialising does) evaluates to the same bits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Positive {
    pub(crate) log: f64,
    pub(crate) value: f64,
}

impl Positive {
    /// A natural-space value, checked by [`check_positive`].
    pub(crate) fn new(name: &str, value: f64) -> Result<Self> {
        let log = check_positive(name, value)?;
        Ok(Self { log, value })
    }
    /// A log-space value (unchecked: see [`check_log`] and [`checked_logs`]).
    pub(crate) fn from_log(log: f64) -> Self {
        Self {
            log,
            value: log.exp(),
        }
    }
}

/// Checks `p` against `names` and returns the accepted values (all or nothing).
pub(crate) fn checked_logs<const N: usize>(names: [&str; N], p: &[f64]) -> Result<[Positive; N]> {
    check_count(N, p)?;
    let mut out = [Positive::from_log(0.0); N];
    for ((o, name), &v) in out.iter_mut().zip(names).zip(p) {
        *o = Positive::from_log(check_log(name, v)?);
    }
    Ok(out)
}

/// scikit-learn's default bounds (1e-5, 1e5) in log space.
pub(crate) fn default_log_bounds() -> (f64, f64) {
    (1e-5f64.ln(), 1e5f64.ln())
}

/// Squared Euclidean distance (unchecked: zips the shorter length).
pub(crate) fn sq_dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}
