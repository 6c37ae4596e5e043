//! Stationary kernels of the distance between two points: RBF (isotropic and ARD), Matérn 3/2
//! and 5/2, and the periodic (exp-sine-squared) kernel, each with a signal variance σ².

use crate::error::{GpError, Result};
use crate::kernel::{
    Kernel, Positive, check_count, check_log, checked_logs, default_log_bounds, sq_dist,
};

/// The fields of an isotropic kernel ([`Rbf`], [`Matern32`], [`Matern52`]) as (de)serialised,
/// in natural units; deserialising checks them with the kernel's `new`.
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct IsotropicFields {
    variance: f64,
    length_scale: f64,
}

/// Defines an isotropic kernel k = σ² f(r / ℓ) with hyperparameters `[log σ², log ℓ]`.
macro_rules! isotropic {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq)]
        #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
        #[cfg_attr(
            feature = "serde",
            serde(into = "IsotropicFields", try_from = "IsotropicFields")
        )]
        pub struct $name {
            variance: Positive,
            length_scale: Positive,
        }

        #[cfg(feature = "serde")]
        impl From<$name> for IsotropicFields {
            fn from(k: $name) -> Self {
                Self {
                    variance: k.variance.value,
                    length_scale: k.length_scale.value,
                }
            }
        }

        #[cfg(feature = "serde")]
        impl TryFrom<IsotropicFields> for $name {
            type Error = GpError;
            fn try_from(f: IsotropicFields) -> Result<Self> {
                Self::new(f.variance, f.length_scale)
            }
        }

        impl $name {
            /// A kernel of signal variance σ² = `variance` and length scale ℓ =
            /// `length_scale`.
            ///
            /// # Errors
            /// [`GpError::InvalidHyperparameter`] unless both are finite and > 0.
            pub fn new(variance: f64, length_scale: f64) -> Result<Self> {
                Ok(Self {
                    variance: Positive::new("variance", variance)?,
                    length_scale: Positive::new("length_scale", length_scale)?,
                })
            }
            /// The signal variance σ².
            pub fn variance(&self) -> f64 {
                self.variance.value
            }
            /// The length scale ℓ.
            pub fn length_scale(&self) -> f64 {
                self.length_scale.value
            }
        }

        impl Kernel for $name {
            fn value(&self, a: &[f64], b: &[f64]) -> f64 {
                let (f, _) = Self::profile(sq_dist(a, b), self.length_scale.value);
                self.variance.value * f
            }
            fn log_params(&self) -> Vec<f64> {
                vec![self.variance.log, self.length_scale.log]
            }
            fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
                let [v, l] = checked_logs(["variance", "length_scale"], p)?;
                self.variance = v;
                self.length_scale = l;
                Ok(())
            }
            fn log_bounds(&self) -> Vec<(f64, f64)> {
                vec![default_log_bounds(); 2]
            }
            fn param_names(&self) -> Vec<String> {
                vec!["variance".to_owned(), "length_scale".to_owned()]
            }
            fn gradient(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
                let s = self.variance.value;
                let (f, df) = Self::profile(sq_dist(a, b), self.length_scale.value);
                out[0] = s * f;
                out[1] = s * df;
            }
            fn dim(&self) -> Option<usize> {
                None
            }
            fn scale_param(&self) -> Option<usize> {
                Some(0)
            }
            fn n_params(&self) -> usize {
                2
            }
        }
    };
}

isotropic! {
    /// The isotropic squared-exponential (RBF) kernel
    /// `k(a, b) = σ² exp(−‖a − b‖² / (2ℓ²))`, hyperparameters `[log σ², log ℓ]`.
    ///
    /// scikit-learn: `ConstantKernel(σ²) * RBF(length_scale=ℓ)`; default bounds
    /// (1e-5, 1e5) for both, as scikit-learn's.
    ///
    /// # Example
    /// ```
    /// use haunts_gp::{Kernel, Rbf};
    /// let k = Rbf::new(2.0, 0.5).unwrap();
    /// // ‖a − b‖ = 1 = 2ℓ: σ² e^{−2}
    /// approx::assert_relative_eq!(k.value(&[0.0, 0.0], &[0.6, 0.8]), 2.0 * (-2.0f64).exp(),
    ///     max_relative = 1e-14);
    /// ```
    Rbf
}

