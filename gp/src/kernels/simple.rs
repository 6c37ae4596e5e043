//! Kernels without a distance: white noise and a constant.

use crate::error::Result;
use crate::kernel::{Kernel, check_count, check_log, check_positive, default_log_bounds};

/// White noise: `k(a, b) = σ²` if `a = b`, else 0, hyperparameter `[log σ²]`.
///
/// "a = b" means the two points are exactly equal, coordinate by coordinate, with `==` on
/// `f64` (so `-0.0 = 0.0`, and a point with a NaN equals nothing). Two distinct training
/// points at the same place therefore share noise covariance σ².
///
/// scikit-learn: `WhiteKernel(noise_level=σ²)`, default bounds (1e-5, 1e5). One difference:
/// scikit-learn's `WhiteKernel` puts σ² on the diagonal of `k(X)` only and returns zeros for
/// `k(X, Y)` even where rows of `X` and `Y` coincide; this kernel compares points, so
/// [`cross_covariance`](crate::cross_covariance) of coinciding points gives σ².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct White {
    log_noise: f64,
}

impl White {
    /// White noise of variance σ² = `noise_level`.
    ///
    /// # Errors
    /// [`crate::GpError::InvalidHyperparameter`] unless `noise_level` is finite and > 0.
    pub fn new(noise_level: f64) -> Result<Self> {
        Ok(Self {
            log_noise: check_positive("noise_level", noise_level)?,
        })
    }
    /// The noise variance σ².
    pub fn noise_level(&self) -> f64 {
        self.log_noise.exp()
    }
}

impl Kernel for White {
    fn value(&self, a: &[f64], b: &[f64]) -> f64 {
        if a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y) {
            self.log_noise.exp()
        } else {
            0.0
        }
    }
    fn log_params(&self) -> Vec<f64> {
        vec![self.log_noise]
    }
    fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
        check_count(1, p)?;
        self.log_noise = check_log("noise_level", p[0])?;
        Ok(())
    }
    fn log_bounds(&self) -> Vec<(f64, f64)> {
        vec![default_log_bounds()]
    }
    fn param_names(&self) -> Vec<String> {
        vec!["noise_level".to_owned()]
    }
    fn gradient(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        out[0] = self.value(a, b);
    }
    fn dim(&self) -> Option<usize> {
        None
    }
    fn scale_param(&self) -> Option<usize> {
        Some(0)
    }
    fn n_params(&self) -> usize {
        1
    }
}

/// A constant covariance `k(a, b) = c` for all points, hyperparameter `[log c]`.
///
/// scikit-learn: `ConstantKernel(constant_value=c)`, default bounds (1e-5, 1e5). To scale
/// another kernel by a constant use [`Scaled`](crate::Scaled).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Constant {
    log_value: f64,
}

impl Constant {
    /// The constant kernel of value `c`.
    ///
    /// # Errors
    /// [`crate::GpError::InvalidHyperparameter`] unless `c` is finite and > 0.
    pub fn new(c: f64) -> Result<Self> {
        Ok(Self {
            log_value: check_positive("constant_value", c)?,
        })
    }
    /// The constant c.
    pub fn constant_value(&self) -> f64 {
        self.log_value.exp()
    }
}

impl Kernel for Constant {
    fn value(&self, _a: &[f64], _b: &[f64]) -> f64 {
        self.log_value.exp()
    }
    fn log_params(&self) -> Vec<f64> {
        vec![self.log_value]
    }
    fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
        check_count(1, p)?;
        self.log_value = check_log("constant_value", p[0])?;
        Ok(())
    }
    fn log_bounds(&self) -> Vec<(f64, f64)> {
        vec![default_log_bounds()]
    }
    fn param_names(&self) -> Vec<String> {
        vec!["constant_value".to_owned()]
    }
    fn gradient(&self, _a: &[f64], _b: &[f64], out: &mut [f64]) {
        out[0] = self.log_value.exp();
    }
    fn dim(&self) -> Option<usize> {
        None
    }
    fn scale_param(&self) -> Option<usize> {
        Some(0)
    }
    fn n_params(&self) -> usize {
        1
    }
}
