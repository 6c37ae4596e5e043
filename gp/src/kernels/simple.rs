//! Kernels without a distance: white noise and a constant.

use crate::error::Result;
use crate::kernel::{Kernel, Positive, check_count, check_log, default_log_bounds};

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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(into = "WhiteFields", try_from = "WhiteFields")
)]
pub struct White {
    noise: Positive,
}

impl White {
    /// White noise of variance σ² = `noise_level`.
    ///
    /// # Errors
    /// [`crate::GpError::InvalidHyperparameter`] unless `noise_level` is finite and > 0.
    pub fn new(noise_level: f64) -> Result<Self> {
        Ok(Self {
            noise: Positive::new("noise_level", noise_level)?,
        })
    }
    /// The noise variance σ².
    pub fn noise_level(&self) -> f64 {
        self.noise.value
    }
}

/// The fields of a [`White`] kernel as (de)serialised; deserialising checks them with
/// [`White::new`].
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct WhiteFields {
    noise_level: f64,
}

#[cfg(feature = "serde")]
impl From<White> for WhiteFields {
    fn from(k: White) -> Self {
        Self {
            noise_level: k.noise_level(),
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<WhiteFields> for White {
    type Error = crate::GpError;
    fn try_from(f: WhiteFields) -> Result<Self> {
        Self::new(f.noise_level)
    }
}

impl Kernel for White {
    fn value(&self, a: &[f64], b: &[f64]) -> f64 {
        if a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y) {
            self.noise.value
        } else {
            0.0
        }
    }
    fn log_params(&self) -> Vec<f64> {
        vec![self.noise.log]
    }
    fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
        check_count(1, p)?;
        self.noise = Positive::from_log(check_log("noise_level", p[0])?);
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(into = "ConstantFields", try_from = "ConstantFields")
)]
pub struct Constant {
    c: Positive,
}

impl Constant {
    /// The constant kernel of value `c`.
    ///
    /// # Errors
    /// [`crate::GpError::InvalidHyperparameter`] unless `c` is finite and > 0.
    pub fn new(c: f64) -> Result<Self> {
        Ok(Self {
            c: Positive::new("constant_value", c)?,
        })
    }
    /// The constant c.
    pub fn constant_value(&self) -> f64 {
        self.c.value
    }
}

/// The fields of a [`Constant`] kernel as (de)serialised; deserialising checks them with
/// [`Constant::new`].
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct ConstantFields {
    constant_value: f64,
}

#[cfg(feature = "serde")]
impl From<Constant> for ConstantFields {
    fn from(k: Constant) -> Self {
        Self {
            constant_value: k.constant_value(),
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<ConstantFields> for Constant {
    type Error = crate::GpError;
    fn try_from(f: ConstantFields) -> Result<Self> {
        Self::new(f.constant_value)
    }
}

impl Kernel for Constant {
    fn value(&self, _a: &[f64], _b: &[f64]) -> f64 {
        self.c.value
    }
    fn log_params(&self) -> Vec<f64> {
        vec![self.c.log]
    }
    fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
        check_count(1, p)?;
        self.c = Positive::from_log(check_log("constant_value", p[0])?);
        Ok(())
    }
    fn log_bounds(&self) -> Vec<(f64, f64)> {
        vec![default_log_bounds()]
    }
    fn param_names(&self) -> Vec<String> {
        vec!["constant_value".to_owned()]
    }
    fn gradient(&self, _a: &[f64], _b: &[f64], out: &mut [f64]) {
        out[0] = self.c.value;
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