isotropic! {
    /// The isotropic Matérn kernel with ν = 3/2:
    /// `k(a, b) = σ² (1 + √3 r/ℓ) exp(−√3 r/ℓ)`, r = ‖a − b‖, hyperparameters
    /// `[log σ², log ℓ]`.
    ///
    /// scikit-learn: `ConstantKernel(σ²) * Matern(length_scale=ℓ, nu=1.5)` (the same formula);
    /// default bounds (1e-5, 1e5).
    Matern32
}

isotropic! {
    /// The isotropic Matérn kernel with ν = 5/2:
    /// `k(a, b) = σ² (1 + √5 r/ℓ + 5r²/(3ℓ²)) exp(−√5 r/ℓ)`, r = ‖a − b‖, hyperparameters
    /// `[log σ², log ℓ]`.
    ///
    /// scikit-learn: `ConstantKernel(σ²) * Matern(length_scale=ℓ, nu=2.5)` (the same formula);
    /// default bounds (1e-5, 1e5).
    Matern52
}

impl Rbf {
    /// (f, ∂f/∂log ℓ) of the unit-variance kernel at squared distance `r2`.
    fn profile(r2: f64, l: f64) -> (f64, f64) {
        let q = r2 / (l * l);
        let f = (-0.5 * q).exp();
        (f, f * q)
    }
}

impl Matern32 {
    /// (f, ∂f/∂log ℓ) with u = √3 r/ℓ: f = (1 + u)e^{−u}, ∂f/∂log ℓ = u² e^{−u}.
    fn profile(r2: f64, l: f64) -> (f64, f64) {
        let u = 3f64.sqrt() * r2.sqrt() / l;
        let e = (-u).exp();
        ((1.0 + u) * e, u * u * e)
    }
}

impl Matern52 {
    /// (f, ∂f/∂log ℓ) with u = √5 r/ℓ: f = (1 + u + u²/3)e^{−u},
    /// ∂f/∂log ℓ = u²(1 + u)/3 · e^{−u}.
    fn profile(r2: f64, l: f64) -> (f64, f64) {
        let u = 5f64.sqrt() * r2.sqrt() / l;
        let e = (-u).exp();
        ((1.0 + u + u * u / 3.0) * e, u * u * (1.0 + u) / 3.0 * e)
    }
}

/// The squared-exponential kernel with one length scale per input dimension (automatic
/// relevance determination): `k(a, b) = σ² exp(−½ Σ_i (a_i − b_i)² / ℓ_i²)`, hyperparameters
/// `[log σ², log ℓ_0, …, log ℓ_{d−1}]`.
///
/// scikit-learn: `ConstantKernel(σ²) * RBF(length_scale=[ℓ_0, …])`; default bounds
/// (1e-5, 1e5).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(into = "RbfArdFields", try_from = "RbfArdFields")
)]
pub struct RbfArd {
    variance: Positive,
    length_scales: Vec<Positive>,
    /// 1/ℓ_i², cached.
    inv_sq: Vec<f64>,
}

impl RbfArd {
    /// A kernel of signal variance σ² = `variance` and one length scale per dimension.
    ///
    /// # Errors
    /// [`GpError::InvalidHyperparameter`] unless every value is finite and > 0;
    /// [`GpError::DimensionMismatch`] (expected 1, found 0) if `length_scales` is empty.
    pub fn new(variance: f64, length_scales: &[f64]) -> Result<Self> {
        if length_scales.is_empty() {
            return Err(GpError::DimensionMismatch {
                expected: 1,
                found: 0,
            });
        }
        let variance = Positive::new("variance", variance)?;
        let length_scales = length_scales
            .iter()
            .enumerate()
            .map(|(i, &l)| Positive::new(&format!("length_scale_{i}"), l))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self::from_parts(variance, length_scales))
    }

    fn from_parts(variance: Positive, length_scales: Vec<Positive>) -> Self {
        let inv_sq = length_scales
            .iter()
            .map(|l| (l.value * l.value).recip())
            .collect();
        Self {
            variance,
            length_scales,
            inv_sq,
        }
    }

    /// The signal variance σ².
    pub fn variance(&self) -> f64 {
        self.variance.value
    }

    /// The length scales ℓ_i.
    pub fn length_scales(&self) -> Vec<f64> {
        self.length_scales.iter().map(|l| l.value).collect()
    }
}

/// The fields of an [`RbfArd`] as (de)serialised, in natural units; deserialising checks them
/// with [`RbfArd::new`].
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct RbfArdFields {
    variance: f64,
    length_scales: Vec<f64>,
}

#[cfg(feature = "serde")]
impl From<RbfArd> for RbfArdFields {
    fn from(k: RbfArd) -> Self {
        Self {
            variance: k.variance(),
            length_scales: k.length_scales(),
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<RbfArdFields> for RbfArd {
    type Error = GpError;
    fn try_from(f: RbfArdFields) -> Result<Self> {
        Self::new(f.variance, &f.length_scales)
    }
}

impl Kernel for RbfArd {
    fn value(&self, a: &[f64], b: &[f64]) -> f64 {
        let q: f64 = a
            .iter()
            .zip(b)
            .zip(&self.inv_sq)
            .map(|((x, y), w)| (x - y) * (x - y) * w)
            .sum();
        self.variance.value * (-0.5 * q).exp()
    }
    fn log_params(&self) -> Vec<f64> {
        let mut p = Vec::with_capacity(self.n_params());
        p.push(self.variance.log);
        p.extend(self.length_scales.iter().map(|l| l.log));
        p
    }
    fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
        check_count(self.n_params(), p)?;
        for (name, &v) in self.param_names().iter().zip(p) {
            check_log(name, v)?;
        }
        *self = Self::from_parts(
            Positive::from_log(p[0]),
            p[1..].iter().map(|&l| Positive::from_log(l)).collect(),
        );
        Ok(())
    }
    fn log_bounds(&self) -> Vec<(f64, f64)> {
        vec![default_log_bounds(); self.n_params()]
    }
    fn param_names(&self) -> Vec<String> {
        let mut names = vec!["variance".to_owned()];
        names.extend((0..self.inv_sq.len()).map(|i| format!("length_scale_{i}")));
        names
    }
    fn gradient(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        let k = self.value(a, b);
        out[0] = k;
        for (((o, x), y), w) in out[1..].iter_mut().zip(a).zip(b).zip(&self.inv_sq) {
            *o = k * (x - y) * (x - y) * w;
        }
    }
    fn dim(&self) -> Option<usize> {
        Some(self.inv_sq.len())
    }
    fn scale_param(&self) -> Option<usize> {
        Some(0)
    }
    fn n_params(&self) -> usize {
        1 + self.inv_sq.len()
    }
}

/// The periodic (exp-sine-squared) kernel in scikit-learn's form:
/// `k(a, b) = σ² exp(−2 sin²(π r / p) / ℓ²)`, r = ‖a − b‖ (Euclidean distance), with
/// hyperparameters `[log σ², log ℓ, log p]`.
///
/// scikit-learn: `ConstantKernel(σ²) * ExpSineSquared(length_scale=ℓ, periodicity=p)`;
/// default bounds (1e-5, 1e5) for all three.
///
/// Like scikit-learn's, this form is positive semi-definite for one-dimensional inputs only:
/// in R² and above some point sets give covariance matrices with negative eigenvalues (the
/// tests found one of −0.01 for a trace of 1.6). Use it on 1-D inputs (e.g. time).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(into = "PeriodicFields", try_from = "PeriodicFields")
)]
pub struct Periodic {
    variance: Positive,
    length_scale: Positive,
    periodicity: Positive,
}

/// The fields of a [`Periodic`] kernel as (de)serialised, in natural units; deserialising
/// checks them with [`Periodic::new`].
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct PeriodicFields {
    variance: f64,
    length_scale: f64,
    periodicity: f64,
}

#[cfg(feature = "serde")]
impl From<Periodic> for PeriodicFields {
    fn from(k: Periodic) -> Self {
        Self {
            variance: k.variance(),
            length_scale: k.length_scale(),
            periodicity: k.periodicity(),
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<PeriodicFields> for Periodic {
    type Error = GpError;
    fn try_from(f: PeriodicFields) -> Result<Self> {
        Self::new(f.variance, f.length_scale, f.periodicity)
    }
}

impl Periodic {
    /// A kernel of signal variance σ², length scale ℓ and period p.
    ///
    /// # Errors
    /// [`GpError::InvalidHyperparameter`] unless all three are finite and > 0.
    pub fn new(variance: f64, length_scale: f64, periodicity: f64) -> Result<Self> {
        Ok(Self {
            variance: Positive::new("variance", variance)?,
            length_scale: Positive::new("length_scale", length_scale)?,
            periodicity: Positive::new("periodicity", periodicity)?,
        })
    }
    /// The signal variance σ².
    pub fn variance(&self) -> f64 {
        self.variance.value
    }
    /// The length scale ℓ.
    pub fn length_scale(&self) -> f64 {
        self.length_scale.value
    }
    /// The period p.
    pub fn periodicity(&self) -> f64 {
        self.periodicity.value
    }
    /// (arg = πr/p, sin arg, k).
    fn parts(&self, a: &[f64], b: &[f64]) -> (f64, f64, f64) {
        let arg = std::f64::consts::PI * sq_dist(a, b).sqrt() / self.periodicity.value;
        let s = arg.sin();
        let l = self.length_scale.value;
        let k = self.variance.value * (-2.0 * s * s / (l * l)).exp();
        (arg, s, k)
    }
}

impl Kernel for Periodic {
    fn value(&self, a: &[f64], b: &[f64]) -> f64 {
        self.parts(a, b).2
    }
    fn log_params(&self) -> Vec<f64> {
        vec![
            self.variance.log,
            self.length_scale.log,
            self.periodicity.log,
        ]
    }
    fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
        let [v, l, per] = checked_logs(["variance", "length_scale", "periodicity"], p)?;
        self.variance = v;
        self.length_scale = l;
        self.periodicity = per;
        Ok(())
    }
    fn log_bounds(&self) -> Vec<(f64, f64)> {
        vec![default_log_bounds(); 3]
    }
    fn param_names(&self) -> Vec<String> {
        ["variance", "length_scale", "periodicity"]
            .map(str::to_owned)
            .to_vec()
    }
    /// ∂k/∂log σ² = k; ∂k/∂log ℓ = 4 k sin²(arg)/ℓ²;
    /// ∂k/∂log p = 4 k arg sin(arg) cos(arg)/ℓ² (scikit-learn's gradient), arg = πr/p.
    fn gradient(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        let (arg, s, k) = self.parts(a, b);
        let l2 = self.length_scale.value * self.length_scale.value;
        out[0] = k;
        out[1] = 4.0 * k * s * s / l2;
        out[2] = 4.0 * k * arg * s * arg.cos() / l2;
    }
    fn dim(&self) -> Option<usize> {
        None
    }
    fn scale_param(&self) -> Option<usize> {
        Some(0)
    }
    fn n_params(&self) -> usize {
        3
    }
}
